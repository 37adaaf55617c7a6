//! The object table: each object's primitives, mass and sampler sites
//! (docs/src/reference-facts.md §3), and the goal marker's visual copy of it
//! (docs/src/reference-facts.md §2.4).

use super::bins::{BIN1_FLOOR_HALF, BIN1_POSITION};
use super::primitive::{Friction, Part, Primitive};
use crate::axes::Object;

/// Density of every object geom without an explicit mass: MuJoCo's default
/// (docs/src/reference-facts.md §3).
pub const OBJECT_DENSITY: f64 = 1000.0;

/// Mass of each non-colliding "material" copy of a collision geom (docs/src/reference-facts.md §3).
pub const MATERIAL_COPY_MASS: f64 = 0.001;

/// The start sampler's z offset above bin 1's body (docs/src/reference-facts.md §2.2): 0.02, the
/// floor's half-thickness, so the object's bottom lands on the floor's top.
const START_Z_OFFSET: f64 = BIN1_FLOOR_HALF[2];

/// One object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectGeometry {
    /// The element.
    pub object: Object,
    /// Collision primitives in the object's body frame, whose origin is the point every
    /// distance and `obj_pos` refers to (docs/src/reference-facts.md §3).
    pub parts: &'static [Part],
    /// The goal marker's primitives in its body frame (non-colliding; slightly different
    /// sizes for the plate and the dumbbell, docs/src/reference-facts.md §3 notes).
    pub marker_parts: &'static [Part],
    /// MuJoCo's contact dimensionality of its geoms (docs/src/reference-facts.md §3): 3 is sliding
    /// friction only; 4 adds torsional friction (the dumbbell and the plate).
    pub condim: u32,
    /// How many 0.001 kg material copies the compiled model carries
    /// (docs/src/reference-facts.md §3 notes).
    pub material_copies: u32,
    /// Bottom of the object relative to its origin (m), from its sampler site; negative.
    pub bottom_offset: f64,
    /// Top of the object relative to its origin (m), from its sampler site.
    pub top_offset: f64,
    /// Horizontal radius used by the placement sampler (m).
    pub horizontal_radius: f64,
}

impl ObjectGeometry {
    /// Total mass (kg): the collision volume at [`OBJECT_DENSITY`] plus the material copies.
    pub fn mass(&self) -> f64 {
        let volume: f64 = self.parts.iter().map(|part| part.shape.volume()).sum();
        OBJECT_DENSITY * volume + f64::from(self.material_copies) * MATERIAL_COPY_MASS
    }

    /// Torsional friction coefficient (m) of each collision primitive, in the order of `parts`:
    /// its own torsional friction with condim 4, none with condim 3. MuJoCo takes the larger of
    /// the two geoms' coefficients, and every geom an object can touch has 0.005 or (the finger
    /// pads) 0, never more than the object's own, so the object's value is the contact's.
    pub fn torsional_coefficients(&self) -> Vec<f64> {
        self.parts
            .iter()
            .filter(|part| part.collides)
            .map(|part| {
                if self.condim >= 4 {
                    part.friction.torsion
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// World z of the origin when the object starts on bin 1's floor
    /// (docs/src/reference-facts.md §2.2, §3): Box 0.85, Hollowbox 0.828, Plate 0.84, Dumbbell
    /// 0.872.
    pub fn spawn_z(&self) -> f64 {
        (START_Z_OFFSET + BIN1_POSITION[2]) - self.bottom_offset
    }
}

/// An object box with the objects' friction.
const fn object_box(name: &'static str, half: [f64; 3], offset: [f64; 3]) -> Part {
    let shape = Primitive::cuboid(half[0], half[1], half[2]);
    Part::solid(name, shape, offset, Friction::OBJECT)
}

/// An upright object cylinder centred at height `z`, with the objects' friction.
const fn object_cylinder(name: &'static str, radius: f64, half_length: f64, z: f64) -> Part {
    let shape = Primitive::cylinder(radius, half_length);
    Part::solid(name, shape, [0.0, 0.0, z], Friction::OBJECT)
}

/// The part with MuJoCo's default friction instead (the plate's stem,
/// docs/src/reference-facts.md §3).
const fn with_table_friction(part: Part) -> Part {
    Part {
        friction: Friction::TABLE,
        ..part
    }
}

/// The part as a non-colliding goal-marker piece called `name`.
const fn visual(part: Part, name: &'static str) -> Part {
    Part {
        name,
        collides: false,
        ..part
    }
}

// Box: one 4 × 4 × 6 cm box (docs/src/reference-facts.md §3).
const BOX_BODY: Part = object_box("object/body", [0.02, 0.02, 0.03], [0.0; 3]);

// Hollowbox: a base plate and four walls standing on it, open on top
// (docs/src/reference-facts.md §3).
const HOLLOW_BASE: Part = object_box("object/base", [0.03, 0.03, 0.008], [0.0; 3]);
const HOLLOW_WALL_Y_POS: Part =
    object_box("object/wall_y+", [0.03, 0.008, 0.03], [0.0, 0.03, 0.03]);
const HOLLOW_WALL_Y_NEG: Part =
    object_box("object/wall_y-", [0.03, 0.008, 0.03], [0.0, -0.03, 0.03]);
const HOLLOW_WALL_X_POS: Part =
    object_box("object/wall_x+", [0.008, 0.03, 0.03], [0.03, 0.0, 0.03]);
const HOLLOW_WALL_X_NEG: Part =
    object_box("object/wall_x-", [0.008, 0.03, 0.03], [-0.03, 0.0, 0.03]);

// Plate: a 2 × 2 × 4 cm stem under a 12 cm disc (docs/src/reference-facts.md §3). The stem keeps
// MuJoCo's default friction; the disc has the objects' (1, 1, 1).
const PLATE_STEM: Part =
    with_table_friction(object_box("object/stem", [0.01, 0.01, 0.02], [0.0; 3]));
const PLATE_DISC: Part = object_cylinder("object/disc", 0.06, 0.007, 0.02);
// Its goal marker: a taller stem, a thinner disc lower down (docs/src/reference-facts.md §3 notes).
// Marker-only shapes are named where the row makes them visual.
const MARKER_PLATE_STEM: Part = with_table_friction(object_box("", [0.01, 0.01, 0.016], [0.0; 3]));
const MARKER_PLATE_DISC: Part = object_cylinder("", 0.06, 0.005, 0.016);

// Dumbbell: an upright bar with a disc at each end (docs/src/reference-facts.md §3).
const DUMBBELL_BAR: Part = object_cylinder("object/bar", 0.02, 0.045, 0.0);
const DUMBBELL_DISC_Z_POS: Part = object_cylinder("object/disc_z+", 0.045, 0.0035, 0.045);
const DUMBBELL_DISC_Z_NEG: Part = object_cylinder("object/disc_z-", 0.045, 0.0035, -0.045);
// Its goal marker has 5 cm discs (docs/src/reference-facts.md §3 notes).
const MARKER_DUMBBELL_DISC_Z_POS: Part = object_cylinder("", 0.05, 0.0035, 0.045);
const MARKER_DUMBBELL_DISC_Z_NEG: Part = object_cylinder("", 0.05, 0.0035, -0.045);

const BOX: ObjectGeometry = ObjectGeometry {
    object: Object::Box,
    parts: &[BOX_BODY],
    marker_parts: &[visual(BOX_BODY, "goal/body")],
    condim: 3,
    material_copies: 1,
    bottom_offset: -0.03,
    top_offset: 0.03,
    horizontal_radius: 0.02,
};

const HOLLOW_BOX: ObjectGeometry = ObjectGeometry {
    object: Object::HollowBox,
    parts: &[
        HOLLOW_BASE,
        HOLLOW_WALL_Y_POS,
        HOLLOW_WALL_Y_NEG,
        HOLLOW_WALL_X_POS,
        HOLLOW_WALL_X_NEG,
    ],
    marker_parts: &[
        visual(HOLLOW_BASE, "goal/base"),
        visual(HOLLOW_WALL_Y_POS, "goal/wall_y+"),
        visual(HOLLOW_WALL_Y_NEG, "goal/wall_y-"),
        visual(HOLLOW_WALL_X_POS, "goal/wall_x+"),
        visual(HOLLOW_WALL_X_NEG, "goal/wall_x-"),
    ],
    // Five collision geoms but four copies: the runtime mass is 0.288 + 0.004
    // (docs/src/reference-facts.md §3).
    condim: 3,
    material_copies: 4,
    bottom_offset: -0.008,
    top_offset: 0.068,
    horizontal_radius: 0.038,
};

const PLATE: ObjectGeometry = ObjectGeometry {
    object: Object::Plate,
    parts: &[PLATE_STEM, PLATE_DISC],
    marker_parts: &[
        visual(MARKER_PLATE_STEM, "goal/stem"),
        visual(MARKER_PLATE_DISC, "goal/disc"),
    ],
    condim: 4,
    material_copies: 2,
    bottom_offset: -0.02,
    top_offset: 0.034,
    horizontal_radius: 0.06,
};

const DUMBBELL: ObjectGeometry = ObjectGeometry {
    object: Object::Dumbbell,
    parts: &[DUMBBELL_BAR, DUMBBELL_DISC_Z_POS, DUMBBELL_DISC_Z_NEG],
    marker_parts: &[
        visual(DUMBBELL_BAR, "goal/bar"),
        visual(MARKER_DUMBBELL_DISC_Z_POS, "goal/disc_z+"),
        visual(MARKER_DUMBBELL_DISC_Z_NEG, "goal/disc_z-"),
    ],
    condim: 4,
    material_copies: 3,
    bottom_offset: -0.052,
    top_offset: 0.052,
    horizontal_radius: 0.045,
};

/// The row of an object.
pub fn object_geometry(object: Object) -> &'static ObjectGeometry {
    match object {
        Object::Box => &BOX,
        Object::HollowBox => &HOLLOW_BOX,
        Object::Plate => &PLATE,
        Object::Dumbbell => &DUMBBELL,
    }
}
