//! Push: bring the object to the goal marker in bin 2 without lifting it
//! (docs/src/reference-facts.md §6, Push).
//!
//! As implemented, unlike the paper: success also needs the object low (z ≤ 0.9), and the
//! approach stage uses the 3-D distance to the marker, whose z is 2 cm below a resting object
//! — so it never reaches its maximum — and requires a grasp.

use super::{
    REACH_GAIN, StageSpec, StagedReward, Termination, WorldSnapshot, closeness, reach_distance,
};
use crate::arena::{goal_position, objective_arena};
use crate::axes::{Object, Objective};

// Stage maxima (docs/src/reference-facts.md §6).
const REACH: f64 = 0.2;
const GRASP: f64 = 0.3;
const APPROACH: f64 = 0.7;

#[rustfmt::skip] // one row per stage reads as a table
pub(super) const STAGES: [StageSpec; 3] = [
    StageSpec { name: "reach", max: REACH },
    StageSpec { name: "grasp", max: GRASP },
    StageSpec { name: "approach", max: APPROACH },
];

/// Success: the object's xy within 3 cm of the marker's, inclusive
/// (docs/src/reference-facts.md §6).
const SUCCESS_XY_RADIUS: f64 = 0.03;
/// Both success (≤) and termination (>) compare the object's height above bin 2's body, the
/// "table height" 0.8, with 10 cm (docs/src/reference-facts.md §1, §6).
const MAX_HEIGHT_ABOVE_TABLE: f64 = 0.1;
/// Approach shaping gain (docs/src/reference-facts.md §6).
const APPROACH_GAIN: f64 = 5.0;

/// The table height the reference measures lifting from: bin 2's body z.
fn table_height() -> f64 {
    objective_arena(Objective::Push).bin2_position[2]
}

pub(super) fn staged_reward(object: Object, s: &WorldSnapshot) -> StagedReward {
    let goal = goal_position(Objective::Push, object);
    let p = s.object_position;

    let xy_error = (goal.xy() - p.xy()).norm();
    let success = xy_error <= SUCCESS_XY_RADIUS && p.z <= table_height() + MAX_HEIGHT_ABOVE_TABLE;

    // No stage is gated on success here.
    let reach = REACH * closeness(REACH_GAIN, reach_distance(s));
    let grasp = if s.grasping { GRASP } else { 0.0 };
    let approach = if s.grasping {
        let distance = nalgebra::distance(&goal, &p);
        GRASP + closeness(APPROACH_GAIN, distance) * (APPROACH - GRASP)
    } else {
        0.0
    };

    StagedReward::new(Objective::Push, &STAGES, [reach, grasp, approach], success)
}

pub(super) fn termination(s: &WorldSnapshot) -> Option<Termination> {
    (s.object_position.z - table_height() > MAX_HEIGHT_ABOVE_TABLE)
        .then_some(Termination::ObjectLifted)
}
