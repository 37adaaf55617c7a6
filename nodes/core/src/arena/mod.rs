//! The static scene, as plain data: bins, obstacles, trash can, shelf, goal marker, robot base,
//! the object's start region, and the objects' own primitives.
//!
//! Every number comes from the reference's arena, obstacle and object code (CompoSuite
//! `1fa36f6`; which files: `docs/src/reference-sources.md`) and is written
//! once, in a table with one row per axis element: [`objective_arena`] (bins, fixture, goal),
//! [`obstacle_geometry`] ("no obstacle" is a row with no parts) and [`object_geometry`]. The
//! functions below compose those rows into placed primitives. Units are metres and radians;
//! the world frame has +x away from the robot, +z up, bin 1 on the −y side.
//!
//! What is left out: the bins' legs (visual-only) and the ground, which is a plane
//! ([`GROUND_HALF_SIZE`]) rather than a primitive.

mod bins;
mod fixtures;
mod objective_arena;
mod objects;
mod obstacles;
mod primitive;
mod start_region;

use nalgebra::{Isometry3, Point3, Vector3};

pub use bins::{BIN1_FLOOR_HALF, BIN1_POSITION, BIN2_FLOOR_HALF};
pub use fixtures::{
    GROUND_HALF_SIZE, ROBOT_BASE_POSITION, SHELF, ShelfDims, TRASH_CAN, TrashCanDims,
};
pub use objective_arena::{ObjectiveArena, objective_arena};
pub use objects::{MATERIAL_COPY_MASS, OBJECT_DENSITY, ObjectGeometry, object_geometry};
pub use obstacles::{Footprint, ObstacleGeometry, obstacle_geometry};
pub use primitive::{Friction, Part, Placed, Primitive, merged_solids};
pub use start_region::{KeepOut, PLACEMENT_ATTEMPTS, StartRegion, object_start_region};

use crate::axes::{Object, Objective, Obstacle};

/// Every static solid of a scene in the world frame: bin 1, bin 2, the objective's fixture
/// and the obstacle's parts, in that order.
pub fn arena_parts(objective: Objective, obstacle: Obstacle) -> Vec<Placed> {
    let layout = objective_arena(objective);
    let obstacle = obstacle_geometry(obstacle);
    let mut parts = primitive::place(layout.bin1_parts, BIN1_POSITION, 0.0);
    parts.extend(primitive::place(
        layout.bin2_parts,
        layout.bin2_position,
        0.0,
    ));
    parts.extend(primitive::place(
        layout.fixture_parts,
        layout.fixture_position,
        0.0,
    ));
    parts.extend(primitive::place(
        obstacle.parts,
        obstacle.body_position,
        obstacle.yaw,
    ));
    parts
}

/// The goal marker's body position (docs/src/reference-facts.md §2.4): what the `goal_pos`
/// observation reports and what Push measures against. Its z is the reference height minus the
/// object's bottom offset, so PickPlace and Push markers sit 2 cm below a resting object.
pub fn goal_position(objective: Objective, object: Object) -> Point3<f64> {
    let layout = objective_arena(objective);
    let [rx, ry, rz] = layout.goal_reference;
    let [ox, oy, oz] = layout.goal_offset;
    // Summed in the reference sampler's order: offset + reference, then the bottom offset.
    Point3::new(
        ox + rx,
        oy + ry,
        (oz + rz) - object_geometry(object).bottom_offset,
    )
}

/// The goal marker's visual-only primitives in the world frame (identity orientation).
pub fn goal_marker_parts(objective: Objective, object: Object) -> Vec<Placed> {
    let at = goal_position(objective, object);
    primitive::place(
        object_geometry(object).marker_parts,
        [at.x, at.y, at.z],
        0.0,
    )
}

/// The object's collision primitives in its body frame (origin = the object's reference
/// point, docs/src/reference-facts.md §3).
pub fn object_parts(object: Object) -> Vec<Placed> {
    primitive::place(object_geometry(object).parts, [0.0; 3], 0.0)
}

/// The robot base body's pose in the world, the same for all four arms
/// (docs/src/reference-facts.md §2.7).
pub fn robot_base_pose() -> Isometry3<f64> {
    Isometry3::translation(
        ROBOT_BASE_POSITION[0],
        ROBOT_BASE_POSITION[1],
        ROBOT_BASE_POSITION[2],
    )
}

/// Bin 2's body position for an objective (docs/src/reference-facts.md §2.1).
pub fn bin2_position(objective: Objective) -> Point3<f64> {
    Point3::from(Vector3::from(objective_arena(objective).bin2_position))
}

#[cfg(test)]
mod test;
