//! ROS plumbing for the CompoSuite-ROS nodes: everything between the ROS-free core and the wire.
//! One folder per node, plus the pieces they share:
//!
//! - [`sim`]: physics, joint states, observations, and the ros2_control-style controllers;
//! - [`task_manager`]: scenes, episodes, the task services;
//! - [`reward`]: staged rewards and success;
//! - [`recorder`]: records the wire into a rosbag2 bag;
//! - [`player`]: plays a bag back into a running graph (`composuite bag play`);
//! - [`simulation_interfaces`]: the ROS 2 standard simulation interfaces (which node serves
//!   what, entities, worlds);
//! - [`container`]: many environments' nodes in one process on one participant;
//! - [`nodes`]: the nodes by kind (specs and mains, for the binaries and `composuite launch`);
//! - [`grants`]: the DDS topics each node (and an agent) needs, for security permissions;
//! - [`shared`]: start-up, parameters, logging, names, QoS, message conversions;
//! - [`bag`]: rosbag2 bags in MCAP (writer, reader, reindex), for the recorder and the CLI.
#![warn(missing_docs)]

pub mod bag;
pub mod container;
pub mod grants;
pub mod nodes;
pub mod player;
pub mod recorder;
pub mod reward;
pub mod shared;
pub mod sim;
pub mod simulation_interfaces;
pub mod task_manager;
