//! `recorder_node`: the recorder node as its own binary (`--help` for its parameters).

fn main() -> std::process::ExitCode {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    composuite_ros::nodes::NodeKind::Recorder.main(&argv)
}
