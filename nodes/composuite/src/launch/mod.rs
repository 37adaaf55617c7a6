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

mod argv;
mod process;
mod suite;
mod validate;

use std::ops::Range;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;

pub(crate) use suite::Suite;

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
    /// The security enclave of every node (with ROS_SECURITY_ENABLE=true; see `composuite
    /// security`): each node gets `--ros-args --enclave NAME`, and a composed process, one DDS
    /// participant for all its nodes, joins as NAME. ROS_SECURITY_ENCLAVE_OVERRIDE still wins.
    /// [default: /]
    #[arg(long, value_name = "NAME")]
    enclave: Option<String>,
    /// Every node in a security enclave of its own, `PREFIX/<node>` (PREFIX/sim,
    /// PREFIX/task_manager, PREFIX/reward, PREFIX/recorder), e.g. made with `composuite
    /// security create-enclave KEYSTORE PREFIX/sim --grant sim --namespace NS`. Needs node
    /// processes (one environment, or --isolate): a composed process is one participant.
    #[arg(long, value_name = "PREFIX", conflicts_with = "enclave")]
    node_enclaves: Option<String>,
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

    /// One lockstep environment of `task` in `namespace`, everything else at its default.
    /// The same, its nodes in security enclave `enclave` (None: `/`).
    pub(crate) fn with_enclave(mut self, enclave: Option<String>) -> LaunchArgs {
        self.enclave = enclave;
        self
    }

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
            enclave: None,
            node_enclaves: None,
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

#[cfg(test)]
#[derive(clap::Parser)]
struct Cli {
    #[command(flatten)]
    launch: LaunchArgs,
}

/// A `launch` command line parsed as the CLI parses it (for the tests).
#[cfg(test)]
fn parse(argv: &[&str]) -> LaunchArgs {
    use clap::Parser;
    Cli::try_parse_from(std::iter::once("launch").chain(argv.iter().copied()))
        .unwrap()
        .launch
}
