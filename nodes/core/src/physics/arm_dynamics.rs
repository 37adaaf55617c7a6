//! The arm's joint-space dynamics at one instant: the mass matrix M(q) (armature included) and
//! the bias torques (gravity, Coriolis and centrifugal: what the joints must exert for zero
//! joint acceleration). The reference's joint controller needs both, every physics step:
//! τ = M(q)·(kp·e − kd·q̇) + bias (MuJoCo's `qfrc_bias`).
//!
//! Computed from the model's bodies at their current world poses, by composite bodies: each arm
//! joint moves the bodies downstream of it. The fingers count as rigid parts of the hand (their
//! own slide velocities are left out of the bias: grams moving millimetres).

use nalgebra::{Isometry3, Matrix3, SMatrix, Vector3};

use super::robot_model::{ARM_DOF, MAX_BODIES, RobotModel};

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

/// Sums over the bodies riding on a link (world frame), then over a link and those beyond it.
#[derive(Clone, Copy, Default)]
struct Composite {
    mass: f64,
    /// Σ m·c.
    first_moment: Vector3<f64>,
    /// Σ (I + m·(|c|²·1 − c·cᵀ)): the bodies' inertia about the world origin.
    origin_inertia: Matrix3<f64>,
    /// Σ of the forces the bodies need (gravity and the velocity-product accelerations).
    force: Vector3<f64>,
    /// Σ (moment + c × force): their moments about the world origin.
    torque: Vector3<f64>,
}

impl Composite {
    fn add(&mut self, other: &Composite) {
        self.mass += other.mass;
        self.first_moment += other.first_moment;
        self.origin_inertia += other.origin_inertia;
        self.force += other.force;
        self.torque += other.torque;
    }
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
    debug_assert!(
        (1..ARM_DOF).all(|j| arm.downstream[j]
            .iter()
            .all(|b| arm.downstream[j - 1].contains(b))),
        "each arm joint moves what the next one moves"
    );
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

    // Bias, outward: each link's motion with every joint acceleration zero; then the wrench
    // each body needs for it (and against gravity).
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

    // Composite bodies, inward: what joint j moves is every body riding on link j or beyond,
    // so each sum below is taken per link, then accumulated from the hand towards the base.
    let mut composite = [Composite::default(); ARM_DOF];
    for body in bodies.iter().flatten() {
        let (w, a) = (omega[body.link], alpha[body.link]);
        let r = body.com - joints[body.link].anchor;
        let com_acc = anchor_acc[body.link] + a.cross(&r) + w.cross(&w.cross(&r));
        let force = body.mass * (com_acc - g);
        let moment = body.inertia * a + w.cross(&(body.inertia * w));
        let c = body.com;
        let sum = &mut composite[body.link];
        sum.mass += body.mass;
        sum.first_moment += body.mass * c;
        sum.origin_inertia +=
            body.inertia + body.mass * (Matrix3::identity() * c.norm_squared() - c * c.transpose());
        sum.force += force;
        sum.torque += moment + c.cross(&force);
    }
    for j in (0..ARM_DOF - 1).rev() {
        let outer = composite[j + 1];
        composite[j].add(&outer);
    }

    // For a unit rate of joint j (axis a through p), the bodies it moves have the linear
    // momentum Σ m·a × (c − p) = a × (Σ m·c − m·p) and the angular momentum about the world
    // origin Σ m·c × (a × (c − p)) + I·a = Σ (I + m·(|c|²·1 − c·cᵀ))·a − (Σ m·c) × (a × p).
    // For i ≤ j the bodies both joints move are those joint j moves, and
    // M[i, j] = Σ m·v_i·v_j + a_i·I·a_j = a_i · (spin_j − p_i × momentum_j).
    let mut momentum = [Vector3::<f64>::zeros(); ARM_DOF];
    let mut spin = [Vector3::<f64>::zeros(); ARM_DOF];
    for (j, joint) in joints.iter().enumerate() {
        let sum = &composite[j];
        let (a, p) = (&joint.axis, &joint.anchor);
        momentum[j] = a.cross(&(sum.first_moment - sum.mass * p));
        spin[j] = sum.origin_inertia * a - sum.first_moment.cross(&a.cross(p));
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

    // Bias torque of joint j: the wrenches of the bodies it moves about its axis,
    // a · Σ (moment + (c − p) × force) = a · (Σ (moment + c × force) − p × Σ force).
    let bias = std::array::from_fn(|j| {
        let (joint, sum) = (&joints[j], &composite[j]);
        joint
            .axis
            .dot(&(sum.torque - joint.anchor.cross(&sum.force)))
    });
    ArmDynamics { mass_matrix, bias }
}
