//! `composuite bag replay [--verify]`: every lockstep episode of a bag simulated again in
//! process, from what the bag alone says — the task, seed and horizon of its `scene`, and the
//! `joint_command`s the agent sent, applied exactly as the sim applies them. With `--verify`
//! each replayed observation and reward must equal the recorded one bit for bit: the proof
//! that the bag was made by this version and that the run was deterministic.
//!
//! Commands carry no episode number; a command belongs to the episode whose step-0
//! observation was the last one published before it (publish times, from the publishers'
//! source timestamps: the agent sends step k's command after step k−1's observation left the
//! sim, and before step k's).

use std::collections::BTreeMap;
use std::path::Path;

use composuite_core::TaskSpec;
use composuite_core::control::{validate_arm_targets, validate_gripper_width};
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::physics::robot_model;
use composuite_msgs::msg;
use composuite_msgs::sensor_msgs::msg::JointState;
use composuite_ros::bag::reader::for_each_message;
use composuite_ros::shared::convert;

use crate::topics::namespace_of;

/// What one recorded episode holds.
struct Recorded {
    task: TaskSpec,
    seed: u64,
    horizon: u32,
    /// Observations by step: publish time, flat vector, task observation on.
    observations: BTreeMap<u32, (u64, Vec<f64>)>,
    /// Reward totals by step.
    rewards: BTreeMap<u32, f64>,
    /// Commands in publish order.
    commands: Vec<JointState>,
}

/// The outcome of one replayed episode.
struct Replayed {
    namespace: String,
    episode: u32,
    task: TaskSpec,
    seed: u64,
    steps: u32,
    episode_return: f64,
    compared: usize,
    difference: Option<String>,
}

/// Replay the bag; with `verify`, an error when any episode differs.
pub fn run(bag: &Path, verify: bool) -> Result<(), String> {
    let episodes = read(bag)?;
    if episodes.is_empty() {
        return Err(format!(
            "{} holds no replayable episode (it needs scene, observation and joint_command)",
            bag.display()
        ));
    }
    let mut differing = 0;
    for ((namespace, episode), recorded) in &episodes {
        let r = replay(namespace, *episode, recorded)?;
        let verdict = match (&r.difference, verify) {
            (_, false) => String::new(),
            (None, true) => format!(
                "; {} observations and rewards bit-identical to the recording",
                r.compared
            ),
            (Some(d), true) => {
                differing += 1;
                format!("; DIFFERENT: {d}")
            }
        };
        println!(
            "{} episode {} ({} seed {}): {} steps, return {:.3}{verdict}",
            r.namespace, r.episode, r.task, r.seed, r.steps, r.episode_return
        );
    }
    if differing > 0 {
        return Err(format!(
            "{differing} of {} episodes differ from the recording",
            episodes.len()
        ));
    }
    Ok(())
}

type Key = (String, u32);

/// The bag's episodes by (namespace, episode).
fn read(bag: &Path) -> Result<BTreeMap<Key, Recorded>, String> {
    let mut episodes: BTreeMap<Key, Recorded> = BTreeMap::new();
    let mut observations: Vec<(Key, u32, u64, Vec<f64>)> = Vec::new();
    let mut rewards: Vec<(Key, u32, f64)> = Vec::new();
    let mut commands: BTreeMap<String, Vec<(u64, JointState)>> = BTreeMap::new();
    let truncated = for_each_message(bag, |m| {
        let ns = namespace_of(m.topic);
        match (m.type_name, m.topic.rsplit('/').next()) {
            ("composuite_msgs/msg/Scene", _) => {
                let s: msg::Scene = m.decode()?;
                let task = convert::task_of(&s.task).map_err(|e| format!("{}: {e}", m.topic))?;
                episodes.entry((ns, s.episode)).or_insert(Recorded {
                    task,
                    seed: s.seed,
                    horizon: s.horizon,
                    observations: BTreeMap::new(),
                    rewards: BTreeMap::new(),
                    commands: Vec::new(),
                });
            }
            ("composuite_msgs/msg/Observation", _) => {
                let o: msg::Observation = m.decode()?;
                observations.push(((ns, o.episode), o.step, m.publish_time, o.flat));
            }
            ("composuite_msgs/msg/StagedReward", _) => {
                let r: msg::StagedReward = m.decode()?;
                rewards.push(((ns, r.episode), r.step, r.total));
            }
            ("sensor_msgs/msg/JointState", Some("joint_command")) => {
                let c: JointState = m.decode()?;
                commands.entry(ns).or_default().push((m.publish_time, c));
            }
            _ => {}
        }
        Ok(())
    })
    .map_err(|e| e.0)?;
    for (file, why) in truncated {
        eprintln!("composuite bag: {} ends early ({why})", file.display());
    }
    for (key, step, time, flat) in observations {
        if let Some(e) = episodes.get_mut(&key) {
            e.observations.insert(step, (time, flat));
        }
    }
    for (key, step, total) in rewards {
        if let Some(e) = episodes.get_mut(&key) {
            e.rewards.insert(step, total);
        }
    }
    // Only episodes whose start was recorded can be replayed.
    episodes.retain(|_, e| e.observations.contains_key(&0));
    for (ns, mut list) in commands {
        list.sort_by_key(|(t, _)| *t);
        let mut starts: Vec<(u64, u32)> = episodes
            .iter()
            .filter(|((n, _), _)| *n == ns)
            .map(|((_, ep), e)| (e.observations[&0].0, *ep))
            .collect();
        starts.sort();
        for (time, command) in list {
            let owner = starts.iter().rev().find(|(start, _)| *start < time);
            if let Some((_, ep)) = owner
                && let Some(e) = episodes.get_mut(&(ns.clone(), *ep))
            {
                e.commands.push(command);
            }
        }
    }
    Ok(episodes)
}

/// Simulate one episode again, applying each command as the sim does (refused commands change
/// nothing; commands after the episode ended are ignored), and compare.
fn replay(namespace: &str, episode: u32, r: &Recorded) -> Result<Replayed, String> {
    let with_task_part = r.observations[&0].1.len() == composuite_core::obs::FLAT_SIZE_WITH_TASK;
    let config = EnvConfig::default()
        .horizon(r.horizon)
        .task_observation(with_task_part);
    let mut env = Env::new(r.task, config);
    let first = env.reset(r.seed).map_err(|e| e.to_string())?;
    let mut out = Replayed {
        namespace: namespace.into(),
        episode,
        task: r.task,
        seed: r.seed,
        steps: 0,
        episode_return: 0.0,
        compared: 0,
        difference: None,
    };
    let check = |step: u32, replayed: &[f64], reward: Option<f64>, out: &mut Replayed| {
        if let Some((_, recorded)) = r.observations.get(&step) {
            out.compared += 1;
            if out.difference.is_none() {
                out.difference = first_difference(recorded, replayed).map(|i| {
                    format!(
                        "step {step}: observation[{i}] recorded {}, replayed {}",
                        recorded[i], replayed[i]
                    )
                });
            }
        }
        if let (Some(replayed), Some(recorded)) = (reward, r.rewards.get(&step))
            && out.difference.is_none()
            && replayed.to_bits() != recorded.to_bits()
        {
            out.difference = Some(format!(
                "step {step}: reward recorded {recorded}, replayed {replayed}"
            ));
        }
    };
    check(0, &first.flat(), None, &mut out);
    let model = robot_model(r.task.robot);
    for command in &r.commands {
        if env.ended().is_some() {
            break;
        }
        let Ok((arm, finger_gap)) = convert::arm_command(model, command) else {
            continue;
        };
        let valid = validate_arm_targets(model, &arm).is_ok()
            && finger_gap.is_none_or(|g| validate_gripper_width(model, g, 0.0).is_ok());
        if !valid {
            continue;
        }
        let step = env
            .step(&Action::Absolute {
                joints: arm,
                gripper: finger_gap.map(|g| (g, 0.0)),
            })
            .map_err(|e| e.to_string())?;
        check(
            env.steps(),
            &step.observation.flat(),
            Some(step.reward),
            &mut out,
        );
    }
    out.steps = env.steps();
    out.episode_return = env.episode_return();
    if out.difference.is_none() {
        let last_recorded = r.observations.keys().max().copied().unwrap_or(0);
        if last_recorded > out.steps {
            out.difference = Some(format!(
                "the recording has {last_recorded} steps, the commands replay {}",
                out.steps
            ));
        }
    }
    Ok(out)
}

fn first_difference(a: &[f64], b: &[f64]) -> Option<usize> {
    if a.len() != b.len() {
        return Some(a.len().min(b.len()));
    }
    a.iter()
        .zip(b)
        .position(|(x, y)| x.to_bits() != y.to_bits())
}
