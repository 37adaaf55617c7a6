//! The expert as an agent acts (work in progress, issue 49): every action is the reference's
//! 8 numbers, the arm's motions are planned in joint space (`plan.rs`) and followed through
//! the reference's controller (`track.rs`), and the gripper is driven by the sign of a[7]
//! alone. [`crate::expert::Expert`] stays the default until it solves every task.
//!
//! Stages: approach (planned, to a pre-grasp the arm reaches with the least joint travel) →
//! descend (a straight line of the pads into the grasp) → close → lift (a few cm straight up)
//! → the objective's carry (pick_place and trash_can: planned, to above the goal; push:
//! straight lines just off the floor; shelf: planned, to in front of it, then slid in) →
//! lower (pick_place) → release → retreat → hold. A grasp that did not lift the object is
//! let go and the next candidate tried.
//!
//! One file per objective — `pick_place.rs` (lowering into bin 2), `push.rs`, `shelf.rs`,
//! `trash_can.rs` (backing out over the can) — beside the pieces they share: the way into a
//! grasp (`approach.rs`), the carry to above a bin or the can (`carry.rs`), and straight lines
//! of the pads (`lines.rs`). The stage machine and the path planner's use are here.

mod approach;
mod carry;
mod lines;
mod pick_place;
mod push;
mod shelf;
mod trash_can;

use std::collections::VecDeque;

use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};

use self::lines::line;
use self::push::{PUSH_LIFT, PUSH_RISE_CHECK, PUSH_SIDE_TOP, SIDE_PUSH_LIFT};
use super::clearance::{Clearance, MIN_CLEARANCE};
use super::grasp::Grasp;
use super::motion::{least_travel, level_pointing, pads_at};
use super::plan::{Space, path_length, plan};
use super::track::{Joints, Leg, Tracker, joint_distance};
use super::{EpisodeOutcome, run_with};
use crate::TaskSpec;
use crate::arena::{Primitive, arena_parts};
use crate::axes::{Objective, Obstacle};
use crate::env::{Action, Env};
use crate::physics::{ARM_DOF, RobotModel, reference_command_for_gap, robot_model};
use crate::reward::in_bin2;

/// Which version of the expert's actions this is, on this physics: raised whenever a change
/// to the expert (or to the physics under it) changes any action it takes. The offline
/// datasets' noise table records it with each calibration and calibrates again where it
/// differs; `tests/planned_expert.rs` pins a digest of a few episodes to it, so a change
/// that moves the actions fails there until this is raised and the digest pinned anew.
pub const PLANNED_EXPERT_REVISION: u32 = 19;

/// Control steps the gripper is given to open or close: its command moves 0.25 per step
/// (8 steps end to end), and the fingers follow.
const GRIP_STEPS: u32 = 10;
/// Tree nodes a planning request may grow before it gives up: the paths found on seeds 0–1
/// are found within 4,000 as within 10,000, and a search that finds nothing costs 2.5× less
/// (one shelf episode spent 41 s failing with 10,000).
const PLAN_NODES: usize = 4000;
/// Searches made for one path while the best found is a detour: each finds its own way round
/// (the random trees differ), the shortest is kept.
const PLAN_TRIES: usize = 4;
/// A path at most this much longer than the straight move is kept as it is.
const DETOUR_ACCEPTED: f64 = 1.1;
/// How far (m) the pads rise from a side grasp: a plate held by its rim first turns in the
/// pads until its far edge leaves the floor.
const SIDE_LIFT: f64 = 0.08;
/// How far (m) the pads rise straight from the grasp before the carry: off the floor.
const LIFT: f64 = 0.04;
/// The object must rise at least this far (m) with the lift for the grasp to count.
const RISE_CHECK: f64 = 0.025;
/// How far (m) the pads move away after letting go.
const RETREAT: f64 = 0.08;
/// The least clearance (m) a pre-grasp or the carry's end may keep from the arena: the
/// fingers of a side grasp come within millimetres of the floor, and the model's spheres
/// round them outwards.
const LEAST_END_CLEARANCE: f64 = -0.005;
/// The clearance (m) a pose's quicker variant must keep to replace it ([`quicker`]): without
/// it the elbow swung closer to the object wall's top and box grasps behind it failed.
const KEPT_CLEARANCE: f64 = 0.03;
/// How far (rad) inside its limits every joint of a planned pose stays.
const LIMIT_MARGIN: f64 = 0.02;
/// Grasps tried in all.
const MAX_ATTEMPTS: u32 = 3;

/// The stages of an episode, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Not started, or about to try another grasp.
    Start,
    /// To the pre-grasp.
    Approach,
    /// The straight stretch into the grasp.
    Descend,
    /// Closing the fingers.
    Close,
    /// Straight up with the object.
    Lift,
    /// To above the goal.
    Carry,
    /// Into bin 2 (pick_place), still holding the object.
    Lower,
    /// Opening the fingers.
    Release,
    /// Away from the object (up, back out of a side grasp or the shelf).
    Retreat,
    /// Back over the object where it lies in bin 2 out of the gripper's reach (pick_place).
    Return,
    /// Holding still until the episode ends.
    Done,
}

/// The planned expert of one task.
pub struct PlannedExpert {
    task: TaskSpec,
    stage: Stage,
    tracker: Option<Tracker>,
    clearance: Clearance,
    /// The same without the floors, which a push's fingers and object skim on purpose.
    above_the_floors: Clearance,
    /// The reference gripper's command level, as this expert's own actions have moved it
    /// (0 after a reset, ±0.25 per step, in [−1, 1]: −1 open, +1 closed).
    gripper: f64,
    /// The level the gripper is driven to.
    gripper_goal: f64,
    /// Steps left before the current stage may end (the gripper moving).
    wait: u32,
    /// Legs of the current stage still to run after the one running.
    queue: VecDeque<Leg>,
    /// The grasp being executed and the straight descent into it.
    grasp: Option<Grasp>,
    descent: Vec<Joints>,
    /// The pads' offset from the object's origin once grasped (world frame, m).
    held: Vector3<f64>,
    /// The object's height when the lift began (m).
    lift_start_z: f64,
    /// Grasps tried so far.
    attempts: u32,
    /// Planning requests made (each seeds its own sampler).
    requests: u32,
}

impl PlannedExpert {
    /// The expert of `task`; call [`PlannedExpert::act`] once per control step.
    pub fn new(task: TaskSpec) -> PlannedExpert {
        PlannedExpert {
            task,
            stage: Stage::Start,
            tracker: None,
            clearance: Clearance::new(robot_model(task.robot), task.objective, task.obstacle),
            above_the_floors: Clearance::above_the_floors(
                robot_model(task.robot),
                task.objective,
                task.obstacle,
            ),
            gripper: 0.0,
            gripper_goal: -1.0,
            wait: 0,
            queue: VecDeque::new(),
            grasp: None,
            descent: Vec::new(),
            held: Vector3::zeros(),
            lift_start_z: 0.0,
            attempts: 0,
            requests: 0,
        }
    }

    /// The stage the expert is in.
    pub fn stage(&self) -> Stage {
        self.stage
    }

    /// The way the pads move into the grasp being made or held (a unit vector in the world:
    /// horizontal for a side grasp, straight down for a top grasp), `None`
    /// while no grasp is chosen. Which grasp an episode took, for looking inside one
    /// (`examples/planned_stages`).
    pub fn grasp_heading(&self) -> Option<[f64; 3]> {
        self.grasp
            .as_ref()
            .map(|g| [g.approach.x, g.approach.y, g.approach.z])
    }

    /// The next action (the reference's 8 numbers) for the environment's current state.
    pub fn act(&mut self, env: &Env) -> Action {
        Action::Reference(self.reference_action(env))
    }

    /// [`PlannedExpert::act`]'s 8 numbers: 7 joint-goal offsets in units of 0.05 rad and the
    /// gripper's direction, each in [−1, 1].
    pub fn reference_action(&mut self, env: &Env) -> [f64; 8] {
        let world = env.world();
        let (q, v) = (world.arm_positions(), world.arm_velocities());
        let physics = &env.config().physics;
        self.tracker.get_or_insert_with(|| Tracker::new(physics, q));
        // A stage that ends at once (nothing to move) lets the next one start this step.
        for _ in 0..4 {
            let tracker = self.tracker.as_ref().expect("made above");
            if self.stage == Stage::Done || self.wait > 0 || !tracker.arrived(&q, &v) {
                break;
            }
            match self.queue.pop_front() {
                Some(leg) => self.start(leg),
                None => self.advance(env, q),
            }
        }
        let joints = self.tracker.as_mut().expect("made above").act(&q, &v);
        self.wait = self.wait.saturating_sub(1);
        let sign = if self.gripper < self.gripper_goal - 1e-9 {
            1.0
        } else if self.gripper > self.gripper_goal + 1e-9 {
            -1.0
        } else {
            0.0
        };
        self.gripper = (self.gripper + 0.25 * sign).clamp(-1.0, 1.0);
        let mut action = [0.0; 8];
        action[..ARM_DOF].copy_from_slice(&joints);
        action[7] = sign;
        action
    }

    fn start(&mut self, leg: Leg) {
        self.tracker.as_mut().expect("made in act").start(leg);
    }

    fn hold(&mut self, q: Joints) {
        self.start(Leg::new(vec![q]));
    }

    /// Plan the next stage from what the environment shows now.
    fn advance(&mut self, env: &Env, q: Joints) {
        let model = env.world().model;
        let pose = object_pose(env);
        let object = Point3::from(pose.translation.vector);
        let rotation = pose.rotation;
        match self.stage {
            Stage::Start => {
                if self.attempts >= MAX_ATTEMPTS {
                    self.hold(q);
                    self.stage = Stage::Done;
                    return;
                }
                self.attempts += 1;
                match self.plan_approach(env, q, object, rotation) {
                    Some((path, grasp, descent)) => {
                        self.gripper_goal = gripper_level(grasp.open);
                        self.grasp = Some(grasp);
                        self.descent = descent;
                        self.start(Leg::new(path));
                        self.stage = Stage::Approach;
                    }
                    None => {
                        self.hold(q);
                        self.stage = Stage::Done;
                    }
                }
            }
            Stage::Approach => {
                let descent = std::mem::take(&mut self.descent);
                self.start(Leg::new(descent));
                self.stage = Stage::Descend;
            }
            Stage::Descend => {
                self.gripper_goal = 1.0;
                self.wait = GRIP_STEPS;
                self.hold(q);
                self.stage = Stage::Close;
            }
            Stage::Close => {
                let (pad, orientation) = pads_at(model, &q);
                self.held = pad - object.coords;
                self.lift_start_z = object.z;
                let side = self.grasp.is_some_and(|g| !g.top_down);
                let lift = match (self.pushing(), side) {
                    // Up to just under the line that ends a Push episode: a plate held by its
                    // rim turns in the pads before it leaves the floor.
                    (true, true) => (PUSH_SIDE_TOP - object.z).clamp(PUSH_LIFT, SIDE_PUSH_LIFT),
                    (true, false) => PUSH_LIFT,
                    (false, true) => SIDE_LIFT,
                    (false, false) => LIFT,
                };
                let top = pad + Vector3::z() * lift;
                match line(model, q, pad, top, orientation) {
                    Some(points) => self.start(Leg::new(points)),
                    None => self.hold(q),
                }
                self.stage = Stage::Lift;
            }
            Stage::Lift => {
                let rise_check = if self.pushing() {
                    PUSH_RISE_CHECK
                } else {
                    RISE_CHECK
                };
                if object.z - self.lift_start_z < rise_check {
                    self.let_go(q);
                    self.stage = Stage::Release;
                    self.grasp = None;
                    return;
                }
                let legs = if self.pushing() {
                    self.plan_slide(env, q)
                } else if self.task.objective == Objective::Shelf {
                    self.plan_shelf(env, q)
                } else {
                    self.plan_carry(env, q).map(|path| vec![Leg::new(path)])
                };
                match legs {
                    Some(mut legs) => {
                        self.start(legs.remove(0));
                        self.queue.extend(legs);
                        self.stage = Stage::Carry;
                    }
                    None => {
                        // Nowhere to take it: hold it rather than drop it back.
                        self.hold(q);
                        self.stage = Stage::Done;
                    }
                }
            }
            Stage::Carry if self.task.objective == Objective::PickPlace => {
                self.lower_into_bin2(model, q, object);
                self.stage = Stage::Lower;
            }
            Stage::Carry | Stage::Lower => {
                self.let_go(q);
                self.stage = Stage::Release;
            }
            Stage::Release => {
                let (pad, orientation) = pads_at(model, &q);
                // Out of the shelf backwards (its top block is above); from a side grasp back
                // along the gripper, level (open fingers rising at once carry the dumbbell's
                // upper disc with them); else straight up.
                let level = level_pointing(&orientation);
                let backing_out = self.grasp.is_some_and(|g| !g.top_down) && level.norm() > 0.3;
                let away = if self.task.objective == Objective::Shelf && self.grasp.is_some() {
                    -Vector3::y()
                } else if backing_out {
                    -level.normalize()
                } else {
                    Vector3::z()
                };
                let points = if backing_out && self.task.objective == Objective::TrashCan {
                    self.back_out(model, q, pad, away, orientation)
                } else {
                    line(model, q, pad, pad + away * RETREAT, orientation)
                };
                match points {
                    Some(points) => self.start(Leg::new(points)),
                    None => self.hold(q),
                }
                self.stage = Stage::Retreat;
            }
            Stage::Retreat => {
                if self.grasp.is_none() {
                    // The grasp failed: try again from here.
                    self.stage = Stage::Start;
                    self.hold(q);
                } else if self.task.objective == Objective::PickPlace
                    && !env.success_seen()
                    && in_bin2(&object)
                    && self.back_over_the_object(env, q, object)
                {
                    // In the bin, but the gripper too far from it to count.
                    self.stage = Stage::Return;
                } else {
                    self.hold(q);
                    self.stage = Stage::Done;
                }
            }
            Stage::Return => {
                self.hold(q);
                self.stage = Stage::Done;
            }
            Stage::Done => {}
        }
    }

    /// Open the fingers, the arm held where it is.
    fn let_go(&mut self, q: Joints) {
        self.gripper_goal = -1.0;
        self.wait = GRIP_STEPS;
        self.hold(q);
    }

    /// The arena's clearance model with the object, where it is now, carried by the hand.
    fn carrying(&self, env: &Env, q: &Joints) -> Clearance {
        self.clearance
            .holding(env.world().model, q, self.task.object, &object_pose(env))
    }

    /// Whether the objective is Push (the object slides just off the floor).
    fn pushing(&self) -> bool {
        self.task.objective == Objective::Push
    }

    /// A path from `from` to `to` keeping the arm clear of the arena.
    fn plan_path(
        &mut self,
        env: &Env,
        model: &RobotModel,
        clearance: &Clearance,
        from: Joints,
        to: Joints,
    ) -> Option<Vec<Joints>> {
        // Ends close to the arena (a grasp low in the bin) may be as close on the way, no
        // closer.
        let least = MIN_CLEARANCE
            .min(clearance.at(model, &from) - 1e-3)
            .min(clearance.at(model, &to) - 1e-3);
        let free = |c: &Joints| clearance.keeps(model, c, least);
        let space = Space {
            limits: limits(model),
            free: &free,
        };
        let direct = joint_distance(&from, &to);
        let mut best: Option<(f64, Vec<Joints>)> = None;
        for _ in 0..PLAN_TRIES {
            self.requests += 1;
            let seed = (env.seed() as u32)
                .wrapping_mul(7919)
                .wrapping_add(self.requests);
            let Some(path) = plan(&space, &from, &to, seed, PLAN_NODES) else {
                // Where one search found nothing, another is unlikely to.
                break;
            };
            let length = path_length(&path);
            if best.as_ref().is_none_or(|(shortest, _)| length < *shortest) {
                best = Some((length, path));
            }
            if best
                .as_ref()
                .is_some_and(|(shortest, _)| *shortest <= direct * DETOUR_ACCEPTED)
            {
                break;
            }
        }
        best.map(|(_, path)| path)
    }
}

/// `solved` moved along the arm's self-motion to where the move from `q` takes least time
/// ([`least_travel`]), unless that brings the arm closer to the arena than [`KEPT_CLEARANCE`]
/// (or than `solved` is already): time is not traded for a near miss. Returns the pose kept
/// and its clearance.
fn quicker(
    model: &RobotModel,
    clearance: &Clearance,
    q: &Joints,
    solved: Joints,
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> (Joints, f64) {
    let moved = least_travel(model, q, solved, pad, orientation);
    let (moved_gap, solved_gap) = (clearance.at(model, &moved), clearance.at(model, &solved));
    if moved_gap >= solved_gap.min(KEPT_CLEARANCE) {
        (moved, moved_gap)
    } else {
        (solved, solved_gap)
    }
}

/// The object's pose as the observation reports it.
fn object_pose(env: &Env) -> Isometry3<f64> {
    let obs = env.observation();
    let [x, y, z, w] = obs.object.orientation;
    Isometry3::from_parts(
        Vector3::from(obs.object.position).into(),
        UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
    )
}

/// The top (m) of the tallest of the arena's collision solids whose name starts with
/// `prefix` (upright boxes: the bins' walls, the trash can's).
fn top_of(objective: Objective, prefix: &str) -> f64 {
    arena_parts(objective, Obstacle::NoObstacle)
        .iter()
        .filter(|p| p.collides && p.name.starts_with(prefix))
        .map(|p| match p.shape {
            Primitive::Box { half_extents } => p.pose.translation.z + half_extents.z,
            Primitive::Cylinder { half_length, .. } => p.pose.translation.z + half_length,
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Whether every joint of `q` is at least [`LIMIT_MARGIN`] inside its limits: a joint's
/// stop in the physics holds it short of the limit itself, and the tracker then pushes
/// against it for the rest of the leg.
fn off_the_limits(model: &RobotModel, q: &Joints) -> bool {
    model.joints[..ARM_DOF].iter().zip(q).all(|(joint, &x)| {
        joint
            .limits
            .is_none_or(|(lo, hi)| x >= lo + LIMIT_MARGIN && x <= hi - LIMIT_MARGIN)
    })
}

/// The joint limits of the arm (±π for continuous joints).
fn limits(model: &RobotModel) -> [(f64, f64); ARM_DOF] {
    std::array::from_fn(|j| {
        model.joints[j]
            .limits
            .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI))
    })
}

/// The reference gripper's command level for an opening `width` (m), in the 0.25 steps its
/// command moves by (−1 fully open, +1 closed).
fn gripper_level(width: f64) -> f64 {
    ((reference_command_for_gap(width) * 4.0).round() / 4.0).clamp(-1.0, 1.0)
}

/// Runs one episode of `task` with `seed` (default config) driven by the planned expert.
pub fn run_planned_episode(task: TaskSpec, seed: u64) -> EpisodeOutcome {
    let mut expert = PlannedExpert::new(task);
    run_with(task, seed, |env| expert.act(env))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The heights the expert drops and lowers to, read from the arena's table: bin 2's walls
    /// and floor, the trash can's walls (docs/src/reference-facts.md §2).
    #[test]
    fn the_drop_heights_come_from_the_arena() {
        assert!((top_of(Objective::PickPlace, "bin2/wall") - 0.90).abs() < 1e-9);
        assert!((top_of(Objective::PickPlace, "bin2/floor") - 0.82).abs() < 1e-9);
        assert!((top_of(Objective::TrashCan, "trash_can/") - 0.9855).abs() < 1e-9);
        assert!((top_of(Objective::Shelf, "shelf/bottom") - 0.945).abs() < 1e-9);
    }

    /// Planned poses stay inside the joints' limits by a margin: every arm's initial pose
    /// does; the same pose with a limited joint moved onto its limit does not.
    #[test]
    fn planned_poses_keep_off_the_joint_limits() {
        use crate::axes::Robot;
        for robot in [Robot::Iiwa, Robot::Jaco, Robot::Gen3, Robot::Panda] {
            let model = robot_model(robot);
            let q = robot.init_qpos();
            assert!(off_the_limits(model, &q), "{robot:?}");
            let (j, (_, hi)) = model.joints[..ARM_DOF]
                .iter()
                .enumerate()
                .find_map(|(j, joint)| joint.limits.map(|l| (j, l)))
                .expect("a limited joint");
            let mut at_limit = q;
            at_limit[j] = hi - LIMIT_MARGIN / 2.0;
            assert!(!off_the_limits(model, &at_limit), "{robot:?} joint {j}");
        }
    }
}
