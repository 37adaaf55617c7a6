//! The message definitions a bag embeds, looked up by ROS type name: every type the msgs crate
//! generates (its own and the standard ones the suite uses), with the `ros2msg` text rosbag2
//! stores and the RIHS01 hash. One source: the `.msg` files.

use std::collections::HashMap;
use std::sync::OnceLock;

use composuite_msgs::{MessageVisitor, RosMessage};

/// What a bag needs to know of a message type.
#[derive(Debug, Clone, Copy)]
pub struct Definition {
    /// The `ros2msg` schema text (the type's file, then its dependencies).
    pub definition: &'static str,
    /// `RIHS01_…`.
    pub type_hash: &'static str,
}

/// The definition of `type_name` (`pkg/msg/Name`), if the msgs crate has the type.
pub fn lookup(type_name: &str) -> Option<Definition> {
    static TABLE: OnceLock<HashMap<&'static str, Definition>> = OnceLock::new();
    TABLE
        .get_or_init(|| {
            struct Collect(HashMap<&'static str, Definition>);
            impl MessageVisitor for Collect {
                fn visit<T: RosMessage>(&mut self) {
                    self.0.insert(
                        T::ROS_NAME,
                        Definition {
                            definition: T::DEFINITION,
                            type_hash: T::TYPE_HASH,
                        },
                    );
                }
            }
            let mut collect = Collect(HashMap::new());
            composuite_msgs::visit_messages(&mut collect);
            collect.0
        })
        .get(type_name)
        .copied()
}

/// `pkg/msg/Name` from a DDS type name (`pkg::msg::dds_::Name_`), as the ROS 2 RMWs register
/// types; `None` for names that do not follow that convention.
pub fn ros_type_name(dds_name: &str) -> Option<String> {
    let mut parts = dds_name.split("::");
    let (package, kind, dds, name) = (parts.next()?, parts.next()?, parts.next()?, parts.next()?);
    if parts.next().is_some() || dds != "dds_" || package.is_empty() {
        return None;
    }
    let name = name.strip_suffix('_')?;
    (!name.is_empty()).then(|| format!("{package}/{kind}/{name}"))
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn every_suite_type_has_its_definition() {
        let obs = lookup("composuite_msgs/msg/Observation").unwrap();
        assert_eq!(
            obs.definition,
            composuite_msgs::msg::Observation::DEFINITION
        );
        assert!(obs.type_hash.starts_with("RIHS01_"));
        assert!(lookup("sensor_msgs/msg/JointState").is_some());
        assert!(lookup("acme_msgs/msg/Unknown").is_none());
    }

    #[test]
    fn dds_names_map_to_ros_names() {
        assert_eq!(
            ros_type_name("sensor_msgs::msg::dds_::JointState_").as_deref(),
            Some("sensor_msgs/msg/JointState")
        );
        assert_eq!(ros_type_name("DCPSParticipant"), None);
        assert_eq!(ros_type_name("a::msg::dds_::B"), None);
    }
}
