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

use std::collections::VecDeque;

use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};

use super::clearance::{Clearance, MIN_CLEARANCE};
use super::grasp::{Grasp, GraspInput, Headings, grasp_candidates};
use super::motion::{least_travel, pad_ik, pad_ik_clear, pad_ik_solutions, pads_at};
use super::plan::{Space, path_length, plan};
use super::track::{Joints, Leg, Tracker, joint_distance};
use super::{EpisodeOutcome, run_with};
use crate::TaskSpec;
use crate::arena::{Primitive, ROBOT_BASE_POSITION, TRASH_CAN, arena_parts, object_geometry};
use crate::axes::{Object, Objective, Obstacle};
use crate::env::{Action, Env};
use crate::physics::{ARM_DOF, RobotModel, reference_command_for_gap, robot_model};

/// Which version of the expert's actions this is, on this physics: raised whenever a change
/// to the expert (or to the physics under it) changes any action it takes. The offline
/// datasets' noise table records it with each calibration and calibrates again where it
/// differs; `tests/planned_expert.rs` pins a digest of a few episodes to it, so a change
/// that moves the actions fails there until this is raised and the digest pinned anew.
pub const PLANNED_EXPERT_REVISION: u32 = 8;

/// Control steps the gripper is given to open or close: its command moves 0.25 per step
/// (8 steps end to end), and the fingers follow.
const GRIP_STEPS: u32 = 10;
/// Spacing (m) of the IK points along a straight line of the pads.
const LINE_SPACING: f64 = 0.01;
/// Tree nodes a planning request may grow before it gives up: the paths found on seeds 0–1
/// are found within 4,000 as within 10,000, and a search that finds nothing costs 2.5× less
/// (one shelf episode spent 41 s failing with 10,000).
const PLAN_NODES: usize = 4000;
/// Pre-grasps a path is searched to, cheapest first: a search that finds nothing grows its
/// whole tree, and behind the door 80 candidates could all fail in turn.
const PLANNED_OPTIONS: usize = 8;
/// Searches made for one path while the best found is a detour: each finds its own way round
/// (the random trees differ), the shortest is kept.
const PLAN_TRIES: usize = 4;
/// A path at most this much longer than the straight move is kept as it is.
const DETOUR_ACCEPTED: f64 = 1.1;
/// The longest straight stretch (m) into a top grasp.
const TOP_BACKOFF: f64 = 0.06;
/// Leans (rad) of a top grasp's approach towards the robot, tried in turn.
const GRASP_TILTS: [f64; 2] = [0.0, 0.45];
/// What a leaning grasp counts as in joint travel (rad) when grasps are compared.
const LEANING: f64 = 10.0;
/// How far (m) the object's bottom is above the walls of what it is dropped into.
const DROP_CLEARANCE: f64 = 0.03;
/// Where the object's origin is lowered to in bin 2 (m): 3 cm under the 0.9 m line below which
/// it counts as in the bin.
const IN_BIN_Z: f64 = 0.87;
/// How far (m) the pads rise from a side grasp: a plate held by its rim first turns in the
/// pads until its far edge leaves the floor.
const SIDE_LIFT: f64 = 0.08;
/// How far (m) the pads rise for a push: the object slides just off the floor, far under the
/// 0.9 m line whose crossing ends a Push episode.
const PUSH_LIFT: f64 = 0.012;
/// The most (m) the pads rise from a side grasp for a push…
const SIDE_PUSH_LIFT: f64 = 0.04;
/// …keeping the object's origin under this height (m; a Push episode ends above 0.9): the
/// dumbbell (origin 0.868 at rest) rises 1.2 cm.
const PUSH_SIDE_TOP: f64 = 0.88;
/// The object must rise at least this far (m) with a push's lift for the grasp to count.
const PUSH_RISE_CHECK: f64 = 0.006;
/// The goal wall's line (y, m; on the seam between the bins) and points past its free end
/// (which is at x 0.11) that a pushed object may go round by (x, m), in the order tried.
const GOAL_WALL_Y: f64 = -0.01;
const AROUND_GOAL_WALL_X: [f64; 3] = [0.22, 0.17, 0.26];
/// A push past the goal wall may first go along the wall to its lane (when the diagonal to the
/// lane comes closer to the wall) where the object is more than this (m) short of the lane.
const ALONG_THE_WALL_FIRST: f64 = 0.05;
/// The object's origin's height (m) on the way round the goal wall from a top grasp: as high as
/// a Push lets it (its episode ends above 0.9), so the forearm passes over the wall's end
/// higher. (A side grasp keeps its lift: the plate held by its rim tilts in the pads.)
const ROUND_THE_WALL_Z: f64 = 0.885;
/// Where a push round the goal wall may end (x, y offsets from the goal, m; success allows 3 cm):
/// the goal, or a little further from the wall's end, which the gripper of a side grasp then
/// clears more easily.
const GOAL_SHIFTS: [[f64; 2]; 2] = [[0.0, 0.0], [0.015, 0.015]];
/// Turns (rad) about the vertical the gripper may make on a push's last line, from past the
/// goal wall's end to the goal (a gripper that held the object from the object's side of the
/// wall otherwise ends reaching back across the wall's line, right by its end) or from behind
/// the door (where the gripper reached in through the opening).
const FINAL_TURNS: [f64; 7] = [0.0, 0.4, -0.4, 0.8, -0.8, 1.2, -1.2];
/// How much more gap (m) turned or shifted lines must keep than the best so far to replace it.
const TURN_GAIN: f64 = 0.005;
/// Where the object's origin waits in front of the shelf (y, m; its front is at 0.14).
const SHELF_FRONT_Y: f64 = 0.07;
/// A way into the shelf: the object's origin's height while it goes in, where it is slid to
/// (y, m), and the lanes (x, m) across the opening (x −0.1…0.3) it may go in along.
struct ShelfWay {
    z: f64,
    inside_y: f64,
    lanes: &'static [f64],
}

/// The ways into the shelf, tried in order. First mid-way in the 0.945…1.095 height band, the
/// gripper's housing clear of the top block (bottom 1.10), slid in to mid-depth of the 0.18…0.33
/// band (short of the back panel at 0.32). Where no first way keeps clear (the IIWA past the
/// goal wall: stretched to the shelf, its forearm crosses the wall's end at the wall's top),
/// higher and only just past the band's front, further out: 3 cm up lifts the forearm over the
/// wall, 5 cm less deep keeps the wrist's housing out from under the top block.
const SHELF_WAYS: [ShelfWay; 2] = [
    ShelfWay {
        z: 1.0,
        inside_y: 0.25,
        lanes: &[0.1, 0.17, 0.03, 0.24],
    },
    ShelfWay {
        z: 1.03,
        inside_y: 0.20,
        lanes: &[0.24, 0.28, 0.17],
    },
];
/// Turns (rad) of the gripper about the vertical in front of the shelf, tried with each lane.
const SHELF_YAWS: [f64; 3] = [0.0, 0.35, -0.35];
/// How far (rad) the gripper may still point down as it goes into the shelf: each 0.1 rad is
/// 0.1 rad less for the wrist to turn on the way (~13 control steps); the clearance model
/// decides how far its housing clears the top block.
const SHELF_PITCHES: [f64; 4] = [0.6, 0.4, 0.2, 0.0];
/// How far (m) the object's bottom stays above the board (top 0.945) as it goes in, whatever
/// the way's height: the upright dumbbell reaches 5.2 cm below its origin.
const SHELF_BOARD_CLEARANCE: f64 = 0.015;
/// How far (m) the pads rise straight from the grasp before the carry: off the floor.
const LIFT: f64 = 0.04;
/// The object must rise at least this far (m) with the lift for the grasp to count.
const RISE_CHECK: f64 = 0.025;
/// How far (m) the pads move away after letting go.
const RETREAT: f64 = 0.08;
/// Turns (rad) about the vertical of a side grasp's way out over the trash can, tried in this
/// order where backing straight out comes close to the arena ([`PlannedExpert::back_out`]).
const BACK_OUT_TURNS: [f64; 5] = [0.0, 0.5, -0.5, 1.0, -1.0];
/// The least clearance (m) a pre-grasp or the carry's end may keep from the arena: the
/// fingers of a side grasp come within millimetres of the floor, and the model's spheres
/// round them outwards.
const LEAST_END_CLEARANCE: f64 = -0.005;
/// The clearance (m) a pose's quicker variant must keep to replace it ([`quicker`]): without
/// it the elbow swung closer to the object wall's top and box grasps behind it failed.
const KEPT_CLEARANCE: f64 = 0.03;
/// How far (m) above the plate's disc centre the pads aim: the lower finger slides in 1.3 cm
/// over bin 1's floor, and the tracker's few mm of sag put it on the floor on some seeds
/// (the Panda stalled there: 11 of 20 episodes without an obstacle, 19 of 20 raised).
const PLATE_GRASP_RAISE: f64 = 0.003;
/// How far (rad) inside its limits every joint of a planned pose stays.
const LIMIT_MARGIN: f64 = 0.02;
/// Grasps tried in all.
const MAX_ATTEMPTS: u32 = 3;
/// Turns (rad) of the gripper about the vertical tried for the carry's end, besides the turn
/// of the arm's base from the object to the goal.
const CARRY_TURNS: [f64; 17] = [
    0.0, -0.3, 0.3, -0.6, 0.6, -0.9, 0.9, -1.2, 1.2, -1.5, 1.5, -1.9, 1.9, -2.4, 2.4, -2.8, 2.8,
];

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
    /// Holding still until the episode ends.
    Done,
}

/// A way into a grasp: what it costs (joint travel to the pre-grasp, more for a leaning top
/// grasp), the pre-grasp's joints, the grasp, and the straight descent into it.
struct ApproachOption {
    cost: f64,
    pre: Joints,
    grasp: Grasp,
    descent: Vec<Joints>,
}

/// Ways into the shelf along one [`ShelfWay`], each nearest to the arm first (the largest joint
/// change to it, rad): the starts in front of the shelf with the straight slides in from them
/// that keep clear, and the poses with the object inside that keep clear (for a planned way in
/// where no slide does).
struct ShelfCandidates {
    slides: Vec<(f64, Joints, Vec<Joints>)>,
    insides: Vec<(f64, Joints)>,
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
        let bottom = object_geometry(self.task.object).bottom_offset;
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
                // Success needs the object below bin 2's wall tops with the gripper near it:
                // lowered there, not dropped.
                let (pad, orientation) = pads_at(model, &q);
                let floor = top_of(Objective::PickPlace, "bin2/floor");
                let floor_gap = object.z + bottom - (floor + 0.01);
                let depth = (object.z - IN_BIN_Z).clamp(0.0, floor_gap.max(0.0));
                match line(model, q, pad, pad - Vector3::z() * depth, orientation) {
                    Some(points) => self.start(Leg::new(points)),
                    None => self.hold(q),
                }
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
                let pointing = orientation * Vector3::z();
                let level = Vector3::new(pointing.x, pointing.y, 0.0);
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
                } else {
                    self.hold(q);
                    self.stage = Stage::Done;
                }
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

    /// A side grasp's way out over the trash can, the pads from `pad` along `away` (level,
    /// back along the gripper): a dumbbell hangs on the open fingers by its upper disc until
    /// they back out from under it. Where that line comes closer to the arena above its floors
    /// than [`LEAST_END_CLEARANCE`] (past the goal wall the wrist backs into the wall), the way
    /// out turns about the vertical ([`BACK_OUT_TURNS`]): the first line that keeps clear, else
    /// the one that comes least close (a turned one by [`TURN_GAIN`] more than the straight).
    fn back_out(
        &self,
        model: &RobotModel,
        q: Joints,
        pad: Vector3<f64>,
        away: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Option<Vec<Joints>> {
        let mut best: Option<(f64, Vec<Joints>)> = None;
        for turn in BACK_OUT_TURNS {
            let way = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn) * away;
            let Some(points) = line(model, q, pad, pad + way * RETREAT, orientation) else {
                continue;
            };
            let gap = smallest_gap(model, &self.above_the_floors, &points[1..]);
            if gap >= LEAST_END_CLEARANCE {
                return Some(points);
            }
            if keeps_more(&best, gap, turn == 0.0) {
                best = Some((gap, points));
            }
        }
        best.map(|(_, points)| points)
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

    /// Push: the pads along straight lines that take the object, just off the floor, to the
    /// goal (round the goal wall's free end where the wall stands between them), the gripper
    /// as it is (past the goal wall, out from behind the door, or where the IK loses the line
    /// with the gripper as it is, it may turn about the vertical on the last line), the elbow
    /// swung away from the arena where it comes close.
    fn plan_slide(&mut self, env: &Env, q: Joints) -> Option<Vec<Leg>> {
        let carrying = self.carrying(env, &q);
        let top_down = self.grasp.as_ref().is_some_and(|g| g.top_down);
        self.slide_lines(env, &carrying, top_down, q, &object_pose(env))
            .map(|(_, legs)| legs)
    }

    /// [`Self::plan_slide`]'s lines from the arm at `q` holding the object at `pose` (held from
    /// above where `top_down`; the elbow swung clear of the arena as `carrying` says), with the
    /// smallest gap kept on them: straight to the goal, the arm's own (the held object rides
    /// just off the floor on purpose); round the goal wall, out from behind the door, or
    /// turning, the arm's and the object's from the arena above its floors.
    fn slide_lines(
        &self,
        env: &Env,
        carrying: &Clearance,
        top_down: bool,
        q: Joints,
        pose: &Isometry3<f64>,
    ) -> Option<(f64, Vec<Leg>)> {
        let model = env.world().model;
        let object = Point3::from(pose.translation.vector);
        let goal = env.goal();
        let (pad, orientation) = pads_at(model, &q);
        let offset = pad - object.coords;
        let round_the_wall = self.task.obstacle == Obstacle::GoalWall
            && goal.y > GOAL_WALL_Y
            && object.y < GOAL_WALL_Y;
        if !round_the_wall && self.task.obstacle != Obstacle::ObjectDoor {
            let to = Vector3::new(goal.x, goal.y, object.z) + offset;
            if let Some(points) = swinging_line(model, carrying, q, pad, to, orientation) {
                let gap = smallest_gap(model, &self.clearance, &points);
                return Some((gap, vec![Leg::new(points)]));
            }
            // The IK loses the straight line with the gripper held as it is: the same line,
            // the gripper turning on the way, below.
        }
        let walls = &self
            .above_the_floors
            .holding(model, &q, self.task.object, pose);
        // Routes to where the last line to the goal starts, that line's ends, and the object's
        // height on the way. Past the goal wall, round its free end: diagonally to one of the
        // lanes past the end, else first along the wall (at the object's distance from it) to
        // the lane and then across the wall's line; a top-grasped object as high as a push
        // allows; the last line ends at the goal or a little beyond it. Out from behind the
        // door (the gripper reached in through the opening), or where the straight line with
        // the gripper as it is was lost, straight there.
        let (z, routes, ends) = if round_the_wall {
            let z = if top_down {
                object.z.max(ROUND_THE_WALL_Z)
            } else {
                object.z
            };
            let routes = [false, true]
                .into_iter()
                .flat_map(|along| AROUND_GOAL_WALL_X.map(|x| (x, along)))
                .filter(|&(x, along)| !along || object.x < x - ALONG_THE_WALL_FIRST)
                .map(|(x, along)| {
                    let mut stops = Vec::new();
                    if along {
                        stops.push(Vector3::new(x, object.y, z));
                    }
                    stops.push(Vector3::new(x, GOAL_WALL_Y, z));
                    stops
                })
                .collect::<Vec<_>>();
            (z, routes, &GOAL_SHIFTS[..])
        } else {
            (object.z, vec![Vec::new()], &[[0.0, 0.0]][..])
        };
        // On the last line the gripper may turn about the vertical so that it ends clear of the
        // wall's end (it held the object from the object's side of the wall) or of the door's
        // post. The first lines that keep clear, else those that come least close (the model's
        // spheres are rounder than the links: a few mm in is often no contact).
        let mut best: Option<(f64, Vec<Leg>)> = None;
        for stops in routes {
            let Some((on_the_way, legs)) =
                lines_through(model, carrying, walls, q, pad, offset, orientation, &stops)
            else {
                continue;
            };
            let from = legs.last().map_or(q, Leg::end);
            let from_object = stops.last().copied().unwrap_or(object.coords);
            for (&[dx, dy], &turn) in ends
                .iter()
                .flat_map(|shift| FINAL_TURNS.iter().map(move |turn| (shift, turn)))
            {
                let to = Vector3::new(goal.x + dx, goal.y + dy, z);
                let line = (from_object, to);
                let Some(points) =
                    last_line(model, carrying, from, line, offset, orientation, turn)
                else {
                    continue;
                };
                let gap = on_the_way.min(smallest_gap(model, walls, &points));
                let mut all = legs.clone();
                all.push(Leg::new(points));
                if gap >= LEAST_END_CLEARANCE {
                    return Some((gap, all));
                }
                if keeps_more(&best, gap, turn == 0.0 && dx == 0.0 && dy == 0.0) {
                    best = Some((gap, all));
                }
            }
        }
        best
    }

    /// Shelf: a free path, the object carried, to in front of the shelf's opening with the
    /// gripper turned to point into the shelf (+y; from a top grasp, which closes along x for
    /// this, a quarter turn about x), then straight in. Of the lanes across the opening and
    /// small turns about the vertical, the first the arm reaches clear of the arena, slide
    /// included; where none does, a path planned all the way in; each of the
    /// [`SHELF_WAYS`] in turn.
    fn plan_shelf(&mut self, env: &Env, q: Joints) -> Option<Vec<Leg>> {
        let model = env.world().model;
        let carrying = self.carrying(env, &q);
        for way in &SHELF_WAYS {
            let ShelfCandidates { slides, insides } = self.shelf_options(model, &carrying, q, way);
            for (_, start, slide) in slides.into_iter().take(3) {
                if let Some(path) = self.plan_path(env, model, &carrying, q, start) {
                    return Some(vec![Leg::new(path), Leg::new(slide)]);
                }
            }
            // No straight way in keeps clear (past the goal wall the forearm would cross
            // it): a path planned all the way in.
            for (_, inside) in insides.into_iter().take(3) {
                if let Some(path) = self.plan_path(env, model, &carrying, q, inside) {
                    return Some(vec![Leg::new(path)]);
                }
            }
        }
        None
    }

    /// [`Self::plan_shelf`]'s candidates along `way` for the arm at `q` (the object carried as
    /// `carrying` says).
    fn shelf_options(
        &self,
        model: &RobotModel,
        carrying: &Clearance,
        q: Joints,
        way: &ShelfWay,
    ) -> ShelfCandidates {
        let (_, orientation) = pads_at(model, &q);
        let insert_z = way.z.max(
            top_of(Objective::Shelf, "shelf/bottom") + SHELF_BOARD_CLEARANCE
                - object_geometry(self.task.object).bottom_offset,
        );
        let mut options: Vec<(f64, Joints, Vec<Joints>)> = Vec::new();
        let mut insides: Vec<(f64, Joints)> = Vec::new();
        for (&lane, yaw, pitch) in way.lanes.iter().flat_map(|lane| {
            SHELF_YAWS
                .into_iter()
                .flat_map(move |yaw| SHELF_PITCHES.map(|pitch| (lane, yaw, pitch)))
        }) {
            // The gripper turned the shortest way from where it points now to pointing
            // into the shelf (+y turned by `yaw`), still `pitch` below level: for a top
            // grasp a turn about x.
            let into_shelf = Vector3::new(
                -yaw.sin() * pitch.cos(),
                yaw.cos() * pitch.cos(),
                -pitch.sin(),
            );
            let Some(turn) =
                UnitQuaternion::rotation_between(&(orientation * Vector3::z()), &into_shelf)
            else {
                continue;
            };
            let front = Vector3::new(lane, SHELF_FRONT_Y, insert_z);
            let inside = Vector3::new(lane, way.inside_y, insert_z);
            let (pad_front, pad_inside) = (front + turn * self.held, inside + turn * self.held);
            // A quarter turn of the wrist is too far for the IK seeded here alone.
            let mut starts = pad_ik_solutions(model, &q, pad_front, turn * orientation);
            starts.truncate(3);
            for start in starts {
                if !carrying.keeps(model, &start, LEAST_END_CLEARANCE) {
                    continue;
                }
                let Some(slide) = line(model, start, pad_front, pad_inside, turn * orientation)
                else {
                    continue;
                };
                let end = *slide.last().expect("a point");
                if carrying.keeps(model, &end, LEAST_END_CLEARANCE) {
                    insides.push((joint_distance(&q, &end), end));
                }
                if slide
                    .iter()
                    .any(|c| !carrying.keeps(model, c, LEAST_END_CLEARANCE))
                {
                    continue;
                }
                options.push((joint_distance(&q, &start), start, slide));
            }
        }
        options.sort_by(|a, b| a.0.total_cmp(&b.0));
        insides.sort_by(|a, b| a.0.total_cmp(&b.0));
        ShelfCandidates {
            slides: options,
            insides,
        }
    }

    /// The height (m) of the object's bottom where it is let go: just over bin 2's walls or
    /// the trash can's.
    fn drop_bottom(&self) -> f64 {
        let top = match self.task.objective {
            Objective::TrashCan => top_of(Objective::TrashCan, "trash_can/"),
            _ => top_of(Objective::PickPlace, "bin2/wall"),
        };
        top + DROP_CLEARANCE
    }

    /// A free path to a pre-grasp, the grasp, and the straight descent into it: of the
    /// candidates the arm reaches clear of the arena and the object, the one with the least
    /// joint travel. Side grasps pointing towards bin 2 are tried first (the carry and the
    /// push start well from them); only where none has a path, every other heading; for the
    /// dumbbell, last, every heading pitched steeper (behind the door the hand must come down
    /// from above the posts). For a push, grasps from which its lines keep clear go first in
    /// each of these ([`Self::clear_slides_first`]); for the plate and the dumbbell, where no
    /// first-choice heading gives such lines, the first two are weighed together.
    fn plan_approach(
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
        let mut first =
            self.approach_options(env, q, object, rotation, &around, Headings::TowardsBin2);
        if self.pushing() {
            let any_clear;
            (first, any_clear) = self.clear_slides_first(env, first);
            if side && !any_clear {
                // A push whose lines would drag the arm along the arena from every
                // first-choice grasp: the other headings too, those with clear lines first.
                first.extend(self.approach_options(
                    env,
                    q,
                    object,
                    rotation,
                    &around,
                    Headings::Around,
                ));
                first.sort_by(|a, b| a.cost.total_cmp(&b.cost));
                first = self.clear_slides_first(env, first).0;
            }
        }
        if let Some(found) = self.plan_first(env, &around, q, first) {
            return Some(found);
        }
        if !side {
            return None;
        }
        let others = self.pushes_clear_first(
            env,
            self.approach_options(env, q, object, rotation, &around, Headings::Around),
        );
        if let Some(found) = self.plan_first(env, &around, q, others) {
            return Some(found);
        }
        if self.task.object != Object::Dumbbell {
            return None;
        }
        let steep = self.pushes_clear_first(
            env,
            self.approach_options(env, q, object, rotation, &around, Headings::AroundSteep),
        );
        self.plan_first(env, &around, q, steep)
    }

    /// The ways into a grasp of the object at `object` (side grasps pointing along
    /// `headings`) whose pre-grasp and descent keep clear, cheapest first.
    fn approach_options(
        &self,
        env: &Env,
        q: Joints,
        object: Point3<f64>,
        rotation: UnitQuaternion<f64>,
        around: &Clearance,
        headings: Headings,
    ) -> Vec<ApproachOption> {
        let model = env.world().model;
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
            })
            .into_iter()
            .filter(move |g| tilt == 0.0 || g.top_down)
            .map(move |g| (tilt, g))
        });
        let mut options = Vec::new();
        for (tilt, grasp) in candidates {
            // The planned approach keeps clear of the object, so the straight stretch into a
            // top grasp can be short.
            let grasp = Grasp {
                pad: if self.task.object == Object::Plate {
                    grasp.pad + Vector3::z() * PLATE_GRASP_RAISE
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
                if descent.iter().any(|c| !off_the_limits(model, c)) {
                    continue;
                }
                // Only the fingers may come close to the floor on the way in.
                let arm_gap = descent
                    .iter()
                    .map(|c| self.clearance.without_fingers(model, c))
                    .fold(f64::INFINITY, f64::min);
                if arm_gap < 0.0 {
                    continue;
                }
                // A leaning grasp only where no upright one will do.
                let cost = joint_distance(&q, &pre) + if tilt > 0.0 { LEANING } else { 0.0 };
                options.push(ApproachOption {
                    cost,
                    pre,
                    grasp,
                    descent,
                });
            }
        }
        options.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        options
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

    /// `options` as [`Self::clear_slides_first`] orders them where the objective is Push (it
    /// goes on from the grasp in straight lines), else as they are.
    fn pushes_clear_first(&self, env: &Env, options: Vec<ApproachOption>) -> Vec<ApproachOption> {
        if self.pushing() {
            self.clear_slides_first(env, options).0
        } else {
            options
        }
    }

    /// `options` (cheapest first) with those first from whose grasp the push's straight lines
    /// keep the arm clear (behind the object wall a gripper pointing towards bin 2 can leave
    /// the wrist over the wall, and the push then drags it along the wall); whether any does.
    /// Only the first [`PLANNED_OPTIONS`] are looked at.
    fn clear_slides_first(
        &self,
        env: &Env,
        options: Vec<ApproachOption>,
    ) -> (Vec<ApproachOption>, bool) {
        let model = env.world().model;
        let pose = object_pose(env);
        let mut ranked: Vec<(bool, ApproachOption)> = options
            .into_iter()
            .take(PLANNED_OPTIONS)
            .map(|option| {
                let grasped = *option.descent.last().expect("a point");
                let carrying = self
                    .clearance
                    .holding(model, &grasped, self.task.object, &pose);
                let clear = self
                    .slide_lines(env, &carrying, option.grasp.top_down, grasped, &pose)
                    .is_some_and(|(gap, _)| gap >= LEAST_END_CLEARANCE);
                (clear, option)
            })
            .collect();
        ranked.sort_by_key(|(clear, _)| !clear);
        let any = ranked.first().is_some_and(|(clear, _)| *clear);
        (ranked.into_iter().map(|(_, option)| option).collect(), any)
    }

    /// A free path, the object carried, from just off the floor to where it is let go: above
    /// the goal, its bottom clear of what it drops into. Of the turns of the gripper about the
    /// vertical, the one moving the joints least.
    fn plan_carry(&mut self, env: &Env, q: Joints) -> Option<Vec<Joints>> {
        let model = env.world().model;
        let carrying = self.carrying(env, &q);
        let (pad, orientation) = pads_at(model, &q);
        let object_now = pad - self.held;
        let origin_z = self.drop_bottom() - object_geometry(self.task.object).bottom_offset;
        let goal = match self.task.objective {
            Objective::TrashCan => {
                let [x, y, _] = TRASH_CAN.position;
                Vector3::new(x, y, origin_z)
            }
            _ => {
                let g = env.goal();
                Vector3::new(g.x, g.y, origin_z)
            }
        };
        // The base's own turn from the object to the goal turns the gripper with it.
        let [bx, by, _] = ROBOT_BASE_POSITION;
        let base_turn =
            (goal.y - by).atan2(goal.x - bx) - (object_now.y - by).atan2(object_now.x - bx);
        let mut ends: Vec<(f64, Joints)> = Vec::new();
        for extra in CARRY_TURNS {
            let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), base_turn + extra);
            let (pad_end, orientation_end) = (goal + turn * self.held, turn * orientation);
            // The quicker variant of `solved`, kept as an end where it keeps clear.
            let mut keep = |solved: Joints| {
                let (solved, gap) = quicker(model, &carrying, &q, solved, pad_end, orientation_end);
                let clear = gap >= LEAST_END_CLEARANCE;
                if clear {
                    ends.push((joint_distance(&q, &solved), solved));
                }
                clear
            };
            let (solved, met) = pad_ik(model, &q, pad_end, orientation_end);
            if met && keep(solved) {
                continue;
            }
            // The IK from here finds one way of holding that pose: where it meets the arena
            // (or nothing), look for the others.
            for solved in pad_ik_solutions(model, &q, pad_end, orientation_end)
                .into_iter()
                .take(3)
            {
                keep(solved);
            }
        }
        ends.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (_, end) in ends.into_iter().take(3) {
            if let Some(path) = self.plan_path(env, model, &carrying, q, end) {
                return Some(path);
            }
        }
        None
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

/// Joints along the straight line of the pads from `from` to `to` (the gripper turned to
/// `orientation`), starting with `q`, each solved from the last: `None` where the IK does not
/// meet a point.
fn line(
    model: &RobotModel,
    q: Joints,
    from: Vector3<f64>,
    to: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> Option<Vec<Joints>> {
    line_by(q, from, to, |last, p, _| {
        pad_ik(model, last, p, orientation)
    })
}

/// [`line`], the arm swung away from the arena in the IK's null space wherever a link comes
/// close to it (the elbow turning about the shoulder–wrist line, the pads held on the line).
fn swinging_line(
    model: &RobotModel,
    clearance: &Clearance,
    q: Joints,
    from: Vector3<f64>,
    to: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> Option<Vec<Joints>> {
    line_by(q, from, to, |last, p, _| {
        pad_ik_clear(model, clearance, last, p, orientation)
    })
}

/// Whether lines keeping `gap` (m) replace `best`: they keep more, and a turned or shifted
/// variant (not `plain`) by [`TURN_GAIN`] more — among lines that all come close, one that
/// comes a fraction of a millimetre less close is no better.
fn keeps_more<T>(best: &Option<(f64, T)>, gap: f64, plain: bool) -> bool {
    let margin = if plain { 0.0 } else { TURN_GAIN };
    best.as_ref().is_none_or(|(g, _)| gap > *g + margin)
}

/// A push's last line: [`swinging_line`] of the pads where `turn` is 0, else
/// [`turning_line`]; the object from `line.0` to `line.1`, held by the pads at `offset` from it.
fn last_line(
    model: &RobotModel,
    carrying: &Clearance,
    q: Joints,
    line: (Vector3<f64>, Vector3<f64>),
    offset: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    turn: f64,
) -> Option<Vec<Joints>> {
    if turn == 0.0 {
        let (from, to) = line;
        swinging_line(model, carrying, q, from + offset, to + offset, orientation)
    } else {
        turning_line(model, carrying, q, line, offset, orientation, turn)
    }
}

/// Joints along the object's straight line from `from` to `to` (m), held by the pads at
/// `offset` from it with the gripper at `orientation`, both turned about the vertical by
/// `turn` (rad) in proportion on the way, the elbow swung clear as in [`swinging_line`];
/// starting with `q`, `None` where the IK does not meet a point.
fn turning_line(
    model: &RobotModel,
    clearance: &Clearance,
    q: Joints,
    (from, to): (Vector3<f64>, Vector3<f64>),
    offset: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    turn: f64,
) -> Option<Vec<Joints>> {
    line_by(q, from, to, |last, p, t| {
        let yaw = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn * t);
        pad_ik_clear(model, clearance, last, p + yaw * offset, yaw * orientation)
    })
}

/// Straight lines of the pads (at `offset` from the object, the gripper at `orientation`)
/// taking the object from where it is to each of `stops` in turn, the arm starting at `q` with
/// the pads at `pad` and swung clear as `carrying` says: the smallest gap from `walls` on
/// them and the legs, or `None` where the IK does not meet a point.
#[allow(clippy::too_many_arguments)]
fn lines_through(
    model: &RobotModel,
    carrying: &Clearance,
    walls: &Clearance,
    q: Joints,
    pad: Vector3<f64>,
    offset: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    stops: &[Vector3<f64>],
) -> Option<(f64, Vec<Leg>)> {
    let (mut pad, mut from) = (pad, q);
    let mut legs = Vec::new();
    let mut gap = f64::INFINITY;
    for stop in stops {
        let to = stop + offset;
        let points = swinging_line(model, carrying, from, pad, to, orientation)?;
        gap = gap.min(smallest_gap(model, walls, &points));
        from = *points.last().expect("a point");
        pad = to;
        legs.push(Leg::new(points));
    }
    Some((gap, legs))
}

/// The smallest gap (m) the arm keeps from `clearance`'s arena over `points`.
fn smallest_gap(model: &RobotModel, clearance: &Clearance, points: &[Joints]) -> f64 {
    points
        .iter()
        .map(|c| clearance.at(model, c))
        .fold(f64::INFINITY, f64::min)
}

/// Points every [`LINE_SPACING`] from `from` to `to`, each turned into joints by `solve` from
/// the joints of the one before (`q` first) and how far along the line it is (0…1): the
/// joints, `q` included, or `None` where `solve` does not meet a point.
fn line_by(
    q: Joints,
    from: Vector3<f64>,
    to: Vector3<f64>,
    mut solve: impl FnMut(&Joints, Vector3<f64>, f64) -> (Joints, bool),
) -> Option<Vec<Joints>> {
    let n = ((to - from).norm() / LINE_SPACING).ceil().max(1.0) as usize;
    let mut points = vec![q];
    for k in 1..=n {
        let t = k as f64 / n as f64;
        let p = from + (to - from) * t;
        let (solved, met) = solve(points.last().expect("q first"), p, t);
        if !met {
            return None;
        }
        points.push(solved);
    }
    Some(points)
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
