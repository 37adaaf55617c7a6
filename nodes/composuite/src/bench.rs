//! `composuite bench`: in-process speed of whole tasks, measured like the reference was
//! (docs/src/reference-speed.md): random actions, a reset every 500 steps, one core.

use std::time::Instant;

use clap::Args;
use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use rand::{Rng, SeedableRng};
use serde_json::json;

/// The four tasks the reference was timed on.
const REFERENCE_TASKS: [&str; 4] = [
    "IIWA/box/no_obstacle/pick_place",
    "Jaco/dumbbell/object_door/shelf",
    "Panda/plate/goal_wall/trash_can",
    "Gen3/hollow_box/object_wall/push",
];

/// Measure env steps/s, reset time and memory on whole tasks.
///
/// Per task: a warm-up episode, then `--steps` steps of uniform random reference actions with a
/// reset every `--horizon` steps (and whenever an episode ends early), on this thread only.
/// Reports steps per second (time inside `step` only), the median reset time, and the process's
/// peak resident memory.
///
/// Examples:
///   composuite bench
///   composuite bench --tasks Panda/box/no_obstacle/push --steps 5000 --json
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct BenchArgs {
    /// Tasks to time (robot/object/obstacle/objective); default: the reference's four.
    #[arg(long, num_args = 1.., value_name = "TASK")]
    tasks: Vec<String>,
    /// Steps timed per task.
    #[arg(long, default_value_t = 2000)]
    steps: u32,
    /// Reset every this many steps.
    #[arg(long, default_value_t = 500)]
    horizon: u32,
    /// Print JSON: [{"task", "steps_per_s", "reset_us", "rss_mb"}, ...].
    #[arg(long)]
    json: bool,
}

/// Peak resident set size of this process (MB), from /proc.
fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .map(str::to_owned)
        })
        .and_then(|l| {
            l.split_whitespace()
                .nth(1)
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// Run the subcommand.
pub fn run(args: &BenchArgs) -> Result<(), String> {
    if args.steps == 0 || args.horizon == 0 {
        return Err("--steps and --horizon must be at least 1".into());
    }
    let names: Vec<String> = if args.tasks.is_empty() {
        REFERENCE_TASKS.iter().map(|s| s.to_string()).collect()
    } else {
        args.tasks.clone()
    };
    let tasks: Vec<TaskSpec> = names
        .iter()
        .map(|n| n.parse::<TaskSpec>().map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()?;
    if !args.json {
        println!(
            "{:<40} {:>12} {:>12} {:>10}",
            "task", "steps/s", "reset (us)", "RSS (MB)"
        );
    }
    let mut rows = Vec::new();
    for task in tasks {
        let config = EnvConfig::default().horizon(args.horizon);
        let mut env = Env::new(task, config);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
        let mut action = || Action::Reference(std::array::from_fn(|_| rng.random_range(-1.0..1.0)));
        // Warm-up: one short episode (shorter when the horizon is).
        env.reset(0).map_err(|e| e.to_string())?;
        for _ in 0..20 {
            if env.ended().is_some() {
                break;
            }
            env.step(&action()).map_err(|e| e.to_string())?;
        }
        let mut resets = Vec::new();
        let mut seed = 1;
        let mut in_step = 0.0;
        let t = Instant::now();
        env.reset(seed).map_err(|e| e.to_string())?;
        resets.push(t.elapsed().as_secs_f64());
        for _ in 0..args.steps {
            if env.ended().is_some() {
                seed += 1;
                let t = Instant::now();
                env.reset(seed).map_err(|e| e.to_string())?;
                resets.push(t.elapsed().as_secs_f64());
            }
            let a = action();
            let t = Instant::now();
            env.step(&a).map_err(|e| e.to_string())?;
            in_step += t.elapsed().as_secs_f64();
        }
        resets.sort_by(f64::total_cmp);
        let steps_per_s = f64::from(args.steps) / in_step;
        let reset_us = resets[resets.len() / 2] * 1e6;
        let rss = peak_rss_mb();
        if !args.json {
            println!(
                "{:<40} {:>12.0} {:>12.1} {:>10.1}",
                task.to_string(),
                steps_per_s,
                reset_us,
                rss
            );
        }
        rows.push(json!({"task": task.to_string(), "steps_per_s": steps_per_s, "reset_us": reset_us, "rss_mb": rss}));
    }
    if args.json {
        println!("{}", serde_json::Value::Array(rows));
    }
    Ok(())
}
