//! ROS plumbing for the CompoSuite-ROS nodes: everything between the ROS-free core and the wire.
//!
//! - [`convert`]: core types to `composuite_msgs` and standard messages, and incoming commands
//!   back (by joint name, with errors that name what is valid);
//! - [`names`]: the topic and service names, relative so a namespace can hold one environment;
//! - [`ros_args`]: the `--ros-args` command line every ROS 2 node accepts;
//! - [`qos`]: the QoS profile of each kind of topic;
//! - [`environment`]: `ROS_DOMAIN_ID` and the discovery range, which ros2-client does not read;
//! - [`node`] and [`params`]: what every node shares (start-up, parameters, logging, signals);
//! - [`sim`], [`task_manager`], [`reward`]: the three nodes (the binaries are thin mains);
//! - [`bag`] and [`recorder`]: rosbag2 bags in MCAP (writer, reader, reindex) and the node that
//!   records the wire into one.
#![warn(missing_docs)]

pub mod bag;
pub mod convert;
pub mod dds_log;
pub mod environment;
pub mod names;
pub mod node;
pub mod nodes;
pub mod param_server;
pub mod params;
pub mod qos;
pub mod recorder;
pub mod reward;
pub mod ros_args;
pub mod sim;
pub mod task_manager;
