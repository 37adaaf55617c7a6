//! The controllers the sim offers, named and typed as a ros2_control driver's controllers are,
//! with the hardware interfaces each one needs: what `controller_manager`'s
//! `list_controllers` and `list_hardware_interfaces` report.

use composuite_core::physics::{ARM_DOF, RobotModel};

use crate::sim::hardware::JOINTS;

/// A controller the sim can run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Controller {
    /// `/joint_states` from every state interface (always up: the suite's own contract).
    JointStateBroadcaster,
    /// `joint_trajectory_controller/{follow_joint_trajectory,joint_trajectory}`.
    JointTrajectory,
    /// `forward_position_controller/commands`.
    ForwardPosition,
    /// `gripper_action_controller/gripper_cmd`.
    GripperAction,
}

/// The controllers the `controllers` parameter can name, in listing order.
pub const OPTIONAL: [Controller; 3] = [
    Controller::JointTrajectory,
    Controller::ForwardPosition,
    Controller::GripperAction,
];

/// The interface kinds, as ros2_control names them.
const POSITION: &str = "position";
const VELOCITY: &str = "velocity";

impl Controller {
    /// The controller's name (its topics and actions live under it).
    pub fn name(self) -> &'static str {
        match self {
            Controller::JointStateBroadcaster => "joint_state_broadcaster",
            Controller::JointTrajectory => "joint_trajectory_controller",
            Controller::ForwardPosition => "forward_position_controller",
            Controller::GripperAction => "gripper_action_controller",
        }
    }

    /// The plugin type ros2_controllers gives such a controller.
    pub fn type_name(self) -> &'static str {
        match self {
            Controller::JointStateBroadcaster => "joint_state_broadcaster/JointStateBroadcaster",
            Controller::JointTrajectory => "joint_trajectory_controller/JointTrajectoryController",
            Controller::ForwardPosition => "position_controllers/JointGroupPositionController",
            Controller::GripperAction => "position_controllers/GripperActionController",
        }
    }

    /// The controller named `name`, among the optional ones.
    pub fn parse(name: &str) -> Option<Controller> {
        OPTIONAL.into_iter().find(|c| c.name() == name)
    }

    /// The command interfaces it claims (`<joint>/position`).
    pub fn command_interfaces(self, model: &RobotModel) -> Vec<String> {
        match self {
            Controller::JointStateBroadcaster => Vec::new(),
            Controller::JointTrajectory | Controller::ForwardPosition => {
                interfaces(model, 0..ARM_DOF, &[POSITION])
            }
            Controller::GripperAction => interfaces(model, ARM_DOF..JOINTS, &[POSITION]),
        }
    }

    /// The state interfaces it reads.
    pub fn state_interfaces(self, model: &RobotModel) -> Vec<String> {
        match self {
            Controller::JointStateBroadcaster => state_interfaces(model),
            Controller::JointTrajectory => interfaces(model, 0..ARM_DOF, &[POSITION, VELOCITY]),
            Controller::ForwardPosition => Vec::new(),
            Controller::GripperAction => interfaces(model, ARM_DOF..JOINTS, &[POSITION, VELOCITY]),
        }
    }
}

/// Parse the `controllers` parameter: names of optional controllers, each at most once.
pub fn parse_list(names: &[String]) -> Result<Vec<Controller>, String> {
    let mut out = Vec::new();
    for name in names {
        let controller = Controller::parse(name).ok_or_else(|| {
            format!(
                "unknown controller `{name}`; valid: {}",
                OPTIONAL.map(Controller::name).join(", ")
            )
        })?;
        if out.contains(&controller) {
            return Err(format!("controller `{name}` is named twice"));
        }
        out.push(controller);
    }
    out.sort();
    Ok(out)
}

/// Every command interface of the hardware, sorted as controller_manager lists them.
pub fn command_interfaces(model: &RobotModel) -> Vec<String> {
    let mut all = interfaces(model, 0..JOINTS, &[POSITION]);
    all.sort();
    all
}

/// Every state interface of the hardware, sorted as controller_manager lists them.
pub fn state_interfaces(model: &RobotModel) -> Vec<String> {
    let mut all = interfaces(model, 0..JOINTS, &[POSITION, VELOCITY]);
    all.sort();
    all
}

fn interfaces(model: &RobotModel, joints: std::ops::Range<usize>, kinds: &[&str]) -> Vec<String> {
    model.joints[joints]
        .iter()
        .flat_map(|joint| {
            kinds
                .iter()
                .map(move |kind| format!("{}/{kind}", joint.name))
        })
        .collect()
}
