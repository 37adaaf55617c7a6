//! The one place joint commands are checked. Bad input never reaches the physics: NaN/∞ and
//! wrong lengths are refused with an error naming what was wrong and what is valid; targets
//! beyond a joint's limits are clamped and reported.

use std::fmt;

use crate::physics::{ARM_DOF, RobotModel, pad_gap};

/// An arm command that cannot be applied.
#[derive(Debug, Clone, PartialEq)]
pub enum ArmCommandError {
    /// Not one value per arm joint.
    WrongLength {
        /// Values given.
        got: usize,
        /// The arm's joint names, in order.
        joints: Vec<String>,
    },
    /// A value is NaN or infinite.
    NotFinite {
        /// Joint name.
        joint: String,
        /// The value.
        value: f64,
    },
}

impl fmt::Display for ArmCommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ArmCommandError::WrongLength { got, joints } => write!(
                f,
                "arm command has {got} values; expected {} (one per joint: {})",
                joints.len(),
                joints.join(", ")
            ),
            ArmCommandError::NotFinite { joint, value } => {
                write!(
                    f,
                    "arm command for joint `{joint}` is {value}; targets must be finite numbers (rad)"
                )
            }
        }
    }
}

impl std::error::Error for ArmCommandError {}

/// A target that was moved to the nearest limit.
#[derive(Debug, Clone, PartialEq)]
pub struct Clamped {
    /// Joint name.
    pub joint: String,
    /// What was asked (rad or m).
    pub requested: f64,
    /// What is applied.
    pub applied: f64,
    /// The joint's lower limit.
    pub lower: f64,
    /// The joint's upper limit.
    pub upper: f64,
}

impl fmt::Display for Clamped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Six decimals: µrad / µm, enough to read and short (limits like 0.0141 come out of
        // arithmetic as 0.014100000000000001).
        write!(
            f,
            "target {:.6} for `{}` is outside its limits [{:.6}, {:.6}]; using {:.6}",
            self.requested, self.joint, self.lower, self.upper, self.applied
        )
    }
}

/// Check absolute arm joint targets (rad): exactly seven finite values; each clamped into its
/// joint's limits (continuous joints are not clamped). Returns the targets to apply and the
/// list of clamped ones.
pub fn validate_arm_targets(
    model: &RobotModel,
    targets: &[f64],
) -> Result<([f64; ARM_DOF], Vec<Clamped>), ArmCommandError> {
    let joints = &model.joints[..ARM_DOF];
    if targets.len() != ARM_DOF {
        return Err(ArmCommandError::WrongLength {
            got: targets.len(),
            joints: joints.iter().map(|j| j.name.clone()).collect(),
        });
    }
    let mut out = [0.0; ARM_DOF];
    let mut clamped = Vec::new();
    for (i, (joint, &value)) in joints.iter().zip(targets).enumerate() {
        if !value.is_finite() {
            return Err(ArmCommandError::NotFinite {
                joint: joint.name.clone(),
                value,
            });
        }
        out[i] = value;
        if let Some((lower, upper)) = joint.limits {
            let applied = value.clamp(lower, upper);
            if applied != value {
                clamped.push(Clamped {
                    joint: joint.name.clone(),
                    requested: value,
                    applied,
                    lower,
                    upper,
                });
                out[i] = applied;
            }
        }
    }
    Ok((out, clamped))
}

/// A gripper command that cannot be applied.
#[derive(Debug, Clone, PartialEq)]
pub enum GripperCommandError {
    /// Width or effort is NaN or infinite.
    NotFinite {
        /// Which field.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// Negative effort.
    NegativeEffort(f64),
}

impl fmt::Display for GripperCommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GripperCommandError::NotFinite { field, value } => {
                write!(
                    f,
                    "gripper command {field} is {value}; it must be a finite number"
                )
            }
            GripperCommandError::NegativeEffort(v) => {
                write!(
                    f,
                    "gripper max_effort is {v} N; it must be >= 0 (0 means the default, 20 N)"
                )
            }
        }
    }
}

impl std::error::Error for GripperCommandError {}

/// Check a gripper opening command (pad gap in m, effort in N). Widths outside the reachable
/// range are clamped and reported.
pub fn validate_gripper_width(
    model: &RobotModel,
    width: f64,
    max_effort: f64,
) -> Result<(f64, Option<Clamped>), GripperCommandError> {
    if !width.is_finite() {
        return Err(GripperCommandError::NotFinite {
            field: "position",
            value: width,
        });
    }
    if !max_effort.is_finite() {
        return Err(GripperCommandError::NotFinite {
            field: "max_effort",
            value: max_effort,
        });
    }
    if max_effort < 0.0 {
        return Err(GripperCommandError::NegativeEffort(max_effort));
    }
    let (lo, hi) = model.joints[ARM_DOF]
        .limits
        .expect("finger joints are limited");
    let (lower, upper) = (pad_gap(lo), pad_gap(hi));
    let applied = width.clamp(lower, upper);
    let clamped = (applied != width).then(|| Clamped {
        joint: "gripper opening".into(),
        requested: width,
        applied,
        lower,
        upper,
    });
    Ok((applied, clamped))
}
