//! The object's start position, drawn exactly as the reference draws it for a seed.

use nalgebra::Point3;

use super::EnvError;
use crate::arena::{PLACEMENT_ATTEMPTS, object_start_region};
use crate::axes::{Object, Obstacle};
use crate::rng::Mt19937;

/// The largest seed: the reference seeds numpy's legacy generator, which takes 32 bits.
pub const MAX_SEED: u64 = u32::MAX as u64;

/// The seed an episode reports when its start was drawn from a generator's state rather than
/// from a seed ([`super::Env::reset_from`]); past [`MAX_SEED`], so no seed is mistaken for it.
pub const UNSEEDED: u64 = u64::MAX;

/// Where the object starts for `seed` (docs/src/reference-facts.md §7.3). The draws, in order: 7
/// standard normals for the robot's initialisation noise (scaled by 0 in the reference, but
/// consumed); 2 uniforms for the obstacle's placement (over an empty range) when there is one; x
/// then y of the object, redrawn while the obstacle's disc rejects them; 2 uniforms for the goal
/// marker.
pub fn sample_object_start(
    obstacle: Obstacle,
    object: Object,
    seed: u64,
) -> Result<Point3<f64>, EnvError> {
    let numpy_seed = u32::try_from(seed).map_err(|_| EnvError::BadSeed(seed))?;
    draw_object_start(obstacle, object, &mut Mt19937::numpy_seed(numpy_seed))
        .ok_or(EnvError::NoClearStart { seed })
}

/// The draws of one reset (as [`sample_object_start`] makes them) from `rng` as it stands —
/// numpy's global generator in whatever state a script left it, for the reference's own API.
/// `None` when no start clear of the obstacle came up in the reference's number of tries.
pub fn draw_object_start(
    obstacle: Obstacle,
    object: Object,
    rng: &mut Mt19937,
) -> Option<Point3<f64>> {
    for _ in 0..7 {
        rng.standard_normal();
    }
    if obstacle != Obstacle::NoObstacle {
        rng.uniform(0.0, 0.0);
        rng.uniform(0.0, 0.0);
    }
    let region = object_start_region(obstacle, object);
    for _ in 0..PLACEMENT_ATTEMPTS {
        let dx = rng.uniform(region.x_range[0], region.x_range[1]);
        let dy = rng.uniform(region.y_range[0], region.y_range[1]);
        let p = region.position(dx, dy);
        if region.is_clear(p.x, p.y) {
            // The goal marker's 2 draws come last; they do not move anything we use, but they
            // are consumed so the generator ends where the reference's does.
            rng.uniform(0.0, 0.0);
            rng.uniform(0.0, 0.0);
            return Some(p);
        }
    }
    // Every start region has a clear part (the worst, the plate behind the object wall, is
    // rejected 98 % of the time: 5000 misses in a row has probability ~1e-44); the reference
    // raises here too.
    None
}
