//! The sim node's parameters: their specs and checks, the [`Mode`] that `mode` names, and
//! what a change at run time does.

use ros2_client::ParameterValue;

use super::Sim;
use super::cameras;
use super::controllers::catalog;
use crate::shared::node::{Logger, ParamChange};
use crate::shared::params::{ParamSpec, any_value, positive_number};

fn check_mode(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::String(s) if Mode::parse(s).is_some() => Ok(()),
        _ => Err("valid: lockstep, realtime".into()),
    }
}

fn check_controllers(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::StringArray(names) => catalog::parse_list(names).map(|_| ()),
        _ => Err("a list of controller names".into()),
    }
}

/// The sim node's parameters.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mode",
        default: || ParameterValue::String("lockstep".into()),
        description: "lockstep: one control period per command (goals advance the sim \
                      themselves); realtime: wall-clock pace",
        check: check_mode,
    },
    ParamSpec {
        name: "realtime_factor",
        default: || ParameterValue::Double(1.0),
        description: "realtime mode: sim seconds per wall second",
        check: positive_number,
    },
    ParamSpec {
        name: "task_observation",
        default: || ParameterValue::Boolean(true),
        description: "include the task one-hots in observation.flat (93 values) or not (77)",
        check: any_value,
    },
    ParamSpec {
        name: "controllers",
        default: || {
            ParameterValue::StringArray(
                catalog::OPTIONAL
                    .iter()
                    .map(|c| c.name().to_string())
                    .collect(),
            )
        },
        description: "ros2_control controllers to offer (read at start-up): \
                      joint_trajectory_controller, forward_position_controller, \
                      gripper_action_controller",
        check: check_controllers,
    },
    ParamSpec {
        name: "cameras",
        default: || ParameterValue::StringArray(Vec::new()),
        description: "cameras whose images to publish on camera/<name>/image_raw and \
                      camera_info after every step (read at start-up): frontview, agentview, \
                      birdview, sideview, eye_in_hand",
        check: cameras::check_cameras,
    },
    ParamSpec {
        name: "camera_width",
        default: || ParameterValue::Integer(cameras::DEFAULT_SIZE),
        description: "width of the published images (pixels, read at start-up)",
        check: cameras::check_size,
    },
    ParamSpec {
        name: "camera_height",
        default: || ParameterValue::Integer(cameras::DEFAULT_SIZE),
        description: "height of the published images (pixels, read at start-up)",
        check: cameras::check_size,
    },
    ParamSpec {
        name: "fault_panic",
        default: || ParameterValue::Boolean(false),
        description: "fault injection, for testing how a suite survives a failing node: set it \
                      to true and the sim panics at once (composed, its environment is \
                      restarted; as a process, the process dies and launch respawns it)",
        check: any_value,
    },
];

/// How the sim advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// One control period per direct command; a running goal advances the sim itself.
    Lockstep,
    /// Wall-clock pace, last targets held.
    Realtime,
}

impl Mode {
    /// `lockstep` / `realtime`.
    pub fn parse(s: &str) -> Option<Mode> {
        match s.to_ascii_lowercase().as_str() {
            "lockstep" => Some(Mode::Lockstep),
            "realtime" => Some(Mode::Realtime),
            _ => None,
        }
    }
}

impl Sim {
    pub(super) fn on_param(&mut self, change: &ParamChange, log: &Logger) {
        match (change.name.as_str(), &change.value) {
            ("mode", ParameterValue::String(s)) => {
                if let Some(mode) = Mode::parse(s) {
                    self.mode = mode;
                    log.info(format!("mode is now {mode:?}"));
                }
            }
            ("realtime_factor", ParameterValue::Double(f)) => self.realtime_factor = *f,
            ("task_observation", ParameterValue::Boolean(b)) => {
                self.task_observation = *b;
                log.info("task_observation takes effect with the next scene");
            }
            ("controllers" | "cameras" | "camera_width" | "camera_height", _) => log.warn(format!(
                "{} takes effect when the sim starts again; unchanged now",
                change.name
            )),
            ("fault_panic", ParameterValue::Boolean(true)) => {
                log.error("fault_panic was set: panicking now, as asked");
                panic!("fault_panic was set (fault injection)");
            }
            _ => {}
        }
    }
}
