//! `composuite`: the user-facing command of CompoSuite-ROS. It lists the 256 tasks and the
//! reference's train/test splits (`tasks`), times whole tasks in process (`bench`), runs the
//! scripted expert over tasks and seeds (`expert`), starts the ROS 2 node suite (`launch`; one
//! node: `node`), drives the suite with a built-in policy (`demo`) or records that as a session
//! (`session`), and reads, checks, exports and plays recorded bags (`bag`). Every subcommand, with
//! an example: docs/src/getting-started.md.

mod bag;
mod bag_render;
mod bench;
mod demo;
mod drive;
mod expert;
mod export;
mod launch;
mod play;
mod plots;
mod replay;
mod security;
mod session;
mod tasks;
mod topics;
mod video;

use clap::{Parser, Subcommand};

/// CompoSuite-ROS: the 256 compositional manipulation tasks of CompoSuite
/// (robot × object × obstacle × objective), simulated in Rust and served over ROS 2.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Tasks(tasks::TasksArgs),
    Bench(bench::BenchArgs),
    Expert(expert::ExpertArgs),
    Launch(Box<launch::LaunchArgs>),
    Demo(demo::DemoArgs),
    Session(session::SessionArgs),
    Bag(bag::BagArgs),
    Security(security::SecurityArgs),
    /// Run one node of the suite (what `launch` starts): `composuite node sim --ros-args ...`.
    #[command(hide = true, disable_help_flag = true)]
    Node {
        /// sim, task_manager, reward or recorder.
        kind: String,
        /// The node's arguments (`--ros-args ...`, `--help`).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

fn main() -> std::process::ExitCode {
    let node = std::env::args().nth(1).as_deref() == Some("node");
    if !node {
        end_quietly_when_stdout_closes();
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Node { kind, args } => {
            return match composuite_ros::nodes::NodeKind::parse(&kind) {
                Some(kind) => kind.main(&args),
                None => {
                    eprintln!(
                        "composuite node: `{kind}` is no node; valid: sim, task_manager, reward, recorder"
                    );
                    std::process::ExitCode::from(2)
                }
            };
        }
        Command::Launch(args) => launch::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Bag(args) => bag::run(&args),
        Command::Security(args) => security::run(&args),
        Command::Session(args) => session::run(&args),
        Command::Tasks(args) => tasks::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Expert(args) => expert::run(&args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("composuite: {message}");
            std::process::ExitCode::from(2)
        }
    }
}

/// A reader that stops early (`composuite tasks | head -1`) closes our stdout. Rust ignores
/// SIGPIPE, so the next `println!` would panic with a backtrace; with the default action the
/// command ends quietly, as every Unix filter does. Nodes keep Rust's behaviour: a node must not
/// die because whoever watched its output went away.
fn end_quietly_when_stdout_closes() {
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
