//! The four compositional axes. Every element is a row of its axis table: wire name (the
//! suite's spelling), the reference benchmark's spelling, accepted aliases, and the element's
//! positions in the reference's orderings (its observation one-hot and its task-sampling list,
//! which differ from each other and from the suite's order).

mod object;
mod objective;
mod obstacle;
mod robot;

use std::fmt;

pub use object::Object;
pub use objective::Objective;
pub use obstacle::Obstacle;
pub use robot::Robot;

/// Which axis an element belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// The arm.
    Robot,
    /// The object to manipulate.
    Object,
    /// The obstacle in the way (or none).
    Obstacle,
    /// What to do with the object.
    Objective,
}

impl Axis {
    /// Lower-case axis name, as used in messages and errors.
    pub fn name(self) -> &'static str {
        match self {
            Axis::Robot => "robot",
            Axis::Object => "object",
            Axis::Obstacle => "obstacle",
            Axis::Objective => "objective",
        }
    }
}

/// The naming and ordering data of one element (one row of an axis table).
#[derive(Debug, Clone, Copy)]
pub struct ElementNames<E> {
    /// The element.
    pub element: E,
    /// The suite's wire name (`IIWA`, `hollow_box`, `no_obstacle`, `pick_place`, ...).
    pub wire: &'static str,
    /// The reference benchmark's code name (`Kinova3`, `Hollowbox`, `None`, `PickPlace`, ...).
    pub reference: &'static str,
    /// Further accepted spellings (paper names and the like).
    pub aliases: &'static [&'static str],
    /// Position in the reference's observation one-hot for this axis.
    pub one_hot_index: usize,
    /// Position in the reference's task-sampling list for this axis (`AVAILABLE_*`).
    pub reference_order: usize,
}

/// An element of one of the four axes.
pub trait AxisElement: Copy + Eq + fmt::Debug + 'static {
    /// The axis.
    const AXIS: Axis;
    /// The table of all elements, in the suite's order (the order of the design table).
    const TABLE: &'static [ElementNames<Self>];

    /// This element's row.
    fn names(self) -> &'static ElementNames<Self> {
        Self::TABLE
            .iter()
            .find(|row| row.element == self)
            .expect("every element has a row")
    }

    /// The suite's wire name.
    fn wire_name(self) -> &'static str {
        self.names().wire
    }

    /// Index in the suite's order (0..4).
    fn index(self) -> usize {
        Self::TABLE
            .iter()
            .position(|row| row.element == self)
            .expect("every element has a row")
    }

    /// All elements in the suite's order.
    fn all() -> Vec<Self> {
        Self::TABLE.iter().map(|row| row.element).collect()
    }

    /// Parse any accepted spelling, case-insensitively, ignoring `_`, `-` and spaces.
    fn parse(name: &str) -> Result<Self, UnknownElement> {
        let wanted = normalise(name);
        Self::TABLE
            .iter()
            .find(|row| {
                std::iter::once(row.wire)
                    .chain(std::iter::once(row.reference))
                    .chain(row.aliases.iter().copied())
                    .any(|spelling| normalise(spelling) == wanted)
            })
            .map(|row| row.element)
            .ok_or_else(|| UnknownElement {
                axis: Self::AXIS,
                given: name.to_string(),
                valid: Self::TABLE.iter().map(|row| row.wire).collect(),
            })
    }
}

fn normalise(name: &str) -> String {
    name.chars()
        .filter(|c| !matches!(c, '_' | '-' | ' '))
        .flat_map(char::to_lowercase)
        .collect()
}

/// A name that is no element of its axis.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownElement {
    /// The axis that was asked.
    pub axis: Axis,
    /// What was given.
    pub given: String,
    /// The valid wire names.
    pub valid: Vec<&'static str>,
}

impl fmt::Display for UnknownElement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} {:?}; valid: {} (reference spellings such as Kinova3, PickPlace or ObjectWall \
             are accepted too, case-insensitively)",
            self.axis.name(),
            self.given,
            self.valid.join(", ")
        )
    }
}

impl std::error::Error for UnknownElement {}

#[cfg(test)]
mod test;
