//! The forward position controller, as ros2_controllers' `forward_command_controller` in its
//! `position_controllers/JointGroupPositionController` form: a `Float64MultiArray` with one
//! position per arm joint, in the controller's joint order, written as is. Unlike the Jazzy
//! controller (which errors in its update and gets deactivated on a wrong-length command), a bad
//! command is refused on arrival with the reason and the controller stays up.

use composuite_core::control::validate_arm_targets;
use composuite_core::physics::{ARM_DOF, RobotModel};

/// The arm targets a forward command carries, or why it is refused: the same checks
/// `joint_command` gets (seven finite values; out-of-limit targets are clamped at the step and
/// reported), so both reach the world alike.
pub fn parse_command(model: &RobotModel, data: &[f64]) -> Result<[f64; ARM_DOF], String> {
    validate_arm_targets(model, data).map_err(|e| e.to_string())?;
    Ok(data.try_into().expect("validated: one value per arm joint"))
}
