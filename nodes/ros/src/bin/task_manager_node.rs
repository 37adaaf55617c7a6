//! `task_manager_node`: the task_manager node as its own binary (`--help` for its parameters).

fn main() -> std::process::ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    composuite_ros::nodes::NodeKind::TaskManager.main(&argv)
}
