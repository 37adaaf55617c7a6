//! Stepping a paused simulation: the `step_simulation` service and the `simulate_steps` action
//! (its goals, feedback, cancels and results), each step one control period with the last
//! command held.

use composuite_msgs::simulation_interfaces::action::{
    SimulateStepsFeedback, SimulateStepsGoal, SimulateStepsResult,
};
use composuite_msgs::simulation_interfaces::msg::Result as SimResult;
use ros2_client::RmwRequestId;
use ros2_client::action::{GoalId, GoalStatusEnum, SendGoalRequest};
use ros2_client::action_msgs::CancelGoalRequest;

use super::{Servers, StepsServer};
use crate::shared::convert;
use crate::shared::names;
use crate::shared::node::Logger;
use crate::sim::stepping::Advance;
use crate::sim::{ActionServers, Mode, Sim};
use crate::simulation_interfaces::{failed, ok};

/// The `simulate_steps` goal being executed.
pub(in crate::sim) struct StepsGoal {
    pub(super) id: GoalId,
    /// The episode it steps: a new episode ends it.
    episode: u32,
    pub(super) total: u64,
    pub(super) done: u64,
}

/// Why a step cannot be taken now, as the standard's result.
enum NoStep {
    /// Not paused (realtime), or no episode, or the episode is over.
    Refused(SimResult),
}

impl Sim {
    /// Whether one step may be taken now, or the standard's result saying why not.
    fn may_step(&self) -> Result<(), NoStep> {
        if self.mode != Mode::Lockstep {
            return Err(NoStep::Refused(failed(
                SimResult::RESULT_OPERATION_FAILED,
                "the simulation is PLAYING (realtime): steps are taken only when it is PAUSED; \
                 set_simulation_state to STATE_PAUSED first",
            )));
        }
        let Some(run) = &self.run else {
            return Err(NoStep::Refused(failed(
                SimResult::RESULT_INCORRECT_STATE,
                "no episode yet (the task manager publishes the scene)",
            )));
        };
        if run.env.ended().is_some() {
            return Err(NoStep::Refused(failed(
                SimResult::RESULT_INCORRECT_STATE,
                format!(
                    "episode {} is over after {} steps; reset_simulation starts the next",
                    run.episode,
                    run.env.steps()
                ),
            )));
        }
        Ok(())
    }

    /// `steps` control periods with the last command held, each published as a lockstep
    /// command's step is; stops early if the episode ends.
    pub(super) fn step_simulation(
        &mut self,
        servers: &ActionServers,
        steps: u64,
        log: &Logger,
    ) -> SimResult {
        if steps == 0 {
            return failed(
                SimResult::RESULT_OPERATION_FAILED,
                "steps is 0; a step is one control period, and at least 1 is needed",
            );
        }
        for done in 0..steps {
            if let Err(NoStep::Refused(mut result)) = self.may_step() {
                if done > 0 {
                    result.error_message =
                        format!("{} of {steps} steps done: {}", done, result.error_message);
                }
                return result;
            }
            if !self.advance(servers, Advance::Command, log) {
                return failed(
                    SimResult::RESULT_OPERATION_FAILED,
                    format!(
                        "{done} of {steps} steps done: the sim refused the held command (see its log)"
                    ),
                );
            }
        }
        ok()
    }

    pub(super) fn on_steps_goal(
        &mut self,
        server: &StepsServer,
        request_id: RmwRequestId,
        request: SendGoalRequest<SimulateStepsGoal>,
        log: &Logger,
    ) {
        let now = convert::time_from_nanos(self.sim_time_ns);
        if let Err(err) = self
            .steps_goals
            .accept(server, request_id, request.goal_id, &now)
        {
            log.warn(err);
            return;
        }
        // Accepted, then ended at once when it cannot run: the result says why (a rejection
        // could not).
        let refused = if request.goal.steps == 0 {
            Some(failed(
                SimResult::RESULT_OPERATION_FAILED,
                "steps is 0; a step is one control period, and at least 1 is needed",
            ))
        } else if let Some(running) = &self.steps_running {
            Some(failed(
                SimResult::RESULT_INCORRECT_STATE,
                format!(
                    "another simulate_steps goal is running ({} of {} steps done); cancel it or \
                     wait for it",
                    running.done, running.total
                ),
            ))
        } else {
            self.may_step().err().map(|NoStep::Refused(result)| result)
        };
        match refused {
            Some(result) => {
                let message = result.error_message.clone();
                self.end_steps_goal(
                    server,
                    request.goal_id,
                    GoalStatusEnum::Aborted,
                    result.result,
                    message,
                    log,
                );
            }
            None => {
                self.steps_running = Some(StepsGoal {
                    id: request.goal_id,
                    episode: self.run.as_ref().map_or(0, |r| r.episode),
                    total: request.goal.steps,
                    done: 0,
                })
            }
        }
    }

    /// Whether a `simulate_steps` goal wants the next step (the loop calls
    /// [`Sim::simulate_step`] then).
    pub(in crate::sim) fn steps_goal_running(&self) -> bool {
        self.steps_running.is_some()
    }

    /// One step of the running `simulate_steps` goal, its feedback, and its end when done.
    pub(in crate::sim) fn simulate_step(
        &mut self,
        servers: &ActionServers,
        si_servers: &Servers,
        log: &Logger,
    ) {
        let Some(mut goal) = self.steps_running.take() else {
            return;
        };
        let server = &si_servers.steps;
        if self.run.as_ref().is_some_and(|r| r.episode != goal.episode) {
            let message = format!(
                "{} of {} steps done: a new episode started",
                goal.done, goal.total
            );
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Aborted,
                SimResult::RESULT_INCORRECT_STATE,
                message,
                log,
            );
            return;
        }
        if let Err(NoStep::Refused(result)) = self.may_step() {
            let message = format!(
                "{} of {} steps done: {}",
                goal.done, goal.total, result.error_message
            );
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Aborted,
                result.result,
                message,
                log,
            );
            return;
        }
        if !self.advance(servers, Advance::Command, log) {
            let message = format!(
                "{} of {} steps done: the sim refused the held command (see its log)",
                goal.done, goal.total
            );
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Aborted,
                SimResult::RESULT_OPERATION_FAILED,
                message,
                log,
            );
            return;
        }
        goal.done += 1;
        let feedback = SimulateStepsFeedback {
            completed_steps: goal.done,
            remaining_steps: goal.total - goal.done,
        };
        if let Err(err) = server.send_feedback(goal.id, feedback) {
            log.warn(format!(
                "{} feedback not sent: {err:?}",
                names::SIMULATE_STEPS
            ));
        }
        if goal.done == goal.total {
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Succeeded,
                SimResult::RESULT_OK,
                String::new(),
                log,
            );
        } else {
            self.steps_running = Some(goal);
        }
    }

    pub(super) fn on_steps_cancel(
        &mut self,
        server: &StepsServer,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        log: &Logger,
    ) {
        let running = &mut self.steps_running;
        let (ended, replied) = self.steps_goals.cancel(server, request_id, request, |id| {
            running.take_if(|g| g.id == id)
        });
        if let Err(err) = replied {
            log.warn(err);
        }
        for goal in ended {
            let message = format!("canceled after {} of {} steps", goal.done, goal.total);
            self.end_steps_goal(
                server,
                goal.id,
                GoalStatusEnum::Canceled,
                SimResult::RESULT_OK,
                message,
                log,
            );
        }
    }

    pub(super) fn end_steps_goal(
        &mut self,
        server: &StepsServer,
        id: GoalId,
        status: GoalStatusEnum,
        code: u8,
        message: String,
        log: &Logger,
    ) {
        match status {
            GoalStatusEnum::Succeeded => {
                log.debug(format!("{} goal succeeded", names::SIMULATE_STEPS))
            }
            _ => log.info(format!(
                "{} goal {status:?}: {message}",
                names::SIMULATE_STEPS
            )),
        }
        let result = SimulateStepsResult {
            result: failed(code, message),
        };
        if let Err(err) = self.steps_goals.end(server, id, status, result) {
            log.warn(err);
        }
    }
}
