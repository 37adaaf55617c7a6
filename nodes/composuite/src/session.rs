//! `composuite session`: one headless, recorded session. It launches one lockstep environment
//! and the recorder, drives tasks × episodes with a built-in policy through the ROS interfaces
//! (see `drive`), and leaves in `--out`: the rosbag2 bag of everything on the wire (`bag/`),
//! the per-episode table as CSV and JSON, PNG plots (staged reward per episode, success per
//! task), and a printed summary; with `--video`, a video of each episode rendered from the bag
//! (`videos/`, see [`crate::bag_render`]).

use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use clap::Args;
use composuite_core::TaskSpec;

use crate::bag::{Episode, episodes_csv};
use composuite_ros::shared::node::shutdown_signal;

use crate::drive::{Driven, EpisodeOutcome, Plan, PolicyKind, drive};
use crate::launch::{LaunchArgs, Suite};

/// Run a recorded headless session: the suite, the recorder, and a built-in policy as the agent.
///
/// Launches one lockstep environment (task_manager, sim, reward) and the recorder, then plays
/// every --tasks × --episodes (seeds --seed, --seed+1, ...) with --policy over ROS 2 (set_task,
/// reset, joint_command; observation, reward, episode). Writes into --out: `bag/` (rosbag2,
/// MCAP: every topic, the agent's commands included), `episodes.csv` and `episodes.json` (task,
/// seed, length, return, success, furthest stage per episode), `rewards.png` (each episode's
/// staged reward over time) and `success.png` (success per task), and prints a summary. Every
/// observation is checked against the in-process environment given the same commands. With
/// --video, `videos/episode_<n>.gif` (or .mp4) per episode, drawn from the bag alone.
///
/// Examples:
///   composuite session
///   composuite session --episodes 2 --video --video-camera agentview
///   composuite session --tasks IIWA/box/no_obstacle/pick_place Jaco/plate/goal_wall/push
///       --episodes 5 --policy random --out runs/random
#[derive(Args, Debug)]
pub struct SessionArgs {
    /// Tasks, robot/object/obstacle/objective, played in order.
    #[arg(long, num_args = 1.., default_values_t = [composuite_ros::task_manager::DEFAULT_TASK.to_string()])]
    tasks: Vec<String>,
    /// Episodes per task.
    #[arg(long, default_value_t = 3)]
    episodes: u32,
    /// The agent: expert (the scripted expert, absolute joint targets), planned (the planned
    /// expert, the reference's 8 numbers on reference_action_stamped: the recorded session is
    /// also a dataset, `composuite-dataset from-bag`), random (joint goals measured
    /// q + 0.05·U(-1,1)), zero (hold the start pose).
    #[arg(long, default_value = "expert")]
    policy: String,
    /// Seed of each task's first episode.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Control steps per episode [default: 500].
    #[arg(long)]
    horizon: Option<u32>,
    /// Output directory (must not exist) [default: runs/session_<unix time>].
    // This doc comment is also the option's --help text, where `<unix time>` is literal.
    #[allow(rustdoc::invalid_html_tags)]
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print the per-episode table as JSON instead of the summary.
    #[arg(long)]
    json: bool,
    /// Run without the recorder: no bag, the rest as usual (what recording costs is the
    /// difference; `scripts/bench-recording` measures it).
    #[arg(long)]
    no_record: bool,
    /// Start a new bag file every this many bytes, as `ros2 bag record --max-bag-size` (the
    /// recorder's memory then restarts with each file: an MCAP file's index grows with it).
    #[arg(long, value_name = "BYTES", conflicts_with = "no_record")]
    max_bag_size: Option<u64>,
    /// Start a new bag file every this many seconds, as `ros2 bag record --max-bag-duration`.
    #[arg(long, value_name = "SECONDS", conflicts_with = "no_record")]
    max_bag_duration: Option<f64>,
    /// Also write one video per episode into `videos/` beside the table, rendered from the bag
    /// (as `composuite bag render` does).
    #[arg(long, conflicts_with = "no_record")]
    video: bool,
    /// With --video: the camera (frontview, agentview, birdview, sideview, eye_in_hand).
    #[arg(long, default_value = "frontview", requires = "video")]
    video_camera: String,
    /// With --video: gif (needs nothing) or mp4 (needs ffmpeg).
    #[arg(long, default_value = "gif", requires = "video")]
    video_format: String,
    /// With --video: frame width and height (pixels).
    #[arg(long, default_value_t = 256, requires = "video")]
    video_size: u32,
}

/// Run the session.
pub fn run(args: &SessionArgs) -> Result<(), String> {
    let tasks = args
        .tasks
        .iter()
        .map(|t| {
            t.parse::<TaskSpec>()
                .map_err(|e| format!("--tasks {t}: {e}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let policy = PolicyKind::parse(&args.policy).map_err(|e| format!("--policy: {e}"))?;
    if args.episodes == 0 {
        return Err("--episodes must be at least 1".into());
    }
    let video_format = crate::video::VideoFormat::parse(&args.video_format)
        .map_err(|e| format!("--video-format: {e}"))?;
    if args.video {
        composuite_core::render::camera_spec(&args.video_camera)
            .map_err(|e| format!("--video-camera: {e}"))?;
        if !(1..=composuite_core::render::MAX_SIDE).contains(&args.video_size) {
            return Err(format!(
                "--video-size {}: pixels, 1 to {}",
                args.video_size,
                composuite_core::render::MAX_SIDE
            ));
        }
        if video_format == crate::video::VideoFormat::Mp4 {
            crate::video::find_ffmpeg(None).map_err(|e| format!("--video-format mp4: {e}"))?;
        }
    }
    if args.max_bag_size == Some(0) {
        return Err("--max-bag-size 0 is invalid; bytes > 0 (leave it out for one file)".into());
    }
    if let Some(s) = args.max_bag_duration
        && !(s.is_finite() && s > 0.0)
    {
        return Err(format!(
            "--max-bag-duration {s} is invalid; seconds > 0 (leave it out for one file)"
        ));
    }
    let out = args.out.clone().unwrap_or_else(|| {
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0);
        PathBuf::from(format!("runs/session_{now}"))
    });
    if out.exists() {
        return Err(format!(
            "--out {}: it exists already; give a new directory",
            out.display()
        ));
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let bag = out.join("bag");
    let namespace = format!("/session_{}", std::process::id());
    let mut launch = LaunchArgs::one_environment(&args.tasks[0], &namespace, "warn");
    launch.record = (!args.no_record).then(|| bag.clone());
    launch.record_max_bag_size = args.max_bag_size;
    launch.record_max_bag_duration = args.max_bag_duration;
    launch.horizon = args.horizon;
    let total = tasks.len() as u64 * u64::from(args.episodes);
    eprintln!(
        "composuite session: {} task(s) × {} episode(s), policy {}, {}",
        tasks.len(),
        args.episodes,
        policy.name(),
        if args.no_record {
            "not recording".to_string()
        } else {
            format!("recording into {}", bag.display())
        }
    );
    // Watched before the nodes start: a signal from then on stops the session in order (the
    // episode under way, then the environment, then the recorder) instead of ending it there.
    let signals = shutdown_signal().map_err(|e| format!("cannot watch for SIGINT/SIGTERM: {e}"))?;
    let mut suite = Suite::start(&launch)?;
    let plan = Plan {
        namespace: namespace.clone(),
        tasks,
        episodes: args.episodes,
        seed: args.seed,
        policy,
        wait_for_recorder: !args.no_record,
        signals: Some(signals),
        enclave: None,
    };
    let progress = Progress::new(total);
    let result = drive(&plan, &mut suite, |o| progress.episode(o));
    match &result {
        // Stopped early: the bar stays where it got to.
        Ok(driven) if driven.interrupted.is_some() => progress.bar.abandon(),
        _ => progress.finish(),
    }
    let clean = suite.stop();
    let Driven {
        outcomes,
        interrupted,
    } = result?;
    if !clean {
        return Err("some nodes did not shut down cleanly (see above)".into());
    }
    if outcomes.is_empty()
        && let Some(signal) = interrupted
    {
        return Err(format!(
            "stopped by signal {signal} before the first episode ended; {} holds what was recorded",
            out.display()
        ));
    }
    let rows: Vec<Episode> = (1..)
        .zip(&outcomes)
        .map(|(number, o)| row(&namespace, number, o))
        .collect();
    write(&out.join("episodes.csv"), &episodes_csv(&rows))?;
    let json: Vec<_> = rows.iter().map(Episode::json).collect();
    write(
        &out.join("episodes.json"),
        &serde_json::to_string_pretty(&json).unwrap_or_default(),
    )?;
    draw_plots(&out, &outcomes)?;
    let videos = if args.video {
        let options = crate::bag_render::RenderOptions {
            camera: args.video_camera.clone(),
            width: args.video_size,
            height: args.video_size,
            namespace: Some(namespace.clone()),
            episodes: outcomes.iter().map(|o| o.episode).collect(),
            fps: None,
            ffmpeg: None,
        };
        let dir = out.join("videos");
        let written = crate::bag_render::video_per_episode(&bag, &options, video_format, &dir)?;
        format!(", videos/ ({} {})", written.len(), video_format.extension())
    } else {
        String::new()
    };
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&json).unwrap_or_default()
        );
    } else {
        print!("{}", summary(&outcomes));
        let bag_note = if args.no_record {
            String::new()
        } else {
            format!("bag/ (composuite bag info {}), ", bag.display())
        };
        println!(
            "wrote {}: {bag_note}episodes.csv, episodes.json, rewards.png, success.png{videos}",
            out.display(),
        );
    }
    if outcomes.iter().any(|o| !o.identical) {
        return Err("the suite's observations differ from the in-process environment".into());
    }
    match interrupted {
        Some(signal) => Err(format!(
            "stopped by signal {signal} after {} of {total} episodes; the table holds those, the bag all that was recorded",
            outcomes.len()
        )),
        None => Ok(()),
    }
}

/// The session's row for its `number`-th episode (1-based, as the progress printed it), in the
/// table `composuite bag episodes` recomputes from the bag.
fn row(namespace: &str, number: u32, o: &EpisodeOutcome) -> Episode {
    Episode {
        namespace: namespace.into(),
        episode: number,
        suite_episode: o.episode,
        task: o.task.to_string(),
        seed: o.seed,
        length: o.steps,
        episode_return: o.episode_return,
        success: o.first_success.is_some(),
        furthest_stage: o.furthest_stage,
        done: true,
        reason: o.reason.clone(),
    }
}

/// `rewards.png` (each episode's staged reward over time) and `success.png` (success rate per
/// task).
fn draw_plots(out: &Path, outcomes: &[EpisodeOutcome]) -> Result<(), String> {
    let curves: Vec<(String, Vec<f64>)> = outcomes
        .iter()
        .map(|o| (format!("{} seed {}", o.task, o.seed), o.rewards.clone()))
        .collect();
    crate::plots::reward_curves(&out.join("rewards.png"), "Staged reward per step", &curves)?;
    let tasks: Vec<(String, f64)> = by_task(outcomes)
        .iter()
        .map(|(task, of)| (task.to_string(), success_rate(of)))
        .collect();
    crate::plots::success_bars(&out.join("success.png"), "Success per task", &tasks)
}

/// The outcomes grouped by task, tasks in the order they were played.
fn by_task(outcomes: &[EpisodeOutcome]) -> Vec<(TaskSpec, Vec<&EpisodeOutcome>)> {
    let mut groups: Vec<(TaskSpec, Vec<&EpisodeOutcome>)> = Vec::new();
    for o in outcomes {
        match groups.iter_mut().find(|(task, _)| *task == o.task) {
            Some((_, of)) => of.push(o),
            None => groups.push((o.task, vec![o])),
        }
    }
    groups
}

/// The share of episodes with a success (0 for none).
fn success_rate(of: &[&EpisodeOutcome]) -> f64 {
    let successes = of.iter().filter(|o| o.first_success.is_some()).count();
    successes as f64 / of.len().max(1) as f64
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Per task: episodes, success rate, mean return, mean length; then the whole session.
fn summary(outcomes: &[EpisodeOutcome]) -> String {
    let mut out = format!(
        "{:<40} {:>8} {:>8} {:>11} {:>11}\n",
        "task", "episodes", "success", "mean return", "mean length"
    );
    let tasks = by_task(outcomes);
    let line = |name: &str, of: &[&EpisodeOutcome]| {
        let n = of.len().max(1) as f64;
        format!(
            "{:<40} {:>8} {:>7.0}% {:>11.2} {:>11.1}\n",
            name,
            of.len(),
            100.0 * success_rate(of),
            of.iter().map(|o| o.episode_return).sum::<f64>() / n,
            of.iter().map(|o| f64::from(o.steps)).sum::<f64>() / n
        )
    };
    for (task, of) in &tasks {
        out.push_str(&line(&task.to_string(), of));
    }
    if tasks.len() > 1 {
        let all: Vec<&EpisodeOutcome> = outcomes.iter().collect();
        out.push_str(&line("all", &all));
    }
    out
}

/// The progress bar: episodes done, steps/s, success so far.
struct Progress {
    bar: indicatif::ProgressBar,
    started: Instant,
    state: std::cell::Cell<(u64, u64, u64)>,
}

impl Progress {
    fn new(total: u64) -> Progress {
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:30} {pos}/{len} episodes  {msg}  [{elapsed_precise}, eta {eta}]",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Progress {
            bar,
            started: Instant::now(),
            state: std::cell::Cell::new((0, 0, 0)),
        }
    }

    fn episode(&self, o: &EpisodeOutcome) {
        let (episodes, steps, successes) = self.state.get();
        let state = (
            episodes + 1,
            steps + u64::from(o.steps),
            successes + u64::from(o.first_success.is_some()),
        );
        self.state.set(state);
        let rate = state.1 as f64 / self.started.elapsed().as_secs_f64();
        let message = format!("{rate:.0} steps/s, success {}/{}", state.2, state.0);
        if self.bar.is_hidden() {
            // Not a terminal (a log file, CI): one line per episode instead of a bar.
            eprintln!(
                "episode {}/{}: {} seed {}: {} in {} steps, return {:.2}; {message}",
                state.0,
                self.bar.length().unwrap_or(0),
                o.task,
                o.seed,
                if o.first_success.is_some() {
                    "success"
                } else {
                    "no success"
                },
                o.steps,
                o.episode_return
            );
        }
        self.bar.set_message(message);
        self.bar.inc(1);
    }

    fn finish(&self) {
        self.bar.finish();
    }
}
