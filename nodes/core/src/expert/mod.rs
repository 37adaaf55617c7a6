//! A scripted expert: a phase machine that solves tasks through the public [`Env`] interface.
//!
//! The expert reads only what an agent can see — the observation (object pose, joint angles)
//! and the scene description ([`Env::goal`], [`Env::task`], the tables in [`crate::arena`]) —
//! and acts only with [`Action::Absolute`] joint targets plus a gripper opening. Gripper poses
//! are turned into joint targets with the crate's own damped-least-squares IK
//! ([`crate::kinematics::solve_ik`]) on the arm's kinematic model, seeded from the previous
//! solution so consecutive targets stay on one IK branch.
//!
//! Every motion is a straight line of the pads' centre (and a slerp of the gripper's
//! orientation) with a smoothstep time law over 1–2 s, sampled once per control step.
//!
//! Phases: approach (over the object at a clearance height) → descend → close → lift →
//! transport → the objective's finish (lower into bin 2 / slide to the goal / release over
//! the trash can) → release → retreat → hold.
//!
//! First pass: top-down grasps of the box (closing along x for Shelf, which then turns the
//! gripper and the box about the closing axis so the approach axis points at the shelf and
//! slides it in along +y); obstacles are passed over (object wall, door) or over / around
//! (goal wall). The hollow box often works with the same grasp; the plate and the dumbbell
//! need their own grasps (rim, bar) and are not handled yet.

use std::collections::VecDeque;

use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};

use crate::TaskSpec;
use std::f64::consts::FRAC_PI_2;

use crate::arena::{SHELF, TRASH_CAN, objective_arena};
use crate::axes::{Objective, Obstacle, Robot};
use crate::env::{Action, Env, EnvConfig};
use crate::kinematics::{IkTarget, frame_from_axes, link_pose, solve_ik};
use crate::physics::{ARM_DOF, GRIP_SITE_LINK, RobotModel};

/// The pads' centre is this far above the grip site along the gripper's approach axis (m):
/// the pads span 0.0859…0.1189 from the gripper mount, the grip site is at 0.109.
const PAD_CENTRE_ABOVE_GRIP_SITE: f64 = 0.109 - (0.0859 + 0.1189) / 2.0;
/// Gripper opening (m) while approaching and releasing.
const OPEN: f64 = 0.08;
/// Gripper opening (m) commanded to grasp (the 20 N finger servos then hold the object).
const CLOSED: f64 = 0.0;
/// Pad-centre height (m) that clears the object wall and door (tops at z 1.07).
const OVER_OBJECT_WALL_Z: f64 = 1.17;
/// Object-centre height (m) that clears the goal wall (top at z 1.10) with the box below it.
const OVER_GOAL_WALL_Z: f64 = 1.19;
/// Object-centre height (m) for a plain lift and carry.
const CARRY_Z: f64 = 1.05;
/// How far above the object's resting height the object is carried while pushing (m).
const PUSH_LIFT: f64 = 0.012;
/// x (m) of the lane that goes around the goal wall's free end (the wall ends at x 0.11).
const AROUND_GOAL_WALL_X: f64 = 0.22;
/// How far (rad) the approach axis leans towards the robot when walls are near the arm.
const GRASP_TILT: f64 = 0.45;
/// Height (m) of the carried box's centre above the shelf board while inserting: midway in
/// the 15.5 cm opening, so the gripper's housing around the box clears the board and the top
/// block (the box, lying on its side, then drops about 5 cm onto the board).
const SHELF_INSERT_HEIGHT: f64 = 0.075;
/// How far past the shelf's front the box's centre goes (m): to y 0.28, inside the
/// 0.18…0.33 success band, with its far end 1 cm short of the back panel.
const SHELF_INSERT_DEPTH: f64 = 0.05;
/// x (m) of the lane into the shelf when the goal wall stands at x −0.10…0.11: past the
/// wall's free end, so the forearm crosses the wall's line beyond it.
const SHELF_LANE_PAST_GOAL_WALL_X: f64 = 0.17;
/// Iterations per IK solve (seeded from the previous step's solution, so few are needed).
const IK_ITERATIONS: usize = 80;
/// Position error (m) above which an IK solve is retried with more iterations.
const IK_RETRY_ERROR: f64 = 2e-3;
/// Iterations of the retry.
const IK_RETRY_ITERATIONS: usize = 600;
/// Orientation error weight in the IK.
const IK_ORIENTATION_WEIGHT: f64 = 0.5;

/// What an episode of the expert achieved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeOutcome {
    /// Whether any step succeeded.
    pub success: bool,
    /// Sum of the rewards.
    pub ret: f64,
    /// Control steps run.
    pub length: u32,
}

/// Runs one episode of `task` with `seed` (default config) driven by the expert.
pub fn run_episode(task: TaskSpec, seed: u64) -> EpisodeOutcome {
    let mut env = Env::new(task, EnvConfig::default());
    let mut outcome = EpisodeOutcome {
        success: false,
        ret: 0.0,
        length: 0,
    };
    if env.reset(seed).is_err() {
        return outcome;
    }
    let mut expert = Expert::new(task);
    while env.ended().is_none() {
        let action = expert.act(&env);
        match env.step(&action) {
            Ok(step) => outcome.success |= step.info.success,
            Err(_) => break,
        }
    }
    outcome.ret = env.episode_return();
    outcome.length = env.steps();
    outcome
}

/// The phases of the script, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    /// Not started.
    Start,
    /// Over the object at a clearance height, gripper open and turned to the grasp.
    Approach,
    /// Straight down to the grasp pose.
    Descend,
    /// Closing the fingers.
    Close,
    /// Lifting the object.
    Lift,
    /// Carrying it towards the objective's target.
    Transport,
    /// The objective's placing motion (lower into the bin; slide to the goal; over the can).
    Place,
    /// Opening the fingers.
    Release,
    /// Moving the gripper away.
    Retreat,
    /// Holding still until the episode ends.
    Done,
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
    /// Where the object was when the grasp was planned (m).
    grasp_object: Point3<f64>,
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
            gripper: OPEN,
            grasp_object: Point3::origin(),
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

    /// Plans the segments of the phase after the current one.
    fn next_phase(&mut self, env: &Env) {
        let model = env.world().model;
        let obs = env.observation();
        let object = Point3::from(obs.object.position);
        let [x, y, z, w] = obs.object.orientation;
        let object_rotation = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        let task = self.task;
        let walled = matches!(task.obstacle, Obstacle::ObjectWall | Obstacle::ObjectDoor);
        let goal_wall = task.obstacle == Obstacle::GoalWall;
        match self.phase {
            Phase::Start => {
                let q = env.world().arm_positions();
                self.q = Some(q);
                let grip = link_pose(model, &q, GRIP_SITE_LINK).expect("grip site link");
                self.orientation = grip.rotation;
                self.pad = (grip * Point3::new(0.0, 0.0, -PAD_CENTRE_ABOVE_GRIP_SITE)).coords;
                self.phase = Phase::Approach;
                // The Panda's forearm hangs low over walls near the robot unless the gripper
                // leans; the other arms clear them with a vertical gripper.
                let near_wall = walled || (goal_wall && task.objective == Objective::Push);
                let tilt = if task.robot == Robot::Panda && near_wall {
                    GRASP_TILT
                } else {
                    0.0
                };
                let down = if task.objective == Objective::Shelf {
                    // Close along x (the box later turns about it); of the two signs take the
                    // one the IK reaches over the object, moving the joints least.
                    let over = Vector3::new(object.x, object.y, object.z + 0.12);
                    [Vector3::x(), -Vector3::x()]
                        .map(|axis| {
                            grasp_orientation(model, &q, &object_rotation, tilt, Some(axis))
                        })
                        .into_iter()
                        .map(|o| (o, reach_cost(model, &q, over, o)))
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .map(|(o, _)| o)
                        .expect("two candidates")
                } else {
                    grasp_orientation(model, &q, &object_rotation, tilt, None)
                };
                let clear = if walled {
                    OVER_OBJECT_WALL_Z
                } else {
                    object.z + 0.12
                };
                let mut rise = self.pad;
                rise.z = rise.z.max(clear);
                self.segment(model, rise, down, 1.0);
                self.segment(model, Vector3::new(object.x, object.y, clear), down, 1.5);
            }
            Phase::Approach => {
                self.phase = Phase::Descend;
                self.grasp_object = object;
                self.segment(model, object.coords, self.orientation, 1.5);
            }
            Phase::Descend => {
                self.phase = Phase::Close;
                self.gripper = CLOSED;
                self.hold(0.6);
            }
            Phase::Close => {
                self.phase = Phase::Lift;
                let rest = self.grasp_object.z;
                let lift_to = match task.objective {
                    Objective::Push => rest + PUSH_LIFT,
                    _ if goal_wall => OVER_GOAL_WALL_Z,
                    _ if walled => OVER_OBJECT_WALL_Z,
                    _ => CARRY_Z,
                };
                let offset = self.pad - self.grasp_object.coords;
                let target = Vector3::new(self.pad.x, self.pad.y, lift_to + offset.z);
                self.segment(model, target, self.orientation, 1.5);
            }
            Phase::Lift => {
                self.phase = Phase::Transport;
                let h = self.pad.z;
                let o = self.orientation;
                match task.objective {
                    Objective::Push => {
                        let goal = env.goal();
                        if goal_wall {
                            let lane = AROUND_GOAL_WALL_X;
                            self.segment(model, Vector3::new(lane, self.pad.y, h), o, 1.0);
                            self.segment(model, Vector3::new(lane, goal.y - 0.03, h), o, 2.0);
                        }
                        self.segment(model, Vector3::new(goal.x, goal.y, h), o, 2.0);
                    }
                    Objective::PickPlace => {
                        let bin = objective_arena(Objective::PickPlace).bin2_position;
                        self.segment(model, Vector3::new(bin[0], bin[1], h), o, 2.0);
                    }
                    Objective::Shelf => {
                        // In front of the shelf, then down to the opening's height.
                        let x = if goal_wall {
                            SHELF_LANE_PAST_GOAL_WALL_X
                        } else {
                            SHELF.position[0]
                        };
                        let z = SHELF.position[2] + SHELF.z_offset + SHELF_INSERT_HEIGHT;
                        let (front_y, turn_high) = shelf_approach(task.robot);
                        self.segment(model, Vector3::new(x, front_y, h), o, 2.0);
                        let o = if turn_high {
                            let sideways = turned_to_shelf(&o);
                            self.segment(model, Vector3::new(x, front_y, h), sideways, 2.0);
                            sideways
                        } else {
                            o
                        };
                        self.segment(model, Vector3::new(x, front_y, z), o, 1.5);
                    }
                    Objective::TrashCan => {
                        let [cx, cy, _] = TRASH_CAN.position;
                        self.segment(model, Vector3::new(cx, cy, h), o, 2.0);
                    }
                }
            }
            Phase::Transport => {
                self.phase = Phase::Place;
                let offset = self.pad.z - object.z;
                match task.objective {
                    Objective::Shelf => {
                        // Turn the gripper (and the box with it) about the closing axis until
                        // the approach axis points at the shelf (unless it already turned), then go
                        // straight in along +y.
                        let sideways = if shelf_approach(task.robot).1 {
                            self.orientation
                        } else {
                            let sideways = turned_to_shelf(&self.orientation);
                            self.segment(model, self.pad, sideways, 2.0);
                            sideways
                        };
                        let inside = SHELF.position[1] - SHELF.y_size + SHELF_INSERT_DEPTH;
                        let t = Vector3::new(self.pad.x, inside, self.pad.z);
                        self.segment(model, t, sideways, 2.0);
                    }
                    Objective::PickPlace => {
                        // Bin 2's floor top is z 0.82: bring the box's bottom 1.5 cm above it.
                        let bin = objective_arena(Objective::PickPlace).bin2_position;
                        let target_z = bin[2] + 0.02 + 0.015 + 0.03;
                        let t = Vector3::new(self.pad.x, self.pad.y, target_z + offset);
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    Objective::Push => self.hold(0.3),
                    Objective::TrashCan => {
                        // Just above the can's walls (top z 0.9855) before letting go.
                        let t = Vector3::new(self.pad.x, self.pad.y, 1.04 + offset);
                        let t = if goal_wall { self.pad } else { t };
                        self.segment(model, t, self.orientation, 1.0);
                    }
                }
            }
            Phase::Place => {
                self.phase = Phase::Release;
                self.gripper = OPEN;
                self.hold(0.8);
            }
            Phase::Release => {
                self.phase = Phase::Retreat;
                match task.objective {
                    Objective::TrashCan => {
                        let t = Vector3::new(self.pad.x, self.pad.y - 0.05, self.pad.z + 0.12);
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    Objective::Shelf => {
                        let t = Vector3::new(self.pad.x, shelf_approach(task.robot).0, self.pad.z);
                        self.segment(model, t, self.orientation, 1.5);
                    }
                    _ => self.hold(0.2),
                }
            }
            Phase::Retreat | Phase::Done => self.phase = Phase::Done,
        }
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

    /// A straight line of the pads' centre to `pad` while turning to `orientation`.
    fn segment(
        &mut self,
        model: &RobotModel,
        pad: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        seconds: f64,
    ) {
        let (p0, r0) = (self.pad, self.orientation);
        let mut q = self.q.expect("planned from a known pose");
        let n = steps(seconds);
        for k in 1..=n {
            let s = k as f64 / n as f64;
            let s = s * s * (3.0 - 2.0 * s);
            let p = p0 + (pad - p0) * s;
            let r = r0.slerp(&orientation, s);
            let target = IkTarget {
                position: p - r * Vector3::new(0.0, 0.0, -PAD_CENTRE_ABOVE_GRIP_SITE),
                orientation: Some(r),
                orientation_weight: IK_ORIENTATION_WEIGHT,
            };
            let mut result = solve_ik(model, GRIP_SITE_LINK, &target, &q, IK_ITERATIONS);
            if result.is_none_or(|r| r.position_error > IK_RETRY_ERROR) {
                // A large step (a wrist turn): give the solver more room before accepting.
                result = solve_ik(model, GRIP_SITE_LINK, &target, &q, IK_RETRY_ITERATIONS);
            }
            if let Some(result) = result {
                q = result.q;
            }
            self.plan.push_back(Action::Absolute {
                joints: q,
                gripper: Some((self.gripper, 0.0)),
            });
        }
        self.q = Some(q);
        self.pad = pad;
        self.orientation = orientation;
    }
}

/// How hard it is to put the pads at `pad` with `orientation` from `q`: the IK's remaining
/// error (heavily weighted) plus the joint motion.
fn reach_cost(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> f64 {
    let target = IkTarget {
        position: pad - orientation * Vector3::new(0.0, 0.0, -PAD_CENTRE_ABOVE_GRIP_SITE),
        orientation: Some(orientation),
        orientation_weight: IK_ORIENTATION_WEIGHT,
    };
    match solve_ik(model, GRIP_SITE_LINK, &target, q, IK_RETRY_ITERATIONS) {
        Some(r) => {
            let motion: f64 = r.q.iter().zip(q).map(|(a, b)| (a - b).abs()).sum();
            100.0 * (r.position_error + r.orientation_error) + motion
        }
        None => f64::INFINITY,
    }
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

/// `orientation` (gripper pointing down, closing along x) turned about the world x axis until
/// the approach axis points along +y, into the shelf.
fn turned_to_shelf(orientation: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2) * orientation
}

/// Control steps (50 ms) in `seconds`.
fn steps(seconds: f64) -> usize {
    ((seconds / 0.05).round() as usize).max(1)
}

/// The grip-site orientation that points the gripper straight down with the fingers closing
/// along whichever horizontal axis of the object is nearest their current closing direction.
///
/// With `tilt` ≠ 0 (rad) the fingers close along the object axis nearest world y and the
/// approach axis leans towards the robot (−x) by `tilt`, so the wrist and forearm stay high
/// and far from walls standing between the robot and the grasp.
fn grasp_orientation(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    object_rotation: &UnitQuaternion<f64>,
    tilt: f64,
    close_along: Option<Vector3<f64>>,
) -> UnitQuaternion<f64> {
    let gripper = link_pose(model, q, "gripper_base").expect("gripper base link");
    let mut heading = gripper.rotation * Vector3::y();
    heading.z = 0.0;
    if let Some(axis) = close_along {
        heading = axis;
    } else if tilt != 0.0 {
        heading = Vector3::y() * heading.y.signum();
    }
    let candidates = [
        object_rotation * Vector3::x(),
        object_rotation * Vector3::y(),
    ];
    let mut best = heading;
    let mut best_dot = -1.0;
    for c in candidates {
        let mut c = c;
        c.z = 0.0;
        if c.norm() < 1e-6 {
            continue;
        }
        let c = c.normalize();
        for c in [c, -c] {
            let d = c.dot(&heading);
            if d > best_dot {
                best_dot = d;
                best = c;
            }
        }
    }
    let approach = if tilt != 0.0 {
        // Perpendicular to the closing axis, leaning towards −x.
        let along = best.cross(&Vector3::z()).normalize();
        let along = if along.x > 0.0 { -along } else { along };
        (along * tilt.sin() - Vector3::z() * tilt.cos()).normalize()
    } else {
        -Vector3::z()
    };
    frame_from_axes(approach, best)
        * UnitQuaternion::from_euler_angles(0.0, 0.0, -std::f64::consts::FRAC_PI_2)
}
