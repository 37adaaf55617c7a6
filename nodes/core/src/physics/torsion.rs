//! Torsional friction: the resistance of a contact to spinning about its own normal, which the
//! reference gives the dumbbell and the plate (MuJoCo `condim="4"`, torsional coefficient 1 m on
//! their geoms, docs/src/reference-facts.md §3) and rapier's contacts do not have.
//!
//! Each object contact (one manifold: one object primitive against one primitive of another
//! collider) gets an impulse joint between the two bodies whose only effect is a velocity motor
//! about the contact normal: target spin 0, as stiff as the solver allows, its torque capped at
//! `torsion · normal force` of that contact in the previous step. Solved with every other
//! constraint, it holds the relative spin at 0 below the cap and lets it slip above, as dry
//! friction does — MuJoCo's torsional friction, except that the cap is taken on its own rather
//! than inside one elliptic cone with the sliding friction.

use std::collections::BTreeMap;

use rapier3d::dynamics::{
    GenericJoint, GenericJointBuilder, ImpulseJointHandle, JointAxesMask, JointAxis, MotorModel,
    RigidBodyHandle,
};
use rapier3d::geometry::{ColliderHandle, PairContacts};
use rapier3d::math::{Pose, Real, Rotation, Vector};
use rapier3d::pipeline::PhysicsWorld;

/// Damping of the spin motor (N·m·s/rad): large enough that the motor is a hard velocity
/// constraint (its compliance, 1/(dt·D), is ~1e-6 of an object's inverse spin inertia).
const SPIN_MOTOR_DAMPING: Real = 1.0e9;

/// One object contact: the other collider, the object's primitive, the other's primitive.
type ContactKey = ((u32, u32), u32, u32);

/// The torsional-friction joints of one object.
#[derive(Debug, Clone, Default)]
pub struct TorsionalFriction {
    /// Torsional coefficient (m) of each of the object's collision primitives, in the order of
    /// its compound collider; 0 for a primitive without torsional friction.
    coefficients: Vec<f64>,
    /// The joint of each contact seen so far (disabled by a zero cap while out of contact).
    joints: BTreeMap<ContactKey, ImpulseJointHandle>,
    /// This step's touching contacts (key, other body, normal, torque cap); kept between steps
    /// so a step allocates nothing.
    touching: Vec<(ContactKey, RigidBodyHandle, Vector, Real)>,
}

impl TorsionalFriction {
    /// Torsional friction for an object whose primitives have these coefficients (m).
    pub fn new(coefficients: Vec<f64>) -> Self {
        TorsionalFriction {
            coefficients,
            joints: BTreeMap::new(),
            touching: Vec::new(),
        }
    }

    /// Whether any primitive has torsional friction.
    pub fn is_active(&self) -> bool {
        self.coefficients.iter().any(|&c| c > 0.0)
    }

    /// Set every joint from the object's current contacts, before a physics step: the spin axis
    /// from the contact normal, the torque cap from the normal impulse the last step applied.
    pub fn update(&mut self, physics: &mut PhysicsWorld, object: RigidBodyHandle) {
        if !self.is_active() {
            return;
        }
        let Some(&collider) = physics.bodies[object].colliders().first() else {
            return;
        };
        let dt = physics.integration_parameters.dt;
        let centre = physics.bodies[object].center_of_mass();
        // (key, other body, spin axis, torque cap) of every touching contact.
        let mut touching = std::mem::take(&mut self.touching);
        touching.clear();
        for pair in physics.narrow_phase.contact_pairs_with(collider) {
            let PairContacts::Rigid(rigid) = &pair.contacts else {
                continue;
            };
            let object_first = pair.collider1 == collider;
            let other: ColliderHandle = if object_first {
                pair.collider2
            } else {
                pair.collider1
            };
            let Some(other_body) = physics.colliders[other].parent() else {
                continue;
            };
            for manifold in &rigid.manifolds {
                let (own, theirs) = if object_first {
                    (manifold.subshape1, manifold.subshape2)
                } else {
                    (manifold.subshape2, manifold.subshape1)
                };
                let coefficient = self.coefficients.get(own as usize).copied().unwrap_or(0.0);
                let normal_impulse: Real = manifold.points.iter().map(|p| p.data.impulse).sum();
                if coefficient <= 0.0 || normal_impulse <= 0.0 {
                    continue;
                }
                let cap = coefficient as Real * normal_impulse / dt;
                let key = (other.into_raw_parts(), own, theirs);
                touching.push((key, other_body, manifold.data.normal, cap));
            }
        }
        // Out of contact: no cap. Only joints that still hold one are touched (each mutable
        // access queues the joint for rapier's bookkeeping, every 2 ms step).
        for (key, &handle) in &self.joints {
            let capped = physics
                .impulse_joints
                .get(handle)
                .and_then(|joint| joint.data.motor(JointAxis::AngZ))
                .is_some_and(|motor| motor.max_force != 0.0);
            if capped
                && !touching.iter().any(|t| t.0 == *key)
                && let Some(joint) = physics.impulse_joints.get_mut(handle, false)
            {
                joint.data.set_motor_max_force(JointAxis::AngZ, 0.0);
            }
        }
        for &(key, other_body, normal, cap) in &touching {
            // The joint frame's z is the normal (either sign: friction does not care), expressed
            // in each body; both frames sit at the object's centre of mass.
            let normal = if normal.z < 0.0 { -normal } else { normal };
            let axis = Rotation::from_rotation_arc(Vector::Z, normal.normalize());
            let world_frame = Pose::from_parts(centre, axis);
            let frame1 = physics.bodies[object].position().inverse() * world_frame;
            let frame2 = physics.bodies[other_body].position().inverse() * world_frame;
            match self.joints.get(&key) {
                Some(&handle) => {
                    let joint = &mut physics
                        .impulse_joints
                        .get_mut(handle, false)
                        .expect("torsion joints are never removed")
                        .data;
                    joint.set_local_frame1(frame1);
                    joint.set_local_frame2(frame2);
                    joint.set_motor_max_force(JointAxis::AngZ, cap);
                }
                None => {
                    let joint: GenericJoint = GenericJointBuilder::new(JointAxesMask::empty())
                        .local_frame1(frame1)
                        .local_frame2(frame2)
                        .motor_model(JointAxis::AngZ, MotorModel::ForceBased)
                        .motor_velocity(JointAxis::AngZ, 0.0, SPIN_MOTOR_DAMPING)
                        .motor_max_force(JointAxis::AngZ, cap)
                        .contacts_enabled(true)
                        .build();
                    let handle = physics
                        .impulse_joints
                        .insert(object, other_body, joint, false);
                    self.joints.insert(key, handle);
                }
            }
        }
        self.touching = touching;
    }
}
