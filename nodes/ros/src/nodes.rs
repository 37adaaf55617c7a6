//! The suite's nodes by kind: their specs (name, help, parameters) and mains, shared by the
//! `*_node` binaries and `composuite launch` (which runs each node as `composuite node KIND`).
//! The kinds themselves are in `shared::node_kind`, where the interfaces the nodes serve can
//! name them without depending on the nodes.

use std::process::ExitCode;

use crate::shared::node::{NodeSpec, RosNode, run_node};
pub use crate::shared::node_kind::NodeKind;

/// A node's main loop: runs on a started node until the channel delivers a stop.
pub type NodeBody = fn(&mut RosNode, async_channel::Receiver<i32>) -> Result<(), String>;

impl NodeKind {
    /// `sim` / `task_manager` / `reward` / `recorder` (and `*_node`).
    pub fn parse(s: &str) -> Option<NodeKind> {
        NodeKind::ALL
            .into_iter()
            .chain([NodeKind::Recorder])
            .find(|k| s == k.name() || s == k.spec().binary)
    }

    /// Name, help text and parameters.
    pub fn spec(self) -> &'static NodeSpec {
        match self {
            NodeKind::Sim => &SIM,
            NodeKind::TaskManager => &TASK_MANAGER,
            NodeKind::Reward => &REWARD,
            NodeKind::Recorder => &RECORDER,
        }
    }

    /// Run the node with `argv` (the arguments after the program name) until a signal stops it.
    pub fn main(self, argv: &[String]) -> ExitCode {
        run_node(self.spec(), argv, self.body())
    }

    /// What the node does once started, until its channel delivers a stop (a signal number).
    pub fn body(self) -> NodeBody {
        match self {
            NodeKind::Sim => crate::sim::run,
            NodeKind::TaskManager => crate::task_manager::run,
            NodeKind::Reward => crate::reward::run,
            NodeKind::Recorder => crate::recorder::run,
        }
    }
}

const SIM: NodeSpec = NodeSpec {
    name: NodeKind::Sim.name(),
    binary: "sim_node",
    about: "CompoSuite-ROS sim node: owns the physics world of one environment; steps it on \
            joint_command or reference_action (lockstep) or on the wall clock (realtime); \
            publishes joint_states, observation, world_state, clock, tf (every link), \
            tf_static, robot_description, scene_markers and object_markers; serves the \
            standard simulation interfaces' state, stepping and entity services.",
    params: crate::sim::PARAMS,
};

const TASK_MANAGER: NodeSpec = NodeSpec {
    name: NodeKind::TaskManager.name(),
    binary: "task_manager_node",
    about: "CompoSuite-ROS task manager node: composes and publishes the scene (one per \
            episode), follows episodes and publishes episode; serves set_task, reset and \
            sample_tasks, and the standard simulation interfaces' reset and world services.",
    params: crate::task_manager::PARAMS,
};

const REWARD: NodeSpec = NodeSpec {
    name: NodeKind::Reward.name(),
    binary: "reward_node",
    about: "CompoSuite-ROS reward node: the staged reward of every step (from scene + \
            world_state) on reward, and the success flag on success.",
    params: crate::reward::PARAMS,
};

const RECORDER: NodeSpec = NodeSpec {
    name: NodeKind::Recorder.name(),
    binary: "recorder_node",
    about: "CompoSuite-ROS recorder node: records topics from the wire (all, a list or a \
            regex, as `ros2 bag record`) into a rosbag2 directory with MCAP storage: \
            metadata.yaml + <dir>_<N>.mcap, ros2msg schemas, zstd chunks. SIGINT/SIGTERM \
            close the bag; after a SIGKILL, `composuite bag reindex DIR` restores it.",
    params: crate::recorder::PARAMS,
};
