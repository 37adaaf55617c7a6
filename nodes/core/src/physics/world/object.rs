//! The manipulated object: adding it (one compound collider with the reference's mass),
//! moving it, pushing it, and reading its pose.

use nalgebra::{Isometry3, Vector3};
use rapier3d::prelude::*;

use super::SimWorld;
use super::build::primitive_shape;
use super::convert::{from_pose, to_pose, to_vec};
use crate::arena::object_geometry;
use crate::axes::Object;
use crate::physics::tags::ColliderTag;
use crate::physics::torsion::TorsionalFriction;

impl SimWorld {
    /// Add the manipulated object at `pose`: one compound collider of its primitives, with the
    /// reference's mass (uniform density, so the primitives give its centre of mass and inertia).
    pub fn add_object(&mut self, object: Object, pose: &Isometry3<f64>) -> RigidBodyHandle {
        let geometry = object_geometry(object);
        let shapes: Vec<(Pose, SharedShape)> = crate::arena::object_parts(object)
            .iter()
            .filter(|p| p.collides)
            .map(|p| {
                let (shape, local) = primitive_shape(&p.shape, &p.pose);
                (local, shape)
            })
            .collect();
        let compound = SharedShape::compound(shapes);
        let unit = compound.mass_properties(1.0);
        let density = (geometry.mass() / unit.mass() as f64) as Real;
        let friction = geometry.parts.first().map_or(1.0, |p| p.friction.slide);
        let body = self.physics.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(to_pose(pose))
                .can_sleep(false),
        );
        self.physics.insert_collider(
            ColliderBuilder::new(compound)
                .density(density)
                .friction(friction as Real)
                .user_data(ColliderTag::Object.encode()),
            Some(body),
        );
        self.object = Some(body);
        self.torsion = TorsionalFriction::new(geometry.torsional_coefficients());
        body
    }

    /// Move the object to `pose`, at rest.
    pub fn place_object(&mut self, pose: &Isometry3<f64>) {
        if let Some(body) = self.object.and_then(|h| self.physics.bodies.get_mut(h)) {
            body.set_position(to_pose(pose), true);
            body.set_linvel(Vector::ZERO, true);
            body.set_angvel(Vector::ZERO, true);
        }
    }

    /// Move the object to `pose` with velocities `linear` (m/s) and `angular` (rad/s), world
    /// frame — a teleport, as a simulator's "set entity state" does.
    pub fn set_object_motion(
        &mut self,
        pose: &Isometry3<f64>,
        linear: &Vector3<f64>,
        angular: &Vector3<f64>,
    ) {
        if let Some(body) = self.object.and_then(|h| self.physics.bodies.get_mut(h)) {
            body.set_position(to_pose(pose), true);
            body.set_linvel(to_vec(linear), true);
            body.set_angvel(to_vec(angular), true);
        }
    }

    /// Hold a torque (N·m, world frame) on the object about its centre of mass until it is
    /// changed — MuJoCo's `xfrc_applied`, for test rigs and disturbance studies.
    pub fn set_object_torque(&mut self, torque: Vector3<f64>) {
        if let Some(body) = self.object.and_then(|h| self.physics.bodies.get_mut(h)) {
            body.reset_torques(false);
            body.add_torque(to_vec(&torque), true);
        }
    }

    /// Pose of the object body.
    pub fn object_pose(&self) -> Option<Isometry3<f64>> {
        self.object
            .map(|h| from_pose(self.physics.bodies[h].position()))
    }
}
