//! `composuite launch`: the node suite headless. Every environment is the three nodes
//! (task_manager, sim, reward) in a namespace of its own.
//!
//! With several environments the nodes are composed: they all run in this process, on one DDS
//! participant, each on a thread of its own (`composuite_ros::container`); an environment whose
//! node fails is stopped and started again (`--respawn`) while the others go on. With one
//! environment, or with `--isolate`, every node is a child process of its own — this same
//! executable run as `composuite node KIND --ros-args ...`, so the launcher never looks for
//! binaries on a path — and signals are passed on; a node that dies is started again
//! (`--respawn`, like `respawn=True` in `ros2 launch`). `--processes K` splits the composed
//! environments over K child processes (this executable run as `composuite launch` with a
//! hidden `--env-range`), each a container on its own participant, restarted as a whole if it
//! dies. Past the respawn limit, or when time is
//! up, every node is stopped (SIGINT, then SIGKILL after a grace period) and the launcher exits
//! with a code that says what happened. A recorder is always a process of its own.

use std::ops::Range;
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};

use clap::Args;
use composuite_core::TaskSpec;
use composuite_ros::container::{Container, EnvironmentLaunch, NodeLaunch, RespawnPolicy};
use composuite_ros::nodes::NodeKind;
use composuite_ros::shared::ros_args::is_valid_name;

/// How long nodes get to exit after SIGINT before they are killed.
const GRACE: Duration = Duration::from_secs(5);
/// With a recorder: how long the environments keep running after the last command before they
/// are stopped, so reliable DDS can resend whatever the recorder missed (RustDDS heartbeats a
/// lagging reader every 100 ms); a node that exits takes its unacknowledged samples with it.
const RECORDER_SETTLE: Duration = Duration::from_secs(1);
/// The recorder runs this much nicer than the environments: it is never on the lockstep
/// chain (sim → reward → agent → sim), so on a machine with few cores it should take the CPU
/// only when the chain leaves it idle and catch up then — reliable DDS keeps what it has not
/// acknowledged until it does.
const RECORDER_NICENESS: libc::c_int = 10;

/// Start the node suite headless: N environments × (task_manager, sim, reward).
///
/// Each environment lives in its own namespace: with `--envs 1` the namespace given (default
/// `/`), with more `NS/env_00`, `NS/env_01`, ... Environment i starts at seed `--seed` + i.
/// Ctrl-C (or SIGTERM) stops everything cleanly. DDS settings come from the environment as for
/// any ROS 2 node (ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE).
///
/// Example: composuite launch --task Panda/plate/goal_wall/trash_can --mode lockstep --envs 2
/// --namespace /train
#[derive(Args, Debug)]
pub struct LaunchArgs {
    /// Task of the first episode, robot/object/obstacle/objective (any spelling of each axis)
    /// [default: IIWA/box/no_obstacle/pick_place].
    #[arg(long)]
    task: Option<String>,
    /// lockstep (one control period per joint_command) or realtime (wall-clock pace)
    /// [default: lockstep].
    #[arg(long)]
    mode: Option<String>,
    /// Namespace of the environment(s), e.g. /train.
    #[arg(long, default_value = "/")]
    namespace: String,
    /// Number of environments.
    #[arg(long, default_value_t = 1)]
    envs: usize,
    /// Every node a process of its own, as with one environment, instead of all environments'
    /// nodes in this process on one DDS participant (the default with --envs > 1). Costs a
    /// participant per node (discovery grows with the square of the nodes); buys isolation: a
    /// node killed (SIGKILL) takes only itself down.
    #[arg(long)]
    isolate: bool,
    /// Split the composed environments over this many processes, each holding a contiguous
    /// share of them on a DDS participant of its own (e.g. one per NUMA node or core group).
    /// A process that dies (even SIGKILL) is started again with its environments (--respawn);
    /// the other processes go on. Not with --isolate.
    #[arg(long, default_value_t = 1)]
    processes: usize,
    /// Threads that step the composed environments' physics, shared by all of them: an
    /// environment's reset or step waits for a free thread, never for the other environments;
    /// one that finds no other running runs at once on its sim's own thread (each process of
    /// --processes has this many) [default: the available cores].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// The environments this process holds, START..END of --envs (set by a launcher that
    /// splits them over --processes; not for users).
    #[arg(long, hide = true, value_name = "START..END")]
    env_range: Option<String>,
    /// Seed of the first episode (environment i: seed + i) [default: 0].
    #[arg(long)]
    seed: Option<u64>,
    /// Control steps per episode [default: 500].
    #[arg(long)]
    pub(crate) horizon: Option<u32>,
    /// Sparse rewards, as the reference's `make(reward_shaping=False)`: 1 on success, else 0
    /// (the stages are still published) [default: shaped].
    #[arg(long)]
    sparse_rewards: bool,
    /// Multiply every reward by this, as the reference's `reward_scale` [default: 1].
    #[arg(long, value_name = "SCALE")]
    reward_scale: Option<f64>,
    /// Service wire format: fastdds (rmw_fastrtps, Jazzy's default) or cyclone (rmw_cyclonedds)
    /// [default: fastdds].
    #[arg(long)]
    service_mapping: Option<String>,
    /// Start the next episode as soon as one ends.
    #[arg(long)]
    auto_reset: bool,
    /// A parameters file (`/**: ros__parameters:` form) given to every node; the options above,
    /// when given, win over it.
    #[arg(long)]
    params_file: Option<PathBuf>,
    /// Log level of the nodes: debug, info, warn, error, fatal.
    #[arg(long, default_value = "info")]
    log_level: String,
    /// Stop after this many seconds (default: run until Ctrl-C / SIGTERM).
    #[arg(long)]
    duration: Option<f64>,
    /// Start a node that dies again, at most this many times per node; 0: a dying node stops
    /// the whole suite. A restarted node rejoins its environment: the step in flight is lost (the
    /// agent times out on it) and the next reset starts a consistent episode.
    #[arg(long, default_value_t = 3)]
    respawn: u32,
    /// Seconds between a node's death and its restart.
    #[arg(long, default_value_t = 1.0)]
    respawn_delay: f64,
    /// Record every topic of the graph into this new rosbag2 directory (MCAP), as
    /// `ros2 bag record -a -s mcap -o DIR` would: the recorder node starts first and closes the
    /// bag last. If it dies, the suite keeps running without it.
    #[arg(long, value_name = "DIR")]
    pub(crate) record: Option<PathBuf>,
    /// With --record: record only topics whose full name matches this regex.
    #[arg(long, value_name = "REGEX", requires = "record")]
    record_regex: Option<String>,
    /// With --record: never record topics whose full name matches this regex.
    #[arg(long, value_name = "REGEX", requires = "record")]
    record_exclude: Option<String>,
    /// With --record: start a new bag file every this many bytes (like --max-bag-size).
    #[arg(long, value_name = "BYTES", requires = "record")]
    pub(crate) record_max_bag_size: Option<u64>,
    /// With --record: start a new bag file every this many seconds (like --max-bag-duration).
    #[arg(long, value_name = "SECONDS", requires = "record")]
    pub(crate) record_max_bag_duration: Option<f64>,
}

struct Running {
    /// What it is, for messages: "sim in /env_00", "environments 0..4 of /train".
    what: String,
    /// A recorder: never started again (its bag exists), stopped after the environments.
    recorder: bool,
    /// Its command line after the executable (it is started again with the same).
    argv: Vec<String>,
    child: Child,
    /// Times it was started again.
    restarts: u32,
    /// When it died, while it waits for its restart.
    died_at: Option<Instant>,
    /// Dead for good (a recorder is never restarted: its bag exists).
    gone: bool,
}

/// The namespace of environment `index` of `count`.
fn env_namespace(base: &str, index: usize, count: usize) -> String {
    let base = base.trim_end_matches('/');
    if count == 1 {
        if base.is_empty() {
            "/".into()
        } else {
            base.into()
        }
    } else {
        format!("{base}/env_{index:02}")
    }
}

fn validate(args: &LaunchArgs) -> Result<(), String> {
    if let Some(task) = &args.task {
        task.parse::<TaskSpec>()
            .map_err(|e| format!("--task: {e}"))?;
    }
    if let Some(mode) = &args.mode
        && composuite_ros::sim::Mode::parse(mode).is_none()
    {
        return Err(format!(
            "--mode {mode} is invalid; valid: lockstep, realtime"
        ));
    }
    if let Some(mapping) = &args.service_mapping {
        composuite_ros::shared::node::service_mapping(mapping)
            .map_err(|e| format!("--service-mapping: {e}"))?;
    }
    let namespace_ok = args.namespace == "/"
        || (args.namespace.starts_with('/') && is_valid_name(&args.namespace, true));
    if !namespace_ok {
        return Err(format!(
            "--namespace {} is invalid; it must be absolute, e.g. /train",
            args.namespace
        ));
    }
    if !(1..=100).contains(&args.envs) {
        return Err(format!("--envs {} is invalid; valid: 1 to 100", args.envs));
    }
    if !(1..=args.envs).contains(&args.processes) {
        return Err(format!(
            "--processes {} is invalid; valid: 1 to --envs ({})",
            args.processes, args.envs
        ));
    }
    if args.processes > 1 && !args.composed() {
        return Err(
            "--processes needs composed environments: --envs 2 or more, without --isolate".into(),
        );
    }
    args.env_indices()?;
    if args.threads == Some(0) {
        return Err(
            "--threads 0 is invalid; at least 1 thread steps the environments (leave it out \
             for one per available core)"
                .into(),
        );
    }
    if args.threads.is_some() && !args.composed() {
        return Err(
            "--threads needs composed environments: --envs 2 or more, without --isolate (a \
             node process steps its one environment on its own thread)"
                .into(),
        );
    }
    if args.horizon == Some(0) {
        return Err("--horizon must be at least 1".into());
    }
    if let Some(scale) = args.reward_scale
        && !scale.is_finite()
    {
        return Err(format!(
            "--reward-scale {scale} is invalid; a finite number"
        ));
    }
    if let Some(d) = args.duration
        && !(d.is_finite() && d > 0.0)
    {
        return Err(format!("--duration {d} is invalid; seconds > 0"));
    }
    if !(args.respawn_delay.is_finite() && args.respawn_delay >= 0.0) {
        return Err(format!(
            "--respawn-delay {} is invalid; seconds >= 0",
            args.respawn_delay
        ));
    }
    if let Some(dir) = &args.record
        && dir.exists()
    {
        return Err(format!(
            "--record {}: it exists already; give a new directory (a bag is never overwritten)",
            dir.display()
        ));
    }
    if args.record_max_bag_size == Some(0) {
        return Err(
            "--record-max-bag-size 0 is invalid; bytes > 0 (leave it out for one file)".into(),
        );
    }
    if let Some(s) = args.record_max_bag_duration
        && !(s.is_finite() && s > 0.0)
    {
        return Err(format!(
            "--record-max-bag-duration {s} is invalid; seconds > 0 (leave it out for one file)"
        ));
    }
    for (flag, regex) in [
        ("--record-regex", &args.record_regex),
        ("--record-exclude", &args.record_exclude),
    ] {
        if let Some(r) = regex {
            regex::Regex::new(r).map_err(|e| format!("{flag}: not a regex: {e}"))?;
        }
    }
    if let Some(f) = &args.params_file
        && !f.is_file()
    {
        return Err(format!("--params-file {}: no such file", f.display()));
    }
    Ok(())
}

/// A node's command line after the executable: `node KIND --ros-args ...`.
fn node_argv(kind: NodeKind, args: &LaunchArgs, namespace: &str, index: usize) -> Vec<String> {
    let mut argv = vec!["node".to_string(), kind.name().to_string()];
    argv.extend(node_arguments(args, kind, namespace, index));
    argv
}

/// `envs` environments in `processes` contiguous shares, the larger ones first.
fn split_environments(envs: usize, processes: usize) -> Vec<Range<usize>> {
    let (share, larger) = (envs / processes, envs % processes);
    let mut start = 0;
    (0..processes)
        .map(|k| {
            let end = start + share + usize::from(k < larger);
            let range = start..end;
            start = end;
            range
        })
        .collect()
}

/// The `--ros-args` of one node.
fn node_arguments(args: &LaunchArgs, kind: NodeKind, namespace: &str, index: usize) -> Vec<String> {
    let mut out = vec![
        "--ros-args".to_string(),
        "-r".into(),
        format!("__ns:={namespace}"),
    ];
    if let Some(file) = &args.params_file {
        out.extend(["--params-file".into(), file.display().to_string()]);
    }
    let mut param = |name: &str, value: String| {
        out.extend(["-p".into(), format!("{name}:={value}")]);
    };
    // Only what was asked for: anything else comes from the params file or the defaults.
    if let Some(mapping) = &args.service_mapping {
        param("service_mapping", mapping.clone());
    }
    match kind {
        NodeKind::Sim => {
            if let Some(mode) = &args.mode {
                param("mode", mode.clone());
            }
        }
        NodeKind::TaskManager => {
            if let Some(task) = &args.task {
                param("task", task.clone());
            }
            if args.seed.is_some() || index > 0 {
                param("seed", (args.seed.unwrap_or(0) + index as u64).to_string());
            }
            if let Some(horizon) = args.horizon {
                param("horizon", horizon.to_string());
            }
            if args.auto_reset {
                param("auto_reset", "true".into());
            }
        }
        NodeKind::Reward => {
            if args.sparse_rewards {
                param("reward_shaping", "false".into());
            }
            if let Some(scale) = args.reward_scale {
                param("reward_scale", format!("{scale:?}"));
            }
        }
        NodeKind::Recorder => {
            if let Some(dir) = &args.record {
                param("output", dir.display().to_string());
            }
            match &args.record_regex {
                Some(r) => param("regex", r.clone()),
                None => param("all", "true".into()),
            }
            if let Some(r) = &args.record_exclude {
                param("exclude_regex", r.clone());
            }
            if let Some(size) = args.record_max_bag_size {
                param("max_bag_size", size.to_string());
            }
            if let Some(seconds) = args.record_max_bag_duration {
                param("max_bag_duration", format!("{seconds:?}"));
            }
        }
    }
    out.extend(["--log-level".into(), args.log_level.clone()]);
    out
}

/// What a node process does between fork and exec:
/// - its own process group, so a Ctrl-C at the terminal reaches only the launcher, which stops
///   the nodes in order (the environments, then the recorder, which records until they are
///   gone) instead of all at once;
/// - SIGTERM when the launcher dies, however it dies (even SIGKILL): the node then shuts down
///   as on any SIGTERM — a recorder closes its bag — instead of running on, orphaned. (Linux
///   sends it when the *thread* that spawned the node ends: the suite spawns from the main
///   thread only.)
/// - the recorder at a lower priority, set before the node starts any thread so that it holds
///   for all of them: it is never on the lockstep chain and catches up in the chain's gaps.
///
/// # Safety
/// Only async-signal-safe calls: it runs in the forked child of a multi-threaded process.
unsafe fn node_process_setup(niceness: libc::c_int, launcher: libc::pid_t) -> std::io::Result<()> {
    let failed = || Err(std::io::Error::last_os_error());
    // SAFETY: plain system calls on the calling process; no memory is shared or allocated.
    unsafe {
        if libc::setpgid(0, 0) != 0 {
            return failed();
        }
        if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
            return failed();
        }
        // The launcher may have died between fork and prctl: then no SIGTERM will come.
        if libc::getppid() != launcher {
            return Err(std::io::Error::from_raw_os_error(libc::ESRCH));
        }
        if niceness != 0 {
            let now = libc::getpriority(libc::PRIO_PROCESS, 0);
            if libc::setpriority(libc::PRIO_PROCESS, 0, now + niceness) != 0 {
                return failed();
            }
        }
    }
    Ok(())
}

/// Send `signal` to a child (it may have exited already; that is fine).
fn signal(child: &Child, signal: i32) {
    // SAFETY: kill(2) on a pid we spawned; no memory is touched.
    unsafe {
        libc::kill(child.id() as libc::pid_t, signal);
    }
}

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
            match Container::start(environments, policy, args.step_threads()) {
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
    fn respawn(&mut self, limit: u32, delay: Duration) -> Result<(), String> {
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

impl LaunchArgs {
    /// Whether the environments' nodes run composed in this process (several environments,
    /// no `--isolate`).
    pub(crate) fn composed(&self) -> bool {
        self.envs > 1 && !self.isolate
    }

    /// Threads stepping the composed environments: `--threads`, or one per available core.
    fn step_threads(&self) -> usize {
        self.threads.unwrap_or_else(|| {
            std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
        })
    }

    /// The environments this process holds: `--env-range`, or all of them.
    fn env_indices(&self) -> Result<Range<usize>, String> {
        let Some(range) = &self.env_range else {
            return Ok(0..self.envs);
        };
        let parsed = range
            .split_once("..")
            .and_then(|(a, b)| Some(a.parse::<usize>().ok()?..b.parse::<usize>().ok()?));
        match parsed {
            Some(r) if r.start < r.end && r.end <= self.envs => Ok(r),
            _ => Err(format!(
                "--env-range {range} is invalid; START..END with START < END <= --envs ({})",
                self.envs
            )),
        }
    }

    /// The command line of a child process holding `range` of the composed environments: the
    /// options every environment's nodes get, and nothing the launcher keeps for itself (the
    /// recorder, --duration, --processes).
    fn container_process_argv(&self, range: &Range<usize>) -> Vec<String> {
        let mut argv: Vec<String> = vec![
            "launch".into(),
            "--namespace".into(),
            self.namespace.clone(),
            "--envs".into(),
            self.envs.to_string(),
            "--env-range".into(),
            format!("{}..{}", range.start, range.end),
            "--respawn".into(),
            self.respawn.to_string(),
            "--respawn-delay".into(),
            format!("{:?}", self.respawn_delay),
            "--log-level".into(),
            self.log_level.clone(),
        ];
        let mut option = |flag: &str, value: Option<String>| {
            if let Some(value) = value {
                argv.extend([flag.to_string(), value]);
            }
        };
        option("--task", self.task.clone());
        option("--mode", self.mode.clone());
        option("--threads", self.threads.map(|t| t.to_string()));
        option("--seed", self.seed.map(|s| s.to_string()));
        option("--horizon", self.horizon.map(|h| h.to_string()));
        option(
            "--reward-scale",
            self.reward_scale.map(|r| format!("{r:?}")),
        );
        option("--service-mapping", self.service_mapping.clone());
        option(
            "--params-file",
            self.params_file.as_ref().map(|f| f.display().to_string()),
        );
        if self.sparse_rewards {
            argv.push("--sparse-rewards".into());
        }
        if self.auto_reset {
            argv.push("--auto-reset".into());
        }
        argv
    }

    /// One lockstep environment of `task` in `namespace`, everything else at its default.
    pub(crate) fn one_environment(task: &str, namespace: &str, log_level: &str) -> LaunchArgs {
        LaunchArgs {
            task: Some(task.into()),
            mode: Some("lockstep".into()),
            namespace: namespace.into(),
            envs: 1,
            isolate: false,
            processes: 1,
            threads: None,
            env_range: None,
            seed: None,
            horizon: None,
            sparse_rewards: false,
            reward_scale: None,
            service_mapping: None,
            auto_reset: false,
            params_file: None,
            log_level: log_level.into(),
            duration: None,
            respawn: 0,
            respawn_delay: 1.0,
            record: None,
            record_regex: None,
            record_exclude: None,
            record_max_bag_size: None,
            record_max_bag_duration: None,
        }
    }
}

/// Run the suite until a signal, `--duration`, or a node's death.
pub fn run(args: &LaunchArgs) -> Result<(), String> {
    let signals = composuite_ros::shared::node::shutdown_signal()
        .map_err(|e| format!("cannot watch for signals: {e}"))?;
    let mut suite = Suite::start(args)?;
    eprintln!(
        "composuite launch: {} environment(s) × 3 nodes started {}{}; Ctrl-C stops them",
        args.env_indices()?.len(),
        if args.composed() && args.processes > 1 {
            format!("in {} processes (one DDS participant each)", args.processes)
        } else if args.composed() {
            "in this process (one DDS participant)".to_string()
        } else {
            "as processes".to_string()
        },
        match &args.record {
            Some(dir) => format!(", recording into {}", dir.display()),
            None => String::new(),
        }
    );
    let deadline = args
        .duration
        .map(|d| Instant::now() + Duration::from_secs_f64(d));
    let outcome = loop {
        if let Ok(sig) = signals.try_recv() {
            eprintln!("composuite launch: signal {sig}, stopping the nodes");
            break Ok(());
        }
        if deadline.is_some_and(|d| Instant::now() >= d) {
            eprintln!("composuite launch: --duration reached, stopping the nodes");
            break Ok(());
        }
        if let Err(what) = suite.respawn(args.respawn, Duration::from_secs_f64(args.respawn_delay))
        {
            break Err(format!("{what}; stopped the others"));
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let clean = suite.stop();
    match outcome {
        Err(e) => Err(e),
        Ok(()) if clean => Ok(()),
        Ok(()) => Err("some nodes did not shut down cleanly (see above)".into()),
    }
}

impl Running {
    /// "sim in /env_00 exited on its own (killed by signal 9)".
    fn death(&self, status: ExitStatus) -> String {
        format!("{} exited on its own ({})", self.what, describe(status))
    }
}

fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exit code {code}"),
        (None, Some(sig)) => format!("killed by signal {sig}"),
        _ => "unknown status".into(),
    }
}

/// SIGINT to every node still running, wait up to [`GRACE`], SIGKILL the rest. True when all
/// exited with code 0. (A node waiting for its restart is dead already, and was reported.)
fn stop_all(nodes: &mut [Running]) -> bool {
    // The environments first, then the recorder: it records until they are gone.
    let (recorders, environments): (Vec<&mut Running>, Vec<&mut Running>) = nodes
        .iter_mut()
        .filter(|n| n.died_at.is_none())
        .partition(|n| n.recorder);
    if !recorders.is_empty() && !environments.is_empty() {
        std::thread::sleep(RECORDER_SETTLE);
    }
    let clean = stop_group(environments);
    stop_group(recorders) && clean
}

fn stop_group(mut nodes: Vec<&mut Running>) -> bool {
    for n in nodes.iter() {
        signal(&n.child, libc::SIGINT);
    }
    let until = Instant::now() + GRACE;
    let mut clean = true;
    for n in nodes.iter_mut() {
        let status = loop {
            match n.child.try_wait() {
                Ok(Some(status)) => break Some(status),
                Ok(None) if Instant::now() < until => std::thread::sleep(Duration::from_millis(20)),
                _ => break None,
            }
        };
        match status {
            Some(s) if s.success() => {}
            Some(s) => {
                clean = false;
                eprintln!("composuite launch: {}: {}", n.what, describe(s));
            }
            None => {
                clean = false;
                eprintln!(
                    "composuite launch: {} did not stop within {:?}; killing it",
                    n.what, GRACE
                );
                signal(&n.child, libc::SIGKILL);
                let _ = n.child.wait();
            }
        }
    }
    clean
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn namespaces_per_environment() {
        assert_eq!(env_namespace("/", 0, 1), "/");
        assert_eq!(env_namespace("/train", 0, 1), "/train");
        assert_eq!(env_namespace("/", 3, 4), "/env_03");
        assert_eq!(env_namespace("/train/", 1, 2), "/train/env_01");
    }

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        launch: LaunchArgs,
    }

    fn parse(argv: &[&str]) -> LaunchArgs {
        use clap::Parser;
        Cli::try_parse_from(std::iter::once("launch").chain(argv.iter().copied()))
            .unwrap()
            .launch
    }

    #[test]
    fn environments_split_into_contiguous_shares() {
        assert_eq!(split_environments(8, 2), [0..4, 4..8]);
        assert_eq!(split_environments(7, 3), [0..3, 3..5, 5..7]);
        assert_eq!(split_environments(3, 3), [0..1, 1..2, 2..3]);
        assert_eq!(split_environments(64, 1), vec![Range { start: 0, end: 64 }]);
    }

    // A share's process gives every one of its nodes the arguments the launcher would have.
    #[test]
    fn a_share_process_gives_its_nodes_the_launchers_arguments() {
        let parent = parse(&[
            "--task",
            "Jaco/plate/wall/push",
            "--mode",
            "realtime",
            "--namespace",
            "/train",
            "--envs",
            "5",
            "--processes",
            "2",
            "--threads",
            "3",
            "--seed",
            "7",
            "--horizon",
            "80",
            "--sparse-rewards",
            "--reward-scale",
            "2.5",
            "--service-mapping",
            "cyclone",
            "--auto-reset",
            "--log-level",
            "warn",
            "--respawn",
            "4",
            "--respawn-delay",
            "0.25",
            "--duration",
            "9",
        ]);
        for range in split_environments(parent.envs, parent.processes) {
            let argv = parent.container_process_argv(&range);
            assert_eq!(argv[0], "launch");
            let argv: Vec<&str> = argv[1..].iter().map(String::as_str).collect();
            let child = parse(&argv);
            assert_eq!(child.env_indices(), Ok(range.clone()));
            assert!(child.composed() && child.processes == 1 && child.duration.is_none());
            assert_eq!((child.respawn, child.respawn_delay), (4, 0.25));
            assert_eq!(child.step_threads(), 3);
            for index in range {
                let namespace = env_namespace("/train", index, 5);
                for kind in NodeKind::ALL {
                    assert_eq!(
                        node_arguments(&child, kind, &namespace, index),
                        node_arguments(&parent, kind, &namespace, index),
                        "{kind} of environment {index}"
                    );
                }
            }
        }
    }

    #[test]
    fn bad_processes_and_ranges_are_refused_with_what_is_valid() {
        let refused = |argv: &[&str]| validate(&parse(argv)).unwrap_err();
        assert!(refused(&["--envs", "4", "--processes", "5"]).contains("valid: 1 to --envs (4)"));
        assert!(refused(&["--envs", "4", "--processes", "0"]).contains("--processes 0"));
        assert!(
            refused(&["--envs", "4", "--processes", "2", "--isolate"])
                .contains("without --isolate")
        );
        assert!(
            refused(&["--envs", "4", "--env-range", "3..3"]).contains("START < END <= --envs (4)")
        );
        assert!(refused(&["--envs", "4", "--env-range", "2..9"]).contains("--env-range 2..9"));
        assert!(refused(&["--envs", "4", "--env-range", "x"]).contains("START..END"));
        assert!(validate(&parse(&["--envs", "4", "--processes", "4"])).is_ok());
        assert!(refused(&["--envs", "4", "--threads", "0"]).contains("--threads 0 is invalid"));
        assert!(validate(&parse(&["--envs", "4", "--threads", "1"])).is_ok());
        assert!(refused(&["--envs", "4", "--isolate", "--threads", "2"]).contains("composed"));
    }
}
