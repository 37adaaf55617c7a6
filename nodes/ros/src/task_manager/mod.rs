//! The `task_manager` node: chooses the task, composes and publishes the `scene` (one scene =
//! one episode), follows each episode from `world_state` (return, success, the objective's
//! termination, the horizon) and publishes `episode`; serves `set_task`, `reset` and
//! `sample_tasks`.
//!
//! Also serves its part of the ROS 2 standard simulation interfaces
//! ([`crate::simulation_interfaces`]):
//! `reset_simulation`, `get_available_worlds`, `load_world`, `get_current_world`, `unload_world`.
//!
//! `reset` answers with the episode's first observation: it publishes the new scene and replies
//! when the sim's step-0 observation of that episode arrives (or says the sim did not answer).

mod simulation_services;

use std::time::{Duration, Instant};

use composuite_core::TaskSpec;
use composuite_core::env::{EnvConfig, EpisodeLayout, MAX_SEED};
use composuite_core::reward::{staged_reward, termination};
use composuite_core::sampling::{Experiment, sample_tasks};
use composuite_msgs::builtin_interfaces::msg::Time;
use composuite_msgs::msg;
use composuite_msgs::srv;
use futures::{FutureExt, StreamExt};
use ros2_client::ParameterValue;
use ros2_client::RmwRequestId;
use ros2_client::dds::Server;

use crate::shared::convert;
use crate::shared::intra_process::Publisher;
use crate::shared::names;
use crate::shared::node::{Logger, ParamChange, RosNode};
use crate::shared::params::{ParamSpec, any_value, positive_number};
use crate::shared::qos;

/// The task a suite starts with when nothing else is asked.
pub const DEFAULT_TASK: &str = "IIWA/box/no_obstacle/pick_place";

fn check_task(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::String(s) => s.parse::<TaskSpec>().map(|_| ()).map_err(|e| e.to_string()),
        _ => Err("a task `robot/object/obstacle/objective`".into()),
    }
}

fn check_seed(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::Integer(s) if (0..=MAX_SEED as i64).contains(s) => Ok(()),
        _ => Err(format!("valid seeds: 0..={MAX_SEED}")),
    }
}

fn check_horizon(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::Integer(h) if (1..=u32::MAX as i64).contains(h) => Ok(()),
        _ => Err("the horizon is a number of control steps >= 1".into()),
    }
}

/// The task manager's parameters.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "task",
        default: || ParameterValue::String(DEFAULT_TASK.into()),
        description: "the task of the first episode, robot/object/obstacle/objective",
        check: check_task,
    },
    ParamSpec {
        name: "seed",
        default: || ParameterValue::Integer(0),
        description: "seed of the first episode; later ones count up unless reset names one",
        check: check_seed,
    },
    ParamSpec {
        name: "horizon",
        default: || ParameterValue::Integer(500),
        description: "control steps per episode",
        check: check_horizon,
    },
    ParamSpec {
        name: "auto_reset",
        default: || ParameterValue::Boolean(false),
        description: "start the next episode (next seed) as soon as one ends",
        check: any_value,
    },
    ParamSpec {
        name: "reset_timeout",
        default: || ParameterValue::Double(5.0),
        description: "seconds reset waits for the sim's first observation",
        check: positive_number,
    },
];

/// An episode being followed.
struct Episode {
    task: TaskSpec,
    seed: u64,
    number: u32,
    horizon: u32,
    last_step: u32,
    /// Header (sim-time stamp) of the last world state counted.
    last_header: composuite_msgs::std_msgs::msg::Header,
    episode_return: f64,
    success_seen: bool,
    done: bool,
    /// Whether the sim's step-0 observation of this episode arrived (a second one means the
    /// sim was started again and lost the episode).
    started: bool,
}

/// Which service a reset is answered on.
enum Waiting {
    /// `reset` (answered with the first observation).
    Reset,
    /// `reset_simulation`.
    ResetSimulation,
    /// `load_world` of this task.
    LoadWorld(TaskSpec),
}

/// A reset waiting for the sim's first observation.
struct PendingReset {
    request: RmwRequestId,
    episode: u32,
    seed: u64,
    deadline: Instant,
    waiting: Waiting,
}

struct TaskManager {
    task: TaskSpec,
    horizon: u32,
    next_seed: u64,
    episodes_started: u32,
    auto_reset: bool,
    reset_timeout: Duration,
    current: Option<Episode>,
    pending: Vec<PendingReset>,
    /// The latest sim time seen on `world_state` or `observation`; each scene carries it, so a
    /// sim that was started again goes on from there.
    sim_time: Time,
    scene: Publisher<msg::Scene>,
    status: Publisher<msg::EpisodeStatus>,
}

/// Run the task manager until SIGINT/SIGTERM.
pub fn run(node: &mut RosNode, signals: async_channel::Receiver<i32>) -> Result<(), String> {
    let e = |e: crate::shared::node::StartError| e.to_string();
    let scene = node.publisher(names::SCENE, qos::latched()).map_err(e)?;
    let status = node.publisher(names::EPISODE, qos::state()).map_err(e)?;
    let world_sub = node
        .subscription::<msg::WorldState>(names::WORLD_STATE, qos::state())
        .map_err(e)?;
    let observation_sub = node
        .subscription::<msg::Observation>(names::OBSERVATION, qos::state())
        .map_err(e)?;
    let set_task = node.server::<srv::SetTask>(names::SET_TASK).map_err(e)?;
    let reset = node.server::<srv::Reset>(names::RESET).map_err(e)?;
    let sample = node
        .server::<srv::SampleTasks>(names::SAMPLE_TASKS)
        .map_err(e)?;
    let si_servers = simulation_services::Servers::new(node).map_err(e)?;
    let replies = Replies {
        reset: &reset,
        si: &si_servers,
    };
    let task: TaskSpec = node
        .param_string("task")
        .parse()
        .map_err(|err: composuite_core::TaskParseError| err.to_string())?;
    let mut manager = TaskManager {
        task,
        horizon: node.param_i64("horizon") as u32,
        next_seed: node.param_i64("seed") as u64,
        episodes_started: 0,
        auto_reset: node.param_bool("auto_reset"),
        reset_timeout: Duration::from_secs_f64(node.param_f64("reset_timeout")),
        current: None,
        pending: Vec::new(),
        sim_time: Default::default(),
        scene,
        status,
    };
    let log = node.log.clone();
    log.info(format!(
        "{} up: task {}, services in the {} format{}",
        node.fully_qualified_name(),
        manager.task,
        node.param_string("service_mapping"),
        if world_sub.is_handed_over() && observation_sub.is_handed_over() {
            "; world_state and observation handed over in this process"
        } else {
            ""
        }
    ));
    if let Err(err) = manager.start_episode(None) {
        log.error(format!("cannot start the first episode: {err}"));
    }
    let param_changes = node.param_changes.clone();
    smol::block_on(async {
        let mut worlds = std::pin::pin!(world_sub.async_stream());
        let mut observations = std::pin::pin!(observation_sub.async_stream());
        let mut set_task_requests = std::pin::pin!(set_task.receive_request_stream());
        let mut reset_requests = std::pin::pin!(reset.receive_request_stream());
        let mut sample_requests = std::pin::pin!(sample.receive_request_stream());
        let mut simulation_requests = std::pin::pin!(si_servers.requests());
        // Armed only while a reset waits for its first observation: an idle environment wakes
        // for nothing (a 100 ms poll in each of 64 composed environments was a third of the
        // suite's idle CPU).
        let mut expiry = smol::Timer::never();
        let mut armed_for = None;
        loop {
            let deadline = manager.next_reset_deadline();
            if deadline != armed_for {
                expiry = deadline.map_or_else(smol::Timer::never, smol::Timer::at);
                armed_for = deadline;
            }
            futures::select_biased! {
                signal = signals.recv().fuse() => {
                    log.info(format!("signal {} received, shutting down", signal.unwrap_or(0)));
                    return Ok(());
                }
                change = param_changes.recv().fuse() => {
                    if let Ok(change) = change { manager.on_param(&change, &log) }
                }
                world = worlds.select_next_some() => match world {
                    Ok((w, _)) => manager.on_world_state(&w, &log),
                    Err(err) => log.warn(format!("unreadable world_state dropped: {err:?}")),
                },
                observation = observations.select_next_some() => match observation {
                    Ok((o, _)) => manager.on_observation(o, &replies, &log),
                    Err(err) => log.warn(format!("unreadable observation dropped: {err:?}")),
                },
                request = set_task_requests.select_next_some() => match request {
                    Ok((id, req)) => {
                        let response = manager.on_set_task(&req, &log);
                        if let Err(err) = set_task.send_response(id, response) {
                            log.error(format!("set_task reply failed: {err:?}"));
                        }
                    }
                    Err(err) => log.warn(format!("unreadable set_task request dropped: {err:?}")),
                },
                request = reset_requests.select_next_some() => match request {
                    Ok((id, req)) => {
                        if let Some(response) = manager.on_reset(id, &req, &log)
                            && let Err(err) = reset.send_response(id, response)
                        {
                            log.error(format!("reset reply failed: {err:?}"));
                        }
                    }
                    Err(err) => log.warn(format!("unreadable reset request dropped: {err:?}")),
                },
                request = sample_requests.select_next_some() => match request {
                    Ok((id, req)) => {
                        if let Err(err) = sample.send_response(id, on_sample_tasks(&req)) {
                            log.error(format!("sample_tasks reply failed: {err:?}"));
                        }
                    }
                    Err(err) => log.warn(format!("unreadable sample_tasks request dropped: {err:?}")),
                },
                request = simulation_requests.select_next_some() => {
                    manager.on_simulation_request(&si_servers, request, &log);
                }
                _ = futures::FutureExt::fuse(&mut expiry) => {
                    armed_for = None;
                    manager.expire_resets(&replies, &log);
                }
            }
        }
    })
}

impl TaskManager {
    fn on_param(&mut self, change: &ParamChange, log: &Logger) {
        match (change.name.as_str(), &change.value) {
            ("auto_reset", ParameterValue::Boolean(b)) => self.auto_reset = *b,
            ("horizon", ParameterValue::Integer(h)) => {
                self.horizon = *h as u32;
                log.info(format!("horizon {h} from the next episode on"));
            }
            ("reset_timeout", ParameterValue::Double(s)) => {
                self.reset_timeout = Duration::from_secs_f64(*s)
            }
            ("seed", ParameterValue::Integer(s)) => self.next_seed = *s as u64,
            ("task", ParameterValue::String(t)) => {
                if let Ok(task) = t.parse() {
                    self.task = task;
                    log.info(format!("task {task} from the next episode on"));
                }
            }
            ("service_mapping", _) => {
                log.warn("service_mapping is read at start; restart the node to change it")
            }
            _ => {}
        }
    }

    /// Compose and publish the scene of a new episode of the current task.
    fn start_episode(&mut self, seed: Option<u64>) -> Result<(u32, u64), String> {
        let seed = seed.unwrap_or(self.next_seed);
        // Laid out exactly as the sim's reset(seed) will place it (same core function).
        let layout = EpisodeLayout::new(self.task, seed).map_err(|e| e.to_string())?;
        self.episodes_started += 1;
        let number = self.episodes_started;
        self.next_seed = if seed >= MAX_SEED { 0 } else { seed + 1 };
        self.end_current(msg::EpisodeStatus::REASON_RESET, "a new episode started");
        let config = EnvConfig::default().horizon(self.horizon);
        let scene = convert::scene(&layout, &config, number, self.sim_time.clone());
        self.scene
            .publish(scene)
            .map_err(|e| format!("scene publish failed: {e:?}"))?;
        self.current = Some(Episode {
            task: self.task,
            seed,
            number,
            horizon: self.horizon,
            last_step: 0,
            last_header: convert::header(convert::time_from_nanos(0)),
            episode_return: 0.0,
            success_seen: false,
            done: false,
            started: false,
        });
        Ok((number, seed))
    }

    /// Close the current episode, if it is still running, with `reason`.
    fn end_current(&mut self, reason: u8, text: &str) {
        // An episode whose start was announced (its step-0 status) is announced ended too.
        if let Some(ep) = &mut self.current
            && !ep.done
            && (ep.started || ep.last_step > 0)
        {
            ep.done = true;
            let status = status_message(ep, reason, text, false, false);
            let _ = self.status.publish(status);
        }
    }

    /// Note the sim time of a message from the sim. False when it is not later than the last
    /// step counted of the current episode although it belongs to that episode: a sim started
    /// again replays the episode from its start, and that must not be counted as its steps.
    fn sim_time_goes_on(&mut self, episode: u32, step: u32, stamp: &Time) -> bool {
        if convert::nanos_of(stamp) > convert::nanos_of(&self.sim_time) {
            self.sim_time = stamp.clone();
        }
        match &self.current {
            Some(ep) if ep.number == episode && step > 0 && ep.last_step > 0 => {
                convert::nanos_of(stamp) > convert::nanos_of(&ep.last_header.stamp)
            }
            _ => true,
        }
    }

    /// The sim lost the current episode (it was started again): end the episode with the reason,
    /// and start the next one so that sim, reward and agents agree on the episode again. The
    /// agent's step in flight never comes; its next reset goes on as usual.
    fn sim_restarted(&mut self, what: &str, log: &Logger) {
        let Some(number) = self.current.as_ref().map(|ep| ep.number) else {
            return;
        };
        log.warn(format!(
            "the sim was started again during episode {number} ({what}): that episode's state is lost; \
             it ends here and a new episode starts"
        ));
        self.end_current(
            msg::EpisodeStatus::REASON_RESET,
            "the sim was started again; this episode's state was lost",
        );
        if let Err(err) = self.start_episode(None) {
            log.error(format!(
                "cannot start a new episode after the sim restart: {err}"
            ));
        }
    }

    fn on_world_state(&mut self, w: &msg::WorldState, log: &Logger) {
        if !self.sim_time_goes_on(w.episode, w.step, &w.header.stamp) {
            self.sim_restarted(
                &format!("world_state of step {} went back in sim time", w.step),
                log,
            );
            return;
        }
        let Some(ep) = &mut self.current else { return };
        if w.episode != ep.number || w.step == 0 || w.step <= ep.last_step || ep.done {
            return; // another episode's, the reset state, or already counted
        }
        if w.step != ep.last_step + 1 {
            log.warn(format!(
                "episode {}: world_state jumped from step {} to {} (messages lost?)",
                ep.number, ep.last_step, w.step
            ));
        }
        let snapshot = convert::snapshot(w);
        let reward = staged_reward(ep.task.objective, ep.task.object, &snapshot);
        ep.last_step = w.step;
        ep.last_header = w.header.clone();
        ep.episode_return += reward.total;
        ep.success_seen |= reward.success;
        let ended = termination(ep.task.objective, &snapshot);
        let truncated = ended.is_none() && w.step >= ep.horizon;
        let (reason, text) = match (ended, truncated) {
            (Some(t), _) => (
                msg::EpisodeStatus::REASON_OBJECT_LIFTED,
                t.reason().to_string(),
            ),
            (None, true) => (
                msg::EpisodeStatus::REASON_HORIZON,
                composuite_core::reward::horizon_reason(ep.horizon),
            ),
            (None, false) => (msg::EpisodeStatus::REASON_RUNNING, String::new()),
        };
        ep.done = ended.is_some() || truncated;
        let status = status_message(ep, reason, &text, ended.is_some(), truncated);
        let _ = self.status.publish(status);
        if ep.done {
            log.info(format!(
                "episode {} ended after {} steps: {}; return {:.3}, success {}",
                ep.number,
                ep.last_step,
                if text.is_empty() { "done" } else { &text },
                ep.episode_return,
                ep.success_seen
            ));
            if self.auto_reset
                && let Err(err) = self.start_episode(None)
            {
                log.error(format!("auto reset failed: {err}"));
            }
        }
    }

    fn on_set_task(&mut self, req: &srv::SetTaskRequest, log: &Logger) -> srv::SetTaskResponse {
        match TaskSpec::from_names(&req.robot, &req.object, &req.obstacle, &req.objective) {
            Ok(task) => {
                self.task = task;
                match self.start_episode(None) {
                    Ok((episode, seed)) => {
                        log.info(format!("set_task: {task} (episode {episode}, seed {seed})"));
                        srv::SetTaskResponse {
                            success: true,
                            message: format!(
                                "task {task}; episode {episode} started with seed {seed}"
                            ),
                            task: convert::task_spec(&task),
                        }
                    }
                    Err(err) => srv::SetTaskResponse {
                        success: false,
                        message: err,
                        task: convert::task_spec(&task),
                    },
                }
            }
            Err(err) => {
                log.warn(format!("set_task refused: {err}"));
                srv::SetTaskResponse {
                    success: false,
                    message: err.to_string(),
                    task: convert::task_spec(&self.task),
                }
            }
        }
    }

    /// Start the episode; the reply waits for its first observation (None = not yet).
    fn on_reset(
        &mut self,
        id: RmwRequestId,
        req: &srv::ResetRequest,
        log: &Logger,
    ) -> Option<srv::ResetResponse> {
        let seed = req.use_seed.then_some(req.seed);
        if let Some(seed) = seed
            && seed > MAX_SEED
        {
            return Some(failed_reset(format!(
                "seed {seed} is out of range; valid seeds are 0..={MAX_SEED}"
            )));
        }
        match self.start_episode(seed) {
            Ok((episode, seed)) => {
                log.info(format!("reset: episode {episode}, seed {seed}"));
                self.wait_for_start(id, episode, seed, Waiting::Reset);
                None
            }
            Err(err) => {
                log.warn(format!("reset refused: {err}"));
                Some(failed_reset(err))
            }
        }
    }

    /// Answer request `id` when episode `episode`'s first observation arrives (or at the
    /// timeout).
    fn wait_for_start(&mut self, id: RmwRequestId, episode: u32, seed: u64, waiting: Waiting) {
        self.pending.push(PendingReset {
            request: id,
            episode,
            seed,
            deadline: Instant::now() + self.reset_timeout,
            waiting,
        });
    }

    fn on_observation(&mut self, o: msg::Observation, replies: &Replies, log: &Logger) {
        self.sim_time_goes_on(o.episode, o.step, &o.header.stamp);
        if o.step != 0 {
            return;
        }
        if let Some(ep) = &mut self.current
            && ep.number == o.episode
        {
            if ep.started {
                self.sim_restarted("it published the episode's first observation again", log);
                return;
            }
            ep.started = true;
            // The episode's step-0 status: it is running. Sent at the reset so that an agent
            // knows this writer reaches it before step 1's status depends on that.
            ep.last_header = o.header.clone();
            let status = status_message(ep, msg::EpisodeStatus::REASON_RUNNING, "", false, false);
            let _ = self.status.publish(status);
        }
        let mut waiting = Vec::new();
        for p in self.pending.drain(..) {
            if p.episode == o.episode {
                replies.answer(&p, Ok(&o), log);
            } else if p.episode > o.episode {
                waiting.push(p);
            } else {
                // A newer episode superseded this reset before the sim answered it.
                let why = format!(
                    "episode {} was replaced by a newer one before it started",
                    p.episode
                );
                replies.answer(&p, Err(why), log);
            }
        }
        self.pending = waiting;
    }

    /// When the first of the waiting resets times out (none waits: never).
    fn next_reset_deadline(&self) -> Option<Instant> {
        self.pending.iter().map(|p| p.deadline).min()
    }

    fn expire_resets(&mut self, replies: &Replies, log: &Logger) {
        let now = Instant::now();
        let (expired, waiting): (Vec<_>, Vec<_>) =
            self.pending.drain(..).partition(|p| p.deadline <= now);
        self.pending = waiting;
        for p in expired {
            let message = format!(
                "the sim did not publish episode {}'s first observation within {:.1} s; is sim_node running in this namespace?",
                p.episode,
                self.reset_timeout.as_secs_f64()
            );
            log.error(&message);
            replies.answer(&p, Err(message), log);
        }
    }
}

/// The servers a started (or failed) episode answers on.
struct Replies<'a> {
    reset: &'a Server<srv::ResetRequest, srv::ResetResponse>,
    si: &'a simulation_services::Servers,
}

impl Replies<'_> {
    /// Answer `p`: its episode started with first observation `o`, or did not, for a reason.
    fn answer(&self, p: &PendingReset, outcome: Result<&msg::Observation, String>, log: &Logger) {
        use composuite_msgs::simulation_interfaces::msg::Result as SimResult;
        use composuite_msgs::simulation_interfaces::srv as si_srv;
        let result = match &outcome {
            Ok(_) => crate::simulation_interfaces::ok(),
            Err(why) => crate::simulation_interfaces::failed(
                SimResult::RESULT_OPERATION_FAILED,
                why.clone(),
            ),
        };
        let sent = match &p.waiting {
            Waiting::Reset => {
                let response = match outcome {
                    Ok(o) => srv::ResetResponse {
                        success: true,
                        message: String::new(),
                        episode: p.episode,
                        seed: p.seed,
                        observation: o.clone(),
                    },
                    Err(why) => failed_reset(why),
                };
                self.reset
                    .send_response(p.request, response)
                    .map_err(|e| format!("{e:?}"))
            }
            Waiting::ResetSimulation => self
                .si
                .reset
                .send_response(p.request, si_srv::ResetSimulationResponse { result })
                .map_err(|e| format!("{e:?}")),
            Waiting::LoadWorld(task) => {
                let world = if outcome.is_ok() {
                    crate::simulation_interfaces::worlds::world(*task)
                } else {
                    Default::default()
                };
                self.si
                    .load
                    .send_response(p.request, si_srv::LoadWorldResponse { result, world })
                    .map_err(|e| format!("{e:?}"))
            }
        };
        if let Err(err) = sent {
            log.error(format!("reply to a reset failed: {err}"));
        }
    }
}

fn failed_reset(message: String) -> srv::ResetResponse {
    srv::ResetResponse {
        success: false,
        message,
        ..Default::default()
    }
}

fn status_message(
    ep: &Episode,
    reason: u8,
    text: &str,
    terminated: bool,
    truncated: bool,
) -> msg::EpisodeStatus {
    msg::EpisodeStatus {
        // Stamped like the last step counted (a reset ending an episode has no step of its own).
        header: ep.last_header.clone(),
        task: convert::task_spec(&ep.task),
        seed: ep.seed,
        episode: ep.number,
        step: ep.last_step,
        horizon: ep.horizon,
        done: ep.done,
        terminated,
        truncated,
        reason,
        reason_text: text.into(),
        episode_return: ep.episode_return,
        success_seen: ep.success_seen,
    }
}

fn on_sample_tasks(req: &srv::SampleTasksRequest) -> srv::SampleTasksResponse {
    let result = req
        .experiment
        .parse::<Experiment>()
        .map_err(|e| e.to_string())
        .and_then(|experiment| {
            let element = Some(req.element.as_str()).filter(|e| !e.is_empty());
            sample_tasks(
                experiment,
                req.num_train as usize,
                element,
                req.seed,
                req.no_shuffle,
            )
            .map_err(|e| e.to_string())
        });
    match result {
        Ok(split) => srv::SampleTasksResponse {
            success: true,
            message: String::new(),
            train: split.train.iter().map(convert::task_spec).collect(),
            test: split.test.iter().map(convert::task_spec).collect(),
        },
        Err(message) => srv::SampleTasksResponse {
            success: false,
            message,
            train: Vec::new(),
            test: Vec::new(),
        },
    }
}
