//! Where the planned expert's episodes go: for each task and seed, the control step at which
//! each stage began, and for the episodes that fail, the stage they ended in. Meant for
//! finding what holds a task back (time run out mid-carry, no plan found, a grasp that
//! slipped) before changing the expert.
//!
//! ```text
//! cargo run --profile session -p composuite_core --example planned_stages -- [--seeds N] [--first S] [--threads T] [--all] TASK...
//! ```
//! Prints one line per failed episode (every episode with `--all`): task, seed, the stages
//! with the step each began at (`Approach@0 Descend@131 …`), then a count of the failures by
//! the stage they ended in and by task.

use std::collections::BTreeMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use composuite_core::env::{Env, EnvConfig};
use composuite_core::expert::{PlannedExpert, Stage as PlannedStage};
use composuite_core::{TaskSpec, all_tasks};

/// One episode: whether it succeeded, and each stage with the step it began at.
fn run(task: TaskSpec, seed: u64) -> (bool, Vec<(PlannedStage, u32)>) {
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    let mut expert = PlannedExpert::new(task);
    let mut timeline: Vec<(PlannedStage, u32)> = Vec::new();
    let (mut success, mut step) = (false, 0u32);
    while env.ended().is_none() {
        let action = expert.act(&env);
        // The stage the action was chosen in.
        if timeline.last().is_none_or(|(s, _)| *s != expert.stage()) {
            timeline.push((expert.stage(), step));
        }
        success |= env.step(&action).expect("step").info.success;
        step += 1;
    }
    (success, timeline)
}

fn main() {
    let (mut seeds, mut first) = (1u64, 0u64);
    let mut threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut every = false;
    let mut names = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = |flag: &str| -> u64 {
            let v = args
                .next()
                .unwrap_or_else(|| panic!("{flag} needs a number"));
            v.parse()
                .unwrap_or_else(|_| panic!("{flag} {v}: not a number"))
        };
        match arg.as_str() {
            "--seeds" => seeds = value("--seeds"),
            "--first" => first = value("--first"),
            "--threads" => threads = value("--threads") as usize,
            "--all" => every = true,
            _ => names.push(arg),
        }
    }
    let tasks: Vec<TaskSpec> = if names.is_empty() {
        all_tasks()
    } else {
        names
            .iter()
            .map(|n| n.parse().unwrap_or_else(|e| panic!("{n}: {e}")))
            .collect()
    };
    let jobs: Vec<(TaskSpec, u64)> = tasks
        .iter()
        .flat_map(|&t| (first..first + seeds).map(move |s| (t, s)))
        .collect();
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            scope.spawn(|| {
                while let Some(&(task, seed)) = jobs.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let (success, timeline) = run(task, seed);
                    results
                        .lock()
                        .unwrap()
                        .push((task.to_string(), seed, success, timeline));
                }
            });
        }
    });
    let mut results = results.into_inner().unwrap();
    results.sort_by(|a, b| (&a.0, a.1).cmp(&(&b.0, b.1)));
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
                .map_or("none".into(), |(s, _)| format!("{s:?}"));
            *by_stage.entry(last).or_default() += 1;
        }
        if every || !success {
            let stages: Vec<String> = timeline.iter().map(|(s, n)| format!("{s:?}@{n}")).collect();
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
