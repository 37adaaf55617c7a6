//! `composuite demo`: a headless session of the whole suite. It launches the three nodes of one
//! lockstep environment and drives them over ROS 2 — reset through the `reset` service, one
//! `joint_command` per step, the step's `observation`, `reward` and `episode` awaited by
//! (episode, step) — with the scripted expert choosing the commands. Per episode it prints the
//! outcome, and checks every observation and reward against the in-process `Env` given the same
//! commands (bit for bit): the suite is exactly the core library behind ROS.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use clap::Args;
use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::expert::Expert;
use composuite_core::physics::{ARM_DOF, FINGER_JOINTS, finger_for_gap, pad_gap, robot_model};
use composuite_msgs::msg;
use composuite_msgs::sensor_msgs::msg::JointState;
use composuite_msgs::srv;
use composuite_ros::node::{NodeSpec, RosNode, Startup};
use composuite_ros::{convert, names, qos};
use futures::{FutureExt, StreamExt};

use crate::launch::{LaunchArgs, Suite};

/// Run the scripted expert through the ROS 2 node suite, headless.
///
/// Starts one lockstep environment (task_manager, sim, reward as child processes, in a
/// namespace of its own), then plays `--episodes` episodes with the scripted expert as the
/// agent over ROS 2 topics and services. Prints each episode's outcome and whether every
/// observation and reward equalled the in-process environment's (they must, bit for bit).
/// DDS settings come from the environment (ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE).
///
/// Example: composuite demo --task Gen3/box/object_wall/trash_can --episodes 2
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Task, robot/object/obstacle/objective.
    #[arg(long, default_value = composuite_ros::task_manager::DEFAULT_TASK)]
    task: String,
    /// Episodes to play.
    #[arg(long, default_value_t = 3)]
    episodes: u32,
    /// Seed of the first episode (then +1 per episode).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print one JSON object per episode instead of text.
    #[arg(long)]
    json: bool,
}

/// Seconds to wait for one step's messages, or for a reset reply.
const STEP_TIMEOUT: Duration = Duration::from_secs(10);
/// How long the suite gets to come up (discovery included).
const STARTUP_TIMEOUT: Duration = Duration::from_secs(30);

const AGENT: NodeSpec = NodeSpec {
    name: "demo_agent",
    binary: "composuite demo",
    about: "the scripted expert as a ROS 2 agent",
    params: &[],
};

struct Outcome {
    episode: u32,
    seed: u64,
    steps: u32,
    episode_return: f64,
    first_success: Option<u32>,
    identical: bool,
    steps_per_s: f64,
}

/// Play the episodes; an error if the suite fails or differs from the in-process environment.
pub fn run(args: &DemoArgs) -> Result<(), String> {
    let task: TaskSpec = args
        .task
        .parse()
        .map_err(|e: composuite_core::TaskParseError| format!("--task: {e}"))?;
    if args.episodes == 0 {
        return Err("--episodes must be at least 1".into());
    }
    let namespace = format!("/demo_{}", std::process::id());
    let mut suite = Suite::start(&LaunchArgs::one_environment(&args.task, &namespace, "warn"))?;
    let result = play(args, task, &namespace, &mut suite);
    let clean = suite.stop();
    let outcomes = result?;
    if !clean {
        return Err("some nodes did not shut down cleanly (see above)".into());
    }
    if outcomes.iter().any(|o| !o.identical) {
        return Err("the suite's observations differ from the in-process environment".into());
    }
    Ok(())
}

fn play(
    args: &DemoArgs,
    task: TaskSpec,
    namespace: &str,
    suite: &mut Suite,
) -> Result<Vec<Outcome>, String> {
    let argv: Vec<String> = ["--ros-args", "-r", &format!("__ns:={namespace}")]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut node = match RosNode::start(&AGENT, &argv).map_err(|e| e.to_string())? {
        Startup::Node(node) => node,
        Startup::Help(_) => unreachable!("no --help given"),
    };
    let command = node
        .publisher::<JointState>(names::JOINT_COMMAND, qos::state())
        .map_err(|e| e.to_string())?;
    let observations = node
        .subscription::<msg::Observation>(names::OBSERVATION, qos::state())
        .map_err(|e| e.to_string())?;
    let rewards = node
        .subscription::<msg::StagedReward>(names::REWARD, qos::state())
        .map_err(|e| e.to_string())?;
    let statuses = node
        .subscription::<msg::EpisodeStatus>(names::EPISODE, qos::state())
        .map_err(|e| e.to_string())?;
    let reset = node
        .client::<srv::Reset>(names::RESET)
        .map_err(|e| e.to_string())?;
    let joint_names = convert::joint_names(robot_model(task.robot));
    let mut outcomes = Vec::new();
    smol::block_on(async {
        let mut observation_stream = std::pin::pin!(observations.async_stream());
        let mut reward_stream = std::pin::pin!(rewards.async_stream());
        let mut status_stream = std::pin::pin!(statuses.async_stream());
        let mut seen = Received::default();
        // The in-process twin, fed the same commands (each reset starts from a fresh copy of
        // its world, so one serves every episode).
        let mut shadow = Env::new(task, EnvConfig::default());
        for e in 0..args.episodes {
            let seed = args.seed + e as u64;
            let timeout = if e == 0 {
                STARTUP_TIMEOUT
            } else {
                STEP_TIMEOUT
            };
            let reply = call_reset(&reset, seed, timeout, suite).await?;
            let first = shadow.reset(seed).map_err(|e| e.to_string())?;
            let mut identical = bits(&reply.observation.flat) == bits(&first.flat());
            let mut expert = Expert::new(task);
            let (mut episode_return, mut first_success) = (0.0, None);
            let started = Instant::now();
            seen.clear();
            loop {
                let Action::Absolute { joints, gripper } = expert.act(&shadow) else {
                    return Err("the expert acted with a reference action".to_string());
                };
                // The gripper rides in the same message (a finger joint target), so arm and
                // gripper change in the same step; the sim turns it into this opening.
                let finger = gripper.map(|(gap, _)| finger_for_gap(gap));
                let mut names: Vec<String> = joint_names[..ARM_DOF].to_vec();
                let mut positions = joints.to_vec();
                if let Some(q) = finger {
                    names.push(FINGER_JOINTS[0].into());
                    positions.push(q);
                }
                command
                    .publish(JointState {
                        name: names,
                        position: positions,
                        ..Default::default()
                    })
                    .map_err(|e| format!("joint_command: {e:?}"))?;
                let step = shadow
                    .step(&Action::Absolute {
                        joints,
                        gripper: finger.map(|q| (pad_gap(q), 0.0)),
                    })
                    .map_err(|e| e.to_string())?;
                let key = (reply.episode, shadow.steps());
                let deadline = Instant::now() + STEP_TIMEOUT;
                while !seen.complete(key) {
                    let remaining = deadline.saturating_duration_since(Instant::now());
                    futures::select! {
                        o = observation_stream.select_next_some() => if let Ok((o, _)) = o { seen.observations.insert((o.episode, o.step), o); },
                        r = reward_stream.select_next_some() => if let Ok((r, _)) = r { seen.rewards.insert((r.episode, r.step), r); },
                        s = status_stream.select_next_some() => if let Ok((s, _)) = s { seen.statuses.insert((s.episode, s.step), s); },
                        _ = FutureExt::fuse(smol::Timer::after(remaining)) => {
                            return Err(format!("no observation/reward/episode for step {} within {:?}{}",
                                key.1, STEP_TIMEOUT, suite.died().map(|d| format!(" ({d})")).unwrap_or_default()));
                        }
                    }
                }
                let (o, r, s) = seen.take(key);
                identical &= bits(&o.flat) == bits(&step.observation.flat())
                    && r.total.to_bits() == step.reward.to_bits();
                episode_return += r.total;
                if r.success && first_success.is_none() {
                    first_success = Some(key.1);
                }
                if s.done {
                    break;
                }
            }
            let outcome = Outcome {
                episode: reply.episode,
                seed,
                steps: shadow.steps(),
                episode_return,
                first_success,
                identical,
                steps_per_s: shadow.steps() as f64 / started.elapsed().as_secs_f64(),
            };
            report(&outcome, args.json);
            outcomes.push(outcome);
        }
        Ok::<(), String>(())
    })?;
    node.shutdown();
    Ok(outcomes)
}

/// Messages received, by (episode, step), until their step is complete.
#[derive(Default)]
struct Received {
    observations: HashMap<(u32, u32), msg::Observation>,
    rewards: HashMap<(u32, u32), msg::StagedReward>,
    statuses: HashMap<(u32, u32), msg::EpisodeStatus>,
}

impl Received {
    fn complete(&self, key: (u32, u32)) -> bool {
        self.observations.contains_key(&key)
            && self.rewards.contains_key(&key)
            && self.statuses.contains_key(&key)
    }

    fn take(
        &mut self,
        key: (u32, u32),
    ) -> (msg::Observation, msg::StagedReward, msg::EpisodeStatus) {
        (
            self.observations.remove(&key).expect("complete"),
            self.rewards.remove(&key).expect("complete"),
            self.statuses.remove(&key).expect("complete"),
        )
    }

    fn clear(&mut self) {
        self.observations.clear();
        self.rewards.clear();
        self.statuses.clear();
    }
}

/// Call `reset`, resending every second until `timeout` (the first call may go out before
/// discovery has matched the service).
async fn call_reset(
    client: &ros2_client::dds::Client<srv::ResetRequest, srv::ResetResponse>,
    seed: u64,
    timeout: Duration,
    suite: &mut Suite,
) -> Result<srv::ResetResponse, String> {
    let deadline = Instant::now() + timeout;
    while Instant::now() < deadline {
        if let Some(died) = suite.died() {
            return Err(died);
        }
        let request = srv::ResetRequest {
            seed,
            use_seed: true,
        };
        let Ok(id) = client.send_request(request) else {
            smol::Timer::after(Duration::from_millis(200)).await;
            continue;
        };
        futures::select! {
            reply = client.async_receive_response(id).fuse() => match reply {
                Ok(reply) if reply.success => return Ok(reply),
                Ok(reply) => return Err(format!("reset refused: {}", reply.message)),
                Err(_) => {}
            },
            _ = FutureExt::fuse(smol::Timer::after(Duration::from_secs(1))) => {}
        }
    }
    Err(format!("the suite did not answer reset within {timeout:?}"))
}

fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

fn report(o: &Outcome, json: bool) {
    if json {
        println!(
            "{}",
            serde_json::json!({"episode": o.episode, "seed": o.seed, "steps": o.steps,
                "return": o.episode_return, "success": o.first_success.is_some(),
                "first_success_step": o.first_success, "identical_to_in_process": o.identical,
                "steps_per_s": o.steps_per_s})
        );
    } else {
        println!(
            "episode {} (seed {}): {}, return {:.2} over {} steps, {:.0} steps/s; observations {} the in-process env",
            o.episode,
            o.seed,
            match o.first_success {
                Some(step) => format!("success at step {step}"),
                None => "no success".into(),
            },
            o.episode_return,
            o.steps,
            o.steps_per_s,
            if o.identical {
                "identical to"
            } else {
                "DIFFERENT from"
            }
        );
    }
}
