//! The gripper action controller, as ros2_controllers' position `gripper_action_controller`
//! (Jazzy) decides a `GripperCommand` goal: it commands the goal position once, then each update
//! checks the gripper joint — within `goal_tolerance` of the goal: reached; otherwise, once the
//! joint has not moved faster than `stall_velocity_threshold` for longer than `stall_timeout`:
//! stalled (aborted, as `allow_stalling` is false by default). The gripper joint is the left
//! finger joint (m; the fingers are coupled). ROS-free: the node converts messages.

use crate::sim::hardware::{GRIPPER, GripperTarget, JointSnapshot};

/// The controller's parameters, with gripper_action_controller's defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripperParams {
    /// |goal − position| below which the goal is reached (m).
    pub goal_tolerance: f64,
    /// Speed at or below which the joint counts as not moving (m/s).
    pub stall_velocity_threshold: f64,
    /// How long the joint may not move before the goal is stalled (s).
    pub stall_timeout: f64,
    /// Whether a stalled goal succeeds (true) or aborts (false).
    pub allow_stalling: bool,
}

impl Default for GripperParams {
    fn default() -> Self {
        GripperParams {
            goal_tolerance: 0.01,
            stall_velocity_threshold: 0.001,
            stall_timeout: 1.0,
            allow_stalling: false,
        }
    }
}

/// A `GripperCommand` goal: the gripper joint's position and the effort limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripperGoal {
    /// Left finger joint position (m).
    pub position: f64,
    /// Effort limit (N); 0 = the gripper's default.
    pub max_effort: f64,
}

/// The goal's result fields, as `control_msgs/action/GripperCommand` reports them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripperResult {
    /// The gripper joint's position at the end (m).
    pub position: f64,
    /// The effort commanded (the goal's limit, as the position variant reports it).
    pub effort: f64,
    /// The joint stopped short of the goal (e.g. on an object between the fingers).
    pub stalled: bool,
    /// The joint got within the goal tolerance.
    pub reached_goal: bool,
}

/// Where a gripper goal stands after an update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GripperOutcome {
    /// Still moving.
    Running,
    /// Decided: succeeded (reached, or stalled with stalling allowed) or aborted (stalled).
    Done {
        /// Whether the action succeeds (else it is aborted).
        succeeded: bool,
        /// The result to send.
        result: GripperResult,
    },
}

/// A gripper goal being carried out.
#[derive(Debug, Clone)]
pub struct GripperFollowing {
    goal: GripperGoal,
    params: GripperParams,
    /// When the joint last moved (ns); set at the first update.
    last_movement_ns: Option<u64>,
    /// Whether the target has been written (it is written once, at the first update).
    commanded: bool,
}

impl GripperFollowing {
    /// Carry out `goal` from the next update on.
    pub fn new(goal: GripperGoal, params: GripperParams) -> Self {
        GripperFollowing {
            goal,
            params,
            last_movement_ns: None,
            commanded: false,
        }
    }

    /// The goal.
    pub fn goal(&self) -> GripperGoal {
        self.goal
    }

    /// The target to write this period: the goal at the first update, then nothing (held).
    pub fn command(&mut self) -> Option<GripperTarget> {
        (!std::mem::replace(&mut self.commanded, true))
            .then(|| GripperTarget::finger(self.goal.position, self.goal.max_effort))
    }

    /// The result if the goal ends now without being reached (cancel, preemption).
    pub fn result_now(&self, state: &JointSnapshot) -> GripperResult {
        GripperResult {
            position: state.positions[GRIPPER],
            effort: self.goal.max_effort,
            stalled: false,
            reached_goal: false,
        }
    }

    /// One update at `state.time_ns`.
    pub fn update(&mut self, state: &JointSnapshot) -> GripperOutcome {
        let now = state.time_ns;
        let last_movement = *self.last_movement_ns.get_or_insert(now);
        let position = state.positions[GRIPPER];
        let speed = state.velocities[GRIPPER].abs();
        let result = |stalled, reached_goal| GripperResult {
            position,
            effort: self.goal.max_effort,
            stalled,
            reached_goal,
        };
        if (self.goal.position - position).abs() < self.params.goal_tolerance {
            return GripperOutcome::Done {
                succeeded: true,
                result: result(false, true),
            };
        }
        if speed > self.params.stall_velocity_threshold {
            self.last_movement_ns = Some(now);
        } else if now.saturating_sub(last_movement) as f64 * 1e-9 > self.params.stall_timeout {
            return GripperOutcome::Done {
                succeeded: self.params.allow_stalling,
                result: result(true, false),
            };
        }
        GripperOutcome::Running
    }
}
