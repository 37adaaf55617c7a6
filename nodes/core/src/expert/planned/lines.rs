//! Straight lines of the pads turned into joints, one IK solution from the last: plain, with the
//! elbow swung clear of the arena, or with the gripper turning about the vertical on the way;
//! and the gaps they keep.

use nalgebra::{UnitQuaternion, Vector3};

use crate::expert::clearance::Clearance;
use crate::expert::motion::{pad_ik, pad_ik_clear};
use crate::expert::track::{Joints, Leg};
use crate::physics::RobotModel;

/// Spacing (m) of the IK points along a straight line of the pads.
const LINE_SPACING: f64 = 0.01;
/// How much more gap (m) turned or shifted lines must keep than the best so far to replace it.
const TURN_GAIN: f64 = 0.005;

/// Joints along the straight line of the pads from `from` to `to` (the gripper turned to
/// `orientation`), starting with `q`, each solved from the last: `None` where the IK does not
/// meet a point.
pub(super) fn line(
    model: &RobotModel,
    q: Joints,
    from: Vector3<f64>,
    to: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> Option<Vec<Joints>> {
    line_by(q, from, to, |last, p, _| {
        pad_ik(model, last, p, orientation)
    })
}

/// [`line`], the arm swung away from the arena in the IK's null space wherever a link comes
/// close to it (the elbow turning about the shoulder–wrist line, the pads held on the line).
pub(super) fn swinging_line(
    model: &RobotModel,
    clearance: &Clearance,
    q: Joints,
    from: Vector3<f64>,
    to: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
) -> Option<Vec<Joints>> {
    line_by(q, from, to, |last, p, _| {
        pad_ik_clear(model, clearance, last, p, orientation)
    })
}

/// Whether lines keeping `gap` (m) replace `best`: they keep more, and a turned or shifted
/// variant (not `plain`) by [`TURN_GAIN`] more — among lines that all come close, one that
/// comes a fraction of a millimetre less close is no better.
pub(super) fn keeps_more<T>(best: &Option<(f64, T)>, gap: f64, plain: bool) -> bool {
    let margin = if plain { 0.0 } else { TURN_GAIN };
    best.as_ref().is_none_or(|(g, _)| gap > *g + margin)
}

/// A push's last line: [`swinging_line`] of the pads where `turn` is 0, else
/// [`turning_line`]; the object from `line.0` to `line.1`, held by the pads at `offset` from it.
pub(super) fn last_line(
    model: &RobotModel,
    carrying: &Clearance,
    q: Joints,
    line: (Vector3<f64>, Vector3<f64>),
    offset: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    turn: f64,
) -> Option<Vec<Joints>> {
    if turn == 0.0 {
        let (from, to) = line;
        swinging_line(model, carrying, q, from + offset, to + offset, orientation)
    } else {
        turning_line(model, carrying, q, line, offset, orientation, turn)
    }
}

/// Joints along the object's straight line from `from` to `to` (m), held by the pads at
/// `offset` from it with the gripper at `orientation`, both turned about the vertical by
/// `turn` (rad) in proportion on the way, the elbow swung clear as in [`swinging_line`];
/// starting with `q`, `None` where the IK does not meet a point.
fn turning_line(
    model: &RobotModel,
    clearance: &Clearance,
    q: Joints,
    (from, to): (Vector3<f64>, Vector3<f64>),
    offset: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    turn: f64,
) -> Option<Vec<Joints>> {
    line_by(q, from, to, |last, p, t| {
        let yaw = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn * t);
        pad_ik_clear(model, clearance, last, p + yaw * offset, yaw * orientation)
    })
}

/// Straight lines of the pads (at `offset` from the object, the gripper at `orientation`)
/// taking the object from where it is to each of `stops` in turn, the arm starting at `q` with
/// the pads at `pad` and swung clear as `carrying` says: the smallest gap from `walls` on
/// them and the legs, or `None` where the IK does not meet a point.
#[allow(clippy::too_many_arguments)]
pub(super) fn lines_through(
    model: &RobotModel,
    carrying: &Clearance,
    walls: &Clearance,
    q: Joints,
    pad: Vector3<f64>,
    offset: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    stops: &[Vector3<f64>],
) -> Option<(f64, Vec<Leg>)> {
    let (mut pad, mut from) = (pad, q);
    let mut legs = Vec::new();
    let mut gap = f64::INFINITY;
    for stop in stops {
        let to = stop + offset;
        let points = swinging_line(model, carrying, from, pad, to, orientation)?;
        gap = gap.min(smallest_gap(model, walls, &points));
        from = *points.last().expect("a point");
        pad = to;
        legs.push(Leg::new(points));
    }
    Some((gap, legs))
}

/// The smallest gap (m) the arm keeps from `clearance`'s arena over `points`.
pub(super) fn smallest_gap(model: &RobotModel, clearance: &Clearance, points: &[Joints]) -> f64 {
    points
        .iter()
        .map(|c| clearance.at(model, c))
        .fold(f64::INFINITY, f64::min)
}

/// Points every [`LINE_SPACING`] from `from` to `to`, each turned into joints by `solve` from
/// the joints of the one before (`q` first) and how far along the line it is (0…1): the
/// joints, `q` included, or `None` where `solve` does not meet a point.
fn line_by(
    q: Joints,
    from: Vector3<f64>,
    to: Vector3<f64>,
    mut solve: impl FnMut(&Joints, Vector3<f64>, f64) -> (Joints, bool),
) -> Option<Vec<Joints>> {
    let n = ((to - from).norm() / LINE_SPACING).ceil().max(1.0) as usize;
    let mut points = vec![q];
    for k in 1..=n {
        let t = k as f64 / n as f64;
        let p = from + (to - from) * t;
        let (solved, met) = solve(points.last().expect("q first"), p, t);
        if !met {
            return None;
        }
        points.push(solved);
    }
    Some(points)
}
