//! What every node shares: start-up, parameters, logging, names, QoS and the conversions between
//! the core's types and messages.
//!
//! - [`convert`]: core types to `composuite_msgs` and standard messages, and incoming commands
//!   back (by joint name, with errors that name what is valid);
//! - [`names`]: the topic and service names, relative so a namespace can hold one environment;
//! - [`ros_args`]: the `--ros-args` command line every ROS 2 node accepts;
//! - [`qos`]: the QoS profile of each kind of topic;
//! - [`environment`]: `ROS_DOMAIN_ID`, the discovery range and the security switches, which
//!   ros2-client does not read; [`security`]: which enclave's files a participant joins with;
//! - [`node`], [`params`] and [`param_server`]: start-up, parameters and their services,
//!   logging, signals;
//! - [`dds_log`]: RustDDS's log output, quietened where it reports expected events;
//! - [`intra_process`]: messages handed over between the nodes of one composed process.

pub mod convert;
pub mod dds_log;
pub mod environment;
pub mod intra_process;
pub mod names;
pub mod node;
pub mod node_kind;
pub mod param_server;
pub mod params;
pub mod qos;
pub mod ros_args;
pub mod security;
