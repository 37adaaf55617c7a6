//! Stepping the world: the arm's joint servos (stiff position servos or the reference's torque
//! controller), their targets, the arm's dynamics and gravity torques, and the physics steps.

use nalgebra::{Isometry3, Vector3};
use rapier3d::prelude::*;

use super::SimWorld;
use super::convert::from_pose;
use crate::physics::arm_dynamics::{ArmDynamics, ArmState, arm_dynamics};
use crate::physics::robot_model::{ARM_DOF, MAX_BODIES};

/// How the arm's joint servos behave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ServoMode {
    /// Stiff position servos (the `ArmGains`), set points rate-limited by each joint's velocity
    /// limit: how a real arm's driver tracks absolute position commands.
    #[default]
    Stiff,
    /// The reference benchmark's joint controller (docs/src/reference-facts.md §4.2), every physics
    /// step: torques
    /// τ = M(q)·(kp·e − kd·q̇) + bias with kp 50, kd 2√50 (critical damping), the full joint-space
    /// mass matrix M (armature included) and the gravity, Coriolis and centrifugal torques
    /// (rapier's `ComputedTorquePd`, from the step's own CRBA mass matrix and Newton–Euler
    /// bias), clipped to the effort limits — so each joint settles like an ideal
    /// critically damped spring, and agents trained on the reference see the same soft,
    /// slow-settling response. No set-point rate limit (the reference has none).
    Reference,
}

/// The reference's joint-controller stiffness (1/s²); its damping is 2√kp (ζ = 1).
pub(crate) const REFERENCE_KP: f64 = 50.0;

impl SimWorld {
    /// Set arm joint targets (rad), used from the next physics step on, as given: absolute
    /// commands are validated and clamped by the caller (`control::limits`), while the
    /// reference's goals (q + 0.05·a) may lie past a limit, as in the reference, where the
    /// joint's limit constraint (here rapier's) stops the joint and the servo pushes into it.
    pub fn set_arm_targets(&mut self, targets: &[f64; ARM_DOF]) {
        self.arm_targets = *targets;
    }

    /// Current arm targets (rad).
    pub fn arm_targets(&self) -> [f64; ARM_DOF] {
        self.arm_targets
    }

    /// Switch the arm servos' behaviour.
    pub fn set_servo_mode(&mut self, mode: ServoMode) {
        self.servo_mode = mode;
    }

    /// The current servo behaviour.
    pub fn servo_mode(&self) -> ServoMode {
        self.servo_mode
    }

    /// Gravity torque on each arm joint at the current configuration (N·m): what the servos
    /// must add to hold still.
    pub fn gravity_torques(&self) -> [f64; ARM_DOF] {
        let g = Vector3::new(0.0, 0.0, -self.params.gravity);
        let bodies = &self.physics.bodies;
        let mut tau = [0.0; ARM_DOF];
        for (j, joint) in self.model.joints.iter().enumerate().take(ARM_DOF) {
            let child = &bodies[self.arm.bodies[joint.child]];
            let frame = from_pose(child.position());
            let anchor = frame.translation.vector;
            let axis = frame.rotation * joint.axis;
            for &b in &self.arm.downstream[j] {
                let body = &bodies[self.arm.bodies[b]];
                let com = body.center_of_mass();
                let r = Vector3::new(com.x as f64, com.y as f64, com.z as f64) - anchor;
                tau[j] += r.cross(&(g * body.mass() as f64)).dot(&axis);
            }
        }
        tau
    }

    fn update_servos(&mut self) {
        let gripper_targets = self.finger_targets();
        // The reference controller drives the joints with torques, computed inside the physics
        // step from the step's own mass matrix and bias forces (`ComputedTorquePd`); the stiff
        // servos with rapier's joint motors (implicit springs), gravity fed forward through
        // their set points.
        let reference = self.servo_mode == ServoMode::Reference;
        let tau_g = if reference {
            [0.0; ARM_DOF]
        } else {
            self.gravity_torques()
        };
        let (kp, kd) = (self.gains.kp, self.gains.kd);
        let gripper = &self.gripper;
        let link_ids = &self.arm.link_ids;
        let (mb, _) = self
            .physics
            .multibody_joints
            .get_mut(self.arm.joints[0])
            .expect("arm multibody");
        let dt = self.params.dt;
        for j in 0..ARM_DOF {
            let joint = &self.model.joints[j];
            let data = &mut mb.link_mut(link_ids[j]).expect("link").joint.data;
            if reference {
                self.setpoints[j] = self.arm_targets[j];
                data.set_motor_position(JointAxis::AngX, 0.0, 0.0, 0.0);
                data.set_motor_max_force(JointAxis::AngX, 0.0);
                continue;
            }
            let max_step = joint.velocity * dt;
            let step = (self.arm_targets[j] - self.setpoints[j]).clamp(-max_step, max_step);
            self.setpoints[j] += step;
            // Feed-forward gravity compensation through the servo's set point: at q = set point
            // the spring pushes exactly −τ_g.
            let target = self.setpoints[j] - tau_g[j] / kp[j];
            data.set_motor_position(
                JointAxis::AngX,
                target as Real,
                kp[j] as Real,
                kd[j] as Real,
            );
            data.set_motor_max_force(JointAxis::AngX, joint.effort as Real);
        }
        let (targets, max_force) = gripper_targets;
        for (i, target) in targets.iter().enumerate() {
            let data = &mut mb.link_mut(link_ids[ARM_DOF + i]).expect("link").joint.data;
            data.set_motor_position(
                JointAxis::LinX,
                *target as Real,
                gripper.kp as Real,
                gripper.kd as Real,
            );
            data.set_motor_max_force(JointAxis::LinX, max_force as Real);
        }
        if !reference {
            mb.set_computed_torque_pd(None);
            return;
        }
        // The arm's DoFs come first in the multibody, one per joint, in joint order.
        let first_dof = mb.link(link_ids[0]).expect("link").assembly_id();
        debug_assert!(
            (0..ARM_DOF)
                .all(|j| mb.link(link_ids[j]).expect("link").assembly_id() == first_dof + j)
        );
        if mb.computed_torque_pd().is_none() {
            let kd = 2.0 * REFERENCE_KP.sqrt();
            mb.set_computed_torque_pd(Some(ComputedTorquePd {
                first_dof,
                kp: REFERENCE_KP as Real,
                kd: kd as Real,
                targets: vec![0.0; ARM_DOF],
                effort_limits: self.model.joints[..ARM_DOF]
                    .iter()
                    .map(|joint| joint.effort as Real)
                    .collect(),
                torques: vec![0.0; ARM_DOF],
            }));
        }
        let pd = mb.computed_torque_pd_mut().expect("set above");
        for (target, goal) in pd.targets.iter_mut().zip(&self.arm_targets) {
            *target = *goal as Real;
        }
    }

    /// The arm's mass matrix and bias torques now.
    pub fn dynamics(&self) -> ArmDynamics {
        let mut body_poses = [Isometry3::identity(); MAX_BODIES];
        for (pose, &h) in body_poses.iter_mut().zip(&self.arm.bodies) {
            *pose = from_pose(self.physics.bodies[h].position());
        }
        arm_dynamics(&ArmState {
            model: self.model,
            body_poses: &body_poses[..self.arm.bodies.len()],
            downstream: &self.arm.downstream,
            armature: &self.gains.armature,
            velocities: &self.arm_velocities(),
            gravity: self.params.gravity,
        })
    }

    /// The torques the reference controller exerted in the last physics step (N·m; zeros with
    /// the stiff servos).
    pub fn reference_torques(&self) -> [f64; ARM_DOF] {
        let pd = self.multibody().computed_torque_pd();
        std::array::from_fn(|j| {
            pd.map_or(0.0, |pd| pd.torques.get(j).copied().unwrap_or(0.0) as f64)
        })
    }

    /// One physics step. Never inlined: `scripts/profile-physics` counts the instructions
    /// inside this function, and whole-program optimisation would otherwise fold it into its
    /// callers (one call per 2 ms step costs nothing measurable).
    #[inline(never)]
    pub fn step(&mut self) {
        self.update_servos();
        if let Some(object) = self.object {
            self.torsion.update(&mut self.physics, object);
        }
        self.physics.step();
        self.steps += 1;
    }

    /// One control period (`substeps` physics steps).
    pub fn step_control(&mut self) {
        for _ in 0..self.params.substeps {
            self.step();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axes::{AxisElement, Robot};
    use crate::physics::params::PhysicsParams;
    use crate::physics::world::FINGER_OPEN;
    use rand::{Rng, SeedableRng};

    /// The reference controller runs inside rapier's step on the multibody's own CRBA mass
    /// matrix and Newton–Euler bias (f32); `arm_dynamics` computes both independently in f64
    /// from the body poses. Mid-motion (joints driven towards far targets, so the Coriolis
    /// terms are not zero) on every arm, the multibody's arm block of M and the torques it
    /// exerted agree with `arm_dynamics` and the law τ = M·(kp·e − kd·q̇) + bias. Measured: M
    /// to ~1e-6 of its largest entry, the torques to ~1e-4 N·m.
    #[test]
    fn the_reference_law_in_the_step_equals_the_f64_dynamics() {
        for robot in Robot::all() {
            let mut world = SimWorld::new(robot, PhysicsParams::default());
            world.set_servo_mode(ServoMode::Reference);
            let home = world.arm_positions();
            let targets: [f64; ARM_DOF] = std::array::from_fn(|j| home[j] + 0.4 - 0.1 * j as f64);
            world.set_arm_targets(&targets);
            let mut checked = 0;
            for step in 0..60 {
                let before = world.dynamics();
                let (q, qd) = (world.arm_positions(), world.arm_velocities());
                world.step();
                if step % 10 != 9 {
                    continue;
                }
                assert!(
                    qd.iter().any(|v| v.abs() > 0.05),
                    "{robot:?}: the arm moves"
                );
                let ours = world.multibody().mass_matrix();
                let scale = before.mass_matrix.amax();
                for i in 0..ARM_DOF {
                    for k in 0..ARM_DOF {
                        let error = (ours[(i, k)] as f64 - before.mass_matrix[(i, k)]).abs();
                        assert!(
                            error <= 2e-5 * scale,
                            "{robot:?} step {step}: M[{i},{k}] = {} here, {} in f64",
                            ours[(i, k)],
                            before.mass_matrix[(i, k)]
                        );
                    }
                }
                let kd = 2.0 * REFERENCE_KP.sqrt();
                let acceleration = nalgebra::SVector::<f64, ARM_DOF>::from_fn(|j, _| {
                    REFERENCE_KP * (targets[j] - q[j]) - kd * qd[j]
                });
                let tau = before.mass_matrix * acceleration;
                let exerted = world.reference_torques();
                for j in 0..ARM_DOF {
                    let effort = world.model.joints[j].effort;
                    let expected = (tau[j] + before.bias[j]).clamp(-effort, effort);
                    assert!(
                        (exerted[j] - expected).abs() <= 2e-3 + 1e-4 * expected.abs(),
                        "{robot:?} step {step}: joint {j} exerted {} N·m, the f64 law gives {expected}",
                        exerted[j]
                    );
                }
                checked += 1;
            }
            assert_eq!(checked, 6);
        }
    }

    /// `arm_dynamics` sums over composite bodies (a link and all beyond it); here M(q) and the
    /// bias torques are summed body by body from their definitions — each joint's velocity
    /// Jacobian column at each body, each body's wrench about each joint's axis — in random
    /// configurations and joint velocities of every arm. Measured: they agree to ~1e-15 of
    /// the largest entry.
    #[test]
    fn composite_body_dynamics_equal_the_body_by_body_sums() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for robot in Robot::all() {
            let mut world = SimWorld::new(robot, PhysicsParams::default());
            let model = world.model;
            for _ in 0..50 {
                let q: [f64; ARM_DOF] = std::array::from_fn(|j| {
                    let (lo, hi) = model.joints[j]
                        .limits
                        .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI));
                    rng.random_range(lo..=hi)
                });
                let qd: [f64; ARM_DOF] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
                world.reset_arm(&q, FINGER_OPEN);
                let poses: Vec<Isometry3<f64>> = world
                    .arm
                    .bodies
                    .iter()
                    .map(|&h| from_pose(world.physics.bodies[h].position()))
                    .collect();
                let fast = arm_dynamics(&ArmState {
                    model,
                    body_poses: &poses,
                    downstream: &world.arm.downstream,
                    armature: &world.gains.armature,
                    velocities: &qd,
                    gravity: world.params.gravity,
                });

                // Each joint's axis and anchor; each moving body's link, mass, com, inertia.
                let axis: Vec<Vector3<f64>> = (0..ARM_DOF)
                    .map(|j| poses[model.joints[j].child].rotation * model.joints[j].axis)
                    .collect();
                let anchor: Vec<Vector3<f64>> = (0..ARM_DOF)
                    .map(|j| poses[model.joints[j].child].translation.vector)
                    .collect();
                let link_of = |b: usize| {
                    (0..ARM_DOF)
                        .rev()
                        .find(|&j| world.arm.downstream[j].contains(&b))
                };
                let mut mass_matrix = nalgebra::SMatrix::<f64, ARM_DOF, ARM_DOF>::zeros();
                let mut bias = [0.0; ARM_DOF];
                // Link motion with zero joint accelerations, outward.
                let mut omega = [Vector3::zeros(); ARM_DOF];
                let mut alpha = [Vector3::zeros(); ARM_DOF];
                let mut anchor_acc = [Vector3::zeros(); ARM_DOF];
                for j in 0..ARM_DOF {
                    let spin = axis[j] * qd[j];
                    if j > 0 {
                        let d = anchor[j] - anchor[j - 1];
                        let (w, a) = (omega[j - 1], alpha[j - 1]);
                        omega[j] = w + spin;
                        alpha[j] = a + w.cross(&spin);
                        anchor_acc[j] = anchor_acc[j - 1] + a.cross(&d) + w.cross(&w.cross(&d));
                    } else {
                        omega[0] = spin;
                    }
                }
                let g = Vector3::new(0.0, 0.0, -world.params.gravity);
                for (b, pose) in poses.iter().enumerate() {
                    let Some(link) = link_of(b) else { continue };
                    let body = &model.bodies[b];
                    let r = pose.rotation.to_rotation_matrix();
                    let inertia = r.matrix() * body.inertia * r.matrix().transpose();
                    let com = (pose * nalgebra::Point3::from(body.com)).coords;
                    for j in 0..=link {
                        for i in 0..=link {
                            let v_i = axis[i].cross(&(com - anchor[i]));
                            let v_j = axis[j].cross(&(com - anchor[j]));
                            mass_matrix[(i, j)] +=
                                body.mass * v_i.dot(&v_j) + axis[i].dot(&(inertia * axis[j]));
                        }
                    }
                    let (w, a) = (omega[link], alpha[link]);
                    let rc = com - anchor[link];
                    let com_acc = anchor_acc[link] + a.cross(&rc) + w.cross(&w.cross(&rc));
                    let force = body.mass * (com_acc - g);
                    let moment = inertia * a + w.cross(&(inertia * w));
                    for j in 0..=link {
                        bias[j] += axis[j].dot(&(moment + (com - anchor[j]).cross(&force)));
                    }
                }
                for j in 0..ARM_DOF {
                    mass_matrix[(j, j)] += world.gains.armature[j];
                }
                let m_scale = mass_matrix.amax();
                let m_error = (fast.mass_matrix - mass_matrix).amax();
                assert!(
                    m_error <= 1e-12 * m_scale,
                    "{robot:?} q = {q:?}: M differs by {m_error:e} (largest entry {m_scale})"
                );
                let b_scale = bias.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                for (j, (ours, summed)) in fast.bias.iter().zip(&bias).enumerate() {
                    assert!(
                        (ours - summed).abs() <= 1e-12 * b_scale,
                        "{robot:?} q = {q:?}, q̇ = {qd:?}: bias {j} is {ours} here, {summed} summed body by body"
                    );
                }
            }
        }
    }
}
