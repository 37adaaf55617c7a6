//! The QoS profiles of the suite's topics, named once (STYLE N8). They follow what ROS 2 nodes
//! use for each kind of topic; never KeepAll (ros2-client's KeepAll readers drop data).

use ros2_client::QosProfile;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};

/// Depth of rclcpp/rclpy's default profile (`rmw_qos_profile_default`).
pub const DEFAULT_DEPTH: usize = 10;

/// State and command topics (`joint_states`, `joint_command`, `observation`, `reward`, ...):
/// ROS's default — reliable, volatile, keep last 10.
pub fn state() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast {
            depth: DEFAULT_DEPTH,
        })
}

/// Latched configuration (`scene`, `robot_description`, `tf_static`, `scene_markers`): reliable,
/// transient local, keep last 1, so a late joiner (a recorder, RViz) gets the current value.
pub fn latched() -> QosProfile {
    state()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 })
}

/// `/clock` as ROS publishes it (rclcpp's `ClockQoS`): best effort, volatile, keep last 1 —
/// what rclpy's time source subscribes with.
pub fn clock() -> QosProfile {
    QosProfile::publisher_default()
        .reliability(Reliability::BestEffort)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 1 })
}

/// Services (`rmw_qos_profile_services_default`): reliable, volatile, keep last 10.
pub fn services() -> QosProfile {
    state()
}

/// Parameter services (`rmw_qos_profile_parameters`): reliable, volatile, keep last 1000.
pub fn parameter_services() -> QosProfile {
    state().history(History::KeepLast { depth: 1000 })
}
