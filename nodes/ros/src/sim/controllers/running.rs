//! What commands the arm and the gripper, updated together once per control period in
//! ros2_control's order: read the hardware, update every controller on that one reading, write
//! the commands. ROS-free and generic over the goal id `Id` (the node's action goal ids; tests use
//! integers), so the mock hardware runs it without rapier or DDS.
//!
//! The arm has one command source at a time: the last direct command (`joint_command`,
//! `reference_action`, `forward_position_controller/commands`), held; or a trajectory being
//! followed (an action goal, or a `joint_trajectory` topic message). A direct command ends a
//! running trajectory, and a new trajectory ends the previous one, each with the reason. The
//! gripper likewise: a gripper action goal, or direct gripper targets.

use composuite_core::physics::ARM_DOF;

use super::gripper::{GripperFollowing, GripperOutcome, GripperResult};
use super::trajectory::{Following, Outcome, Update, code};
use crate::sim::hardware::{ArmCommand, Command, GRIPPER, GripperTarget, JointSnapshot};

/// How a goal ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// Reached.
    Succeeded,
    /// Given up by the controller (tolerance, preemption, a direct command, a new episode).
    Aborted,
    /// Canceled at the client's request (or, for the gripper, preempted by a new goal).
    Canceled,
}

/// Something the node reports to a client.
#[derive(Debug, Clone, PartialEq)]
pub enum Event<Id> {
    /// One update of a trajectory action goal (its feedback).
    TrajectoryFeedback {
        /// The goal.
        goal: Id,
        /// The update's values.
        update: Box<Update>,
    },
    /// A trajectory ended (`goal` is `None` for one received on the topic).
    TrajectoryEnded {
        /// The goal.
        goal: Option<Id>,
        /// How.
        end: End,
        /// `FollowJointTrajectory` error code.
        code: i32,
        /// Why, for people.
        message: String,
    },
    /// A gripper goal ended.
    GripperEnded {
        /// The goal.
        goal: Id,
        /// How.
        end: End,
        /// The result fields.
        result: GripperResult,
    },
}

/// The message of a successful trajectory, as joint_trajectory_controller words it.
pub const TRAJECTORY_SUCCEEDED: &str = "Goal successfully reached!";
/// The message of a trajectory goal preempted by a new goal, as joint_trajectory_controller
/// words it.
pub const TRAJECTORY_PREEMPTED: &str = "Current goal preempted by new incoming action.";

struct ActiveTrajectory<Id> {
    following: Following,
    goal: Option<Id>,
}

struct ActiveGripper<Id> {
    following: GripperFollowing,
    goal: Id,
}

/// The arm's and the gripper's command sources.
pub struct Controllers<Id> {
    /// The arm command written when no trajectory runs (and held after one ends).
    arm: ArmCommand,
    /// A direct gripper target waiting for the next write.
    pending_gripper: Option<GripperTarget>,
    trajectory: Option<ActiveTrajectory<Id>>,
    gripper: Option<ActiveGripper<Id>>,
}

impl<Id: Copy + PartialEq> Controllers<Id> {
    /// Holding the arm at `positions`, the gripper at its last target.
    pub fn holding(positions: [f64; ARM_DOF]) -> Self {
        Controllers {
            arm: ArmCommand::Positions(positions),
            pending_gripper: None,
            trajectory: None,
            gripper: None,
        }
    }

    /// Whether a goal is running, i.e. wants time to pass (in lockstep the sim advances for it).
    pub fn running(&self) -> bool {
        self.trajectory.is_some() || self.gripper.is_some()
    }

    /// The running trajectory's goal, if it came from the action.
    pub fn trajectory_goal(&self) -> Option<Id> {
        self.trajectory.as_ref().and_then(|t| t.goal)
    }

    /// The running gripper goal.
    pub fn gripper_goal(&self) -> Option<Id> {
        self.gripper.as_ref().map(|g| g.goal)
    }

    /// A direct arm command (held until the next); ends a running trajectory.
    pub fn command_arm(&mut self, arm: ArmCommand, source: &str) -> Option<Event<Id>> {
        self.arm = arm;
        self.end_trajectory(
            End::Aborted,
            code::INVALID_GOAL,
            format!("superseded by a command on `{source}`"),
        )
    }

    /// A direct gripper target for the next write; ends a running gripper goal.
    pub fn command_gripper(
        &mut self,
        target: GripperTarget,
        state: &JointSnapshot,
    ) -> Option<Event<Id>> {
        self.pending_gripper = Some(target);
        self.end_gripper(End::Aborted, state)
    }

    /// Follow `following` from the next update (`goal` `None`: from the topic); ends the running
    /// trajectory, as joint_trajectory_controller does.
    pub fn start_trajectory(
        &mut self,
        following: Following,
        goal: Option<Id>,
    ) -> Option<Event<Id>> {
        let ended = self.end_trajectory(
            End::Aborted,
            code::INVALID_GOAL,
            match goal {
                Some(_) => TRAJECTORY_PREEMPTED.to_string(),
                None => "replaced by a trajectory on the `joint_trajectory` topic".to_string(),
            },
        );
        self.trajectory = Some(ActiveTrajectory { following, goal });
        ended
    }

    /// Carry out a gripper goal from the next update; a running one is canceled (as
    /// gripper_action_controller preempts).
    pub fn start_gripper(
        &mut self,
        following: GripperFollowing,
        goal: Id,
        state: &JointSnapshot,
    ) -> Option<Event<Id>> {
        let ended = self.end_gripper(End::Canceled, state);
        self.pending_gripper = None;
        self.gripper = Some(ActiveGripper { following, goal });
        ended
    }

    /// Cancel trajectory goal `goal` if it is the running one: the arm holds where it is.
    pub fn cancel_trajectory(&mut self, goal: Id, state: &JointSnapshot) -> Option<Event<Id>> {
        if self.trajectory_goal() != Some(goal) {
            return None;
        }
        self.arm = ArmCommand::Positions(arm_positions(state));
        self.end_trajectory(End::Canceled, code::SUCCESSFUL, "Goal canceled".into())
    }

    /// Cancel gripper goal `goal` if it is the running one: the gripper holds where it is.
    pub fn cancel_gripper(&mut self, goal: Id, state: &JointSnapshot) -> Option<Event<Id>> {
        if self.gripper_goal() != Some(goal) {
            return None;
        }
        self.pending_gripper = Some(GripperTarget::finger(state.positions[GRIPPER], 0.0));
        self.end_gripper(End::Canceled, state)
    }

    /// End every goal (a new episode, the node stopping), holding the arm where `state` has it.
    pub fn abort_all(&mut self, message: &str, state: &JointSnapshot) -> Vec<Event<Id>> {
        self.arm = ArmCommand::Positions(arm_positions(state));
        let trajectory = self.end_trajectory(End::Aborted, code::INVALID_GOAL, message.into());
        let gripper = self.end_gripper(End::Aborted, state);
        self.pending_gripper = None;
        trajectory.into_iter().chain(gripper).collect()
    }

    /// One update on `state`: the command to write for the next `period_ns`, and what to report.
    pub fn update(&mut self, state: &JointSnapshot, period_ns: u64) -> (Command, Vec<Event<Id>>) {
        let mut events = Vec::new();
        if let Some(active) = &mut self.trajectory {
            let update = active.following.update(state, period_ns);
            if let Some(command) = update.command {
                self.arm = ArmCommand::Positions(command);
            }
            let goal = active.goal;
            let outcome = update.outcome.clone();
            if let Some(goal) = goal {
                events.push(Event::TrajectoryFeedback {
                    goal,
                    update: Box::new(update),
                });
            }
            match outcome {
                Outcome::Running => {}
                Outcome::Succeeded => events.extend(self.end_trajectory(
                    End::Succeeded,
                    code::SUCCESSFUL,
                    TRAJECTORY_SUCCEEDED.into(),
                )),
                Outcome::Aborted { code, message } => {
                    // joint_trajectory_controller holds the position it measured.
                    self.arm = ArmCommand::Positions(arm_positions(state));
                    events.extend(self.end_trajectory(End::Aborted, code, message));
                }
            }
        }
        let mut gripper = self.pending_gripper.take();
        if let Some(active) = &mut self.gripper {
            gripper = gripper.or_else(|| active.following.command());
            if let GripperOutcome::Done { succeeded, result } = active.following.update(state) {
                let goal = active.goal;
                self.gripper = None;
                events.push(Event::GripperEnded {
                    goal,
                    end: if succeeded {
                        End::Succeeded
                    } else {
                        End::Aborted
                    },
                    result,
                });
            }
        }
        (
            Command {
                arm: self.arm,
                gripper,
            },
            events,
        )
    }

    fn end_trajectory(&mut self, end: End, code: i32, message: String) -> Option<Event<Id>> {
        let active = self.trajectory.take()?;
        // Also for a topic trajectory (goal `None`): the node only logs it, there is no client.
        Some(Event::TrajectoryEnded {
            goal: active.goal,
            end,
            code,
            message,
        })
    }

    fn end_gripper(&mut self, end: End, state: &JointSnapshot) -> Option<Event<Id>> {
        let active = self.gripper.take()?;
        Some(Event::GripperEnded {
            goal: active.goal,
            end,
            result: active.following.result_now(state),
        })
    }
}

fn arm_positions(state: &JointSnapshot) -> [f64; ARM_DOF] {
    std::array::from_fn(|j| state.positions[j])
}
