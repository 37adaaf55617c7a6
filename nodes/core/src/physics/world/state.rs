//! The arm's state: its joints' positions and velocities, the world poses of its frames, and
//! putting it at rest in a given configuration.

use nalgebra::Isometry3;
use rapier3d::prelude::*;

use super::SimWorld;
use super::convert::from_pose;
use super::gripper::{GripperCommand, pad_gap};
use crate::physics::robot_model::{ARM_DOF, JointKind};

impl SimWorld {
    /// The multibody link id of model joint `j`.
    pub(super) fn link_id(&self, j: usize) -> usize {
        self.arm.link_ids[j]
    }

    pub(super) fn multibody(&self) -> &Multibody {
        self.physics
            .multibody_joints
            .get(self.arm.joints[0])
            .expect("arm multibody")
            .0
    }

    /// Position of model joint `j` (rad or m).
    pub fn joint_position(&self, j: usize) -> f64 {
        let link = self.multibody().link(self.link_id(j)).expect("link");
        let axis = coordinate_axis(self.model.joints[j].kind);
        link.joint.coords()[axis] as f64
    }

    /// Velocity of model joint `j` (rad/s or m/s).
    pub fn joint_velocity(&self, j: usize) -> f64 {
        let mb = self.multibody();
        let link = mb.link(self.link_id(j)).expect("link");
        mb.joint_velocity(link)[0] as f64
    }

    /// The seven arm joint positions (rad).
    pub fn arm_positions(&self) -> [f64; ARM_DOF] {
        std::array::from_fn(|j| self.joint_position(j))
    }

    /// The seven arm joint velocities (rad/s).
    pub fn arm_velocities(&self) -> [f64; ARM_DOF] {
        std::array::from_fn(|j| self.joint_velocity(j))
    }

    /// Finger joint positions (left, right) in m.
    pub fn finger_positions(&self) -> [f64; 2] {
        [
            self.joint_position(ARM_DOF),
            self.joint_position(ARM_DOF + 1),
        ]
    }

    /// Put the arm at `q` (rad) and the fingers at `q_left` (m), at rest, with matching targets.
    pub fn reset_arm(&mut self, q: &[f64; ARM_DOF], q_left: f64) {
        let mut wanted: Vec<f64> = q.to_vec();
        wanted.push(q_left);
        wanted.push(-q_left);
        let current: Vec<f64> = (0..wanted.len()).map(|j| self.joint_position(j)).collect();
        let link_ids = &self.arm.link_ids;
        let physics = &mut self.physics;
        let (mb, _) = physics
            .multibody_joints
            .get_mut(self.arm.joints[0])
            .expect("arm multibody");
        // Displacements are indexed by generalized coordinate (the root may own some).
        let mut disp: Vec<Real> = vec![0.0; mb.ndofs()];
        for (j, link) in link_ids.iter().enumerate() {
            disp[mb.link(*link).expect("link").assembly_id()] = (wanted[j] - current[j]) as Real;
        }
        mb.apply_displacements(&disp);
        mb.generalized_velocity_mut().fill(0.0);
        mb.forward_kinematics(&physics.bodies, true);
        mb.update_rigid_bodies(&mut physics.bodies, false);
        for &handle in &self.arm.bodies {
            if let Some(body) = physics.bodies.get_mut(handle) {
                body.set_linvel(Vector::ZERO, true);
                body.set_angvel(Vector::ZERO, true);
            }
        }
        self.arm_targets = *q;
        self.setpoints = *q;
        self.gripper_c = 0.0;
        self.gripper_command = GripperCommand::Width {
            width: pad_gap(q_left),
            max_effort: self.gripper.max_force,
        };
    }

    fn link_pose(&self, (body, in_body): (usize, Isometry3<f64>)) -> Isometry3<f64> {
        from_pose(self.physics.bodies[self.arm.bodies[body]].position()) * in_body
    }

    /// World pose of the grip site (the reference's end-effector point).
    pub fn grip_site_pose(&self) -> Isometry3<f64> {
        self.link_pose(self.arm.grip_site)
    }

    /// World pose of the hand frame (its orientation is the reference's `eef_quat`).
    pub fn hand_pose(&self) -> Isometry3<f64> {
        self.link_pose(self.arm.hand)
    }

    /// World pose of a URDF link by name.
    pub fn link_world_pose(&self, name: &str) -> Option<Isometry3<f64>> {
        self.model.links.get(name).map(|l| self.link_pose(*l))
    }
}

fn coordinate_axis(kind: JointKind) -> usize {
    match kind {
        JointKind::Prismatic => 0, // LinX
        JointKind::Revolute => 3,  // AngX
    }
}
