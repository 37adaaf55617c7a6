//! The robot axis: four 7-DoF arms, all with the same two-finger gripper.

use super::{Axis, AxisElement, ElementNames};

/// A robot arm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Robot {
    /// KUKA LBR iiwa 7 R800.
    Iiwa,
    /// Kinova Jaco (j2s7s300).
    Jaco,
    /// Kinova Gen3 (7-DoF); `Kinova3` in the reference.
    Gen3,
    /// Franka Emika Panda.
    Panda,
}

impl AxisElement for Robot {
    const AXIS: Axis = Axis::Robot;
    // One-hot order in the reference: IIWA, Jaco, Panda, Kinova3.
    // Sampling order: IIWA, Jaco, Kinova3, Panda.
    #[rustfmt::skip] // one row per element reads as a table
    const TABLE: &'static [ElementNames<Robot>] = &[
        ElementNames { element: Robot::Iiwa, wire: "IIWA", reference: "IIWA", aliases: &["kuka", "lbr_iiwa"], one_hot_index: 0, reference_order: 0 },
        ElementNames { element: Robot::Jaco, wire: "Jaco", reference: "Jaco", aliases: &["kinova_jaco"], one_hot_index: 1, reference_order: 1 },
        ElementNames { element: Robot::Gen3, wire: "Gen3", reference: "Kinova3", aliases: &["kinova_gen3"], one_hot_index: 3, reference_order: 2 },
        ElementNames { element: Robot::Panda, wire: "Panda", reference: "Panda", aliases: &["franka", "franka_panda"], one_hot_index: 2, reference_order: 3 },
    ];
}
