//! The obstacle table: one row per element of the obstacle axis, "no obstacle" included as a
//! row with no parts (docs/src/reference-facts.md §2.2, §2.3).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::bins::{BIN1_FLOOR_HALF, BIN1_POSITION};
use super::primitive::{Friction, Part, Primitive};
use crate::axes::Obstacle;

/// The disc an obstacle occupies for the object placement sampler
/// (docs/src/reference-facts.md §2.2): a sample is rejected when its xy distance to `centre` is at
/// most `radius` + the object's radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    /// World xy of the obstacle body (m).
    pub centre: [f64; 2],
    /// The obstacle's horizontal radius (m).
    pub radius: f64,
}

/// One obstacle: where its body goes, what it is made of, and what it keeps free of objects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObstacleGeometry {
    /// The element.
    pub obstacle: Obstacle,
    /// World position of the body (m); the origin for "no obstacle", which is what the
    /// observation reports then.
    pub body_position: [f64; 3],
    /// Rotation of the body about +z (rad).
    pub yaw: f64,
    /// The solids, in the body frame; none for "no obstacle".
    pub parts: &'static [Part],
    /// Sampler footprints; none for "no obstacle".
    pub footprint: &'static [Footprint],
    /// Bottom offset of the obstacle's sampler sites (m); the body sits this far below 0.8.
    pub bottom_offset: f64,
    /// Top offset of the obstacle's sampler sites (m).
    pub top_offset: f64,
    /// x range of the object's start region relative to bin 1's x, before the object's
    /// radius shrinks it (m): the central half of the floor, or only its far quarter strip
    /// beyond an object wall or door (docs/src/reference-facts.md §2.2).
    pub object_x_range: [f64; 2],
}

impl ObstacleGeometry {
    /// The body's pose in the world.
    pub fn body_pose(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(Vector3::from(self.body_position)),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.yaw),
        )
    }
}

/// The obstacle sampler's reference height (docs/src/reference-facts.md §2.3): bodies sit at
/// 0.8 − bottom_offset.
const OBSTACLE_BASE_Z: f64 = BIN1_POSITION[2];

/// The object's x range (relative to bin 1) over the whole central half of the floor
/// (docs/src/reference-facts.md §2.2): ± bin1_size.x / 2.
const FULL_X_RANGE: [f64; 2] = [-(BIN1_FLOOR_HALF[0] / 2.0), BIN1_FLOOR_HALF[0] / 2.0];
/// Beyond an object wall or door: only the far half of that range
/// (docs/src/reference-facts.md §2.2).
const BEYOND_WALL_X_RANGE: [f64; 2] = [0.0, BIN1_FLOOR_HALF[0] / 2.0];

// ObjectWall and ObjectDoor share a body (docs/src/reference-facts.md §2.3): a quarter of the way
// into bin 1 (x = 0.1 − 0.2/2.2), turned 90° so the wall runs along y, at z = 0.8 + 0.125.
const OBJECT_WALL_BOTTOM: f64 = -0.125;
const OBJECT_WALL_BODY: [f64; 3] = [
    -(BIN1_FLOOR_HALF[0] / 2.2) + BIN1_POSITION[0],
    BIN1_POSITION[1],
    OBSTACLE_BASE_Z - OBJECT_WALL_BOTTOM,
];
const OBJECT_WALL_YAW: f64 = std::f64::consts::FRAC_PI_2;

// GoalWall (docs/src/reference-facts.md §2.3): on the seam between the bins (y = −0.26 + 0.25),
// z = 0.8 + 0.14.
const GOAL_WALL_BOTTOM: f64 = -0.14;
const GOAL_WALL_BODY: [f64; 3] = [
    BIN1_POSITION[0],
    BIN1_FLOOR_HALF[1] + BIN1_POSITION[1],
    OBSTACLE_BASE_Z - GOAL_WALL_BOTTOM,
];

const fn wall(name: &'static str, half: [f64; 3], offset: [f64; 3]) -> Part {
    Part::solid(
        name,
        Primitive::cuboid(half[0], half[1], half[2]),
        offset,
        Friction::TABLE,
    )
}

const NO_OBSTACLE: ObstacleGeometry = ObstacleGeometry {
    obstacle: Obstacle::NoObstacle,
    body_position: [0.0; 3],
    yaw: 0.0,
    parts: &[],
    footprint: &[],
    bottom_offset: 0.0,
    top_offset: 0.0,
    object_x_range: FULL_X_RANGE,
};

const OBJECT_WALL: ObstacleGeometry = ObstacleGeometry {
    obstacle: Obstacle::ObjectWall,
    body_position: OBJECT_WALL_BODY,
    yaw: OBJECT_WALL_YAW,
    // 0.20 m along the body's x (world y), 1 cm thick, 0.25 m tall, raised 2 cm
    // (docs/src/reference-facts.md §2.3).
    parts: &[wall("obstacle/wall", [0.1, 0.005, 0.125], [0.0, 0.0, 0.02])],
    footprint: &[Footprint {
        centre: [OBJECT_WALL_BODY[0], OBJECT_WALL_BODY[1]],
        radius: 0.1,
    }],
    bottom_offset: OBJECT_WALL_BOTTOM,
    top_offset: 0.125,
    object_x_range: BEYOND_WALL_X_RANGE,
};

const OBJECT_DOOR: ObstacleGeometry = ObstacleGeometry {
    obstacle: Obstacle::ObjectDoor,
    body_position: OBJECT_WALL_BODY,
    yaw: OBJECT_WALL_YAW,
    // Two 0.14 m posts at body x = ±0.16 (world y −0.42 and −0.10), leaving an 0.18 m opening
    // with no lintel (docs/src/reference-facts.md §2.3).
    parts: &[
        wall("obstacle/post_y-", [0.07, 0.005, 0.125], [-0.16, 0.0, 0.02]),
        wall("obstacle/post_y+", [0.07, 0.005, 0.125], [0.16, 0.0, 0.02]),
    ],
    footprint: &[Footprint {
        centre: [OBJECT_WALL_BODY[0], OBJECT_WALL_BODY[1]],
        radius: 0.07,
    }],
    bottom_offset: OBJECT_WALL_BOTTOM,
    top_offset: 0.125,
    object_x_range: BEYOND_WALL_X_RANGE,
};

const GOAL_WALL: ObstacleGeometry = ObstacleGeometry {
    obstacle: Obstacle::GoalWall,
    body_position: GOAL_WALL_BODY,
    yaw: 0.0,
    // On the robot-near half of the seam only: x −0.10…0.11, 28 cm tall
    // (docs/src/reference-facts.md §2.3).
    parts: &[wall(
        "obstacle/wall",
        [0.105, 0.005, 0.14],
        [-0.095, 0.0, 0.02],
    )],
    footprint: &[Footprint {
        centre: [GOAL_WALL_BODY[0], GOAL_WALL_BODY[1]],
        radius: 0.08,
    }],
    bottom_offset: GOAL_WALL_BOTTOM,
    top_offset: 0.14,
    object_x_range: FULL_X_RANGE,
};

/// The row of an obstacle.
pub fn obstacle_geometry(obstacle: Obstacle) -> &'static ObstacleGeometry {
    match obstacle {
        Obstacle::NoObstacle => &NO_OBSTACLE,
        Obstacle::ObjectWall => &OBJECT_WALL,
        Obstacle::ObjectDoor => &OBJECT_DOOR,
        Obstacle::GoalWall => &GOAL_WALL,
    }
}
