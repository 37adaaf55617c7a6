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
mod commands;
pub mod controllers;
mod episode;
mod goals;
pub mod hardware;
mod params;
mod publish;
pub mod ros_control;
mod simulation_services;
mod stepping;
pub mod view;

use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::{Duration, Instant};

use composuite_core::batch::StepPool;
use composuite_core::env::{Env, EnvConfig};
use composuite_core::physics::RobotModel;
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
use ros2_client::action::GoalId;
use ros2_client::dds::ActionServer;
use ros2_client::{Gid, Message, ParameterValue, RmwRequestId};

use self::action_server::Goals;
use self::controllers::catalog::{self, Controller};
use self::controllers::running::Controllers;
use self::hardware::{JointSnapshot, read_env};
use crate::shared::intra_process::{Publisher, Subscription};
use crate::shared::names;
use crate::shared::node::RosNode;
use crate::shared::param_server::Parameters;
use crate::shared::qos;

pub use params::{Mode, PARAMS};
use stepping::{Advance, StepTiming};

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
}
