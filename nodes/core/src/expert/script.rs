//! The phase machine.

use std::collections::VecDeque;
use std::f64::consts::FRAC_PI_2;

use nalgebra::{Point2, Point3, Quaternion, UnitQuaternion, Vector3};

use crate::TaskSpec;
use crate::arena::{SHELF, TRASH_CAN, object_geometry, objective_arena};
use crate::axes::{Object, Objective, Obstacle, Robot};
use crate::env::{Action, Env};
use crate::physics::{ARM_DOF, RobotModel, robot_model};

use super::clearance::{Clearance, MIN_CLEARANCE, best_clear};
use super::grasp::{
    Grasp, GraspInput, Headings, PlatePitch, closed, grasp_candidates, gripper_closing_axis,
    gripper_orientation, open,
};
use super::motion::{
    CONTROL_PERIOD, pad_ik, pad_ik_clear, pad_ik_solutions, pads_at, smoothstep, steps,
};
use super::nudge;

/// Pad-centre height (m) that clears the object wall and door (tops at z 1.07).
const OVER_OBJECT_WALL_Z: f64 = 1.17;
/// Object-centre height (m) that clears the goal wall (top at z 1.10) with the box below it.
const OVER_GOAL_WALL_Z: f64 = 1.19;
/// The largest joint change (rad) planned per 50 ms control step: about 1 rad/s, what the
/// arms' torque limits follow (the Jaco's elbow lags by up to 0.7 rad at 1.6 rad/s).
const MAX_JOINT_STEP: f64 = 0.05;
/// A move through joint space (no straight line to follow) may run each joint at up to this
/// fraction of its rated speed at the peak, where that is faster than [`MAX_JOINT_STEP`]: the
/// Panda's joints (2.2–2.6 rad/s) and the IIWA's outer ones; the Gen3's and the Jaco's stay at
/// [`MAX_JOINT_STEP`]. Some approaches turn the wrist through several radians (the Panda's
/// plate behind the door: 5 rad, 8 s at 1 rad/s), which at 1 rad/s leaves too little of the
/// episode for the grasp and the carry; the arms whose joints are rated faster follow this much
/// of it. The measured effect: docs/src/expert.md, "How the expert's settings were chosen".
const JOINT_MOVE_SPEED_FRACTION: f64 = 0.7;
/// What a plan that ends short of one of its poses counts as lost clearance (m): any plan that
/// reaches its poses is preferred.
const UNREACHED: f64 = 1.0;
/// How high (m) the gripper must rise straight from a grasp for it to count as liftable: over
/// bin 2's walls (Push: just off the floor).
const LIFT_CHECK: f64 = 0.1;
/// The same for Push.
const PUSH_LIFT_CHECK: f64 = 0.03;
/// How far (m) the planned pads may end from a grasp and still close on the object; a grasp
/// they end further from counts as unreached. The Gen3's dumbbell grasps pointing +y from
/// behind the object wall end 5–6 cm short (at the edge of its reach) with a clear path, land a
/// finger on the dumbbell's disc and fail on every seed. Only the grasp counts: the IIWA's
/// rise from its start pose ends up to 30 cm short and the next segments recover.
const GRASP_MISS: f64 = 0.03;
/// What a grasp that cannot be lifted straight counts as lost clearance (m): less than an
/// unreached one.
const UNLIFTABLE: f64 = 0.5;
/// Where a side-grasped object is set down past the goal wall's free end before it is
/// grasped again from the robot's side and carried to the goal (Push; x, y, m): just past the
/// wall's line (y −0.01), so the second grasp's wrist (towards the robot and +y) keeps clear
/// of it, yet within the arms' reach with the gripper pointing +y; just past the wall's free
/// end (x 0.11) with the plate's rim clear of it, and far enough from bin 2's far wall
/// (x 0.29) for the fingers of the second grasp.
const GOAL_WALL_SPOT: [f64; 2] = [0.2, 0.0];
/// The second grasp's approach, grasp and lift take this fraction of the usual time.
const REGRASP_PACE: f64 = 0.6;
/// How far below its resting height (m) the gripper lowers a set-down object before letting
/// go: the plate tilts in a rim grasp while carried (0.4 rad) and, let go just above the
/// floor, stays tilted on its stem's edge where no rim grasp takes it again; pressed down,
/// the floor turns it level first (the dumbbell likewise). 2.5 cm did best of the depths tried
/// (docs/src/expert.md, "How the expert's settings were chosen").
const SET_DOWN_PRESS: f64 = 0.025;
/// Grasps tried again after one that did not lift the object.
const MAX_RETRIES: usize = 2;
/// Duration of one leg of a push without a grasp (s; legs are up to 5 cm).
const NUDGE_LEG_SECONDS: f64 = 0.8;
/// How far the pads rise (m) when the object is no longer between the fingers, before they
/// are set behind it again: above the dumbbell's upper disc from 2 cm over the floor.
const NUDGE_LOST_RISE: f64 = 0.09;
/// Object-centre height (m) for a plain lift and carry.
const CARRY_Z: f64 = 1.05;
/// How far above the object's resting height a top-grasped object is carried while pushing
/// where no goal wall is in the way (m).
const PUSH_LIFT: f64 = 0.012;
/// Object-centre height (m) a side-grasped object, or any object past the goal wall, is
/// carried at while pushing: just under the 0.9 m line whose crossing ends a Push episode.
const PUSH_SIDE_CARRY_Z: f64 = 0.885;
/// How far above its resting height (m) the dumbbell is carried while pushing with a side
/// grasp: just off the floor. Carried up at [`PUSH_SIDE_CARRY_Z`] (1.7 cm), it tilts in the
/// grasp and its origin crosses the 0.9 m line that ends the episode. Only the dumbbell: the
/// plate's rim drags on the floor this low.
const DUMBBELL_PUSH_LIFT: f64 = 0.01;
/// Inner face of bin 2's far wall (x, m; docs/src/reference-facts.md §2.1).
const BIN2_FAR_WALL_X: f64 = 0.29;
/// x (m) of a lane further out than [`AROUND_GOAL_WALL_X`], for arms whose wrist swings wide.
const PUSH_WIDE_LANE_X: f64 = 0.26;
/// x (m) of the lane that goes around the goal wall's free end (the wall ends at x 0.11).
const AROUND_GOAL_WALL_X: f64 = 0.22;
/// x (m) of a lane just past the goal wall's free end with a small object's edge 2 cm clear
/// of it, for arms that do not reach [`AROUND_GOAL_WALL_X`] with a top grasp this low.
const NEAR_GOAL_WALL_X: f64 = 0.17;
/// How far (rad) the gripper may lean about the x axis (its wrist towards +y) while pushing
/// past the goal wall, least first.
const PUSH_LEANS: [f64; 3] = [0.0, 0.3, 0.55];
/// How far (rad) the approach axis leans towards the robot when walls are near the arm.
const GRASP_TILT: f64 = 0.45;
/// Height (m) of the carried box's centre above the shelf board while inserting: midway in
/// the 15.5 cm opening, so the gripper's housing around the box clears the board and the top
/// block (the box, lying on its side, then drops about 5 cm onto the board).
const SHELF_INSERT_HEIGHT: f64 = 0.075;
/// How far past the shelf's front the box's centre goes (m): to y 0.28, inside the
/// 0.18…0.33 success band, with its far end 1 cm short of the back panel.
const SHELF_INSERT_DEPTH: f64 = 0.05;
/// Where a side-grasped object's origin ends in the shelf (y, m): inside the 0.18…0.33 band
/// with the plate's far rim short of the back panel (y 0.32).
const SHELF_SIDE_TARGET_Y: f64 = 0.25;
/// How far (m) the object's edge stays outside the shelf's near end (x −0.1), and past the goal
/// wall's end at the same x, before it goes in through that end.
const SHELF_NEAR_END_CLEAR: f64 = 0.04;
/// How far past the shelf's near end (m) the object's origin goes in: to x −0.04, inside the
/// success band's x −0.1 bound, with the gripper's housing still outside the end.
const SHELF_NEAR_END_DEPTH: f64 = 0.06;
/// How far (m) the arm may run into the arena on the best way through the shelf's front before
/// the ways through its near end are tried: where the clearance model has the arm run in by
/// more than this, the front way mostly fails and the near end mostly works; by less, the front
/// does better (docs/src/expert.md, "How the expert's settings were chosen").
const SHELF_FRONT_MISS: f64 = -0.04;
/// Clearance (m) below which a top-grasped object's other ways into the shelf are tried.
const SHELF_TOP_OTHERS_BELOW: f64 = -0.06;
/// How far (m) the pads may end from a planned pose in front of the shelf for the way in
/// to count as reachable.
const SHELF_REACH_ERROR: f64 = 0.03;
/// The same for the slide into the shelf (m): the object's origin still ends past y 0.2.
const SHELF_SLIDE_SHORT: f64 = 0.05;
/// Lanes into the shelf for the box when the goal wall stands at x −0.10…0.11, best first
/// (the opening spans x −0.1…0.3).
const SHELF_LANES_PAST_GOAL_WALL_X: [f64; 3] = [0.17, 0.22, 0.26];
/// Lanes (the object's x, m) in front of the shelf, best first: its middle, then towards its
/// far end, then near its x −0.1 end.
const SHELF_LANES_X: [f64; 4] = [0.1, 0.17, 0.24, 0.03];
/// The same for a side-grasped object past the goal wall: past the wall's free end first.
const SHELF_SIDE_LANES_PAST_GOAL_WALL_X: [f64; 5] = [0.17, 0.22, 0.26, 0.1, 0.03];
/// Turns (rad) of the gripper about the vertical in front of the shelf, best first: positive
/// swings the wrist towards +x (past the goal wall's free end, away from the object wall's
/// and door's posts at x 0.009), negative towards −x (the forearm then crosses the goal
/// wall's line beyond its x −0.10 end).
const SHELF_YAWS: [f64; 5] = [0.0, 0.35, 0.7, -0.35, -0.7];
/// Lower object-centre heights (m) to carry at where [`CARRY_Z`] is out of reach and nothing
/// needs clearing but bin 2's walls (tops at z 0.90).
const LOWER_CARRIES_Z: [f64; 3] = [1.0, 0.96, 0.93];
/// Gap (m) between a side-grasped object's bottom and the surface it is put down on before
/// the fingers open.
const DROP_GAP: f64 = 0.015;
/// Where a side-grasped object may be put into bin 2 (x, y; m), best first: past the bin's
/// centre (0.1, 0.18) so the wrist behind the gripper is inside the bin rather than over its
/// near walls (top z 0.90).
const BIN2_SIDE_SPOTS: [[f64; 2]; 5] = [
    [0.1, 0.26],
    [0.17, 0.24],
    [0.2, 0.18],
    [0.1, 0.18],
    [0.2, 0.28],
];
/// How much closer to the arena (m) a side-grasped carry to the shelf counts when some segment
/// of it leaves its straight line (a joint-space swing, which can fling a rim-held plate): a
/// small penalty, so a straight carry wins over a swinging one that is about as clear. Not a
/// whole [`UNLIFTABLE`]: that would rule out the IIWA's plate and dumbbell insertions from
/// behind the door, whose clear options all swing and which succeed with them.
const SHELF_SWING_PENALTY: f64 = 0.02;
/// Turns of a side-grasped object's gripper about the vertical (rad) on its way into bin 2,
/// tried in this order with each spot of [`BIN2_SIDE_SPOTS`].
const CARRY_YAWS: [f64; 5] = [0.0, 0.35, -0.35, 0.7, -0.7];
/// Top of bin 2's floor (m, docs/src/reference-facts.md §2.1).
const PICK_PLACE_FLOOR: f64 = 0.82;
/// Highest the origin of a side-grasped object is lowered to in bin 2 (m): under the bin's
/// 0.9 m success line, so the wrist stays as high as it can above the bin's walls.
const SIDE_RELEASE_Z: f64 = 0.885;
/// Height (m) of the trash can's wall tops (0.825 + 0.005 + 2 · 0.08 ≈ 0.9855) plus a margin:
/// the object's bottom is released here.
const OVER_TRASH_CAN_Z: f64 = 1.01;

/// Where the dumbbell is let go over the trash can, relative to the can's centre (x, y; m).
/// Released over the centre it tips away from the opening fingers (+x, +y) and often comes
/// to rest leaning on the can's rim, its origin above the 0.93 m in-can line; let go from here,
/// towards the robot and bin 1, it lands inside (with the fingers slid out level before
/// rising).
const DUMBBELL_DROP_OFFSET: [f64; 2] = [-0.02, -0.02];

/// The phases of the script, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    /// Not started.
    Start,
    /// To the pre-grasp, gripper open and turned to the grasp.
    Approach,
    /// The last stretch into the grasp pose.
    Descend,
    /// Closing the fingers.
    Close,
    /// Lifting the object.
    Lift,
    /// Carrying it towards the objective's target.
    Transport,
    /// The objective's placing motion (lower into the bin; slide to the goal; over the can).
    Place,
    /// Pushing the object to the goal without a grasp (see `expert/nudge.rs`).
    Nudge,
    /// Opening the fingers.
    Release,
    /// Moving the gripper away.
    Retreat,
    /// Holding still until the episode ends.
    Done,
}

/// Where planning stands (the last planned joints, pad and orientation, and the plan's
/// length): trial plans are rewound to it.
#[derive(Clone, Copy)]
struct PlanMark {
    q: Option<[f64; ARM_DOF]>,
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    len: usize,
}

/// A way into the shelf.
#[derive(Debug, Clone, Copy, PartialEq)]
enum ShelfWay {
    /// Through its front (y 0.14, facing the robot's bins): the object on the lane at x (m),
    /// the gripper turned by the yaw (rad; see [`SHELF_YAWS`]) from pointing +y.
    Front { x: f64, yaw: f64 },
    /// Through its end nearest the robot (x −0.1; the shelf is open at both ends), the gripper
    /// level and pointing +x: the wrist and forearm stay on the robot's side of the end, clear
    /// of the goal wall, which ends at the same x. A top-grasped object's fingers close along
    /// `closing` · y (±1). With `out_first` the object goes out past the end where it was lifted
    /// and along it from there, else straight to the corner of the shelf's front and end.
    NearEnd { closing: f64, out_first: bool },
}

/// Whether the object stands behind the object wall or the door (both passed over).
fn behind_wall(obstacle: Obstacle) -> bool {
    matches!(obstacle, Obstacle::ObjectWall | Obstacle::ObjectDoor)
}

/// The scripted expert of one task.
pub struct Expert {
    task: TaskSpec,
    phase: Phase,
    /// Planned actions not yet sent.
    plan: VecDeque<Action>,
    /// The joints of the last planned target (the next segment's IK seed).
    q: Option<[f64; ARM_DOF]>,
    /// The pads' centre at the end of the last planned segment.
    pad: Vector3<f64>,
    /// The grip site orientation at the end of the last planned segment.
    orientation: UnitQuaternion<f64>,
    /// The gripper opening last commanded.
    gripper: f64,
    /// The grasp being executed.
    grasp: Option<Grasp>,
    /// Where the object was when the grasp was planned (m).
    grasp_object: Point3<f64>,
    /// The arm's distance to the arena, for choosing among IK solutions.
    clearance: Clearance,
    /// Orientations of grasps that did not lift the object (not tried again).
    failed: Vec<UnitQuaternion<f64>>,
    /// The pads' height when the lift began (m).
    lift_start_pad_z: f64,
    /// Whether a segment planned since this was last cleared ends short of its pose (the
    /// IK found no joints for it).
    missed: bool,
    /// Whether every segment planned since this was last set follows its straight line (none
    /// needed a joint-space move, whose curved path can drag a held object over the floor).
    straight: bool,
    /// Whether the object has been set down and grasped again.
    regrasped: bool,
    /// Points a push without a grasp takes the object through before the goal.
    via: Vec<Point2<f64>>,
    /// The way into the shelf last planned.
    shelf_way: Option<ShelfWay>,
}

impl Expert {
    /// The expert of `task`; call [`Expert::act`] once per control step.
    pub fn new(task: TaskSpec) -> Expert {
        Expert {
            task,
            phase: Phase::Start,
            plan: VecDeque::new(),
            q: None,
            pad: Vector3::zeros(),
            orientation: UnitQuaternion::identity(),
            gripper: open(),
            grasp: None,
            grasp_object: Point3::origin(),
            clearance: Clearance::new(robot_model(task.robot), task.objective, task.obstacle),
            failed: Vec::new(),
            lift_start_pad_z: 0.0,
            missed: false,
            straight: true,
            regrasped: false,
            via: Vec::new(),
            shelf_way: None,
        }
    }

    /// The phase the expert is in.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The next action for the environment's current state.
    pub fn act(&mut self, env: &Env) -> Action {
        while self.plan.is_empty() && self.phase != Phase::Done {
            self.next_phase(env);
        }
        match self.plan.pop_front() {
            Some(action) => action,
            None => Action::Absolute {
                joints: self.q.unwrap_or_else(|| env.world().arm_positions()),
                gripper: Some((self.gripper, 0.0)),
            },
        }
    }

    /// How long the approach, grasp and lift take, as a fraction of the usual: grasping a
    /// set-down object again must fit in what is left of the episode.
    fn pace(&self) -> f64 {
        if self.regrasped { REGRASP_PACE } else { 1.0 }
    }

    /// Where the current grasp sets the object down, to be grasped again (Push with a side grasp
    /// past the goal wall: no single heading keeps the wrist clear of it all the way): just past
    /// the wall's free end. None once grasped again, for objects grasped from the top, and where
    /// the object is pushed without a grasp.
    fn relocation(&self) -> Option<[f64; 2]> {
        let task = self.task;
        let side_grasped = matches!(task.object, Object::Plate | Object::Dumbbell);
        let relocates = task.objective == Objective::Push
            && task.obstacle == Obstacle::GoalWall
            && side_grasped
            && !self.regrasped
            && !self.nudges();
        relocates.then_some(GOAL_WALL_SPOT)
    }

    /// Whether the object is pushed without a grasp ([`super::nudge`]): the plate and the
    /// dumbbell from behind the object wall or the door, where no side grasp keeps the low
    /// wrist off the wall (`reach.rs` checks that pose by pose); round the goal wall only by the
    /// Panda, whose two-grasp plan does not fit in the episode (the other arms do better with
    /// two grasps there).
    fn nudges(&self) -> bool {
        let task = self.task;
        let side_grasped = matches!(task.object, Object::Plate | Object::Dumbbell);
        let past = behind_wall(task.obstacle)
            || task.obstacle == Obstacle::GoalWall && task.robot == Robot::Panda;
        task.objective == Objective::Push && side_grasped && past
    }

    /// Plans the next leg of a push without a grasp from where the pads and the object are
    /// now, the fingers' closing axis kept across the push; done once the object is at the goal.
    fn nudge_leg(&mut self, env: &Env, model: &RobotModel, object: Point3<f64>) {
        let (pad, _) = pads_at(model, &env.world().arm_positions());
        if self.via.first().is_some_and(|v| nudge::passed(object, v)) {
            self.via.remove(0);
        }
        let (target, u) = match nudge::leg(self.task.object, object, self.nudge_target(env), pad) {
            nudge::Leg::To(target, u) => (target, u),
            nudge::Leg::Done => {
                self.phase = Phase::Done;
                return;
            }
            nudge::Leg::Lost => {
                // Up clear of the object, then set the fingers behind it again.
                let up = Vector3::new(self.pad.x, self.pad.y, self.pad.z + NUDGE_LOST_RISE);
                self.segment(model, up, self.orientation, 0.6);
                self.phase = Phase::Start;
                return;
            }
        };
        let across = u.cross(&Vector3::z());
        let current = gripper_closing_axis(&self.orientation);
        let closing = if across.dot(&current) >= 0.0 {
            across
        } else {
            -across
        };
        // The lean so far, unless another keeps the arm clearer of the walls on this leg
        // (the nearest such).
        let mut orientations = nudge::pusher_orientations(self.task.object, u, closing);
        let now = self.orientation;
        orientations.sort_by(|a, b| a.angle_to(&now).total_cmp(&b.angle_to(&now)));
        let t = Vector3::new(target.x, target.y, self.pad.z);
        self.first_clear(model, &orientations, |e, orientation| {
            e.segment(model, t, orientation, NUDGE_LEG_SECONDS);
        });
    }

    /// Where a push without a grasp takes the object next: the first point on its way, else
    /// the goal.
    fn nudge_target(&self, env: &Env) -> Point2<f64> {
        self.via.first().copied().unwrap_or_else(|| env.goal().xy())
    }

    /// The object-centre height (m) a side-grasped object resting at `rest` (or any object past
    /// the goal wall) is carried at while pushing.
    fn push_carry_z(&self, rest: f64) -> f64 {
        if self.task.object == Object::Dumbbell {
            rest + DUMBBELL_PUSH_LIFT
        } else {
            PUSH_SIDE_CARRY_Z.max(rest + PUSH_LIFT)
        }
    }

    /// Whether the grasp is a top-down one.
    fn top_down(&self) -> bool {
        self.grasp.is_none_or(|g| g.top_down)
    }

    /// Plans the segments of the phase after the current one.
    fn next_phase(&mut self, env: &Env) {
        let model = env.world().model;
        let obs = env.observation();
        let object = Point3::from(obs.object.position);
        let [x, y, z, w] = obs.object.orientation;
        let object_rotation = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        let task = self.task;
        let walled = behind_wall(task.obstacle);
        let goal_wall = task.obstacle == Obstacle::GoalWall;
        let bottom = object_geometry(task.object).bottom_offset;
        match self.phase {
            Phase::Start => {
                let q = env.world().arm_positions();
                self.q = Some(q);
                (self.pad, self.orientation) = pads_at(model, &q);
                self.phase = Phase::Approach;
                // The Panda's forearm hangs low over walls near the robot unless the gripper
                // leans; the other arms clear them with a vertical gripper.
                let near_wall = walled || (goal_wall && task.objective == Objective::Push);
                let tilt = if task.robot == Robot::Panda && near_wall {
                    GRASP_TILT
                } else {
                    0.0
                };
                let headings = if self.regrasped {
                    Headings::Regrasp
                } else {
                    Headings::TowardsBin2
                };
                let candidates = if self.nudges() {
                    self.via = nudge::route(task.object, task.obstacle, object, env.goal().xy());
                    nudge::pushers(task.object, object, self.nudge_target(env))
                } else {
                    grasp_candidates(&GraspInput {
                        model,
                        q,
                        object: task.object,
                        objective: task.objective,
                        obstacle: task.obstacle,
                        position: object,
                        rotation: object_rotation,
                        tilt,
                        headings,
                        plate_pitch: PlatePitch::Level,
                    })
                };
                if candidates.is_empty() {
                    // Pushed without a grasp, the object is already at the goal.
                    self.phase = Phase::Done;
                    return;
                }
                // Grasps that already failed go last.
                let (mut candidates, tried): (Vec<Grasp>, Vec<Grasp>) = candidates
                    .into_iter()
                    .partition(|g| self.failed.iter().all(|f| f.angle_to(&g.orientation) > 0.1));
                candidates.extend(tried);
                self.grasp_object = object;
                // Where the object is carried (or pushed) straight on from the grasp (to the
                // goal after a regrasp; to the next point on the way of a push without a
                // grasp): that carry must keep clear too.
                let carry_to = if task.objective != Objective::Push {
                    None
                } else if self.nudges() {
                    Some(self.nudge_target(env))
                } else if self.regrasped {
                    Some(env.goal().xy())
                } else {
                    None
                };
                let clear_z = if walled {
                    OVER_OBJECT_WALL_Z
                } else if self.regrasped {
                    // Turning to the new grasp over the goal wall, not beside it.
                    OVER_GOAL_WALL_Z
                } else {
                    object.z + 0.12
                };
                // The first grasp (in the planner's order of preference) whose whole approach
                // keeps clear of the arena, else the one coming closest to that. Of the ways
                // to push without a grasp, the quickest that keeps clear: the other way round
                // may need a turn of the whole arm (the Jaco's: 9 s of 25).
                let nudging = self.nudges();
                let start = (self.pad, self.orientation);
                let mut best: Option<(Grasp, f64, usize)> = None;
                for grasp in candidates {
                    let gap = self.plan_approach(model, &grasp, clear_z, carry_to);
                    let clear = gap >= MIN_CLEARANCE;
                    if clear && !nudging {
                        best = None;
                        break;
                    }
                    let steps = self.plan.len();
                    let better = best.is_none_or(|(_, b, n)| {
                        let best_clear = b >= MIN_CLEARANCE;
                        if clear && best_clear {
                            steps < n
                        } else {
                            !best_clear && (clear || gap > b)
                        }
                    });
                    if better {
                        best = Some((grasp, gap, steps));
                    }
                    self.plan.clear();
                    self.q = Some(q);
                    (self.pad, self.orientation) = start;
                }
                if let Some((grasp, _, _)) = best {
                    self.plan_approach(model, &grasp, clear_z, carry_to);
                }
            }
            Phase::Approach => {
                self.phase = Phase::Descend;
                let grasp = self.grasp.expect("planned");
                // The object may have been nudged since the plan: keep the grasp's offset.
                let pad = grasp.pad + (object - self.grasp_object);
                self.grasp_object = object;
                self.segment(model, pad, self.orientation, 1.5 * self.pace());
            }
            Phase::Descend if self.nudges() => {
                self.phase = Phase::Nudge;
                self.nudge_leg(env, model, object);
            }
            Phase::Nudge => self.nudge_leg(env, model, object),
            Phase::Descend => {
                self.phase = Phase::Close;
                self.gripper = closed(model);
                self.hold(0.6);
            }
            Phase::Close => {
                self.phase = Phase::Lift;
                let rest = self.grasp_object.z;
                let lift_to = match task.objective {
                    Objective::Push if self.top_down() && !goal_wall => rest + PUSH_LIFT,
                    // Side grasps hold the wrist low, and round the goal wall the forearm
                    // passes over the wall's free end: carry as high as Push allows.
                    Objective::Push => self.push_carry_z(rest),
                    _ if goal_wall => OVER_GOAL_WALL_Z,
                    _ if walled => OVER_OBJECT_WALL_Z,
                    _ => CARRY_Z,
                };
                // Where nothing has to be cleared on the way to bin 2 or the shelf, a lower
                // carry if the arm cannot lift the object that high with this grasp (lifting
                // into an unreachable pose drags the object over the floor instead).
                let lower_ok = !walled
                    && !goal_wall
                    && matches!(task.objective, Objective::PickPlace | Objective::Shelf);
                let mut heights = vec![lift_to];
                if lower_ok {
                    heights.extend(LOWER_CARRIES_Z);
                }
                let offset = self.pad - self.grasp_object.coords;
                self.lift_start_pad_z = self.pad.z;
                let (x, y, o) = (self.pad.x, self.pad.y, self.orientation);
                let seconds = 1.5 * self.pace();
                self.first_straight(&heights, |e, z| {
                    e.segment(model, Vector3::new(x, y, z + offset.z), o, seconds);
                });
            }
            Phase::Lift => {
                // The object did not come up with the gripper: open, back off and try the
                // next grasp from where the object now is.
                let expected = self.pad.z - self.lift_start_pad_z;
                let risen = object.z - self.grasp_object.z;
                if expected > 0.02 && risen < 0.4 * expected && self.failed.len() < MAX_RETRIES {
                    let grasp = self.grasp.expect("planned");
                    self.failed.push(grasp.orientation);
                    self.gripper = grasp.open;
                    self.hold(0.4);
                    let back = self.pad - grasp.approach * 0.06 + Vector3::z() * 0.06;
                    self.segment(model, back, self.orientation, 1.0);
                    self.phase = Phase::Start;
                    return;
                }
                self.phase = Phase::Transport;
                let h = self.pad.z;
                let o = self.orientation;
                // The pads relative to the object, so targets can name where the object goes.
                let held = self.pad - object.coords;
                match task.objective {
                    Objective::Push if let Some([x, y]) = self.relocation() => {
                        // Round the goal wall's free end to the spot where the object is set
                        // down and grasped again.
                        let spot = Vector3::new(x, y, 0.0) + held;
                        let radius = object_geometry(task.object).horizontal_radius;
                        let lane = AROUND_GOAL_WALL_X.min(BIN2_FAR_WALL_X - radius - 0.01);
                        let lane = lane + held.x;
                        self.segment(model, Vector3::new(lane, self.pad.y, h), o, 0.8);
                        self.segment(model, Vector3::new(lane, spot.y, h), o, 1.5);
                        self.segment(model, Vector3::new(spot.x, spot.y, h), o, 1.5);
                    }
                    Objective::Push => {
                        // Straight to the goal, or round a lane at x (the goal wall's free
                        // end; bin 2's near wall for a low wrist): the first that keeps clear.
                        let goal = env.goal();
                        let t = Vector3::new(goal.x + held.x, goal.y + held.y, h);
                        let lanes: &[Option<f64>] = if self.top_down() {
                            // The box's fingertips pass just over the floor: straight, no
                            // clearance check. Past the goal wall (carried high) the first lane
                            // that keeps clear; the nearer one for arms that do not reach
                            // the other with the gripper pointing down this low.
                            if goal_wall {
                                &[Some(AROUND_GOAL_WALL_X), Some(NEAR_GOAL_WALL_X)]
                            } else {
                                &[None]
                            }
                        } else if goal_wall {
                            // A side-grasped object comes here only grasped again past the
                            // wall (see `relocation`): straight on.
                            &[None]
                        } else {
                            &[None, Some(AROUND_GOAL_WALL_X), Some(PUSH_WIDE_LANE_X)]
                        };
                        // Past the goal wall the gripper may lean (its wrist towards +y) so
                        // the wrist and forearm clear the wall's top behind the goal.
                        let leans: &[f64] = if goal_wall && self.top_down() {
                            &PUSH_LEANS
                        } else {
                            &[0.0]
                        };
                        let options: Vec<(Option<f64>, f64)> = leans
                            .iter()
                            .flat_map(|&lean| lanes.iter().map(move |&lane| (lane, lean)))
                            .collect();
                        self.first_clear(model, &options, |e, (lane, lean)| {
                            let leaning =
                                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), -lean) * o;
                            if let Some(lane) = lane {
                                // The object itself must pass inside bin 2's far wall.
                                let radius = object_geometry(task.object).horizontal_radius;
                                let lane = lane.min(BIN2_FAR_WALL_X - radius - 0.01) + held.x;
                                let y = e.pad.y;
                                e.segment(model, Vector3::new(lane, y, h), o, 1.0);
                                e.segment(model, Vector3::new(lane, t.y - 0.03, h), leaning, 2.0);
                            }
                            e.segment(model, t, leaning, 2.0);
                        });
                    }
                    Objective::PickPlace if !self.top_down() => {
                        // Carry and lower in one go, to the first spot in bin 2 the arm
                        // reaches without touching the bin's walls (the wrist is behind and
                        // below the gripper); success comes as soon as the object's origin is
                        // under the bin's 0.9 m line with the gripper on it.
                        // The gripper may turn about the vertical on the way (the object swings
                        // round the pads): where the straight carry runs into a joint limit,
                        // the arm swings through joint space instead and flings a plate held
                        // by its rim out of the fingers (the Panda's, from behind the door).
                        let z = (PICK_PLACE_FLOOR - bottom + DROP_GAP).min(SIDE_RELEASE_Z);
                        let options: Vec<([f64; 2], f64)> = CARRY_YAWS
                            .iter()
                            .flat_map(|&yaw| BIN2_SIDE_SPOTS.iter().map(move |&s| (s, yaw)))
                            .collect();
                        self.first_clear_straight(model, &options, |e, ([x, y], yaw)| {
                            let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
                            let (o, held) = (turn * o, turn * held);
                            let t = Vector3::new(x, y, z) + held;
                            e.segment(model, Vector3::new(t.x, t.y, h), o, 2.0);
                            e.segment(model, t, o, 1.5);
                        });
                    }
                    Objective::PickPlace => {
                        let bin = objective_arena(Objective::PickPlace).bin2_position;
                        let t = Vector3::new(bin[0] + held.x, bin[1] + held.y, h);
                        self.segment(model, t, o, 2.0);
                    }
                    Objective::Shelf if !self.top_down() => {
                        self.shelf_side(model, h, held, bottom, goal_wall);
                    }
                    Objective::Shelf => {
                        // In front of the shelf, down to the opening's height, turned to it and
                        // in. With the goal wall, on the first lane past the wall's free end
                        // along which the arm keeps clear of the arena (the forearm behind the
                        // sideways gripper crosses the wall's line below its top).
                        let z = SHELF.position[2] + SHELF.z_offset + SHELF_INSERT_HEIGHT;
                        let (front_y, turn_high) = shelf_approach(task.robot);
                        let options = shelf_top_options(goal_wall);
                        let plan = |e: &mut Self, way: ShelfWay| {
                            e.shelf_way = Some(way);
                            let (x, yaw) = match way {
                                ShelfWay::Front { x, yaw } => (x, yaw),
                                ShelfWay::NearEnd { closing, out_first } => {
                                    let (reached, held) =
                                        e.shelf_near_end(model, h, held, z, (closing, out_first));
                                    let reached = e.slide_in_near_end(model, held) && reached;
                                    e.missed |= !reached && !goal_wall;
                                    return;
                                }
                            };
                            let sideways = |o: &UnitQuaternion<f64>| {
                                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw)
                                    * turned_to_shelf(o)
                            };
                            e.segment(model, Vector3::new(x, front_y, h), o, 2.0);
                            let o = if turn_high {
                                let sideways = sideways(&o);
                                e.segment(model, Vector3::new(x, front_y, h), sideways, 2.0);
                                sideways
                            } else {
                                o
                            };
                            e.segment(model, Vector3::new(x, front_y, z), o, 1.5);
                            if !turn_high {
                                e.segment(model, e.pad, sideways(&o), 2.0);
                            }
                            let mut reached = e.reached(model) < SHELF_REACH_ERROR;
                            let inside = SHELF.position[1] - SHELF.y_size + SHELF_INSERT_DEPTH;
                            let t = Vector3::new(e.pad.x, inside, e.pad.z);
                            e.segment(model, t, e.orientation, 2.0);
                            reached &= e.reached(model) < SHELF_SLIDE_SHORT;
                            // Not only for the plate: an option whose poses are out of reach
                            // goes after every reachable one.
                            e.missed |= !reached && !goal_wall;
                        };
                        // The first option unless the arm would run well into the arena
                        // along it: the model's near misses mostly work, and the other
                        // options then do worse.
                        // Past the goal wall, the first lane that keeps clear.
                        let front = |e: &mut Self| {
                            let start = e.mark();
                            e.missed = false;
                            plan(e, options[0]);
                            let gap = e.plan_clearance(model, start.len);
                            if goal_wall || e.missed || gap < SHELF_TOP_OTHERS_BELOW {
                                e.rewind(start);
                                e.first_clear(model, &options, plan)
                            } else {
                                gap
                            }
                        };
                        let ends = near_end_ways(true);
                        self.shelf_way(front, |e| e.first_clear(model, &ends, plan));
                    }
                    Objective::TrashCan => {
                        let [cx, cy, _] = TRASH_CAN.position;
                        let [dx, dy] = if task.object == Object::Dumbbell {
                            DUMBBELL_DROP_OFFSET
                        } else {
                            [0.0, 0.0]
                        };
                        let over = Vector3::new(cx + dx, cy + dy, h);
                        if self.top_down() {
                            self.segment(model, over + held.xy().push(0.0), o, 2.0);
                        } else {
                            // As into bin 2: turned about the vertical where the straight
                            // carry would run into a joint limit.
                            self.first_clear_straight(model, &CARRY_YAWS, |e, yaw| {
                                let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
                                let t = over + (turn * held).xy().push(0.0);
                                e.segment(model, t, turn * o, 2.0);
                            });
                        }
                    }
                }
            }
            Phase::Transport => {
                self.phase = Phase::Place;
                let held = self.pad - object.coords;
                match task.objective {
                    _ if self.relocation().is_some() => {
                        // Down to where it rested, pressed a little into the floor.
                        let z = self.grasp_object.z - SET_DOWN_PRESS + held.z;
                        let t = Vector3::new(self.pad.x, self.pad.y, z);
                        self.segment(model, t, self.orientation, 1.0);
                    }
                    Objective::Shelf
                        if matches!(self.shelf_way, Some(ShelfWay::NearEnd { .. }))
                            && !self.top_down() =>
                    {
                        self.slide_in_near_end(model, held);
                    }
                    Objective::Shelf if !self.top_down() => {
                        let t = Vector3::new(self.pad.x, SHELF_SIDE_TARGET_Y + held.y, self.pad.z);
                        self.segment(model, t, self.orientation, 2.0);
                    }
                    // Planned with the lane.
                    Objective::Shelf => self.hold(0.1),
                    Objective::PickPlace if !self.top_down() => self.hold(0.2),
                    Objective::PickPlace => {
                        // Bring the object's bottom 1.5 cm above bin 2's floor.
                        let target_z = PICK_PLACE_FLOOR - bottom + DROP_GAP;
                        let t = Vector3::new(self.pad.x, self.pad.y, target_z + held.z);
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    Objective::Push => self.hold(0.3),
                    Objective::TrashCan => {
                        // Just above the can's walls before letting go.
                        let t = Vector3::new(
                            self.pad.x,
                            self.pad.y,
                            OVER_TRASH_CAN_Z - bottom + held.z,
                        );
                        let t = if goal_wall { self.pad } else { t };
                        self.segment(model, t, self.orientation, 1.0);
                    }
                }
            }
            Phase::Place => {
                self.phase = Phase::Release;
                self.gripper = open();
                self.hold(if self.relocation().is_some() {
                    0.4
                } else {
                    0.8
                });
            }
            Phase::Release => {
                self.phase = Phase::Retreat;
                let back = self.grasp.map_or(Vector3::zeros(), |g| -g.approach);
                if self.relocation().is_some() {
                    // Back out of the grasp and up, then grasp the object again.
                    let t = self.pad + back * 0.07 + Vector3::z() * 0.04;
                    self.segment(model, t, self.orientation, 1.0);
                    self.regrasped = true;
                    self.failed.clear();
                    self.phase = Phase::Start;
                    return;
                }
                match task.objective {
                    Objective::TrashCan if !self.top_down() => {
                        // The open fingers may still hold the dumbbell's upper disc: slide them
                        // out level first (the object drops into the can), then rise — back
                        // along the gripper's approach axis as it is turned now.
                        let approach = self.orientation * Vector3::z();
                        let level = -Vector3::new(approach.x, approach.y, 0.0).normalize();
                        let out = self.pad + level * 0.07;
                        self.segment(model, out, self.orientation, 1.0);
                        self.segment(model, out + Vector3::z() * 0.1, self.orientation, 1.0);
                    }
                    Objective::TrashCan => {
                        let t = Vector3::new(self.pad.x, self.pad.y - 0.05, self.pad.z + 0.12);
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    Objective::Shelf
                        if matches!(self.shelf_way, Some(ShelfWay::NearEnd { .. })) =>
                    {
                        // Back out through the end.
                        let t = self.pad - Vector3::x() * 0.12;
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    Objective::Shelf if self.top_down() => {
                        let t = Vector3::new(self.pad.x, shelf_approach(task.robot).0, self.pad.z);
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    Objective::Shelf => {
                        let t = self.pad + back * 0.12;
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    _ => self.hold(0.2),
                }
            }
            Phase::Retreat | Phase::Done => self.phase = Phase::Done,
        }
    }

    /// Shelf, side grasp: in front of the shelf on the first (lane, yaw) of
    /// [`shelf_side_options`] along which the arm — including the slide in, planned only
    /// later from where the object then is — keeps clear of the arena and reaches its poses,
    /// else the one coming closest.
    fn shelf_side(
        &mut self,
        model: &RobotModel,
        h: f64,
        held: Vector3<f64>,
        bottom: f64,
        goal_wall: bool,
    ) {
        // Planned as `shelf_front` plans: the slide in only on trial (and then rewound), later
        // from where the object then is.
        let near_end = |e: &mut Self, out_first: bool, trial: bool| {
            let from = e.plan.len();
            let z = shelf_side_release_z(bottom);
            let (mut reached, held) = e.shelf_near_end(model, h, held, z, (1.0, out_first));
            if !trial {
                return 0.0;
            }
            let at = e.mark();
            reached &= e.slide_in_near_end(model, held);
            let gap = e.plan_clearance(model, from);
            e.rewind(at);
            if reached { gap } else { gap - UNREACHED }
        };
        let trial = |e: &mut Self, way| {
            e.shelf_way = Some(way);
            e.straight = true;
            let gap = match way {
                ShelfWay::Front { x, yaw } => e.shelf_front(model, h, held, bottom, (x, yaw), true),
                ShelfWay::NearEnd { out_first, .. } => near_end(e, out_first, true),
            };
            if e.straight {
                gap
            } else {
                gap - SHELF_SWING_PENALTY
            }
        };
        let plan = |e: &mut Self, way| {
            e.shelf_way = Some(way);
            match way {
                ShelfWay::Front { x, yaw } => {
                    e.shelf_front(model, h, held, bottom, (x, yaw), false);
                }
                ShelfWay::NearEnd { out_first, .. } => {
                    near_end(e, out_first, false);
                }
            }
        };
        let (fronts, ends) = (shelf_side_options(goal_wall), near_end_ways(false));
        self.shelf_way(
            |e| e.first_with_gap(&fronts, trial, plan),
            |e| e.first_with_gap(&ends, trial, plan),
        );
    }

    /// Plans the way into the shelf through its front that `front` plans (returning its gap to
    /// the arena), unless, past the goal wall, the arm then runs into the arena by more than
    /// [`SHELF_FRONT_MISS`]: then the way through the near end that `near_end` plans, where its
    /// gap is larger. (Only past the goal wall: behind the object wall and the door the near end
    /// does worse.)
    fn shelf_way(&mut self, front: impl Fn(&mut Self) -> f64, near_end: impl Fn(&mut Self) -> f64) {
        let start = self.mark();
        let gap = front(self);
        if gap >= SHELF_FRONT_MISS || self.task.obstacle != Obstacle::GoalWall {
            return;
        }
        self.rewind(start);
        if near_end(self) > gap {
            return;
        }
        self.rewind(start);
        front(self);
    }

    /// Plans the carry to in front of the shelf with the object clear of its front (y 0.14),
    /// the object at x on the lane, the gripper turned by `yaw` about the vertical (see
    /// [`SHELF_YAWS`]), then down to the opening's height. With `trial` also the slide in,
    /// rewound after its clearance is counted; returns the plan's smallest clearance, less
    /// [`UNREACHED`] if the lowered pose or the slide's end is out of reach.
    fn shelf_front(
        &mut self,
        model: &RobotModel,
        h: f64,
        held: Vector3<f64>,
        bottom: f64,
        (x, yaw): (f64, f64),
        trial: bool,
    ) -> f64 {
        let from = self.plan.len();
        let o = self.orientation;
        let radius = object_geometry(self.task.object).horizontal_radius;
        let front = shelf_front_y() - radius - 0.03;
        let z = shelf_side_release_z(bottom);
        // The gripper turns level on the way: pitched down, its wrist rides
        // above the pads and meets the shelf's top block before the object is
        // in (the object tilts with it, its far side up, well inside the
        // 15.5 cm opening).
        let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw) * levelling(&o);
        let (o, held) = (turn * o, turn * held);
        let level = Vector3::new(held.x, held.y, 0.0);
        self.segment(model, Vector3::new(x, front, h) + level, o, 2.0);
        // (Whether the pose above is met matters less: the arm gets there on the way down.)
        self.segment(model, Vector3::new(x, front, z) + held, o, 1.5);
        let mut reached = self.reached(model) < SHELF_REACH_ERROR;
        if trial {
            let at = self.mark();
            let t = Vector3::new(x, SHELF_SIDE_TARGET_Y, z) + held;
            self.segment(model, t, o, 2.0);
            // A slide in that ends a few cm short still puts the object in.
            reached &= self.reached(model) < SHELF_SLIDE_SHORT;
            let gap = self.plan_clearance(model, from);
            self.rewind(at);
            if reached { gap } else { gap - UNREACHED }
        } else {
            0.0
        }
    }

    /// Plans the way to the shelf's near end ([`ShelfWay::NearEnd`]): turned level and pointing
    /// +x on the way out past the end at the carry height (pads at `h`), then over to the middle
    /// of the shelf's depth and down until the object's origin is at `z`. Returns whether the
    /// arm reaches that pose, and the pads relative to the object as turned.
    fn shelf_near_end(
        &mut self,
        model: &RobotModel,
        h: f64,
        held: Vector3<f64>,
        z: f64,
        (closing, out_first): (f64, bool),
    ) -> (bool, Vector3<f64>) {
        let o = self.orientation;
        let object = self.pad - held;
        let turned = if self.top_down() {
            gripper_orientation(Vector3::x(), Vector3::y() * closing)
        } else {
            // Side grasps keep their closing axis: level, then about the vertical.
            let level = levelling(&o) * o;
            let a = level * Vector3::z();
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), -a.y.atan2(a.x)) * level
        };
        let held = (turned * o.inverse()) * held;
        let geometry = object_geometry(self.task.object);
        // A top-grasped object turned this way lies with its height along x.
        let extent = if self.top_down() {
            geometry.top_offset.max(-geometry.bottom_offset)
        } else {
            geometry.horizontal_radius
        };
        let outside = shelf_near_end_x() - extent - SHELF_NEAR_END_CLEAR + held.x;
        let y = SHELF_SIDE_TARGET_Y + held.y;
        if out_first {
            self.segment(
                model,
                Vector3::new(outside, object.y + held.y, h),
                turned,
                2.0,
            );
        } else {
            // Over the goal wall, to the corner of the shelf's front and near end.
            let front = shelf_front_y() - extent - SHELF_NEAR_END_CLEAR;
            self.segment(model, Vector3::new(outside, front + held.y, h), turned, 2.5);
        }
        self.segment(model, Vector3::new(outside, y, z + held.z), turned, 2.0);
        (self.reached(model) < SHELF_REACH_ERROR, held)
    }

    /// The slide in through the shelf's near end, with the pads at `held` from the object;
    /// returns whether the arm gets within [`SHELF_SLIDE_SHORT`] of its end.
    fn slide_in_near_end(&mut self, model: &RobotModel, held: Vector3<f64>) -> bool {
        let inside = shelf_near_end_x() + SHELF_NEAR_END_DEPTH + held.x;
        let t = Vector3::new(inside, self.pad.y, self.pad.z);
        self.segment(model, t, self.orientation, 2.0);
        self.reached(model) < SHELF_SLIDE_SHORT
    }

    /// How far (m) the last planned joints put the pads from where they were planned to be.
    fn reached(&self, model: &RobotModel) -> f64 {
        let (pad, _) = pads_at(model, &self.q.expect("planned"));
        (pad - self.pad).norm()
    }

    /// Keeps the last target for `seconds`, with the current gripper command.
    fn hold(&mut self, seconds: f64) {
        let q = self.q.expect("planned from a known pose");
        for _ in 0..steps(seconds) {
            self.plan.push_back(Action::Absolute {
                joints: q,
                gripper: Some((self.gripper, 0.0)),
            });
        }
    }

    /// Plans `plan(self, option)` for the first of `options` whose motion keeps
    /// [`MIN_CLEARANCE`] from the arena, else for the one coming closest.
    fn first_clear<T: Copy>(
        &mut self,
        model: &RobotModel,
        options: &[T],
        plan: impl Fn(&mut Self, T),
    ) -> f64 {
        self.first_clear_ranked(model, options, false, plan)
    }

    /// As [`Expert::first_clear`], but an option along which some segment leaves its straight
    /// line (a joint-space move, for a joint limit in the way) ranks [`UNLIFTABLE`] closer to
    /// the arena.
    fn first_clear_straight<T: Copy>(
        &mut self,
        model: &RobotModel,
        options: &[T],
        plan: impl Fn(&mut Self, T),
    ) -> f64 {
        self.first_clear_ranked(model, options, true, plan)
    }

    /// [`Expert::first_clear`], with `straight_first` that of [`Expert::first_clear_straight`].
    fn first_clear_ranked<T: Copy>(
        &mut self,
        model: &RobotModel,
        options: &[T],
        straight_first: bool,
        plan: impl Fn(&mut Self, T),
    ) -> f64 {
        let from = self.plan.len();
        self.first_with_gap(
            options,
            |e, option| {
                (e.missed, e.straight) = (false, true);
                plan(e, option);
                let gap = e.plan_clearance(model, from);
                let gap = if e.straight || !straight_first {
                    gap
                } else {
                    gap - UNLIFTABLE
                };
                if e.missed { gap - UNREACHED } else { gap }
            },
            &plan,
        )
    }

    /// Keeps the plan of the first of `options` whose `trial` (which plans it and returns its
    /// gap to the arena) keeps [`MIN_CLEARANCE`]; else rewinds and plans the one with the
    /// largest gap with `plan`. Returns the gap of what it kept (−∞ without options).
    fn first_with_gap<T: Copy>(
        &mut self,
        options: &[T],
        trial: impl Fn(&mut Self, T) -> f64,
        plan: impl Fn(&mut Self, T),
    ) -> f64 {
        let start = self.mark();
        let mut best: Option<(T, f64)> = None;
        for &option in options {
            let gap = trial(self, option);
            if gap >= MIN_CLEARANCE {
                return gap;
            }
            if best.is_none_or(|(_, b)| gap > b) {
                best = Some((option, gap));
            }
            self.rewind(start);
        }
        match best {
            Some((option, gap)) => {
                plan(self, option);
                gap
            }
            None => f64::NEG_INFINITY,
        }
    }

    /// Where planning stands now.
    fn mark(&self) -> PlanMark {
        PlanMark {
            q: self.q,
            pad: self.pad,
            orientation: self.orientation,
            len: self.plan.len(),
        }
    }

    /// Drop what was planned after `mark` and continue from there.
    fn rewind(&mut self, mark: PlanMark) {
        (self.q, self.pad, self.orientation) = (mark.q, mark.pad, mark.orientation);
        self.plan.truncate(mark.len);
    }

    /// Plans `plan(self, option)` for the first of `options` whose segments all follow their
    /// straight lines, else for the first option.
    fn first_straight<T: Copy>(&mut self, options: &[T], plan: impl Fn(&mut Self, T)) {
        let start = self.mark();
        for &option in options {
            self.straight = true;
            plan(self, option);
            if self.straight {
                return;
            }
            self.rewind(start);
        }
        if let Some(&first) = options.first() {
            plan(self, first);
        }
    }

    /// The smallest clearance from the arena of the planned actions from `from` on.
    fn plan_clearance(&self, model: &RobotModel, from: usize) -> f64 {
        self.plan
            .iter()
            .skip(from)
            .map(|a| match a {
                Action::Absolute { joints, .. } => self.clearance.at(model, joints),
                Action::Reference(_) => f64::INFINITY,
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The smallest clearance from the arena along `path`.
    fn path_clearance(&self, model: &RobotModel, path: &[[f64; ARM_DOF]]) -> f64 {
        path.iter()
            .map(|q| self.clearance.at(model, q))
            .fold(f64::INFINITY, f64::min)
    }

    /// Plans the approach to `grasp`'s pre-grasp (up to `clear_z`, over, down) and returns the
    /// smallest clearance from the arena along it and along the last stretch into the grasp
    /// (which is planned only later, from where the object is then) and, with `carry_to`,
    /// along the carry of the lifted object straight to there (xy, m); less [`UNLIFTABLE`] if
    /// the gripper cannot then rise straight, less [`UNREACHED`] if a pose is out of reach
    /// (for the grasp itself: the pads end more than [`GRASP_MISS`] from it).
    fn plan_approach(
        &mut self,
        model: &RobotModel,
        grasp: &Grasp,
        clear_z: f64,
        carry_to: Option<Point2<f64>>,
    ) -> f64 {
        self.missed = false;
        self.grasp = Some(*grasp);
        self.gripper = grasp.open;
        let pre = grasp.pre();
        let clear = clear_z.max(pre.z);
        let mut rise = self.pad;
        rise.z = rise.z.max(clear);
        self.segment(model, rise, grasp.orientation, self.pace());
        self.segment(
            model,
            Vector3::new(pre.x, pre.y, clear),
            grasp.orientation,
            1.5 * self.pace(),
        );
        if pre.z < clear - 1e-6 {
            // At full time even after a regrasp: the pads must be at the pre-grasp, level
            // with the plate, before they slide in.
            self.segment(model, pre, grasp.orientation, 1.0);
        }
        let at_pre = self.mark();
        self.segment(model, grasp.pad, grasp.orientation, 1.5 * self.pace());
        // Pads that end well short of the grasp cannot close on the object, whatever the
        // clearance on the way (waypoints before it may end short: later segments recover).
        let (reached, _) = pads_at(model, &self.q.expect("planned from a known pose"));
        self.missed |= (reached - grasp.pad).norm() > GRASP_MISS;
        let gap = self.plan_clearance(model, 0);
        // The first stretch of the lift, not counted in the clearance (the object is lifted
        // off the floor): a grasp from which the gripper cannot rise straight would drag the
        // object over the floor.
        // Not behind the object wall or door, where the approach over the wall decides and a
        // grasp that needs a joint-space lift still works (measured: Panda/dumbbell/wall/shelf).
        self.straight = true;
        let rise = if self.task.objective == Objective::Push {
            PUSH_LIFT_CHECK
        } else {
            LIFT_CHECK
        };
        if !behind_wall(self.task.obstacle) {
            let lift = grasp.pad + Vector3::z() * rise;
            self.segment(model, lift, grasp.orientation, 1.0);
        }
        let liftable = self.straight;
        let gap = if let Some(to) = carry_to {
            let carry = (to - self.grasp_object.xy()).push(0.0);
            // Pushed without a grasp the object stays on the floor.
            let rest = self.grasp_object.z;
            let up = if self.nudges() {
                Vector3::zeros()
            } else {
                Vector3::z() * (self.push_carry_z(rest) - rest).max(0.0)
            };
            let from = self.plan.len();
            self.segment(model, grasp.pad + up, grasp.orientation, 1.0);
            self.segment(model, grasp.pad + up + carry, grasp.orientation, 2.0);
            gap.min(self.plan_clearance(model, from))
        } else {
            gap
        };
        self.rewind(at_pre);
        let gap = if liftable { gap } else { gap - UNLIFTABLE };
        if self.missed { gap - UNREACHED } else { gap }
    }

    /// Of the IK solutions for the pose, the first (least motion from `q`) that keeps
    /// [`MIN_CLEARANCE`] from the arena, else the one with the most clearance.
    fn best_solution(
        &self,
        model: &RobotModel,
        q: &[f64; ARM_DOF],
        pad: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Option<[f64; ARM_DOF]> {
        best_clear(
            &self.clearance,
            model,
            pad_ik_solutions(model, q, pad, orientation),
        )
        .map(|(q, _)| q)
    }

    /// Joints moved in a straight line (smoothstep) to `goal`, which puts the pads at `pad`
    /// with `orientation`.
    fn joint_move(
        &mut self,
        goal: [f64; ARM_DOF],
        pad: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        seconds: f64,
    ) {
        let q0 = self.q.expect("planned from a known pose");
        // The smoothstep's peak speed is 1.5 times the mean.
        let joints = &robot_model(self.task.robot).joints;
        let n = (0..ARM_DOF)
            .map(|j| {
                let rated = JOINT_MOVE_SPEED_FRACTION * joints[j].velocity * CONTROL_PERIOD;
                let peak_step = MAX_JOINT_STEP.max(rated);
                (1.5 * (goal[j] - q0[j]).abs() / peak_step).ceil() as usize
            })
            .fold(steps(seconds), usize::max);
        for joints in joint_path(&q0, &goal, n) {
            self.plan.push_back(Action::Absolute {
                joints,
                gripper: Some((self.gripper, 0.0)),
            });
        }
        self.q = Some(goal);
        self.pad = pad;
        self.orientation = orientation;
    }

    /// A straight line of the pads' centre to `pad` while turning to `orientation`.
    fn segment(
        &mut self,
        model: &RobotModel,
        pad: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        seconds: f64,
    ) {
        let (p0, r0) = (self.pad, self.orientation);
        let q0 = self.q.expect("planned from a known pose");
        let mut n = steps(seconds);
        // Pushing without a grasp, the fingers' way is the plan: no swinging the arm off the
        // arena (a swing at the turn round the goal wall lets the object slip out from between
        // the fingers).
        let nudging = self.nudges();
        let (mut line, mut all_met, mut end_met);
        loop {
            let mut q = q0;
            line = Vec::with_capacity(n);
            all_met = true;
            end_met = false;
            for k in 1..=n {
                let s = smoothstep(k as f64 / n as f64);
                let (to, turned) = (p0 + (pad - p0) * s, r0.slerp(&orientation, s));
                let (next, met) = if nudging {
                    pad_ik(model, &q, to, turned)
                } else {
                    pad_ik_clear(model, &self.clearance, &q, to, turned)
                };
                all_met &= met;
                end_met = met;
                q = next;
                line.push(q);
            }
            // Too fast for the joints' torque limits: the lagging joints would bend the path
            // (into a wall it was planned to pass over). Slow down, up to three times.
            let fastest = max_joint_step(&q0, &line);
            let limit = 3 * steps(seconds);
            if fastest <= MAX_JOINT_STEP || n >= limit {
                break;
            }
            n = ((n as f64 * fastest / MAX_JOINT_STEP).ceil() as usize).min(limit);
        }
        let q = *line.last().expect("at least one step");
        self.straight &= all_met;
        if !all_met && let Some(goal) = self.best_solution(model, &q0, pad, orientation) {
            // The straight line runs into a joint limit: move the joints straight instead —
            // unless the line still ends on its goal and the joint-space path comes closer to
            // the arena than the line (it may swing the gripper into a wall the line passes
            // over).
            let line_gap = self.path_clearance(model, &line);
            let joint_gap = self.path_clearance(model, &joint_path(&q0, &goal, n));
            let seconds = n as f64 * CONTROL_PERIOD;
            if !end_met || joint_gap >= line_gap.min(MIN_CLEARANCE) {
                self.joint_move(goal, pad, orientation, seconds);
                return;
            }
        }
        // A segment that ends short of its pose (no IK solution met it) marks the plan. Used
        // for the plate, where it steers the choice of rim grasps and bin spots to ones the arm
        // reaches, and for pushes without a grasp, whose fingers must get down behind the
        // object. Not for the dumbbell's grasps: there it would reject approaches that work
        // (the slide in ends within a few cm).
        self.missed |= !end_met && (self.task.object == Object::Plate || self.nudges());
        for joints in line {
            self.plan.push_back(Action::Absolute {
                joints,
                gripper: Some((self.gripper, 0.0)),
            });
        }
        self.q = Some(q);
        self.pad = pad;
        self.orientation = orientation;
    }
}

/// The largest joint change (rad) between consecutive targets of `path` (starting at `q0`).
fn max_joint_step(q0: &[f64; ARM_DOF], path: &[[f64; ARM_DOF]]) -> f64 {
    let mut prev = q0;
    let mut most = 0.0_f64;
    for q in path {
        most = most.max(distance_max(prev, q));
        prev = q;
    }
    most
}

/// The largest absolute joint difference (rad).
fn distance_max(a: &[f64; ARM_DOF], b: &[f64; ARM_DOF]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// `n` joint targets from `q0` (excluded) to `goal` in a straight line with a smoothstep law.
fn joint_path(q0: &[f64; ARM_DOF], goal: &[f64; ARM_DOF], n: usize) -> Vec<[f64; ARM_DOF]> {
    (1..=n)
        .map(|k| {
            let s = smoothstep(k as f64 / n as f64);
            std::array::from_fn(|j| q0[j] + (goal[j] - q0[j]) * s)
        })
        .collect()
}

/// The (lane x, yaw) options of a side-grasped object's way into the shelf, best first: each
/// lane with each of [`SHELF_YAWS`].
fn shelf_side_options(goal_wall: bool) -> Vec<ShelfWay> {
    let lanes: &[f64] = if goal_wall {
        &SHELF_SIDE_LANES_PAST_GOAL_WALL_X
    } else {
        &SHELF_LANES_X
    };
    lanes
        .iter()
        .flat_map(|&x| {
            SHELF_YAWS
                .iter()
                .map(move |&yaw| ShelfWay::Front { x, yaw })
        })
        .collect()
}

/// The (lane x, yaw) options of a top-grasped object's way into the shelf, best first (see
/// [`shelf_side_options`]); the first is the lane used before yaws were tried.
fn shelf_top_options(goal_wall: bool) -> Vec<ShelfWay> {
    if goal_wall {
        // Yaws gained nothing past the goal wall: the forearm meets the wall whichever way.
        return SHELF_LANES_PAST_GOAL_WALL_X
            .map(|x| ShelfWay::Front { x, yaw: 0.0 })
            .to_vec();
    }
    shelf_side_options(false)
}

/// The ways into the shelf through its near end, best first: to the corner of its front and
/// end, then out past the end first; a top-grasped object's fingers closing along +y, then −y.
fn near_end_ways(top_down: bool) -> Vec<ShelfWay> {
    let closings: &[f64] = if top_down { &[1.0, -1.0] } else { &[1.0] };
    [false, true]
        .iter()
        .flat_map(|&out_first| {
            closings
                .iter()
                .map(move |&closing| ShelfWay::NearEnd { closing, out_first })
        })
        .collect()
}

/// y (m) of the shelf's front, the face towards the robot's bins.
fn shelf_front_y() -> f64 {
    SHELF.position[1] - 2.0 * SHELF.y_size
}

/// The height (m) of a side-grasped object's origin where it is let go in the shelf: its
/// bottom (`bottom` below the origin) 2.5 cm above the board.
fn shelf_side_release_z(bottom: f64) -> f64 {
    SHELF.position[2] + SHELF.z_offset - bottom + DROP_GAP + 0.01
}

/// x (m) of the shelf's end nearest the robot.
fn shelf_near_end_x() -> f64 {
    SHELF.position[0] - SHELF.x_size
}

/// Where the box waits in front of the shelf (y, m; the opening starts at y 0.14) and whether
/// the gripper turns to the shelf there at the carry height (`true`) or only after lowering
/// to the opening's height. Measured per arm: turning high at y 0.08 would sweep the fingers
/// into the shelf's top block; turning low at y 0.08 keeps the IIWA's, Jaco's and Panda's
/// forearms clear of the door's near post, while the Gen3 does best turning high at y 0.
fn shelf_approach(robot: Robot) -> (f64, bool) {
    match robot {
        Robot::Gen3 => (0.0, true),
        _ => (0.08, false),
    }
}

/// The turn about a horizontal axis that makes the approach axis of a gripper at
/// `orientation` level.
fn levelling(orientation: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    let approach = orientation * Vector3::z();
    let level = Vector3::new(approach.x, approach.y, 0.0);
    UnitQuaternion::rotation_between(&approach, &level).unwrap_or_else(UnitQuaternion::identity)
}

/// `orientation` (gripper pointing down, closing along x) turned about the world x axis until
/// the approach axis points along +y, into the shelf.
fn turned_to_shelf(orientation: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2) * orientation
}
