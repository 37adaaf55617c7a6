//! The controllers' goals: the trajectory and gripper actions' goals and cancels, the
//! `joint_trajectory` topic, and telling the clients what the controllers did (feedback,
//! results) — or ending every goal at once.

use composuite_msgs::control_msgs::action::{
    FollowJointTrajectoryGoal, FollowJointTrajectoryResult, GripperCommandGoal,
    GripperCommandResult,
};
use composuite_msgs::trajectory_msgs::msg::JointTrajectory;
use ros2_client::RmwRequestId;
use ros2_client::action::{GoalId, GoalStatusEnum, SendGoalRequest};
use ros2_client::action_msgs::CancelGoalRequest;

use super::action_server::{self, Goals};
use super::controllers::gripper::{GripperFollowing, GripperGoal, GripperParams};
use super::controllers::running::{End, Event};
use super::controllers::trajectory;
use super::hardware::GripperTarget;
use super::ros_control;
use super::{ActionServers, Mode, Sim};
use crate::shared::convert;
use crate::shared::names;
use crate::shared::node::Logger;

/// In lockstep, how long past its end a trajectory goal with goal tolerances and no goal time
/// tolerance may take to meet them (s of sim time), so the goal always ends.
const LOCKSTEP_GOAL_TIME_S: f64 = 1.0;

impl Sim {
    /// End every running goal with `why` (a new episode, shutting down), holding the arm still.
    pub(super) fn end_all_goals(&mut self, servers: &ActionServers, why: &str, log: &Logger) {
        let Some(state) = self.snapshot() else { return };
        let Some(run) = &mut self.run else { return };
        let events = run.controllers.abort_all(why, &state);
        self.report(servers, events, log);
    }

    /// A trajectory checked as joint_trajectory_controller checks it, with the tolerances it
    /// asks for, ready to follow; or why not.
    fn trajectory_for(
        &self,
        request: &trajectory::TrajectoryRequest,
        log: &Logger,
    ) -> Result<trajectory::Following, String> {
        let Some(run) = &self.run else {
            return Err("no episode yet (the task manager publishes the scene)".into());
        };
        if run.env.ended().is_some() {
            return Err(format!(
                "episode {} is over; a new episode (reset) lets the arm move again",
                run.episode
            ));
        }
        let model = run.model();
        let checked = trajectory::validate(request, model, self.sim_time_ns)?;
        let (mut tolerances, note) =
            trajectory::resolve_tolerances(request, &trajectory::Tolerances::default(), model);
        if let Some(note) = note {
            log.warn(format!("trajectory goal: {note}"));
        }
        // A goal time tolerance of 0 waits for the goal tolerance forever; in lockstep the goal
        // itself advances the sim, so "forever" would never hand control back.
        if self.mode == Mode::Lockstep
            && tolerances.goal_time == 0.0
            && tolerances.goal.iter().any(|&t| t > 0.0)
        {
            tolerances.goal_time = LOCKSTEP_GOAL_TIME_S;
            log.debug(format!(
                "trajectory goal: goal_time_tolerance 0 (wait forever) is {LOCKSTEP_GOAL_TIME_S} s \
                 of sim time in lockstep"
            ));
        }
        Ok(trajectory::Following::new(checked, tolerances))
    }

    pub(super) fn on_trajectory_goal(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: SendGoalRequest<FollowJointTrajectoryGoal>,
        log: &Logger,
    ) {
        let server = servers
            .trajectory
            .as_ref()
            .expect("a goal came: the server is up");
        let now = convert::time_from_nanos(self.sim_time_ns);
        let following =
            ros_control::goal_request(&request.goal).and_then(|r| self.trajectory_for(&r, log));
        let following = match following {
            Ok(following) => following,
            Err(why) => {
                // The goal response has no field for a reason: it goes to the log (/rosout).
                log.warn(format!("{} goal rejected: {why}", names::TRAJECTORY_ACTION));
                if let Err(err) =
                    Goals::<FollowJointTrajectoryResult>::reject(server, request_id, &now)
                {
                    log.warn(err);
                }
                return;
            }
        };
        if let Err(err) = self
            .trajectory_goals
            .accept(server, request_id, request.goal_id, &now)
        {
            log.warn(err);
            return;
        }
        let run = self.run.as_mut().expect("checked by trajectory_for");
        let ended = run
            .controllers
            .start_trajectory(following, Some(request.goal_id));
        self.report(servers, ended, log);
    }

    pub(super) fn on_trajectory_topic(
        &mut self,
        servers: &ActionServers,
        message: &JointTrajectory,
        log: &Logger,
    ) {
        let request = ros_control::topic_request(message);
        match self.trajectory_for(&request, log) {
            Ok(following) => {
                let run = self.run.as_mut().expect("checked by trajectory_for");
                let ended = run.controllers.start_trajectory(following, None);
                self.report(servers, ended, log);
            }
            Err(why) => log.warn(format!("{} refused: {why}", names::TRAJECTORY_TOPIC)),
        }
    }

    pub(super) fn on_gripper_goal(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: SendGoalRequest<GripperCommandGoal>,
        log: &Logger,
    ) {
        let server = servers
            .gripper
            .as_ref()
            .expect("a goal came: the server is up");
        let now = convert::time_from_nanos(self.sim_time_ns);
        let command = &request.goal.command;
        let goal = GripperGoal {
            position: command.position,
            max_effort: command.max_effort,
        };
        let checked = match (&self.run, self.snapshot()) {
            (Some(run), Some(state)) if run.env.ended().is_none() => {
                composuite_core::control::validate_gripper_width(
                    run.model(),
                    GripperTarget::finger(goal.position, goal.max_effort).opening,
                    goal.max_effort,
                )
                .map(|_| state)
                .map_err(|e| e.to_string())
            }
            (Some(run), _) => Err(format!(
                "episode {} is over; a new episode (reset) lets the gripper move again",
                run.episode
            )),
            _ => Err("no episode yet (the task manager publishes the scene)".into()),
        };
        let state = match checked {
            Ok(state) => state,
            Err(why) => {
                log.warn(format!("{} goal rejected: {why}", names::GRIPPER_ACTION));
                if let Err(err) = Goals::<GripperCommandResult>::reject(server, request_id, &now) {
                    log.warn(err);
                }
                return;
            }
        };
        if let Err(err) = self
            .gripper_goals
            .accept(server, request_id, request.goal_id, &now)
        {
            log.warn(err);
            return;
        }
        let run = self.run.as_mut().expect("checked above");
        let following = GripperFollowing::new(goal, GripperParams::default());
        let ended = run
            .controllers
            .start_gripper(following, request.goal_id, &state);
        self.report(servers, ended, log);
    }

    pub(super) fn on_trajectory_cancel(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        log: &Logger,
    ) {
        let server = servers
            .trajectory
            .as_ref()
            .expect("a cancel came: the server is up");
        let state = self.snapshot();
        let mut run = self.run.as_mut();
        let ended = self
            .trajectory_goals
            .cancel(server, request_id, request, |goal| {
                run.as_deref_mut()?
                    .controllers
                    .cancel_trajectory(goal, state.as_ref()?)
            });
        self.report_cancel(servers, ended, log);
    }

    pub(super) fn on_gripper_cancel(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        log: &Logger,
    ) {
        let server = servers
            .gripper
            .as_ref()
            .expect("a cancel came: the server is up");
        let state = self.snapshot();
        let mut run = self.run.as_mut();
        let ended = self
            .gripper_goals
            .cancel(server, request_id, request, |goal| {
                run.as_deref_mut()?
                    .controllers
                    .cancel_gripper(goal, state.as_ref()?)
            });
        self.report_cancel(servers, ended, log);
    }

    /// Report the goals a cancel ended (their results), or say why the reply was not sent.
    fn report_cancel(
        &mut self,
        servers: &ActionServers,
        ended: (Vec<Event<GoalId>>, Result<(), action_server::ReplyError>),
        log: &Logger,
    ) {
        let (events, replied) = ended;
        if let Err(err) = replied {
            log.warn(err);
        }
        self.report(servers, events, log);
    }

    /// Tell the clients what the controllers did: feedback, and goals that ended.
    pub(super) fn report(
        &mut self,
        servers: &ActionServers,
        events: impl IntoIterator<Item = Event<GoalId>>,
        log: &Logger,
    ) {
        let Some(model) = self.model() else { return };
        for event in events {
            let outcome = match event {
                Event::TrajectoryFeedback { goal, update } => {
                    let Some(server) = &servers.trajectory else {
                        continue;
                    };
                    server
                        .send_feedback(goal, ros_control::feedback(model, &update))
                        .map(|_| ())
                        .map_err(|e| format!("trajectory feedback not sent: {e:?}"))
                }
                Event::TrajectoryEnded {
                    goal: None,
                    end,
                    message,
                    ..
                } => {
                    log.debug(format!("joint_trajectory {end:?}: {message}"));
                    Ok(())
                }
                Event::TrajectoryEnded {
                    goal: Some(goal),
                    end,
                    code,
                    message,
                } => {
                    let Some(server) = &servers.trajectory else {
                        continue;
                    };
                    say_end(log, names::TRAJECTORY_ACTION, end, &message);
                    self.trajectory_goals.end(
                        server,
                        goal,
                        goal_status(end),
                        FollowJointTrajectoryResult {
                            error_code: code,
                            error_string: message,
                        },
                    )
                }
                Event::GripperEnded { goal, end, result } => {
                    let Some(server) = &servers.gripper else {
                        continue;
                    };
                    say_end(
                        log,
                        names::GRIPPER_ACTION,
                        end,
                        &format!(
                            "position {:.4} m, reached_goal {}, stalled {}",
                            result.position, result.reached_goal, result.stalled
                        ),
                    );
                    self.gripper_goals.end(
                        server,
                        goal,
                        goal_status(end),
                        ros_control::gripper_result(&result),
                    )
                }
            };
            if let Err(err) = outcome {
                log.warn(err);
            }
        }
    }
}

/// The action status of a goal that ended so.
fn goal_status(end: End) -> GoalStatusEnum {
    match end {
        End::Succeeded => GoalStatusEnum::Succeeded,
        End::Aborted => GoalStatusEnum::Aborted,
        End::Canceled => GoalStatusEnum::Canceled,
    }
}

/// Log a goal's end: success at debug level (there may be one per step), the rest louder.
fn say_end(log: &Logger, action: &str, end: End, message: &str) {
    match end {
        End::Succeeded => log.debug(format!("{action} goal succeeded: {message}")),
        End::Canceled => log.info(format!("{action} goal canceled: {message}")),
        End::Aborted => log.warn(format!("{action} goal aborted: {message}")),
    }
}
