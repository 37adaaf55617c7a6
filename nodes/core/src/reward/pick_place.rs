//! PickPlace: carry the object into bin 2 and keep the gripper near it
//! (docs/src/reference-facts.md §6, PickPlace).

use super::{
    REACH_GAIN, StageSpec, StagedReward, WorldSnapshot, closeness, reach_distance,
    strictly_between, xy_distance,
};
use nalgebra::Point3;

use crate::arena::{BIN2_FLOOR_HALF, objective_arena};
use crate::axes::Objective;

// Stage maxima (docs/src/reference-facts.md §6).
const REACH: f64 = 0.2;
const GRASP: f64 = 0.3;
const LIFT: f64 = 0.5;
const HOVER: f64 = 0.7;
const DROP: f64 = 0.9;

#[rustfmt::skip] // one row per stage reads as a table
pub(super) const STAGES: [StageSpec; 5] = [
    StageSpec { name: "reach", max: REACH },
    StageSpec { name: "grasp", max: GRASP },
    StageSpec { name: "lift", max: LIFT },
    StageSpec { name: "hover", max: HOVER },
    StageSpec { name: "drop", max: DROP },
];

/// "In the bin" means below bin-2 body z + 0.1, the top of its walls
/// (docs/src/reference-facts.md §6: 0.8 < z < 0.9); the drop stage's height target is the same
/// level.
const IN_BIN_HEIGHT: f64 = 0.1;
/// Lift target above bin 2's body: z = 1.05 (docs/src/reference-facts.md §6).
const LIFT_HEIGHT: f64 = 0.25;
/// Success also needs 1 − tanh(10·d_reach) > 0.35, i.e. d_reach < 0.0775 m
/// (docs/src/reference-facts.md §6).
const SUCCESS_MIN_CLOSENESS: f64 = 0.35;
/// Hover starts once lift exceeds this (⇔ |1.05 − z| < 0.0511 while grasped)
/// (docs/src/reference-facts.md §6).
const HOVER_MIN_LIFT: f64 = 0.45;
// Shaping gains (docs/src/reference-facts.md §6).
const LIFT_GAIN: f64 = 5.0;
const HOVER_GAIN: f64 = 2.0;
const DROP_GAIN: f64 = 5.0;

/// Whether an object whose origin is at `p` is in bin 2 as PickPlace counts it: inside its
/// floor's footprint and below its walls' tops (strictly).
pub(crate) fn in_bin2(p: &Point3<f64>) -> bool {
    let bin = objective_arena(Objective::PickPlace).bin2_position;
    let [half_x, half_y, _] = BIN2_FLOOR_HALF;
    strictly_between(p.x, bin[0] - half_x, bin[0] + half_x)
        && strictly_between(p.y, bin[1] - half_y, bin[1] + half_y)
        && strictly_between(p.z, bin[2], bin[2] + IN_BIN_HEIGHT)
}

pub(super) fn staged_reward(s: &WorldSnapshot) -> StagedReward {
    let bin = objective_arena(Objective::PickPlace).bin2_position;
    let [half_x, half_y, _] = BIN2_FLOOR_HALF;
    let p = s.object_position;

    let in_bin = in_bin2(&p);
    let d_reach = reach_distance(s);
    // The reference's "object in bin" flag includes the gripper-near test and gates stages.
    let success = in_bin && closeness(REACH_GAIN, d_reach) > SUCCESS_MIN_CLOSENESS;

    let reach = if success {
        0.0
    } else {
        REACH * closeness(REACH_GAIN, d_reach)
    };
    let grasp = if s.grasping { GRASP } else { 0.0 };
    let lift = if !success && s.grasping {
        let dz = (bin[2] + LIFT_HEIGHT - p.z).abs();
        GRASP + closeness(LIFT_GAIN, dz) * (LIFT - GRASP)
    } else {
        0.0
    };
    // Above bin 2 in xy, at any height.
    let above_bin = (p.x - bin[0]).abs() < half_x && (p.y - bin[1]).abs() < half_y;
    let hover = if !success && lift > HOVER_MIN_LIFT {
        // Outside the bin's footprint the hover term builds on lift; above it, on lift's max.
        let base = if above_bin { LIFT } else { lift };
        base + closeness(HOVER_GAIN, xy_distance(&p, bin[0], bin[1])) * (HOVER - LIFT)
    } else {
        0.0
    };
    // Not gated on success: only on the grasp and being above the bin.
    let drop = if s.grasping && above_bin {
        let excess = (p.z - (bin[2] + IN_BIN_HEIGHT)).max(0.0);
        HOVER + closeness(DROP_GAIN, excess) * (DROP - HOVER)
    } else {
        0.0
    };

    StagedReward::new(
        Objective::PickPlace,
        &STAGES,
        [reach, grasp, lift, hover, drop],
        success,
    )
}
