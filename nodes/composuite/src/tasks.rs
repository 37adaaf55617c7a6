//! `composuite tasks`: list the tasks, optionally filtered per axis.

use clap::Args;
use composuite_core::prelude::*;
use serde_json::json;

/// List the 256 tasks (robot/object/obstacle/objective), in the suite's canonical order.
///
/// Each filter takes any accepted spelling of its axis (wire names such as `Gen3`, `hollow_box`,
/// `object_wall`, `trash_can`, or the reference's `Kinova3`, `Hollowbox`, `ObjectWall`,
/// `Trashcan`), case-insensitively.
///
/// Examples:
///   composuite tasks
///   composuite tasks --robot Panda --objective shelf
///   composuite tasks --obstacle none --json
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct TasksArgs {
    /// Only tasks with this robot (IIWA, Jaco, Gen3, Panda).
    #[arg(long)]
    robot: Option<String>,
    /// Only tasks with this object (box, hollow_box, plate, dumbbell).
    #[arg(long)]
    object: Option<String>,
    /// Only tasks with this obstacle (no_obstacle, object_wall, object_door, goal_wall).
    #[arg(long)]
    obstacle: Option<String>,
    /// Only tasks with this objective (pick_place, push, trash_can, shelf).
    #[arg(long)]
    objective: Option<String>,
    /// Print JSON: {"tasks": [{"task", "index", "reference_task_id", "reference"}, ...]}.
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

/// Run the subcommand.
pub fn run(args: &TasksArgs) -> Result<(), String> {
    let robot = parse_filter::<Robot>(&args.robot)?;
    let object = parse_filter::<Object>(&args.object)?;
    let obstacle = parse_filter::<Obstacle>(&args.obstacle)?;
    let objective = parse_filter::<Objective>(&args.objective)?;
    let tasks: Vec<TaskSpec> = all_tasks()
        .into_iter()
        .filter(|t| robot.is_none_or(|r| t.robot == r))
        .filter(|t| object.is_none_or(|o| t.object == o))
        .filter(|t| obstacle.is_none_or(|o| t.obstacle == o))
        .filter(|t| objective.is_none_or(|o| t.objective == o))
        .collect();
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
