//! Rust types of the `composuite_msgs` ROS 2 interfaces and of the standard ROS 2 messages the
//! suite uses, generated at build time from the `.msg`/`.srv` files (never typed twice).
//!
//! Every message type implements [`RosMessage`]: serde (de)serialisation in the exact CDR layout
//! ROS 2 puts on the wire (the serializer `ros2-client` uses, see [`cdr`]), its ROS name
//! (`pkg/msg/Name`) and DDS name (`pkg::msg::dds_::Name_`), the full definition text rosbag2
//! stores in MCAP, and its RIHS01 type hash. Services implement [`RosService`].
//!
//! ```
//! use composuite_msgs::{RosMessage, cdr, std_msgs::msg::Header};
//! let header = Header { frame_id: "world".into(), ..Default::default() };
//! let bytes = cdr::encode(&header).unwrap();
//! assert_eq!(cdr::decode::<Header>(&bytes).unwrap(), header);
//! assert_eq!(Header::DDS_NAME, "std_msgs::msg::dds_::Header_");
//! ```
#![warn(missing_docs)]

pub mod cdr;
mod description;

pub use description::{ArrayKind, BoundsError, ElementType, FieldDescription, TypeDescription};

/// A ROS 2 message type.
pub trait RosMessage:
    serde::Serialize
    + serde::de::DeserializeOwned
    + Clone
    + PartialEq
    + std::fmt::Debug
    + Default
    + Send
    + Sync
    + 'static
{
    /// ROS type name, `pkg/msg/Name` (`pkg/srv/Name_Request` for service halves).
    const ROS_NAME: &'static str;
    /// DDS type name as the ROS 2 RMWs register it, `pkg::msg::dds_::Name_`.
    const DDS_NAME: &'static str;
    /// The complete `ros2msg` definition (the type's file text, then its dependencies), as
    /// rosbag2 writes it into an MCAP schema record.
    const DEFINITION: &'static str;
    /// The RIHS01 type hash, as ROS 2 Jazzy computes it.
    const TYPE_HASH: &'static str;
    /// The field layout, for generic tools.
    const DESCRIPTION: &'static TypeDescription;
    /// Checks bounded strings and sequences against their bounds (recursively).
    fn check_bounds(&self) -> Result<(), BoundsError>;
}

/// A ROS 2 service type.
pub trait RosService: 'static {
    /// The request message (`pkg/srv/Name_Request`).
    type Request: RosMessage;
    /// The response message (`pkg/srv/Name_Response`).
    type Response: RosMessage;
    /// ROS type name, `pkg/srv/Name`.
    const ROS_NAME: &'static str;
    /// The RIHS01 type hash of the service, as ROS 2 Jazzy computes it.
    const TYPE_HASH: &'static str;
}

/// Receives every message type of the crate, one call per type (see [`visit_messages`]).
pub trait MessageVisitor {
    /// Called once for message type `T`.
    fn visit<T: RosMessage>(&mut self);
}

/// Receives every service type of the crate (see [`visit_services`]).
pub trait ServiceVisitor {
    /// Called once for service type `S`.
    fn visit<S: RosService>(&mut self);
}

include!(concat!(env!("OUT_DIR"), "/generated.rs"));

pub use self::composuite_msgs::{msg, srv};
