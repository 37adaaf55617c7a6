//! What every node of the suite shares: start-up from the command line the way rcl does it
//! (`--ros-args`, `ROS_DOMAIN_ID`, discovery range, parameters), a ros2-client node with its
//! parameter services on a thread of their own, topic/service creation that
//! applies the remaps, a logger that writes to stderr and `/rosout`, and SIGINT/SIGTERM as an
//! async event so the main loop can shut down cleanly.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::{SystemTime, UNIX_EPOCH};

use composuite_core::batch::StepPool;
use composuite_msgs::{RosMessage, RosService};
use ros2_client::action::ActionServerQosPolicies;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::dds::rustdds::DomainParticipantSecurityConfigFiles;
use ros2_client::dds::rustdds::{Topic, TopicDescription};
use ros2_client::dds::{ActionServer, Context, Node, NodeLoggingHandle, Server, ServiceMapping};
use ros2_client::log::LogLevel;
use ros2_client::rosout::RosoutRaw;
use ros2_client::{
    ActionTypeName, Message, MessageTypeName, Name, NodeName, NodeOptions, ParameterValue,
    QosProfile, ServiceTypeName,
};

use crate::shared::dds_log;
use crate::shared::environment::{DiscoveryRange, RosEnvironment};
use crate::shared::intra_process::{IntraProcess, Publisher, Subscription};
use crate::shared::param_server::{ParameterServices, Parameters};
use crate::shared::params::{self, ParamSpec};
use crate::shared::ros_args::{self, RosArgs};
use crate::shared::security;

/// Log severities, ordered (rcutils' levels).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// Details for developers.
    Debug = 10,
    /// Normal progress.
    Info = 20,
    /// Something was wrong with the input and was refused or corrected.
    Warn = 30,
    /// Something failed.
    Error = 40,
    /// The node cannot go on.
    Fatal = 50,
}

impl Level {
    fn parse(text: &str) -> Option<Level> {
        Some(match text.to_ascii_lowercase().as_str() {
            "debug" => Level::Debug,
            "info" => Level::Info,
            "warn" | "warning" => Level::Warn,
            "error" => Level::Error,
            "fatal" => Level::Fatal,
            _ => return None,
        })
    }

    fn label(self) -> &'static str {
        match self {
            Level::Debug => "DEBUG",
            Level::Info => "INFO",
            Level::Warn => "WARN",
            Level::Error => "ERROR",
            Level::Fatal => "FATAL",
        }
    }

    fn ros(self) -> LogLevel {
        match self {
            Level::Debug => LogLevel::Debug,
            Level::Info => LogLevel::Info,
            Level::Warn => LogLevel::Warn,
            Level::Error => LogLevel::Error,
            Level::Fatal => LogLevel::Fatal,
        }
    }
}

/// A node's logger: `[LEVEL] [wall time] [logger name]: message` on stderr (rcutils' default
/// format) and the same record on `/rosout`. Records below the level are dropped.
pub struct Logger {
    name: String,
    level: AtomicU8,
    rosout: Option<NodeLoggingHandle>,
}

impl Logger {
    /// A logger named like rcl names node loggers (`env_00.sim`), optionally without `/rosout`.
    pub fn new(name: impl Into<String>, level: Level, rosout: Option<NodeLoggingHandle>) -> Self {
        Logger {
            name: name.into(),
            level: AtomicU8::new(level as u8),
            rosout,
        }
    }

    /// Whether records of `level` are written.
    pub fn enabled(&self, level: Level) -> bool {
        level as u8 >= self.level.load(Ordering::Relaxed)
    }

    /// Write one record.
    #[track_caller]
    pub fn log(&self, level: Level, message: impl fmt::Display) {
        if !self.enabled(level) {
            return;
        }
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        let text = message.to_string();
        dds_log::write_stderr_line(&format!(
            "[{}] [{}.{:09}] [{}]: {}",
            level.label(),
            now.as_secs(),
            now.subsec_nanos(),
            self.name,
            text
        ));
        if let Some(rosout) = &self.rosout {
            let at = std::panic::Location::caller();
            let stamp = ros2_client::builtin_interfaces::Time::from_nanos(now.as_nanos() as i64);
            rosout.rosout_raw(
                stamp,
                level.ros(),
                &self.name,
                &text,
                at.file(),
                "",
                at.line(),
            );
        }
    }

    /// [`Level::Debug`].
    #[track_caller]
    pub fn debug(&self, message: impl fmt::Display) {
        self.log(Level::Debug, message)
    }
    /// [`Level::Info`].
    #[track_caller]
    pub fn info(&self, message: impl fmt::Display) {
        self.log(Level::Info, message)
    }
    /// [`Level::Warn`].
    #[track_caller]
    pub fn warn(&self, message: impl fmt::Display) {
        self.log(Level::Warn, message)
    }
    /// [`Level::Error`].
    #[track_caller]
    pub fn error(&self, message: impl fmt::Display) {
        self.log(Level::Error, message)
    }
}

/// What a node binary is: its default name, what it does, and its parameters.
pub struct NodeSpec {
    /// Default node name (`sim`, `task_manager`, `reward`).
    pub name: &'static str,
    /// The binary's name, for `--help`.
    pub binary: &'static str,
    /// One paragraph for `--help`.
    pub about: &'static str,
    /// Declared parameters.
    pub params: &'static [ParamSpec],
}

impl NodeSpec {
    /// The `--help` text: usage, the ROS arguments, every parameter with its default.
    pub fn help(&self) -> String {
        let mut out = format!(
            "{about}\n\nUsage: {bin} [--ros-args [-r __ns:=/NS] [-r __node:=NAME] [-r FROM:=TO] \
             [-p NAME:=VALUE] [--params-file FILE] [--log-level LEVEL]]\n\n\
             Environment: ROS_DOMAIN_ID (0-232), ROS_AUTOMATIC_DISCOVERY_RANGE \
             (OFF|LOCALHOST|SUBNET; ROS_LOCALHOST_ONLY=1 = LOCALHOST).\n\nParameters (default):\n",
            about = self.about,
            bin = self.binary
        );
        for p in self.all_params() {
            out.push_str(&format!(
                "  {:<22} {} ({})\n",
                p.name,
                p.description,
                show_value(&(p.default)())
            ));
        }
        let first = &self.all_params()[0];
        out.push_str(&format!(
            "\nExample:\n  {} --ros-args -r __ns:=/env_00 -p {}:={}\n",
            self.binary,
            first.name,
            show_value(&(first.default)())
        ));
        out
    }
}

/// A parameter value the way `-p name:=value` writes it.
pub fn show_value(v: &ParameterValue) -> String {
    match v {
        ParameterValue::String(s) => s.clone(),
        ParameterValue::Boolean(b) => b.to_string(),
        ParameterValue::Integer(i) => i.to_string(),
        ParameterValue::Double(d) => format!("{d:?}"),
        // Arrays as YAML flow lists, which `-p name:=[a, b]` and params files both read.
        ParameterValue::StringArray(items) => format!("[{}]", items.join(", ")),
        ParameterValue::BooleanArray(items) => list(items),
        ParameterValue::IntegerArray(items) => list(items),
        ParameterValue::DoubleArray(items) => {
            format!(
                "[{}]",
                items
                    .iter()
                    .map(|d| format!("{d:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
        other => format!("{other:?}"),
    }
}

fn list<T: fmt::Display>(items: &[T]) -> String {
    format!(
        "[{}]",
        items
            .iter()
            .map(T::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    )
}

pub use crate::shared::param_server::ParamChange;

/// Parameters every node of the suite has, after its own.
pub const COMMON_PARAMS: &[ParamSpec] = &[ParamSpec {
    name: "service_mapping",
    default: || ParameterValue::String("fastdds".into()),
    description: "wire format of the node's services (incl. parameter services): fastdds (rmw_fastrtps, Jazzy's default) or cyclone (rmw_cyclonedds); read at start",
    check: check_mapping,
}];

fn check_mapping(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::String(s) => service_mapping(s).map(|_| ()),
        _ => Err("valid: fastdds, cyclone".into()),
    }
}

impl NodeSpec {
    /// The node's own parameters, then the common ones.
    pub fn all_params(&self) -> Vec<ParamSpec> {
        self.params.iter().chain(COMMON_PARAMS).cloned().collect()
    }
}

/// What the nodes composed into one process share (`crate::container`): the DDS participant,
/// the intra-process hand-off of their topics, and the threads that step their environments.
#[derive(Clone)]
pub struct Composition {
    /// The one participant.
    pub context: Context,
    /// Messages between the process's nodes, handed over without DDS.
    pub intra_process: Arc<IntraProcess>,
    /// The threads the sims' physics runs on.
    pub step_pool: Arc<StepPool>,
}

/// A running node: the ros2-client node, its logger, its parameters.
pub struct RosNode {
    /// The ros2-client node (create entities through [`RosNode`]'s methods, which remap).
    pub node: Node,
    /// The ROS context (its DDS participant is what the recorder subscribes through).
    pub context: Context,
    /// Logger (stderr + `/rosout`).
    pub log: Arc<Logger>,
    /// The parsed `--ros-args`.
    pub args: RosArgs,
    /// Where the node talks.
    pub environment: RosEnvironment,
    /// Parameter changes made through the parameter services, as they are accepted.
    pub param_changes: async_channel::Receiver<ParamChange>,
    /// The parameter values (also served by the parameter services).
    pub parameters: Arc<Parameters>,
    /// The wire format of this node's services (`service_mapping` parameter).
    pub service_mapping: ServiceMapping,
    /// The threads to step environments on: the process's when composed, else none (the
    /// node's own thread steps).
    pub step_pool: Arc<StepPool>,
    /// The process's hand-off, when composed.
    intra_process: Option<Arc<IntraProcess>>,
    parameter_services: Option<ParameterServices>,
    /// Whether the participant is this node's alone (so its end is the participant's).
    owns_participant: bool,
}

/// Why a node could not start (bad arguments, bad environment, DDS failure).
#[derive(Debug)]
pub struct StartError(pub String);

impl fmt::Display for StartError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for StartError {}

/// What start-up gave: a running node, or the `--help` text.
pub enum Startup {
    /// The node runs.
    Node(Box<RosNode>),
    /// Print this and exit 0.
    Help(String),
}

impl RosNode {
    /// Start a node from the process's arguments (without the program name) and environment,
    /// on a DDS participant of its own.
    pub fn start(spec: &NodeSpec, argv: &[String]) -> Result<Startup, StartError> {
        Self::start_in(spec, argv, None)
    }

    /// Start a node as [`RosNode::start`] does, in `shared` when given (many nodes in one
    /// process, as ROS 2's composition puts them: one participant, so DDS discovery does not
    /// grow with the square of the nodes), else on a participant of its own.
    pub fn start_in(
        spec: &NodeSpec,
        argv: &[String],
        shared: Option<&Composition>,
    ) -> Result<Startup, StartError> {
        let args = ros_args::parse(argv).map_err(|e| StartError(e.to_string()))?;
        if args.other.iter().any(|a| a == "-h" || a == "--help") {
            return Ok(Startup::Help(spec.help()));
        }
        if let Some(extra) = args.other.first() {
            return Err(StartError(format!(
                "unexpected argument `{extra}`; {} takes only ROS arguments (see --help)",
                spec.binary
            )));
        }
        let environment = RosEnvironment::read(|k| std::env::var(k).ok())
            .map_err(|e| StartError(e.to_string()))?;
        let namespace = args.namespace.clone().unwrap_or_else(|| "/".into());
        let base = args.node_name.clone().unwrap_or_else(|| spec.name.into());
        let node_name = NodeName::new(&namespace, &base)
            .map_err(|e| StartError(format!("node name {namespace}/{base}: {e:?}")))?;
        let fully_qualified = node_name.fully_qualified_name();
        let specs = spec.all_params();
        let (values, unknown) =
            params::resolve(&specs, &args, &fully_qualified).map_err(StartError)?;
        let level = match &args.log_level {
            Some(l) => Level::parse(l.rsplit('=').next().unwrap_or(l)).ok_or_else(|| {
                StartError(format!(
                    "log level `{l}` is invalid; valid: debug, info, warn, error, fatal"
                ))
            })?,
            None => Level::Info,
        };

        let context = match shared {
            Some(composition) => composition.context.clone(),
            None => new_context(&environment, args.enclave.as_deref(), &fully_qualified)?,
        };

        // No ros2-client spinner (see param_server): parameters are served by our own thread.
        let options = NodeOptions::new()
            .enable_rosout(true)
            .start_parameter_services(false);
        let mut node = context
            .new_node(node_name, options)
            .map_err(|e| StartError(format!("cannot create node {fully_qualified}: {e}")))?;
        let logger_name = fully_qualified.trim_start_matches('/').replace('/', ".");
        let log = Arc::new(Logger::new(logger_name, level, Some(node.logging_handle())));
        for name in unknown {
            log.warn(format!(
                "ignoring parameter `{name}`: not a parameter of this node; its parameters are: {}",
                specs.iter().map(|p| p.name).collect::<Vec<_>>().join(", ")
            ));
        }
        let (change_tx, param_changes) = async_channel::unbounded();
        let parameters = Arc::new(Parameters::new(&specs, values, change_tx));
        let mapping = match parameters.get("service_mapping") {
            ParameterValue::String(m) => service_mapping(&m).map_err(StartError)?,
            _ => ServiceMapping::Enhanced,
        };
        let parameter_services =
            ParameterServices::start(&mut node, mapping, Arc::clone(&parameters))
                .map_err(StartError)?;
        Ok(Startup::Node(Box::new(RosNode {
            node,
            context,
            log,
            args,
            environment,
            param_changes,
            parameters,
            service_mapping: mapping,
            step_pool: match shared {
                Some(composition) => Arc::clone(&composition.step_pool),
                None => Arc::new(StepPool::default()),
            },
            intra_process: shared.map(|c| Arc::clone(&c.intra_process)),
            parameter_services: Some(parameter_services),
            owns_participant: shared.is_none(),
        })))
    }

    /// The current value of a declared parameter.
    pub fn param(&self, name: &str) -> ParameterValue {
        self.parameters.get(name)
    }

    /// A string parameter.
    pub fn param_string(&self, name: &str) -> String {
        match self.param(name) {
            ParameterValue::String(s) => s,
            other => show_value(&other),
        }
    }

    /// A double parameter.
    pub fn param_f64(&self, name: &str) -> f64 {
        match self.param(name) {
            ParameterValue::Double(d) => d,
            ParameterValue::Integer(i) => i as f64,
            _ => f64::NAN,
        }
    }

    /// An integer parameter.
    pub fn param_i64(&self, name: &str) -> i64 {
        match self.param(name) {
            ParameterValue::Integer(i) => i,
            _ => 0,
        }
    }

    /// A boolean parameter.
    pub fn param_bool(&self, name: &str) -> bool {
        matches!(self.param(name), ParameterValue::Boolean(true))
    }

    /// The fully qualified node name (`/env_00/sim`).
    pub fn fully_qualified_name(&self) -> String {
        self.node.fully_qualified_name()
    }

    /// The absolute name of topic or service `name`: remapped, then put in the node's
    /// namespace. (Given ros2-client a relative name in the root namespace `/`, it would write
    /// `rt//name`, which no ROS 2 peer matches.)
    fn resolve_name(&self, name: &str) -> Result<Name, StartError> {
        let remapped = self.args.remapped(name);
        let absolute = if remapped.starts_with('/') {
            remapped.to_string()
        } else {
            match self.node.namespace().trim_end_matches('/') {
                "" => format!("/{remapped}"),
                ns => format!("{ns}/{remapped}"),
            }
        };
        Name::parse(&absolute).map_err(|e| StartError(format!("topic name `{absolute}`: {e:?}")))
    }

    /// Topic `name` of type `T` (remaps applied, relative to the namespace).
    fn topic<T: RosMessage>(&self, name: &str, qos: &QosProfile) -> Result<Topic, StartError> {
        let topic_name = self.resolve_name(name)?;
        self.node
            .create_topic(&topic_name, message_type_name::<T>(), qos)
            .map_err(|e| StartError(format!("topic {name}: {e:?}")))
    }

    /// A publisher of `T` on topic `name` (remaps applied, relative to the namespace); in a
    /// composed process it also hands its messages to the process's subscriptions of the topic
    /// ([`crate::shared::intra_process`]).
    pub fn publisher<T: RosMessage + Message + Clone + Send + 'static>(
        &mut self,
        name: &str,
        qos: QosProfile,
    ) -> Result<Publisher<T>, StartError> {
        let topic = self.topic::<T>(name, &qos)?;
        let wire = self
            .node
            .create_publisher(&topic, Some(qos.clone()))
            .map_err(|e| StartError(format!("publisher {name}: {e:?}")))?;
        let topic_name = topic.name();
        Ok(Publisher::new(
            wire,
            &topic_name,
            &qos,
            self.intra_process.as_deref(),
        ))
    }

    /// A subscription to `T` on topic `name` (remaps applied, relative to the namespace); in a
    /// composed process it also receives what the process's publishers of the topic hand over.
    pub fn subscription<T: RosMessage + Message + Clone + Send + 'static>(
        &mut self,
        name: &str,
        qos: QosProfile,
    ) -> Result<Subscription<T>, StartError> {
        let topic = self.topic::<T>(name, &qos)?;
        let wire = self
            .node
            .create_subscription(&topic, Some(qos.clone()))
            .map_err(|e| StartError(format!("subscription {name}: {e:?}")))?;
        let topic_name = topic.name();
        Ok(Subscription::new(
            wire,
            &topic_name,
            &qos,
            self.intra_process.as_deref(),
        ))
    }

    /// Service `name` (remaps applied) and the ROS type of `S`.
    fn service<S: RosService>(&self, name: &str) -> Result<(Name, ServiceTypeName), StartError> {
        let (package, _, type_name) = split_ros_name(S::ROS_NAME);
        Ok((
            self.resolve_name(name)?,
            ServiceTypeName::new(package, type_name),
        ))
    }

    /// A server of service `S` named `name`, in this node's service wire format.
    pub fn server<S: RosService>(
        &mut self,
        name: &str,
    ) -> Result<Server<S::Request, S::Response>, StartError>
    where
        S::Request: Message,
        S::Response: Message,
    {
        let (service_name, type_name) = self.service::<S>(name)?;
        let qos = crate::shared::qos::services();
        self.node
            .create_server(
                self.service_mapping,
                &service_name,
                &type_name,
                qos.clone(),
                qos,
            )
            .map_err(|e| StartError(format!("service {name}: {e:?}")))
    }

    /// A server of action `package/action/type_name` named `name` (remaps applied), with
    /// rclcpp's action QoS: reliable services, feedback as a default topic, the status latched
    /// (transient local, keep last 1). `G`, `R`, `F` are the action's goal, result and feedback.
    pub fn action_server<G, R, F>(
        &mut self,
        name: &str,
        package: &str,
        type_name: &str,
    ) -> Result<ActionServer<G, R, F>, StartError>
    where
        G: Message + Clone + 'static,
        R: Message + Clone + 'static,
        F: Message + 'static,
    {
        use crate::shared::qos;
        let action_name = self.resolve_name(name)?;
        let policies = ActionServerQosPolicies {
            goal_service: qos::services(),
            result_service: qos::services(),
            cancel_service: qos::services(),
            feedback_publisher: qos::state(),
            status_publisher: qos::latched(),
        };
        self.node
            .create_action_server(
                self.service_mapping,
                &action_name,
                &ActionTypeName::new(package, type_name),
                policies,
            )
            .map_err(|e| StartError(format!("action {name}: {e:?}")))
    }

    /// A client of service `S` named `name`, in this node's service wire format.
    pub fn client<S: RosService>(
        &mut self,
        name: &str,
    ) -> Result<ros2_client::dds::Client<S::Request, S::Response>, StartError>
    where
        S::Request: Message,
        S::Response: Message,
    {
        let (service_name, type_name) = self.service::<S>(name)?;
        let qos = crate::shared::qos::services();
        self.node
            .create_client(
                self.service_mapping,
                &service_name,
                &type_name,
                qos.clone(),
                qos,
            )
            .map_err(|e| StartError(format!("service client {name}: {e:?}")))
    }

    /// Run `body` on this node until it returns (told to stop by `stop`), log how it ended
    /// (a failure as fatal) and shut the node down.
    pub fn run(
        mut self,
        body: impl FnOnce(&mut RosNode, async_channel::Receiver<i32>) -> Result<(), String>,
        stop: async_channel::Receiver<i32>,
    ) -> Result<(), String> {
        let result = body(&mut self, stop);
        match &result {
            Ok(()) => self.log.info("shut down cleanly"),
            Err(e) => self.log.log(Level::Fatal, e),
        }
        self.shutdown();
        result
    }

    /// Stop the parameter services and wait for their thread; if the participant is this
    /// node's own, quiet its teardown.
    pub fn shutdown(mut self) {
        drop(self.parameter_services.take());
        if self.owns_participant {
            // Tearing down the participant, RustDDS reports every entity it can no longer
            // unregister ("Cannot remove Writer GUID ...: Disconnected") as an error: expected.
            dds_log::quiet();
        }
    }
}

fn split_ros_name(ros_name: &'static str) -> (&'static str, &'static str, &'static str) {
    let mut parts = ros_name.splitn(3, '/');
    let package = parts.next().unwrap_or_default();
    let kind = parts.next().unwrap_or_default();
    let name = parts.next().unwrap_or_default();
    (package, kind, name)
}

/// ros2-client's type name for a generated message (`pkg/msg/Name`).
pub fn message_type_name<T: RosMessage>() -> MessageTypeName {
    let (package, _, name) = split_ros_name(T::ROS_NAME);
    MessageTypeName::new(package, name)
}

/// The service wire format named by the `service_mapping` parameter.
pub fn service_mapping(name: &str) -> Result<ServiceMapping, String> {
    match name.to_ascii_lowercase().as_str() {
        "fastdds" | "fastrtps" | "enhanced" => Ok(ServiceMapping::Enhanced),
        "cyclone" | "cyclonedds" => Ok(ServiceMapping::Cyclone),
        other => Err(format!(
            "service mapping `{other}` is unknown; valid: fastdds (rmw_fastrtps, Jazzy's default), cyclone (rmw_cyclonedds)"
        )),
    }
}

/// SIGINT and SIGTERM as a channel: one message when either arrives.
pub fn shutdown_signal() -> std::io::Result<async_channel::Receiver<i32>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    let (tx, rx) = async_channel::bounded(4);
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                if tx.try_send(signal).is_err() {
                    break;
                }
            }
        })?;
    Ok(rx)
}

/// A ROS context on a new DDS participant, as `environment` asks (domain, discovery range,
/// DDS-Security with the files of the enclave rcl's switches and `enclave` choose), with
/// RustDDS's own log records at the level `COMPOSUITE_DDS_LOG` sets, each line naming `owner`
/// (the node, or the container of composed nodes).
pub fn new_context(
    environment: &RosEnvironment,
    enclave: Option<&str>,
    owner: &str,
) -> Result<Context, StartError> {
    let dds_level = dds_log::parse_level(std::env::var(dds_log::DDS_LOG_VAR).ok().as_deref())
        .map_err(StartError)?;
    dds_log::install(dds_level, owner);
    let mut builder = DomainParticipantBuilder::new(environment.domain_id);
    if environment.discovery_range != DiscoveryRange::Subnet {
        builder = builder.with_only_networks([std::net::Ipv4Addr::LOCALHOST]);
    }
    match security::decide(&environment.security, enclave).map_err(StartError)? {
        security::Join::Plain { warning: None } => {}
        security::Join::Plain {
            warning: Some(warning),
        } => eprintln!("[WARN] security: {warning}"),
        security::Join::Secure { dir, enclave } => {
            // Files that are there but unusable stop the node under either strategy (the
            // permissive one only forgives missing files, as rcl's does).
            security::verify_enclave(&dir).map_err(|problem| {
                StartError(format!("SECURITY ERROR: enclave {enclave}: {problem}"))
            })?;
            // The plugins take unencrypted keys only: no password.
            let files =
                DomainParticipantSecurityConfigFiles::with_ros_default_names(dir, String::new());
            builder = builder.builtin_security(files);
        }
    }
    let participant = builder
        .build()
        .map_err(|e| StartError(format!("cannot create the DDS participant: {e:?}")))?;
    Context::from_domain_participant(participant)
        .map_err(|e| StartError(format!("cannot create the ROS context: {e:?}")))
}

/// The main of a node: start from `argv` (the arguments after the program name), run `body`
/// until it returns (on SIGINT/SIGTERM), report errors, give the exit code.
pub fn run_node(
    spec: &NodeSpec,
    argv: &[String],
    body: impl FnOnce(&mut RosNode, async_channel::Receiver<i32>) -> Result<(), String>,
) -> std::process::ExitCode {
    let node = match RosNode::start(spec, argv) {
        Ok(Startup::Help(text)) => {
            print!("{text}");
            return std::process::ExitCode::SUCCESS;
        }
        Ok(Startup::Node(node)) => node,
        Err(e) => {
            eprintln!("{}: {e}", spec.binary);
            return std::process::ExitCode::from(2);
        }
    };
    let signals = match shutdown_signal() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{}: cannot watch for signals: {e}", spec.binary);
            return std::process::ExitCode::FAILURE;
        }
    };
    match node.run(body, signals) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(_) => std::process::ExitCode::FAILURE,
    }
}
