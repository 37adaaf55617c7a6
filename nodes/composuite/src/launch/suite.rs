//! Starting the suite's nodes (as child processes or composed into this process) and
//! supervising them: noticing deaths, respawning, stopping the whole suite.

use std::path::PathBuf;
use std::process::{Child, Command};
use std::time::{Duration, Instant};

use composuite_ros::container::{Container, EnvironmentLaunch, NodeLaunch, RespawnPolicy};
use composuite_ros::nodes::NodeKind;

use super::LaunchArgs;
use super::argv::{env_namespace, node_arguments, node_argv, split_environments};
use super::process::{RECORDER_NICENESS, RECORDER_SETTLE, Running, node_process_setup, stop_all};
use super::validate::validate;

/// The nodes of a running suite (every environment's three).
pub(crate) struct Suite {
    exe: PathBuf,
    nodes: Vec<Running>,
    /// The environments' nodes when they are composed into this process.
    container: Option<Container>,
}

impl Suite {
    /// Validate `args` and start every node as a child process of this executable.
    pub(crate) fn start(args: &LaunchArgs) -> Result<Suite, String> {
        validate(args)?;
        let exe =
            std::env::current_exe().map_err(|e| format!("cannot find this executable: {e}"))?;
        let mut suite = Suite {
            exe,
            nodes: Vec::new(),
            container: None,
        };
        // The recorder first, so it hears the environments from their first message.
        if args.record.is_some() {
            let namespace = env_namespace(&args.namespace, 0, 1);
            suite.add(
                format!("{} in {namespace}", NodeKind::Recorder),
                true,
                node_argv(NodeKind::Recorder, args, "/", 0),
            )?;
        }
        if args.composed() && args.processes > 1 {
            for range in split_environments(args.envs, args.processes) {
                let what = format!(
                    "environments {}..{} of {} (a process)",
                    range.start, range.end, args.namespace
                );
                suite.add(what, false, args.container_process_argv(&range))?;
            }
            return Ok(suite);
        }
        if args.composed() {
            let environments = args
                .env_indices()?
                .map(|index| {
                    let namespace = env_namespace(&args.namespace, index, args.envs);
                    EnvironmentLaunch {
                        nodes: NodeKind::ALL
                            .into_iter()
                            .map(|kind| NodeLaunch {
                                kind,
                                argv: node_arguments(args, kind, &namespace, index),
                            })
                            .collect(),
                        namespace,
                    }
                })
                .collect();
            let policy = RespawnPolicy {
                limit: args.respawn,
                delay: Duration::from_secs_f64(args.respawn_delay),
            };
            match Container::start(
                environments,
                policy,
                args.step_threads(),
                args.enclave.as_deref(),
            ) {
                Ok(container) => suite.container = Some(container),
                Err(e) => {
                    stop_all(&mut suite.nodes);
                    return Err(format!("cannot start the environments: {e}"));
                }
            }
            return Ok(suite);
        }
        for index in 0..args.envs {
            let namespace = env_namespace(&args.namespace, index, args.envs);
            for kind in NodeKind::ALL {
                let argv = node_argv(kind, args, &namespace, index);
                suite.add(format!("{kind} in {namespace}"), false, argv)?;
            }
        }
        Ok(suite)
    }

    /// Start one child process (a node, or a share of the composed environments); on failure
    /// stop the ones started and say why.
    fn add(&mut self, what: String, recorder: bool, argv: Vec<String>) -> Result<(), String> {
        match self.spawn(recorder, &argv) {
            Ok(child) => {
                self.nodes.push(Running {
                    what,
                    recorder,
                    argv,
                    child,
                    restarts: 0,
                    died_at: None,
                    gone: false,
                });
                Ok(())
            }
            Err(e) => {
                stop_all(&mut self.nodes);
                Err(format!("cannot start {what}: {e}"))
            }
        }
    }

    fn spawn(&self, recorder: bool, argv: &[String]) -> std::io::Result<Child> {
        use std::os::unix::process::CommandExt;
        let mut command = Command::new(&self.exe);
        command.args(argv);
        let niceness = if recorder { RECORDER_NICENESS } else { 0 };
        let launcher = std::process::id() as libc::pid_t;
        // SAFETY: the closure runs in the forked child before exec and makes only system calls
        // that are async-signal-safe (setpgid, prctl, getppid, getpriority, setpriority).
        unsafe {
            command.pre_exec(move || node_process_setup(niceness, launcher));
        }
        command.spawn()
    }

    /// The first node that exited on its own, described.
    pub(crate) fn died(&mut self) -> Option<String> {
        if let Some(container) = &mut self.container
            && let Err(death) = container.poll(Duration::ZERO)
        {
            return Some(death);
        }
        self.nodes
            .iter_mut()
            .find_map(|n| n.child.try_wait().ok().flatten().map(|s| n.death(s)))
    }

    /// Start again every node that died, `delay` after its death, at most `limit` times per
    /// node. Err (the node's death, described) when one died once more than `limit` allows.
    pub(super) fn respawn(&mut self, limit: u32, delay: Duration) -> Result<(), String> {
        if let Some(container) = &mut self.container {
            container.poll(Duration::ZERO)?;
        }
        let now = Instant::now();
        for index in 0..self.nodes.len() {
            let n = &mut self.nodes[index];
            if n.died_at.is_none()
                && let Ok(Some(status)) = n.child.try_wait()
            {
                let death = n.death(status);
                if n.recorder {
                    // Its bag directory exists now, so it cannot start again; the
                    // environments go on (what it wrote stays readable, see `bag reindex`).
                    eprintln!("composuite launch: {death}; the suite goes on without recording");
                    n.died_at = Some(now);
                    n.gone = true;
                    continue;
                }
                if n.restarts >= limit {
                    return Err(match limit {
                        0 => death,
                        _ => format!("{death}, after {limit} restart(s) (--respawn {limit})"),
                    });
                }
                eprintln!(
                    "composuite launch: {death}; starting it again in {:.1} s (restart {} of {limit})",
                    delay.as_secs_f64(),
                    n.restarts + 1
                );
                n.died_at = Some(now);
            }
            let n = &self.nodes[index];
            if !n.gone && n.died_at.is_some_and(|t| now >= t + delay) {
                let child = self
                    .spawn(n.recorder, &n.argv)
                    .map_err(|e| format!("cannot start {} again: {e}", n.what))?;
                let n = &mut self.nodes[index];
                n.child = child;
                n.restarts += 1;
                n.died_at = None;
            }
        }
        Ok(())
    }

    /// Stop every node; true when all exited cleanly.
    pub(crate) fn stop(mut self) -> bool {
        // The environments first, then the recorder: it records until they are gone.
        let mut clean = true;
        if let Some(container) = self.container.take() {
            if self.nodes.iter().any(|n| n.died_at.is_none()) {
                std::thread::sleep(RECORDER_SETTLE);
            }
            clean = container.stop();
        }
        stop_all(&mut self.nodes) && clean
    }
}
