//! The two bins: table-top boxes whose top is the work surface, with low rims (bin 1) or
//! walls (bin 2). docs/src/reference-facts.md §2.1. The bins' legs are visual-only and left out.

use super::primitive::{Friction, Part, Primitive};

/// Bin 1 (the object's start bin) body position, the same for every objective
/// (docs/src/reference-facts.md §2.1).
pub const BIN1_POSITION: [f64; 3] = [0.1, -0.26, 0.8];

/// Bin 1 floor half-size, the reference's `bin1_size` (docs/src/reference-facts.md §2.1):
/// 0.40 × 0.50 m.
pub const BIN1_FLOOR_HALF: [f64; 3] = [0.2, 0.25, 0.02];

/// Bin 2 (the goal-side bin) floor half-size, the reference's `bin2_size`
/// (docs/src/reference-facts.md §2.1): 0.40 × 0.35 m.
pub const BIN2_FLOOR_HALF: [f64; 3] = [0.2, 0.175, 0.02];

/// Bin 2 body position for PickPlace, Shelf and Trashcan (docs/src/reference-facts.md §2.1: the
/// arena XML's y = 0.18 wins over the PickPlace class default 0.13, and the reward uses it too).
pub(crate) const BIN2_POSITION: [f64; 3] = [0.1, 0.18, 0.8];

/// Bin 2 body position in the Push arena (docs/src/reference-facts.md §2.1): 5 cm closer, so the
/// two floors overlap and form one surface.
pub(crate) const PUSH_BIN2_POSITION: [f64; 3] = [0.1, 0.13, 0.8];

const fn bin_part(name: &'static str, half: [f64; 3], offset: [f64; 3]) -> Part {
    Part::solid(
        name,
        Primitive::cuboid(half[0], half[1], half[2]),
        offset,
        Friction::TABLE,
    )
}

// Bin 1: floor centred on the body, rims 2 cm high above it (half-height 0.01 at body
// z + 0.03 → z 0.82…0.84). docs/src/reference-facts.md §2.1.
const BIN1_FLOOR: Part = bin_part("bin1/floor", BIN1_FLOOR_HALF, [0.0, 0.0, 0.0]);
const BIN1_RIM_Y_NEG: Part = bin_part("bin1/rim_y-", [0.21, 0.01, 0.01], [0.0, -0.25, 0.03]);
/// The rim facing bin 2, absent in the Push arena.
const BIN1_RIM_Y_POS: Part = bin_part("bin1/rim_y+", [0.21, 0.01, 0.01], [0.0, 0.25, 0.03]);
const BIN1_RIM_X_NEG: Part = bin_part("bin1/rim_x-", [0.01, 0.25, 0.01], [-0.2, 0.0, 0.03]);
const BIN1_RIM_X_POS: Part = bin_part("bin1/rim_x+", [0.01, 0.25, 0.01], [0.2, 0.0, 0.03]);

// Bin 2: floor centred on the body, walls 10 cm tall above the body origin (half-height 0.05
// at body z + 0.05 → z 0.80…0.90). docs/src/reference-facts.md §2.1.
const BIN2_FLOOR: Part = bin_part("bin2/floor", BIN2_FLOOR_HALF, [0.0, 0.0, 0.0]);
const BIN2_WALL_Y_POS: Part = bin_part("bin2/wall_y+", [0.2, 0.01, 0.05], [0.0, 0.175, 0.05]);
/// The wall facing bin 1, absent in the Push arena.
const BIN2_WALL_Y_NEG: Part = bin_part("bin2/wall_y-", [0.21, 0.01, 0.05], [0.0, -0.175, 0.05]);
const BIN2_WALL_X_NEG: Part = bin_part("bin2/wall_x-", [0.01, 0.175, 0.05], [-0.2, 0.0, 0.05]);
const BIN2_WALL_X_POS: Part = bin_part("bin2/wall_x+", [0.01, 0.175, 0.05], [0.2, 0.0, 0.05]);

/// Bin 1 with all four rims (every arena but Push).
pub(crate) const BIN1_PARTS: &[Part] = &[
    BIN1_FLOOR,
    BIN1_RIM_Y_NEG,
    BIN1_RIM_Y_POS,
    BIN1_RIM_X_NEG,
    BIN1_RIM_X_POS,
];
/// Bin 1 in the Push arena: no rim towards bin 2 (docs/src/reference-facts.md §2.1).
pub(crate) const PUSH_BIN1_PARTS: &[Part] =
    &[BIN1_FLOOR, BIN1_RIM_Y_NEG, BIN1_RIM_X_NEG, BIN1_RIM_X_POS];

/// Bin 2 with all four walls (every arena but Push).
pub(crate) const BIN2_PARTS: &[Part] = &[
    BIN2_FLOOR,
    BIN2_WALL_Y_POS,
    BIN2_WALL_Y_NEG,
    BIN2_WALL_X_NEG,
    BIN2_WALL_X_POS,
];
/// Bin 2 in the Push arena: no wall towards bin 1 (docs/src/reference-facts.md §2.1).
pub(crate) const PUSH_BIN2_PARTS: &[Part] = &[
    BIN2_FLOOR,
    BIN2_WALL_Y_POS,
    BIN2_WALL_X_NEG,
    BIN2_WALL_X_POS,
];
