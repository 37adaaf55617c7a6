//! The joint trajectory controller, as ros2_controllers' `joint_trajectory_controller` (Jazzy)
//! behaves towards its clients: the same goal validation, the same spline interpolation, the
//! same tolerance rules and result codes. Each update at time `t` reads the joints, samples the
//! desired state at `t` (for feedback and tolerance checks) and commands the sample at
//! `t + period` (the set point the joints should reach by the next update). ROS-free: the node
//! converts messages to and from these types.

use composuite_core::physics::{ARM_DOF, RobotModel};

use super::spline::{JointSample, Knot, interpolate};
use crate::sim::hardware::JointSnapshot;

/// `FollowJointTrajectory` result codes (control_msgs).
pub mod code {
    /// The goal was reached.
    pub const SUCCESSFUL: i32 = 0;
    /// Preempted by a new goal (ros2_controllers ≥ 4.41) or ended otherwise.
    pub const INVALID_GOAL: i32 = -1;
    /// A path tolerance was violated while moving.
    pub const PATH_TOLERANCE_VIOLATED: i32 = -4;
    /// The goal tolerance was not met within the goal time tolerance.
    pub const GOAL_TOLERANCE_VIOLATED: i32 = -5;
}

/// One waypoint as received (values in the goal's joint order; empty = not given).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Waypoint {
    /// When to be there, ns from the trajectory's start.
    pub time_from_start_ns: i64,
    /// Positions.
    pub positions: Vec<f64>,
    /// Velocities.
    pub velocities: Vec<f64>,
    /// Accelerations.
    pub accelerations: Vec<f64>,
    /// Efforts (refused: the arm has position command interfaces only).
    pub effort: Vec<f64>,
}

/// A tolerance entry of a goal: 0 keeps the default, −1 removes the limit.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTolerance {
    /// Joint name.
    pub name: String,
    /// Position tolerance.
    pub position: f64,
    /// Velocity tolerance.
    pub velocity: f64,
    /// Acceleration tolerance.
    pub acceleration: f64,
}

/// A trajectory as a client sends it (action goal or topic message).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrajectoryRequest {
    /// Joint names, in the order of each point's values.
    pub joint_names: Vec<String>,
    /// Waypoints.
    pub points: Vec<Waypoint>,
    /// Absolute start time (ns); 0 = at the next update.
    pub start_ns: u64,
    /// Path tolerances (action goals only).
    pub path_tolerance: Vec<JointTolerance>,
    /// Goal tolerances (action goals only).
    pub goal_tolerance: Vec<JointTolerance>,
    /// How long past the end the goal tolerance may take to be met (ns); 0 = the default.
    pub goal_time_tolerance_ns: i64,
}

/// Position tolerances per arm joint (0 = not checked) and the goal time tolerance (0 = none).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Tolerances {
    /// Allowed |desired − actual| while moving.
    pub path: [f64; ARM_DOF],
    /// Allowed |desired − actual| at the end.
    pub goal: [f64; ARM_DOF],
    /// Allowed time past the end to get within the goal tolerance (s); 0 = wait forever.
    pub goal_time: f64,
}

/// A validated trajectory in the controller's joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Absolute start (ns), or 0 for "at the next update".
    pub start_ns: u64,
    /// Per point: one knot per arm joint, times relative to the start.
    pub points: Vec<[Knot; ARM_DOF]>,
}

/// Check a request as joint_trajectory_controller does (its default parameters: all joints
/// required, zero velocity at the end, positions required, no effort), plus the joint limits.
/// `now_ns` is the current time. The error says what was wrong; the controller rejects the goal
/// with it (ros2_control only logs it; this suite also logs it to `/rosout`).
pub fn validate(
    request: &TrajectoryRequest,
    model: &RobotModel,
    now_ns: u64,
) -> Result<Trajectory, String> {
    let joints: Vec<&str> = model.joints[..ARM_DOF]
        .iter()
        .map(|j| j.name.as_str())
        .collect();
    let names = &request.joint_names;
    if names.len() != ARM_DOF {
        return Err(format!(
            "Joints on incoming trajectory don't match the controller joints: {} given, the \
             controller has {ARM_DOF}: {joints:?}",
            names.len()
        ));
    }
    if request.points.is_empty() {
        return Err("Empty trajectory received.".into());
    }
    // Where each of the goal's joints sits in the controller's order.
    let mut slot = [usize::MAX; ARM_DOF];
    for (index, name) in names.iter().enumerate() {
        let Some(joint) = joints.iter().position(|j| j == name) else {
            return Err(format!(
                "Incoming joint {name} doesn't match the controller's joints {joints:?}."
            ));
        };
        if slot.contains(&joint) {
            return Err(format!("Joint {name} is named twice."));
        }
        slot[index] = joint;
    }
    let last = request.points.last().expect("checked non-empty");
    if let Some((index, v)) = last
        .velocities
        .iter()
        .enumerate()
        .find(|(_, v)| v.abs() > f64::from(f32::EPSILON))
    {
        return Err(format!(
            "Velocity of last trajectory point of joint {} is not zero: {v:.15}",
            names[index]
        ));
    }
    let end = i128::from(request.start_ns) + i128::from(last.time_from_start_ns);
    if request.start_ns != 0 && end < i128::from(now_ns) {
        return Err(format!(
            "Received trajectory with non-zero start time ({:.9}) that ends in the past ({:.9})",
            request.start_ns as f64 * 1e-9,
            end as f64 * 1e-9
        ));
    }
    let mut points = Vec::with_capacity(request.points.len());
    for (i, point) in request.points.iter().enumerate() {
        if i > 0 && point.time_from_start_ns <= request.points[i - 1].time_from_start_ns {
            return Err(format!(
                "Time between points {} and {i} is not strictly increasing, it is {:.9} and {:.9} \
                 respectively",
                i - 1,
                request.points[i - 1].time_from_start_ns as f64 * 1e-9,
                point.time_from_start_ns as f64 * 1e-9
            ));
        }
        if point.time_from_start_ns < 0 {
            return Err(format!("Point {i} has a negative time_from_start."));
        }
        for (what, values, required) in [
            ("positions", &point.positions, true),
            ("velocities", &point.velocities, false),
            ("accelerations", &point.accelerations, false),
        ] {
            if values.len() != ARM_DOF && (required || !values.is_empty()) {
                return Err(format!(
                    "Mismatch between joint_names size ({ARM_DOF}) and {what} ({}) at point #{i}.",
                    values.len()
                ));
            }
            if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                return Err(format!("Point #{i} has a non-finite value in {what}: {v}."));
            }
        }
        if !point.effort.is_empty() {
            return Err(
                "Trajectories with effort fields are only supported for controllers \
                        using the 'effort' command interface."
                    .into(),
            );
        }
        let mut knots = [Knot {
            time_ns: point.time_from_start_ns,
            position: 0.0,
            velocity: None,
            acceleration: None,
        }; ARM_DOF];
        for (index, &joint) in slot.iter().enumerate() {
            let position = point.positions[index];
            if let Some((lower, upper)) = model.joints[joint].limits
                && !(lower..=upper).contains(&position)
            {
                return Err(format!(
                    "Point #{i} puts {} at {position:.6}, outside its limits [{lower:.6}, \
                     {upper:.6}].",
                    names[index]
                ));
            }
            knots[joint] = Knot {
                time_ns: point.time_from_start_ns,
                position,
                velocity: point.velocities.get(index).copied(),
                acceleration: point.accelerations.get(index).copied(),
            };
        }
        points.push(knots);
    }
    Ok(Trajectory {
        start_ns: request.start_ns,
        points,
    })
}

/// The tolerances a goal asks for over `defaults`, as joint_trajectory_controller resolves
/// them: a value > 0 is used, −1 removes the limit, 0 keeps the default; any other negative
/// value or an unknown joint name makes the whole goal use the defaults (with the reason).
pub fn resolve_tolerances(
    request: &TrajectoryRequest,
    defaults: &Tolerances,
    model: &RobotModel,
) -> (Tolerances, Option<String>) {
    let resolve = |value: f64, default: f64| -> Result<f64, String> {
        if value > 0.0 {
            Ok(value)
        } else if value == -1.0 {
            Ok(0.0)
        } else if value == 0.0 {
            Ok(default)
        } else {
            Err(format!(
                "tolerance {value} is invalid (valid: > 0, 0 for the default, -1 for none)"
            ))
        }
    };
    let mut resolved = *defaults;
    let apply = |entries: &[JointTolerance], out: &mut [f64; ARM_DOF], base: &[f64; ARM_DOF]| {
        for entry in entries {
            let Some(joint) = model.joints[..ARM_DOF]
                .iter()
                .position(|j| j.name == entry.name)
            else {
                return Err(format!("tolerance for unknown joint `{}`", entry.name));
            };
            out[joint] = resolve(entry.position, base[joint])?;
        }
        Ok(())
    };
    let outcome = apply(&request.path_tolerance, &mut resolved.path, &defaults.path)
        .and_then(|()| apply(&request.goal_tolerance, &mut resolved.goal, &defaults.goal))
        .and_then(|()| {
            let goal_time = request.goal_time_tolerance_ns as f64 * 1e-9;
            resolved.goal_time = resolve(goal_time, defaults.goal_time)?;
            Ok(())
        });
    match outcome {
        Ok(()) => (resolved, None),
        Err(why) => (
            *defaults,
            Some(format!("{why}; using the default tolerances")),
        ),
    }
}

/// How a trajectory stands after an update.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Still moving (or waiting to get within the goal tolerance).
    Running,
    /// Every goal tolerance met at or after the end.
    Succeeded,
    /// Ended with a failure code and why.
    Aborted {
        /// A [`code`] value.
        code: i32,
        /// For people.
        message: String,
    },
}

/// What one update gives: the feedback values and the command.
#[derive(Debug, Clone, PartialEq)]
pub struct Update {
    /// Time of the update (ns).
    pub time_ns: u64,
    /// Time since the trajectory's start (ns; negative before a future start).
    pub time_from_start_ns: i64,
    /// The desired state at the update's time, per arm joint.
    pub desired: [JointSample; ARM_DOF],
    /// The measured positions.
    pub actual_positions: [f64; ARM_DOF],
    /// The measured velocities.
    pub actual_velocities: [f64; ARM_DOF],
    /// The position targets to write for the next period (`None` once aborted: the caller holds).
    pub command: Option<[f64; ARM_DOF]>,
    /// Where the trajectory stands.
    pub outcome: Outcome,
}

/// A trajectory being followed.
#[derive(Debug, Clone)]
pub struct Following {
    trajectory: Trajectory,
    tolerances: Tolerances,
    /// Set at the first update: when the trajectory started and the state it was picked up in.
    picked_up: Option<PickedUp>,
}

/// Where a followed trajectory begins.
#[derive(Debug, Clone, Copy)]
struct PickedUp {
    /// Absolute start (ns): the request's, or the first update's time if it gave none.
    start_ns: u64,
    /// The joints' state at the first update, timed relative to the start: the first segment's
    /// beginning.
    state: [Knot; ARM_DOF],
}

impl Following {
    /// Follow `trajectory` with `tolerances`, from the next update on.
    pub fn new(trajectory: Trajectory, tolerances: Tolerances) -> Self {
        Following {
            trajectory,
            tolerances,
            picked_up: None,
        }
    }

    /// The desired state of every joint at `t_ns` after the start.
    fn sample(&self, picked_up: &PickedUp, t_ns: i64) -> [JointSample; ARM_DOF] {
        std::array::from_fn(|j| {
            let mut previous = picked_up.state[j];
            for point in &self.trajectory.points {
                if t_ns <= point[j].time_ns {
                    return interpolate(&previous, &point[j], t_ns);
                }
                previous = point[j];
            }
            interpolate(&previous, &previous, t_ns) // past the end: the last point, held
        })
    }

    /// One controller update at `state.time_ns`, commanding for the period `period_ns` ahead.
    pub fn update(&mut self, state: &JointSnapshot, period_ns: u64) -> Update {
        let now = state.time_ns;
        let first_sample = self.picked_up.is_none();
        let picked_up = *self.picked_up.get_or_insert_with(|| {
            let start_ns = match self.trajectory.start_ns {
                0 => now,
                start => start,
            };
            let time_ns = (i128::from(now) - i128::from(start_ns)) as i64;
            PickedUp {
                start_ns,
                state: std::array::from_fn(|j| Knot {
                    time_ns,
                    position: state.positions[j],
                    velocity: Some(state.velocities[j]),
                    acceleration: Some(0.0),
                }),
            }
        });
        let time_from_start_ns = (i128::from(now) - i128::from(picked_up.start_ns)) as i64;
        let desired = self.sample(&picked_up, time_from_start_ns);
        let last_time = self.trajectory.points.last().expect("validated")[0].time_ns;
        let before_last_point = time_from_start_ns < last_time;
        let actual_positions: [f64; ARM_DOF] = std::array::from_fn(|j| state.positions[j]);
        let actual_velocities: [f64; ARM_DOF] = std::array::from_fn(|j| state.velocities[j]);
        let error = |j: usize| desired[j].position - actual_positions[j];
        let violated = |tolerance: &[f64; ARM_DOF]| {
            (0..ARM_DOF).find(|&j| tolerance[j] > 0.0 && error(j).abs() > tolerance[j])
        };
        let mut outcome = Outcome::Running;
        if (before_last_point || first_sample)
            && let Some(j) = violated(&self.tolerances.path)
        {
            outcome = Outcome::Aborted {
                code: code::PATH_TOLERANCE_VIOLATED,
                message: format!(
                    "Aborted due to path tolerance violation (joint {j}: error {:.6} > {:.6})",
                    error(j),
                    self.tolerances.path[j]
                ),
            };
        }
        if outcome == Outcome::Running && !before_last_point {
            let past_end = (time_from_start_ns - last_time) as f64 * 1e-9;
            match violated(&self.tolerances.goal) {
                None => outcome = Outcome::Succeeded,
                Some(_)
                    if self.tolerances.goal_time != 0.0 && past_end > self.tolerances.goal_time =>
                {
                    outcome = Outcome::Aborted {
                        code: code::GOAL_TOLERANCE_VIOLATED,
                        message: format!(
                            "Aborted due to goal_time_tolerance exceeding by {:.6} seconds",
                            past_end - self.tolerances.goal_time
                        ),
                    };
                }
                Some(_) => {}
            }
        }
        let command = match outcome {
            Outcome::Aborted { .. } => None,
            _ => {
                let next = self.sample(&picked_up, time_from_start_ns + period_ns as i64);
                Some(std::array::from_fn(|j| next[j].position))
            }
        };
        Update {
            time_ns: now,
            time_from_start_ns,
            desired,
            actual_positions,
            actual_velocities,
            command,
            outcome,
        }
    }
}
