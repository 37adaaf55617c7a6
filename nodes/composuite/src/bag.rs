//! `composuite bag`: tools that read a recorded session from the bag alone — `info` (what
//! `ros2 bag info` prints, plus the episodes found), `episodes` (the per-episode table
//! recomputed from the recorded topics) and `reindex` (rebuild `metadata.yaml`, and the summary
//! of a file whose recorder was killed, as `ros2 bag reindex` and `mcap recover` do), `render`
//! (a video of its episodes, [`crate::bag_render`]); `play` publishes it into a running graph
//! again, as `ros2 bag play` does.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use composuite_msgs::msg;
use composuite_ros::bag::reader::{for_each_message, read_metadata, reindex};
use serde_json::json;

use crate::topics::namespace_of;

/// Read a recorded session from its bag alone: info, episodes, replay, export, render, reindex;
/// or play it back into a running ROS graph.
///
/// Examples:
///   composuite bag info runs/s1/bag
///   composuite bag episodes runs/s1/bag --csv episodes.csv
///   composuite bag replay runs/s1/bag --verify
///   composuite bag export runs/s1/bag --topics /ns/reward --format csv --out exported
///   composuite bag render runs/s1/bag --camera frontview --out ep.gif
///   composuite bag reindex runs/s1/bag
///   composuite bag play runs/s1/bag --rate 2 --clock 100
#[derive(Args, Debug)]
pub struct BagArgs {
    #[command(subcommand)]
    command: BagCommand,
}

#[derive(Subcommand, Debug)]
enum BagCommand {
    /// Duration, start and end, size, messages, and per topic its type, count and
    /// serialization format (as `ros2 bag info`), then the episodes found.
    Info {
        /// The bag directory.
        bag: PathBuf,
        /// Print JSON instead.
        #[arg(long)]
        json: bool,
    },
    /// The per-episode table (namespace, task, seed, length, return, success, furthest stage)
    /// recomputed from the recorded `episode` and `reward` topics.
    Episodes {
        /// The bag directory.
        bag: PathBuf,
        /// Also write the table as CSV here.
        #[arg(long, value_name = "FILE")]
        csv: Option<PathBuf>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Re-simulate every recorded lockstep episode in-process from its recorded task, seed and
    /// commands; with --verify, check that every observation and reward is bit-identical to the
    /// recorded one (the determinism proof: a bag made by this version passes).
    Replay {
        /// The bag directory.
        bag: PathBuf,
        /// Compare with the recorded observations and rewards; exit non-zero on a difference.
        #[arg(long)]
        verify: bool,
    },
    /// Write chosen topics (all by default) to one file per topic in --out: JSON lines
    /// ({"log_time", "publish_time", "message"}) or CSV (the message flattened: a.b, a[i]).
    // This doc comment is also the subcommand's --help text, where `a[i]` is literal.
    #[allow(rustdoc::broken_intra_doc_links)]
    Export {
        /// The bag directory.
        bag: PathBuf,
        /// Topics to export (full names); default: every topic.
        #[arg(long, num_args = 1..)]
        topics: Vec<String>,
        /// jsonl or csv.
        #[arg(long, value_enum, default_value = "jsonl")]
        format: crate::export::Format,
        /// Output directory (created; existing files are never overwritten).
        #[arg(long)]
        out: PathBuf,
    },
    /// Publish the recorded messages again, on their topics and with the QoS their publishers
    /// offered (latched topics stay latched), at the recorded pace times --rate, as
    /// `ros2 bag play` does. Speaks DDS on ROS_DOMAIN_ID (ROS_AUTOMATIC_DISCOVERY_RANGE as the
    /// nodes); SIGINT/SIGTERM stop it.
    Play {
        /// The bag directory.
        bag: PathBuf,
        /// Speed factor: 2 = twice as fast as recorded, 0.5 = half as fast.
        #[arg(long, short = 'r', default_value_t = 1.0)]
        rate: f64,
        /// Topics to play (full names); default: every topic.
        #[arg(long, num_args = 1..)]
        topics: Vec<String>,
        /// Also publish /clock at this rate (Hz) with the bag's time (a recorded /clock is then
        /// not played).
        #[arg(long, value_name = "HZ")]
        clock: Option<f64>,
        /// Publish a topic under another name, FROM:=TO (e.g. /env_00/tf:=/tf for RViz).
        #[arg(long, short = 'm', num_args = 1.., value_name = "FROM:=TO")]
        remap: Vec<String>,
        /// Seconds between creating the publishers and the first message, for subscribers to
        /// discover them (volatile messages sent before a subscriber matched never reach it).
        #[arg(long, default_value_t = 1.0)]
        delay: f64,
    },
    /// A video of the recorded episodes (GIF, or MP4 through ffmpeg; the extension decides),
    /// one frame per recorded observation — the episode's start, then every step — drawn from
    /// the recorded states alone: the arm's joints, the fingers and the object's pose of each
    /// `observation`, the task of each `scene`.
    Render {
        /// The bag directory.
        bag: PathBuf,
        /// Camera: frontview, agentview, birdview, sideview or eye_in_hand.
        #[arg(long, default_value = "frontview")]
        camera: String,
        /// The video file to write (.gif or .mp4; must not exist).
        #[arg(long)]
        out: PathBuf,
        /// Frame width (pixels).
        #[arg(long, default_value_t = 256)]
        width: u32,
        /// Frame height (pixels).
        #[arg(long, default_value_t = 256)]
        height: u32,
        /// Only these episodes (numbers as `composuite bag episodes` lists them); default: all,
        /// one after the other.
        #[arg(long = "episode", num_args = 1..)]
        episodes: Vec<u32>,
        /// The environment (namespace) to render, when the bag holds several.
        #[arg(long)]
        namespace: Option<String>,
        /// Frames per second [default: the recorded control rate, i.e. sim time].
        #[arg(long)]
        fps: Option<f64>,
        /// The ffmpeg that writes .mp4 [default: $COMPOSUITE_FFMPEG, else `ffmpeg` on PATH].
        #[arg(long, value_name = "PATH")]
        ffmpeg: Option<PathBuf>,
    },
    /// Rebuild metadata.yaml from the MCAP files (a bag whose recorder was killed has none);
    /// a file without its summary is first rewritten from its complete chunks.
    Reindex {
        /// The bag directory.
        bag: PathBuf,
    },
}

/// Run `composuite bag ...`.
pub fn run(args: &BagArgs) -> Result<(), String> {
    match &args.command {
        BagCommand::Info { bag, json } => info(bag, *json),
        BagCommand::Episodes { bag, csv, json } => {
            let episodes = episodes(bag)?;
            if let Some(path) = csv {
                std::fs::write(path, episodes_csv(&episodes))
                    .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
            }
            if *json {
                let rows: Vec<_> = episodes.iter().map(Episode::json).collect();
                println!(
                    "{}",
                    serde_json::to_string_pretty(&rows).unwrap_or_default()
                );
            } else {
                print!("{}", episodes_table(&episodes));
            }
            Ok(())
        }
        BagCommand::Replay { bag, verify } => crate::replay::run(bag, *verify),
        BagCommand::Export {
            bag,
            topics,
            format,
            out,
        } => crate::export::run(bag, topics, *format, out),
        BagCommand::Play {
            bag,
            rate,
            topics,
            clock,
            remap,
            delay,
        } => crate::play::run(bag, *rate, topics, *clock, remap, *delay),
        BagCommand::Render {
            bag,
            camera,
            out,
            width,
            height,
            episodes,
            namespace,
            fps,
            ffmpeg,
        } => {
            let options = crate::bag_render::RenderOptions {
                camera: camera.clone(),
                width: *width,
                height: *height,
                namespace: namespace.clone(),
                episodes: episodes.clone(),
                fps: *fps,
                ffmpeg: ffmpeg.clone(),
            };
            crate::bag_render::run(bag, &options, out)
        }
        BagCommand::Reindex { bag } => {
            let report = reindex(bag).map_err(|e| e.0)?;
            for (file, why) in &report.recovered {
                eprintln!(
                    "composuite bag: {} had no summary ({why}); rewritten from its complete chunks",
                    file.display()
                );
            }
            println!(
                "reindexed {}: {} files, {} messages on {} topics",
                bag.display(),
                report.metadata.files.len(),
                report.metadata.message_count,
                report.metadata.topics.len()
            );
            Ok(())
        }
    }
}

fn info(bag: &Path, as_json: bool) -> Result<(), String> {
    let metadata = read_metadata(bag).map_err(|e| e.0)?;
    let size: u64 = metadata
        .files
        .iter()
        .filter_map(|f| std::fs::metadata(bag.join(&f.path)).ok())
        .map(|m| m.len())
        .sum();
    let episodes = episodes(bag)?;
    let finished = episodes.iter().filter(|e| e.done).count();
    let successes = episodes.iter().filter(|e| e.success).count();
    if as_json {
        let topics: Vec<_> = metadata
            .topics
            .iter()
            .map(|t| {
                json!({"name": t.name, "type": t.type_name, "count": t.message_count,
                       "serialization_format": t.serialization_format})
            })
            .collect();
        let out = json!({
            "files": metadata.files.iter().map(|f| &f.path).collect::<Vec<_>>(),
            "bag_size": size,
            "storage_identifier": "mcap",
            "ros_distro": metadata.ros_distro,
            "duration_ns": metadata.duration_ns,
            "start_ns": metadata.end_time_ns().map(|_| metadata.starting_time_ns),
            "end_ns": metadata.end_time_ns(),
            "messages": metadata.message_count,
            "topics": topics,
            "episodes": episodes.len(),
            "episodes_finished": finished,
            "episodes_succeeded": successes,
        });
        println!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
        return Ok(());
    }
    let files: Vec<&str> = metadata.files.iter().map(|f| f.path.as_str()).collect();
    println!("Files:             {}", files.join("\n                   "));
    println!("Bag size:          {}", human_size(size));
    println!("Storage id:        mcap");
    println!("ROS Distro:        {}", metadata.ros_distro);
    println!(
        "Duration:          {:.9}s",
        metadata.duration_ns as f64 / 1e9
    );
    if let Some(end) = metadata.end_time_ns() {
        println!("Start:             {}", stamp(metadata.starting_time_ns));
        println!("End:               {}", stamp(end));
    }
    println!("Messages:          {}", metadata.message_count);
    let width = metadata
        .topics
        .iter()
        .map(|t| t.name.len())
        .max()
        .unwrap_or(0);
    for (i, t) in metadata.topics.iter().enumerate() {
        let label = if i == 0 {
            "Topic information: "
        } else {
            "                   "
        };
        println!(
            "{label}Topic: {:width$} | Type: {} | Count: {} | Serialization Format: {}",
            t.name, t.type_name, t.message_count, t.serialization_format
        );
    }
    println!(
        "Episodes:          {} ({finished} finished, {successes} succeeded)",
        episodes.len()
    );
    Ok(())
}

/// `1795554521.784715650` as ros2 bag info shows stamps (seconds since the epoch).
fn stamp(ns: u64) -> String {
    format!("{}.{:09}", ns / 1_000_000_000, ns % 1_000_000_000)
}

fn human_size(bytes: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < units.len() {
        value /= 1024.0;
        unit += 1;
    }
    format!("{value:.1} {}", units[unit])
}

/// One episode as the bag shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct Episode {
    /// Namespace of its environment (`/` or `/env_00`).
    pub namespace: String,
    /// 1-based, in the order the environment's episodes started, counting those that took a
    /// step: what `composuite session` prints ("episode 1/3").
    pub episode: u32,
    /// The task manager's number for it (its `episode` topic's, and the session's video names),
    /// which also counts the episodes ended before their first step (the one `set_task` starts).
    pub suite_episode: u32,
    /// `robot/object/obstacle/objective`.
    pub task: String,
    /// Its seed.
    pub seed: u64,
    /// Control steps taken.
    pub length: u32,
    /// Sum of its rewards.
    pub episode_return: f64,
    /// Whether any step had reward 1 (the paper's success).
    pub success: bool,
    /// Furthest stage reached (index into the objective's stages; -1 for none).
    pub furthest_stage: i8,
    /// Whether it ended (horizon, termination, reset) before the recording did.
    pub done: bool,
    /// Why it ended, as the task manager said.
    pub reason: String,
}

impl Episode {
    /// The row as JSON (what `--json` prints).
    pub fn json(&self) -> serde_json::Value {
        json!({"namespace": self.namespace, "episode": self.episode,
               "suite_episode": self.suite_episode, "task": self.task,
               "seed": self.seed, "length": self.length, "return": self.episode_return,
               "success": self.success, "furthest_stage": self.furthest_stage,
               "done": self.done, "reason": self.reason})
    }
}

/// The episodes of a bag that took at least one step, from its `episode` (EpisodeStatus) and
/// `reward` (StagedReward) topics, in the order they started. (An episode ended before its first
/// step, e.g. the one `set_task` starts before a seeded `reset`, has only its step-0 status.)
pub fn episodes(bag: &Path) -> Result<Vec<Episode>, String> {
    let mut found: Vec<Episode> = Vec::new();
    let mut index: BTreeMap<(String, u32, u64), usize> = BTreeMap::new();
    let mut stages: BTreeMap<(String, u32), i8> = BTreeMap::new();

    let truncated = for_each_message(bag, |m| {
        match m.type_name {
            "composuite_msgs/msg/EpisodeStatus" => {
                let s: msg::EpisodeStatus = m.decode()?;
                let ns = namespace_of(m.topic);
                let key = (ns.clone(), s.episode, s.seed);
                let i = *index.entry(key).or_insert_with(|| {
                    found.push(Episode {
                        namespace: ns,
                        episode: 0, // numbered below, once the stepless ones are gone
                        suite_episode: s.episode,
                        task: format!(
                            "{}/{}/{}/{}",
                            s.task.robot, s.task.object, s.task.obstacle, s.task.objective
                        ),
                        seed: s.seed,
                        length: 0,
                        episode_return: 0.0,
                        success: false,
                        furthest_stage: -1,
                        done: false,
                        reason: String::new(),
                    });
                    found.len() - 1
                });
                let e = &mut found[i];
                if s.step >= e.length {
                    e.length = s.step;
                    e.episode_return = s.episode_return;
                    e.success |= s.success_seen;
                    e.done |= s.done;
                    if s.done {
                        e.reason = s.reason_text.clone();
                    }
                }
            }
            "composuite_msgs/msg/StagedReward" => {
                let r: msg::StagedReward = m.decode()?;
                if r.step == 0 {
                    return Ok(()); // the reset state: where the episode starts, not a step of it
                }
                let stage = stages
                    .entry((namespace_of(m.topic), r.episode))
                    .or_insert(-1);
                *stage = (*stage).max(r.current_stage);
            }
            _ => {}
        }
        Ok(())
    })
    .map_err(|e| e.0)?;
    for (file, why) in truncated {
        eprintln!(
            "composuite bag: {} ends early ({why}); episodes counted up to its last complete chunk",
            file.display()
        );
    }
    found.retain(|e| e.length > 0);
    let mut numbered: BTreeMap<String, u32> = BTreeMap::new();
    for e in &mut found {
        if let Some(stage) = stages.get(&(e.namespace.clone(), e.suite_episode)) {
            e.furthest_stage = *stage;
        }
        let count = numbered.entry(e.namespace.clone()).or_insert(0);
        *count += 1;
        e.episode = *count;
    }
    Ok(found)
}

/// The table as CSV (one header line).
pub fn episodes_csv(episodes: &[Episode]) -> String {
    let mut out = String::from(
        "namespace,episode,suite_episode,task,seed,length,return,success,furthest_stage,done,reason\n",
    );
    for e in episodes {
        out.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},\"{}\"\n",
            e.namespace,
            e.episode,
            e.suite_episode,
            e.task,
            e.seed,
            e.length,
            e.episode_return,
            e.success,
            e.furthest_stage,
            e.done,
            e.reason.replace('"', "\"\"")
        ));
    }
    out
}

fn episodes_table(episodes: &[Episode]) -> String {
    let mut out = format!(
        "{:<10} {:>7}  {:<40} {:>6} {:>6} {:>9} {:>7} {:>5}\n",
        "namespace", "episode", "task", "seed", "length", "return", "success", "stage"
    );
    for e in episodes {
        out.push_str(&format!(
            "{:<10} {:>7}  {:<40} {:>6} {:>6} {:>9.3} {:>7} {:>5}{}\n",
            e.namespace,
            e.episode,
            e.task,
            e.seed,
            e.length,
            e.episode_return,
            if e.success { "yes" } else { "no" },
            e.furthest_stage,
            if e.done { "" } else { "  (not finished)" }
        ));
    }
    out
}
