//! The direct commands on topics: `joint_command`, `gripper_command`, the forward position
//! controller's `commands`, and `reference_action(_stamped)`; each checked on arrival, held by
//! the controllers, and in lockstep stepping the sim one period.

use composuite_core::physics::ARM_DOF;
use composuite_msgs::builtin_interfaces::msg::Time as BuiltinTime;
use composuite_msgs::control_msgs::msg::GripperCommand;
use composuite_msgs::sensor_msgs::msg::JointState;
use composuite_msgs::std_msgs::msg::Float64MultiArray;

use super::controllers::forward;
use super::hardware::{ArmCommand, GripperTarget, read_env};
use super::stepping::Advance;
use super::{ActionServers, Mode, Running, Sim};
use crate::shared::convert;
use crate::shared::names;
use crate::shared::node::Logger;

/// Whether a command stamped `stamp` answers an observation from before this episode began —
/// e.g. sent by an agent that died with it in flight while another reset — and must not step
/// this one (said in the log). Agents stamp a command with the observation it answers; a zero
/// stamp (unstamped) is always taken.
fn sent_for_earlier_episode(run: &Running, stamp: &BuiltinTime, what: &str, log: &Logger) -> bool {
    let stamp = convert::nanos_of(stamp);
    let stale = stamp != 0 && stamp < run.started_ns;
    if stale {
        log.warn(format!(
            "{what} dropped: stamped {stamp}, before this episode began at {} (sim time, ns): \
             it answers an earlier episode's observation",
            run.started_ns
        ));
    }
    stale
}

/// Values in a `reference_action`: seven joint deltas and the gripper.
const REFERENCE_ACTION_LEN: usize = ARM_DOF + 1;

impl Sim {
    /// The running episode, or `None` after saying why `what` is ignored.
    fn episode_for(&mut self, what: &str, log: &Logger) -> Option<&mut Running> {
        if self.run.is_none() {
            log.warn(format!(
                "{what} ignored: no episode yet (the task manager publishes the scene)"
            ));
        }
        self.run.as_mut()
    }

    pub(super) fn on_gripper(
        &mut self,
        servers: &ActionServers,
        command: &GripperCommand,
        log: &Logger,
    ) {
        let time_ns = self.sim_time_ns;
        let Some(run) = self.episode_for("gripper_command", log) else {
            return;
        };
        let state = read_env(&run.env, time_ns);
        // Checked now so a bad command is refused on arrival, not at the next step.
        if let Err(err) = composuite_core::control::validate_gripper_width(
            run.model(),
            command.position,
            command.max_effort,
        ) {
            log.warn(format!("gripper_command refused: {err}"));
            return;
        }
        let target = GripperTarget {
            opening: command.position,
            max_effort: command.max_effort,
        };
        let ended = run.controllers.command_gripper(target, &state);
        self.report(servers, ended, log);
    }

    pub(super) fn on_joint_command(
        &mut self,
        servers: &ActionServers,
        command: &JointState,
        log: &Logger,
    ) {
        let time_ns = self.sim_time_ns;
        let Some(run) = self.episode_for("joint_command", log) else {
            return;
        };
        if sent_for_earlier_episode(run, &command.header.stamp, "joint_command", log) {
            return;
        }
        let state = read_env(&run.env, time_ns);
        let model = run.model();
        let (arm, finger_gap) = match convert::arm_command(model, command) {
            Ok(parsed) => parsed,
            Err(err) => {
                log.warn(format!("joint_command refused: {err}"));
                return;
            }
        };
        // Refused on arrival with the core's own checks, so the held targets (what realtime
        // steps with) never hold a value the next step would refuse.
        let checked = composuite_core::control::validate_arm_targets(model, &arm)
            .map(|_| ())
            .map_err(|e| e.to_string())
            .and_then(|()| match finger_gap {
                Some(gap) => composuite_core::control::validate_gripper_width(model, gap, 0.0)
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
                None => Ok(()),
            });
        if let Err(err) = checked {
            log.warn(format!("joint_command refused: {err}"));
            return;
        }
        let mut ended: Vec<_> = run
            .controllers
            .command_arm(ArmCommand::Positions(arm), names::JOINT_COMMAND)
            .into_iter()
            .collect();
        if let Some(gap) = finger_gap {
            let target = GripperTarget {
                opening: gap,
                max_effort: 0.0,
            };
            ended.extend(run.controllers.command_gripper(target, &state));
        }
        self.report(servers, ended, log);
        if self.mode == Mode::Lockstep {
            self.advance(servers, Advance::Command, log);
        }
    }

    pub(super) fn on_forward_command(
        &mut self,
        servers: &ActionServers,
        command: &Float64MultiArray,
        log: &Logger,
    ) {
        let what = names::FORWARD_COMMANDS;
        let Some(run) = self.episode_for(what, log) else {
            return;
        };
        let targets = match forward::parse_command(run.model(), &command.data) {
            Ok(targets) => targets,
            Err(err) => {
                log.warn(format!("{what} refused: {err}"));
                return;
            }
        };
        let ended = run
            .controllers
            .command_arm(ArmCommand::Positions(targets), what);
        self.report(servers, ended, log);
        if self.mode == Mode::Lockstep {
            self.advance(servers, Advance::Command, log);
        }
    }

    /// A reference action from `what`: the unstamped topic's values, or the stamped one's with
    /// the stamp of the observation it answers.
    pub(super) fn on_reference_action(
        &mut self,
        servers: &ActionServers,
        action: &[f64],
        stamp: Option<&BuiltinTime>,
        what: &str,
        log: &Logger,
    ) {
        let Some(run) = self.episode_for(what, log) else {
            return;
        };
        if stamp.is_some_and(|stamp| sent_for_earlier_episode(run, stamp, what, log)) {
            return;
        }
        let values: [f64; REFERENCE_ACTION_LEN] = match action.try_into() {
            Ok(values) => values,
            Err(_) => {
                log.warn(format!(
                    "{what} refused: it has {} values; it needs {REFERENCE_ACTION_LEN} \
                     (7 joint deltas, then the gripper), each in [-1, 1]",
                    action.len()
                ));
                return;
            }
        };
        // Out-of-range values are clipped, as the reference does; non-finite ones refused here
        // so the held command never holds a value the next step would refuse.
        if let Some((index, value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            log.warn(format!(
                "{what} refused: value {index} is {value}; each must be finite \
                 (it is clipped to [-1, 1])"
            ));
            return;
        }
        let ended = run
            .controllers
            .command_arm(ArmCommand::Reference(values), what);
        self.report(servers, ended, log);
        if self.mode == Mode::Lockstep {
            self.advance(servers, Advance::Command, log);
        }
    }
}
