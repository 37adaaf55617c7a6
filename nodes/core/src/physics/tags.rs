//! What each collider is, encoded in its `user_data`, so contact classification (finger pad
//! on object, arm on wall) is an integer decode rather than a name lookup.

/// The role of a collider in the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ColliderTag {
    /// Part of the arm (or its mount); the index is the body index in the robot model.
    Arm(u32),
    /// The gripper base.
    GripperBase,
    /// Any part of a finger other than its pad (blade, knuckle, tip).
    Finger(Side),
    /// A finger pad.
    Pad(Side),
    /// Part of the manipulated object.
    Object,
    /// A static part of the arena (bins, obstacles, trash can, shelf); index into its parts list.
    Arena(u32),
    /// The ground plane.
    Ground,
}

/// Left or right finger.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    /// +y in the gripper frame.
    Left,
    /// −y in the gripper frame.
    Right,
}

impl ColliderTag {
    /// Encode for `Collider::user_data` (kind in the high 32 bits, index in the low 32).
    pub fn encode(self) -> u128 {
        let (kind, index): (u128, u32) = match self {
            ColliderTag::Arm(i) => (1, i),
            ColliderTag::GripperBase => (2, 0),
            ColliderTag::Finger(Side::Left) => (3, 0),
            ColliderTag::Finger(Side::Right) => (3, 1),
            ColliderTag::Pad(Side::Left) => (4, 0),
            ColliderTag::Pad(Side::Right) => (4, 1),
            ColliderTag::Object => (5, 0),
            ColliderTag::Arena(i) => (6, i),
            ColliderTag::Ground => (7, 0),
        };
        (kind << 32) | index as u128
    }

    /// Decode a `user_data` value; `None` for colliders this crate did not create.
    pub fn decode(data: u128) -> Option<ColliderTag> {
        let index = (data & 0xffff_ffff) as u32;
        let side = if index == 0 { Side::Left } else { Side::Right };
        Some(match data >> 32 {
            1 => ColliderTag::Arm(index),
            2 => ColliderTag::GripperBase,
            3 => ColliderTag::Finger(side),
            4 => ColliderTag::Pad(side),
            5 => ColliderTag::Object,
            6 => ColliderTag::Arena(index),
            7 => ColliderTag::Ground,
            _ => return None,
        })
    }

    /// Whether this collider belongs to the given finger (pad or not).
    pub fn is_finger(self, side: Side) -> bool {
        matches!(self, ColliderTag::Finger(s) | ColliderTag::Pad(s) if s == side)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_round_trip() {
        let all = [
            ColliderTag::Arm(0),
            ColliderTag::Arm(9),
            ColliderTag::GripperBase,
            ColliderTag::Finger(Side::Left),
            ColliderTag::Finger(Side::Right),
            ColliderTag::Pad(Side::Left),
            ColliderTag::Pad(Side::Right),
            ColliderTag::Object,
            ColliderTag::Arena(41),
            ColliderTag::Ground,
        ];
        for tag in all {
            assert_eq!(ColliderTag::decode(tag.encode()), Some(tag));
        }
        assert_eq!(ColliderTag::decode(0), None);
    }
}
