//! A rapier world holding one arm with its gripper, static scene parts and (optionally) one
//! object, stepped at the physics period with joint position servos.

mod build;
mod contacts;
mod convert;
mod gripper;
mod object;
mod servos;
mod state;

use nalgebra::Isometry3;
use rapier3d::prelude::*;

use super::params::{ArmGains, GripperParams, PhysicsParams};
use super::robot_model::{ARM_DOF, RobotModel};
use super::tags::ColliderTag;
use super::torsion::TorsionalFriction;
use crate::axes::Robot;

pub use contacts::FingerContacts;
pub use convert::{from_pose, to_pose};
pub use gripper::{
    FINGER_OPEN, GripperCommand, finger_for_gap, pad_gap, reference_command_for_gap,
};
pub(crate) use servos::REFERENCE_KP;
pub use servos::ServoMode;

/// Handles of one arm in the world.
#[derive(Debug, Clone)]
pub struct ArmHandles {
    /// Rigid body of each model body (index 0: the fixed base).
    pub bodies: Vec<RigidBodyHandle>,
    /// The multibody joint of each model joint (7 arm joints, then left and right finger).
    pub joints: Vec<MultibodyJointHandle>,
    /// Finger colliders: (collider, tag).
    pub finger_colliders: Vec<(ColliderHandle, ColliderTag)>,
    /// Body and in-body pose of the grip site.
    pub grip_site: (usize, Isometry3<f64>),
    /// Body and in-body pose of the hand frame.
    pub hand: (usize, Isometry3<f64>),
    /// For each arm joint, which bodies move with it (for gravity compensation).
    pub downstream: Vec<Vec<usize>>,
    /// The multibody link id of each model joint (stable: links are never removed).
    pub link_ids: Vec<usize>,
}

/// The simulated world: rapier sets plus the arm's handles and command state.
pub struct SimWorld {
    /// Rapier's world (bodies, colliders, joints, pipeline).
    pub physics: PhysicsWorld,
    /// Which arm.
    pub robot: Robot,
    /// The arm's model.
    pub model: &'static RobotModel,
    /// The arm's handles.
    pub arm: ArmHandles,
    /// Servo gains.
    pub gains: ArmGains,
    /// Finger servo settings.
    pub gripper: GripperParams,
    /// Settings the world was built with.
    pub params: PhysicsParams,
    /// Current joint position targets (rad), as commanded.
    arm_targets: [f64; ARM_DOF],
    /// The servos' set points (rad): they move toward the targets no faster than each joint's
    /// velocity limit, as a real arm's joint-limit layer does with position commands.
    setpoints: [f64; ARM_DOF],
    gripper_command: GripperCommand,
    /// The reference's internal gripper command c in [−1, 1].
    gripper_c: f64,
    /// How the arm servos behave.
    servo_mode: ServoMode,
    /// The object body, if one was added.
    pub object: Option<RigidBodyHandle>,
    /// The object's torsional friction (none until an object with it is added).
    torsion: TorsionalFriction,
    /// Physics steps taken.
    pub steps: u64,
}
