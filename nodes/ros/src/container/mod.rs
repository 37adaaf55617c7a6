//! Many environments' nodes in one process on one DDS participant — ROS 2's composition, as
//! rclcpp_components' containers do it.
//!
//! Each environment's nodes (task_manager, sim, reward) are the same nodes as their own
//! processes would be: the same names, namespaces, topics, services, parameters and QoS, each a
//! ROS node in `ros2 node list`. Here each runs on a thread of its own, and all share one
//! participant: a suite of N environments is one participant to DDS discovery, where N × 3
//! processes were N × 3 participants that each tracked every other.
//!
//! They share two more things ([`Composition`]): the sims' physics (each environment's resets
//! and steps) runs on one pool of `threads` threads, whichever environment asks — a queue, so
//! an environment's step waits for a free thread, never for the other environments; and each
//! environment's sim hands `world_state` and `observation` to its reward and task manager in
//! the process ([`crate::shared::intra_process`]) while they still go on the wire for everyone
//! else.
//!
//! A node that fails — panics, or returns an error — ends its environment only: the
//! environment's other nodes are stopped, the failure is logged, and the environment starts
//! again after a delay, at most `respawn` times (then the whole container stops with the
//! reason). The other environments go on meanwhile. A SIGKILL of the process ends every
//! environment at once: separate processes (`composuite launch --isolate`) are for that.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use std::sync::Arc;

use composuite_core::batch::StepPool;

use crate::nodes::NodeKind;
use crate::shared::environment::RosEnvironment;
use crate::shared::intra_process::IntraProcess;
use crate::shared::node::{Composition, RosNode, Startup, new_context};

/// How long the nodes get to stop after they were told to.
const GRACE: Duration = Duration::from_secs(5);
/// What a node's loop gets on its channel to stop: SIGINT's number, as from a terminal.
const STOP: i32 = 2;

/// One node of an environment: its kind and its command-line arguments (`--ros-args ...`), as
/// its own process would get them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeLaunch {
    /// Which node.
    pub kind: NodeKind,
    /// Its arguments.
    pub argv: Vec<String>,
}

/// One environment: its namespace (for messages) and its nodes, in start order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EnvironmentLaunch {
    /// The environment's namespace, e.g. `/env_03`.
    pub namespace: String,
    /// Its nodes.
    pub nodes: Vec<NodeLaunch>,
}

/// How the container restarts failed environments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RespawnPolicy {
    /// Restarts per environment; past them, a failure stops the container.
    pub limit: u32,
    /// Time between a failure and the restart.
    pub delay: Duration,
}

/// What ended a node's thread.
#[derive(Debug)]
enum Outcome {
    /// Its body returned after it was told to stop.
    Stopped,
    /// It did not start, returned an error or panicked.
    Failed(String),
}

/// A message from a node's thread when it ends.
struct Ended {
    env: usize,
    generation: u32,
    kind: NodeKind,
    outcome: Outcome,
}

/// A running node: how to stop it and its thread.
struct NodeThread {
    kind: NodeKind,
    stop: async_channel::Sender<i32>,
    thread: Option<JoinHandle<()>>,
}

/// An environment's state in the container.
struct Environment {
    launch: EnvironmentLaunch,
    nodes: Vec<NodeThread>,
    /// Bumped at every start, so late messages of a stopped generation are told apart.
    generation: u32,
    restarts: u32,
    /// Since when it waits for its restart (every node of it stopped).
    failed_at: Option<Instant>,
}

/// The container: what its nodes share, the environments and their node threads.
pub struct Container {
    composition: Composition,
    environments: Vec<Environment>,
    ended_tx: mpsc::Sender<Ended>,
    ended_rx: mpsc::Receiver<Ended>,
    policy: RespawnPolicy,
}

impl Container {
    /// Start every environment's nodes on one new participant (domain, discovery range and
    /// security from the process environment, as for any node; `enclave` as a node's
    /// `--enclave`), their physics stepped by `threads` threads.
    pub fn start(
        environments: Vec<EnvironmentLaunch>,
        policy: RespawnPolicy,
        threads: usize,
        enclave: Option<&str>,
    ) -> Result<Container, String> {
        if threads == 0 {
            return Err("the environments need at least 1 thread to step on".into());
        }
        // The sims hand their steps to the pool's workers and wait (a step that finds no other
        // running or waiting runs on its sim's own thread instead).
        let step_pool = StepPool::new(threads).map_err(|e| format!("--threads {threads}: {e}"))?;
        let ros_environment =
            RosEnvironment::read(|k| std::env::var(k).ok()).map_err(|e| e.to_string())?;
        // The composed nodes share one participant, so one enclave.
        let context =
            new_context(&ros_environment, enclave, "container").map_err(|e| e.to_string())?;
        let (ended_tx, ended_rx) = mpsc::channel();
        let mut container = Container {
            composition: Composition {
                context,
                intra_process: Arc::new(IntraProcess::new()),
                step_pool: Arc::new(step_pool),
            },
            environments: environments
                .into_iter()
                .map(|launch| Environment {
                    launch,
                    nodes: Vec::new(),
                    generation: 0,
                    restarts: 0,
                    failed_at: None,
                })
                .collect(),
            ended_tx,
            ended_rx,
            policy,
        };
        for env in 0..container.environments.len() {
            container.start_environment(env)?;
        }
        Ok(container)
    }

    /// Number of environments.
    pub fn len(&self) -> usize {
        self.environments.len()
    }

    /// Whether the container holds no environment.
    pub fn is_empty(&self) -> bool {
        self.environments.is_empty()
    }

    fn start_environment(&mut self, env: usize) -> Result<(), String> {
        let environment = &mut self.environments[env];
        environment.generation += 1;
        environment.failed_at = None;
        let generation = environment.generation;
        let mut nodes = Vec::new();
        for launch in &environment.launch.nodes {
            let (stop, stop_rx) = async_channel::bounded(1);
            let composition = self.composition.clone();
            let ended = self.ended_tx.clone();
            let kind = launch.kind;
            let argv = launch.argv.clone();
            let thread = std::thread::Builder::new()
                .name(format!("{}-{env}", kind.name()))
                .spawn(move || {
                    let outcome = run_node(kind, &argv, &composition, stop_rx);
                    let _ = ended.send(Ended {
                        env,
                        generation,
                        kind,
                        outcome,
                    });
                })
                .map_err(|e| {
                    format!(
                        "cannot start a thread for {kind} in {}: {e}",
                        environment.launch.namespace
                    )
                })?;
            nodes.push(NodeThread {
                kind,
                stop,
                thread: Some(thread),
            });
        }
        environment.nodes = nodes;
        Ok(())
    }

    /// Take what happened since the last call: restart environments whose delay is over, stop
    /// the nodes of environments that lost one. `Err` (the failure, described) when an
    /// environment failed once more than the policy allows: stop the container then.
    pub fn poll(&mut self, wait: Duration) -> Result<(), String> {
        let deadline = Instant::now() + wait;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.ended_rx.recv_timeout(left) {
                Ok(ended) => self.on_ended(ended)?,
                Err(mpsc::RecvTimeoutError::Timeout) => break,
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
        let now = Instant::now();
        for env in 0..self.environments.len() {
            let due = self.environments[env]
                .failed_at
                .is_some_and(|t| now >= t + self.policy.delay);
            if due {
                self.environments[env].restarts += 1;
                self.start_environment(env)?;
            }
        }
        Ok(())
    }

    fn on_ended(&mut self, ended: Ended) -> Result<(), String> {
        let environment = &mut self.environments[ended.env];
        if ended.generation != environment.generation || environment.failed_at.is_some() {
            // A node of an environment already being restarted, stopping as it was told.
            return Ok(());
        }
        let namespace = environment.launch.namespace.clone();
        let why = match ended.outcome {
            Outcome::Failed(why) => why,
            Outcome::Stopped => "stopped on its own".to_string(),
        };
        let death = format!("{} in {namespace} failed: {why}", ended.kind);
        if environment.restarts >= self.policy.limit {
            return Err(match self.policy.limit {
                0 => death,
                limit => format!("{death}, after {limit} restart(s) (--respawn {limit})"),
            });
        }
        eprintln!(
            "composuite container: {death}; stopping the other nodes of {namespace} and starting \
             it again in {:.1} s (restart {} of {}); the other environments go on",
            self.policy.delay.as_secs_f64(),
            environment.restarts + 1,
            self.policy.limit
        );
        let stopped = stop_nodes(std::mem::take(&mut environment.nodes));
        if !stopped.is_empty() {
            eprintln!(
                "composuite container: {} of {namespace} did not stop within {GRACE:?}; its thread is left behind",
                stopped.join(", ")
            );
        }
        environment.failed_at = Some(Instant::now());
        Ok(())
    }

    /// Stop every node (each environment's in reverse start order) and wait for them. True when
    /// every node stopped cleanly within the grace period.
    pub fn stop(mut self) -> bool {
        // Failures reported before the stop are not failures of the stop.
        while self.ended_rx.try_recv().is_ok() {}
        let mut clean = true;
        let environments = std::mem::take(&mut self.environments);
        // Tell every node first, so the environments stop together, then wait.
        for environment in &environments {
            for node in &environment.nodes {
                let _ = node.stop.try_send(STOP);
            }
        }
        for environment in environments {
            let late = stop_nodes(environment.nodes);
            if !late.is_empty() {
                clean = false;
                eprintln!(
                    "composuite container: {} in {} did not stop within {GRACE:?}",
                    late.join(", "),
                    environment.launch.namespace
                );
            }
        }
        while let Ok(ended) = self.ended_rx.try_recv() {
            if let Outcome::Failed(why) = ended.outcome {
                clean = false;
                eprintln!(
                    "composuite container: {} stopped with an error: {why}",
                    ended.kind
                );
            }
        }
        clean
    }
}

/// Tell `nodes` to stop (last started first) and wait for each up to [`GRACE`]; the names of
/// those that did not stop in time.
fn stop_nodes(nodes: Vec<NodeThread>) -> Vec<String> {
    for node in nodes.iter().rev() {
        let _ = node.stop.try_send(STOP);
    }
    let until = Instant::now() + GRACE;
    let mut late = Vec::new();
    for mut node in nodes.into_iter().rev() {
        let Some(thread) = node.thread.take() else {
            continue;
        };
        while !thread.is_finished() && Instant::now() < until {
            std::thread::sleep(Duration::from_millis(10));
        }
        if thread.is_finished() {
            let _ = thread.join();
        } else {
            late.push(node.kind.name().to_string());
        }
    }
    late
}

/// Start node `kind` with `argv` in `composition` and run it until `stop` delivers; a panic is
/// caught and reported like an error.
fn run_node(
    kind: NodeKind,
    argv: &[String],
    composition: &Composition,
    stop: async_channel::Receiver<i32>,
) -> Outcome {
    let result = catch_unwind(AssertUnwindSafe(|| {
        match RosNode::start_in(kind.spec(), argv, Some(composition)) {
            Ok(Startup::Node(node)) => node.run(kind.body(), stop),
            Ok(Startup::Help(_)) => Err("--help is not a node's argument here".into()),
            Err(e) => Err(format!("did not start: {e}")),
        }
    }));
    match result {
        Ok(Ok(())) => Outcome::Stopped,
        Ok(Err(e)) => Outcome::Failed(e),
        Err(panic) => Outcome::Failed(format!("panicked: {}", panic_message(&panic))),
    }
}

fn panic_message(panic: &Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".into()
    }
}
