//! Where the object may start: the placement sampler's ranges and rejection discs
//! (docs/src/reference-facts.md §2.2).

use nalgebra::Point3;

use super::bins::{BIN1_FLOOR_HALF, BIN1_POSITION};
use super::objects::object_geometry;
use super::obstacles::obstacle_geometry;
use crate::axes::{Object, Obstacle};

/// How many draws the reference sampler makes before giving up (docs/src/reference-facts.md §2.2).
pub const PLACEMENT_ATTEMPTS: usize = 5000;

/// The object's y range relative to bin 1 (docs/src/reference-facts.md §2.2): ± bin1_size.y / 2.
const Y_RANGE: [f64; 2] = [-(BIN1_FLOOR_HALF[1] / 2.0), BIN1_FLOOR_HALF[1] / 2.0];

/// A disc of the xy plane the object's origin may not start in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeepOut {
    /// World xy of the obstacle body (m).
    pub centre: [f64; 2],
    /// The obstacle's horizontal radius plus the object's (m); a sample at this distance or
    /// closer is rejected.
    pub radius: f64,
}

/// Where one object may start behind one obstacle.
///
/// A start position is `reference + (dx, dy, 0)` with `dx` uniform between `x_range[0]` and
/// `x_range[1]`, `dy` likewise, redrawn (x, then y) while a [`KeepOut`] rejects it. The
/// ranges are already shrunk by the object's horizontal radius, as the reference's
/// "ensure boundary in range" does, and are kept in its (low, high) order: for the plate
/// behind an object wall or door low > high (0.06 > 0.04), and the draw `low + (high − low)·u`
/// still lands in between.
#[derive(Debug, Clone, PartialEq)]
pub struct StartRegion {
    /// Bin 1's body position, which the draws are relative to (m).
    pub reference: [f64; 3],
    /// (low, high) of the x draw relative to `reference` (m).
    pub x_range: [f64; 2],
    /// (low, high) of the y draw relative to `reference` (m).
    pub y_range: [f64; 2],
    /// World z of the object's origin at the start (m): its bottom on bin 1's floor top.
    pub z: f64,
    /// The obstacle's disc, empty without an obstacle.
    pub keep_out: Vec<KeepOut>,
}

impl StartRegion {
    /// The start position for the draws `dx`, `dy`, summed in the reference's order.
    pub fn position(&self, dx: f64, dy: f64) -> Point3<f64> {
        Point3::new(dx + self.reference[0], dy + self.reference[1], self.z)
    }

    /// Whether a start at world `(x, y)` is clear of every [`KeepOut`] (the range is the
    /// draw's business). The reference's accompanying height test always passes here.
    pub fn is_clear(&self, x: f64, y: f64) -> bool {
        self.keep_out.iter().all(|disc| {
            let dx = x - disc.centre[0];
            let dy = y - disc.centre[1];
            (dx * dx + dy * dy).sqrt() > disc.radius
        })
    }

    /// World x interval (min, max) the start can fall in (m).
    pub fn world_x(&self) -> [f64; 2] {
        world_interval(self.x_range, self.reference[0])
    }

    /// World y interval (min, max) the start can fall in (m).
    pub fn world_y(&self) -> [f64; 2] {
        world_interval(self.y_range, self.reference[1])
    }
}

fn world_interval(range: [f64; 2], reference: f64) -> [f64; 2] {
    let [a, b] = range;
    [a.min(b) + reference, a.max(b) + reference]
}

/// Where `object` may start with `obstacle` in the scene (docs/src/reference-facts.md §2.2).
pub fn object_start_region(obstacle: Obstacle, object: Object) -> StartRegion {
    let object = object_geometry(object);
    let obstacle = obstacle_geometry(obstacle);
    let r = object.horizontal_radius;
    let shrink = |[low, high]: [f64; 2]| [low + r, high - r];
    StartRegion {
        reference: BIN1_POSITION,
        x_range: shrink(obstacle.object_x_range),
        y_range: shrink(Y_RANGE),
        z: object.spawn_z(),
        keep_out: obstacle
            .footprint
            .iter()
            .map(|footprint| KeepOut {
                centre: footprint.centre,
                radius: footprint.radius + r,
            })
            .collect(),
    }
}
