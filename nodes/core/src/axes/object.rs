//! The object axis: four objects built from primitives.

use super::{Axis, AxisElement, ElementNames};

/// An object to manipulate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Object {
    /// A 4 × 4 × 6 cm box.
    Box,
    /// An open-top box, 7.6 cm square.
    HollowBox,
    /// A 12 cm disc on a stem.
    Plate,
    /// An upright dumbbell.
    Dumbbell,
}

impl AxisElement for Object {
    const AXIS: Axis = Axis::Object;
    // One-hot and sampling order in the reference: Box, Dumbbell, Plate, Hollowbox.
    #[rustfmt::skip] // one row per element reads as a table
    const TABLE: &'static [ElementNames<Object>] = &[
        ElementNames { element: Object::Box, wire: "box", reference: "Box", aliases: &[], one_hot_index: 0, reference_order: 0 },
        ElementNames { element: Object::HollowBox, wire: "hollow_box", reference: "Hollowbox", aliases: &[], one_hot_index: 3, reference_order: 3 },
        ElementNames { element: Object::Plate, wire: "plate", reference: "Plate", aliases: &[], one_hot_index: 2, reference_order: 2 },
        ElementNames { element: Object::Dumbbell, wire: "dumbbell", reference: "Dumbbell", aliases: &[], one_hot_index: 1, reference_order: 1 },
    ];
}
