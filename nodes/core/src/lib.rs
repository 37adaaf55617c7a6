//! The ROS-free core of CompoSuite-ROS: the 256 tasks, their arenas, observations and staged
//! rewards, the four arms and the gripper in rapier3d, the in-process environment
//! ([`env::Env`]) and the scripted [`expert`]. Whatever steps a task — the tests, the benchmarks,
//! the ROS 2 nodes, the `composuite` command — steps it through this crate.
//!
//! A CompoSuite task is one element from each of four axes — robot, object, obstacle,
//! objective — giving 4 × 4 × 4 × 4 = 256 tasks. Each axis is its own module under [`axes`],
//! holding an enum and one table of data per element. This crate has no ROS in it; the nodes
//! are thin adapters over it.
#![warn(missing_docs)]

pub mod arena;
pub mod axes;
pub mod batch;
pub mod control;
pub mod dataset;
pub mod env;
pub mod expert;
pub mod kinematics;
pub mod obs;
pub mod physics;
pub mod render;
pub mod reward;
pub mod rng;
pub mod sampling;
mod task;

pub use task::{TaskParseError, TaskSpec, all_tasks};

/// The things most callers need.
pub mod prelude {
    pub use crate::axes::{Axis, AxisElement, Object, Objective, Obstacle, Robot, UnknownElement};
    pub use crate::task::{TaskSpec, all_tasks};
}
