//! The fixed furniture beyond the bins: the trash can (Trashcan), the shelf (Shelf), the
//! robot's base and the ground. docs/src/reference-facts.md §2, §2.5–§2.7.

use super::bins::BIN2_POSITION;
use super::primitive::{Friction, Part, Primitive};

/// The trash can's code constants (docs/src/reference-facts.md §2.5). The reward's in-can box and
/// lift target are built from these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrashCanDims {
    /// Body position (m): on the bin-2 floor (top z 0.82), centred on bin 2.
    pub position: [f64; 3],
    /// Half-size of the floor in x and y (m); the can's inner box in the reward.
    pub half_size: f64,
    /// Floor half-thickness (m), the reference's `trashcan_z_offset`.
    pub z_offset: f64,
    /// Wall half-height (m), the reference's `trashcan_height`.
    pub height: f64,
}

/// The trash can (docs/src/reference-facts.md §2.5).
pub const TRASH_CAN: TrashCanDims = TrashCanDims {
    position: [0.1, 0.18, 0.825],
    half_size: 0.08,
    z_offset: 0.005,
    height: 0.08,
};

/// Local z of the four walls' centres (docs/src/reference-facts.md §2.5): walls span
/// z 0.8255…0.9855 in the world.
const TRASH_CAN_WALL_Z: f64 = 0.0805;

const fn can_part(name: &'static str, half: [f64; 3], offset: [f64; 3]) -> Part {
    Part::solid(
        name,
        Primitive::cuboid(half[0], half[1], half[2]),
        offset,
        Friction::TABLE,
    )
}

const CAN_H: f64 = TRASH_CAN.half_size;
// Walls are as thick as the floor (docs/src/reference-facts.md §2.5).
const CAN_T: f64 = TRASH_CAN.z_offset;

/// The trash can's floor and four walls, in its body frame (docs/src/reference-facts.md §2.5).
pub(crate) const TRASH_CAN_PARTS: &[Part] = &[
    can_part("trash_can/floor", [CAN_H, CAN_H, CAN_T], [0.0, 0.0, 0.0]),
    can_part(
        "trash_can/wall_y+",
        [CAN_H, CAN_T, TRASH_CAN.height],
        [0.0, CAN_H, TRASH_CAN_WALL_Z],
    ),
    can_part(
        "trash_can/wall_y-",
        [CAN_H, CAN_T, TRASH_CAN.height],
        [0.0, -CAN_H, TRASH_CAN_WALL_Z],
    ),
    can_part(
        "trash_can/wall_x+",
        [CAN_T, CAN_H, TRASH_CAN.height],
        [CAN_H, 0.0, TRASH_CAN_WALL_Z],
    ),
    can_part(
        "trash_can/wall_x-",
        [CAN_T, CAN_H, TRASH_CAN.height],
        [-CAN_H, 0.0, TRASH_CAN_WALL_Z],
    ),
];

/// The shelf's code constants (docs/src/reference-facts.md §2.6). The reward's in-shelf and
/// in-front boxes, the approach target and the goal marker are built from these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShelfDims {
    /// Body position (m): bin 2 + (0, y_size + thickness, 0) = (0.1, 0.33, 0.8).
    pub position: [f64; 3],
    /// Half-width along x (m), the reference's `shelf_x_size`.
    pub x_size: f64,
    /// Half-depth along y (m), the reference's `shelf_y_size`.
    pub y_size: f64,
    /// Top block half-height (m), `shelf_thickness`; the reward reuses it as a margin.
    pub thickness: f64,
    /// Height of the board's top surface above the body (m), `shelf_z_offset`.
    pub z_offset: f64,
    /// Height of the free opening's reward box above the board (m), `shelf_z_height`.
    pub z_height: f64,
}

const SHELF_Y_SIZE: f64 = 0.1;
const SHELF_THICKNESS: f64 = 0.05;

/// The shelf (docs/src/reference-facts.md §2.6), placed from bin 2's position as the reference
/// places it.
pub const SHELF: ShelfDims = ShelfDims {
    position: [
        BIN2_POSITION[0],
        BIN2_POSITION[1] + (SHELF_Y_SIZE + SHELF_THICKNESS),
        BIN2_POSITION[2],
    ],
    x_size: 0.2,
    y_size: SHELF_Y_SIZE,
    thickness: SHELF_THICKNESS,
    z_offset: 0.145,
    z_height: 0.15,
};

const fn shelf_part(name: &'static str, half: [f64; 3], offset: [f64; 3]) -> Part {
    Part::solid(
        name,
        Primitive::cuboid(half[0], half[1], half[2]),
        offset,
        Friction::TABLE,
    )
}

/// The shelf's three blocks, in its body frame (docs/src/reference-facts.md §2.6). It opens towards
/// −y (bin 1) and at both x ends; the free opening is z 0.945…1.10, y 0.14…0.32.
pub(crate) const SHELF_PARTS: &[Part] = &[
    // Back panel: x −0.1…0.3, y 0.32…0.34, z 0.80…1.10.
    shelf_part("shelf/back", [0.2, 0.01, 0.15], [0.0, 0.0, 0.15]),
    // Bottom block up to the board's top surface, z 0.80…0.945.
    shelf_part("shelf/bottom", [0.2, 0.1, 0.0725], [0.0, -0.09, 0.0725]),
    // Top block, z 1.10…1.20.
    shelf_part("shelf/top", [0.2, 0.1, 0.05], [0.0, -0.09, 0.35]),
];

/// World position of every arm's base body (docs/src/reference-facts.md §2.7): robosuite's "bins"
/// offset (−0.5, −0.1, 0) on the RethinkMount pedestal. Identity orientation, facing +x.
pub const ROBOT_BASE_POSITION: [f64; 3] = [-0.5, -0.1, 0.912];

/// Half-size in x and y (m) of the ground plane at z = 0 (docs/src/reference-facts.md §2). The
/// plane is not a primitive; physics adds it as a half-space.
pub const GROUND_HALF_SIZE: [f64; 2] = [3.0, 3.0];
