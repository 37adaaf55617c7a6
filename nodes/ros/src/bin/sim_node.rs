//! `sim_node`: see [`composuite_ros::sim`].

use composuite_ros::node::{NodeSpec, run_node};

const SPEC: NodeSpec = NodeSpec {
    name: "sim",
    binary: "sim_node",
    about: "CompoSuite-ROS sim node: owns the physics world of one environment; steps it on joint_command (lockstep) or on the wall clock (realtime); publishes joint_states, observation, world_state, clock, tf, robot_description.",
    params: composuite_ros::sim::PARAMS,
};

fn main() -> std::process::ExitCode {
    run_node(&SPEC, composuite_ros::sim::run)
}
