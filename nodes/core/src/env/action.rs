//! The two ways to act: absolute joint targets (the ROS interface) or the reference
//! benchmark's normalised deltas (so agents written for it work unchanged).

use crate::control::{Clamped, validate_arm_targets, validate_gripper_width};
use crate::physics::{ARM_DOF, GripperCommand, ServoMode, SimWorld, pad_gap};

use super::EnvError;

/// How far the reference's joint goal moves per unit action (rad),
/// docs/src/reference-facts.md §4.2.
pub(crate) const REFERENCE_DELTA_SCALE: f64 = 0.05;

/// An opening change smaller than this (m) counts as "hold" when an absolute gripper command
/// is translated into the reference's open/close sign.
const GRIPPER_HOLD_BAND: f64 = 0.001;

/// One control step's command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Action {
    /// Absolute arm joint targets (rad, URDF joint order) and optionally a gripper opening.
    Absolute {
        /// Joint position targets (rad); clamped into the joint limits, refused if not finite.
        joints: [f64; ARM_DOF],
        /// `(opening in m, max effort in N, 0 = default)`, or `None` to keep the last command.
        gripper: Option<(f64, f64)>,
    },
    /// The reference's 8 numbers in [−1, 1]: joint goal = measured q + 0.05·a[0..7] (not
    /// clamped to the joint limits: as in the reference, the limit stops the joint), and the
    /// sign of `a[7]` moves the gripper (+ close, − open), with the reference's soft controller.
    Reference([f64; 8]),
}

impl Action {
    /// Whether `world` would refuse this action (what [`Action::apply`] checks first), without
    /// touching it.
    pub(crate) fn check(&self, world: &SimWorld) -> Result<(), EnvError> {
        match self {
            Action::Absolute { joints, gripper } => {
                validate_arm_targets(world.model, joints).map_err(EnvError::Arm)?;
                if let Some((width, effort)) = gripper {
                    validate_gripper_width(world.model, *width, *effort)
                        .map_err(EnvError::Gripper)?;
                }
                Ok(())
            }
            Action::Reference(a) => match a.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                Some((index, value)) => Err(EnvError::BadReferenceAction {
                    index,
                    value: *value,
                }),
                None => Ok(()),
            },
        }
    }

    /// Validate and hand the action to the world; returns what was clamped.
    pub(super) fn apply(
        &self,
        world: &mut SimWorld,
        last_gripper_action: &mut f64,
    ) -> Result<Vec<Clamped>, EnvError> {
        match self {
            Action::Absolute { joints, gripper } => {
                let (targets, mut clamped) =
                    validate_arm_targets(world.model, joints).map_err(EnvError::Arm)?;
                let gripper = match gripper {
                    Some((width, effort)) => {
                        let (width, c) = validate_gripper_width(world.model, *width, *effort)
                            .map_err(EnvError::Gripper)?;
                        clamped.extend(c);
                        Some((width, *effort))
                    }
                    None => None,
                };
                world.set_servo_mode(ServoMode::Stiff);
                world.set_arm_targets(&targets);
                if let Some((width, max_effort)) = gripper {
                    // What the reward's "open command" test sees: wider than now is opening.
                    let now = pad_gap(world.finger_positions()[0]);
                    *last_gripper_action = if width > now + GRIPPER_HOLD_BAND {
                        -1.0
                    } else if width < now - GRIPPER_HOLD_BAND {
                        1.0
                    } else {
                        0.0
                    };
                    world.set_gripper(GripperCommand::Width { width, max_effort });
                }
                Ok(clamped)
            }
            Action::Reference(a) => {
                self.check(world)?;
                let a = a.map(|v| v.clamp(-1.0, 1.0));
                let q = world.arm_positions();
                let goal: [f64; ARM_DOF] =
                    std::array::from_fn(|j| q[j] + REFERENCE_DELTA_SCALE * a[j]);
                world.set_servo_mode(ServoMode::Reference);
                world.set_arm_targets(&goal);
                world.set_gripper(GripperCommand::Reference { action: a[7] });
                *last_gripper_action = a[7];
                Ok(Vec::new())
            }
        }
    }
}
