//! The gripper: how it is commanded, the pad gap of a finger position and back, and the finger
//! servos' targets and force limit for a command.

use super::SimWorld;
use crate::physics::robot_model::ARM_DOF;

/// How the gripper is being commanded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GripperCommand {
    /// Reach this opening between the pads (m) with at most this force per finger (N).
    Width {
        /// Target pad gap (m); clamped to what the fingers can reach.
        width: f64,
        /// Force limit per finger (N), at most the servo's limit.
        max_effort: f64,
    },
    /// The reference's scheme: an internal command c in [−1, 1] moves by 0.01·sign(action)
    /// every physics step (+ closes, − opens, 0 holds) and maps linearly onto the servo range.
    Reference {
        /// The last action's gripper component; only its sign matters.
        action: f64,
    },
}

/// The pad gap at finger position `q_left` (fingers coupled, q_right = −q_left):
/// 0.0371 m at q = 0 (docs/src/reference-facts.md §4.4).
pub fn pad_gap(q_left: f64) -> f64 {
    PAD_GAP_AT_ZERO + 2.0 * q_left
}

/// The left finger position whose pad gap is `gap` (the inverse of [`pad_gap`]).
pub fn finger_for_gap(gap: f64) -> f64 {
    (gap - PAD_GAP_AT_ZERO) / 2.0
}

/// Pad gap (m) with both fingers at 0.
const PAD_GAP_AT_ZERO: f64 = 0.0371;

/// The fully open finger position (m), where every episode starts
/// (docs/src/reference-facts.md §4.4).
pub const FINGER_OPEN: f64 = 0.020833;

/// The reference maps its gripper command c linearly onto the actuator range: +1 aims the left
/// finger at −0.020833 (past its closed stop), −1 at +0.0115 (its "open").
const REFERENCE_FINGER_AIMS: (f64, f64) = (-0.020833, 0.0115);

/// Where the reference's gripper command `c` (in [−1, 1]) aims the left finger (m).
fn reference_finger_aim(c: f64) -> f64 {
    let (closed, open) = REFERENCE_FINGER_AIMS;
    open + (c + 1.0) / 2.0 * (closed - open)
}

/// The reference gripper command that aims the pads at a gap of `gap` (m); the inverse of
/// where the reference aims the finger for a command, and of [`pad_gap`]; not clamped.
pub fn reference_command_for_gap(gap: f64) -> f64 {
    let (closed, open) = REFERENCE_FINGER_AIMS;
    2.0 * (finger_for_gap(gap) - open) / (closed - open) - 1.0
}

impl SimWorld {
    /// Command the gripper.
    pub fn set_gripper(&mut self, command: GripperCommand) {
        self.gripper_command = command;
    }

    /// The reference's internal gripper command c in [−1, 1] (+1 closed).
    pub fn gripper_c(&self) -> f64 {
        self.gripper_c
    }

    /// Finger servo targets (left, right) and force limit for the current command; advances
    /// the reference's internal command by one physics step.
    pub(super) fn finger_targets(&mut self) -> ([f64; 2], f64) {
        let (lo, hi) = self.model.joints[ARM_DOF].limits.expect("finger limits");
        match self.gripper_command {
            GripperCommand::Width { width, max_effort } => {
                let mut q = (width - pad_gap(0.0)) / 2.0;
                if q <= lo {
                    // Closing onto the stop (or an object): aim past it so the force saturates.
                    q = lo - self.gripper.close_overshoot;
                }
                let q = q.min(hi);
                let force = if max_effort > 0.0 {
                    max_effort.min(self.gripper.max_force)
                } else {
                    self.gripper.max_force
                };
                ([q, -q], force)
            }
            GripperCommand::Reference { action } => {
                let step = if action > 0.0 {
                    0.01
                } else if action < 0.0 {
                    -0.01
                } else {
                    0.0
                };
                self.gripper_c = (self.gripper_c + step).clamp(-1.0, 1.0);
                let q = reference_finger_aim(self.gripper_c);
                ([q, -q], self.gripper.max_force)
            }
        }
    }
}
