//! The kinds of node the suite runs, by name: what the node table (`crate::nodes`) and the
//! interfaces the nodes serve (`crate::simulation_interfaces`) both name.

use std::fmt;

/// One of the suite's nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeKind {
    /// Physics, joint states, observations.
    Sim,
    /// Scenes, episodes, services.
    TaskManager,
    /// Staged rewards and success.
    Reward,
    /// Records topics into a rosbag2 bag (not part of an environment: one per suite).
    Recorder,
}

impl NodeKind {
    /// Every node of an environment, in start order (the task manager's latched scene first).
    pub const ALL: [NodeKind; 3] = [NodeKind::TaskManager, NodeKind::Sim, NodeKind::Reward];

    /// The node's default name (`sim`, `task_manager`, `reward`, `recorder`).
    pub const fn name(self) -> &'static str {
        match self {
            NodeKind::Sim => "sim",
            NodeKind::TaskManager => "task_manager",
            NodeKind::Reward => "reward",
            NodeKind::Recorder => "recorder",
        }
    }
}

impl fmt::Display for NodeKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
