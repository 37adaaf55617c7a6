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

impl Robot {
    /// The joint positions every episode starts from (rad): robosuite's defaults, which the
    /// reference uses unchanged and without noise (docs/src/reference-facts.md §4.1).
    pub fn init_qpos(self) -> [f64; 7] {
        use std::f64::consts::PI;
        match self {
            Robot::Iiwa => [0.0, 0.65, 0.0, -1.89, 0.0, 0.6, 0.0],
            // 3.142 is robosuite's literal, not π.
            #[allow(clippy::approx_constant)]
            Robot::Jaco => [3.192, 3.680, 0.0, 1.170, 0.050, 3.760, 3.142],
            Robot::Gen3 => [0.0, 0.65, 0.0, 1.89, 0.0, 0.6, -PI / 2.0],
            Robot::Panda => [
                0.0,
                PI / 16.0,
                0.0,
                -5.0 * PI / 6.0,
                0.0,
                PI - 0.2,
                PI / 4.0,
            ],
        }
    }
}
