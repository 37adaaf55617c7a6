//! `composuite expert`: run the scripted expert over tasks × seeds and write the feasibility
//! table (text, CSV, JSON) and a heatmap of success per task.

use std::io::Write as _;
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use clap::Args;
use composuite_core::axes::AxisElement;
use composuite_core::expert::{EpisodeOutcome, run_episode, run_planned_episode};
use composuite_core::{TaskSpec, all_tasks};
use serde_json::json;

/// Run the scripted expert over a set of tasks and seeds, headless, and report how often it
/// succeeds (success = reward 1 at any step of the episode).
///
/// Writes to --out: results.csv (one row per task), summary.txt (the table and per-axis
/// summaries) and success.png (four 8x8 heatmaps, one per robot in the order IIWA, Jaco,
/// Gen3, Panda; within one, row = 2*object + objective/2 and column = 2*obstacle +
/// objective%2 in the suite's axis orders; white = 0, green = 1, the rate written in each cell,
/// grey = not run; labelled with the robots, obstacles, objects and the objectives' places in
/// each 2x2 block).
///
/// Examples:
///   composuite expert --robot IIWA --object box --episodes 3
///   composuite expert --tasks all --episodes 10 --out expert-results --json
///   composuite expert --planned --objective pick_place --episodes 3
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct ExpertArgs {
    /// `all`, or one or more tasks robot/object/obstacle/objective (default: all, filtered by
    /// the axis options).
    #[arg(long, num_args = 1.., value_name = "TASK")]
    tasks: Vec<String>,
    /// Only this robot.
    #[arg(long)]
    robot: Option<String>,
    /// Only this object.
    #[arg(long)]
    object: Option<String>,
    /// Only this obstacle.
    #[arg(long)]
    obstacle: Option<String>,
    /// Only this objective.
    #[arg(long)]
    objective: Option<String>,
    /// Episodes (seeds 0..N) per task.
    #[arg(long, default_value_t = 10)]
    episodes: u64,
    /// Worker threads (default: the machine's cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Folder for results.csv, summary.txt and success.png.
    #[arg(long, default_value = "expert-results")]
    out: PathBuf,
    /// Run the planned expert instead (work in progress, issue 49): it acts as an agent does,
    /// with the reference's 8 numbers, on motions planned in joint space.
    #[arg(long)]
    planned: bool,
    /// Print JSON: {"mean_success", "expert_seconds_median", "expert_seconds_max", "tasks": [{"task", "success_rate", "mean_return", "mean_length"}, ...]}.
    #[arg(long)]
    json: bool,
}

/// One task's results.
struct TaskResult {
    task: TaskSpec,
    outcomes: Vec<EpisodeOutcome>,
}

impl TaskResult {
    fn success_rate(&self) -> f64 {
        self.outcomes.iter().filter(|o| o.success).count() as f64 / self.outcomes.len() as f64
    }
    fn mean_return(&self) -> f64 {
        self.outcomes.iter().map(|o| o.ret).sum::<f64>() / self.outcomes.len() as f64
    }
    fn mean_length(&self) -> f64 {
        self.outcomes
            .iter()
            .map(|o| f64::from(o.length))
            .sum::<f64>()
            / self.outcomes.len() as f64
    }
}

fn selected_tasks(args: &ExpertArgs) -> Result<Vec<TaskSpec>, String> {
    let explicit: Vec<&String> = args.tasks.iter().filter(|t| t.as_str() != "all").collect();
    let base: Vec<TaskSpec> = if explicit.is_empty() {
        all_tasks()
    } else {
        explicit
            .iter()
            .map(|t| t.parse::<TaskSpec>().map_err(|e| e.to_string()))
            .collect::<Result<_, _>>()?
    };
    let tasks = crate::tasks::filter_tasks(
        base,
        &args.robot,
        &args.object,
        &args.obstacle,
        &args.objective,
    )?;
    if tasks.is_empty() {
        return Err("no task matches the given --tasks and axis filters".into());
    }
    Ok(tasks)
}

/// Run the subcommand.
pub fn run(args: &ExpertArgs) -> Result<(), String> {
    if args.episodes == 0 {
        return Err("--episodes must be at least 1".into());
    }
    let tasks = selected_tasks(args)?;
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;

    // Work items: (task index, seed); results gathered per task in the original order.
    let jobs: Vec<(usize, u64)> = (0..tasks.len())
        .flat_map(|t| (0..args.episodes).map(move |s| (t, s)))
        .collect();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Vec<(u64, EpisodeOutcome)>>> = Mutex::new(vec![Vec::new(); tasks.len()]);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(t, seed)) = jobs.get(i) else { break };
                    let outcome = if args.planned {
                        run_planned_episode(tasks[t], seed)
                    } else {
                        run_episode(tasks[t], seed)
                    };
                    results
                        .lock()
                        .expect("no worker panics while holding the lock")[t]
                        .push((seed, outcome));
                    let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                    if finished.is_multiple_of(10) || finished == jobs.len() {
                        eprint!("\rexpert: {finished}/{} episodes", jobs.len());
                        let _ = std::io::stderr().flush();
                    }
                }
            });
        }
    });
    eprintln!();
    let results: Vec<TaskResult> = results
        .into_inner()
        .expect("workers finished")
        .into_iter()
        .zip(&tasks)
        .map(|(mut per_seed, task)| {
            per_seed.sort_by_key(|(seed, _)| *seed);
            TaskResult {
                task: *task,
                outcomes: per_seed.into_iter().map(|(_, o)| o).collect(),
            }
        })
        .collect();
    let mean_success =
        results.iter().map(TaskResult::success_rate).sum::<f64>() / results.len() as f64;

    write_csv(&args.out, &results)?;
    let summary = summary_text(&results, mean_success, args.episodes);
    std::fs::write(args.out.join("summary.txt"), &summary).map_err(|e| e.to_string())?;
    crate::plots::success_heatmap(
        &args.out.join("success.png"),
        if args.planned {
            "Planned expert: success rate per task"
        } else {
            "Scripted expert: success rate per task"
        },
        &|task| {
            results
                .iter()
                .find(|r| r.task == task)
                .map(TaskResult::success_rate)
        },
    )?;
    if args.json {
        let rows: Vec<_> = results
            .iter()
            .map(|r| {
                json!({"task": r.task.to_string(), "success_rate": r.success_rate(),
                       "mean_return": r.mean_return(), "mean_length": r.mean_length()})
            })
            .collect();
        let (median, max) = expert_seconds(&results);
        println!(
            "{}",
            json!({"mean_success": mean_success, "expert_seconds_median": median,
                   "expert_seconds_max": max, "tasks": rows})
        );
    } else {
        print!("{summary}");
        println!(
            "wrote {}/results.csv, summary.txt, success.png",
            args.out.display()
        );
    }
    Ok(())
}

fn write_csv(out: &std::path::Path, results: &[TaskResult]) -> Result<(), String> {
    let mut text = String::from(
        "task,robot,object,obstacle,objective,episodes,success_rate,mean_return,mean_length\n",
    );
    for r in results {
        let t = r.task;
        text.push_str(&format!(
            "{},{},{},{},{},{},{:.4},{:.4},{:.1}\n",
            t,
            t.robot.wire_name(),
            t.object.wire_name(),
            t.obstacle.wire_name(),
            t.objective.wire_name(),
            r.outcomes.len(),
            r.success_rate(),
            r.mean_return(),
            r.mean_length()
        ));
    }
    std::fs::write(out.join("results.csv"), text).map_err(|e| e.to_string())
}

/// The median and the largest time (s) the expert spent choosing an episode's actions.
fn expert_seconds(results: &[TaskResult]) -> (f64, f64) {
    let mut times: Vec<f64> = results
        .iter()
        .flat_map(|r| r.outcomes.iter().map(|o| o.expert_seconds))
        .collect();
    times.sort_by(f64::total_cmp);
    let median = times.get(times.len() / 2).copied().unwrap_or(0.0);
    (median, times.last().copied().unwrap_or(0.0))
}

fn summary_text(results: &[TaskResult], mean_success: f64, episodes: u64) -> String {
    let mut s = format!(
        "{:<42} {:>8} {:>8} {:>8}\n",
        "task", "success", "return", "length"
    );
    for r in results {
        s.push_str(&format!(
            "{:<42} {:>8.2} {:>8.1} {:>8.1}\n",
            r.task.to_string(),
            r.success_rate(),
            r.mean_return(),
            r.mean_length()
        ));
    }
    s.push_str(&format!(
        "\n{} task(s) x {episodes} episode(s): mean success {mean_success:.3}\n",
        results.len()
    ));
    let mut axis = |name: &str, key: &dyn Fn(&TaskSpec) -> &'static str| {
        let mut groups: Vec<(&'static str, f64, usize)> = Vec::new();
        for r in results {
            let k = key(&r.task);
            match groups.iter_mut().find(|g| g.0 == k) {
                Some(g) => {
                    g.1 += r.success_rate();
                    g.2 += 1;
                }
                None => groups.push((k, r.success_rate(), 1)),
            }
        }
        let cells: Vec<String> = groups
            .iter()
            .map(|(k, sum, n)| format!("{k} {:.2}", sum / *n as f64))
            .collect();
        s.push_str(&format!("by {name}: {}\n", cells.join(", ")));
    };
    axis("robot", &|t| t.robot.wire_name());
    axis("object", &|t| t.object.wire_name());
    axis("obstacle", &|t| t.obstacle.wire_name());
    axis("objective", &|t| t.objective.wire_name());
    let (median, max) = expert_seconds(results);
    s.push_str(&format!(
        "expert time per episode (choosing actions, planning included): median {:.0} ms, max {:.0} ms\n",
        1e3 * median,
        1e3 * max
    ));
    let weak: Vec<String> = results
        .iter()
        .filter(|r| r.success_rate() < 0.5)
        .map(|r| format!("{} ({:.2})", r.task, r.success_rate()))
        .collect();
    s.push_str(&format!(
        "below 0.5: {}\n",
        if weak.is_empty() {
            "none".to_string()
        } else {
            weak.join(", ")
        }
    ));
    s
}
