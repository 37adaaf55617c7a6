//! rosbag2 bags in MCAP storage, as ROS 2 Jazzy writes them: the writer the recorder node uses,
//! the reader and reindexer of the `composuite bag` tools, and `metadata.yaml`. No DDS here.
//! What the format requires, and why each choice was made: docs/src/rosbag2-format.md.

pub mod definitions;
pub mod metadata;
pub mod qos;
pub mod reader;
pub mod writer;

pub use metadata::{BagMetadata, FileInfo, TopicInfo};
pub use qos::OfferedQos;
pub use writer::{BagError, BagOptions, BagWriter, TopicId};

#[cfg(test)]
mod test;
