//! The `sim` node: owns the physics world (the core's [`Env`]), steps it, publishes what a real
//! arm's driver and the reward node need.
//!
//! - `scene` (from the task manager) starts an episode: the world is rebuilt when the task
//!   changes, then reset with the scene's seed; the sim time goes on from the scene's stamp
//!   if that is later (a restarted sim);
//! - `joint_command` (absolute targets by joint name; may carry the finger joints) and
//!   `gripper_command` (opening, effort) set the targets; `reference_action_stamped` and
//!   `reference_action` (8 values in [−1, 1], with and without a header) act as the reference
//!   benchmark's agents do (joint deltas + gripper sign, its soft controller), so a Gymnasium
//!   agent written for CompoSuite sees the same environment. A stamped command answering an
//!   observation from before the current episode is dropped;
//! - ros2_control's controllers ([`controllers`], chosen by the `controllers` parameter):
//!   `joint_trajectory_controller/{follow_joint_trajectory,joint_trajectory}`,
//!   `forward_position_controller/commands`, `gripper_action_controller/gripper_cmd`, and
//!   `controller_manager/{list_controllers,list_hardware_interfaces}`;
//! - its part of the ROS 2 standard simulation interfaces ([`crate::simulation_interfaces`]):
//!   features, simulation state (lockstep = PAUSED, realtime = PLAYING), `step_simulation` and
//!   the `simulate_steps` action (each step taken as a lockstep command's step), entities;
//! - every period runs read → update → write on one timestamp through the [`hardware`] seam;
//! - `lockstep` mode: each `joint_command`, reference action or forward command advances exactly
//!   one control period; a trajectory or gripper goal (or topic trajectory) advances the sim
//!   itself, one period per update, until it is decided; nothing else advances it. `realtime`
//!   mode: a wall-clock timer steps with the last command held and running goals updated;
//! - after every step (and at reset): `world_state` first (the reward node's input), then
//!   `observation`, `joint_states`, `tf` (every URDF link, and the eef, object and goal frames),
//!   `object_markers`, `clock`, all stamped with the new sim time; when the task changes, the
//!   latched `robot_description`, `tf_static` (world → the arm's root link) and `scene_markers`
//!   (the arena) — see [`view`]; and, for the cameras the `cameras` parameter enables (none by
//!   default), `camera/<name>/image_raw` and `camera/<name>/camera_info` — see [`cameras`].
//!
//! Sim time never goes backwards: it advances one control period per step, and one per reset,
//! so every stamp is unique within a run.

pub mod action_server;
pub mod cameras;
pub mod controllers;
pub mod hardware;
pub mod ros_control;
mod simulation_services;
pub mod view;

use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::{Duration, Instant};

use composuite_core::TaskSpec;
use composuite_core::batch::StepPool;
use composuite_core::env::{Env, EnvConfig, EnvError};
use composuite_core::physics::{ARM_DOF, RobotModel, robot_description, robot_model};
use composuite_msgs::builtin_interfaces::msg::Time as BuiltinTime;
use composuite_msgs::control_msgs::action::{
    FollowJointTrajectoryFeedback, FollowJointTrajectoryGoal, FollowJointTrajectoryResult,
    GripperCommandFeedback, GripperCommandGoal, GripperCommandResult,
};
use composuite_msgs::control_msgs::msg::GripperCommand;
use composuite_msgs::controller_manager_msgs::srv::{ListControllers, ListHardwareInterfaces};
use composuite_msgs::msg;
use composuite_msgs::rosgraph_msgs::msg::Clock;
use composuite_msgs::sensor_msgs::msg::JointState;
use composuite_msgs::std_msgs::msg::{Float64MultiArray, String as StringMsg};
use composuite_msgs::tf2_msgs::msg::TFMessage;
use composuite_msgs::trajectory_msgs::msg::JointTrajectory;
use composuite_msgs::visualization_msgs::msg::MarkerArray;
use futures::stream::FusedStream;
use futures::{FutureExt, StreamExt};
use ros2_client::action::{GoalId, GoalStatusEnum, SendGoalRequest};
use ros2_client::action_msgs::CancelGoalRequest;
use ros2_client::dds::ActionServer;
use ros2_client::{Gid, Message, ParameterValue, RmwRequestId};

use self::action_server::Goals;
use self::controllers::catalog::{self, Controller};
use self::controllers::gripper::{GripperFollowing, GripperGoal, GripperParams};
use self::controllers::running::{Controllers, End, Event};
use self::controllers::{forward, trajectory};
use self::hardware::{ArmCommand, GripperTarget, Hardware, JointSnapshot, SimHardware, read_env};
use crate::shared::convert;
use crate::shared::intra_process::{Publisher, Subscription};
use crate::shared::names;
use crate::shared::node::{Logger, ParamChange, RosNode};
use crate::shared::param_server::Parameters;
use crate::shared::params::{ParamSpec, any_value, positive_number};
use crate::shared::qos;

fn check_mode(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::String(s) if Mode::parse(s).is_some() => Ok(()),
        _ => Err("valid: lockstep, realtime".into()),
    }
}

fn check_controllers(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::StringArray(names) => catalog::parse_list(names).map(|_| ()),
        _ => Err("a list of controller names".into()),
    }
}

/// The sim node's parameters.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mode",
        default: || ParameterValue::String("lockstep".into()),
        description: "lockstep: one control period per command (goals advance the sim \
                      themselves); realtime: wall-clock pace",
        check: check_mode,
    },
    ParamSpec {
        name: "realtime_factor",
        default: || ParameterValue::Double(1.0),
        description: "realtime mode: sim seconds per wall second",
        check: positive_number,
    },
    ParamSpec {
        name: "task_observation",
        default: || ParameterValue::Boolean(true),
        description: "include the task one-hots in observation.flat (93 values) or not (77)",
        check: any_value,
    },
    ParamSpec {
        name: "controllers",
        default: || {
            ParameterValue::StringArray(
                catalog::OPTIONAL
                    .iter()
                    .map(|c| c.name().to_string())
                    .collect(),
            )
        },
        description: "ros2_control controllers to offer (read at start-up): \
                      joint_trajectory_controller, forward_position_controller, \
                      gripper_action_controller",
        check: check_controllers,
    },
    ParamSpec {
        name: "cameras",
        default: || ParameterValue::StringArray(Vec::new()),
        description: "cameras whose images to publish on camera/<name>/image_raw and \
                      camera_info after every step (read at start-up): frontview, agentview, \
                      birdview, sideview, eye_in_hand",
        check: cameras::check_cameras,
    },
    ParamSpec {
        name: "camera_width",
        default: || ParameterValue::Integer(cameras::DEFAULT_SIZE),
        description: "width of the published images (pixels, read at start-up)",
        check: cameras::check_size,
    },
    ParamSpec {
        name: "camera_height",
        default: || ParameterValue::Integer(cameras::DEFAULT_SIZE),
        description: "height of the published images (pixels, read at start-up)",
        check: cameras::check_size,
    },
    ParamSpec {
        name: "fault_panic",
        default: || ParameterValue::Boolean(false),
        description: "fault injection, for testing how a suite survives a failing node: set it \
                      to true and the sim panics at once (composed, its environment is \
                      restarted; as a process, the process dies and launch respawns it)",
        check: any_value,
    },
];

/// How the sim advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// One control period per direct command; a running goal advances the sim itself.
    Lockstep,
    /// Wall-clock pace, last targets held.
    Realtime,
}

impl Mode {
    /// `lockstep` / `realtime`.
    pub fn parse(s: &str) -> Option<Mode> {
        match s.to_ascii_lowercase().as_str() {
            "lockstep" => Some(Mode::Lockstep),
            "realtime" => Some(Mode::Realtime),
            _ => None,
        }
    }
}

struct Publishers {
    joint_states: Publisher<JointState>,
    observation: Publisher<msg::Observation>,
    world_state: Publisher<msg::WorldState>,
    clock: Publisher<Clock>,
    tf: Publisher<TFMessage>,
    tf_static: Publisher<TFMessage>,
    robot_description: Publisher<StringMsg>,
    scene_markers: Publisher<MarkerArray>,
    object_markers: Publisher<MarkerArray>,
}

type TrajectoryServer = ActionServer<
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    FollowJointTrajectoryFeedback,
>;
type GripperServer = ActionServer<GripperCommandGoal, GripperCommandResult, GripperCommandFeedback>;

/// The controllers' action servers (absent when the controller is not up). They stay outside
/// [`Sim`]: the event loop's request streams borrow them while the handlers change the sim.
struct ActionServers {
    trajectory: Option<TrajectoryServer>,
    gripper: Option<GripperServer>,
}

/// The episode being simulated.
struct Running {
    env: Env,
    /// The scene's episode number (the task manager counts episodes).
    episode: u32,
    /// Who published that scene. A restarted task manager is another writer whose episode
    /// numbers start again at 1: its scenes are new even where a number repeats.
    scene_writer: Gid,
    /// What commands the arm and gripper.
    controllers: Controllers<GoalId>,
    /// Joints already reported as clamped this episode (said once).
    clamp_reported: BTreeSet<String>,
    /// Whether "episode over" was already said for this episode.
    over_reported: bool,
    /// Whether this episode's object markers went out yet (the first clears the old ones).
    object_drawn: bool,
    /// The sim time of the episode's step 0 (ns): a command stamped earlier was meant for an
    /// earlier episode.
    started_ns: u64,
}

impl Running {
    fn model(&self) -> &'static RobotModel {
        self.env.world().model
    }
}

/// Whether a command stamped `stamp` answers an observation from before this episode began —
/// e.g. sent by an agent that died with it in flight while another reset — and must not step
/// this one (said in the log). Agents stamp a command with the observation it answers; a zero
/// stamp (unstamped) is always taken.
fn sent_for_earlier_episode(run: &Running, stamp: &BuiltinTime, what: &str, log: &Logger) -> bool {
    let stamp = convert::nanos_of(stamp);
    let stale = stamp != 0 && stamp < run.started_ns;
    if stale {
        log.warn(format!(
            "{what} dropped: stamped {stamp}, before this episode began at {} (sim time, ns): \
             it answers an earlier episode's observation",
            run.started_ns
        ));
    }
    stale
}

/// In lockstep, how long past its end a trajectory goal with goal tolerances and no goal time
/// tolerance may take to meet them (s of sim time), so the goal always ends.
const LOCKSTEP_GOAL_TIME_S: f64 = 1.0;

/// Values in a `reference_action`: seven joint deltas and the gripper.
const REFERENCE_ACTION_LEN: usize = ARM_DOF + 1;

/// Where a step's time goes, summed until it is logged (at debug level, every
/// [`TIMING_WINDOW`] steps).
#[derive(Default)]
struct StepTiming {
    steps: u32,
    physics: Duration,
    publish: Duration,
}

/// Steps per timing log line.
const TIMING_WINDOW: u32 = 1000;

/// What advanced the sim by one period.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Advance {
    /// A direct command (lockstep) or the realtime timer: the period is always simulated.
    Command,
    /// A running goal (lockstep): simulated only while a goal is still undecided after the update.
    Goal,
}

struct Sim {
    timing: StepTiming,
    mode: Mode,
    realtime_factor: f64,
    task_observation: bool,
    sim_time_ns: u64,
    run: Option<Running>,
    pubs: Publishers,
    /// The optional controllers that are up.
    up: Vec<Controller>,
    trajectory_goals: Goals<FollowJointTrajectoryResult>,
    gripper_goals: Goals<GripperCommandResult>,
    /// The node's parameters (`set_simulation_state` sets `mode` through them).
    parameters: Arc<Parameters>,
    /// `simulate_steps` goals, and the one being executed.
    steps_goals: Goals<composuite_msgs::simulation_interfaces::action::SimulateStepsResult>,
    steps_running: Option<simulation_services::StepsGoal>,
    /// The cameras whose images it publishes.
    cameras: cameras::Cameras,
    /// Where its physics (resets and steps) runs: composed, the threads it shares with the
    /// process's other sims; else its own thread.
    step_pool: Arc<StepPool>,
}

/// A subscription's stream, or a stream that never yields when the topic is not offered.
fn optional_stream<M: Message + Clone + Send + 'static>(
    subscription: Option<&Subscription<M>>,
) -> impl FusedStream<Item = ros2_client::ReadResult<(M, ros2_client::MessageInfo)>> + '_ {
    match subscription {
        Some(s) => s.async_stream().left_stream(),
        None => futures::stream::pending().right_stream(),
    }
}

/// An action service's request stream, or one that never yields when the action is not offered.
fn optional_requests<'a, Req: Message + 'static, Resp: Message + 'static>(
    server: Option<&'a ros2_client::dds::Server<Req, Resp>>,
) -> impl FusedStream<Item = ros2_client::ReadResult<(RmwRequestId, Req)>> + 'a {
    match server {
        Some(s) => s.receive_request_stream().left_stream(),
        None => futures::stream::pending().right_stream(),
    }
}

/// Run the sim node until SIGINT/SIGTERM.
pub fn run(node: &mut RosNode, signals: async_channel::Receiver<i32>) -> Result<(), String> {
    let e = |e: crate::shared::node::StartError| e.to_string();
    let pubs = Publishers {
        joint_states: node
            .publisher(names::JOINT_STATES, qos::state())
            .map_err(e)?,
        observation: node
            .publisher(names::OBSERVATION, qos::state())
            .map_err(e)?,
        world_state: node
            .publisher(names::WORLD_STATE, qos::state())
            .map_err(e)?,
        clock: node.publisher(names::CLOCK, qos::clock()).map_err(e)?,
        tf: node.publisher(names::TF, qos::state()).map_err(e)?,
        tf_static: node
            .publisher(names::TF_STATIC, qos::latched())
            .map_err(e)?,
        robot_description: node
            .publisher(names::ROBOT_DESCRIPTION, qos::latched())
            .map_err(e)?,
        scene_markers: node
            .publisher(names::SCENE_MARKERS, qos::latched())
            .map_err(e)?,
        object_markers: node
            .publisher(names::OBJECT_MARKERS, qos::state())
            .map_err(e)?,
    };
    let scene_sub = node
        .subscription::<msg::Scene>(names::SCENE, qos::latched())
        .map_err(e)?;
    let command_sub = node
        .subscription::<JointState>(names::JOINT_COMMAND, qos::state())
        .map_err(e)?;
    let action_sub = node
        .subscription::<Float64MultiArray>(names::REFERENCE_ACTION, qos::state())
        .map_err(e)?;
    let stamped_action_sub = node
        .subscription::<msg::ReferenceAction>(names::REFERENCE_ACTION_STAMPED, qos::state())
        .map_err(e)?;
    let gripper_sub = node
        .subscription::<GripperCommand>(names::GRIPPER_COMMAND, qos::state())
        .map_err(e)?;
    let up = match node.param("controllers") {
        ParameterValue::StringArray(list) => catalog::parse_list(&list)?,
        _ => Vec::new(),
    };
    let is_up = |c: Controller| up.contains(&c);
    let trajectory_sub = if is_up(Controller::JointTrajectory) {
        Some(
            node.subscription::<JointTrajectory>(names::TRAJECTORY_TOPIC, qos::state())
                .map_err(e)?,
        )
    } else {
        None
    };
    let forward_sub = if is_up(Controller::ForwardPosition) {
        Some(
            node.subscription::<Float64MultiArray>(names::FORWARD_COMMANDS, qos::state())
                .map_err(e)?,
        )
    } else {
        None
    };
    let servers = ActionServers {
        trajectory: if is_up(Controller::JointTrajectory) {
            Some(
                node.action_server(
                    names::TRAJECTORY_ACTION,
                    "control_msgs",
                    "FollowJointTrajectory",
                )
                .map_err(e)?,
            )
        } else {
            None
        },
        gripper: if is_up(Controller::GripperAction) {
            Some(
                node.action_server(names::GRIPPER_ACTION, "control_msgs", "GripperCommand")
                    .map_err(e)?,
            )
        } else {
            None
        },
    };
    let list_controllers = node
        .server::<ListControllers>(names::LIST_CONTROLLERS)
        .map_err(e)?;
    let list_interfaces = node
        .server::<ListHardwareInterfaces>(names::LIST_HARDWARE_INTERFACES)
        .map_err(e)?;
    let si_servers = simulation_services::Servers::new(node).map_err(e)?;
    let cameras = cameras::Cameras::new(node).map_err(e)?;
    let mut sim = Sim {
        mode: Mode::parse(&node.param_string("mode")).unwrap_or(Mode::Lockstep),
        realtime_factor: node.param_f64("realtime_factor"),
        task_observation: node.param_bool("task_observation"),
        sim_time_ns: 0,
        run: None,
        pubs,
        timing: StepTiming::default(),
        up,
        trajectory_goals: Goals::default(),
        gripper_goals: Goals::default(),
        parameters: Arc::clone(&node.parameters),
        steps_goals: Goals::default(),
        steps_running: None,
        cameras,
        step_pool: node.step_pool.clone(),
    };
    let log = node.log.clone();
    log.info(format!(
        "{} up in {:?} mode with controllers [{}] and cameras [{}]; waiting for a scene on `{}`",
        node.fully_qualified_name(),
        sim.mode,
        sim.up
            .iter()
            .map(|c| c.name())
            .collect::<Vec<_>>()
            .join(", "),
        sim.cameras.names().join(", "),
        names::SCENE
    ));
    let param_changes = node.param_changes.clone();
    let servers = &servers;
    smol::block_on(async {
        let mut scenes = std::pin::pin!(scene_sub.async_stream());
        let mut commands = std::pin::pin!(command_sub.async_stream());
        let mut grippers = std::pin::pin!(gripper_sub.async_stream());
        let mut actions = std::pin::pin!(action_sub.async_stream());
        let mut stamped_actions = std::pin::pin!(stamped_action_sub.async_stream());
        let mut trajectories = std::pin::pin!(optional_stream(trajectory_sub.as_ref()));
        let mut forwards = std::pin::pin!(optional_stream(forward_sub.as_ref()));
        let trajectory_server = servers.trajectory.as_ref();
        let gripper_server = servers.gripper.as_ref();
        let mut trajectory_goals = std::pin::pin!(optional_requests(
            trajectory_server.map(|s| s.goal_service())
        ));
        let mut trajectory_cancels = std::pin::pin!(optional_requests(
            trajectory_server.map(|s| s.cancel_service())
        ));
        let mut trajectory_results = std::pin::pin!(optional_requests(
            trajectory_server.map(|s| s.result_service())
        ));
        let mut gripper_goals =
            std::pin::pin!(optional_requests(gripper_server.map(|s| s.goal_service())));
        let mut gripper_cancels = std::pin::pin!(optional_requests(
            gripper_server.map(|s| s.cancel_service())
        ));
        let mut gripper_results = std::pin::pin!(optional_requests(
            gripper_server.map(|s| s.result_service())
        ));
        let mut controller_lists = std::pin::pin!(list_controllers.receive_request_stream());
        let mut interface_lists = std::pin::pin!(list_interfaces.receive_request_stream());
        let mut simulation_requests = std::pin::pin!(si_servers.requests());
        let mut ticker = sim.ticker();
        loop {
            // In lockstep a running goal (a controller's or simulate_steps') advances the sim,
            // after every waiting event is handled.
            let goal_wants_time = sim.mode == Mode::Lockstep
                && (sim.steps_goal_running()
                    || sim.run.as_ref().is_some_and(|r| r.controllers.running()));
            let goal_step = async {
                if goal_wants_time {
                    smol::future::yield_now().await
                } else {
                    futures::future::pending().await
                }
            };
            futures::select_biased! {
                signal = signals.recv().fuse() => {
                    log.info(format!("signal {} received, shutting down", signal.unwrap_or(0)));
                    sim.end_all_goals(servers, "the sim is shutting down", &log);
                    return Ok(());
                }
                change = param_changes.recv().fuse() => {
                    if let Ok(change) = change {
                        sim.on_param(&change, &log);
                        ticker = sim.ticker();
                    }
                }
                scene = scenes.select_next_some() => match scene {
                    Ok((scene, info)) => {
                        sim.on_scene(servers, &scene, info.publisher_gid(), &log);
                        ticker = sim.ticker();
                    }
                    Err(err) => log.warn(format!("unreadable scene message dropped: {err:?}")),
                },
                request = controller_lists.select_next_some() => match request {
                    Ok((id, _)) => {
                        let reply = ros_control::list_controllers(
                            &sim.up, sim.model(), sim.update_rate_hz());
                        if let Err(err) = list_controllers.send_response(id, reply) {
                            log.warn(format!("list_controllers reply not sent: {err:?}"));
                        }
                    }
                    Err(err) => log.warn(format!("unreadable list_controllers request: {err:?}")),
                },
                request = interface_lists.select_next_some() => match request {
                    Ok((id, _)) => {
                        let reply = ros_control::list_hardware_interfaces(&sim.up, sim.model());
                        if let Err(err) = list_interfaces.send_response(id, reply) {
                            log.warn(format!("list_hardware_interfaces reply not sent: {err:?}"));
                        }
                    }
                    Err(err) => log.warn(format!(
                        "unreadable list_hardware_interfaces request: {err:?}")),
                },
                request = trajectory_cancels.select_next_some() => match request {
                    Ok((id, request)) => sim.on_trajectory_cancel(servers, id, &request, &log),
                    Err(err) => log.warn(format!("unreadable cancel request: {err:?}")),
                },
                request = gripper_cancels.select_next_some() => match request {
                    Ok((id, request)) => sim.on_gripper_cancel(servers, id, &request, &log),
                    Err(err) => log.warn(format!("unreadable cancel request: {err:?}")),
                },
                request = trajectory_results.select_next_some() => match request {
                    Ok((id, request)) => {
                        let server = trajectory_server.expect("a request came: the server is up");
                        if let Err(err) =
                            sim.trajectory_goals.result_request(server, id, request.goal_id)
                        {
                            log.warn(err);
                        }
                    }
                    Err(err) => log.warn(format!("unreadable result request: {err:?}")),
                },
                request = gripper_results.select_next_some() => match request {
                    Ok((id, request)) => {
                        let server = gripper_server.expect("a request came: the server is up");
                        if let Err(err) =
                            sim.gripper_goals.result_request(server, id, request.goal_id)
                        {
                            log.warn(err);
                        }
                    }
                    Err(err) => log.warn(format!("unreadable result request: {err:?}")),
                },
                request = trajectory_goals.select_next_some() => match request {
                    Ok((id, request)) => sim.on_trajectory_goal(servers, id, request, &log),
                    Err(err) => log.warn(format!("unreadable trajectory goal: {err:?}")),
                },
                request = gripper_goals.select_next_some() => match request {
                    Ok((id, request)) => sim.on_gripper_goal(servers, id, request, &log),
                    Err(err) => log.warn(format!("unreadable gripper goal: {err:?}")),
                },
                trajectory = trajectories.select_next_some() => match trajectory {
                    Ok((trajectory, _)) => sim.on_trajectory_topic(servers, &trajectory, &log),
                    Err(err) => log.warn(format!("unreadable joint_trajectory dropped: {err:?}")),
                },
                gripper = grippers.select_next_some() => match gripper {
                    Ok((command, _)) => sim.on_gripper(servers, &command, &log),
                    Err(err) => log.warn(format!("unreadable gripper_command dropped: {err:?}")),
                },
                command = commands.select_next_some() => match command {
                    Ok((command, _)) => sim.on_joint_command(servers, &command, &log),
                    Err(err) => log.warn(format!("unreadable joint_command dropped: {err:?}")),
                },
                command = forwards.select_next_some() => match command {
                    Ok((command, _)) => sim.on_forward_command(servers, &command, &log),
                    Err(err) => log.warn(format!("unreadable forward command dropped: {err:?}")),
                },
                action = actions.select_next_some() => match action {
                    Ok((action, _)) => sim.on_reference_action(
                        servers, &action.data, None, names::REFERENCE_ACTION, &log,
                    ),
                    Err(err) => log.warn(format!("unreadable reference_action dropped: {err:?}")),
                },
                action = stamped_actions.select_next_some() => match action {
                    Ok((action, _)) => sim.on_reference_action(
                        servers,
                        &action.action,
                        Some(&action.header.stamp),
                        names::REFERENCE_ACTION_STAMPED,
                        &log,
                    ),
                    Err(err) => log.warn(format!(
                        "unreadable {} dropped: {err:?}",
                        names::REFERENCE_ACTION_STAMPED
                    )),
                },
                _ = ticker.next().fuse() => {
                    sim.advance(servers, Advance::Command, &log);
                }
                request = simulation_requests.select_next_some() => {
                    sim.on_simulation_request(servers, &si_servers, request, &log);
                }
                _ = goal_step.fuse() => {
                    if sim.steps_goal_running() {
                        sim.simulate_step(servers, &si_servers, &log);
                    } else {
                        sim.advance(servers, Advance::Goal, &log);
                    }
                }
            }
        }
    })
}

impl Sim {
    /// The realtime step timer (never fires in lockstep or without an episode).
    fn ticker(&self) -> smol::Timer {
        match (&self.run, self.mode) {
            (Some(run), Mode::Realtime) => {
                let period = run.env.config().control_period() / self.realtime_factor;
                let period = Duration::from_secs_f64(period);
                smol::Timer::interval_at(Instant::now() + period, period)
            }
            _ => smol::Timer::never(),
        }
    }

    /// The loaded robot (none before the first scene).
    fn model(&self) -> Option<&'static RobotModel> {
        self.run.as_ref().map(Running::model)
    }

    /// Control updates per second (the controllers' update rate).
    fn update_rate_hz(&self) -> u16 {
        let period = self
            .run
            .as_ref()
            .map(|r| r.env.config().control_period())
            .unwrap_or_else(|| EnvConfig::default().control_period());
        (1.0 / period).round() as u16
    }

    fn period_ns(run: &Running) -> u64 {
        (run.env.config().control_period() * 1e9).round() as u64
    }

    /// The joints now, at the current sim time.
    fn snapshot(&self) -> Option<JointSnapshot> {
        self.run
            .as_ref()
            .map(|run| read_env(&run.env, self.sim_time_ns))
    }

    fn on_param(&mut self, change: &ParamChange, log: &Logger) {
        match (change.name.as_str(), &change.value) {
            ("mode", ParameterValue::String(s)) => {
                if let Some(mode) = Mode::parse(s) {
                    self.mode = mode;
                    log.info(format!("mode is now {mode:?}"));
                }
            }
            ("realtime_factor", ParameterValue::Double(f)) => self.realtime_factor = *f,
            ("task_observation", ParameterValue::Boolean(b)) => {
                self.task_observation = *b;
                log.info("task_observation takes effect with the next scene");
            }
            ("controllers" | "cameras" | "camera_width" | "camera_height", _) => log.warn(format!(
                "{} takes effect when the sim starts again; unchanged now",
                change.name
            )),
            ("fault_panic", ParameterValue::Boolean(true)) => {
                log.error("fault_panic was set: panicking now, as asked");
                panic!("fault_panic was set (fault injection)");
            }
            _ => {}
        }
    }

    fn on_scene(&mut self, servers: &ActionServers, scene: &msg::Scene, writer: Gid, log: &Logger) {
        let task: TaskSpec = match convert::task_of(&scene.task) {
            Ok(task) => task,
            Err(err) => {
                log.error(format!("scene refused: {err}"));
                return;
            }
        };
        if let Some(run) = &self.run
            && run.episode == scene.episode
            && run.scene_writer == writer
            && run.env.task() == task
        {
            return; // the latched scene again (e.g. a re-match); nothing new
        }
        self.end_all_goals(servers, &format!("episode {} started", scene.episode), log);
        // The scene carries the latest sim time the task manager has seen: a sim started again
        // (after a crash) goes on from there instead of from 0, so time never runs backwards.
        self.sim_time_ns = self.sim_time_ns.max(convert::nanos_of(&scene.header.stamp));
        let config = EnvConfig::default()
            .horizon(scene.horizon)
            .task_observation(self.task_observation);
        if (config.control_period() - scene.control_period).abs() > 1e-12 {
            log.warn(format!(
                "scene asks for a {} s control period; this sim runs {} s",
                scene.control_period,
                config.control_period()
            ));
        }
        let reuse = self
            .run
            .take()
            .map(|r| r.env)
            .filter(|env| env.task() == task && *env.config() == config);
        let robot_changed = reuse.is_none();
        let started = self.step_pool.run(|| {
            let mut env = reuse.unwrap_or_else(|| Env::new(task, config));
            env.reset(scene.seed).map(|_| env)
        });
        let env = match started {
            Ok(env) => env,
            Err(err) => {
                log.error(format!("cannot start episode {}: {err}", scene.episode));
                return;
            }
        };
        let controllers = Controllers::holding(env.world().arm_positions());
        self.run = Some(Running {
            env,
            episode: scene.episode,
            scene_writer: writer,
            controllers,
            clamp_reported: BTreeSet::new(),
            over_reported: false,
            object_drawn: false,
            started_ns: 0,
        });
        if robot_changed {
            let _ = self.pubs.robot_description.publish(StringMsg {
                data: robot_description(task.robot),
            });
            // The URDF's root link sits at the robot base pose in the world. Only this one
            // transform is static: robot_state_publisher would put the URDF's fixed joints here
            // too, but the task (so the arm) can change during a run, and tf2's and Foxglove's
            // static buffers keep a static transform for good, whichever arm sent it last
            // (IIWA and Jaco both have a `right_hand_mount` from `link_7`, at other offsets). So
            // the fixed joints go out on `tf` with the moving ones at every step, and every link
            // resolves to `world` at every stamp from that step's transforms alone; the root
            // links differ between the four arms, so their static transforms never clash.
            let root = &robot_model(task.robot).bodies[0].name;
            let base = convert::pose(&composuite_core::arena::robot_base_pose());
            let stamp = convert::time_from_nanos(self.sim_time_ns);
            let mut transforms = vec![convert::world_transform(root, &base, stamp.clone())];
            transforms.extend(self.cameras.static_transforms(&stamp));
            let _ = self.pubs.tf_static.publish(TFMessage { transforms });
        }
        log.info(format!(
            "episode {} of {task}, seed {}",
            scene.episode, scene.seed
        ));
        self.advance_clock();
        if let Some(run) = &mut self.run {
            run.started_ns = self.sim_time_ns;
        }
        if robot_changed {
            // The arena is the task's (the goal marker's place too): drawn again when it changes.
            let stamp = convert::time_from_nanos(self.sim_time_ns);
            let _ = self
                .pubs
                .scene_markers
                .publish(view::arena_markers(scene, stamp));
        }
        self.publish_state();
    }

    /// End every running goal with `why` (a new episode, shutting down), holding the arm still.
    fn end_all_goals(&mut self, servers: &ActionServers, why: &str, log: &Logger) {
        let Some(state) = self.snapshot() else { return };
        let Some(run) = &mut self.run else { return };
        let events = run.controllers.abort_all(why, &state);
        self.report(servers, events, log);
    }

    /// The running episode, or `None` after saying why `what` is ignored.
    fn episode_for(&mut self, what: &str, log: &Logger) -> Option<&mut Running> {
        if self.run.is_none() {
            log.warn(format!(
                "{what} ignored: no episode yet (the task manager publishes the scene)"
            ));
        }
        self.run.as_mut()
    }

    fn on_gripper(&mut self, servers: &ActionServers, command: &GripperCommand, log: &Logger) {
        let time_ns = self.sim_time_ns;
        let Some(run) = self.episode_for("gripper_command", log) else {
            return;
        };
        let state = read_env(&run.env, time_ns);
        // Checked now so a bad command is refused on arrival, not at the next step.
        if let Err(err) = composuite_core::control::validate_gripper_width(
            run.model(),
            command.position,
            command.max_effort,
        ) {
            log.warn(format!("gripper_command refused: {err}"));
            return;
        }
        let target = GripperTarget {
            opening: command.position,
            max_effort: command.max_effort,
        };
        let ended = run.controllers.command_gripper(target, &state);
        self.report(servers, ended, log);
    }

    fn on_joint_command(&mut self, servers: &ActionServers, command: &JointState, log: &Logger) {
        let time_ns = self.sim_time_ns;
        let Some(run) = self.episode_for("joint_command", log) else {
            return;
        };
        if sent_for_earlier_episode(run, &command.header.stamp, "joint_command", log) {
            return;
        }
        let state = read_env(&run.env, time_ns);
        let model = run.model();
        let (arm, finger_gap) = match convert::arm_command(model, command) {
            Ok(parsed) => parsed,
            Err(err) => {
                log.warn(format!("joint_command refused: {err}"));
                return;
            }
        };
        // Refused on arrival with the core's own checks, so the held targets (what realtime
        // steps with) never hold a value the next step would refuse.
        let checked = composuite_core::control::validate_arm_targets(model, &arm)
            .map(|_| ())
            .map_err(|e| e.to_string())
            .and_then(|()| match finger_gap {
                Some(gap) => composuite_core::control::validate_gripper_width(model, gap, 0.0)
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
                None => Ok(()),
            });
        if let Err(err) = checked {
            log.warn(format!("joint_command refused: {err}"));
            return;
        }
        let mut ended: Vec<_> = run
            .controllers
            .command_arm(ArmCommand::Positions(arm), names::JOINT_COMMAND)
            .into_iter()
            .collect();
        if let Some(gap) = finger_gap {
            let target = GripperTarget {
                opening: gap,
                max_effort: 0.0,
            };
            ended.extend(run.controllers.command_gripper(target, &state));
        }
        self.report(servers, ended, log);
        if self.mode == Mode::Lockstep {
            self.advance(servers, Advance::Command, log);
        }
    }

    fn on_forward_command(
        &mut self,
        servers: &ActionServers,
        command: &Float64MultiArray,
        log: &Logger,
    ) {
        let what = names::FORWARD_COMMANDS;
        let Some(run) = self.episode_for(what, log) else {
            return;
        };
        let targets = match forward::parse_command(run.model(), &command.data) {
            Ok(targets) => targets,
            Err(err) => {
                log.warn(format!("{what} refused: {err}"));
                return;
            }
        };
        let ended = run
            .controllers
            .command_arm(ArmCommand::Positions(targets), what);
        self.report(servers, ended, log);
        if self.mode == Mode::Lockstep {
            self.advance(servers, Advance::Command, log);
        }
    }

    /// A reference action from `what`: the unstamped topic's values, or the stamped one's with
    /// the stamp of the observation it answers.
    fn on_reference_action(
        &mut self,
        servers: &ActionServers,
        action: &[f64],
        stamp: Option<&BuiltinTime>,
        what: &str,
        log: &Logger,
    ) {
        let Some(run) = self.episode_for(what, log) else {
            return;
        };
        if stamp.is_some_and(|stamp| sent_for_earlier_episode(run, stamp, what, log)) {
            return;
        }
        let values: [f64; REFERENCE_ACTION_LEN] = match action.try_into() {
            Ok(values) => values,
            Err(_) => {
                log.warn(format!(
                    "{what} refused: it has {} values; it needs {REFERENCE_ACTION_LEN} \
                     (7 joint deltas, then the gripper), each in [-1, 1]",
                    action.len()
                ));
                return;
            }
        };
        // Out-of-range values are clipped, as the reference does; non-finite ones refused here
        // so the held command never holds a value the next step would refuse.
        if let Some((index, value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            log.warn(format!(
                "{what} refused: value {index} is {value}; each must be finite \
                 (it is clipped to [-1, 1])"
            ));
            return;
        }
        let ended = run
            .controllers
            .command_arm(ArmCommand::Reference(values), what);
        self.report(servers, ended, log);
        if self.mode == Mode::Lockstep {
            self.advance(servers, Advance::Command, log);
        }
    }

    /// A trajectory checked as joint_trajectory_controller checks it, with the tolerances it
    /// asks for, ready to follow; or why not.
    fn trajectory_for(
        &self,
        request: &trajectory::TrajectoryRequest,
        log: &Logger,
    ) -> Result<trajectory::Following, String> {
        let Some(run) = &self.run else {
            return Err("no episode yet (the task manager publishes the scene)".into());
        };
        if run.env.ended().is_some() {
            return Err(format!(
                "episode {} is over; a new episode (reset) lets the arm move again",
                run.episode
            ));
        }
        let model = run.model();
        let checked = trajectory::validate(request, model, self.sim_time_ns)?;
        let (mut tolerances, note) =
            trajectory::resolve_tolerances(request, &trajectory::Tolerances::default(), model);
        if let Some(note) = note {
            log.warn(format!("trajectory goal: {note}"));
        }
        // A goal time tolerance of 0 waits for the goal tolerance forever; in lockstep the goal
        // itself advances the sim, so "forever" would never hand control back.
        if self.mode == Mode::Lockstep
            && tolerances.goal_time == 0.0
            && tolerances.goal.iter().any(|&t| t > 0.0)
        {
            tolerances.goal_time = LOCKSTEP_GOAL_TIME_S;
            log.debug(format!(
                "trajectory goal: goal_time_tolerance 0 (wait forever) is {LOCKSTEP_GOAL_TIME_S} s \
                 of sim time in lockstep"
            ));
        }
        Ok(trajectory::Following::new(checked, tolerances))
    }

    fn on_trajectory_goal(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: SendGoalRequest<FollowJointTrajectoryGoal>,
        log: &Logger,
    ) {
        let server = servers
            .trajectory
            .as_ref()
            .expect("a goal came: the server is up");
        let now = convert::time_from_nanos(self.sim_time_ns);
        let following =
            ros_control::goal_request(&request.goal).and_then(|r| self.trajectory_for(&r, log));
        let following = match following {
            Ok(following) => following,
            Err(why) => {
                // The goal response has no field for a reason: it goes to the log (/rosout).
                log.warn(format!("{} goal rejected: {why}", names::TRAJECTORY_ACTION));
                if let Err(err) =
                    Goals::<FollowJointTrajectoryResult>::reject(server, request_id, &now)
                {
                    log.warn(err);
                }
                return;
            }
        };
        if let Err(err) = self
            .trajectory_goals
            .accept(server, request_id, request.goal_id, &now)
        {
            log.warn(err);
            return;
        }
        let run = self.run.as_mut().expect("checked by trajectory_for");
        let ended = run
            .controllers
            .start_trajectory(following, Some(request.goal_id));
        self.report(servers, ended, log);
    }

    fn on_trajectory_topic(
        &mut self,
        servers: &ActionServers,
        message: &JointTrajectory,
        log: &Logger,
    ) {
        let request = ros_control::topic_request(message);
        match self.trajectory_for(&request, log) {
            Ok(following) => {
                let run = self.run.as_mut().expect("checked by trajectory_for");
                let ended = run.controllers.start_trajectory(following, None);
                self.report(servers, ended, log);
            }
            Err(why) => log.warn(format!("{} refused: {why}", names::TRAJECTORY_TOPIC)),
        }
    }

    fn on_gripper_goal(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: SendGoalRequest<GripperCommandGoal>,
        log: &Logger,
    ) {
        let server = servers
            .gripper
            .as_ref()
            .expect("a goal came: the server is up");
        let now = convert::time_from_nanos(self.sim_time_ns);
        let command = &request.goal.command;
        let goal = GripperGoal {
            position: command.position,
            max_effort: command.max_effort,
        };
        let checked = match (&self.run, self.snapshot()) {
            (Some(run), Some(state)) if run.env.ended().is_none() => {
                composuite_core::control::validate_gripper_width(
                    run.model(),
                    GripperTarget::finger(goal.position, goal.max_effort).opening,
                    goal.max_effort,
                )
                .map(|_| state)
                .map_err(|e| e.to_string())
            }
            (Some(run), _) => Err(format!(
                "episode {} is over; a new episode (reset) lets the gripper move again",
                run.episode
            )),
            _ => Err("no episode yet (the task manager publishes the scene)".into()),
        };
        let state = match checked {
            Ok(state) => state,
            Err(why) => {
                log.warn(format!("{} goal rejected: {why}", names::GRIPPER_ACTION));
                if let Err(err) = Goals::<GripperCommandResult>::reject(server, request_id, &now) {
                    log.warn(err);
                }
                return;
            }
        };
        if let Err(err) = self
            .gripper_goals
            .accept(server, request_id, request.goal_id, &now)
        {
            log.warn(err);
            return;
        }
        let run = self.run.as_mut().expect("checked above");
        let following = GripperFollowing::new(goal, GripperParams::default());
        let ended = run
            .controllers
            .start_gripper(following, request.goal_id, &state);
        self.report(servers, ended, log);
    }

    fn on_trajectory_cancel(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        log: &Logger,
    ) {
        let server = servers
            .trajectory
            .as_ref()
            .expect("a cancel came: the server is up");
        let state = self.snapshot();
        let mut run = self.run.as_mut();
        let ended = self
            .trajectory_goals
            .cancel(server, request_id, request, |goal| {
                run.as_deref_mut()?
                    .controllers
                    .cancel_trajectory(goal, state.as_ref()?)
            });
        self.report_cancel(servers, ended, log);
    }

    fn on_gripper_cancel(
        &mut self,
        servers: &ActionServers,
        request_id: RmwRequestId,
        request: &CancelGoalRequest,
        log: &Logger,
    ) {
        let server = servers
            .gripper
            .as_ref()
            .expect("a cancel came: the server is up");
        let state = self.snapshot();
        let mut run = self.run.as_mut();
        let ended = self
            .gripper_goals
            .cancel(server, request_id, request, |goal| {
                run.as_deref_mut()?
                    .controllers
                    .cancel_gripper(goal, state.as_ref()?)
            });
        self.report_cancel(servers, ended, log);
    }

    /// Report the goals a cancel ended (their results), or say why the reply was not sent.
    fn report_cancel(
        &mut self,
        servers: &ActionServers,
        ended: (Vec<Event<GoalId>>, Result<(), action_server::ReplyError>),
        log: &Logger,
    ) {
        let (events, replied) = ended;
        if let Err(err) = replied {
            log.warn(err);
        }
        self.report(servers, events, log);
    }

    /// Tell the clients what the controllers did: feedback, and goals that ended.
    fn report(
        &mut self,
        servers: &ActionServers,
        events: impl IntoIterator<Item = Event<GoalId>>,
        log: &Logger,
    ) {
        let Some(model) = self.model() else { return };
        for event in events {
            let outcome = match event {
                Event::TrajectoryFeedback { goal, update } => {
                    let Some(server) = &servers.trajectory else {
                        continue;
                    };
                    server
                        .send_feedback(goal, ros_control::feedback(model, &update))
                        .map(|_| ())
                        .map_err(|e| format!("trajectory feedback not sent: {e:?}"))
                }
                Event::TrajectoryEnded {
                    goal: None,
                    end,
                    message,
                    ..
                } => {
                    log.debug(format!("joint_trajectory {end:?}: {message}"));
                    Ok(())
                }
                Event::TrajectoryEnded {
                    goal: Some(goal),
                    end,
                    code,
                    message,
                } => {
                    let Some(server) = &servers.trajectory else {
                        continue;
                    };
                    say_end(log, names::TRAJECTORY_ACTION, end, &message);
                    self.trajectory_goals.end(
                        server,
                        goal,
                        goal_status(end),
                        FollowJointTrajectoryResult {
                            error_code: code,
                            error_string: message,
                        },
                    )
                }
                Event::GripperEnded { goal, end, result } => {
                    let Some(server) = &servers.gripper else {
                        continue;
                    };
                    say_end(
                        log,
                        names::GRIPPER_ACTION,
                        end,
                        &format!(
                            "position {:.4} m, reached_goal {}, stalled {}",
                            result.position, result.reached_goal, result.stalled
                        ),
                    );
                    self.gripper_goals.end(
                        server,
                        goal,
                        goal_status(end),
                        ros_control::gripper_result(&result),
                    )
                }
            };
            if let Err(err) = outcome {
                log.warn(err);
            }
        }
    }

    /// One control period in ros2_control's order: read the hardware, update the controllers on
    /// that reading, write their commands (the world simulates the period). Advanced by a goal,
    /// the period is simulated only if a goal is still undecided after the update: an N-period
    /// trajectory takes exactly N steps, like N `joint_command`s. True when a period was
    /// simulated and published.
    fn advance(&mut self, servers: &ActionServers, by: Advance, log: &Logger) -> bool {
        let time_ns = self.sim_time_ns;
        let Some(run) = &mut self.run else {
            return false;
        };
        let period_ns = Self::period_ns(run);
        let started = Instant::now();
        let mut hardware = SimHardware::new(&mut run.env, time_ns);
        let state = hardware.read();
        let (command, events) = run.controllers.update(&state, period_ns);
        let simulate = by == Advance::Command || run.controllers.running();
        let step = simulate.then(|| {
            self.step_pool.run(|| {
                // The write's outcome is also in `last_step`, with the step's details.
                let _ = hardware.write(&command);
                hardware.last_step.take().expect("a write records its step")
            })
        });
        let physics = started.elapsed();
        self.report(servers, events, log);
        let Some(step) = step else { return false };
        let run = self.run.as_mut().expect("checked above");
        match step {
            Ok(step) => {
                for c in &step.info.clamped {
                    if run.clamp_reported.insert(c.joint.to_string()) {
                        log.warn(format!(
                            "target clamped: {c} (said once per joint and episode)"
                        ));
                    }
                }
                if let Some((terminated, truncated)) = run.env.ended() {
                    log.info(format!(
                        "episode {} over after {} steps ({}), return {:.3}, success {}",
                        run.episode,
                        run.env.steps(),
                        if terminated {
                            "terminated"
                        } else if truncated {
                            "horizon"
                        } else {
                            "?"
                        },
                        run.env.episode_return(),
                        run.env.success_seen()
                    ));
                }
            }
            Err(err @ EnvError::EpisodeOver { .. }) => {
                self.end_all_goals(
                    servers,
                    &format!("{err}; a new episode (reset) goes on"),
                    log,
                );
                let run = self.run.as_mut().expect("checked above");
                if self.mode == Mode::Realtime {
                    // The world stands still until the next episode; time and joint_states go on.
                    let world_msg = convert::world_state(
                        &run.env.world_state(),
                        convert::time_from_nanos(self.sim_time_ns),
                        run.episode,
                        run.env.steps(),
                    );
                    self.advance_clock();
                    self.publish_robot_state(&world_msg);
                } else if !run.over_reported {
                    run.over_reported = true;
                    log.warn(format!("command ignored: {err} (said once per episode)"));
                }
                return false;
            }
            Err(err) => {
                log.warn(format!("command refused: {err}"));
                self.end_all_goals(servers, &format!("the sim refused a command: {err}"), log);
                return false;
            }
        }
        self.advance_clock();
        self.publish_state();
        let t = &mut self.timing;
        t.steps += 1;
        t.physics += physics;
        t.publish += started.elapsed() - physics;
        if t.steps == TIMING_WINDOW {
            log.debug(format!(
                "last {} steps: physics {:.0} µs, publishing {:.0} µs per step",
                t.steps,
                t.physics.as_secs_f64() * 1e6 / t.steps as f64,
                t.publish.as_secs_f64() * 1e6 / t.steps as f64
            ));
            *t = StepTiming::default();
        }
        true
    }

    fn advance_clock(&mut self) {
        if let Some(run) = &self.run {
            self.sim_time_ns += Self::period_ns(run);
        }
    }
    /// Publish everything that describes the world now, stamped with the sim time: the
    /// episode's step (`world_state` first — the reward node's input — then `observation`),
    /// then the robot's state for ROS tools.
    fn publish_state(&mut self) {
        let Some(run) = &self.run else { return };
        let env = &run.env;
        let stamp = convert::time_from_nanos(self.sim_time_ns);
        let step = env.steps();
        let world_msg = convert::world_state(&env.world_state(), stamp.clone(), run.episode, step);
        // Publishing only fails when DDS is shutting down; the next step tries again.
        let _ = self.pubs.world_state.publish(world_msg.clone());
        let _ = self.pubs.observation.publish(convert::observation(
            &env.observation(),
            stamp.clone(),
            run.episode,
            step,
        ));
        self.publish_robot_state(&world_msg);
        if let Some(run) = &mut self.run {
            self.cameras.publish(&mut run.env, &stamp);
        }
    }

    /// `joint_states`, `tf`, `object_markers` and `clock` (also while a realtime episode is over,
    /// so ROS tools keep seeing a live robot).
    fn publish_robot_state(&mut self, world_msg: &msg::WorldState) {
        let Some(run) = &mut self.run else { return };
        let env = &run.env;
        let stamp = convert::time_from_nanos(self.sim_time_ns);
        let w = env.world();
        let mut positions = w.arm_positions().to_vec();
        positions.extend(w.finger_positions());
        let mut velocities = w.arm_velocities().to_vec();
        velocities.extend([w.joint_velocity(ARM_DOF), w.joint_velocity(ARM_DOF + 1)]);
        let _ = self.pubs.joint_states.publish(convert::joint_state(
            w.model,
            &positions,
            &velocities,
            stamp.clone(),
        ));
        let goal = env.goal();
        let goal_pose = convert::pose(&nalgebra::Isometry3::translation(goal.x, goal.y, goal.z));
        let mut transforms = vec![
            convert::world_transform(names::EEF_FRAME, &world_msg.eef_pose, stamp.clone()),
            convert::world_transform(names::OBJECT_FRAME, &world_msg.object_pose, stamp.clone()),
            convert::world_transform(names::GOAL_FRAME, &goal_pose, stamp.clone()),
        ];
        transforms.extend(view::link_transforms(w).iter().map(|link| {
            view::transform_stamped(link.parent, link.child, &link.transform, stamp.clone())
        }));
        let _ = self.pubs.tf.publish(TFMessage { transforms });
        if let Some(object_pose) = w.object_pose() {
            let _ = self.pubs.object_markers.publish(view::object_markers(
                env.task().object,
                &object_pose,
                stamp.clone(),
                !run.object_drawn,
            ));
            run.object_drawn = true;
        }
        let _ = self.pubs.clock.publish(Clock { clock: stamp });
    }
}

/// The action status of a goal that ended so.
fn goal_status(end: End) -> GoalStatusEnum {
    match end {
        End::Succeeded => GoalStatusEnum::Succeeded,
        End::Aborted => GoalStatusEnum::Aborted,
        End::Canceled => GoalStatusEnum::Canceled,
    }
}

/// Log a goal's end: success at debug level (there may be one per step), the rest louder.
fn say_end(log: &Logger, action: &str, end: End, message: &str) {
    match end {
        End::Succeeded => log.debug(format!("{action} goal succeeded: {message}")),
        End::Canceled => log.info(format!("{action} goal canceled: {message}")),
        End::Aborted => log.warn(format!("{action} goal aborted: {message}")),
    }
}
