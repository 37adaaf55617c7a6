//! Commands entering the simulation: validation against the arm's limits.

mod limits;

pub use limits::{
    ArmCommandError, Clamped, GripperCommandError, validate_arm_targets, validate_gripper_width,
};
