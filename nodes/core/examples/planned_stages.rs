//! Where the planned expert's episodes go: for each task and seed, the control step at which
//! each stage began, and for the episodes that fail, the stage they ended in. Meant for
//! finding what holds a task back (time run out mid-carry, no plan found, a grasp that
//! slipped) before changing the expert.
//!
//! ```text
//! cargo run --profile session -p composuite_core --example planned_stages -- [--seeds N] [--first S] [--threads T] [--all] TASK...
//! ```
//! Prints one line per failed episode (every episode with `--all`): task, seed, the stages
//! with the step each began at (`Approach@0 Descend@131 …`; each descent into a grasp with the
//! way the pads move into it, `Descend@131(+0.26,-0.97,+0.00)`), then a count of the failures
//! by the stage they ended in and by task.

use std::collections::BTreeMap;

use composuite_core::TaskSpec;
use composuite_core::env::{Env, EnvConfig};
use composuite_core::expert::{PlannedExpert, Stage as PlannedStage};

#[path = "common/episodes.rs"]
mod episodes;

/// One stage of an episode: the step it began at, and for a descent the grasp's heading.
type Began = (PlannedStage, u32, Option<[f64; 3]>);

/// One episode: whether it succeeded, and each stage as it began.
fn run(task: TaskSpec, seed: u64) -> (bool, Vec<Began>) {
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    let mut expert = PlannedExpert::new(task);
    let mut timeline: Vec<Began> = Vec::new();
    let (mut success, mut step) = (false, 0u32);
    while env.ended().is_none() {
        let action = expert.act(&env);
        // The stage the action was chosen in.
        let stage = expert.stage();
        if timeline.last().is_none_or(|(s, _, _)| *s != stage) {
            let heading = (stage == PlannedStage::Descend)
                .then(|| expert.grasp_heading())
                .flatten();
            timeline.push((stage, step, heading));
        }
        success |= env.step(&action).expect("step").info.success;
        step += 1;
    }
    (success, timeline)
}

fn main() {
    let episodes = episodes::from_args(&["--all"]);
    let every = !episodes.switches.is_empty();
    let results: Vec<_> = episodes
        .run(run)
        .into_iter()
        .map(|(task, seed, (success, timeline))| (task.to_string(), seed, success, timeline))
        .collect();
    let mut by_stage: BTreeMap<String, usize> = BTreeMap::new();
    let mut by_task: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    for (task, seed, success, timeline) in &results {
        let entry = by_task.entry(task).or_default();
        entry.1 += 1;
        if *success {
            entry.0 += 1;
        } else {
            let last = timeline
                .last()
                .map_or("none".into(), |(s, _, _)| format!("{s:?}"));
            *by_stage.entry(last).or_default() += 1;
        }
        if every || !success {
            let stages: Vec<String> = timeline
                .iter()
                .map(|(s, n, heading)| match heading {
                    Some([x, y, z]) => format!("{s:?}@{n}({x:+.2},{y:+.2},{z:+.2})"),
                    None => format!("{s:?}@{n}"),
                })
                .collect();
            let verdict = if *success { "success" } else { "FAIL" };
            println!("{task} seed {seed}: {verdict}: {}", stages.join(" "));
        }
    }
    println!("failures by the stage they ended in:");
    for (stage, n) in &by_stage {
        println!("  {stage}: {n}");
    }
    let solved: usize = by_task.values().map(|v| v.0).sum();
    println!(
        "{solved} of {} episodes succeeded; per task (successes/episodes), worst first:",
        results.len()
    );
    let mut tasks: Vec<_> = by_task.into_iter().collect();
    tasks.sort_by_key(|(_, (s, n))| (*s * 1000 / *n, *s));
    for (task, (s, n)) in tasks.iter().filter(|(_, (s, n))| s < n) {
        println!("  {task}: {s}/{n}");
    }
}
