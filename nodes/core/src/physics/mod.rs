//! Physics: the arms and gripper in rapier3d, joint servos, contacts.
//!
//! Settings that keep grasps firm at 2 ms steps (see `PhysicsParams`): multibody (reduced
//! coordinate) arms, force-based joint motors, stiff contacts, one solver iteration with eight
//! inner PGS iterations, coupled fingers.

mod arm_dynamics;
mod params;
mod robot_model;
mod tags;
mod torsion;
mod urdf;
mod world;

pub use arm_dynamics::{ArmDynamics, ArmState, arm_dynamics};
pub use params::{ArmGains, GripperParams, PhysicsParams};
pub use robot_model::{
    ARM_DOF, BodyModel, CollisionShape, FINGER_JOINTS, GRIP_SITE_LINK, HAND_LINK, JointKind,
    JointModel, LinkJoint, RobotModel, Shape, build_model, robot_description, robot_model,
};
pub use tags::{ColliderTag, Side};
pub use torsion::TorsionalFriction;
pub use urdf::ModelError;
pub(crate) use urdf::urdf_pose;
pub(crate) use world::REFERENCE_KP;
pub use world::{
    ArmHandles, FINGER_OPEN, FingerContacts, GripperCommand, ServoMode, SimWorld, finger_for_gap,
    from_pose, pad_gap, reference_command_for_gap, to_pose,
};
