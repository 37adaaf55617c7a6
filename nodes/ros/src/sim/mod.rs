//! The `sim` node: owns the physics world (the core's [`Env`]), steps it, publishes what a real
//! arm's driver and the reward node need.
//!
//! - `scene` (from the task manager) starts an episode: the world is rebuilt when the task
//!   changes, then reset with the scene's seed; the sim time goes on from the scene's stamp
//!   if that is later (a restarted sim);
//! - `joint_command` (absolute targets by joint name; may carry the finger joints) and
//!   `gripper_command` (opening, effort) set the targets; `reference_action` (8 values in
//!   [−1, 1]) acts as the reference benchmark's agents do (joint deltas + gripper sign, its
//!   soft controller), so a Gymnasium agent written for CompoSuite sees the same environment;
//! - `lockstep` mode: each `joint_command` or `reference_action` advances exactly one control
//!   period, and nothing else does; `realtime` mode: a wall-clock timer steps with the last
//!   command held;
//! - after every step (and at reset): `world_state` first (the reward node's input), then
//!   `observation`, `joint_states`, `tf`, `clock`, all stamped with the new sim time; when the
//!   robot changes, the latched `robot_description` and `tf_static` (world → the arm's root link).
//!
//! Sim time never goes backwards: it advances one control period per step, and one per reset,
//! so every stamp is unique within a run.

pub mod controllers;
pub mod hardware;

use std::collections::BTreeSet;
use std::time::{Duration, Instant};

use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig, EnvError};
use composuite_core::physics::{ARM_DOF, robot_description, robot_model};
use composuite_msgs::control_msgs::msg::GripperCommand;
use composuite_msgs::msg;
use composuite_msgs::rosgraph_msgs::msg::Clock;
use composuite_msgs::sensor_msgs::msg::JointState;
use composuite_msgs::std_msgs::msg::{Float64MultiArray, String as StringMsg};
use composuite_msgs::tf2_msgs::msg::TFMessage;
use futures::{FutureExt, StreamExt};
use ros2_client::dds::Publisher;
use ros2_client::{Gid, ParameterValue};

use crate::shared::convert;
use crate::shared::names;
use crate::shared::node::{ParamChange, RosNode};
use crate::shared::params::{ParamSpec, any_value, positive_number};
use crate::shared::qos;

fn check_mode(v: &ParameterValue) -> Result<(), String> {
    match v {
        ParameterValue::String(s) if Mode::parse(s).is_some() => Ok(()),
        _ => Err("valid: lockstep, realtime".into()),
    }
}

/// The sim node's parameters.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mode",
        default: || ParameterValue::String("lockstep".into()),
        description: "lockstep: one control period per joint_command; realtime: wall-clock pace",
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
];

/// How the sim advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// One control period per `joint_command` or `reference_action`.
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
}

/// The episode being simulated.
struct Running {
    env: Env,
    /// The scene's episode number (the task manager counts episodes).
    episode: u32,
    /// Who published that scene. A restarted task manager is another writer whose episode
    /// numbers start again at 1: its scenes are new even where a number repeats.
    scene_writer: Gid,
    /// The arm command held between commands (realtime mode steps with it).
    held: HeldCommand,
    /// A gripper command waiting for the next step.
    gripper: Option<(f64, f64)>,
    /// Joints already reported as clamped this episode (said once).
    clamp_reported: BTreeSet<String>,
    /// Whether "episode over" was already said for this episode.
    over_reported: bool,
}

/// The last arm command received, which the next step uses.
#[derive(Debug, Clone, Copy)]
enum HeldCommand {
    /// Absolute joint targets (`joint_command`, or the pose at reset).
    Targets([f64; ARM_DOF]),
    /// The reference's normalised action (`reference_action`): held like a velocity command,
    /// each step moves the goal from the joints' measured positions again.
    Reference([f64; REFERENCE_ACTION_LEN]),
}

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

struct Sim {
    timing: StepTiming,
    mode: Mode,
    realtime_factor: f64,
    task_observation: bool,
    sim_time_ns: u64,
    run: Option<Running>,
    pubs: Publishers,
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
    let gripper_sub = node
        .subscription::<GripperCommand>(names::GRIPPER_COMMAND, qos::state())
        .map_err(e)?;
    let mut sim = Sim {
        mode: Mode::parse(&node.param_string("mode")).unwrap_or(Mode::Lockstep),
        realtime_factor: node.param_f64("realtime_factor"),
        task_observation: node.param_bool("task_observation"),
        sim_time_ns: 0,
        run: None,
        pubs,
        timing: StepTiming::default(),
    };
    let log = node.log.clone();
    log.info(format!(
        "{} up in {:?} mode; waiting for a scene on `{}`",
        node.fully_qualified_name(),
        sim.mode,
        names::SCENE
    ));
    let param_changes = node.param_changes.clone();
    smol::block_on(async {
        let mut scenes = std::pin::pin!(scene_sub.async_stream());
        let mut commands = std::pin::pin!(command_sub.async_stream());
        let mut grippers = std::pin::pin!(gripper_sub.async_stream());
        let mut actions = std::pin::pin!(action_sub.async_stream());
        let mut ticker = sim.ticker();
        loop {
            futures::select_biased! {
                signal = signals.recv().fuse() => {
                    log.info(format!("signal {} received, shutting down", signal.unwrap_or(0)));
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
                        sim.on_scene(&scene, info.publisher_gid(), &log);
                        ticker = sim.ticker();
                    }
                    Err(err) => log.warn(format!("unreadable scene message dropped: {err:?}")),
                },
                gripper = grippers.select_next_some() => match gripper {
                    Ok((command, _)) => sim.on_gripper(&command, &log),
                    Err(err) => log.warn(format!("unreadable gripper_command dropped: {err:?}")),
                },
                command = commands.select_next_some() => match command {
                    Ok((command, _)) => sim.on_joint_command(&command, &log),
                    Err(err) => log.warn(format!("unreadable joint_command dropped: {err:?}")),
                },
                action = actions.select_next_some() => match action {
                    Ok((action, _)) => sim.on_reference_action(&action, &log),
                    Err(err) => log.warn(format!("unreadable reference_action dropped: {err:?}")),
                },
                _ = ticker.next().fuse() => sim.step(&log),
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

    fn on_param(&mut self, change: &ParamChange, log: &crate::shared::node::Logger) {
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
            _ => {}
        }
    }

    fn on_scene(&mut self, scene: &msg::Scene, writer: Gid, log: &crate::shared::node::Logger) {
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
        let mut env = reuse.unwrap_or_else(|| Env::new(task, config));
        if let Err(err) = env.reset(scene.seed) {
            log.error(format!("cannot start episode {}: {err}", scene.episode));
            return;
        }
        let held = HeldCommand::Targets(env.world().arm_positions());
        self.run = Some(Running {
            env,
            episode: scene.episode,
            scene_writer: writer,
            held,
            gripper: None,
            clamp_reported: BTreeSet::new(),
            over_reported: false,
        });
        if robot_changed {
            let _ = self.pubs.robot_description.publish(StringMsg {
                data: robot_description(task.robot),
            });
            // The URDF's root link sits at the robot base pose in the world.
            let root = &robot_model(task.robot).bodies[0].name;
            let base = convert::pose(&composuite_core::arena::robot_base_pose());
            let _ = self.pubs.tf_static.publish(TFMessage {
                transforms: vec![convert::world_transform(
                    root,
                    &base,
                    convert::time_from_nanos(self.sim_time_ns),
                )],
            });
        }
        log.info(format!(
            "episode {} of {task}, seed {}",
            scene.episode, scene.seed
        ));
        self.advance_clock();
        self.publish_state();
    }

    fn on_gripper(&mut self, command: &GripperCommand, log: &crate::shared::node::Logger) {
        let Some(run) = &mut self.run else {
            log.warn(
                "gripper_command ignored: no episode yet (the task manager publishes the scene)",
            );
            return;
        };
        let model = robot_model(run.env.task().robot);
        // Checked now so a bad command is refused on arrival, not at the next step.
        match composuite_core::control::validate_gripper_width(
            model,
            command.position,
            command.max_effort,
        ) {
            Ok(_) => run.gripper = Some((command.position, command.max_effort)),
            Err(err) => log.warn(format!("gripper_command refused: {err}")),
        }
    }

    fn on_joint_command(&mut self, command: &JointState, log: &crate::shared::node::Logger) {
        let Some(run) = &mut self.run else {
            log.warn(
                "joint_command ignored: no episode yet (the task manager publishes the scene)",
            );
            return;
        };
        let model = robot_model(run.env.task().robot);
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
        run.held = HeldCommand::Targets(arm);
        if let Some(gap) = finger_gap {
            run.gripper = Some((gap, 0.0));
        }
        if self.mode == Mode::Lockstep {
            self.step(log);
        }
    }

    fn on_reference_action(
        &mut self,
        action: &Float64MultiArray,
        log: &crate::shared::node::Logger,
    ) {
        let Some(run) = &mut self.run else {
            log.warn(
                "reference_action ignored: no episode yet (the task manager publishes the scene)",
            );
            return;
        };
        let values: [f64; REFERENCE_ACTION_LEN] = match action.data.as_slice().try_into() {
            Ok(values) => values,
            Err(_) => {
                log.warn(format!(
                    "reference_action refused: it has {} values; it needs {REFERENCE_ACTION_LEN} \
                     (7 joint deltas, then the gripper), each in [-1, 1]",
                    action.data.len()
                ));
                return;
            }
        };
        // Out-of-range values are clipped, as the reference does; non-finite ones refused here
        // so the held command never holds a value the next step would refuse.
        if let Some((index, value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            log.warn(format!(
                "reference_action refused: value {index} is {value}; each must be finite \
                 (it is clipped to [-1, 1])"
            ));
            return;
        }
        run.held = HeldCommand::Reference(values);
        if self.mode == Mode::Lockstep {
            self.step(log);
        }
    }

    /// One control period with the held targets.
    fn step(&mut self, log: &crate::shared::node::Logger) {
        let Some(run) = &mut self.run else { return };
        let action = match run.held {
            HeldCommand::Targets(joints) => Action::Absolute {
                joints,
                gripper: run.gripper.take(),
            },
            // The reference's action carries its own gripper command.
            HeldCommand::Reference(values) => Action::Reference(values),
        };
        let started = Instant::now();
        let result = run.env.step(&action);
        let physics = started.elapsed();
        match result {
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
            Err(EnvError::EpisodeOver { .. }) if self.mode == Mode::Realtime => {
                // The world stands still until the next episode; time and joint_states go on.
                let run = self.run.as_ref().expect("checked above");
                let world_msg = convert::world_state(
                    &run.env.world_state(),
                    convert::time_from_nanos(self.sim_time_ns),
                    run.episode,
                    run.env.steps(),
                );
                self.advance_clock();
                self.publish_robot_state(&world_msg);
                return;
            }
            Err(err @ EnvError::EpisodeOver { .. }) => {
                if !run.over_reported {
                    run.over_reported = true;
                    log.warn(format!(
                        "joint_command ignored: {err} (said once per episode)"
                    ));
                }
                return;
            }
            Err(err) => {
                log.warn(format!("command refused: {err}"));
                return;
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
    }

    fn advance_clock(&mut self) {
        if let Some(run) = &self.run {
            let period_ns = (run.env.config().control_period() * 1e9).round() as u64;
            self.sim_time_ns += period_ns;
        }
    }

    /// Publish everything that describes the world now, stamped with the sim time: the
    /// episode's step (`world_state` first — the reward node's input — then `observation`),
    /// then the robot's state for ROS tools.
    fn publish_state(&self) {
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
    }

    /// `joint_states`, `tf` and `clock` (also while a realtime episode is over, so ROS tools
    /// keep seeing a live robot).
    fn publish_robot_state(&self, world_msg: &msg::WorldState) {
        let Some(run) = &self.run else { return };
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
        let _ = self.pubs.tf.publish(TFMessage {
            transforms: vec![
                convert::world_transform(names::EEF_FRAME, &world_msg.eef_pose, stamp.clone()),
                convert::world_transform(
                    names::OBJECT_FRAME,
                    &world_msg.object_pose,
                    stamp.clone(),
                ),
                convert::world_transform(names::GOAL_FRAME, &goal_pose, stamp.clone()),
            ],
        });
        let _ = self.pubs.clock.publish(Clock { clock: stamp });
    }
}
