//! The controllers a real arm's ros2_control driver runs, over the [`Hardware`] seam only:
//!
//! - [`trajectory`]: joint_trajectory_controller (goal validation, spline interpolation,
//!   tolerances, result codes);
//! - [`spline`]: the interpolation it uses between waypoints.
//!
//! [`Hardware`]: crate::sim::hardware::Hardware

pub mod spline;
pub mod trajectory;

#[cfg(test)]
mod test;
