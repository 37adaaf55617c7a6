//! `composuite`: the user-facing command of CompoSuite-ROS. Subcommands grow with the suite;
//! today it lists the 256 tasks and their reference splits, and times whole tasks.

mod bench;
mod expert;
mod tasks;

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
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Tasks(args) => tasks::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Expert(args) => expert::run(&args),
    };
    if let Err(message) = result {
        eprintln!("composuite: {message}");
        std::process::exit(2);
    }
}
