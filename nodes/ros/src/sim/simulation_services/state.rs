//! The standard's simulation state, which is the sim's `mode`: getting it, and setting it
//! through the `mode` parameter (lockstep is PAUSED, realtime PLAYING).

use composuite_msgs::simulation_interfaces::msg::{Result as SimResult, SimulationState};
use composuite_msgs::simulation_interfaces::srv;
use ros2_client::ParameterValue;
use ros2_client::action::GoalStatusEnum;

use super::Servers;
use crate::shared::names;
use crate::shared::node::Logger;
use crate::sim::{Mode, Sim};
use crate::simulation_interfaces::{failed, ok};

impl Sim {
    /// The standard's state: no world before the first scene; PAUSED in lockstep, PLAYING in
    /// realtime.
    pub(super) fn simulation_state(&self) -> u8 {
        match (&self.run, self.mode) {
            (None, _) => SimulationState::STATE_NO_WORLD,
            (Some(_), Mode::Lockstep) => SimulationState::STATE_PAUSED,
            (Some(_), Mode::Realtime) => SimulationState::STATE_PLAYING,
        }
    }

    pub(super) fn set_simulation_state(
        &mut self,
        target: u8,
        si_servers: &Servers,
        log: &Logger,
    ) -> SimResult {
        use srv::SetSimulationStateResponse as R;
        let mode = match target {
            SimulationState::STATE_PLAYING => Mode::Realtime,
            SimulationState::STATE_PAUSED => Mode::Lockstep,
            SimulationState::STATE_STOPPED => {
                return failed(
                    SimResult::RESULT_FEATURE_UNSUPPORTED,
                    "STATE_STOPPED (paused and reset) is not offered: reset_simulation starts a \
                     new episode, and STATE_PAUSED holds it",
                );
            }
            SimulationState::STATE_QUITTING => {
                return failed(
                    SimResult::RESULT_FEATURE_UNSUPPORTED,
                    "STATE_QUITTING is not offered: the suite stops on SIGINT/SIGTERM, as \
                     `ros2 launch` stops it",
                );
            }
            other => {
                return failed(
                    R::INCORRECT_TRANSITION,
                    format!(
                        "state {other} is not a state to set; valid targets: STATE_PLAYING (1), \
                         STATE_PAUSED (2)"
                    ),
                );
            }
        };
        if mode == self.mode {
            return failed(
                R::ALREADY_IN_TARGET_STATE,
                format!("already {}", state_name(target)),
            );
        }
        if mode == Mode::Realtime
            && let Some(goal) = self.steps_running.take()
        {
            let message = format!(
                "the simulation was set to PLAYING after {} of {} steps",
                goal.done, goal.total
            );
            self.end_steps_goal(
                &si_servers.steps,
                goal.id,
                GoalStatusEnum::Aborted,
                SimResult::RESULT_INCORRECT_STATE,
                message,
                log,
            );
        }
        // Through the parameter, so `ros2 param get` agrees; its change (handled next, before any
        // other request) sets the realtime timer.
        let value = match mode {
            Mode::Lockstep => "lockstep",
            Mode::Realtime => "realtime",
        };
        if let Err(err) = self
            .parameters
            .set("mode", ParameterValue::String(value.into()))
        {
            return failed(R::STATE_TRANSITION_ERROR, err);
        }
        self.mode = mode;
        log.info(format!(
            "{}: now {}",
            names::SET_SIMULATION_STATE,
            state_name(target)
        ));
        ok()
    }
}

fn state_name(state: u8) -> &'static str {
    match state {
        SimulationState::STATE_PLAYING => "PLAYING",
        SimulationState::STATE_PAUSED => "PAUSED",
        _ => "in that state",
    }
}
