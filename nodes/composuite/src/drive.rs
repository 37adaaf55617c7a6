//! An agent that drives one lockstep environment of the suite over ROS 2, as a user's agent
//! would: `set_task` and `reset` through the services, one `joint_command` per step, and the
//! step's `observation`, `reward` and `episode` awaited by (episode, step). A built-in policy
//! chooses the commands; an in-process twin `Env`, fed the same commands, gives the policy its
//! state and checks every observation and reward bit for bit. `composuite demo` and
//! `composuite session` are both this loop.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use composuite_core::TaskSpec;
use composuite_core::dataset::{ActionSource, ExpertActions};
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::expert::Expert;
use composuite_core::physics::{ARM_DOF, FINGER_JOINTS, finger_for_gap, pad_gap, robot_model};
use composuite_msgs::msg;
use composuite_msgs::sensor_msgs::msg::JointState;
use composuite_msgs::srv;
use composuite_msgs::std_msgs::msg::Header;
use composuite_ros::shared::intra_process::Publisher;
use composuite_ros::shared::node::{NodeSpec, RosNode, Startup};
use composuite_ros::shared::{convert, names, qos};
use futures::{FutureExt, StreamExt};
use rand::{Rng, SeedableRng};

use crate::launch::Suite;

/// Seconds to wait for one step's messages, or for a service reply.
const STEP_TIMEOUT: Duration = Duration::from_secs(10);
/// How long the suite gets to come up (discovery included).
const STARTUP_TIMEOUT: Duration = Duration::from_secs(30);
/// How long the agent waits, when a recorder runs, for every reader of its commands to have
/// received the last ones before it leaves.
const ACKNOWLEDGE_TIMEOUT: Duration = Duration::from_secs(5);

const AGENT: NodeSpec = NodeSpec {
    name: "agent",
    binary: "composuite",
    about: "a built-in policy as a ROS 2 agent",
    params: &[],
};

/// Who chooses the commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PolicyKind {
    /// The scripted expert (absolute joint targets on `joint_command`).
    Expert,
    /// The planned expert: the reference's 8 numbers on `reference_action_stamped`, as an agent
    /// written for CompoSuite acts, rounded to `f32` as an `expert` dataset stores them — a
    /// recorded session of it is also a dataset (`composuite-dataset from-bag`), its episodes
    /// those of an `expert` file with the same seeds.
    Planned,
    /// Joint goals = measured q + 0.05·U(−1, 1) per joint (the reference's action scale for
    /// a uniform random action), gripper left as it is.
    Random,
    /// Hold the start pose.
    Zero,
}

impl PolicyKind {
    /// `expert`, `planned`, `random` or `zero`.
    pub fn parse(s: &str) -> Result<PolicyKind, String> {
        match s {
            "expert" => Ok(PolicyKind::Expert),
            "planned" => Ok(PolicyKind::Planned),
            "random" => Ok(PolicyKind::Random),
            "zero" => Ok(PolicyKind::Zero),
            other => Err(format!(
                "policy `{other}` is unknown; valid: expert, planned, random, zero"
            )),
        }
    }

    /// The name `parse` takes.
    pub fn name(self) -> &'static str {
        match self {
            PolicyKind::Expert => "expert",
            PolicyKind::Planned => "planned",
            PolicyKind::Random => "random",
            PolicyKind::Zero => "zero",
        }
    }
}

/// One policy for one episode.
enum Policy {
    Expert(Box<Expert>),
    Planned(Box<ExpertActions>),
    Random(Box<rand_chacha::ChaCha8Rng>),
    Zero([f64; ARM_DOF]),
}

impl Policy {
    fn new(kind: PolicyKind, task: TaskSpec, seed: u64, env: &Env) -> Policy {
        match kind {
            PolicyKind::Expert => Policy::Expert(Box::new(Expert::new(task))),
            PolicyKind::Planned => Policy::Planned(Box::new(ExpertActions::new(task, seed, 0.0))),
            PolicyKind::Random => {
                Policy::Random(Box::new(rand_chacha::ChaCha8Rng::seed_from_u64(seed)))
            }
            PolicyKind::Zero => Policy::Zero(measured(env)),
        }
    }

    /// The next command.
    fn act(&mut self, env: &Env) -> Result<Command, String> {
        match self {
            Policy::Expert(expert) => match expert.act(env) {
                Action::Absolute { joints, gripper } => Ok(Command::Joints {
                    joints,
                    finger: gripper.map(|(gap, _)| finger_for_gap(gap)),
                }),
                Action::Reference(_) => Err("the expert acted with a reference action".into()),
            },
            Policy::Planned(expert) => Ok(Command::Reference(expert.action(env).map(f64::from))),
            Policy::Random(rng) => {
                let mut q = measured(env);
                for v in &mut q {
                    *v += 0.05 * rng.random_range(-1.0..=1.0);
                }
                Ok(Command::Joints {
                    joints: q,
                    finger: None,
                })
            }
            Policy::Zero(home) => Ok(Command::Joints {
                joints: *home,
                finger: None,
            }),
        }
    }
}

/// The agent's command topic: the one its policy's commands go on.
enum CommandWriter {
    Joints(Publisher<JointState>),
    Reference(Publisher<msg::ReferenceAction>),
}

impl CommandWriter {
    fn topic(&self) -> &'static str {
        match self {
            CommandWriter::Joints(_) => names::JOINT_COMMAND,
            CommandWriter::Reference(_) => names::REFERENCE_ACTION_STAMPED,
        }
    }

    /// Every reader has what was published (true), up to [`ACKNOWLEDGE_TIMEOUT`].
    fn wait_for_acknowledgments(&self) -> ros2_client::WriteResult<bool, ()> {
        match self {
            CommandWriter::Joints(p) => p.wait_for_acknowledgments(ACKNOWLEDGE_TIMEOUT),
            CommandWriter::Reference(p) => p.wait_for_acknowledgments(ACKNOWLEDGE_TIMEOUT),
        }
    }
}

/// One step's command, in the form its topic takes.
enum Command {
    /// Arm joint targets and, when the gripper is commanded, its finger joint target
    /// (`joint_command`).
    Joints {
        joints: [f64; ARM_DOF],
        finger: Option<f64>,
    },
    /// The reference's 8 numbers (`reference_action_stamped`).
    Reference([f64; 8]),
}

fn measured(env: &Env) -> [f64; ARM_DOF] {
    std::array::from_fn(|j| env.world().joint_position(j))
}

/// What to drive: every task × `episodes` episodes (seeds `seed`, `seed` + 1, ...).
pub struct Plan {
    /// Namespace of the environment.
    pub namespace: String,
    /// Tasks in order (the environment starts on the first).
    pub tasks: Vec<TaskSpec>,
    /// Episodes per task.
    pub episodes: u32,
    /// Seed of each task's first episode.
    pub seed: u64,
    /// The policy.
    pub policy: PolicyKind,
    /// Wait until a recorder has subscribed to the environment's topics before the first reset,
    /// so the session's messages are all recorded.
    pub wait_for_recorder: bool,
    /// SIGINT/SIGTERM as they arrive (`shutdown_signal`); `None` lets a signal end the process.
    pub signals: Option<async_channel::Receiver<i32>>,
    /// The agent's security enclave (`--ros-args --enclave`; None: `/`).
    pub enclave: Option<String>,
}

/// What a drive played.
pub struct Driven {
    /// The episodes played to their end, in order.
    pub outcomes: Vec<EpisodeOutcome>,
    /// The signal that stopped the drive before the plan's end, if one did.
    pub interrupted: Option<i32>,
}

/// How a drive answers SIGINT/SIGTERM: the first lets the episode under way finish, so what was
/// recorded and tabled ends on a whole episode; a second stops at once (that episode is dropped).
struct Interrupt {
    signals: Option<async_channel::Receiver<i32>>,
    first: Option<i32>,
    now: bool,
}

impl Interrupt {
    fn poll(&mut self) {
        let Some(signals) = &self.signals else { return };
        while let Ok(signal) = signals.try_recv() {
            if self.first.is_none() {
                self.first = Some(signal);
                eprintln!(
                    "\nsignal {signal}: finishing this episode, then stopping (again to stop now)"
                );
            } else {
                self.now = true;
                eprintln!("\nsignal {signal}: stopping now, without this episode");
            }
        }
    }
}

/// One episode as the agent saw it.
#[derive(Debug, Clone)]
pub struct EpisodeOutcome {
    /// The task.
    pub task: TaskSpec,
    /// Episode number the task manager gave.
    pub episode: u32,
    /// Its seed.
    pub seed: u64,
    /// Control steps.
    pub steps: u32,
    /// Sum of the step rewards.
    pub episode_return: f64,
    /// First step with reward 1, if any.
    pub first_success: Option<u32>,
    /// Furthest stage reached (−1: none).
    pub furthest_stage: i8,
    /// Why it ended, as the task manager said.
    pub reason: String,
    /// Every observation and reward equalled the in-process twin's, bit for bit.
    pub identical: bool,
    /// Lockstep steps per second over the episode.
    pub steps_per_s: f64,
    /// The staged reward of every step (step 1 first).
    pub rewards: Vec<f64>,
}

/// Play the plan on a running suite; `each` is called after every episode.
pub fn drive(
    plan: &Plan,
    suite: &mut Suite,
    mut each: impl FnMut(&EpisodeOutcome),
) -> Result<Driven, String> {
    let mut argv: Vec<String> = ["--ros-args", "-r", &format!("__ns:={}", plan.namespace)]
        .iter()
        .map(|s| s.to_string())
        .collect();
    if let Some(enclave) = &plan.enclave {
        argv.extend(["--enclave".to_string(), enclave.clone()]);
    }
    let mut node = match RosNode::start(&AGENT, &argv).map_err(|e| e.to_string())? {
        Startup::Node(node) => node,
        Startup::Help(_) => unreachable!("no --help given"),
    };
    let e = |e: composuite_ros::shared::node::StartError| e.to_string();
    // Only the topic the policy commands on: a recorded session then holds the commands its
    // agent sent and no empty topic beside them.
    let command = match plan.policy {
        PolicyKind::Planned => CommandWriter::Reference(
            node.publisher(names::REFERENCE_ACTION_STAMPED, qos::state())
                .map_err(e)?,
        ),
        PolicyKind::Expert | PolicyKind::Random | PolicyKind::Zero => CommandWriter::Joints(
            node.publisher(names::JOINT_COMMAND, qos::state())
                .map_err(e)?,
        ),
    };
    let observations = node
        .subscription::<msg::Observation>(names::OBSERVATION, qos::state())
        .map_err(e)?;
    let rewards = node
        .subscription::<msg::StagedReward>(names::REWARD, qos::state())
        .map_err(e)?;
    let statuses = node
        .subscription::<msg::EpisodeStatus>(names::EPISODE, qos::state())
        .map_err(e)?;
    let reset = node.client::<srv::Reset>(names::RESET).map_err(e)?;
    let set_task = node.client::<srv::SetTask>(names::SET_TASK).map_err(e)?;
    if plan.wait_for_recorder {
        wait_for_recorder(&node, &plan.namespace, command.topic(), suite)?;
    }
    let mut outcomes = Vec::new();
    let mut interrupt = Interrupt {
        signals: plan.signals.clone(),
        first: None,
        now: false,
    };
    smol::block_on(async {
        // The three step topics as one stream (unreadable samples are None).
        let incoming = futures::stream::select(
            observations
                .async_stream()
                .map(|m| m.ok().map(|(o, _)| Incoming::Observation(Box::new(o)))),
            futures::stream::select(
                rewards
                    .async_stream()
                    .map(|m| m.ok().map(|(r, _)| Incoming::Reward(r))),
                statuses
                    .async_stream()
                    .map(|m| m.ok().map(|(s, _)| Incoming::Status(s))),
            ),
        );
        let mut incoming = std::pin::pin!(incoming);
        let mut seen = Received::default();
        for (t, &task) in plan.tasks.iter().enumerate() {
            if t > 0 {
                call_set_task(&set_task, task, suite).await?;
            }
            let joint_names = convert::joint_names(robot_model(task.robot));
            // The in-process twin (each reset starts from a fresh copy of its world).
            let mut twin = Env::new(task, EnvConfig::default());
            for e in 0..plan.episodes {
                interrupt.poll();
                if interrupt.first.is_some() {
                    return Ok(());
                }
                let seed = plan.seed + e as u64;
                let timeout = if outcomes.is_empty() {
                    STARTUP_TIMEOUT
                } else {
                    STEP_TIMEOUT
                };
                let reply =
                    start_episode(&reset, seed, timeout, suite, &mut seen, &mut incoming).await?;
                let first = twin.reset(seed).map_err(|e| e.to_string())?;
                let mut outcome = EpisodeOutcome {
                    task,
                    episode: reply.episode,
                    seed,
                    steps: 0,
                    episode_return: 0.0,
                    first_success: None,
                    furthest_stage: -1,
                    reason: String::new(),
                    identical: bits(&reply.observation.flat) == bits(&first.flat()),
                    steps_per_s: 0.0,
                    rewards: Vec::new(),
                };
                let mut policy = Policy::new(plan.policy, task, seed, &twin);
                // Each command carries the stamp of the observation it answers: the sim drops
                // one meant for an earlier episode.
                let mut answered = reply.observation.header.stamp.clone();
                let started = Instant::now();
                loop {
                    interrupt.poll();
                    if interrupt.now {
                        return Ok(());
                    }
                    let header = Header {
                        stamp: answered.clone(),
                        frame_id: String::new(),
                    };
                    let action = match (policy.act(&twin)?, &command) {
                        (Command::Joints { joints, finger }, CommandWriter::Joints(command)) => {
                            // The gripper rides in the same message (a finger joint target), so
                            // arm and gripper change in the same step.
                            let mut names: Vec<String> = joint_names[..ARM_DOF].to_vec();
                            let mut positions = joints.to_vec();
                            if let Some(q) = finger {
                                names.push(FINGER_JOINTS[0].into());
                                positions.push(q);
                            }
                            command
                                .publish(JointState {
                                    header,
                                    name: names,
                                    position: positions,
                                    ..Default::default()
                                })
                                .map_err(|e| format!("joint_command: {e:?}"))?;
                            Action::Absolute {
                                joints,
                                gripper: finger.map(|q| (pad_gap(q), 0.0)),
                            }
                        }
                        (Command::Reference(action), CommandWriter::Reference(command)) => {
                            command
                                .publish(msg::ReferenceAction { header, action })
                                .map_err(|e| format!("reference_action_stamped: {e:?}"))?;
                            Action::Reference(action)
                        }
                        _ => unreachable!("the writer is chosen by the policy"),
                    };
                    let step = twin.step(&action).map_err(|e| e.to_string())?;
                    let key = (reply.episode, twin.steps());
                    if !seen.wait_for(key, &mut incoming, STEP_TIMEOUT).await {
                        return Err(format!(
                            "no observation/reward/episode for step {} within {:?}{}",
                            key.1,
                            STEP_TIMEOUT,
                            suite.died().map(|d| format!(" ({d})")).unwrap_or_default()
                        ));
                    }
                    let (o, r, s) = seen.take(key);
                    answered = o.header.stamp.clone();
                    outcome.identical &= bits(&o.flat) == bits(&step.observation.flat())
                        && r.total.to_bits() == step.reward.to_bits();
                    outcome.episode_return += r.total;
                    outcome.rewards.push(r.total);
                    outcome.furthest_stage = outcome.furthest_stage.max(r.current_stage);
                    if r.success && outcome.first_success.is_none() {
                        outcome.first_success = Some(key.1);
                    }
                    if s.done {
                        outcome.reason = s.reason_text;
                        break;
                    }
                }
                outcome.steps = twin.steps();
                outcome.steps_per_s = outcome.steps as f64 / started.elapsed().as_secs_f64();
                each(&outcome);
                outcomes.push(outcome);
            }
        }
        Ok::<(), String>(())
    })?;
    if plan.wait_for_recorder {
        // The last commands may still be on their way to the recorder, which is slower than
        // the sim under load: dropping the writer now would lose them from the bag.
        match command.wait_for_acknowledgments() {
            Ok(true) => {}
            Ok(false) => eprintln!(
                "warning: the recorder did not acknowledge the last commands within {ACKNOWLEDGE_TIMEOUT:?}; the bag may miss them"
            ),
            Err(e) => eprintln!("warning: cannot wait for the recorder's acknowledgments: {e:?}"),
        }
    }
    node.shutdown();
    Ok(Driven {
        outcomes,
        interrupted: interrupt.first,
    })
}

/// Until a recorder reads the environment's topics: topics only a recorder subscribes to
/// (`clock`, `joint_states`, `success`, `tf`, `object_markers`) have a reader, and the agent's
/// `command_topic` (`joint_command`, or `reference_action_stamped` for the planned expert) has
/// two (the sim and the recorder); then a moment for the readers to match their writers.
fn wait_for_recorder(
    node: &RosNode,
    namespace: &str,
    command_topic: &str,
    suite: &mut Suite,
) -> Result<(), String> {
    let ns = namespace.trim_end_matches('/');
    let wanted = [
        (names::CLOCK, 1),
        (names::JOINT_STATES, 1),
        (names::SUCCESS, 1),
        (names::TF, 1),
        (names::OBJECT_MARKERS, 1),
        (command_topic, 2),
    ];
    let participant = node.context.domain_participant();
    let deadline = Instant::now() + STARTUP_TIMEOUT;
    loop {
        let readers = participant.discovered_readers();
        let count = |topic: &str| {
            let dds = format!("rt{ns}/{topic}");
            readers
                .iter()
                .filter(|r| r.subscription_topic_data.topic_name() == &dds)
                .count()
        };
        if wanted.iter().all(|(topic, n)| count(topic) >= *n) {
            std::thread::sleep(Duration::from_millis(500));
            return Ok(());
        }
        if let Some(died) = suite.died() {
            return Err(died);
        }
        if Instant::now() > deadline {
            return Err(format!(
                "the recorder did not subscribe to {ns}'s topics within {STARTUP_TIMEOUT:?}"
            ));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A message on one of the three step topics.
enum Incoming {
    Observation(Box<msg::Observation>),
    Reward(msg::StagedReward),
    Status(msg::EpisodeStatus),
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

    /// Drop what belongs to other episodes than `episode`.
    fn keep_episode(&mut self, episode: u32) {
        self.observations.retain(|k, _| k.0 == episode);
        self.rewards.retain(|k, _| k.0 == episode);
        self.statuses.retain(|k, _| k.0 == episode);
    }

    fn insert(&mut self, message: Incoming) {
        match message {
            Incoming::Observation(o) => _ = self.observations.insert((o.episode, o.step), *o),
            Incoming::Reward(r) => _ = self.rewards.insert((r.episode, r.step), r),
            Incoming::Status(s) => _ = self.statuses.insert((s.episode, s.step), s),
        }
    }

    /// Receive until the messages of `key` are all here (true) or `timeout` passed (false).
    async fn wait_for(
        &mut self,
        key: (u32, u32),
        incoming: &mut (impl futures::Stream<Item = Option<Incoming>> + Unpin),
        timeout: Duration,
    ) -> bool {
        let deadline = Instant::now() + timeout;
        while !self.complete(key) {
            let remaining = deadline.saturating_duration_since(Instant::now());
            futures::select! {
                message = incoming.next().fuse() => match message {
                    Some(Some(message)) => self.insert(message),
                    Some(None) => {} // an unreadable sample
                    None => return false,
                },
                _ = FutureExt::fuse(smol::Timer::after(remaining)) => return false,
            }
        }
        true
    }
}

/// How long the step-0 messages of a reset may take before the reset is asked again.
const STEP0_WAIT: Duration = Duration::from_secs(1);
/// Resets asked (same seed: the same start) before giving up on the step-0 messages.
const RESET_ATTEMPTS: usize = 5;

/// Reset with `seed` and wait for the episode's step-0 observation, reward and status: their
/// arrival shows each writer knows this agent's reader (a volatile step message sent before
/// that is lost, which happens right after discovery). Without them, reset again.
async fn start_episode(
    client: &ros2_client::dds::Client<srv::ResetRequest, srv::ResetResponse>,
    seed: u64,
    timeout: Duration,
    suite: &mut Suite,
    seen: &mut Received,
    incoming: &mut (impl futures::Stream<Item = Option<Incoming>> + Unpin),
) -> Result<srv::ResetResponse, String> {
    for _ in 0..RESET_ATTEMPTS {
        let reply = call_reset(client, seed, timeout, suite).await?;
        seen.keep_episode(reply.episode);
        let key = (reply.episode, 0);
        if seen.wait_for(key, incoming, STEP0_WAIT).await {
            seen.take(key);
            return Ok(reply);
        }
    }
    Err(format!(
        "{RESET_ATTEMPTS} resets with seed {seed}, and the step-0 observation, reward and episode status \
         never all arrived{}",
        suite.died().map(|d| format!(" ({d})")).unwrap_or_default()
    ))
}

/// Send a request, resending every second until `timeout` (the first call may go out before
/// discovery has matched the service); the first reply.
async fn call<Req, Resp>(
    client: &ros2_client::dds::Client<Req, Resp>,
    request: Req,
    what: &str,
    timeout: Duration,
    suite: &mut Suite,
) -> Result<Resp, String>
where
    Req: composuite_msgs::RosMessage + ros2_client::Message + Clone,
    Resp: composuite_msgs::RosMessage + ros2_client::Message,
{
    let deadline = Instant::now() + timeout;
    while Instant::now() < deadline {
        if let Some(died) = suite.died() {
            return Err(died);
        }
        let Ok(id) = client.send_request(request.clone()) else {
            smol::Timer::after(Duration::from_millis(200)).await;
            continue;
        };
        futures::select! {
            reply = client.async_receive_response(id).fuse() => if let Ok(reply) = reply {
                return Ok(reply);
            },
            _ = FutureExt::fuse(smol::Timer::after(Duration::from_secs(1))) => {}
        }
    }
    Err(format!(
        "the suite did not answer {what} within {timeout:?}"
    ))
}

async fn call_reset(
    client: &ros2_client::dds::Client<srv::ResetRequest, srv::ResetResponse>,
    seed: u64,
    timeout: Duration,
    suite: &mut Suite,
) -> Result<srv::ResetResponse, String> {
    let request = srv::ResetRequest {
        seed,
        use_seed: true,
    };
    let reply = call(client, request, "reset", timeout, suite).await?;
    if reply.success {
        Ok(reply)
    } else {
        Err(format!("reset refused: {}", reply.message))
    }
}

async fn call_set_task(
    client: &ros2_client::dds::Client<srv::SetTaskRequest, srv::SetTaskResponse>,
    task: TaskSpec,
    suite: &mut Suite,
) -> Result<(), String> {
    let spec = convert::task_spec(&task);
    let request = srv::SetTaskRequest {
        robot: spec.robot,
        object: spec.object,
        obstacle: spec.obstacle,
        objective: spec.objective,
    };
    let reply = call(client, request, "set_task", STEP_TIMEOUT, suite).await?;
    if reply.success {
        Ok(())
    } else {
        Err(format!("set_task {task} refused: {}", reply.message))
    }
}

fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}
