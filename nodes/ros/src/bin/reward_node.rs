//! `reward_node`: see [`composuite_ros::reward`].

use composuite_ros::node::{NodeSpec, run_node};

const SPEC: NodeSpec = NodeSpec {
    name: "reward",
    binary: "reward_node",
    about: "CompoSuite-ROS reward node: the staged reward of every step (from scene + world_state) on reward, and success.",
    params: composuite_ros::reward::PARAMS,
};

fn main() -> std::process::ExitCode {
    run_node(&SPEC, composuite_ros::reward::run)
}
