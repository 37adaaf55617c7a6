//! The way into a grasp: of the candidates (`grasp.rs`) whose pre-grasp and straight descent
//! keep clear of the arena and the object, the one with the least joint travel that has a
//! planned path; side grasps towards bin 2 first, then every other heading, then (the
//! dumbbell) pitched steeper.

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};

use super::lines::line;
use super::{LEAST_END_CLEARANCE, PlannedExpert, off_the_limits, quicker};
use crate::axes::{Object, Objective, Obstacle};
use crate::env::Env;
use crate::expert::clearance::Clearance;
use crate::expert::grasp::{Grasp, GraspInput, Headings, PlatePitch, grasp_candidates};
use crate::expert::motion::pad_ik_solutions;
use crate::expert::track::{Joints, joint_distance};
use crate::physics::RobotModel;

/// Pre-grasps a path is searched to, cheapest first: a search that finds nothing grows its
/// whole tree, and behind the door 80 candidates could all fail in turn.
pub(super) const PLANNED_OPTIONS: usize = 8;
/// The longest straight stretch (m) into a top grasp.
const TOP_BACKOFF: f64 = 0.06;
/// Leans (rad) of a top grasp's approach towards the robot, tried in turn.
const GRASP_TILTS: [f64; 2] = [0.0, 0.45];
/// What a leaning grasp counts as in joint travel (rad) when grasps are compared.
const LEANING: f64 = 10.0;
/// How far (m) above the plate's disc centre the pads aim: the lower finger slides in 1.3 cm
/// over bin 1's floor, and the tracker's few mm of sag put it on the floor on some seeds
/// (the Panda stalled there: 11 of 20 episodes without an obstacle, 19 of 20 raised).
const PLATE_GRASP_RAISE: f64 = 0.003;
/// The same for the steeper rim grasp ([`PlatePitch::Steep`]), whose lower fingertip hangs
/// lower: at 3 mm the pick-and-place and trash-can plate tasks (seeds 0–9) lifted the plate in
/// 154 of 320 episodes at 0.65 rad, at 6 mm in 293 (5 mm 283, 8 mm 281).
const PLATE_STEEP_GRASP_RAISE: f64 = 0.006;
/// The last stretches (m) into a side grasp tried, in turn, where no other way in is found:
/// shorter than the grasps' own (7–8 cm), the fingers still outside the object's outline.
/// On the five side-grasp tasks with the most episodes finding no way in (seeds 0–9): 23 of 50
/// without; from the grasp at 8 cm 24, 6 cm 25, 5 cm 30, 3 cm 32, 5 then 3 cm 36.
const SHORT_BACKOFFS: [f64; 2] = [0.05, 0.03];
/// How squarely a grasp from the goal's side points away from the goal (out from behind the
/// door, [`from_the_goals_side`]): the cosine of the largest angle between the
/// gripper's heading and the way from the goal to the object, 45°.
const GOAL_SIDE: f64 = std::f64::consts::FRAC_1_SQRT_2;
/// How far back towards bin 1 a plate's grasp into the shelf may point: the sine of the
/// angle past pointing across the bins (+x), halfway between the 15° and 30° of the headings
/// tried, so 15° back still counts. The shelf takes the object moving +y, and from a grasp
/// pointing further back the hand must turn ~2 rad on the carry, where the plate slips out of
/// the rim grasp (the 16 plate shelf tasks, seeds 0–9, survey of revision 18 by the heading each
/// episode's grasp took: pointing 30° back or more 3 of 24 episodes, the others 128 of 135).
const INTO_THE_SHELF: f64 = 0.383;
/// IK solutions at the grasp tried per candidate where the pre-grasp is found from the grasp.
const GRASP_FIRST_SOLUTIONS: usize = 8;

/// What a grasp's lean `tilt` (rad) adds to its joint travel when grasps are compared: a
/// leaning grasp only where no upright one will do.
fn leaning(tilt: f64) -> f64 {
    if tilt > 0.0 { LEANING } else { 0.0 }
}

/// A way into a grasp: what it costs (joint travel to the pre-grasp, more for a leaning top
/// grasp), the pre-grasp's joints, the grasp, and the straight descent into it.
pub(super) struct ApproachOption {
    pub(super) cost: f64,
    pub(super) pre: Joints,
    pub(super) grasp: Grasp,
    pub(super) descent: Vec<Joints>,
}

impl ApproachOption {
    /// The way from `q` to the pre-grasp `pre` of `grasp` (its top grasp leaning by `tilt`)
    /// and down `descent`, costed.
    fn from(q: &Joints, tilt: f64, pre: Joints, grasp: Grasp, descent: Vec<Joints>) -> Self {
        ApproachOption {
            cost: joint_distance(q, &pre) + leaning(tilt),
            pre,
            grasp,
            descent,
        }
    }
}

/// Whether a grasp is made from the goal's side of the object at `object`: the gripper points
/// away from the goal ([`GOAL_SIDE`]), so a push leads with the hand. Out from behind the door
/// this leaves no link trailing through the opening: a grasp reaching in through it drags the
/// wrist into the door's y+ post as the object goes towards bin 2, and the push's lines do not
/// tell the two apart (both come 3–4 cm close: from the goal's side the hand ends over bin 2's
/// far wall, which it clears in fact).
fn from_the_goals_side(goal: Point3<f64>, object: Point3<f64>) -> impl Fn(&Grasp) -> bool {
    let towards_goal = Vector3::new(goal.x - object.x, goal.y - object.y, 0.0).normalize();
    move |grasp: &Grasp| grasp.approach.dot(&towards_goal) < -GOAL_SIDE
}

/// Whether a grasp of the plate can go on into the shelf without the hand turning back
/// ([`INTO_THE_SHELF`]).
fn into_the_shelf(grasp: &Grasp) -> bool {
    grasp.approach.y > -INTO_THE_SHELF
}

/// Every grasp: the filter of the lists that take them all.
fn any_grasp(_: &Grasp) -> bool {
    true
}

/// `options` (cheapest first) with only the first of each grasp (the same orientation of the
/// gripper): its cheapest way in.
fn cheapest_per_grasp(mut options: Vec<ApproachOption>) -> Vec<ApproachOption> {
    let mut seen: Vec<UnitQuaternion<f64>> = Vec::new();
    options.retain(|option| {
        let new = seen
            .iter()
            .all(|r| r.angle_to(&option.grasp.orientation) > 1e-3);
        if new {
            seen.push(option.grasp.orientation);
        }
        new
    });
    options
}

impl PlannedExpert {
    /// A free path to a pre-grasp, the grasp, and the straight descent into it: of the
    /// candidates the arm reaches clear of the arena and the object, the one with the least
    /// joint travel. Side grasps pointing towards bin 2 are tried first (the carry and the
    /// push start well from them); only where none has a path, every other heading; for the
    /// dumbbell, every heading pitched steeper (behind the door the hand must come down
    /// from above the posts); for both, last, every heading from the arm's pose at the grasp
    /// with a shorter last stretch ([`SHORT_BACKOFFS`]), descents that come a few mm close
    /// after the clear ones. For a push, grasps from which its lines keep clear go first in each
    /// of these, the rest by how close their lines come ([`Self::clear_slides_first`]); for the
    /// plate and the dumbbell, where no first-choice heading gives clear lines, every grasp of
    /// the first two is weighed, by its cheapest way in.
    pub(super) fn plan_approach(
        &mut self,
        env: &Env,
        q: Joints,
        object: Point3<f64>,
        rotation: UnitQuaternion<f64>,
    ) -> Option<(Vec<Joints>, Grasp, Vec<Joints>)> {
        let around = self.clearance.with_object(
            self.task.object,
            &Isometry3::from_parts(object.coords.into(), rotation),
        );
        let side = matches!(self.task.object, Object::Plate | Object::Dumbbell);
        if side
            && self.pushing()
            && self.task.obstacle == Obstacle::ObjectDoor
            && let Some(found) = self.grasp_where(
                env,
                q,
                object,
                rotation,
                &around,
                &from_the_goals_side(env.goal(), object),
            )
        {
            return Some(found);
        }
        if self.task.object == Object::Plate
            && self.task.objective == Objective::Shelf
            && let Some(found) =
                self.grasp_where(env, q, object, rotation, &around, &into_the_shelf)
        {
            return Some(found);
        }
        let mut first = self.approach_options(
            env,
            q,
            object,
            rotation,
            &around,
            Headings::TowardsBin2,
            &any_grasp,
        );
        if self.pushing() {
            let any_clear;
            (first, any_clear) = self.clear_slides_first(env, first, PLANNED_OPTIONS);
            if side && !any_clear {
                // A push whose lines would drag the arm along the arena from every
                // first-choice grasp: the other headings too, each grasp by its cheapest way
                // in and every one looked at, those with clear lines first (the 64 push tasks
                // on seeds 0-9, with lines weighed at 20 rad/m: 576 episodes against 564 with
                // only the cheapest eight looked at).
                first.extend(self.approach_options(
                    env,
                    q,
                    object,
                    rotation,
                    &around,
                    Headings::Around,
                    &any_grasp,
                ));
                first.sort_by(|a, b| a.cost.total_cmp(&b.cost));
                first = self
                    .clear_slides_first(env, cheapest_per_grasp(first), usize::MAX)
                    .0;
            }
        }
        if let Some(found) = self.plan_first(env, &around, q, first) {
            return Some(found);
        }
        if !side {
            return None;
        }
        // Then the other headings, then (the dumbbell) every heading pitched steeper.
        for headings in self.every_heading().into_iter().skip(1) {
            let options =
                self.approach_options(env, q, object, rotation, &around, headings, &any_grasp);
            let options = self.pushes_clear_first(env, options);
            if let Some(found) = self.plan_first(env, &around, q, options) {
                return Some(found);
            }
        }
        // Last, every heading with the arm's pose at the grasp found first and the descent
        // drawn back from it, shorter each time: a pre-grasp solved on its own may sit on an IK
        // branch whose descent runs the forearm into a wall, and behind a wall the full
        // stretch back may itself reach into it (behind the object wall the IIWA's dumbbell:
        // no way in on 6 of seeds 0–9 at 8 cm, one on every seed at 3 cm); and after those,
        // descents that come a few mm close.
        for last in self.options_from_the_grasp(env, q, object, rotation, &around, &any_grasp) {
            let last = self.pushes_clear_first(env, last);
            if let Some(found) = self.plan_first(env, &around, q, last) {
                return Some(found);
            }
        }
        None
    }

    /// The lists of side-grasp headings in the order they are tried: towards bin 2 first, then
    /// every other heading, then (the dumbbell) every heading pitched steeper.
    fn every_heading(&self) -> Vec<Headings> {
        let mut all = vec![Headings::TowardsBin2, Headings::Around];
        if self.task.object == Object::Dumbbell {
            all.push(Headings::AroundSteep);
        }
        all
    }

    /// The first way into a side grasp that `keep` keeps, on every heading: the clear ways in
    /// first (the dumbbell's steeper grasps among them), cheapest first, then those from the
    /// arm's pose at the grasp, as [`Self::plan_approach`] tries them.
    fn grasp_where(
        &mut self,
        env: &Env,
        q: Joints,
        object: Point3<f64>,
        rotation: UnitQuaternion<f64>,
        around: &Clearance,
        keep: &dyn Fn(&Grasp) -> bool,
    ) -> Option<(Vec<Joints>, Grasp, Vec<Joints>)> {
        let mut clear: Vec<ApproachOption> = self
            .every_heading()
            .into_iter()
            .flat_map(|headings| {
                self.approach_options(env, q, object, rotation, around, headings, keep)
            })
            .collect();
        clear.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        if let Some(found) = self.plan_first(env, around, q, clear) {
            return Some(found);
        }
        for last in self.options_from_the_grasp(env, q, object, rotation, around, keep) {
            if let Some(found) = self.plan_first(env, around, q, last) {
                return Some(found);
            }
        }
        None
    }

    /// The ways into a grasp of the object at `object` (side grasps pointing along
    /// `headings`, of the grasps `keep` keeps) whose pre-grasp and descent keep clear, cheapest
    /// first: the pre-grasp solved for first, the descent drawn from it.
    #[allow(clippy::too_many_arguments)]
    fn approach_options(
        &self,
        env: &Env,
        q: Joints,
        object: Point3<f64>,
        rotation: UnitQuaternion<f64>,
        around: &Clearance,
        headings: Headings,
        keep: &dyn Fn(&Grasp) -> bool,
    ) -> Vec<ApproachOption> {
        let model = env.world().model;
        let mut options = Vec::new();
        for (tilt, grasp) in self
            .grasp_choices(model, q, object, rotation, headings)
            .into_iter()
            .filter(|(_, grasp)| keep(grasp))
        {
            let mut solutions = pad_ik_solutions(model, &q, grasp.pre(), grasp.orientation);
            solutions.truncate(4);
            for pre in solutions {
                let (pre, gap) = quicker(model, around, &q, pre, grasp.pre(), grasp.orientation);
                if gap < LEAST_END_CLEARANCE {
                    continue;
                }
                let Some(descent) = line(model, pre, grasp.pre(), grasp.pad, grasp.orientation)
                else {
                    continue;
                };
                if !self.clear_descent(model, &descent) {
                    continue;
                }
                options.push(ApproachOption::from(&q, tilt, pre, grasp, descent));
            }
        }
        options.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        options
    }

    /// The ways into a side grasp on every heading (of the grasps `keep` keeps) with the arm's
    /// pose at the grasp solved for first and the descent drawn back from it, in the lists
    /// tried in turn, each cheapest first: for each of [`SHORT_BACKOFFS`] (the same poses at the grasp, a shorter stretch
    /// back) those whose descent keeps clear, then for each those whose descent comes no closer
    /// than a pre-grasp may ([`LEAST_END_CLEARANCE`]). Behind the door and the object wall the
    /// dumbbell's best descents came 2–19 mm into a post or the wall and the episode ended at its
    /// start; last, no episode with a clear descent changes (13 plate and dumbbell tasks with
    /// such episodes, seeds 0–9: 73 → 77 of 130; mixed in with the clear ones by cost, 75).
    fn options_from_the_grasp(
        &self,
        env: &Env,
        q: Joints,
        object: Point3<f64>,
        rotation: UnitQuaternion<f64>,
        around: &Clearance,
        keep: &dyn Fn(&Grasp) -> bool,
    ) -> [Vec<ApproachOption>; 2 * SHORT_BACKOFFS.len()] {
        let model = env.world().model;
        let mut by_backoff: [Vec<ApproachOption>; 2 * SHORT_BACKOFFS.len()] = Default::default();
        let (clear, close) = by_backoff.split_at_mut(SHORT_BACKOFFS.len());
        for headings in self.every_heading() {
            for (tilt, grasp) in self
                .grasp_choices(model, q, object, rotation, headings)
                .into_iter()
                .filter(|(_, grasp)| keep(grasp))
            {
                let mut solutions = pad_ik_solutions(model, &q, grasp.pad, grasp.orientation);
                solutions.truncate(GRASP_FIRST_SOLUTIONS);
                for at_grasp in solutions {
                    for ((clear, close), backoff) in
                        clear.iter_mut().zip(close.iter_mut()).zip(SHORT_BACKOFFS)
                    {
                        let grasp = Grasp { backoff, ..grasp };
                        let Some(mut descent) =
                            line(model, at_grasp, grasp.pad, grasp.pre(), grasp.orientation)
                        else {
                            continue;
                        };
                        descent.reverse();
                        let pre = descent[0];
                        if around.at(model, &pre) < LEAST_END_CLEARANCE {
                            continue;
                        }
                        let options = match self.descent_gap(model, &descent) {
                            Some(gap) if gap >= 0.0 => &mut *clear,
                            Some(gap) if gap >= LEAST_END_CLEARANCE => &mut *close,
                            _ => continue,
                        };
                        options.push(ApproachOption::from(&q, tilt, pre, grasp, descent));
                    }
                }
            }
        }
        for options in &mut by_backoff {
            options.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        }
        by_backoff
    }

    /// The grasps of the object at `object` (side grasps pointing along `headings`), each
    /// with the lean of its top grasp's approach (0 for side grasps), as the planned expert
    /// takes them: the plate's pads raised, a top grasp's last stretch short.
    fn grasp_choices(
        &self,
        model: &RobotModel,
        q: Joints,
        object: Point3<f64>,
        rotation: UnitQuaternion<f64>,
        headings: Headings,
    ) -> Vec<(f64, Grasp)> {
        let pitch = self.plate_pitch();
        // Top grasps also leaning towards the robot: over a wall near it, a vertical gripper
        // hangs the Panda's forearm on the wall.
        let candidates = GRASP_TILTS.into_iter().flat_map(|tilt| {
            grasp_candidates(&GraspInput {
                model,
                q,
                object: self.task.object,
                objective: self.task.objective,
                obstacle: self.task.obstacle,
                position: object,
                rotation,
                tilt,
                headings,
                plate_pitch: pitch,
            })
            .into_iter()
            .filter(move |g| tilt == 0.0 || g.top_down)
            .map(move |g| (tilt, g))
        });
        candidates
            .map(|(tilt, grasp)| {
                // The planned approach keeps clear of the object, so the straight stretch into
                // a top grasp can be short.
                let grasp = Grasp {
                    pad: if self.task.object == Object::Plate {
                        grasp.pad
                            + Vector3::z()
                                * match pitch {
                                    PlatePitch::Level => PLATE_GRASP_RAISE,
                                    PlatePitch::Steep => PLATE_STEEP_GRASP_RAISE,
                                }
                    } else {
                        grasp.pad
                    },
                    backoff: if grasp.top_down {
                        grasp.backoff.min(TOP_BACKOFF)
                    } else {
                        grasp.backoff
                    },
                    ..grasp
                };
                (tilt, grasp)
            })
            .collect()
    }

    /// Whether a descent into a grasp stays within the joints' limits with the arm clear of
    /// the arena (the fingers left out: they come close to the floor on purpose).
    fn clear_descent(&self, model: &RobotModel, descent: &[Joints]) -> bool {
        self.descent_gap(model, descent)
            .is_some_and(|gap| gap >= 0.0)
    }

    /// The smallest gap (m) between the arena and the arm (the fingers left out) along a
    /// descent, `None` where the descent leaves the joints' limit margin.
    fn descent_gap(&self, model: &RobotModel, descent: &[Joints]) -> Option<f64> {
        descent.iter().all(|c| off_the_limits(model, c)).then(|| {
            descent
                .iter()
                .map(|c| self.clearance.without_fingers(model, c))
                .fold(f64::INFINITY, f64::min)
        })
    }

    /// How steeply the plate's rim grasp points down. Steep where the plate is only carried
    /// (pick-and-place, trash can): the wrist turns less on the way in and on the carry (the
    /// 32 such plate tasks, seeds 0–9: 238 → 293 of 320 episodes; the Panda behind the door
    /// 0 → 11 of 20, its level approach ~340 of the 500 steps). Level where the held plate
    /// turns in the hand or is dragged (seeds 0–9, steep against level): into the shelf the
    /// steep-held plate slipped out as the gripper turned to point in (no obstacle 24 against
    /// 38 of 40, behind the object wall 22 against 28), and pushes past the goal wall and out
    /// from behind the door did worse (39 against 58 of 80). Into the shelf from behind the door
    /// it is steep all the same: reaching through the door's slot, the level grasp's approach
    /// took 200–350 of the 500 steps and left too few for the shelf (27 against 6 of 40). So
    /// past the goal wall, where the carry to the shelf goes round the wall: 31 against 37 of
    /// 40 (the Panda's level approach took ~245 steps, 2 → 8 of 10); behind the object wall
    /// steep is worse (22 against 28 above; at revision 14, 22 against 29).
    fn plate_pitch(&self) -> PlatePitch {
        match (self.task.objective, self.task.obstacle) {
            (Objective::PickPlace | Objective::TrashCan, _) => PlatePitch::Steep,
            (Objective::Shelf, Obstacle::ObjectDoor | Obstacle::GoalWall) => PlatePitch::Steep,
            (Objective::Push | Objective::Shelf, _) => PlatePitch::Level,
        }
    }

    /// The first of `options` (cheapest first, the first [`PLANNED_OPTIONS`]) with a free
    /// path from `q` to its pre-grasp.
    fn plan_first(
        &mut self,
        env: &Env,
        around: &Clearance,
        q: Joints,
        options: Vec<ApproachOption>,
    ) -> Option<(Vec<Joints>, Grasp, Vec<Joints>)> {
        let model = env.world().model;
        for option in options.into_iter().take(PLANNED_OPTIONS) {
            if let Some(path) = self.plan_path(env, model, around, q, option.pre) {
                return Some((path, option.grasp, option.descent));
            }
        }
        None
    }
}
