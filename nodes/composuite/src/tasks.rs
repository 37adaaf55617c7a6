//! `composuite tasks`: list the tasks, optionally filtered per axis, or draw a reference-identical
//! train/test split.

use clap::Args;
use composuite_core::prelude::*;
use composuite_core::sampling::{Experiment, Split, sample_tasks};
use serde_json::json;

/// List the 256 tasks (robot/object/obstacle/objective), in the suite's canonical order, or
/// draw a train/test split of them exactly as the reference benchmark's `sample_tasks` does.
///
/// Each filter takes any accepted spelling of its axis (wire names such as `Gen3`, `hollow_box`,
/// `object_wall`, `trash_can`, or the reference's `Kinova3`, `Hollowbox`, `ObjectWall`,
/// `Trashcan`), case-insensitively.
///
/// Splits (`--split`; the same seed gives the reference's lists, task for task):
///   default     the first N of the 256 shuffled tasks train, the rest test (N: 0 to 256)
///   smallscale  only the 64 tasks with --element, split the same way (N: 0 to 64)
///   holdout     N-1 tasks without --element, then one with it (last); the other 63 with it
///               test (N: 1 to 193)
///
/// Examples:
///   composuite tasks
///   composuite tasks --robot Panda --objective shelf
///   composuite tasks --obstacle none --json
///   composuite tasks --split default --num-train 56 --seed 42
///   composuite tasks --split holdout --num-train 10 --element Gen3 --seed 0 --json
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct TasksArgs {
    /// Only tasks with this robot (IIWA, Jaco, Gen3, Panda).
    #[arg(long, conflicts_with = "split")]
    robot: Option<String>,
    /// Only tasks with this object (box, hollow_box, plate, dumbbell).
    #[arg(long, conflicts_with = "split")]
    object: Option<String>,
    /// Only tasks with this obstacle (no_obstacle, object_wall, object_door, goal_wall).
    #[arg(long, conflicts_with = "split")]
    obstacle: Option<String>,
    /// Only tasks with this objective (pick_place, push, trash_can, shelf).
    #[arg(long, conflicts_with = "split")]
    objective: Option<String>,
    /// Draw a train/test split instead of listing: default, smallscale or holdout.
    #[arg(long, value_name = "EXPERIMENT")]
    split: Option<String>,
    /// Number of training tasks (default 0 to 256, smallscale 0 to 64, holdout 1 to 193).
    #[arg(long, value_name = "N", requires = "split")]
    num_train: Option<usize>,
    /// The element smallscale keeps or holdout holds out (any axis, any accepted spelling).
    #[arg(long, value_name = "E", requires = "split")]
    element: Option<String>,
    /// Shuffling seed (the reference's `shuffling_seed`); not needed with --no-shuffle.
    #[arg(long, value_name = "S", requires = "split")]
    seed: Option<u64>,
    /// Keep the reference's unshuffled task order.
    #[arg(long, requires = "split")]
    no_shuffle: bool,
    /// Print JSON: {"tasks": [{"task", "index", "reference_task_id", "reference"}, ...]}; with
    /// --split, {"train": ["robot/object/obstacle/objective", ...], "test": [...]}.
    #[arg(long)]
    json: bool,
}

fn parse_filter<E: AxisElement>(value: &Option<String>) -> Result<Option<E>, String> {
    value
        .as_deref()
        .map(E::parse)
        .transpose()
        .map_err(|e| e.to_string())
}

/// Keep the tasks whose elements match the given per-axis filters (any accepted spelling;
/// `None` keeps every element of that axis). Shared by the subcommands that select tasks.
pub fn filter_tasks(
    tasks: Vec<TaskSpec>,
    robot: &Option<String>,
    object: &Option<String>,
    obstacle: &Option<String>,
    objective: &Option<String>,
) -> Result<Vec<TaskSpec>, String> {
    let robot = parse_filter::<Robot>(robot)?;
    let object = parse_filter::<Object>(object)?;
    let obstacle = parse_filter::<Obstacle>(obstacle)?;
    let objective = parse_filter::<Objective>(objective)?;
    Ok(tasks
        .into_iter()
        .filter(|t| robot.is_none_or(|r| t.robot == r))
        .filter(|t| object.is_none_or(|o| t.object == o))
        .filter(|t| obstacle.is_none_or(|o| t.obstacle == o))
        .filter(|t| objective.is_none_or(|o| t.objective == o))
        .collect())
}

/// Run the subcommand.
pub fn run(args: &TasksArgs) -> Result<(), String> {
    if let Some(experiment) = &args.split {
        return run_split(args, experiment);
    }
    let tasks = filter_tasks(
        all_tasks(),
        &args.robot,
        &args.object,
        &args.obstacle,
        &args.objective,
    )?;
    if args.json {
        let rows: Vec<_> = tasks
            .iter()
            .map(|t| {
                json!({
                    "task": t.to_string(),
                    "index": t.task_index(),
                    "reference_task_id": t.reference_task_id(),
                    "reference": t.reference_names(),
                })
            })
            .collect();
        println!("{}", json!({ "tasks": rows }));
        return Ok(());
    }
    println!(
        "{:>5}  {:<38}  {:>6}  reference (robot, object, obstacle, objective)",
        "index", "task", "ref id"
    );
    for t in &tasks {
        println!(
            "{:>5}  {:<38}  {:>6}  {}",
            t.task_index(),
            t.to_string(),
            t.reference_task_id(),
            t.reference_names().join(", ")
        );
    }
    println!("{} task(s)", tasks.len());
    Ok(())
}

/// `--split`: draw the split and print it.
fn run_split(args: &TasksArgs, experiment: &str) -> Result<(), String> {
    let experiment = experiment
        .parse::<Experiment>()
        .map_err(|e| e.to_string())?;
    let range = experiment.num_train_range();
    let num_train = args.num_train.ok_or_else(|| {
        format!(
            "--split {experiment} needs --num-train N ({} to {})",
            range.start(),
            range.end()
        )
    })?;
    // The seed only drives the shuffle, so without one there is nothing to seed.
    let seed = match (args.seed, args.no_shuffle) {
        (Some(seed), _) => seed,
        (None, true) => 0,
        (None, false) => {
            return Err(format!(
                "--split {experiment} needs --seed S (or --no-shuffle for the reference order)"
            ));
        }
    };
    let split = sample_tasks(
        experiment,
        num_train,
        args.element.as_deref(),
        seed,
        args.no_shuffle,
    )
    .map_err(|e| e.to_string())?;
    if args.json {
        println!("{}", split_json(&split));
        return Ok(());
    }
    for (name, tasks) in [("train", &split.train), ("test", &split.test)] {
        println!("{name} ({} task(s)):", tasks.len());
        for t in tasks.iter() {
            println!("  {t}");
        }
    }
    Ok(())
}

/// `{"train": [...], "test": [...]}`, keys in that order (a `json!` map would sort them).
fn split_json(split: &Split) -> String {
    let names = |tasks: &[TaskSpec]| {
        serde_json::Value::from(tasks.iter().map(|t| t.to_string()).collect::<Vec<_>>())
    };
    format!(
        "{{\"train\":{},\"test\":{}}}",
        names(&split.train),
        names(&split.test)
    )
}
