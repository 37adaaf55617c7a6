//! Privileged ground truth after a step.

use nalgebra::{Isometry3, Vector3};

use crate::axes::Object;
use crate::physics::{ARM_DOF, FingerContacts, SimWorld};

/// What the reward needs and an agent does not observe directly.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldState {
    /// Object body pose (world).
    pub object_pose: Isometry3<f64>,
    /// Object linear velocity (m/s, world).
    pub object_linear_velocity: Vector3<f64>,
    /// Object angular velocity (rad/s, world).
    pub object_angular_velocity: Vector3<f64>,
    /// Grip-site position with the hand's orientation.
    pub eef_pose: Isometry3<f64>,
    /// Finger/object contacts.
    pub contacts: FingerContacts,
    /// The benchmark's grasp test.
    pub grasping: bool,
    /// Last gripper action in the reference convention (+ close, − open).
    pub last_gripper_action: f64,
    /// The reference's internal finger command c in [−1, 1].
    pub gripper_target: f64,
    /// Arm joint positions (rad).
    pub arm_joint_positions: [f64; ARM_DOF],
    /// Arm joint velocities (rad/s).
    pub arm_joint_velocities: [f64; ARM_DOF],
    /// Finger positions (m), left then right.
    pub finger_joint_positions: [f64; 2],
}

impl WorldState {
    pub(super) fn read(
        world: &SimWorld,
        object: Object,
        eef: &Isometry3<f64>,
        last_gripper_action: f64,
    ) -> WorldState {
        let body = &world.physics.bodies[world.object.expect("object")];
        let lin = body.linvel();
        let ang = body.angvel();
        let contacts = world.finger_contacts();
        WorldState {
            object_pose: world.object_pose().expect("object"),
            object_linear_velocity: Vector3::new(lin.x as f64, lin.y as f64, lin.z as f64),
            object_angular_velocity: Vector3::new(ang.x as f64, ang.y as f64, ang.z as f64),
            eef_pose: *eef,
            contacts,
            grasping: contacts.grasping(object),
            last_gripper_action,
            gripper_target: world.gripper_c(),
            arm_joint_positions: world.arm_positions(),
            arm_joint_velocities: world.arm_velocities(),
            finger_joint_positions: world.finger_positions(),
        }
    }
}
