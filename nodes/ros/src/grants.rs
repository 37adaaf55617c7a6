//! What each of the suite's nodes, and an agent of one environment, needs on the wire: the DDS
//! topic names (with `*` wildcards) it publishes and subscribes to, for DDS-Security
//! permissions that allow exactly that (`composuite security create-enclave --grant`). Built
//! from the same name constants and interface table the nodes create their endpoints from; the
//! secured tests start every node in an enclave of its own grant, under Enforce, and play an
//! episode through them (a missing entry stops the node that needs it).
//!
//! On the wire a ROS topic `/ns/name` is `rt/ns/name`; a service's request and reply
//! `rq/ns/nameRequest` and `rr/ns/nameReply`; an action `/ns/a` is the services
//! `a/_action/{send_goal,get_result,cancel_goal}` and the topics `a/_action/{feedback,status}`.

use crate::shared::names;
use crate::shared::node_kind::NodeKind;
use crate::simulation_interfaces::INTERFACES;

/// Who a grant is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// One of the suite's nodes.
    Node(NodeKind),
    /// `composuite play`: publishes the recorded topics again.
    Player,
    /// An agent of the environment: commands it, resets it, reads all it publishes; cannot
    /// publish what the suite publishes (observations, rewards, the scene, ...).
    Agent,
}

impl Role {
    /// The roles by name, as `--grant` takes them.
    pub const NAMES: [&'static str; 6] = [
        "sim",
        "task_manager",
        "reward",
        "recorder",
        "player",
        "agent",
    ];

    /// The role named `name` (one of [`Role::NAMES`]).
    pub fn parse(name: &str) -> Option<Role> {
        Some(match name {
            "sim" => Role::Node(NodeKind::Sim),
            "task_manager" => Role::Node(NodeKind::TaskManager),
            "reward" => Role::Node(NodeKind::Reward),
            "recorder" => Role::Node(NodeKind::Recorder),
            "player" => Role::Player,
            "agent" => Role::Agent,
            _ => return None,
        })
    }
}

/// The DDS topics a role may publish and subscribe to.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Topics {
    /// Topics it may write.
    pub publish: Vec<String>,
    /// Topics it may read.
    pub subscribe: Vec<String>,
}

/// The parameter services every node serves under its own name.
const PARAMETER_SERVICES: [&str; 6] = [
    "describe_parameters",
    "get_parameter_types",
    "get_parameters",
    "list_parameters",
    "set_parameters",
    "set_parameters_atomically",
];

/// The services of an action, relative to it.
const ACTION_SERVICES: [&str; 3] = ["send_goal", "get_result", "cancel_goal"];
/// The topics of an action, relative to it.
const ACTION_TOPICS: [&str; 2] = ["feedback", "status"];

/// The commands an agent may send the sim.
const COMMANDS: [&str; 6] = [
    names::JOINT_COMMAND,
    names::REFERENCE_ACTION,
    names::REFERENCE_ACTION_STAMPED,
    names::GRIPPER_COMMAND,
    names::FORWARD_COMMANDS,
    names::TRAJECTORY_TOPIC,
];

/// The services (not actions) `kind` serves, relative to the namespace.
fn services(kind: NodeKind) -> Vec<&'static str> {
    let own: &[&str] = match kind {
        NodeKind::Sim => &[names::LIST_CONTROLLERS, names::LIST_HARDWARE_INTERFACES],
        NodeKind::TaskManager => &[names::RESET, names::SET_TASK, names::SAMPLE_TASKS],
        NodeKind::Reward | NodeKind::Recorder => &[],
    };
    let standard = INTERFACES
        .iter()
        .filter(|i| i.node == kind && i.type_name.contains("/srv/"))
        .map(|i| i.name);
    own.iter().copied().chain(standard).collect()
}

/// The actions `kind` serves, relative to the namespace.
fn actions(kind: NodeKind) -> Vec<&'static str> {
    let own: &[&str] = match kind {
        NodeKind::Sim => &[names::TRAJECTORY_ACTION, names::GRIPPER_ACTION],
        _ => &[],
    };
    let standard = INTERFACES
        .iter()
        .filter(|i| i.node == kind && i.type_name.contains("/action/"))
        .map(|i| i.name);
    own.iter().copied().chain(standard).collect()
}

/// `prefix` + the namespace + `/name` (the root namespace adds nothing).
fn wire(prefix: &str, namespace: &str, name: &str) -> String {
    format!("{prefix}{}/{name}", namespace.trim_end_matches('/'))
}

impl Topics {
    /// `topic` added to `list` unless it is there already: the permissions name each once.
    fn add(list: &mut Vec<String>, topic: String) {
        if !list.contains(&topic) {
            list.push(topic);
        }
    }

    /// Publishing ROS topic `name` of `namespace`.
    pub fn publish_topic(&mut self, namespace: &str, name: &str) {
        Self::add(&mut self.publish, wire("rt", namespace, name));
    }

    /// Subscribing to ROS topic `name` of `namespace`.
    pub fn subscribe_topic(&mut self, namespace: &str, name: &str) {
        Self::add(&mut self.subscribe, wire("rt", namespace, name));
    }

    /// Serving `service` of `namespace`: its requests in, its replies out.
    pub fn serve(&mut self, namespace: &str, service: &str) {
        Self::add(
            &mut self.subscribe,
            wire("rq", namespace, &format!("{service}Request")),
        );
        Self::add(
            &mut self.publish,
            wire("rr", namespace, &format!("{service}Reply")),
        );
    }

    /// Calling `service` of `namespace`: its requests out, its replies in.
    pub fn call(&mut self, namespace: &str, service: &str) {
        Self::add(
            &mut self.publish,
            wire("rq", namespace, &format!("{service}Request")),
        );
        Self::add(
            &mut self.subscribe,
            wire("rr", namespace, &format!("{service}Reply")),
        );
    }

    /// Serving `action` of `namespace`: its services, and its feedback and status out.
    pub fn serve_action(&mut self, namespace: &str, action: &str) {
        for service in ACTION_SERVICES {
            self.serve(namespace, &format!("{action}/_action/{service}"));
        }
        for name in ACTION_TOPICS {
            self.publish_topic(namespace, &format!("{action}/_action/{name}"));
        }
    }

    /// Calling `action` of `namespace`: its services, and its feedback and status in.
    pub fn call_action(&mut self, namespace: &str, action: &str) {
        for service in ACTION_SERVICES {
            self.call(namespace, &format!("{action}/_action/{service}"));
        }
        for name in ACTION_TOPICS {
            self.subscribe_topic(namespace, &format!("{action}/_action/{name}"));
        }
    }

    /// What every ROS node has: the log, parameter events, and its parameter services (under
    /// `node` in `namespace`, or under any name for `node = "*"`).
    pub fn ros_node(&mut self, namespace: &str, node: &str) {
        self.publish_topic("/", "rosout");
        self.publish_topic("/", "parameter_events");
        for service in PARAMETER_SERVICES {
            if node == "*" {
                Self::add(&mut self.subscribe, format!("rq/*/{service}Request"));
                Self::add(&mut self.publish, format!("rr/*/{service}Reply"));
            } else {
                self.serve(namespace, &format!("{node}/{service}"));
            }
        }
    }

    /// `other`'s topics added, each once, in the order first named.
    pub fn merge(&mut self, other: Topics) {
        for topic in other.publish {
            Self::add(&mut self.publish, topic);
        }
        for topic in other.subscribe {
            Self::add(&mut self.subscribe, topic);
        }
    }
}

/// What `role` needs in the environment in `namespace` (absolute, `/` for the root).
pub fn grant(role: Role, namespace: &str) -> Topics {
    let mut t = Topics::default();
    match role {
        Role::Node(kind) => {
            t.ros_node(namespace, kind.name());
            if kind == NodeKind::Recorder {
                // `composuite launch --record` runs it in the root namespace, whatever the
                // environments' are.
                t.ros_node("/", kind.name());
            }
            let (publish, subscribe): (Vec<&str>, Vec<&str>) = match kind {
                NodeKind::Sim => (
                    vec![
                        names::CLOCK,
                        names::JOINT_STATES,
                        names::OBSERVATION,
                        names::WORLD_STATE,
                        names::TF,
                        names::TF_STATIC,
                        names::ROBOT_DESCRIPTION,
                        names::SCENE_MARKERS,
                        names::OBJECT_MARKERS,
                        // Every camera's image_raw and camera_info.
                        "camera/*",
                    ],
                    COMMANDS.into_iter().chain([names::SCENE]).collect(),
                ),
                NodeKind::TaskManager => (
                    vec![names::EPISODE, names::SCENE],
                    vec![names::OBSERVATION, names::WORLD_STATE],
                ),
                NodeKind::Reward => (
                    vec![names::REWARD, names::SUCCESS],
                    vec![names::SCENE, names::WORLD_STATE],
                ),
                // It records whatever its regex picks, in any namespace (below).
                NodeKind::Recorder => (vec![], vec![]),
            };
            for name in publish {
                t.publish_topic(namespace, name);
            }
            for name in subscribe {
                t.subscribe_topic(namespace, name);
            }
            if kind == NodeKind::Recorder {
                t.subscribe_topic("/", "*");
            }
            for service in services(kind) {
                t.serve(namespace, service);
            }
            for action in actions(kind) {
                t.serve_action(namespace, action);
            }
        }
        Role::Player => {
            t.ros_node(namespace, "*");
            t.publish_topic(namespace, "*");
        }
        Role::Agent => {
            t.ros_node(namespace, "*");
            for name in COMMANDS {
                t.publish_topic(namespace, name);
            }
            for kind in [NodeKind::Sim, NodeKind::TaskManager] {
                for service in services(kind) {
                    t.call(namespace, service);
                }
                for action in actions(kind) {
                    for service in ACTION_SERVICES {
                        t.call(namespace, &format!("{action}/_action/{service}"));
                    }
                }
            }
            // Everything the environment publishes, parameter events included.
            t.subscribe_topic(namespace, "*");
            t.subscribe_topic("/", "parameter_events");
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sim's grant in a namespace: its outputs and the agents' commands as topics, its
    /// services and actions as the request/reply and action topics their servers use.
    #[test]
    fn the_sims_grant_names_its_topics_services_and_actions_on_the_wire() {
        let t = grant(Role::Node(NodeKind::Sim), "/env_00");
        for p in [
            "rt/env_00/observation",
            "rt/env_00/camera/*",
            "rr/env_00/step_simulationReply",
            "rr/env_00/sim/get_parametersReply",
            "rt/env_00/simulate_steps/_action/status",
            "rr/env_00/joint_trajectory_controller/follow_joint_trajectory/_action/send_goalReply",
            "rt/rosout",
        ] {
            assert!(
                t.publish.iter().any(|x| x == p),
                "publish {p}: {:?}",
                t.publish
            );
        }
        for s in [
            "rt/env_00/joint_command",
            "rt/env_00/scene",
            "rq/env_00/step_simulationRequest",
        ] {
            assert!(t.subscribe.iter().any(|x| x == s), "subscribe {s}");
        }
        assert!(!t.publish.iter().any(|x| x.contains("resetReply")));
    }

    /// In the root namespace names get no extra `/`; the agent commands and calls but publishes
    /// none of the suite's outputs or replies.
    #[test]
    fn an_agent_commands_and_calls_but_cannot_speak_for_the_suite() {
        let t = grant(Role::Agent, "/");
        assert!(t.publish.contains(&"rt/joint_command".to_string()));
        assert!(t.publish.contains(&"rq/resetRequest".to_string()));
        assert!(t.subscribe.contains(&"rt/*".to_string()));
        assert!(t.subscribe.contains(&"rr/resetReply".to_string()));
        for suite_only in ["rt/observation", "rt/reward", "rt/scene", "rr/resetReply"] {
            assert!(!t.publish.iter().any(|x| x == suite_only), "{suite_only}");
        }
        assert!(t.publish.iter().all(|x| !x.starts_with("rt/*")));
    }

    #[test]
    fn every_role_name_parses() {
        for name in Role::NAMES {
            assert!(Role::parse(name).is_some(), "{name}");
        }
        assert_eq!(Role::parse("simulator"), None);
    }
}
