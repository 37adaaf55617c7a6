//! The arm's joint-space dynamics at one instant: the mass matrix M(q) (armature included) and
//! the bias torques (gravity, Coriolis and centrifugal: what the joints must exert for zero
//! joint acceleration). The reference's joint controller needs both, every physics step:
//! τ = M(q)·(kp·e − kd·q̇) + bias (MuJoCo's `qfrc_bias`).
//!
//! Computed from the model's bodies at their current world poses, by composite bodies: each arm
//! joint moves the bodies downstream of it. The fingers count as rigid parts of the hand (their
//! own slide velocities are left out of the bias: grams moving millimetres).

use nalgebra::{Isometry3, Matrix3, SMatrix, Vector3};

use super::robot_model::{MAX_BODIES, RobotModel};
use super::world::ARM_DOF;

/// M(q) and the bias torques of the 7 arm joints.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmDynamics {
    /// Joint-space inertia (kg·m²), symmetric, armature on the diagonal.
    pub mass_matrix: SMatrix<f64, ARM_DOF, ARM_DOF>,
    /// Torques (N·m) that hold every joint at zero acceleration against gravity and the
    /// velocity-product forces.
    pub bias: [f64; ARM_DOF],
}

/// What [`arm_dynamics`] reads of the arm.
pub struct ArmState<'a> {
    /// The arm's bodies and joints.
    pub model: &'a RobotModel,
    /// Each model body's world pose (body frame; the joint frames are the child bodies').
    pub body_poses: &'a [Isometry3<f64>],
    /// For each arm joint, the bodies it moves.
    pub downstream: &'a [Vec<usize>],
    /// Rotor inertia per joint (kg·m²).
    pub armature: &'a [f64; ARM_DOF],
    /// Joint velocities (rad/s).
    pub velocities: &'a [f64; ARM_DOF],
    /// Gravitational acceleration (m/s², along −z).
    pub gravity: f64,
}

/// A joint's frame in the world: where its axis passes and which way it points.
struct JointFrame {
    anchor: Vector3<f64>,
    axis: Vector3<f64>,
}

/// A body's mass properties in the world frame.
#[derive(Clone, Copy)]
struct WorldBody {
    mass: f64,
    com: Vector3<f64>,
    inertia: Matrix3<f64>,
    /// The outermost arm joint that moves it (the link it rides on).
    link: usize,
}

/// M(q) and the bias torques of the arm in `arm`'s state. Runs every physics step, so it keeps
/// its per-joint and per-body values on the stack.
pub fn arm_dynamics(arm: &ArmState) -> ArmDynamics {
    let model = arm.model;
    debug_assert!(
        (1..ARM_DOF).all(|j| model.joints[j].parent == model.joints[j - 1].child),
        "the arm joints form a chain"
    );
    let joints: [JointFrame; ARM_DOF] = std::array::from_fn(|j| {
        let frame = arm.body_poses[model.joints[j].child];
        JointFrame {
            anchor: frame.translation.vector,
            axis: frame.rotation * model.joints[j].axis,
        }
    });
    // The outermost arm joint that moves each body (the link it rides on); none for the base.
    // (`robot_model` refuses models with more bodies than MAX_BODIES.)
    let mut link_of = [None; MAX_BODIES];
    for (j, moved) in arm.downstream.iter().enumerate().take(ARM_DOF) {
        for &b in moved {
            link_of[b] = Some(j);
        }
    }
    let bodies: [Option<WorldBody>; MAX_BODIES] = std::array::from_fn(|b| {
        let link = link_of[b]?;
        let body = &model.bodies[b];
        let pose = arm.body_poses[b];
        let r = pose.rotation.to_rotation_matrix();
        Some(WorldBody {
            mass: body.mass,
            com: (pose * nalgebra::Point3::from(body.com)).coords,
            inertia: r.matrix() * body.inertia * r.matrix().transpose(),
            link,
        })
    });

    // M by momenta: a unit rate of joint j gives the bodies downstream of it a linear momentum
    // `momentum[j]` and an angular momentum about the world origin `spin[j]`. For i ≤ j the
    // bodies both joints move are those downstream of j, and the work term of M is
    // Σ_b m_b·v_i(b)·v_j(b) + a_i·I_b·a_j with v_i(b) = a_i × (c_b − p_i), which is
    // a_i · (spin[j] − p_i × momentum[j]): one pass over the bodies per joint, not per pair.
    let mut momentum = [Vector3::<f64>::zeros(); ARM_DOF];
    let mut spin = [Vector3::<f64>::zeros(); ARM_DOF];
    for (j, joint) in joints.iter().enumerate() {
        for &b in &arm.downstream[j] {
            if let Some(body) = &bodies[b] {
                let p = body.mass * joint.axis.cross(&(body.com - joint.anchor));
                momentum[j] += p;
                spin[j] += body.com.cross(&p) + body.inertia * joint.axis;
            }
        }
    }
    let mut mass_matrix = SMatrix::<f64, ARM_DOF, ARM_DOF>::zeros();
    for j in 0..ARM_DOF {
        for i in 0..=j {
            let a_i = &joints[i];
            let m = a_i.axis.dot(&(spin[j] - a_i.anchor.cross(&momentum[j])));
            mass_matrix[(i, j)] = m;
            mass_matrix[(j, i)] = m;
        }
        mass_matrix[(j, j)] += arm.armature[j];
    }

    // Bias: each link's motion with every joint acceleration zero (outward), then the wrench
    // each body needs for it (and against gravity), summed about each joint (inward).
    let mut omega = [Vector3::<f64>::zeros(); ARM_DOF];
    let mut alpha = [Vector3::<f64>::zeros(); ARM_DOF];
    let mut anchor_acc = [Vector3::<f64>::zeros(); ARM_DOF];
    for j in 0..ARM_DOF {
        let spin = joints[j].axis * arm.velocities[j];
        if j == 0 {
            omega[0] = spin;
            continue;
        }
        let (w, a, acc) = (omega[j - 1], alpha[j - 1], anchor_acc[j - 1]);
        let d = joints[j].anchor - joints[j - 1].anchor;
        omega[j] = w + spin;
        alpha[j] = a + w.cross(&spin);
        anchor_acc[j] = acc + a.cross(&d) + w.cross(&w.cross(&d));
    }
    let g = Vector3::new(0.0, 0.0, -arm.gravity);
    let wrenches: [Option<(Vector3<f64>, Vector3<f64>)>; MAX_BODIES] = std::array::from_fn(|b| {
        let body = bodies[b].as_ref()?;
        let (w, a) = (omega[body.link], alpha[body.link]);
        let r = body.com - joints[body.link].anchor;
        let com_acc = anchor_acc[body.link] + a.cross(&r) + w.cross(&w.cross(&r));
        let force = body.mass * (com_acc - g);
        let moment = body.inertia * a + w.cross(&(body.inertia * w));
        Some((force, moment))
    });
    let bias = std::array::from_fn(|j| {
        let joint = &joints[j];
        let mut torque = Vector3::zeros();
        for &b in &arm.downstream[j] {
            if let (Some(body), Some((force, moment))) = (&bodies[b], &wrenches[b]) {
                torque += moment + (body.com - joint.anchor).cross(force);
            }
        }
        joint.axis.dot(&torque)
    });
    ArmDynamics { mass_matrix, bias }
}
