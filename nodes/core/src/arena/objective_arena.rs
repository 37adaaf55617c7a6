//! The objective table: which bins, which fixture, and where the goal marker goes, per
//! element of the objective axis (docs/src/reference-facts.md §2.1, §2.4–§2.6).

use super::bins::{
    BIN1_PARTS, BIN1_POSITION, BIN2_PARTS, BIN2_POSITION, PUSH_BIN1_PARTS, PUSH_BIN2_PARTS,
    PUSH_BIN2_POSITION,
};
use super::fixtures::{SHELF, SHELF_PARTS, TRASH_CAN, TRASH_CAN_PARTS};
use super::primitive::Part;
use crate::axes::Objective;

/// The static layout one objective adds to the common scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectiveArena {
    /// The element.
    pub objective: Objective,
    /// Bin 2's body position (m): y = 0.18, or 0.13 for Push (docs/src/reference-facts.md §2.1).
    pub bin2_position: [f64; 3],
    /// Bin 1's floor and rims, in its body frame (Push lacks the rim towards bin 2).
    pub bin1_parts: &'static [Part],
    /// Bin 2's floor and walls, in its body frame (Push lacks the wall towards bin 1).
    pub bin2_parts: &'static [Part],
    /// Body position of the objective's fixture (m); the origin when it has none.
    pub fixture_position: [f64; 3],
    /// The fixture's parts (trash can, shelf) in its body frame; none for PickPlace and Push.
    pub fixture_parts: &'static [Part],
    /// The goal marker sampler's reference point (m): bin 2, the shelf or the trash can
    /// (docs/src/reference-facts.md §2.4).
    pub goal_reference: [f64; 3],
    /// The marker's offset from `goal_reference` (m), before its own bottom offset is taken
    /// off z (docs/src/reference-facts.md §2.4).
    pub goal_offset: [f64; 3],
}

const PICK_PLACE: ObjectiveArena = ObjectiveArena {
    objective: Objective::PickPlace,
    bin2_position: BIN2_POSITION,
    bin1_parts: BIN1_PARTS,
    bin2_parts: BIN2_PARTS,
    fixture_position: [0.0; 3],
    fixture_parts: &[],
    // Centre of bin 2 at its body height (the reference's z offset is bin2.z − bin1.z = 0).
    goal_reference: BIN2_POSITION,
    goal_offset: [0.0, 0.0, BIN2_POSITION[2] - BIN1_POSITION[2]],
};

const PUSH: ObjectiveArena = ObjectiveArena {
    objective: Objective::Push,
    bin2_position: PUSH_BIN2_POSITION,
    bin1_parts: PUSH_BIN1_PARTS,
    bin2_parts: PUSH_BIN2_PARTS,
    fixture_position: [0.0; 3],
    fixture_parts: &[],
    goal_reference: PUSH_BIN2_POSITION,
    goal_offset: [0.0; 3],
};

const TRASH_CAN_ARENA: ObjectiveArena = ObjectiveArena {
    objective: Objective::TrashCan,
    bin2_position: BIN2_POSITION,
    bin1_parts: BIN1_PARTS,
    bin2_parts: BIN2_PARTS,
    fixture_position: TRASH_CAN.position,
    fixture_parts: TRASH_CAN_PARTS,
    // On the can's floor: z 0.825 + 0.005.
    goal_reference: TRASH_CAN.position,
    goal_offset: [0.0, 0.0, TRASH_CAN.z_offset],
};

const SHELF_ARENA: ObjectiveArena = ObjectiveArena {
    objective: Objective::Shelf,
    bin2_position: BIN2_POSITION,
    bin1_parts: BIN1_PARTS,
    bin2_parts: BIN2_PARTS,
    fixture_position: SHELF.position,
    fixture_parts: SHELF_PARTS,
    // Half-way into the shelf (y 0.33 − 0.1) on its board (z 0.8 + 0.145).
    goal_reference: SHELF.position,
    goal_offset: [0.0, -SHELF.y_size, SHELF.z_offset],
};

/// The row of an objective.
pub fn objective_arena(objective: Objective) -> &'static ObjectiveArena {
    match objective {
        Objective::PickPlace => &PICK_PLACE,
        Objective::Push => &PUSH,
        Objective::TrashCan => &TRASH_CAN_ARENA,
        Objective::Shelf => &SHELF_ARENA,
    }
}
