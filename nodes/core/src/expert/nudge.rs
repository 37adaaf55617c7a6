//! Pushing without a grasp: the gripper points down with its fingers a little apart, sets
//! them behind the object (as seen from the goal) and pushes it along the floor to the goal
//! in short legs, each aimed again from where the object is then.
//!
//! Two fingers side by side behind a round object (the plate's disc, the dumbbell's discs)
//! hold it between them: pushed off-centre it rolls back into the middle. The gripper's
//! wrist and forearm stay above the pads, clear of walls beside the object's path that a
//! side grasp's low wrist would run into.

use nalgebra::{Point2, Point3, Unit, UnitQuaternion, Vector2, Vector3};

use crate::arena::{arena_parts, object_geometry};
use crate::axes::{Object, Objective, Obstacle};

use super::grasp::{Grasp, gripper_orientation};

/// The pads' gap while pushing (m): the fingers touch a round object about 2.4 cm either
/// side of the push's line.
const NUDGE_GAP: f64 = 0.04;
/// Half the fingers' depth along the push (m): the finger blades are 1 cm thick.
const FINGER_HALF_DEPTH: f64 = 0.005;
/// Half the fingertips' width across the push (m): the pads' inner faces are `NUDGE_GAP`
/// apart, the tips 8 mm wide.
const FINGERTIP_HALF_WIDTH: f64 = 0.004;
/// How far behind the contact the pushing starts (m).
const NUDGE_BACKOFF: f64 = 0.05;
/// The longest leg (m) before the push is aimed again.
const NUDGE_STEP: f64 = 0.05;
/// How close to the goal (m, xy) the push stops (success is within 3 cm).
const NUDGE_DONE: f64 = 0.01;
/// How close to a point on the way (m, xy) the object counts as having passed it.
const VIA_PASSED: f64 = 0.025;

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
fn contact_distance(radius: f64) -> f64 {
    let half_span = NUDGE_GAP / 2.0 + FINGERTIP_HALF_WIDTH;
    (radius * radius - half_span * half_span).max(0.0).sqrt() + FINGER_HALF_DEPTH
}

/// How far (m) the object's edge keeps from the goal wall on its way round the wall's end.
const WALL_MARGIN: f64 = 0.015;
/// How far (m) in front of the goal wall's line (beyond the object's radius) the object is
/// turned round the wall's end.
const TURN_BEFORE_WALL: f64 = 0.01;

/// Where the object is pushed through on its way from `position` to `goal` (xy), before the
/// goal itself: with the goal wall in the way, a point in front of the wall's line from which
/// the straight push to the goal passes the wall's free end with the object's edge
/// [`WALL_MARGIN`] clear of it — or, where bin 2's far wall leaves no room for that (the
/// plate), a lane past the wall's end from in front of its line to behind it. None where the
/// straight push is clear; points the object is already at are left out.
pub(super) fn route(
    object: Object,
    obstacle: Obstacle,
    position: Point3<f64>,
    goal: Point2<f64>,
) -> Vec<Point2<f64>> {
    if obstacle != Obstacle::GoalWall {
        return Vec::new();
    }
    let parts = arena_parts(Objective::Push, obstacle);
    let solid = |name: &str| {
        let part = parts.iter().find(|p| p.name.starts_with(name));
        part.unwrap_or_else(|| panic!("no {name} in the Push arena"))
            .aabb()
    };
    let (low, high) = solid("obstacle/");
    // The object's edge stays a centimetre inside bin 2's far wall.
    let far_wall_x = solid("bin2/wall_x+").0.x;
    let radius = object_geometry(object).horizontal_radius;
    let clear = radius + WALL_MARGIN;
    let clears = |from: Point2<f64>| path_gap(from, goal, &(low, high)) >= clear;
    if clears(position.xy()) {
        return Vec::new();
    }
    let before = low.y - radius - TURN_BEFORE_WALL;
    let last_x = far_wall_x - radius - 0.01;
    let mut x = position.x.max(high.x);
    while x < last_x && !clears(Point2::new(x, before)) {
        x += 0.005;
    }
    let route = if clears(Point2::new(x, before)) {
        vec![Point2::new(x, before)]
    } else {
        let lane = (high.x + clear).max(position.x).min(last_x);
        vec![Point2::new(lane, before), Point2::new(lane, high.y + clear)]
    };
    // Points already reached (pushed to one, about to turn) are passed.
    route
        .into_iter()
        .skip_while(|via| passed(position, via))
        .collect()
}

/// Whether the object at `position` has passed the point `via` on its way.
pub(super) fn passed(position: Point3<f64>, via: &Point2<f64>) -> bool {
    (position.xy() - via).norm() < VIA_PASSED
}

/// The smallest horizontal distance (m) from the straight path `from` → `to` to the box with
/// corners `solid` (sampled every 5 mm).
fn path_gap(from: Point2<f64>, to: Point2<f64>, solid: &(Point3<f64>, Point3<f64>)) -> f64 {
    let (low, high) = solid;
    let n = ((to - from).norm() / 0.005).ceil().max(1.0) as usize;
    (0..=n)
        .map(|k| from + (to - from) * (k as f64 / n as f64))
        .map(|p| {
            let dx = (low.x - p.x).max(p.x - high.x).max(0.0);
            let dy = (low.y - p.y).max(p.y - high.y).max(0.0);
            dx.hypot(dy)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The direction (unit, horizontal) from the object to the goal; None once it is there.
fn heading(object: Point3<f64>, goal: Point2<f64>) -> Option<Vector3<f64>> {
    let to_goal: Vector2<f64> = goal - object.xy();
    (to_goal.norm() > NUDGE_DONE).then(|| to_goal.normalize().push(0.0))
}

/// Leans of the gripper from pointing straight down (rad), tried both ways: about the push's
/// direction with the wrist away from the robot (+x), which lifts the forearm over the
/// door's posts (the Panda's); and, for the plate, about the fingers' closing axis with the
/// wrist ahead of the pads, which the plate's pushes gain from. The dumbbell is pushed
/// upright: leaning ahead, the fingers meet its upper disc before the lower one and tip it over.
const LEANS: [f64; 3] = [0.0, 0.3, 0.55];

/// The grip site's orientations for pushing `object` along `u` (unit, horizontal): pointing
/// down, the fingers closing along `closing` (across the push), leaning by each pair of
/// [`LEANS`] the object allows — the least leaning first.
pub(super) fn pusher_orientations(
    object: Object,
    u: Vector3<f64>,
    closing: Vector3<f64>,
) -> Vec<UnitQuaternion<f64>> {
    let aheads: &[f64] = if object == Object::Plate {
        &LEANS
    } else {
        &[0.0]
    };
    let mut leans: Vec<(f64, f64)> = LEANS
        .iter()
        .flat_map(|&away| aheads.iter().map(move |&ahead| (away, ahead)))
        .collect();
    leans.sort_by(|a, b| {
        (a.0.max(a.1), a.0 + a.1)
            .partial_cmp(&(b.0.max(b.1), b.0 + b.1))
            .expect("finite")
    });
    leans
        .into_iter()
        .map(|(away, ahead)| pusher_orientation(u, closing, away, ahead))
        .collect()
}

/// The grip site's orientation for pushing along `u` with the fingers closing along
/// `closing`, leaning by `away` about `u` (the wrist towards +x) and by `ahead` about the
/// closing axis (the wrist towards +`u`).
fn pusher_orientation(
    u: Vector3<f64>,
    closing: Vector3<f64>,
    away: f64,
    ahead: f64,
) -> UnitQuaternion<f64> {
    // The wrist is behind the fingertips: leaning it one way turns the approach axis (wrist
    // to fingertips) the other.
    let signed = |axis: Vector3<f64>, angle: f64, wrist_towards: Vector3<f64>| {
        let turn = |a: f64| UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), a);
        if (turn(angle) * -Vector3::z()).dot(&wrist_towards) <= 0.0 {
            turn(angle)
        } else {
            turn(-angle)
        }
    };
    let along_across = signed(closing, ahead, u);
    let about_push = signed(u, away, Vector3::x());
    about_push * along_across * gripper_orientation(-Vector3::z(), closing)
}

/// The ways of setting the fingers behind `object` (resting at `position`) to push it
/// towards `goal` (each of [`pusher_orientations`], the fingers' closing axis across the push
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
    let mut orientations = pusher_orientations(object, u, across);
    orientations.extend(pusher_orientations(object, u, -across));
    orientations
        .into_iter()
        .map(|orientation| Grasp {
            orientation,
            pad,
            approach: u,
            backoff: NUDGE_BACKOFF,
            open: NUDGE_GAP,
            top_down: true,
        })
        .collect()
}

/// What the push does next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Leg {
    /// The object is at the goal.
    Done,
    /// The pads go to this point (xy) pushing along this direction.
    To(Point2<f64>, Vector3<f64>),
    /// The object is no longer between the fingers on their way to the goal (it slid
    /// aside, or went past the goal): set them behind it again.
    Lost,
}

/// The next leg of the push, from the pads' measured centre `pad`. The pads move towards the
/// goal by up to [`NUDGE_STEP`], plus whatever gap has opened between them and the object
/// (up to another step), and sideways by the object's offset from their line.
pub(super) fn leg(
    object: Object,
    position: Point3<f64>,
    goal: Point2<f64>,
    pad: Vector3<f64>,
) -> Leg {
    let Some(u) = heading(position, goal) else {
        return Leg::Done;
    };
    let u2 = u.xy();
    let to_go = (goal - position.xy()).norm();
    let relative: Vector2<f64> = position.xy().coords - pad.xy();
    let ahead = relative.dot(&u2);
    let sideways = relative - u2 * ahead;
    if ahead <= 0.0 || sideways.norm() > NUDGE_GAP / 2.0 {
        return Leg::Lost;
    }
    let contact = contact_distance(object_geometry(object).horizontal_radius);
    let gap = (ahead - contact).clamp(0.0, NUDGE_STEP);
    let target = pad.xy() + sideways + u2 * (NUDGE_STEP.min(to_go) + gap);
    Leg::To(Point2::from(target), u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_the_goal_wall_the_push_turns_in_front_of_its_free_end() {
        let goal = Point2::new(0.1, 0.13);
        // The goal wall spans x -0.10…0.11 at y -0.015…-0.005 (docs/src/reference-facts.md §2.3).
        let wall = (
            Point3::new(-0.10, -0.015, 0.82),
            Point3::new(0.11, -0.005, 1.1),
        );
        for object in [Object::Plate, Object::Dumbbell] {
            let r = object_geometry(object).horizontal_radius;
            for start in [
                Point3::new(0.06, -0.25, 0.84),
                Point3::new(0.14, -0.3, 0.84),
            ] {
                let via = route(object, Obstacle::GoalWall, start, goal);
                assert!(!via.is_empty(), "{object:?} from {start}");
                // In front of the wall's line, then (if at all) straight past its end.
                assert!((via[0].y - (-0.015 - r - 0.01)).abs() < 1e-9, "{via:?}");
                let mut from = start.xy();
                for w in via.iter().chain([&goal]) {
                    assert!(path_gap(from, *w, &wall) >= r + 0.01 - 1e-9, "{from} → {w}");
                    // Inside bin 2's far wall (x 0.29, docs/src/reference-facts.md §2.1).
                    assert!(w.x + r <= 0.29, "{w}");
                    from = *w;
                }
            }
            // The dumbbell turns once; the plate needs a lane.
            let start = Point3::new(0.1, -0.25, 0.84);
            let via = route(object, Obstacle::GoalWall, start, goal);
            let turns = if object == Object::Plate { 2 } else { 1 };
            assert_eq!(via.len(), turns, "{via:?}");
            // Without the wall, or from past it: straight.
            let start = Point3::new(0.06, -0.25, 0.84);
            assert!(route(object, Obstacle::NoObstacle, start, goal).is_empty());
            let past = Point3::new(0.2, 0.08, 0.84);
            assert!(route(object, Obstacle::GoalWall, past, goal).is_empty());
            // At a point on the way, the rest of the way.
            let via = route(object, Obstacle::GoalWall, start, goal);
            let there = Point3::new(via[0].x - 0.01, via[0].y - 0.01, 0.84);
            assert_eq!(route(object, Obstacle::GoalWall, there, goal), via[1..]);
        }
    }

    #[test]
    fn the_fingers_start_behind_the_object_as_seen_from_the_goal() {
        let position = Point3::new(0.15, -0.25, 0.84);
        let goal = Point2::new(0.1, 0.13);
        let pushers = pushers(Object::Plate, position, goal);
        assert_eq!(pushers.len(), 2 * LEANS.len() * LEANS.len());
        for p in &pushers {
            // Behind: the object lies between the pads and the goal.
            let to_object = position.xy().coords - p.pad.xy();
            let to_goal = goal.coords - p.pad.xy();
            assert!(to_object.dot(&to_goal) > 0.0);
            assert!(to_object.norm() < to_goal.norm());
            // The plate's disc (0.06 m) reaches the fingers 2.4 cm either side of the line.
            let expected = (0.06f64.powi(2) - 0.024f64.powi(2)).sqrt() + 0.005;
            assert!((to_object.norm() - expected).abs() < 1e-9);
            // At the disc's height, pointing down or leaning the wrist away from the robot
            // and ahead along the push: the fingertips towards the robot and back.
            assert!((p.pad.z - (0.82 + 0.035)).abs() < 1e-9);
            let approach_axis = p.orientation * Vector3::z();
            let u = (goal - position.xy()).normalize().push(0.0);
            assert!(approach_axis.z < -0.5, "{approach_axis}");
            let across = u.cross(&Vector3::z());
            let sideways = approach_axis.dot(&across) * across;
            assert!(sideways.x <= 1e-9, "{approach_axis}");
            assert!(approach_axis.dot(&u) <= 1e-9, "{approach_axis}");
            // The fingers close across the push.
            let closing = p.orientation * Vector3::x();
            assert!(closing.xy().dot(&(goal - position.xy())).abs() < 1e-9);
        }
        // Upright first, each way round.
        assert!((pushers[0].orientation * Vector3::z() + Vector3::z()).norm() < 1e-9);
        let n = LEANS.len() * LEANS.len();
        assert!(pushers[0].orientation.angle_to(&pushers[n].orientation) > 3.0);
    }

    #[test]
    fn a_leg_steps_towards_the_goal_and_recentres_the_object() {
        let goal = Point2::new(0.1, 0.13);
        let position = Point3::new(0.1, -0.2, 0.872);
        let contact = contact_distance(0.045);
        // The object touches the fingers but sits 1 cm off their line (+x).
        let pad = Vector3::new(0.09, -0.2 - contact, 0.84);
        let Leg::To(target, u) = leg(Object::Dumbbell, position, goal, pad) else {
            panic!("not there yet");
        };
        assert!((u - Vector3::y()).norm() < 1e-9);
        assert!((target.x - 0.1).abs() < 1e-9, "recentred: {target}");
        assert!((target.y - (pad.y + NUDGE_STEP)).abs() < 1e-9);
        // Near the goal the leg is only as long as what is left; at it, none.
        let near = Point3::new(0.1, 0.11, 0.872);
        let pad = Vector3::new(0.1, 0.11 - contact, 0.84);
        let Leg::To(target, _) = leg(Object::Dumbbell, near, goal, pad) else {
            panic!("2 cm to go");
        };
        assert!((target.y - (pad.y + 0.02)).abs() < 1e-9);
        let at_goal = Point3::new(0.1, 0.125, 0.872);
        assert_eq!(leg(Object::Dumbbell, at_goal, goal, pad), Leg::Done);
        // Past the goal, or slid out from between the fingers: lost.
        let past = Point3::new(0.1, 0.2, 0.872);
        let pad = Vector3::new(0.1, 0.2 - contact, 0.84);
        assert_eq!(leg(Object::Dumbbell, past, goal, pad), Leg::Lost);
        let aside = Point3::new(0.13, -0.2, 0.872);
        let pad = Vector3::new(0.1, -0.2 - contact, 0.84);
        assert_eq!(leg(Object::Dumbbell, aside, goal, pad), Leg::Lost);
    }
}
