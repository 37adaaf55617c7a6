//! Pushing without a grasp: the gripper points down with its fingers a little apart, sets
//! them behind the object (as seen from the goal) and pushes it along the floor to the goal
//! in short legs, each aimed again from where the object is then.
//!
//! Two fingers side by side behind a round object (the plate's disc, the dumbbell's discs)
//! hold it between them: pushed off-centre it rolls back into the middle. The gripper's
//! wrist and forearm stay above the pads, clear of walls beside the object's path that a
//! side grasp's low wrist would run into.

use nalgebra::{Point2, Point3, Unit, UnitQuaternion, Vector2, Vector3};

use crate::arena::object_geometry;
use crate::axes::Object;

use super::grasp::{Grasp, gripper_orientation};

/// The pads' gap while pushing (m): the fingers touch a round object about 2.4 cm either
/// side of the push's line.
pub(super) const NUDGE_GAP: f64 = 0.04;
/// Half the fingers' depth along the push (m): the finger blades are 1 cm thick.
const FINGER_HALF_DEPTH: f64 = 0.005;
/// Half the fingertips' width across the push (m): the pads' inner faces are `NUDGE_GAP`
/// apart, the tips 8 mm wide.
const FINGERTIP_HALF_WIDTH: f64 = 0.004;
/// How far behind the contact the pushing starts (m).
const NUDGE_BACKOFF: f64 = 0.05;
/// The longest leg (m) before the push is aimed again.
pub(super) const NUDGE_STEP: f64 = 0.05;
/// How close to the goal (m, xy) the push stops (success is within 3 cm).
const NUDGE_DONE: f64 = 0.01;

/// The pads' centre above the floor while pushing (m): the plate by its disc's rim (the
/// disc spans 3.3–4.7 cm above the floor); the dumbbell by its discs (the lower one spans
/// 0–0.7 cm, the fingertips reach 2 cm below the pads' centre).
fn pad_above_floor(object: Object) -> f64 {
    match object {
        Object::Plate => 0.035,
        _ => 0.0225,
    }
}

/// How far ahead of the pads' centre (m, along the push) a round object of radius `radius`
/// sits when it touches both fingers.
pub(super) fn contact_distance(radius: f64) -> f64 {
    let half_span = NUDGE_GAP / 2.0 + FINGERTIP_HALF_WIDTH;
    (radius * radius - half_span * half_span).max(0.0).sqrt() + FINGER_HALF_DEPTH
}

/// The direction (unit, horizontal) from the object to the goal; None once it is there.
pub(super) fn heading(object: Point3<f64>, goal: Point2<f64>) -> Option<Vector3<f64>> {
    let to_goal: Vector2<f64> = goal - object.xy();
    (to_goal.norm() > NUDGE_DONE).then(|| to_goal.normalize().push(0.0))
}

/// Leans of the gripper about the push's direction (rad), the wrist away from the robot
/// (+x), in the planner's order of preference: upright keeps the fingertips level on the
/// dumbbell's lower disc; leaning lifts the forearm over the door's posts (the Panda's).
const NUDGE_LEANS: [f64; 3] = [0.0, 0.3, 0.55];

/// The grip site's orientation for pushing along `u` (unit, horizontal): pointing down,
/// the fingers closing along `closing` (across the push), leaning by `lean` about the push's
/// direction so that the wrist moves away from the robot.
pub(super) fn pusher_orientation(
    u: Vector3<f64>,
    closing: Vector3<f64>,
    lean: f64,
) -> UnitQuaternion<f64> {
    let axis = Unit::new_normalize(u);
    let tilt = |angle: f64| UnitQuaternion::from_axis_angle(&axis, angle);
    let away = if (tilt(lean) * -Vector3::z()).x <= 0.0 {
        lean
    } else {
        -lean
    };
    tilt(away) * gripper_orientation(-Vector3::z(), closing)
}

/// How far the gripper in `orientation` leans from pointing straight down (rad).
pub(super) fn lean_of(orientation: &UnitQuaternion<f64>) -> f64 {
    (-(orientation * Vector3::z()).z).clamp(-1.0, 1.0).acos()
}

/// The ways of setting the fingers behind `object` (resting at `position`) to push it
/// towards `goal` (each lean of [`NUDGE_LEANS`], the fingers' closing axis across the push
/// either way round), best first; none if it is already there. Each is a [`Grasp`] whose
/// last stretch brings the fingers up to the object, with the gripper opened to
/// [`NUDGE_GAP`].
pub(super) fn pushers(object: Object, position: Point3<f64>, goal: Point2<f64>) -> Vec<Grasp> {
    let Some(u) = heading(position, goal) else {
        return Vec::new();
    };
    let geometry = object_geometry(object);
    let floor = position.z + geometry.bottom_offset;
    let behind = position.coords - u * contact_distance(geometry.horizontal_radius);
    let pad = Vector3::new(behind.x, behind.y, floor + pad_above_floor(object));
    let across = u.cross(&Vector3::z());
    NUDGE_LEANS
        .iter()
        .flat_map(|&lean| [(across, lean), (-across, lean)])
        .map(|(closing, lean)| Grasp {
            orientation: pusher_orientation(u, closing, lean),
            pad,
            approach: u,
            backoff: NUDGE_BACKOFF,
            open: NUDGE_GAP,
            top_down: true,
        })
        .collect()
}

/// The next leg of the push, from the pads' measured centre `pad`: where the pads go (xy)
/// and the push's direction; None once the object is at the goal. The pads move towards the
/// goal by up to [`NUDGE_STEP`], plus whatever gap has opened between them and the object,
/// and sideways by the object's offset from their line.
pub(super) fn leg(
    object: Object,
    position: Point3<f64>,
    goal: Point2<f64>,
    pad: Vector3<f64>,
) -> Option<(Point2<f64>, Vector3<f64>)> {
    let u = heading(position, goal)?;
    let u2 = u.xy();
    let to_go = (goal - position.xy()).norm();
    let relative: Vector2<f64> = position.xy().coords - pad.xy();
    let ahead = relative.dot(&u2);
    let sideways = relative - u2 * ahead;
    let contact = contact_distance(object_geometry(object).horizontal_radius);
    let gap = (ahead - contact).max(0.0);
    let target = pad.xy() + sideways + u2 * (NUDGE_STEP.min(to_go) + gap);
    Some((Point2::from(target), u))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fingers_start_behind_the_object_as_seen_from_the_goal() {
        let position = Point3::new(0.15, -0.25, 0.84);
        let goal = Point2::new(0.1, 0.13);
        let pushers = pushers(Object::Plate, position, goal);
        assert_eq!(pushers.len(), 2 * NUDGE_LEANS.len());
        for p in &pushers {
            // Behind: the object lies between the pads and the goal.
            let to_object = position.xy().coords - p.pad.xy();
            let to_goal = goal.coords - p.pad.xy();
            assert!(to_object.dot(&to_goal) > 0.0);
            assert!(to_object.norm() < to_goal.norm());
            // The plate's disc (0.06 m) reaches the fingers 2.4 cm either side of the line.
            let expected = (0.06f64.powi(2) - 0.024f64.powi(2)).sqrt() + 0.005;
            assert!((to_object.norm() - expected).abs() < 1e-9);
            // At the disc's height, pointing down or leaning the wrist away from the robot.
            assert!((p.pad.z - (0.82 + 0.035)).abs() < 1e-9);
            let approach_axis = p.orientation * Vector3::z();
            let lean = lean_of(&p.orientation);
            assert!(
                NUDGE_LEANS.iter().any(|l| (l - lean).abs() < 1e-9),
                "{lean}"
            );
            assert!(
                approach_axis.x <= 1e-9,
                "fingertips towards the robot: {approach_axis}"
            );
            // The fingers close across the push.
            let closing = p.orientation * Vector3::x();
            assert!(closing.xy().dot(&(goal - position.xy())).abs() < 1e-9);
        }
        assert!(pushers[0].orientation.angle_to(&pushers[1].orientation) > 3.0);
    }

    #[test]
    fn a_leg_steps_towards_the_goal_and_recentres_the_object() {
        let goal = Point2::new(0.1, 0.13);
        let position = Point3::new(0.1, -0.2, 0.872);
        let contact = contact_distance(0.045);
        // The object touches the fingers but sits 1 cm off their line (+x).
        let pad = Vector3::new(0.09, -0.2 - contact, 0.84);
        let (target, u) = leg(Object::Dumbbell, position, goal, pad).expect("not there yet");
        assert!((u - Vector3::y()).norm() < 1e-9);
        assert!((target.x - 0.1).abs() < 1e-9, "recentred: {target}");
        assert!((target.y - (pad.y + NUDGE_STEP)).abs() < 1e-9);
        // Near the goal the leg is only as long as what is left; at it, none.
        let near = Point3::new(0.1, 0.11, 0.872);
        let pad = Vector3::new(0.1, 0.11 - contact, 0.84);
        let (target, _) = leg(Object::Dumbbell, near, goal, pad).expect("2 cm to go");
        assert!((target.y - (pad.y + 0.02)).abs() < 1e-9);
        assert!(leg(Object::Dumbbell, Point3::new(0.1, 0.125, 0.872), goal, pad).is_none());
    }
}
