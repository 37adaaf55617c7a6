//! The `reward` node: for every `world_state` of a step, the objective's staged reward (the
//! core library's functions) on `reward`, stamped like the world state it came from, and the
//! success flag on `success`. The objective and object come from the latched `scene`. The
//! reset state (step 0) gets a reward message too, with total 0 and no `success`.

use composuite_core::TaskSpec;
use composuite_core::reward::{RewardConfig, staged_reward};
use composuite_msgs::msg;
use composuite_msgs::std_msgs::msg::Bool;
use futures::{FutureExt, StreamExt};
use ros2_client::ParameterValue;

use crate::shared::convert;
use crate::shared::names;
use crate::shared::node::RosNode;
use crate::shared::params::{ParamSpec, any_value};
use crate::shared::qos;

/// World states kept while their episode's scene is on its way.
const MAX_EARLY: usize = 64;

fn check_scale(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::Double(d) if d.is_finite() => Ok(()),
        _ => Err("the reward scale is a finite number (1.0: rewards as they are)".into()),
    }
}

/// The reward node's parameters: the reference's `make()` reward options.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "reward_shaping",
        default: || ParameterValue::Boolean(true),
        description: "staged rewards (true) or sparse ones: 1 on success, else 0",
        check: any_value,
    },
    ParamSpec {
        name: "reward_scale",
        default: || ParameterValue::Double(1.0),
        description: "every reward (StagedReward.total) is multiplied by this",
        check: check_scale,
    },
];

/// Run the reward node until SIGINT/SIGTERM.
pub fn run(node: &mut RosNode, signals: async_channel::Receiver<i32>) -> Result<(), String> {
    let e = |e: crate::shared::node::StartError| e.to_string();
    let reward_pub = node
        .publisher::<msg::StagedReward>(names::REWARD, qos::state())
        .map_err(e)?;
    let success_pub = node
        .publisher::<Bool>(names::SUCCESS, qos::state())
        .map_err(e)?;
    let scene_sub = node
        .subscription::<msg::Scene>(names::SCENE, qos::latched())
        .map_err(e)?;
    let world_sub = node
        .subscription::<msg::WorldState>(names::WORLD_STATE, qos::state())
        .map_err(e)?;
    let log = node.log.clone();
    let param_changes = node.param_changes.clone();
    // Read by `score` and changed by parameter events: a Cell, as both live on this thread.
    let config = std::cell::Cell::new(RewardConfig {
        shaping: node.param_bool("reward_shaping"),
        scale: node.param_f64("reward_scale"),
    });
    log.info(format!(
        "{} up{}",
        node.fully_qualified_name(),
        if world_sub.is_handed_over() {
            "; world_state handed over in this process"
        } else {
            ""
        }
    ));
    // The task and episode the world states belong to.
    let mut current: Option<(TaskSpec, u32)> = None;
    // World states of an episode whose scene has not arrived yet (scene and world_state are
    // separate topics, so their order is not guaranteed); scored when it does.
    let mut early: Vec<msg::WorldState> = Vec::new();
    let score = |task: TaskSpec, w: &msg::WorldState| {
        let r = staged_reward(task.objective, task.object, &convert::snapshot(w));
        let mut message =
            convert::staged_reward(&r, &config.get(), w.header.stamp.clone(), w.episode, w.step);
        // The reset state (step 0): no action was taken, so it earns nothing, but the message
        // is sent (its stages show where the episode starts) so that an agent knows at the
        // reset that this writer reaches it, before step 1's reward depends on that.
        let reset_state = w.step == 0;
        if reset_state {
            message.total = 0.0;
            message.success = false;
        }
        // Publishing only fails when DDS is shutting down.
        let _ = reward_pub.publish(message);
        if !reset_state {
            let _ = success_pub.publish(Bool { data: r.success });
        }
    };
    smol::block_on(async {
        let mut scenes = std::pin::pin!(scene_sub.async_stream());
        let mut worlds = std::pin::pin!(world_sub.async_stream());
        loop {
            futures::select_biased! {
                signal = signals.recv().fuse() => {
                    log.info(format!("signal {} received, shutting down", signal.unwrap_or(0)));
                    return Ok(());
                }
                change = param_changes.recv().fuse() => {
                    let Ok(change) = change else { continue };
                    let mut c = config.get();
                    match (change.name.as_str(), &change.value) {
                        ("reward_shaping", ParameterValue::Boolean(on)) => c.shaping = *on,
                        ("reward_scale", ParameterValue::Double(scale)) => c.scale = *scale,
                        _ => {}
                    }
                    config.set(c);
                    log.info(format!("rewards from now on: shaping {}, scale {}", c.shaping, c.scale));
                }
                scene = scenes.select_next_some() => match scene {
                    Ok((scene, _)) => {
                        match convert::task_of(&scene.task) {
                            Ok(task) => {
                                current = Some((task, scene.episode));
                                for w in early.drain(..).filter(|w| w.episode == scene.episode) {
                                    score(task, &w);
                                }
                            }
                            Err(err) => log.error(format!("scene refused: {err}")),
                        }
                    }
                    Err(err) => log.warn(format!("unreadable scene message dropped: {err:?}")),
                },
                world = worlds.select_next_some() => match world {
                    Ok((w, _)) => {
                        match current {
                            Some((task, episode)) if w.episode == episode => score(task, &w),
                            Some((_, episode)) if w.episode < episode => {}
                            _ if early.len() < MAX_EARLY => early.push(w),
                            _ => log.warn(format!(
                                "world_state of episode {} dropped: its scene never arrived",
                                w.episode
                            )),
                        }
                    }
                    Err(err) => log.warn(format!("unreadable world_state dropped: {err:?}")),
                },
            }
        }
    })
}
