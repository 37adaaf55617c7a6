//! The staged rewards against the reference's subtask code (`composuite/tasks/*_subtask.py`,
//! see `docs/src/reference-sources.md`): every threshold from
//! both sides, every gate, the maxima, and random snapshots for the invariants.

use nalgebra::{Point3, Vector3};

use super::*;
use crate::arena::goal_position;
use crate::axes::AxisElement;

/// A step small against every threshold, large against rounding near it.
const NUDGE: f64 = 1e-9;
const EPS: f64 = 1e-12;

/// Object at `object`, grip site at `grip`, hand pointing down, no grasp, gripper held.
fn snap(object: [f64; 3], grip: [f64; 3]) -> WorldSnapshot {
    WorldSnapshot {
        object_position: Point3::from(object),
        grip_site_position: Point3::from(grip),
        hand_z_axis: -Vector3::z(),
        grasping: false,
        last_gripper_action: 0.0,
    }
}

/// The gripper on the object (d_reach = 0).
fn held(object: [f64; 3]) -> WorldSnapshot {
    WorldSnapshot {
        grasping: true,
        ..snap(object, object)
    }
}

/// A grip site far from everything: the robot base.
const FAR: [f64; 3] = [-0.5, -0.1, 0.912];

fn value(reward: &StagedReward, name: &str) -> f64 {
    reward
        .stage(name)
        .unwrap_or_else(|| panic!("no stage {name:?}"))
        .value
}

fn reward(objective: Objective, s: &WorldSnapshot) -> StagedReward {
    staged_reward(objective, Object::Box, s)
}

#[track_caller]
fn assert_close(got: f64, want: f64) {
    assert!((got - want).abs() <= EPS, "got {got}, want {want}");
}

fn tanh_closeness(gain: f64, d: f64) -> f64 {
    1.0 - (gain * d).tanh()
}

// ---------------------------------------------------------------- shared

/// docs/src/reference-facts.md §6 and the StagedReward message: names and maxima per objective, all
/// below 1.
#[test]
fn stage_names_and_maxima() {
    let expected: [(Objective, &[(&str, f64)]); 4] = [
        (
            Objective::PickPlace,
            &[
                ("reach", 0.2),
                ("grasp", 0.3),
                ("lift", 0.5),
                ("hover", 0.7),
                ("drop", 0.9),
            ],
        ),
        (
            Objective::Push,
            &[("reach", 0.2), ("grasp", 0.3), ("approach", 0.7)],
        ),
        (
            Objective::TrashCan,
            &[
                ("reach", 0.2),
                ("grasp", 0.3),
                ("lift", 0.5),
                ("hover", 0.7),
                ("drop", 0.95),
            ],
        ),
        (
            Objective::Shelf,
            &[
                ("reach", 0.2),
                ("grasp", 0.3),
                ("lift", 0.5),
                ("align", 0.8),
                ("approach", 0.9),
            ],
        ),
    ];
    for (objective, stages) in expected {
        let specs: Vec<(&str, f64)> = stage_specs(objective)
            .iter()
            .map(|s| (s.name, s.max))
            .collect();
        assert_eq!(specs, stages, "{objective:?}");
        let r = reward(objective, &snap(FAR, FAR));
        assert_eq!(r.objective, objective);
        let names: Vec<&str> = r.stages.iter().map(|s| s.name).collect();
        assert_eq!(names, stages.iter().map(|s| s.0).collect::<Vec<_>>());
        assert!(stages.iter().all(|s| s.1 < 1.0));
    }
}

#[test]
fn current_stage_is_the_latest_maximum() {
    let specs = &pick_place::STAGES;
    let at = |values| StagedReward::new(Objective::PickPlace, specs, values, false);
    assert_eq!(at([0.0; 5]).current_stage(), None);
    assert_eq!(at([0.1, 0.0, 0.0, 0.0, 0.0]).current_stage(), Some(0));
    assert_eq!(at([0.2, 0.3, 0.3, 0.0, 0.0]).current_stage(), Some(2));
    assert_eq!(at([0.2, 0.3, 0.45, 0.6, 0.0]).current_stage(), Some(3));
    let r = at([0.2, 0.3, 0.45, 0.6, 0.0]);
    assert_eq!(r.total, 0.6);
    // On success the total is 1 whatever the stages say.
    let won = StagedReward::new(Objective::PickPlace, specs, [0.0; 5], true);
    assert_eq!((won.total, won.current_stage()), (1.0, None));
}

/// docs/src/reference-facts.md §1: only Push ends early, on the object rising more than 10 cm above
/// the table (z − 0.8 > 0.1); a resting box (0.85) ends the episode 5 cm up, a dumbbell 2.8 cm up.
#[test]
fn only_push_terminates_on_lifting() {
    let at = |z: f64| snap([0.1, 0.0, z], FAR);
    assert_eq!(termination(Objective::Push, &at(0.85)), None);
    assert_eq!(termination(Objective::Push, &at(0.9)), None);
    assert_eq!(
        termination(Objective::Push, &at(0.9 + NUDGE)),
        Some(Termination::ObjectLifted)
    );
    assert_eq!(
        termination(Objective::Push, &at(0.85 + 0.05 + NUDGE)),
        Some(Termination::ObjectLifted)
    );
    assert_eq!(
        termination(Objective::Push, &at(0.872 + 0.028 + NUDGE)),
        Some(Termination::ObjectLifted)
    );
    for objective in [Objective::PickPlace, Objective::TrashCan, Objective::Shelf] {
        assert_eq!(termination(objective, &at(2.0)), None);
    }
    assert_eq!(Termination::ObjectLifted.reason(), "object lifted");
}

// ---------------------------------------------------------------- PickPlace

/// docs/src/reference-facts.md §6: success = object in bin 2 and 1 − tanh(10·d_reach) > 0.35,
/// i.e. d < 0.0775.
#[test]
fn pick_place_success_needs_the_gripper_near() {
    let object = [0.1, 0.18, 0.85];
    let threshold = 0.65f64.atanh() / 10.0;
    assert!(threshold > 0.0775 && threshold < 0.0776, "{threshold}");
    let with_gap = |d: f64| reward(Objective::PickPlace, &snap(object, [0.1, 0.18, 0.85 + d]));
    for d in [0.0, 0.05, 0.0775, threshold - NUDGE] {
        let r = with_gap(d);
        assert!(r.success && r.total == 1.0, "d = {d}");
        assert_eq!(value(&r, "reach"), 0.0, "reach is gated off on success");
    }
    for d in [threshold + NUDGE, 0.0776, 0.2] {
        let r = with_gap(d);
        assert!(!r.success && r.total < 1.0, "d = {d}");
        assert_close(value(&r, "reach"), 0.2 * tanh_closeness(10.0, d));
    }
}

/// docs/src/reference-facts.md §6: in_bin is |x − 0.1| < 0.2, |y − 0.18| < 0.175, 0.8 < z < 0.9,
/// all strict.
#[test]
fn pick_place_in_bin_is_strict() {
    let success_at = |p: [f64; 3]| reward(Objective::PickPlace, &snap(p, p)).success;
    let centre = [0.1, 0.18, 0.85];
    let with = |axis: usize, v: f64| {
        let mut p = centre;
        p[axis] = v;
        p
    };
    assert!(success_at(centre));
    for (axis, low, high) in [(0, -0.1, 0.3), (1, 0.005, 0.355), (2, 0.8, 0.9)] {
        assert!(
            success_at(with(axis, low + NUDGE)),
            "axis {axis} just above {low}"
        );
        assert!(
            !success_at(with(axis, low - NUDGE)),
            "axis {axis} just below {low}"
        );
        assert!(
            success_at(with(axis, high - NUDGE)),
            "axis {axis} just below {high}"
        );
        assert!(
            !success_at(with(axis, high + NUDGE)),
            "axis {axis} just above {high}"
        );
    }
    // Bounds that are exact in floating point: on the boundary is outside.
    for p in [with(0, -0.1), with(1, 0.355), with(2, 0.8), with(2, 0.9)] {
        assert!(!success_at(p), "{p:?} is on the boundary");
    }
}

/// docs/src/reference-facts.md §6: lift only while grasping and not in bin, target z 1.05; hover
/// once lift > 0.45 (|1.05 − z| < 0.0511), building on lift outside the bin's footprint and on 0.5
/// above it.
#[test]
fn pick_place_lift_and_hover() {
    let outside = |z: f64| held([0.1, -0.26, z]);
    let r = reward(Objective::PickPlace, &outside(1.05));
    assert_close(value(&r, "grasp"), 0.3);
    assert_close(value(&r, "lift"), 0.5);
    let d_xy = 0.18 + 0.26;
    assert_close(value(&r, "hover"), 0.5 + 0.2 * tanh_closeness(2.0, d_xy));
    assert_eq!(value(&r, "drop"), 0.0, "not above the bin");

    let not_held = WorldSnapshot {
        grasping: false,
        ..outside(1.05)
    };
    let r = reward(Objective::PickPlace, &not_held);
    assert_eq!(
        [value(&r, "grasp"), value(&r, "lift"), value(&r, "hover")],
        [0.0; 3]
    );

    let gate = 0.25f64.atanh() / 5.0;
    assert!(gate > 0.0510 && gate < 0.0511, "{gate}");
    for dz in [0.05, gate - NUDGE, -(gate - NUDGE)] {
        let r = reward(Objective::PickPlace, &outside(1.05 + dz));
        let lift = 0.3 + 0.2 * tanh_closeness(5.0, dz.abs());
        assert_close(value(&r, "lift"), lift);
        assert_close(value(&r, "hover"), lift + 0.2 * tanh_closeness(2.0, d_xy));
    }
    for dz in [gate + NUDGE, 0.052, -0.052] {
        let r = reward(Objective::PickPlace, &outside(1.05 + dz));
        assert!(value(&r, "lift") > 0.3);
        assert_eq!(value(&r, "hover"), 0.0, "dz = {dz}");
    }

    // Above bin 2 (any height), hover builds on lift's maximum: 0.7 at the bin's centre.
    let above = |x: f64, y: f64| reward(Objective::PickPlace, &held([x, y, 1.05 + 0.04]));
    assert_close(value(&above(0.1, 0.18), "hover"), 0.7);
    assert_close(
        value(&above(0.2, 0.28), "hover"),
        0.5 + 0.2 * tanh_closeness(2.0, 0.02f64.sqrt()),
    );
    // The footprint test is strict: |y − 0.18| < 0.175.
    let edge = 0.18 + 0.175;
    let inside = above(0.1, edge - NUDGE);
    let outside_edge = above(0.1, edge + NUDGE);
    let lift = value(&inside, "lift");
    assert_close(
        value(&inside, "hover"),
        0.5 + 0.2 * tanh_closeness(2.0, 0.175 - NUDGE),
    );
    assert_close(
        value(&outside_edge, "hover"),
        lift + 0.2 * tanh_closeness(2.0, 0.175 + NUDGE),
    );
}

/// docs/src/reference-facts.md §6: drop while grasping above the bin, not gated on in-bin: 0.9 at
/// or below z 0.9.
#[test]
fn pick_place_drop() {
    // In the bin's volume but with the gripper 10 cm away: no success, drop at its maximum.
    let s = WorldSnapshot {
        grasping: true,
        ..snap([0.1, 0.18, 0.85], [0.1, 0.18, 0.95])
    };
    let r = reward(Objective::PickPlace, &s);
    assert!(!r.success);
    assert_close(value(&r, "drop"), 0.9);
    assert_close(r.total, 0.9);
    assert_eq!(r.current_stage(), Some(4));
    for z in [0.9, 0.8] {
        assert_close(
            value(&reward(Objective::PickPlace, &held([0.1, 0.18, z])), "drop"),
            0.9,
        );
    }
    let high = reward(Objective::PickPlace, &held([0.1, 0.18, 1.0]));
    assert_close(value(&high, "drop"), 0.7 + 0.2 * tanh_closeness(5.0, 0.1));
    let released = reward(
        Objective::PickPlace,
        &snap([0.1, 0.18, 1.0], [0.1, 0.18, 1.0]),
    );
    assert_eq!(value(&released, "drop"), 0.0);
    let beside = reward(Objective::PickPlace, &held([0.1, -0.1, 0.85]));
    assert_eq!(value(&beside, "drop"), 0.0);
}

// ---------------------------------------------------------------- Push

/// docs/src/reference-facts.md §6: success = xy within 0.03 of the marker (inclusive) and
/// z ≤ 0.9 (inclusive).
#[test]
fn push_success() {
    for object in Object::all() {
        let goal = goal_position(Objective::Push, object);
        let at = |dx: f64, dy: f64, z: f64| {
            staged_reward(
                Objective::Push,
                object,
                &snap([goal.x + dx, goal.y + dy, z], FAR),
            )
        };
        let rest = 0.85;
        assert!(at(0.0, 0.0, rest).success);
        assert!(at(0.03 - NUDGE, 0.0, rest).success);
        assert!(at(0.0, -(0.03 - NUDGE), rest).success);
        assert!(at(0.021, 0.021, rest).success);
        // 0.13 − 0.1 is exactly 0.03 in floating point: the bound itself counts.
        assert!(at(0.03, 0.0, rest).success, "exactly 3 cm away");
        assert!(!at(0.03 + NUDGE, 0.0, rest).success);
        assert!(!at(0.022, 0.022, rest).success);
        assert!(at(0.0, 0.0, 0.9).success, "z = 0.9 is still low enough");
        assert!(!at(0.0, 0.0, 0.9 + NUDGE).success);
        assert_eq!(at(0.0, 0.0, rest).total, 1.0);
    }
    assert_eq!(
        goal_position(Objective::Push, Object::Box).xy(),
        nalgebra::Point2::new(0.1, 0.13)
    );
}

/// docs/src/reference-facts.md §6: reach is never gated; grasp 0.3; approach only while grasping,
/// on the 3-D distance to the marker (2 cm below a resting object, so it stays below 0.7 there).
#[test]
fn push_stages() {
    let goal = goal_position(Objective::Push, Object::Box);
    let on_goal = [goal.x, goal.y, goal.z + 0.02]; // a box resting at the goal, z 0.85
    let r = reward(Objective::Push, &snap(on_goal, on_goal));
    assert!(r.success);
    assert_close(value(&r, "reach"), 0.2);
    assert_eq!(value(&r, "approach"), 0.0, "no grasp, no approach");

    let r = reward(Objective::Push, &held(on_goal));
    assert_close(value(&r, "grasp"), 0.3);
    assert_close(value(&r, "approach"), 0.3 + 0.4 * tanh_closeness(5.0, 0.02));
    assert!(value(&r, "approach") < 0.7);

    let r = reward(Objective::Push, &held([goal.x, goal.y, goal.z]));
    assert_close(value(&r, "approach"), 0.7);

    // Far from the goal: the 3-D distance, not the xy one.
    let start = [0.1, -0.26, 0.85];
    let r = reward(Objective::Push, &held(start));
    let d = nalgebra::distance(&goal, &Point3::from(start));
    assert_close(value(&r, "approach"), 0.3 + 0.4 * tanh_closeness(5.0, d));
    assert!(!r.success);
    assert_eq!(r.total, value(&r, "approach"));

    // Pushing without a grasp only ever earns reach (≤ 0.2) until success.
    let pushing = reward(Objective::Push, &snap(start, [0.05, -0.26, 0.85]));
    assert_close(pushing.total, 0.2 * tanh_closeness(10.0, 0.05));
    assert_eq!(pushing.current_stage(), Some(0));
}

// ---------------------------------------------------------------- Trashcan

const CAN: [f64; 3] = [0.1, 0.18, 0.88];

/// docs/src/reference-facts.md §6: in_can is |x − 0.1| < 0.08, |y − 0.18| < 0.08, 0.83 < z < 0.93
/// (strict); success = object in the can and grip site not in it.
#[test]
fn trash_can_success() {
    let success_at = |p: [f64; 3]| reward(Objective::TrashCan, &snap(p, FAR)).success;
    let with = |axis: usize, v: f64| {
        let mut p = CAN;
        p[axis] = v;
        p
    };
    assert!(success_at(CAN));
    for (axis, low, high) in [(0, 0.02, 0.18), (1, 0.10, 0.26), (2, 0.83, 0.93)] {
        assert!(
            success_at(with(axis, low + NUDGE)),
            "axis {axis} above {low}"
        );
        assert!(
            !success_at(with(axis, low - NUDGE)),
            "axis {axis} below {low}"
        );
        assert!(
            success_at(with(axis, high - NUDGE)),
            "axis {axis} below {high}"
        );
        assert!(
            !success_at(with(axis, high + NUDGE)),
            "axis {axis} above {high}"
        );
    }
    assert!(!success_at(with(2, 0.83)), "on the floor top is outside");

    // The grip site just above the can's box: success. Inside it: failure, and every stage is
    // gated off, so the reward is 0.
    let above = reward(Objective::TrashCan, &snap(CAN, [0.1, 0.18, 0.93 + NUDGE]));
    assert!(above.success && above.total == 1.0);
    let inside = reward(
        Objective::TrashCan,
        &WorldSnapshot {
            grasping: true,
            last_gripper_action: -1.0,
            ..snap(CAN, [0.1, 0.18, 0.93 - NUDGE])
        },
    );
    assert!(!inside.success);
    assert!(inside.stages.iter().all(|s| s.value == 0.0));
    assert_eq!((inside.total, inside.current_stage()), (0.0, None));
}

/// docs/src/reference-facts.md §6: reach and grasp gated on the object not in the can; lift target
/// 1.11; hover gate lift > 0.45, building on 0.5 above the can and on lift elsewhere.
#[test]
fn trash_can_reach_grasp_lift_hover() {
    let r = reward(
        Objective::TrashCan,
        &snap([0.1, -0.26, 0.85], [0.1, -0.26, 0.95]),
    );
    assert_close(value(&r, "reach"), 0.2 * tanh_closeness(10.0, 0.1));
    let outside = |z: f64| held([0.1, -0.1, z]);
    let r = reward(Objective::TrashCan, &outside(1.11));
    assert_close(value(&r, "grasp"), 0.3);
    assert_close(value(&r, "lift"), 0.5);
    assert_close(value(&r, "hover"), 0.5 + 0.2 * tanh_closeness(2.0, 0.28));
    let gate = 0.25f64.atanh() / 5.0;
    let r = reward(Objective::TrashCan, &outside(1.11 - (gate - NUDGE)));
    assert!(value(&r, "hover") > 0.0);
    let r = reward(Objective::TrashCan, &outside(1.11 - (gate + NUDGE)));
    assert!(value(&r, "lift") > 0.3 && value(&r, "hover") == 0.0);

    let r = reward(Objective::TrashCan, &held([0.1, 0.18, 1.11]));
    assert_close(value(&r, "hover"), 0.7);
    let r = reward(Objective::TrashCan, &held([0.15, 0.18, 1.11]));
    assert_close(value(&r, "hover"), 0.5 + 0.2 * tanh_closeness(2.0, 0.05));

    // Grasped inside the can (gripper outside it: success): reach, grasp, lift all 0.
    let s = WorldSnapshot {
        grasping: true,
        ..snap(CAN, FAR)
    };
    let r = reward(Objective::TrashCan, &s);
    assert!(r.success);
    assert!(r.stages.iter().all(|s| s.value == 0.0));
}

/// docs/src/reference-facts.md §6 (a code-vs-paper difference): drop = 0.95 when the object is
/// above the can, not in it, and the last gripper action is an open command (< 0) — no grasp
/// needed.
#[test]
fn trash_can_drop_is_keyed_on_the_gripper_action() {
    let over = |x: f64, action: f64, grasping: bool| {
        let s = WorldSnapshot {
            grasping,
            last_gripper_action: action,
            ..snap([x, 0.18, 1.0], FAR)
        };
        reward(Objective::TrashCan, &s)
    };
    for action in [-1.0, -0.5, -NUDGE] {
        let r = over(0.1, action, false);
        assert_eq!(value(&r, "drop"), 0.95, "action {action}");
        assert_eq!(r.total, 0.95);
        assert_eq!(r.current_stage(), Some(4));
        assert_eq!(value(&over(0.1, action, true), "drop"), 0.95);
    }
    for action in [0.0, NUDGE, 1.0] {
        assert_eq!(
            value(&over(0.1, action, false), "drop"),
            0.0,
            "action {action}"
        );
    }
    // Only above the can's footprint (strict): |x − 0.1| < 0.08.
    assert_eq!(value(&over(0.18 - NUDGE, -1.0, false), "drop"), 0.95);
    assert_eq!(value(&over(0.18 + NUDGE, -1.0, false), "drop"), 0.0);
    // Not once the object is in the can.
    let s = WorldSnapshot {
        last_gripper_action: -1.0,
        ..snap(CAN, FAR)
    };
    assert_eq!(value(&reward(Objective::TrashCan, &s), "drop"), 0.0);
}

// ---------------------------------------------------------------- Shelf

/// docs/src/reference-facts.md §6: in_shelf = |x − 0.1| < 0.2, 0.18 < y < 0.33, 0.945 < z < 1.095
/// (strict), and it is the whole success test: the gripper may be anywhere.
#[test]
fn shelf_success() {
    let centre = [0.1, 0.25, 1.0];
    let success_at = |p: [f64; 3]| reward(Objective::Shelf, &snap(p, FAR)).success;
    let with = |axis: usize, v: f64| {
        let mut p = centre;
        p[axis] = v;
        p
    };
    let r = reward(Objective::Shelf, &snap(centre, FAR));
    assert!(r.success && r.total == 1.0);
    assert_eq!(value(&r, "reach"), 0.0, "reach is gated off in the shelf");
    for (axis, low, high) in [(0, -0.1, 0.3), (1, 0.18, 0.33), (2, 0.945, 1.095)] {
        assert!(
            success_at(with(axis, low + NUDGE)),
            "axis {axis} above {low}"
        );
        assert!(
            !success_at(with(axis, low - NUDGE)),
            "axis {axis} below {low}"
        );
        assert!(
            success_at(with(axis, high - NUDGE)),
            "axis {axis} below {high}"
        );
        assert!(
            !success_at(with(axis, high + NUDGE)),
            "axis {axis} above {high}"
        );
    }
    assert!(!success_at(with(1, 0.33)), "the shelf body's y is outside");
}

/// docs/src/reference-facts.md §6: align = 0.5 + 0.3·(1 − tanh θ) in front of the shelf (|x − 0.1|
/// < 0.2, 0.995 < z < 1.095, any y), with no grasp needed; θ between hand z and world +y.
#[test]
fn shelf_align() {
    let pointing = |axis: Vector3<f64>, p: [f64; 3]| {
        let s = WorldSnapshot {
            hand_z_axis: axis,
            ..snap(p, FAR)
        };
        reward(Objective::Shelf, &s)
    };
    let front = [0.1, -0.2, 1.05];
    assert_close(value(&pointing(Vector3::y(), front), "align"), 0.8);
    assert_close(
        value(&pointing(Vector3::z(), front), "align"),
        0.5 + 0.3 * tanh_closeness(1.0, std::f64::consts::FRAC_PI_2),
    );
    assert_close(
        value(&pointing(-Vector3::y(), front), "align"),
        0.5 + 0.3 * tanh_closeness(1.0, std::f64::consts::PI),
    );
    // Not normalised by the caller: only the direction counts; a zero axis counts as aligned.
    assert_close(value(&pointing(Vector3::y() * 3.0, front), "align"), 0.8);
    assert_close(value(&pointing(Vector3::zeros(), front), "align"), 0.8);

    let with = |axis: usize, v: f64| {
        let mut p = front;
        p[axis] = v;
        pointing(Vector3::y(), p)
    };
    for (axis, low, high) in [(0, -0.1, 0.3), (2, 0.995, 1.095)] {
        assert!(
            value(&with(axis, low + NUDGE), "align") > 0.0,
            "axis {axis} above {low}"
        );
        assert_eq!(
            value(&with(axis, low - NUDGE), "align"),
            0.0,
            "axis {axis} below {low}"
        );
        assert!(
            value(&with(axis, high - NUDGE), "align") > 0.0,
            "axis {axis} below {high}"
        );
        assert_eq!(
            value(&with(axis, high + NUDGE), "align"),
            0.0,
            "axis {axis} above {high}"
        );
    }
}

/// docs/src/reference-facts.md §6: approach once in front and align > 0.6 (θ < 0.8047 rad), rising
/// to 0.9 at y ≥ 0.23; lift target 1.05.
#[test]
fn shelf_approach_and_lift() {
    let threshold = (2.0f64 / 3.0).atanh();
    assert!(threshold > 0.8047 && threshold < 0.8048, "{threshold}");
    let tilted = |theta: f64, y: f64| {
        let s = WorldSnapshot {
            hand_z_axis: Vector3::new(0.0, theta.cos(), theta.sin()),
            ..snap([0.1, y, 1.05], FAR)
        };
        reward(Objective::Shelf, &s)
    };
    for theta in [0.0, 0.5, 0.804, threshold - 1e-6] {
        let r = tilted(theta, 0.23);
        assert!(value(&r, "align") > 0.6);
        assert_close(value(&r, "approach"), 0.9);
    }
    for theta in [threshold + 1e-6, 0.806, 1.5] {
        let r = tilted(theta, 0.23);
        assert!(value(&r, "align") > 0.5 && value(&r, "align") <= 0.6);
        assert_eq!(value(&r, "approach"), 0.0, "θ = {theta}");
    }
    let r = tilted(0.0, 0.13);
    assert_close(value(&r, "approach"), 0.8 + 0.1 * tanh_closeness(5.0, 0.1));
    assert_close(value(&tilted(0.0, 0.3), "approach"), 0.9);
    assert_eq!(r.total, value(&r, "approach"));

    let lifted = reward(Objective::Shelf, &held([0.1, -0.26, 1.05]));
    assert_close(value(&lifted, "lift"), 0.5);
    assert_close(value(&lifted, "grasp"), 0.3);
    let low = reward(Objective::Shelf, &held([0.1, -0.26, 0.85]));
    assert_close(value(&low, "lift"), 0.3 + 0.2 * tanh_closeness(5.0, 0.2));
    let dropped = reward(Objective::Shelf, &snap([0.1, -0.26, 1.05], FAR));
    assert_eq!(value(&dropped, "lift"), 0.0);
}

// ---------------------------------------------------------------- invariants

/// A 64-bit linear congruential generator (Knuth's MMIX constants): enough for spreading
/// test snapshots, with no dependency.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn between(&mut self, low: f64, high: f64) -> f64 {
        low + (high - low) * self.unit()
    }
}

/// Random snapshots around each objective's goal and across the workspace: every stage in
/// [0, its max], total = 1 on success else max(stages), total ∈ [0, 1], total == 1 ⇔
/// success, and the current stage holds the maximum.
#[test]
fn random_snapshots_keep_the_invariants() {
    let mut rng = Lcg(0x5eed);
    for objective in Objective::all() {
        let mut successes = 0;
        let mut shaped = 0;
        for i in 0..20_000 {
            let object = Object::all()[i % 4];
            let goal = goal_position(objective, object);
            let p = if rng.unit() < 0.5 {
                [
                    goal.x + rng.between(-0.12, 0.12),
                    goal.y + rng.between(-0.12, 0.12),
                    goal.z + rng.between(-0.05, 0.12),
                ]
            } else {
                [
                    rng.between(-0.2, 0.4),
                    rng.between(-0.55, 0.45),
                    rng.between(0.75, 1.25),
                ]
            };
            let grip = if rng.unit() < 0.5 {
                [
                    p[0] + rng.between(-0.06, 0.06),
                    p[1] + rng.between(-0.06, 0.06),
                    p[2] + rng.between(-0.06, 0.1),
                ]
            } else {
                [
                    rng.between(-0.2, 0.4),
                    rng.between(-0.55, 0.45),
                    rng.between(0.75, 1.25),
                ]
            };
            let axis = Vector3::new(
                rng.between(-1.0, 1.0),
                rng.between(-1.0, 1.0),
                rng.between(-1.0, 1.0),
            );
            let s = WorldSnapshot {
                object_position: Point3::from(p),
                grip_site_position: Point3::from(grip),
                hand_z_axis: axis.try_normalize(1e-6).unwrap_or_else(Vector3::y),
                grasping: rng.unit() < 0.5,
                last_gripper_action: rng.between(-1.0, 1.0),
            };
            let r = staged_reward(objective, object, &s);
            let best = r.stages.iter().map(|s| s.value).fold(0.0, f64::max);
            for stage in &r.stages {
                assert!(
                    stage.value >= 0.0 && stage.value <= stage.max,
                    "{objective:?} {stage:?} at {s:?}"
                );
            }
            assert!((0.0..=1.0).contains(&r.total));
            assert_eq!(r.total == 1.0, r.success, "{objective:?} at {s:?}");
            if r.success {
                successes += 1;
                assert_eq!(r.total, 1.0);
            } else {
                assert_eq!(r.total, best);
                if best > 0.0 {
                    shaped += 1;
                }
            }
            match r.current_stage() {
                Some(i) => {
                    assert_eq!(r.stages[i].value, best);
                    assert!(r.stages[i + 1..].iter().all(|s| s.value < best));
                }
                None => assert_eq!(best, 0.0),
            }
        }
        // The sample reaches both sides of the success test.
        assert!(
            successes > 20 && shaped > 1000,
            "{objective:?}: {successes} successes, {shaped} shaped"
        );
    }
}
