//! Build-time generator for the `composuite_msgs` crate.
//!
//! The `.msg` and `.srv` files are the single source of truth for every message layout. This
//! crate parses them ([`spec`]), resolves cross-references ([`Registry`]), and derives from them
//! everything the runtime needs: Rust types with CDR-compatible serde ([`rust`]), the full
//! definition text rosbag2 stores in MCAP ([`definition`]), and the RIHS01 type hash Jazzy
//! computes ([`type_hash`]). It is used from `msgs/build.rs` only; nothing here is linked into
//! the nodes.
#![warn(missing_docs)]

pub mod definition;
mod registry;
pub mod rust;
pub mod spec;
pub mod type_hash;

pub use registry::{LoadError, Registry};
