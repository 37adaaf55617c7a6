//! Motion primitives: straight lines of the pads' centre turned into joint targets with the
//! crate's IK, one per control step.

use nalgebra::{Point3, SVector, UnitQuaternion, Vector3};

use std::f64::consts::PI;

use super::clearance::Clearance;
use super::track::joint_distance;
use crate::kinematics::{
    IkResult, IkTarget, link_pose, null_space_motion, solve_ik, solve_ik_until_stalled,
};
use crate::physics::{ARM_DOF, GRIP_SITE_LINK, RobotModel};

/// The pads' centre is this far above the grip site along the gripper's approach axis (m):
/// the pads span 0.0859…0.1189 from the gripper mount, the grip site is at 0.109.
pub(super) const PAD_CENTRE_ABOVE_GRIP_SITE: f64 = 0.109 - (0.0859 + 0.1189) / 2.0;
/// Iterations per IK solve (seeded from the previous step's solution, so few are needed).
const IK_ITERATIONS: usize = 80;
/// Position error (m) above which an IK solve is retried with more iterations.
const IK_RETRY_ERROR: f64 = 2e-3;
/// Iterations of the retry.
const IK_RETRY_ITERATIONS: usize = 600;
/// Position error (m) up to which a solve counts as reaching its target.
const IK_MET_POSITION: f64 = 0.005;
/// Orientation error (rad) up to which a solve counts as reaching its target.
const IK_MET_ORIENTATION: f64 = 0.05;
/// Spread-out seeds tried by [`pad_ik_global`].
const GLOBAL_SEEDS: usize = 24;
/// Orientation error weight in the IK.
const IK_ORIENTATION_WEIGHT: f64 = 0.5;

/// The environment's control period (s): one planned action per step.
pub(super) const CONTROL_PERIOD: f64 = 0.05;

/// Control steps (50 ms) in `seconds`.
pub(super) fn steps(seconds: f64) -> usize {
    ((seconds / CONTROL_PERIOD).round() as usize).max(1)
}

/// The smoothstep time law: 0 → 1 with zero speed at both ends.
pub(super) fn smoothstep(s: f64) -> f64 {
    s * s * (3.0 - 2.0 * s)
}

/// The IK target that puts the pads' centre at `pad` with the grip site turned to `orientation`.
fn pad_target(pad: Vector3<f64>, orientation: UnitQuaternion<f64>) -> IkTarget {
    IkTarget {
        position: pad - orientation * Vector3::new(0.0, 0.0, -PAD_CENTRE_ABOVE_GRIP_SITE),
        orientation: Some(orientation),
        orientation_weight: IK_ORIENTATION_WEIGHT,
    }
}

/// Joints that put the pads at `pad` with `orientation`, seeded from `q` (and `q` itself when
/// the solver fails outright), and whether the solve met the pose.
pub(super) fn pad_ik(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> ([f64; ARM_DOF], bool) {
    let target = pad_target(pad, orientation);
    let mut result = solve_ik(model, GRIP_SITE_LINK, &target, q, IK_ITERATIONS);
    if result.is_none_or(|r| r.position_error > IK_RETRY_ERROR) {
        // A large step (a wrist turn): give the solver more room before accepting.
        result = solve_ik(model, GRIP_SITE_LINK, &target, q, IK_RETRY_ITERATIONS);
    }
    match result {
        Some(r) => (r.q, met(&r)),
        None => (*q, false),
    }
}

/// How close (m) to the arena the arm may come before [`pad_ik_clear`] swings it away. The swing
/// moves the joints by at most [`SWING_STEP`] per control step, so it starts while a link is
/// still a few cm off: the steps add up before the link gets there. Its measured effect:
/// docs/src/expert.md, "How the expert's settings were chosen".
const SWING_MARGIN: f64 = 0.03;
/// The largest joint change (rad) of one swing step.
const SWING_STEP: f64 = 0.02;
/// Step (rad) of the finite differences of the crowding's gradient.
const SWING_PROBE: f64 = 1e-4;

/// [`pad_ik`], then the arm swung away from the arena in the IK's null space (the elbow of a
/// 7-joint arm turns about the shoulder–wrist line with the gripper held still) by up to
/// [`SWING_STEP`] where it comes within [`SWING_MARGIN`] of it. Called once per step of a
/// straight line, the swings add up to keep the forearm off walls the gripper passes close to.
pub(super) fn pad_ik_clear(
    model: &RobotModel,
    clearance: &Clearance,
    q: &[f64; ARM_DOF],
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> ([f64; ARM_DOF], bool) {
    let (solved, met) = pad_ik(model, q, pad, orientation);
    let crowding = clearance.crowding(model, &solved, SWING_MARGIN);
    if !met || crowding == 0.0 {
        return (solved, met);
    }
    let mut downhill = SVector::<f64, ARM_DOF>::zeros();
    for j in 0..ARM_DOF {
        let mut probe = solved;
        probe[j] += SWING_PROBE;
        downhill[j] = (crowding - clearance.crowding(model, &probe, SWING_MARGIN)) / SWING_PROBE;
    }
    let Some(swing) = null_space_motion(model, GRIP_SITE_LINK, &solved, &downhill) else {
        return (solved, met);
    };
    let largest = swing.amax();
    if largest < 1e-9 {
        return (solved, met);
    }
    // Halve the step until it helps (the crowding is a sum of squares: a full step can
    // overshoot where two parts are close).
    let mut step = SWING_STEP / largest;
    for _ in 0..4 {
        let mut swung = solved;
        for j in 0..ARM_DOF {
            swung[j] += step * swing[j];
        }
        // Back onto the pose: the swing keeps it only to first order.
        let (swung, swung_met) = pad_ik(model, &swung, pad, orientation);
        if swung_met && clearance.crowding(model, &swung, SWING_MARGIN) < crowding {
            return (swung, true);
        }
        step *= 0.5;
    }
    (solved, met)
}

/// Whether an IK result is close enough to its target to be tracked.
fn met(r: &IkResult) -> bool {
    r.position_error < IK_MET_POSITION && r.orientation_error < IK_MET_ORIENTATION
}

/// Every distinct way of meeting the pose found from several seeds (`q`, then `q` with one
/// joint moved far, then spread-out poses), the ones moving the joints least first.
/// Used where following a straight line from `q` runs into a joint limit, and to pick a
/// grasp the arm reaches without touching the arena.
pub(super) fn pad_ik_solutions(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> Vec<[f64; ARM_DOF]> {
    let target = pad_target(pad, orientation);
    let limits: Vec<(f64, f64)> = model.joints[..ARM_DOF]
        .iter()
        .map(|j| j.limits.unwrap_or((-PI, PI)))
        .collect();
    let mut seeds = vec![*q];
    for j in 0..ARM_DOF {
        for delta in [-1.2, 1.2] {
            let mut s = *q;
            s[j] = (s[j] + delta).clamp(limits[j].0, limits[j].1);
            seeds.push(s);
        }
    }
    // A fixed quasi-random spread (golden-ratio sequence) over the joint ranges.
    let mut u = 0.5_f64;
    for _ in 0..GLOBAL_SEEDS {
        let mut s = *q;
        for (j, (lo, hi)) in limits.iter().enumerate() {
            u = (u + 0.618_033_988_75).fract();
            let (lo, hi) = (lo.max(-PI), hi.min(PI));
            s[j] = lo + (hi - lo) * u;
        }
        seeds.push(s);
    }
    let mut found: Vec<([f64; ARM_DOF], f64)> = Vec::new();
    for s in &seeds {
        let Some(r) =
            solve_ik_until_stalled(model, GRIP_SITE_LINK, &target, s, IK_RETRY_ITERATIONS)
        else {
            continue;
        };
        if !met(&r) || found.iter().any(|(f, _)| distance(f, &r.q) < 0.05) {
            continue;
        }
        found.push((r.q, distance(&r.q, q)));
    }
    found.sort_by(|a, b| a.1.total_cmp(&b.1));
    found.into_iter().map(|(q, _)| q).collect()
}

/// Summed absolute joint differences (rad).
pub(super) fn distance(a: &[f64; ARM_DOF], b: &[f64; ARM_DOF]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum()
}

/// How hard it is to put the pads at `pad` with `orientation` from `q`: the IK's remaining
/// error (heavily weighted) plus the joint motion.
pub(super) fn reach_cost(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> f64 {
    let target = pad_target(pad, orientation);
    match solve_ik(model, GRIP_SITE_LINK, &target, q, IK_RETRY_ITERATIONS) {
        Some(r) => {
            let motion: f64 = r.q.iter().zip(q).map(|(a, b)| (a - b).abs()).sum();
            100.0 * (r.position_error + r.orientation_error) + motion
        }
        None => f64::INFINITY,
    }
}

/// The pads' centre and the grip site's orientation with the arm at `q`.
pub(super) fn pads_at(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let grip = link_pose(model, q, GRIP_SITE_LINK).expect("grip site link");
    let pad = grip * Point3::new(0.0, 0.0, -PAD_CENTRE_ABOVE_GRIP_SITE);
    (pad.coords, grip.rotation)
}

/// The way a gripper at the grip-site `orientation` points, level: its approach axis with the
/// vertical part dropped (not normalised: short where the gripper points nearly up or down).
pub(super) fn level_pointing(orientation: &UnitQuaternion<f64>) -> Vector3<f64> {
    let pointing = orientation * Vector3::z();
    Vector3::new(pointing.x, pointing.y, 0.0)
}

/// Steps of [`least_travel`]'s descent.
const LEAST_TRAVEL_STEPS: usize = 40;
/// The largest joint change (rad) of one such step at first.
const LEAST_TRAVEL_STEP: f64 = 0.05;

/// `solved` (joints meeting the pads' pose) slid along the arm's self-motion (the elbow's swing
/// about the shoulder–wrist line, the pads held) towards the pose nearest `q` in the largest
/// joint difference: under the reference's controller that is the time the move takes.
pub(super) fn least_travel(
    model: &RobotModel,
    q: &[f64; ARM_DOF],
    solved: [f64; ARM_DOF],
    pad: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> [f64; ARM_DOF] {
    let travel = |c: &[f64; ARM_DOF]| joint_distance(c, q);
    let (mut best, mut best_travel) = (solved, travel(&solved));
    let mut step = LEAST_TRAVEL_STEP;
    for _ in 0..LEAST_TRAVEL_STEPS {
        if best_travel < 1e-6 || step < 1e-3 {
            break;
        }
        // Downhill of Σ (d_j / max)^8: the joints that move furthest pulled back hardest.
        let downhill = SVector::<f64, ARM_DOF>::from_fn(|j, _| {
            let d = best[j] - q[j];
            -d.signum() * (d.abs() / best_travel).powi(7)
        });
        let Some(swing) = null_space_motion(model, GRIP_SITE_LINK, &best, &downhill) else {
            break;
        };
        let largest = swing.amax();
        if largest < 1e-9 {
            break;
        }
        let mut moved = best;
        for j in 0..ARM_DOF {
            moved[j] += step / largest * swing[j];
        }
        let (moved, met) = pad_ik(model, &moved, pad, orientation);
        let moved_travel = travel(&moved);
        if met && moved_travel < best_travel - 1e-6 {
            (best, best_travel) = (moved, moved_travel);
        } else {
            step *= 0.5;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axes::Robot;
    use crate::physics::robot_model;

    /// Sliding a solution along the arm's self-motion keeps the pads where they were and
    /// finds the quicker poses: for every arm, the pose the shoulder, elbow and wrist bent
    /// from the initial pose put the pads in, its elbow first swung away (1.2 rad of joint motion), comes
    /// back to about the bend's own largest joint move.
    #[test]
    fn least_travel_keeps_the_pose_and_moves_the_joints_less() {
        for robot in [Robot::Iiwa, Robot::Jaco, Robot::Gen3, Robot::Panda] {
            let model = robot_model(robot);
            let q = robot.init_qpos();
            let mut bent = q;
            for (j, by) in [(1, 0.3), (3, 0.5), (5, -0.8)] {
                bent[j] += by;
            }
            let (pad, orientation) = pads_at(model, &bent);
            let travel = |c: &[f64; ARM_DOF]| joint_distance(c, &q);
            // The elbow swung by turning the shoulder (the way that moves the joints more), the
            // pads held.
            let swing_by = |sign: f64| {
                let shoulder =
                    SVector::<f64, ARM_DOF>::from_fn(|j, _| if j == 0 { sign } else { 0.0 });
                let mut swung = bent;
                for _ in 0..20 {
                    let swing = null_space_motion(model, GRIP_SITE_LINK, &swung, &shoulder)
                        .expect("grip site");
                    let step = 0.06 / swing.amax();
                    let moved = std::array::from_fn(|j| swung[j] + step * swing[j]);
                    let (moved, met) = pad_ik(model, &moved, pad, orientation);
                    assert!(met, "{robot:?}");
                    swung = moved;
                }
                swung
            };
            let (plus, minus) = (swing_by(1.0), swing_by(-1.0));
            let swung = if travel(&plus) > travel(&minus) {
                plus
            } else {
                minus
            };
            assert!(travel(&swung) > travel(&bent) + 0.1, "{robot:?}");
            let quicker = least_travel(model, &q, swung, pad, orientation);
            let (at, turned) = pads_at(model, &quicker);
            assert!((at - pad).norm() < IK_MET_POSITION, "{robot:?}");
            assert!(
                turned.angle_to(&orientation) < IK_MET_ORIENTATION,
                "{robot:?}"
            );
            assert!(
                travel(&quicker) < travel(&bent) + 0.02,
                "{robot:?}: {} from {} (the bend's {})",
                travel(&quicker),
                travel(&swung),
                travel(&bent)
            );
        }
    }
}
