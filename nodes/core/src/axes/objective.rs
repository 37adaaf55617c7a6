//! The objective axis: what to do with the object.

use super::{Axis, AxisElement, ElementNames};

/// A task objective.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Objective {
    /// Carry the object to bin 2 and keep the gripper near it.
    PickPlace,
    /// Move the object to the goal in bin 2 without lifting it more than 10 cm.
    Push,
    /// Drop the object into the trash can and pull the gripper out.
    TrashCan,
    /// Put the object on the shelf.
    Shelf,
}

impl AxisElement for Objective {
    const AXIS: Axis = Axis::Objective;
    // One-hot and sampling order in the reference: PickPlace, Push, Shelf, Trashcan.
    #[rustfmt::skip] // one row per element reads as a table
    const TABLE: &'static [ElementNames<Objective>] = &[
        ElementNames { element: Objective::PickPlace, wire: "pick_place", reference: "PickPlace", aliases: &["pick-and-place", "pick_and_place"], one_hot_index: 0, reference_order: 0 },
        ElementNames { element: Objective::Push, wire: "push", reference: "Push", aliases: &[], one_hot_index: 1, reference_order: 1 },
        ElementNames { element: Objective::TrashCan, wire: "trash_can", reference: "Trashcan", aliases: &[], one_hot_index: 3, reference_order: 3 },
        ElementNames { element: Objective::Shelf, wire: "shelf", reference: "Shelf", aliases: &[], one_hot_index: 2, reference_order: 2 },
    ];
}
