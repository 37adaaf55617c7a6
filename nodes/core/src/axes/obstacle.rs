//! The obstacle axis. "No obstacle" is an element like the others.

use super::{Axis, AxisElement, ElementNames};

/// An obstacle between the robot and the object or the goal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Obstacle {
    /// Nothing in the way.
    NoObstacle,
    /// A 25 cm wall across bin 1, between the robot and the object.
    ObjectWall,
    /// The same wall with an 18 cm wide opening.
    ObjectDoor,
    /// A 28 cm wall between the two bins on the robot's side.
    GoalWall,
}

impl AxisElement for Obstacle {
    const AXIS: Axis = Axis::Obstacle;
    // One-hot order in the reference: None, ObjectWall, ObjectDoor, GoalWall.
    // Sampling order: None, GoalWall, ObjectDoor, ObjectWall.
    #[rustfmt::skip] // one row per element reads as a table
    const TABLE: &'static [ElementNames<Obstacle>] = &[
        ElementNames { element: Obstacle::NoObstacle, wire: "no_obstacle", reference: "None", aliases: &["none"], one_hot_index: 0, reference_order: 0 },
        ElementNames { element: Obstacle::ObjectWall, wire: "object_wall", reference: "ObjectWall", aliases: &[], one_hot_index: 1, reference_order: 3 },
        ElementNames { element: Obstacle::ObjectDoor, wire: "object_door", reference: "ObjectDoor", aliases: &[], one_hot_index: 2, reference_order: 2 },
        ElementNames { element: Obstacle::GoalWall, wire: "goal_wall", reference: "GoalWall", aliases: &[], one_hot_index: 3, reference_order: 1 },
    ];
}
