//! Shelf: put the object on the shelf board (docs/src/reference-facts.md §6, Shelf).
//!
//! As implemented: success needs only the object inside the shelf box (no gripper test); the
//! align and approach stages need the object in front of the shelf but no grasp.

use nalgebra::{Point3, Vector3};

use super::{
    REACH_GAIN, StageSpec, StagedReward, WorldSnapshot, closeness, reach_distance, strictly_between,
};
use crate::arena::{SHELF, objective_arena};
use crate::axes::Objective;

// Stage maxima (docs/src/reference-facts.md §6).
const REACH: f64 = 0.2;
const GRASP: f64 = 0.3;
const LIFT: f64 = 0.5;
const ALIGN: f64 = 0.8;
const APPROACH: f64 = 0.9;

#[rustfmt::skip] // one row per stage reads as a table
pub(super) const STAGES: [StageSpec; 5] = [
    StageSpec { name: "reach", max: REACH },
    StageSpec { name: "grasp", max: GRASP },
    StageSpec { name: "lift", max: LIFT },
    StageSpec { name: "align", max: ALIGN },
    StageSpec { name: "approach", max: APPROACH },
];

/// The in-shelf box reaches this fraction of the shelf's full depth (2 · y_size) in front of
/// the shelf body: 0.18 < y < 0.33 (docs/src/reference-facts.md §6).
const IN_SHELF_DEPTH_FRACTION: f64 = 0.75;
/// Lift target above bin 2's body: z = 1.05 (docs/src/reference-facts.md §6).
const LIFT_HEIGHT: f64 = 0.25;
/// Approach starts once align exceeds this (⇔ θ < 0.8047 rad) (docs/src/reference-facts.md §6).
const APPROACH_MIN_ALIGN: f64 = 0.6;
// Shaping gains (docs/src/reference-facts.md §6); align uses 1 − tanh(θ), gain 1.
const LIFT_GAIN: f64 = 5.0;
const ALIGN_GAIN: f64 = 1.0;
const APPROACH_GAIN: f64 = 5.0;

/// Within the shelf's width (strict).
fn within_width(p: &Point3<f64>) -> bool {
    let x = SHELF.position[0];
    strictly_between(p.x, x - SHELF.x_size, x + SHELF.x_size)
}

/// The board's top surface: z 0.945.
fn board_top() -> f64 {
    SHELF.z_offset + SHELF.position[2]
}

/// Inside the shelf: 0.18 < y < 0.33 and 0.945 < z < 1.095 (docs/src/reference-facts.md §6).
fn in_shelf(p: &Point3<f64>) -> bool {
    let y = SHELF.position[1];
    let depth = SHELF.y_size * 2.0 * IN_SHELF_DEPTH_FRACTION;
    within_width(p)
        && strictly_between(p.y, y - depth, y)
        && strictly_between(p.z, board_top(), board_top() + SHELF.z_height)
}

/// At the opening's height, any y: 0.995 < z < 1.095; the lower bound keeps the shelf's
/// thickness as a margin above the board (docs/src/reference-facts.md §6).
fn in_front(p: &Point3<f64>) -> bool {
    within_width(p)
        && strictly_between(
            p.z,
            board_top() + SHELF.thickness,
            board_top() + SHELF.z_height,
        )
}

/// Angle between the hand's z axis and world +y (rad). A zero vector counts as aligned, as
/// in the reference; the cosine is clamped so rounding cannot make it NaN.
fn angle_to_y(hand_z: &Vector3<f64>) -> f64 {
    let norm = hand_z.norm();
    if norm == 0.0 {
        return 0.0;
    }
    (hand_z.dot(&Vector3::y()) / norm).clamp(-1.0, 1.0).acos()
}

pub(super) fn staged_reward(s: &WorldSnapshot) -> StagedReward {
    let p = s.object_position;
    let success = in_shelf(&p);

    let reach = if success {
        0.0
    } else {
        REACH * closeness(REACH_GAIN, reach_distance(s))
    };
    let grasp = if s.grasping { GRASP } else { 0.0 };
    let lift = if s.grasping {
        let target = objective_arena(Objective::Shelf).bin2_position[2] + LIFT_HEIGHT;
        GRASP + closeness(LIFT_GAIN, (target - p.z).abs()) * (LIFT - GRASP)
    } else {
        0.0
    };
    let front = in_front(&p);
    let align = if front {
        LIFT + closeness(ALIGN_GAIN, angle_to_y(&s.hand_z_axis)) * (ALIGN - LIFT)
    } else {
        0.0
    };
    let approach = if front && align > APPROACH_MIN_ALIGN {
        // Push the object at least to half the shelf's depth: y ≥ 0.23.
        let y_target = SHELF.position[1] - SHELF.y_size;
        let shortfall = (y_target - p.y).max(0.0);
        ALIGN + closeness(APPROACH_GAIN, shortfall) * (APPROACH - ALIGN)
    } else {
        0.0
    };

    StagedReward::new(
        Objective::Shelf,
        &STAGES,
        [reach, grasp, lift, align, approach],
        success,
    )
}
