//! Forward and inverse kinematics of an arm model, in f64, independent of the physics engine.
//!
//! FK walks the joint chain of a [`RobotModel`]; IK is damped least squares on that FK with the
//! joint limits respected. This is what scripted controllers use to turn a desired gripper
//! pose into joint targets (the arm itself is driven only through its joint servos).

use nalgebra::{
    Isometry3, Matrix3, Rotation3, SMatrix, SVector, Translation3, UnitQuaternion, Vector3,
};

use crate::arena::robot_base_pose;
use crate::physics::{ARM_DOF, JointKind, JointModel, RobotModel};

/// World poses of every body for joint positions `q` (arm joints; fingers at `q_fingers`).
pub fn body_poses(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    q_fingers: [f64; 2],
) -> Vec<Isometry3<f64>> {
    let mut poses = vec![robot_base_pose(); model.bodies.len()];
    place_children(model, q, q_fingers, model.joints.len(), &mut poses);
    poses
}

/// Sets the poses of the first `joints` joints' child bodies, in order, each from its parent's
/// and the joint's value (the arm's from `q`, the fingers' from `q_fingers`).
fn place_children(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    q_fingers: [f64; 2],
    joints: usize,
    poses: &mut [Isometry3<f64>],
) {
    let values = q.iter().chain(&q_fingers);
    for (joint, value) in model.joints.iter().zip(values).take(joints) {
        place_child(joint, *value, poses);
    }
}

/// Sets the pose of `joint`'s child body from its parent's and the joint's `value`.
fn place_child(joint: &JointModel, value: f64, poses: &mut [Isometry3<f64>]) {
    let motion = match joint.kind {
        JointKind::Revolute => Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_scaled_axis(joint.axis * value),
        ),
        JointKind::Prismatic => Isometry3::from_parts(
            Translation3::from(joint.axis * value),
            UnitQuaternion::identity(),
        ),
    };
    poses[joint.child] = poses[joint.parent] * joint.origin * motion;
}

/// World pose of a named URDF link for arm joint positions `q`.
pub fn link_pose(model: &RobotModel, q: &[f64; ARM_DOF], link: &str) -> Option<Isometry3<f64>> {
    let (body, in_body) = *model.links.get(link)?;
    Some(body_poses(model, q, [0.0, 0.0])[body] * in_body)
}

/// A desired gripper pose for IK.
#[derive(Debug, Clone, Copy)]
pub struct IkTarget {
    /// World position of the point `link` should reach.
    pub position: Vector3<f64>,
    /// Desired world orientation of `link`, or `None` for position only.
    pub orientation: Option<UnitQuaternion<f64>>,
    /// Weight of the orientation error (rad) against the position error (m).
    pub orientation_weight: f64,
}

/// How an IK solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkResult {
    /// Joint positions found (within limits).
    pub q: [f64; ARM_DOF],
    /// Remaining position error (m).
    pub position_error: f64,
    /// Remaining orientation error (rad; 0 when not constrained).
    pub orientation_error: f64,
    /// Iterations used.
    pub iterations: usize,
}

/// Damped-least-squares IK for `link` (e.g. the grip site) from the seed `q0`.
pub fn solve_ik(
    model: &RobotModel,
    link: &str,
    target: &IkTarget,
    q0: &[f64; ARM_DOF],
    max_iterations: usize,
) -> Option<IkResult> {
    solve_ik_with(model, link, target, q0, max_iterations, false)
}

/// Iterations between the checks of [`solve_ik_until_stalled`], and the checks compared.
const STALL_CHECK_EVERY: usize = 25;
const STALL_WINDOW_CHECKS: usize = 2;
/// A solve whose weighted error is still above this fraction of what it was
/// [`STALL_WINDOW_CHECKS`] checks earlier has stalled.
const STALL_RATIO: f64 = 0.99;

/// [`solve_ik`] that gives up early where it stopped converging: when the weighted error
/// (position + orientation weight × orientation) shrank by less than 1 % over the last 50
/// iterations, the result is where the solve stands. Seeds spread over the joint space mostly
/// settle in a local minimum short of the target within a few dozen iterations, and running
/// them out to the limit was ~85 % of the planned expert's IK time; measured on six tasks'
/// searches (25,506 solves), this stops 0.2 % of the solves that would have met their target.
pub fn solve_ik_until_stalled(
    model: &RobotModel,
    link: &str,
    target: &IkTarget,
    q0: &[f64; ARM_DOF],
    max_iterations: usize,
) -> Option<IkResult> {
    solve_ik_with(model, link, target, q0, max_iterations, true)
}

fn solve_ik_with(
    model: &RobotModel,
    link: &str,
    target: &IkTarget,
    q0: &[f64; ARM_DOF],
    max_iterations: usize,
    stop_when_stalled: bool,
) -> Option<IkResult> {
    let (body, in_body) = *model.links.get(link)?;
    let mut q = *q0;
    let damping = 0.05_f64;
    let mut result = None;
    // The weighted errors at the last checks, for `stop_when_stalled` (a ring).
    let mut checked_errors = [f64::INFINITY; STALL_WINDOW_CHECKS];
    // Only the arm joints move the link (unless it is on a finger, then all of them do); the
    // poses are updated in place, in `body_poses`' order and arithmetic.
    let mut poses = body_poses(model, &q, [0.0, 0.0]);
    let moving = if model.joints[ARM_DOF..].iter().any(|j| j.child == body) {
        model.joints.len()
    } else {
        ARM_DOF
    };
    for iteration in 0..=max_iterations {
        if iteration > 0 {
            place_children(model, &q, [0.0, 0.0], moving, &mut poses);
        }
        let pose = poses[body] * in_body;
        let p = pose.translation.vector;
        let e_pos = target.position - p;
        let e_rot = match target.orientation {
            Some(r) => (r * pose.rotation.inverse()).scaled_axis(),
            None => Vector3::zeros(),
        };
        result = Some(IkResult {
            q,
            position_error: e_pos.norm(),
            orientation_error: e_rot.norm(),
            iterations: iteration,
        });
        if iteration == max_iterations || (e_pos.norm() < 1e-5 && e_rot.norm() < 1e-4) {
            break;
        }
        let w = if target.orientation.is_some() {
            target.orientation_weight
        } else {
            0.0
        };
        if stop_when_stalled && iteration % STALL_CHECK_EVERY == 0 {
            let error = e_pos.norm() + w * e_rot.norm();
            let check = iteration / STALL_CHECK_EVERY;
            if check >= STALL_WINDOW_CHECKS
                && error > STALL_RATIO * checked_errors[check % STALL_WINDOW_CHECKS]
            {
                break;
            }
            checked_errors[check % STALL_WINDOW_CHECKS] = error;
        }
        let jac = jacobian(model, &poses, &p, w);
        let mut err = SVector::<f64, 6>::zeros();
        err.fixed_rows_mut::<3>(0).copy_from(&e_pos);
        err.fixed_rows_mut::<3>(3).copy_from(&(e_rot * w));
        let jjt = damped_gram(&jac, damping * damping);
        let dq = transpose_times(&jac, &lu_solve(jjt, err)?);
        for (j, joint) in model.joints.iter().enumerate().take(ARM_DOF) {
            // Limit each update so the linearisation stays valid.
            q[j] += dq[j].clamp(-0.2, 0.2);
            if let Some((lo, hi)) = joint.limits {
                q[j] = q[j].clamp(lo, hi);
            }
        }
    }
    result
}

/// `J·Jᵀ + λ²·I`: what nalgebra's `jac * jac.transpose() + I * λ * λ` computes, bit for bit
/// (each entry summed over the columns in order, the identity term added to every entry), without
/// its generic product loops and the transpose's copy. Entry (j, i) is entry (i, j) mirrored:
/// its products are the same pairs the other way round, which IEEE multiplication gives
/// identically, summed in the same order.
fn damped_gram(jac: &SMatrix<f64, 6, ARM_DOF>, lambda_squared: f64) -> SMatrix<f64, 6, 6> {
    let mut gram = SMatrix::<f64, 6, 6>::zeros();
    for i in 0..6 {
        for j in i..6 {
            let mut sum = jac[(i, 0)] * jac[(j, 0)];
            for k in 1..ARM_DOF {
                sum += jac[(i, k)] * jac[(j, k)];
            }
            let entry = sum + if i == j { lambda_squared } else { 0.0 };
            gram[(i, j)] = entry;
            gram[(j, i)] = entry;
        }
    }
    gram
}

/// `Jᵀ·x`, as nalgebra's `jac.transpose() * x` computes it, bit for bit (summed over the rows in
/// order).
fn transpose_times(jac: &SMatrix<f64, 6, ARM_DOF>, x: &SVector<f64, 6>) -> SVector<f64, ARM_DOF> {
    SVector::from_fn(|i, _| {
        let mut sum = jac[(0, i)] * x[0];
        for k in 1..6 {
            sum += jac[(k, i)] * x[k];
        }
        sum
    })
}

/// `A⁻¹·b` for a 6 × 6 `A`: what nalgebra's `a.lu().solve(&b)` computes, bit for bit (Gaussian
/// elimination with partial pivoting — the first largest magnitude of the column wins, a zero
/// column is skipped —, the multipliers scaled by the pivot's reciprocal, then forward and back
/// substitution column by column), `None` where it gives `None` (a zero pivot). nalgebra's
/// generic loops over views cost the planned expert ~10 % of its time on IK-heavy tasks; this
/// is the same arithmetic on a plain array, which the compiler unrolls.
fn lu_solve(a: SMatrix<f64, 6, 6>, b: SVector<f64, 6>) -> Option<SVector<f64, 6>> {
    const N: usize = 6;
    // Row-major copy: a pivot swap exchanges two rows.
    let mut m: [[f64; N]; N] = core::array::from_fn(|r| core::array::from_fn(|c| a[(r, c)]));
    let mut swaps = [(0usize, 0usize); N];
    let mut num_swaps = 0;
    for i in 0..N {
        let mut piv = i;
        let mut largest = m[i][i].abs();
        for (r, row) in m.iter().enumerate().skip(i + 1) {
            if row[i].abs() > largest {
                largest = row[i].abs();
                piv = r;
            }
        }
        let diag = m[piv][i];
        if diag == 0.0 {
            continue;
        }
        if piv != i {
            m.swap(i, piv);
            swaps[num_swaps] = (i, piv);
            num_swaps += 1;
        }
        let inv_diag = 1.0 / diag;
        let pivot_row = m[i];
        for row in m.iter_mut().skip(i + 1) {
            row[i] *= inv_diag;
            let coeff = row[i];
            for k in i + 1..N {
                row[k] += -pivot_row[k] * coeff;
            }
        }
    }
    let mut x: [f64; N] = b.into();
    for &(i, piv) in &swaps[..num_swaps] {
        x.swap(i, piv);
    }
    // L has a unit diagonal (nalgebra divides by 1, which is exact).
    for i in 0..N - 1 {
        let coeff = x[i];
        for r in i + 1..N {
            x[r] += -coeff * m[r][i];
        }
    }
    for i in (0..N).rev() {
        if m[i][i] == 0.0 {
            return None;
        }
        let coeff = x[i] / m[i][i];
        x[i] = coeff;
        for r in 0..i {
            x[r] += -coeff * m[r][i];
        }
    }
    Some(x.into())
}

/// The arm joints' Jacobian at the point `p` (world) of the last body: linear rows first, then
/// the angular rows scaled by `angular_weight`. `poses` are [`body_poses`] at the joints.
fn jacobian(
    model: &RobotModel,
    poses: &[Isometry3<f64>],
    p: &Vector3<f64>,
    angular_weight: f64,
) -> SMatrix<f64, 6, ARM_DOF> {
    let mut jac = SMatrix::<f64, 6, ARM_DOF>::zeros();
    for (j, joint) in model.joints.iter().enumerate().take(ARM_DOF) {
        let frame = poses[joint.child];
        let axis = frame.rotation * joint.axis;
        let anchor = frame.translation.vector;
        jac.fixed_view_mut::<3, 1>(0, j)
            .copy_from(&axis.cross(&(p - anchor)));
        jac.fixed_view_mut::<3, 1>(3, j)
            .copy_from(&(axis * angular_weight));
    }
    jac
}

/// The part of the joint motion `dq` that leaves the pose of `link` unchanged (to first order):
/// `dq` projected onto the null space of the link's Jacobian at `q`. A 7-joint arm holding its
/// gripper still can still swing its elbow: this is that swing. `None` for an unknown link.
pub fn null_space_motion(
    model: &RobotModel,
    link: &str,
    q: &[f64; ARM_DOF],
    dq: &SVector<f64, ARM_DOF>,
) -> Option<SVector<f64, ARM_DOF>> {
    let (body, in_body) = *model.links.get(link)?;
    let poses = body_poses(model, q, [0.0, 0.0]);
    let p = (poses[body] * in_body).translation.vector;
    let jac = jacobian(model, &poses, &p, 1.0);
    // dq − J⁺ J dq, with a tiny damping so a singular pose does not blow up.
    let jjt = damped_gram(&jac, 1e-9);
    let task = lu_solve(jjt, jac * dq)?;
    Some(dq - transpose_times(&jac, &task))
}

/// A rotation whose z axis points along `z` and whose y axis is as close as possible to `y`.
pub fn frame_from_axes(z: Vector3<f64>, y: Vector3<f64>) -> UnitQuaternion<f64> {
    let z = z.normalize();
    let x = y.cross(&z).normalize();
    let y = z.cross(&x);
    // Exact conversion: nalgebra's iterative `from_matrix` can miss rotations near 180°.
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(Matrix3::from_columns(
        &[x, y, z],
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Mt19937;

    /// The IK's hand-written products give nalgebra's results bit for bit (the IK's solutions,
    /// and so the expert's plans, stay what they were).
    #[test]
    fn the_ik_products_equal_nalgebras() {
        let mut rng = Mt19937::init_genrand(3);
        for _ in 0..200 {
            let jac = SMatrix::<f64, 6, ARM_DOF>::from_fn(|_, _| 2.0 * rng.random_sample() - 1.0);
            let x = SVector::<f64, 6>::from_fn(|_, _| 2.0 * rng.random_sample() - 1.0);
            let damping = 0.05_f64;
            let gram = jac * jac.transpose() + SMatrix::<f64, 6, 6>::identity() * damping * damping;
            let ours = damped_gram(&jac, damping * damping);
            assert!(
                gram.iter()
                    .zip(ours.iter())
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
            let product = jac.transpose() * x;
            let ours = transpose_times(&jac, &x);
            assert!(
                product
                    .iter()
                    .zip(ours.iter())
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
        }
    }

    /// The hand-written 6 × 6 LU solve gives nalgebra's `lu().solve` bit for bit: on the IK's
    /// damped Gram matrices, on general matrices (where rows are swapped), and on singular ones
    /// (a zero column, a zero pivot left after elimination), where both give `None`.
    #[test]
    fn the_lu_solve_equals_nalgebras() {
        let mut rng = Mt19937::init_genrand(11);
        let mut uniform = move || 2.0 * rng.random_sample() - 1.0;
        let mut cases: Vec<SMatrix<f64, 6, 6>> = Vec::new();
        for n in 0..300 {
            let general = SMatrix::<f64, 6, 6>::from_fn(|_, _| uniform());
            let jac = SMatrix::<f64, 6, ARM_DOF>::from_fn(|_, _| uniform());
            cases.push(general);
            cases.push(damped_gram(&jac, if n % 2 == 0 { 0.0025 } else { 1e-9 }));
        }
        let mut zero_column = cases[0];
        zero_column.column_mut(2).fill(0.0);
        let mut rank_deficient = cases[0];
        let sum = rank_deficient.column(0) + rank_deficient.column(1);
        rank_deficient.column_mut(4).copy_from(&sum);
        // Ties for the pivot (the first of equal magnitudes is taken), in the first column and
        // in the second after one elimination step.
        let mut ties = cases[0];
        ties[(1, 0)] = 5.0;
        ties[(3, 0)] = -5.0;
        let mut later_ties = SMatrix::<f64, 6, 6>::identity() * 3.0;
        later_ties[(0, 0)] = 4.0;
        later_ties[(2, 1)] = -3.0;
        later_ties[(5, 1)] = 3.0;
        later_ties[(2, 4)] = 1.5;
        later_ties[(5, 3)] = 0.7;
        cases.extend([
            zero_column,
            rank_deficient,
            ties,
            later_ties,
            SMatrix::zeros(),
        ]);
        let mut nones = 0;
        for a in cases {
            let b = SVector::<f64, 6>::from_fn(|_, _| uniform());
            let expected = a.lu().solve(&b);
            let ours = lu_solve(a, b);
            match (expected, ours) {
                (Some(e), Some(o)) => assert!(
                    e.iter()
                        .zip(o.iter())
                        .all(|(x, y)| x.to_bits() == y.to_bits()),
                    "{a}: {e} against {o}"
                ),
                (None, None) => nones += 1,
                (e, o) => panic!("{a}: nalgebra {e:?}, ours {o:?}"),
            }
        }
        assert!(nones >= 2, "the singular cases give None ({nones})");
    }

    /// Out of reach, the stalling solve gives up within a few dozen iterations where the plain
    /// one runs to the limit; within reach, it converges to the same joints as the plain one.
    #[test]
    fn a_stalled_solve_gives_up_and_a_converging_one_does_not() {
        let model = crate::physics::robot_model(crate::axes::Robot::Panda);
        let q0 = [0.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8];
        let reachable = link_pose(
            model,
            &[0.2, 0.5, -0.1, -1.5, 0.2, 1.9, 0.5],
            crate::physics::GRIP_SITE_LINK,
        )
        .expect("the grip site");
        let target = |position| IkTarget {
            position,
            orientation: Some(reachable.rotation),
            orientation_weight: 0.5,
        };
        let within = target(reachable.translation.vector);
        let plain =
            solve_ik(model, crate::physics::GRIP_SITE_LINK, &within, &q0, 600).expect("solved");
        let stalling =
            solve_ik_until_stalled(model, crate::physics::GRIP_SITE_LINK, &within, &q0, 600)
                .expect("solved");
        assert!(plain.position_error < 1e-5, "{plain:?}");
        assert_eq!(plain, stalling);

        let far = target(Vector3::new(2.5, 0.0, 1.0));
        let plain =
            solve_ik(model, crate::physics::GRIP_SITE_LINK, &far, &q0, 600).expect("a result");
        let stalling =
            solve_ik_until_stalled(model, crate::physics::GRIP_SITE_LINK, &far, &q0, 600)
                .expect("a result");
        assert_eq!(plain.iterations, 600);
        assert!(stalling.iterations < 200, "{stalling:?}");
        assert!(stalling.position_error > 1.0, "{stalling:?}");
    }
}
