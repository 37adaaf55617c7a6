//! The solids every scene is made of: a primitive shape, and where it sits.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// A convex primitive, centred on its own origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Primitive {
    /// A box, given by its half-extents along its local x, y and z axes (m).
    Box {
        /// Half-extents (m).
        half_extents: Vector3<f64>,
    },
    /// A cylinder whose axis is its local z axis.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Half of its length along the local z axis (m).
        half_length: f64,
    },
}

impl Primitive {
    /// A box from its three half-extents (m).
    pub const fn cuboid(hx: f64, hy: f64, hz: f64) -> Self {
        Primitive::Box {
            half_extents: Vector3::new(hx, hy, hz),
        }
    }

    /// A z-axis cylinder from its radius and half-length (m).
    pub const fn cylinder(radius: f64, half_length: f64) -> Self {
        Primitive::Cylinder {
            radius,
            half_length,
        }
    }

    /// Volume (m³).
    pub fn volume(&self) -> f64 {
        match *self {
            Primitive::Box { half_extents: h } => 8.0 * h.x * h.y * h.z,
            Primitive::Cylinder {
                radius,
                half_length,
            } => std::f64::consts::PI * radius * radius * 2.0 * half_length,
        }
    }
}

/// Contact friction in the reference's (MuJoCo's) three coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    /// Sliding (Coulomb) coefficient.
    pub slide: f64,
    /// Torsional coefficient (m).
    pub torsion: f64,
    /// Rolling coefficient (m).
    pub roll: f64,
}

impl Friction {
    /// MuJoCo's default friction, which every bin and table geom uses
    /// (docs/src/reference-facts.md §2) and the reference keeps for the shelf and obstacle geoms,
    /// which set none.
    pub const TABLE: Friction = Friction {
        slide: 1.0,
        torsion: 0.005,
        roll: 0.0001,
    };
    /// The objects' friction, (1, 1, 1) (docs/src/reference-facts.md §3; the plate's stem keeps
    /// [`Friction::TABLE`]).
    pub const OBJECT: Friction = Friction {
        slide: 1.0,
        torsion: 1.0,
        roll: 1.0,
    };
}

/// One primitive in the frame of the body it belongs to: a row of a geometry table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Part {
    /// `kind/piece`, e.g. `bin1/floor`; unique within a composed scene.
    pub name: &'static str,
    /// Shape and size.
    pub shape: Primitive,
    /// Centre in the body frame (m). No part is rotated relative to its body.
    pub offset: [f64; 3],
    /// False for visual-only parts (the goal marker).
    pub collides: bool,
    /// Friction (irrelevant when `collides` is false).
    pub friction: Friction,
}

impl Part {
    /// A colliding part with the given friction.
    pub(crate) const fn solid(
        name: &'static str,
        shape: Primitive,
        offset: [f64; 3],
        friction: Friction,
    ) -> Self {
        Part {
            name,
            shape,
            offset,
            collides: true,
            friction,
        }
    }
}

/// A primitive placed in some frame: the world for the arena, the object body for
/// [`object_parts`](super::object_parts).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// `kind/piece`, e.g. `bin1/floor`, `obstacle/post_y+`, `object/disc`.
    pub name: &'static str,
    /// Shape and size.
    pub shape: Primitive,
    /// Pose of the primitive's centre (its cylinder axis is the pose's z axis).
    pub pose: Isometry3<f64>,
    /// False for visual-only solids, which nothing collides with.
    pub collides: bool,
    /// Friction (irrelevant when `collides` is false).
    pub friction: Friction,
}

impl Placed {
    /// The axis-aligned bounds (min corner, max corner) in the frame of `pose`.
    pub fn aabb(&self) -> (Point3<f64>, Point3<f64>) {
        let rotation = self.pose.rotation.to_rotation_matrix();
        let half: Vector3<f64> = match self.shape {
            Primitive::Box { half_extents } => rotation.matrix().abs() * half_extents,
            Primitive::Cylinder {
                radius,
                half_length,
            } => {
                // Per world axis: the axis segment's reach plus the end disc's reach.
                let axis = rotation * Vector3::z();
                axis.map(|a| half_length * a.abs() + radius * (1.0 - a * a).max(0.0).sqrt())
            }
        };
        let centre = Point3::from(self.pose.translation.vector);
        (centre - half, centre + half)
    }
}

/// Places a body's parts: the body sits at `position`, turned by `yaw` about +z.
pub(crate) fn place(parts: &[Part], position: [f64; 3], yaw: f64) -> Vec<Placed> {
    let body = Isometry3::from_parts(
        Translation3::from(Vector3::from(position)),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
    );
    parts
        .iter()
        .map(|part| Placed {
            name: part.name,
            shape: part.shape,
            pose: body * Translation3::from(Vector3::from(part.offset)),
            collides: part.collides,
            friction: part.friction,
        })
        .collect()
}

/// The colliding solids of `parts`, with boxes that lie flush in one solid merged into one
/// box (each with the index of its first part).
///
/// Two boxes merge when they are turned alike, match in two extents and overlap or touch
/// along the third: together they fill exactly one box. Kept apart, the face of one that is
/// buried in the other still collides, and an object sliding from one onto the other catches
/// on its top edge (the contact normal there is horizontal). The Push arena's two bin floors
/// are such a pair: bin 2's floor starts 3.5 cm inside bin 1's (docs/src/reference-facts.md §2.1).
pub fn merged_solids(parts: &[Placed]) -> Vec<(usize, Placed)> {
    let mut solids: Vec<(usize, Placed)> = parts
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, p)| p.collides)
        .collect();
    // Merge pairs until none is left; each merge removes one solid, so this ends.
    'search: loop {
        for i in 0..solids.len() {
            for j in i + 1..solids.len() {
                if let Some(union) = flush_union(&solids[i].1, &solids[j].1) {
                    solids[i].1 = union;
                    solids.remove(j);
                    continue 'search;
                }
            }
        }
        return solids;
    }
}

/// The box filled by boxes `a` and `b` together, if they fill exactly one (see
/// [`merged_solids`]).
fn flush_union(a: &Placed, b: &Placed) -> Option<Placed> {
    const TOLERANCE: f64 = 1e-9;
    let (Primitive::Box { half_extents: ha }, Primitive::Box { half_extents: hb }) =
        (a.shape, b.shape)
    else {
        return None;
    };
    if a.friction != b.friction || a.pose.rotation.angle_to(&b.pose.rotation) > TOLERANCE {
        return None;
    }
    // b's centre in a's frame: apart along one axis only, alike in the other two.
    let offset = a
        .pose
        .inverse_transform_vector(&(b.pose.translation.vector - a.pose.translation.vector));
    let apart: Vec<usize> = (0..3)
        .filter(|&k| offset[k].abs() > TOLERANCE || (ha[k] - hb[k]).abs() > TOLERANCE)
        .collect();
    let &[k] = apart.as_slice() else {
        return None;
    };
    if offset[k].abs() > ha[k] + hb[k] + TOLERANCE {
        return None;
    }
    let low = (-ha[k]).min(offset[k] - hb[k]);
    let high = ha[k].max(offset[k] + hb[k]);
    let mut half = ha;
    half[k] = (high - low) / 2.0;
    let mut shift = Vector3::zeros();
    shift[k] = (high + low) / 2.0;
    Some(Placed {
        shape: Primitive::Box { half_extents: half },
        pose: a.pose * Translation3::from(shift),
        ..*a
    })
}
