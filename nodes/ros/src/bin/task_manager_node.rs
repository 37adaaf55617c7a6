//! `task_manager_node`: see [`composuite_ros::task_manager`].

use composuite_ros::node::{NodeSpec, run_node};

const SPEC: NodeSpec = NodeSpec {
    name: "task_manager",
    binary: "task_manager_node",
    about: "CompoSuite-ROS task manager node: composes and publishes the scene (one per episode), follows episodes, publishes episode; serves set_task, reset, sample_tasks.",
    params: composuite_ros::task_manager::PARAMS,
};

fn main() -> std::process::ExitCode {
    run_node(&SPEC, composuite_ros::task_manager::run)
}
