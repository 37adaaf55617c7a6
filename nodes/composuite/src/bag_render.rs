//! `composuite bag render`: a video of recorded episodes from the bag alone, one frame per
//! recorded observation (the episode's start, then every step).
//!
//! What a frame needs is in every step's `observation`: the arm's joint angles (their cosines
//! and sines), the finger joints and the object's pose; the episode's `scene` names the task,
//! so the arena, the object's shape and the arm. The core's `StateRenderer` draws that state
//! without physics, the way `Env::render` draws the simulated world (see
//! `docs/src/rendering.md`). `composuite session --video` calls the same code on its own bag.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use composuite_core::TaskSpec;
use composuite_core::render::{SceneState, StateRenderer, camera_spec};
use composuite_msgs::msg;
use composuite_ros::bag::reader::for_each_message;
use composuite_ros::shared::convert;

use crate::topics::namespace_of;
use crate::video::{VideoFormat, VideoWriter};

/// What to render and how.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// One of the five cameras.
    pub camera: String,
    /// Frame width (pixels).
    pub width: u32,
    /// Frame height (pixels).
    pub height: u32,
    /// Only this environment (namespace); needed when the bag holds several.
    pub namespace: Option<String>,
    /// Only these episodes (the task manager's numbers); all when empty.
    pub episodes: Vec<u32>,
    /// Frames per second [default: the recorded control rate, so the video plays in sim time].
    pub fps: Option<f64>,
    /// The ffmpeg to write MP4 with.
    pub ffmpeg: Option<PathBuf>,
}

/// One recorded episode's frames to draw.
#[derive(Debug, Clone)]
pub struct RecordedEpisode {
    /// Its environment's namespace.
    pub namespace: String,
    /// The task manager's episode number.
    pub episode: u32,
    /// Its task.
    pub task: TaskSpec,
    /// The control period (s) its scene announced.
    pub control_period: f64,
    /// Its states by step (step 0: the start), as recorded.
    pub states: Vec<(u32, SceneState)>,
}

/// Every episode of the bag that took at least one step (as `composuite bag episodes` counts
/// them), in the order they started, with the states of its recorded observations.
pub fn recorded_episodes(bag: &Path) -> Result<Vec<RecordedEpisode>, String> {
    // (namespace, episode) → task, control period; and → step → state.
    let mut scenes: BTreeMap<(String, u32), (TaskSpec, f64)> = BTreeMap::new();
    let mut states: BTreeMap<(String, u32), BTreeMap<u32, SceneState>> = BTreeMap::new();
    let mut order: Vec<(String, u32)> = Vec::new();
    let truncated = for_each_message(bag, |m| {
        match m.type_name {
            "composuite_msgs/msg/Scene" => {
                let scene: msg::Scene = m.decode()?;
                let task =
                    convert::task_of(&scene.task).map_err(|e| format!("{}: {e}", m.topic))?;
                scenes.insert(
                    (namespace_of(m.topic), scene.episode),
                    (task, scene.control_period),
                );
            }
            "composuite_msgs/msg/Observation" => {
                let o: msg::Observation = m.decode()?;
                let key = (namespace_of(m.topic), o.episode);
                let q = &o.object.orientation;
                let p = &o.object.position;
                let state = SceneState::from_factors(
                    &o.robot.joint_pos_cos,
                    &o.robot.joint_pos_sin,
                    &o.robot.gripper_qpos,
                    &[p.x, p.y, p.z],
                    &[q.x, q.y, q.z, q.w],
                );
                let of_episode = states.entry(key.clone()).or_insert_with(|| {
                    order.push(key);
                    BTreeMap::new()
                });
                of_episode.insert(o.step, state);
            }
            _ => {}
        }
        Ok(())
    })
    .map_err(|e| e.0)?;
    for (file, why) in truncated {
        eprintln!(
            "composuite bag: {} ends early ({why}); rendering up to its last complete chunk",
            file.display()
        );
    }
    let mut out = Vec::new();
    for key in order {
        let of_episode = states.remove(&key).unwrap_or_default();
        if of_episode.keys().all(|&step| step == 0) {
            continue; // ended before its first step (set_task's episode before a seeded reset)
        }
        let Some(&(task, control_period)) = scenes.get(&key) else {
            return Err(format!(
                "episode {} of {} has observations but no recorded scene: the bag cannot say \
                 its task (was `scene` excluded from the recording?)",
                key.1, key.0
            ));
        };
        out.push(RecordedEpisode {
            namespace: key.0,
            episode: key.1,
            task,
            control_period,
            states: of_episode.into_iter().collect(),
        });
    }
    Ok(out)
}

/// The episodes `options` selects, or an error saying what the bag holds.
pub fn select(
    bag: &Path,
    episodes: Vec<RecordedEpisode>,
    options: &RenderOptions,
) -> Result<Vec<RecordedEpisode>, String> {
    let mut namespaces: Vec<&str> = episodes.iter().map(|e| e.namespace.as_str()).collect();
    namespaces.dedup();
    namespaces.sort();
    namespaces.dedup();
    if namespaces.is_empty() {
        return Err(format!(
            "{} holds no episode with a step (no `observation` recorded)",
            bag.display()
        ));
    }
    let namespace = match &options.namespace {
        Some(ns) if namespaces.contains(&ns.as_str()) => ns.clone(),
        Some(ns) => {
            return Err(format!(
                "--namespace {ns}: no episodes there; the bag's environments: {}",
                namespaces.join(", ")
            ));
        }
        None if namespaces.len() == 1 => namespaces[0].to_string(),
        None => {
            return Err(format!(
                "the bag holds several environments; choose one with --namespace: {}",
                namespaces.join(", ")
            ));
        }
    };
    let of_namespace: Vec<RecordedEpisode> = episodes
        .into_iter()
        .filter(|e| e.namespace == namespace)
        .collect();
    for wanted in &options.episodes {
        if !of_namespace.iter().any(|e| e.episode == *wanted) {
            let have: Vec<String> = of_namespace.iter().map(|e| e.episode.to_string()).collect();
            return Err(format!(
                "--episode {wanted}: not in the bag; episodes of {namespace}: {}",
                have.join(", ")
            ));
        }
    }
    Ok(of_namespace
        .into_iter()
        .filter(|e| options.episodes.is_empty() || options.episodes.contains(&e.episode))
        .collect())
}

/// Render `episodes` one after the other into the video `out`; the frames written.
pub fn write_video(
    episodes: &[RecordedEpisode],
    options: &RenderOptions,
    out: &Path,
) -> Result<usize, String> {
    camera_spec(&options.camera).map_err(|e| format!("--camera: {e}"))?;
    let format = VideoFormat::of_path(out)?;
    let Some(first) = episodes.first() else {
        return Err("no episode to render".into());
    };
    let fps = options.fps.unwrap_or(1.0 / first.control_period);
    let mut video = VideoWriter::create(
        out,
        format,
        options.width,
        options.height,
        fps,
        options.ffmpeg.as_deref(),
    )?;
    let mut renderer: Option<StateRenderer> = None;
    for episode in episodes {
        let renderer = match &mut renderer {
            Some(r) if r.task() == episode.task => r,
            slot => slot.insert(StateRenderer::new(episode.task)),
        };
        for (_, state) in &episode.states {
            let frame = renderer
                .render(state, &options.camera, options.width, options.height)
                .map_err(|e| e.to_string())?;
            video.push(&frame.rgb)?;
        }
    }
    video.finish()
}

/// `composuite bag render`.
pub fn run(bag: &Path, options: &RenderOptions, out: &Path) -> Result<(), String> {
    camera_spec(&options.camera).map_err(|e| format!("--camera: {e}"))?;
    VideoFormat::of_path(out)?;
    let episodes = select(bag, recorded_episodes(bag)?, options)?;
    let frames = write_video(&episodes, options, out)?;
    let list: Vec<String> = episodes
        .iter()
        .map(|e| format!("{} ({}, {} frames)", e.episode, e.task, e.states.len()))
        .collect();
    println!(
        "wrote {}: {frames} frames of {} from {}, episodes {}",
        out.display(),
        options.camera,
        episodes[0].namespace,
        list.join(", ")
    );
    Ok(())
}

/// `<dir>/episode_<n>.<ext>` for every episode of `bag` (one environment): what
/// `composuite session --video` writes. Returns the files.
pub fn video_per_episode(
    bag: &Path,
    options: &RenderOptions,
    format: VideoFormat,
    dir: &Path,
) -> Result<Vec<PathBuf>, String> {
    let episodes = select(bag, recorded_episodes(bag)?, options)?;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut written = Vec::new();
    for episode in episodes {
        let path = dir.join(format!(
            "episode_{:03}.{}",
            episode.episode,
            format.extension()
        ));
        write_video(std::slice::from_ref(&episode), options, &path)?;
        written.push(path);
    }
    Ok(written)
}
