//! The controllers a real arm's ros2_control driver runs, over the [`Hardware`] seam only:
//!
//! - [`trajectory`]: joint_trajectory_controller (goal validation, spline interpolation,
//!   tolerances, result codes), with [`spline`], the interpolation it uses between waypoints;
//! - [`gripper`]: gripper_action_controller (reached / stalled);
//! - [`forward`]: forward_command_controller's position form (checked commands);
//! - [`running`]: what commands the arm and gripper now, all updated on one reading per period;
//! - [`catalog`]: the controllers' names, types and interfaces, as controller_manager lists them.
//!
//! [`Hardware`]: crate::sim::hardware::Hardware

pub mod catalog;
pub mod forward;
pub mod gripper;
pub mod running;
pub mod spline;
pub mod trajectory;

#[cfg(test)]
mod test;
