//! Trashcan: drop the object into the can and take the gripper out
//! (docs/src/reference-facts.md §6, Trashcan).
//!
//! As implemented, unlike the paper: the drop stage is a constant keyed on the last gripper
//! *action* being an open command, with no grasp test; success also needs the grip site
//! outside the can. With both object and grip site in the can, every stage is gated off and
//! the reward is 0.

use nalgebra::Point3;

use super::{
    REACH_GAIN, StageSpec, StagedReward, WorldSnapshot, closeness, reach_distance,
    strictly_between, xy_distance,
};
use crate::arena::TRASH_CAN;
use crate::axes::Objective;

// Stage maxima (docs/src/reference-facts.md §6).
const REACH: f64 = 0.2;
const GRASP: f64 = 0.3;
const LIFT: f64 = 0.5;
const HOVER: f64 = 0.7;
const DROP: f64 = 0.95;

#[rustfmt::skip] // one row per stage reads as a table
pub(super) const STAGES: [StageSpec; 5] = [
    StageSpec { name: "reach", max: REACH },
    StageSpec { name: "grasp", max: GRASP },
    StageSpec { name: "lift", max: LIFT },
    StageSpec { name: "hover", max: HOVER },
    StageSpec { name: "drop", max: DROP },
];

/// Height of the in-can box above the can's floor top
/// (docs/src/reference-facts.md §6: 0.83 < z < 0.93).
const IN_CAN_HEIGHT: f64 = 0.1;
/// Lift target above the top of the can's walls: z = 0.825 + 0.005 + 0.08 + 0.2 = 1.11
/// (docs/src/reference-facts.md §6).
const LIFT_CLEARANCE: f64 = 0.2;
/// Hover starts once lift exceeds this (docs/src/reference-facts.md §6).
const HOVER_MIN_LIFT: f64 = 0.45;
// Shaping gains (docs/src/reference-facts.md §6).
const LIFT_GAIN: f64 = 5.0;
const HOVER_GAIN: f64 = 2.0;

/// Within the can's footprint, at any height (strict, docs/src/reference-facts.md §6).
fn above_can(p: &Point3<f64>) -> bool {
    let [x, y, _] = TRASH_CAN.position;
    let h = TRASH_CAN.half_size;
    strictly_between(p.x, x - h, x + h) && strictly_between(p.y, y - h, y + h)
}

/// Inside the can: above its footprint and between its floor top and 10 cm higher.
fn in_can(p: &Point3<f64>) -> bool {
    let floor_top = TRASH_CAN.z_offset + TRASH_CAN.position[2];
    above_can(p) && strictly_between(p.z, floor_top, floor_top + IN_CAN_HEIGHT)
}

pub(super) fn staged_reward(s: &WorldSnapshot) -> StagedReward {
    let p = s.object_position;
    let object_in_can = in_can(&p);
    let success = object_in_can && !in_can(&s.grip_site_position);

    let reach = if object_in_can {
        0.0
    } else {
        REACH * closeness(REACH_GAIN, reach_distance(s))
    };
    let grasp = if !object_in_can && s.grasping {
        GRASP
    } else {
        0.0
    };
    let lift = if grasp > 0.0 {
        let [_, _, can_z] = TRASH_CAN.position;
        let target = can_z + TRASH_CAN.z_offset + TRASH_CAN.height + LIFT_CLEARANCE;
        GRASP + closeness(LIFT_GAIN, (target - p.z).abs()) * (LIFT - GRASP)
    } else {
        0.0
    };
    let above = above_can(&p);
    let hover = if !object_in_can && lift > HOVER_MIN_LIFT {
        let [x, y, _] = TRASH_CAN.position;
        // Above the can the hover term builds on lift's max, elsewhere on lift.
        let base = if above { LIFT } else { lift };
        base + closeness(HOVER_GAIN, xy_distance(&p, x, y)) * (HOVER - LIFT)
    } else {
        0.0
    };
    // A constant for any open command over the can, grasped or not.
    let drop = if !object_in_can && above && s.last_gripper_action < 0.0 {
        DROP
    } else {
        0.0
    };

    StagedReward::new(
        Objective::TrashCan,
        &STAGES,
        [reach, grasp, lift, hover, drop],
        success,
    )
}
