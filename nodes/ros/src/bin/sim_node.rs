//! `sim_node`: the sim node as its own binary (`--help` for its parameters).

fn main() -> std::process::ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    composuite_ros::nodes::NodeKind::Sim.main(&argv)
}
