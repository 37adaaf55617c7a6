//! The in-process environment: one task, episodes of at most `horizon` control steps, factored
//! observations, staged rewards. Tests, benchmarks and the ROS nodes all drive this one API.
//!
//! ```
//! use composuite_core::env::{Action, Env, EnvConfig};
//! let mut env = Env::new("IIWA/box/no_obstacle/pick_place".parse().unwrap(), EnvConfig::default());
//! let obs = env.reset(7).unwrap();
//! assert_eq!(obs.flat().len(), 93);
//! let step = env.step(&Action::Reference([0.0; 8])).unwrap();
//! assert!((0.0..=1.0).contains(&step.reward));
//! ```

mod action;
mod layout;
mod reset;
mod world_state;

use std::fmt;

use nalgebra::{Isometry3, Point3, Vector3};

pub use action::Action;
pub(crate) use action::REFERENCE_DELTA_SCALE;
pub use layout::EpisodeLayout;
pub use reset::{MAX_SEED, UNSEEDED, draw_object_start, sample_object_start};
pub use world_state::WorldState;

use crate::TaskSpec;
use crate::arena::{Placed, arena_parts, goal_position, obstacle_geometry};
use crate::axes::Obstacle;
use crate::control::{ArmCommandError, Clamped, GripperCommandError};
use crate::obs::{GoalFactor, Observation, RelativePose, RobotFactor, TaskFactor, xyzw};
use crate::physics::{ARM_DOF, FINGER_OPEN, PhysicsParams, ServoMode, SimWorld};
use crate::render::{Camera, Frame, MAX_SIDE, RenderError, SceneRenderer, posed_camera};
use crate::reward::{
    RewardConfig, StagedReward, Termination, WorldSnapshot, staged_reward, termination,
};
use crate::rng::Mt19937;

/// Settings of an environment; start from `EnvConfig::default()` and change fields with the
/// builder methods.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvConfig {
    /// Episode length limit in control steps (the reference's training loop cuts at 500).
    pub horizon: u32,
    /// Whether the flat observation includes the task one-hots (93 values) or not (77).
    pub task_observation: bool,
    /// Physics settings (2 ms steps, 25 per control step by default).
    pub physics: PhysicsParams,
    /// Shaped or sparse rewards, and their scale (shaped, × 1 by default, as the reference).
    pub reward: RewardConfig,
}

impl Default for EnvConfig {
    fn default() -> Self {
        EnvConfig {
            horizon: 500,
            task_observation: true,
            physics: PhysicsParams::default(),
            reward: RewardConfig::default(),
        }
    }
}

impl EnvConfig {
    /// Set the horizon (control steps).
    #[must_use]
    pub fn horizon(mut self, horizon: u32) -> Self {
        self.horizon = horizon;
        self
    }

    /// Include the task one-hots in the flat observation or not.
    #[must_use]
    pub fn task_observation(mut self, on: bool) -> Self {
        self.task_observation = on;
        self
    }

    /// Shaped rewards (`true`, the default) or sparse ones: 1 on success, else 0.
    #[must_use]
    pub fn reward_shaping(mut self, on: bool) -> Self {
        self.reward.shaping = on;
        self
    }

    /// Multiply every reward by `scale` (the reference's `reward_scale`; 1 by default).
    #[must_use]
    pub fn reward_scale(mut self, scale: f64) -> Self {
        self.reward.scale = scale;
        self
    }

    /// Control period (s): physics step × substeps.
    pub fn control_period(&self) -> f64 {
        self.physics.dt * self.physics.substeps as f64
    }
}

/// Why a reset or step was refused. The environment is unchanged when one is returned.
#[derive(Debug, Clone, PartialEq)]
pub enum EnvError {
    /// `step` before the first `reset`.
    NotReset,
    /// `step` after the episode ended (terminated or truncated); reset first.
    EpisodeOver {
        /// The episode that ended.
        episode: u32,
        /// Steps it ran.
        steps: u32,
    },
    /// A seed the reference's numpy seeding cannot take.
    BadSeed(u64),
    /// The start sampler found no position clear of the obstacle (as the reference would fail).
    NoClearStart {
        /// The seed.
        seed: u64,
    },
    /// A bad arm command.
    Arm(ArmCommandError),
    /// A bad gripper command.
    Gripper(GripperCommandError),
    /// A reference action with a NaN or infinite component.
    BadReferenceAction {
        /// Index of the component (0–7).
        index: usize,
        /// Its value.
        value: f64,
    },
}

impl fmt::Display for EnvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EnvError::NotReset => write!(f, "step before the first reset; call reset(seed) first"),
            EnvError::EpisodeOver { episode, steps } => {
                write!(
                    f,
                    "episode {episode} is over (ended after {steps} steps); call reset(seed) to start another"
                )
            }
            EnvError::BadSeed(seed) => write!(
                f,
                "seed {seed} is out of range; valid seeds are 0..={MAX_SEED} (numpy's)"
            ),
            EnvError::NoClearStart { seed } => {
                write!(
                    f,
                    "seed {seed}: no object start clear of the obstacle in {} draws",
                    crate::arena::PLACEMENT_ATTEMPTS
                )
            }
            EnvError::Arm(e) => write!(f, "{e}"),
            EnvError::Gripper(e) => write!(f, "{e}"),
            EnvError::BadReferenceAction { index, value } => write!(
                f,
                "action[{index}] is {value}; reference actions are 8 finite numbers in [-1, 1] \
                 (7 joint deltas, then the gripper)"
            ),
        }
    }
}

impl std::error::Error for EnvError {}

/// What a step returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The observation after the step.
    pub observation: Observation,
    /// The reward: 1 on success, else the best stage value (0 with sparse rewards), times the
    /// reward scale ([`EnvConfig::reward`]).
    pub reward: f64,
    /// The objective's own termination ended the episode (Push: object lifted).
    pub terminated: bool,
    /// The horizon ended the episode.
    pub truncated: bool,
    /// Every stage's value, success, and what was clamped.
    pub info: StepInfo,
}

/// Details of a step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepInfo {
    /// The staged reward, every stage exposed.
    pub staged: StagedReward,
    /// Whether the objective's success test holds (reward = 1).
    pub success: bool,
    /// Why the episode terminated, if it did.
    pub termination: Option<Termination>,
    /// Targets that were outside the limits and were clamped.
    pub clamped: Vec<Clamped>,
}

/// Where the episode stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    NotReset,
    Running,
    Over { terminated: bool, truncated: bool },
}

/// One task's environment.
pub struct Env {
    task: TaskSpec,
    config: EnvConfig,
    /// The task's world as built, never stepped: every reset starts from a copy of it.
    template: SimWorld,
    world: SimWorld,
    phase: Phase,
    episode: u32,
    step: u32,
    seed: u64,
    object_start: Point3<f64>,
    goal: Point3<f64>,
    last_gripper_action: f64,
    episode_return: f64,
    success_seen: bool,
    /// The scene's meshes, built on the first [`Env::render`].
    renderer: Option<Box<SceneRenderer>>,
}

impl Env {
    /// The environment of `task`; call [`Env::reset`] before stepping.
    pub fn new(task: TaskSpec, config: EnvConfig) -> Env {
        let goal = goal_position(task.objective, task.object);
        // The object waits below the floor until the first reset places it.
        let template = build_world(&task, &config, &Isometry3::translation(0.0, 0.0, -10.0));
        Env {
            task,
            config,
            world: template.fresh_copy(),
            template,
            phase: Phase::NotReset,
            episode: 0,
            step: 0,
            seed: 0,
            object_start: Point3::origin(),
            goal,
            last_gripper_action: 0.0,
            episode_return: 0.0,
            success_seen: false,
            renderer: None,
        }
    }

    /// Start an episode: the arm at its initial pose with the gripper open, the object at the
    /// start the reference draws for `seed` (numpy seeding, docs/src/reference-facts.md §2.2
    /// and §7.3). The physics starts from a fresh copy of the task's world, so an episode depends
    /// only on its seed and actions.
    pub fn reset(&mut self, seed: u64) -> Result<Observation, EnvError> {
        let start = sample_object_start(self.task.obstacle, self.task.object, seed)?;
        Ok(self.start_episode(start, seed))
    }

    /// Start an episode with the reference's draws taken from `rng` as it stands (numpy's
    /// global generator, which the reference's `reset()` draws from when no seed is set: the
    /// reference's own API, `composuite_ros.compat`, passes its state through here). `rng` is
    /// left where the reference leaves numpy's. The episode's [`Env::seed`] is
    /// [`UNSEEDED`]: its start came from a generator state, not a seed.
    pub fn reset_from(&mut self, rng: &mut Mt19937) -> Result<Observation, EnvError> {
        let start = draw_object_start(self.task.obstacle, self.task.object, rng)
            .ok_or(EnvError::NoClearStart { seed: UNSEEDED })?;
        Ok(self.start_episode(start, UNSEEDED))
    }

    fn start_episode(&mut self, start: Point3<f64>, seed: u64) -> Observation {
        self.world = self.template.fresh_copy();
        self.world
            .place_object(&Isometry3::translation(start.x, start.y, start.z));
        self.phase = Phase::Running;
        self.episode += 1;
        self.step = 0;
        self.seed = seed;
        self.object_start = start;
        self.last_gripper_action = 0.0;
        self.episode_return = 0.0;
        self.success_seen = false;
        self.observation()
    }

    /// Advance one control period with `action`. Refused (nothing changes) after the episode
    /// ended, before the first reset, or for an invalid action.
    pub fn step(&mut self, action: &Action) -> Result<Step, EnvError> {
        // The action is checked where it is applied.
        self.check_running()?;
        let clamped = action.apply(&mut self.world, &mut self.last_gripper_action)?;
        self.world.step_control();
        self.step += 1;
        let snapshot = self.snapshot();
        let staged = staged_reward(self.task.objective, self.task.object, &snapshot);
        let termination = termination(self.task.objective, &snapshot);
        let terminated = termination.is_some();
        let truncated = !terminated && self.step >= self.config.horizon;
        if terminated || truncated {
            self.phase = Phase::Over {
                terminated,
                truncated,
            };
        }
        let reward = self.config.reward.reward(&staged);
        self.episode_return += reward;
        self.success_seen |= staged.success;
        Ok(Step {
            observation: self.observation(),
            reward,
            terminated,
            truncated,
            info: StepInfo {
                success: staged.success,
                staged,
                termination,
                clamped,
            },
        })
    }

    /// Whether [`Env::step`] would refuse `action` now (no episode running, or an invalid
    /// action), without stepping.
    pub fn check_step(&self, action: &Action) -> Result<(), EnvError> {
        self.check_running()?;
        action.check(&self.world)
    }

    fn check_running(&self) -> Result<(), EnvError> {
        match self.phase {
            Phase::NotReset => Err(EnvError::NotReset),
            Phase::Over { .. } => Err(EnvError::EpisodeOver {
                episode: self.episode,
                steps: self.step,
            }),
            Phase::Running => Ok(()),
        }
    }

    /// The current observation.
    pub fn observation(&self) -> Observation {
        let w = &self.world;
        let eef = self.eef_frame();
        let object = w.object_pose().expect("the env always has an object");
        let object_position = Point3::from(object.translation.vector);
        let obstacle = match self.task.obstacle {
            Obstacle::NoObstacle => RelativePose::absent(&eef),
            other => {
                let pose = obstacle_geometry(other).body_pose();
                RelativePose::new(Point3::from(pose.translation.vector), pose.rotation, &eef)
            }
        };
        let q = w.arm_positions();
        let fingers = w.finger_positions();
        Observation {
            object: RelativePose::new(object_position, object.rotation, &eef),
            obstacle,
            goal: GoalFactor::new(self.goal, object_position, &eef),
            task: TaskFactor::of(&self.task),
            robot: RobotFactor {
                joint_pos_cos: q.map(f64::cos),
                joint_pos_sin: q.map(f64::sin),
                joint_vel: w.arm_velocities(),
                eef_position: eef.translation.vector.into(),
                eef_orientation: xyzw(&eef.rotation),
                gripper_qpos: fingers,
                gripper_qvel: [w.joint_velocity(ARM_DOF), w.joint_velocity(ARM_DOF + 1)],
            },
            includes_task: self.config.task_observation,
        }
    }

    /// The reference's end-effector frame: grip-site position, hand orientation.
    fn eef_frame(&self) -> Isometry3<f64> {
        let grip = self.world.grip_site_pose();
        Isometry3::from_parts(grip.translation, self.world.hand_pose().rotation)
    }

    fn snapshot(&self) -> WorldSnapshot {
        let eef = self.eef_frame();
        let object = self.world.object_pose().expect("object");
        WorldSnapshot {
            object_position: Point3::from(object.translation.vector),
            grip_site_position: Point3::from(eef.translation.vector),
            hand_z_axis: eef.rotation * nalgebra::Vector3::z(),
            grasping: self.world.finger_contacts().grasping(self.task.object),
            last_gripper_action: self.last_gripper_action,
        }
    }

    /// Privileged ground truth (what the reward needs and agents do not observe).
    pub fn world_state(&self) -> WorldState {
        WorldState::read(
            &self.world,
            self.task.object,
            &self.eef_frame(),
            self.last_gripper_action,
        )
    }

    /// The task.
    pub fn task(&self) -> TaskSpec {
        self.task
    }

    /// The configuration.
    pub fn config(&self) -> &EnvConfig {
        &self.config
    }

    /// Episode counter (1 for the first episode; 0 before any reset).
    pub fn episode(&self) -> u32 {
        self.episode
    }

    /// Control steps taken in this episode.
    pub fn steps(&self) -> u32 {
        self.step
    }

    /// The seed of this episode.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Whether the episode ended (and how): `Some((terminated, truncated))`.
    pub fn ended(&self) -> Option<(bool, bool)> {
        match self.phase {
            Phase::Over {
                terminated,
                truncated,
            } => Some((terminated, truncated)),
            _ => None,
        }
    }

    /// Sum of the rewards of this episode.
    pub fn episode_return(&self) -> f64 {
        self.episode_return
    }

    /// Whether any step of this episode succeeded.
    pub fn success_seen(&self) -> bool {
        self.success_seen
    }

    /// Where the object started this episode.
    pub fn object_start(&self) -> Point3<f64> {
        self.object_start
    }

    /// The goal marker's position.
    pub fn goal(&self) -> Point3<f64> {
        self.goal
    }

    /// Where this episode's arena, object start and goal are.
    pub fn layout(&self) -> EpisodeLayout {
        EpisodeLayout {
            task: self.task,
            seed: self.seed,
            object_start: self.object_start,
            goal: self.goal,
        }
    }

    /// Every static solid, the object at its start pose, and the goal marker, in the world.
    pub fn scene_parts(&self) -> Vec<Placed> {
        self.layout().parts()
    }

    /// Hold a torque (N·m, world frame) on the object about its centre of mass — MuJoCo's
    /// `xfrc_applied`, for test rigs and disturbance studies. It lasts until changed or until
    /// the next reset; an episode disturbed this way is not reproducible from its actions alone.
    pub fn set_object_torque(&mut self, torque: Vector3<f64>) {
        self.world.set_object_torque(torque);
    }

    /// Teleport the object: `pose` (world), linear (m/s) and angular (rad/s) velocity, as a
    /// curriculum or a demonstration start sets it. The next [`Env::step`] simulates from there,
    /// so its observation and reward follow the new state; an episode changed this way is not
    /// reproducible from its actions alone. Refused before the first reset, for a non-finite
    /// value, a quaternion that is not of unit length, or a position outside the ground.
    pub fn set_object_state(
        &mut self,
        pose: &Isometry3<f64>,
        linear: &Vector3<f64>,
        angular: &Vector3<f64>,
    ) -> Result<(), String> {
        if self.phase == Phase::NotReset {
            return Err("no episode yet: reset first".into());
        }
        let t = pose.translation.vector;
        let q = pose.rotation.quaternion().coords;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(t.as_slice()) || !finite(q.as_slice()) {
            return Err(format!("the pose has a non-finite value: {t:?}, {q:?}"));
        }
        if !finite(linear.as_slice()) || !finite(angular.as_slice()) {
            return Err(format!(
                "a velocity has a non-finite value: {linear:?}, {angular:?}"
            ));
        }
        let [hx, hy] = crate::arena::GROUND_HALF_SIZE;
        if t.x.abs() > hx || t.y.abs() > hy || t.z < 0.0 {
            return Err(format!(
                "position ({:.3}, {:.3}, {:.3}) m is outside the world: |x| <= {hx}, |y| <= {hy}, z >= 0",
                t.x, t.y, t.z
            ));
        }
        self.world.set_object_motion(pose, linear, angular);
        Ok(())
    }

    /// The simulated world (read only; commands go through [`Env::step`]).
    pub fn world(&self) -> &SimWorld {
        &self.world
    }

    /// The scene as camera `camera` (one of [`CAMERAS`](crate::render::CAMERAS)) sees it now,
    /// `width` × `height` pixels: colour, depth along the optical axis (m) and what each pixel
    /// shows. The same state gives the same frame, bit for bit. The first call reads the URDF's
    /// visuals and tessellates the scene (under 2 ms); later calls only pose and draw it.
    ///
    /// ```
    /// use composuite_core::env::{Env, EnvConfig};
    /// let mut env = Env::new("Panda/box/no_obstacle/pick_place".parse().unwrap(), EnvConfig::default());
    /// env.reset(0).unwrap();
    /// let frame = env.render("frontview", 84, 84).unwrap();
    /// assert_eq!(frame.rgb.len(), 84 * 84 * 3);
    /// assert!(env.render("front", 84, 84).unwrap_err().to_string().contains("frontview"));
    /// ```
    pub fn render(&mut self, camera: &str, width: u32, height: u32) -> Result<Frame, RenderError> {
        let camera = self.camera(camera)?;
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            return Err(RenderError::BadSize { width, height });
        }
        let renderer = self
            .renderer
            .get_or_insert_with(|| Box::new(SceneRenderer::new(self.task, self.world.model)));
        Ok(renderer.render(&self.world, &camera, width, height))
    }

    /// Camera `name` where it is now (the wrist camera moves with the arm).
    pub fn camera(&self, name: &str) -> Result<Camera, RenderError> {
        posed_camera(&self.world, name)
    }
}

fn build_world(task: &TaskSpec, config: &EnvConfig, object_pose: &Isometry3<f64>) -> SimWorld {
    let mut world = SimWorld::new(task.robot, config.physics.clone());
    world.add_arena(&arena_parts(task.objective, task.obstacle));
    world.add_object(task.object, object_pose);
    world.reset_arm(&task.robot.init_qpos(), FINGER_OPEN);
    world.set_servo_mode(ServoMode::Stiff);
    world
}
