//! The reference benchmark's own recorded episodes (`tests/reference/data/`, written by
//! `tests/reference/generate.py` from CompoSuite 1fa36f6 on robosuite 1.4.0 / MuJoCo 2.3.7; the
//! formats are described in `tests/reference/README.md`): loading them and replaying their
//! actions in the port. Shared by the fidelity tests and the `reference_divergence` example.
#![allow(dead_code)]

use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;

use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::reward::WorldSnapshot;
use nalgebra::{Point3, Vector3};
use serde_json::Value;

/// Where the data lives: `tests/reference/data`, or `$COMPOSUITE_REFERENCE_DATA` (to check a
/// freshly generated set before it replaces the committed one).
pub fn data_dir() -> PathBuf {
    match std::env::var_os("COMPOSUITE_REFERENCE_DATA") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/reference/data"),
    }
}

pub mod numpy_random;

/// A data file as JSON (`.json.gz` files are decompressed).
fn load(file: &str) -> Value {
    let path = data_dir().join(file);
    let reader =
        BufReader::new(File::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())));
    let parsed = if file.ends_with(".gz") {
        serde_json::from_reader(flate2::read::GzDecoder::new(reader))
    } else {
        serde_json::from_reader(reader)
    };
    parsed.unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("a list of numbers")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

fn rows(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().expect("a list").iter().map(floats).collect()
}

fn point(v: &[f64]) -> Point3<f64> {
    Point3::new(v[0], v[1], v[2])
}

fn task(record: &Value) -> TaskSpec {
    let name = record["name"].as_str().expect("task name");
    name.parse()
        .unwrap_or_else(|e| panic!("task {name} in the reference data: {e}"))
}

/// Observation index ranges the comparisons name.
pub mod layout {
    use std::ops::Range;
    /// The eef-relative quaternions the reference derives from rotation matrices (object,
    /// obstacle, goal): xyzw, w last.
    pub const RELATIVE_QUATERNIONS: [Range<usize>; 3] = [10..14, 24..28, 38..42];
    /// Object body position.
    pub const OBJECT_POSITION: Range<usize> = 0..3;
    /// Arm joint cosines and sines.
    pub const JOINT_COS: Range<usize> = 61..68;
    pub const JOINT_SIN: Range<usize> = 68..75;
    /// Grip site position.
    pub const EEF_POSITION: Range<usize> = 82..85;
    /// Hand orientation, xyzw.
    pub const EEF_QUATERNION: Range<usize> = 85..89;
    /// Field name of an observation index, for messages.
    pub fn field(index: usize) -> &'static str {
        const FIELDS: [(usize, &str); 23] = [
            (0, "obj_pos"),
            (3, "obj_quat"),
            (7, "obj_to_eef_pos"),
            (10, "obj_to_eef_quat"),
            (14, "obstacle_pos"),
            (17, "obstacle_quat"),
            (21, "obstacle_to_eef_pos"),
            (24, "obstacle_to_eef_quat"),
            (28, "goal_pos"),
            (31, "goal_quat"),
            (35, "goal_to_eef_pos"),
            (38, "goal_to_eef_quat"),
            (42, "obj_to_goal"),
            (45, "object_id"),
            (49, "robot_id"),
            (53, "obstacle_id"),
            (57, "subtask_id"),
            (61, "joint_pos_cos"),
            (68, "joint_pos_sin"),
            (75, "joint_vel"),
            (82, "eef_pos"),
            (85, "eef_quat"),
            (89, "gripper_qpos/qvel"),
        ];
        FIELDS
            .iter()
            .rev()
            .find(|(start, _)| index >= *start)
            .map(|(_, name)| *name)
            .unwrap_or("?")
    }
}

/// One task and seed of `step0.json.gz`: the observation `reset()` returned.
pub struct Step0 {
    pub task: TaskSpec,
    pub seed: u64,
    pub observation: Vec<f64>,
}

impl Step0 {
    /// The port's observation for the same task and seed.
    pub fn ours(&self) -> Vec<f64> {
        let mut env = Env::new(self.task, EnvConfig::default());
        env.reset(self.seed).expect("reset").flat()
    }
}

/// Every task × seed of `step0.json.gz` (256 × 5).
pub fn step0() -> Vec<Step0> {
    let data = load("step0.json.gz");
    let mut cases = Vec::new();
    for record in data["tasks"].as_array().expect("tasks") {
        let task = task(record);
        for seed in record["seeds"].as_array().expect("seeds") {
            cases.push(Step0 {
                task,
                seed: seed["seed"].as_u64().expect("seed"),
                observation: floats(&seed["obs"]),
            });
        }
    }
    cases
}

/// One recorded episode of `trajectories.json.gz`: record 0 is the state after `reset`,
/// record t + 1 the state after action t.
pub struct Trajectory {
    pub task: TaskSpec,
    pub seed: u64,
    pub actions: Vec<[f64; 8]>,
    pub stage_names: Vec<String>,
    pub observations: Vec<Vec<f64>>,
    /// `None` for record 0.
    pub rewards: Vec<Option<f64>>,
    pub staged: Vec<Vec<f64>>,
    pub success: Vec<bool>,
    pub grasp: Vec<bool>,
    pub object_position: Vec<Vec<f64>>,
    pub grip_site_position: Vec<Vec<f64>>,
    pub hand_z: Vec<Vec<f64>>,
}

impl Trajectory {
    /// The world the reference's reward saw at record `r`, as the port's reward reads it.
    /// Trashcan's drop stage reads the last gripper action: record 0 used an all-zero action.
    pub fn snapshot(&self, r: usize) -> WorldSnapshot {
        let hand_z = &self.hand_z[r];
        WorldSnapshot {
            object_position: point(&self.object_position[r]),
            grip_site_position: point(&self.grip_site_position[r]),
            hand_z_axis: Vector3::new(hand_z[0], hand_z[1], hand_z[2]),
            grasping: self.grasp[r],
            last_gripper_action: if r == 0 { 0.0 } else { self.actions[r - 1][7] },
        }
    }

    /// The port's observations and rewards for the same seed and actions, record for record
    /// (stops where the port ends the episode).
    pub fn replay(&self, config: EnvConfig) -> Replay {
        let mut env = Env::new(self.task, config);
        let mut replay = Replay {
            observations: vec![env.reset(self.seed).expect("reset").flat()],
            rewards: vec![None],
        };
        for action in self.actions.iter().take(self.observations.len() - 1) {
            match env.step(&Action::Reference(*action)) {
                Ok(step) => {
                    replay.observations.push(step.observation.flat());
                    replay.rewards.push(Some(step.reward));
                }
                Err(_) => break,
            }
        }
        replay
    }
}

/// The port's side of a [`Trajectory`], laid out like it: `None` reward for record 0.
pub struct Replay {
    pub observations: Vec<Vec<f64>>,
    pub rewards: Vec<Option<f64>>,
}

/// The 32 recorded episodes (16 tasks covering every element 4 times × seeds 0 and 1).
pub fn trajectories() -> Vec<Trajectory> {
    let data = load("trajectories.json.gz");
    let actions: Vec<[f64; 8]> = rows(&data["meta"]["actions"])
        .into_iter()
        .map(|a| a.try_into().expect("8 action values"))
        .collect();
    data["episodes"]
        .as_array()
        .expect("episodes")
        .iter()
        .map(|e| Trajectory {
            task: task(e),
            seed: e["seed"].as_u64().expect("seed"),
            actions: actions.clone(),
            stage_names: e["stage_names"]
                .as_array()
                .expect("stage names")
                .iter()
                .map(|s| s.as_str().expect("a name").to_string())
                .collect(),
            observations: rows(&e["obs"]),
            rewards: e["reward"]
                .as_array()
                .expect("rewards")
                .iter()
                .map(Value::as_f64)
                .collect(),
            staged: rows(&e["staged"]),
            success: bools(&e["success"]),
            grasp: bools(&e["grasp"]),
            object_position: rows(&e["object_pos"]),
            grip_site_position: rows(&e["grip_site_pos"]),
            hand_z: rows(&e["hand_z"]),
        })
        .collect()
}

fn bools(v: &Value) -> Vec<bool> {
    v.as_array()
        .expect("a list of booleans")
        .iter()
        .map(|b| b.as_bool().expect("a boolean"))
        .collect()
}

/// Joint angles from an observation's cosines and sines.
pub fn joint_angles(observation: &[f64]) -> Vec<f64> {
    layout::JOINT_COS
        .zip(layout::JOINT_SIN)
        .map(|(c, s)| observation[s].atan2(observation[c]))
        .collect()
}

/// How far apart two runs are at one record: mean |Δ| over the joints (rad, wrapped), and the
/// distance between the grip sites and between the objects (m).
#[derive(Debug, Clone, Copy, Default)]
pub struct Divergence {
    pub joints: f64,
    pub eef: f64,
    pub object: f64,
}

pub fn divergence(ours: &[f64], reference: &[f64]) -> Divergence {
    let (a, b) = (joint_angles(ours), joint_angles(reference));
    let joints = a
        .iter()
        .zip(&b)
        .map(|(x, y)| {
            let d = (x - y).rem_euclid(std::f64::consts::TAU);
            d.min(std::f64::consts::TAU - d)
        })
        .sum::<f64>()
        / a.len() as f64;
    let distance = |range: std::ops::Range<usize>| {
        range
            .map(|i| (ours[i] - reference[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    Divergence {
        joints,
        eef: distance(layout::EEF_POSITION),
        object: distance(layout::OBJECT_POSITION),
    }
}

/// One random-policy episode of the reference (`random_returns.json`).
pub struct RandomEpisode {
    /// `np.random.seed(seed)` before the reset; the actions come from `default_rng(1000 + seed)`.
    pub seed: u32,
    pub episode_return: f64,
    /// Some step's reward was 1.
    pub success: bool,
    pub length: u32,
    /// The episode's first action at full precision (checks [`numpy_random`]).
    pub first_action: [f64; 8],
}

impl RandomEpisode {
    /// The seed of the episode's action stream.
    pub fn action_seed(&self) -> u32 {
        1000 + self.seed
    }
}

/// The random-policy episodes of one task.
pub struct RandomTask {
    pub task: TaskSpec,
    pub episodes: Vec<RandomEpisode>,
}

/// The reference's random-policy episodes: 16 tasks × 10 episodes of up to 500 steps.
pub fn random_returns() -> Vec<RandomTask> {
    let data = load("random_returns.json");
    data["tasks"]
        .as_array()
        .expect("tasks")
        .iter()
        .map(|t| RandomTask {
            task: task(t),
            episodes: t["episodes"]
                .as_array()
                .expect("episodes")
                .iter()
                .map(|e| RandomEpisode {
                    seed: e["episode"].as_u64().expect("episode") as u32,
                    episode_return: e["return"].as_f64().expect("return"),
                    success: e["success_reward"].as_bool().expect("success_reward"),
                    length: e["length"].as_u64().expect("length") as u32,
                    first_action: floats(&e["first_action"])
                        .try_into()
                        .expect("8 action values"),
                })
                .collect(),
        })
        .collect()
}

/// The port's run of a random-policy episode: (return, success, length).
pub fn random_episode(task: TaskSpec, episode: &RandomEpisode) -> (f64, bool, u32) {
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(episode.seed as u64).expect("reset");
    let mut rng = numpy_random::DefaultRng::new(episode.action_seed());
    while env.ended().is_none() {
        env.step(&Action::Reference(rng.action())).expect("step");
    }
    (env.episode_return(), env.success_seen(), env.steps())
}

/// One recorded spin (`spin.json`): an object resting on bin 1's floor turned by a torque about
/// world z for `torque_steps` control steps, then left alone for `after_steps`.
pub struct Spin {
    pub task: TaskSpec,
    pub seed: u64,
    /// N·m about world z, at the object's centre of mass.
    pub torque: f64,
    /// Zero-action control steps before the torque.
    pub settle_steps: usize,
    /// Control steps with the torque on.
    pub torque_steps: usize,
    /// The object's yaw (rad, unwrapped) after each step with and after the torque, relative to
    /// its yaw before it.
    pub yaw: Vec<f64>,
    /// The height of the object's origin after the last step (m): it stays on the floor unless
    /// the spin threw it out.
    pub z_end: f64,
}

impl Spin {
    /// The yaw after the torque's last step.
    pub fn turned(yaw: &[f64], torque_steps: usize) -> f64 {
        yaw[torque_steps - 1]
    }

    /// The port's run of the same rig: its yaw per step and final height, as recorded for the
    /// reference.
    pub fn ours(&self) -> (Vec<f64>, f64) {
        let mut env = Env::new(self.task, EnvConfig::default());
        env.reset(self.seed).expect("reset");
        let zero = Action::Reference([0.0; 8]);
        for _ in 0..self.settle_steps {
            env.step(&zero).expect("step");
        }
        let yaw_now = |env: &Env| {
            let r = env.world().object_pose().expect("object").rotation;
            let x = r * Vector3::x();
            x.y.atan2(x.x)
        };
        let mut previous = yaw_now(&env);
        let mut turned = 0.0;
        let mut yaws = Vec::with_capacity(self.yaw.len());
        for k in 0..self.yaw.len() {
            let torque = if k < self.torque_steps {
                self.torque
            } else {
                0.0
            };
            env.set_object_torque(Vector3::new(0.0, 0.0, torque));
            env.step(&zero).expect("step");
            let now = yaw_now(&env);
            let pi = std::f64::consts::PI;
            turned += (now - previous + pi).rem_euclid(2.0 * pi) - pi;
            previous = now;
            yaws.push(turned);
        }
        let z_end = env.world().object_pose().expect("object").translation.z;
        (yaws, z_end)
    }
}

/// Every recorded spin.
pub fn spins() -> Vec<Spin> {
    let data = load("spin.json");
    let meta = &data["meta"];
    let count = |key: &str| meta[key].as_u64().expect("step count") as usize;
    let (settle_steps, torque_steps) = (count("settle_steps"), count("torque_steps"));
    data["records"]
        .as_array()
        .expect("records")
        .iter()
        .map(|r| Spin {
            task: task(r),
            seed: r["seed"].as_u64().expect("seed"),
            torque: r["torque"].as_f64().expect("torque"),
            settle_steps,
            torque_steps,
            yaw: floats(&r["yaw"]),
            z_end: r["z_end"].as_f64().expect("z_end"),
        })
        .collect()
}

/// A scripted, contact-rich episode played in both engines (`grasp_plans.json.gz`, the port's
/// scripted expert's joint targets and gripper commands for one task and seed; `grasp.json.gz`,
/// the reference's run of it). Both sides turn the plan into the reference's own actions with
/// the same closed-loop law ([`tracking_action`]), each from its own observation, so the arms
/// follow the same path while grasp, carry and release play out in each engine's contacts.
pub struct GraspPlan {
    pub task: TaskSpec,
    pub seed: u64,
    /// Joint targets (rad) per plan step, each held for `hold` control steps.
    pub targets: Vec<[f64; 7]>,
    /// The gripper action per plan step: +1 close, −1 open.
    pub gripper: Vec<f64>,
    pub hold: usize,
}

/// The reference action that moves each joint towards its target: the wrapped difference over
/// the controller's 0.05 rad per unit of action, clipped to [−1, 1] (so the goal q + 0.05·a is
/// the target itself once within 0.05 rad), and the plan's gripper action.
pub fn tracking_action(targets: &[f64; 7], gripper: f64, observation: &[f64]) -> [f64; 8] {
    let pi = std::f64::consts::PI;
    let q = joint_angles(observation);
    let mut action = [0.0; 8];
    for j in 0..7 {
        let error = (targets[j] - q[j] + pi).rem_euclid(2.0 * pi) - pi;
        action[j] = (error / 0.05).clamp(-1.0, 1.0);
    }
    action[7] = gripper;
    action
}

/// One engine's run of a [`GraspPlan`], sampled after the last control step of each plan step.
#[derive(Debug, Clone, Default)]
pub struct GraspRun {
    pub object_position: Vec<[f64; 3]>,
    pub grip_site_position: Vec<[f64; 3]>,
    pub grasp: Vec<bool>,
    pub reward: Vec<f64>,
    /// The first control step (1-based) whose success test held, if any.
    pub first_success: Option<usize>,
}

impl GraspRun {
    /// The share of samples with the grasp flag set.
    pub fn grasp_share(&self) -> f64 {
        self.grasp.iter().filter(|g| **g).count() as f64 / self.grasp.len().max(1) as f64
    }

    /// Samples both runs have, and at how many of them the grasp flags are equal.
    pub fn grasp_flags_equal(&self, other: &GraspRun) -> (usize, usize) {
        let n = self.grasp.len().min(other.grasp.len());
        let equal = (0..n).filter(|&i| self.grasp[i] == other.grasp[i]).count();
        (n, equal)
    }

    /// The distance (m) between the two runs' objects at each sample both have, sorted.
    pub fn sorted_object_gaps(&self, other: &GraspRun) -> Vec<f64> {
        let mut gaps: Vec<f64> = self
            .object_position
            .iter()
            .zip(&other.object_position)
            .map(|(a, b)| (point(a) - point(b)).norm())
            .collect();
        gaps.sort_by(f64::total_cmp);
        gaps
    }
}

impl GraspPlan {
    /// The port's run of the plan, recorded as the reference's was.
    pub fn ours(&self) -> GraspRun {
        let horizon = (self.targets.len() * self.hold) as u32;
        let mut env = Env::new(self.task, EnvConfig::default().horizon(horizon));
        let mut observation = env.reset(self.seed).expect("reset").flat();
        let mut run = GraspRun::default();
        let mut step = 0;
        'plan: for (targets, gripper) in self.targets.iter().zip(&self.gripper) {
            for _ in 0..self.hold {
                let action = tracking_action(targets, *gripper, &observation);
                let Ok(result) = env.step(&Action::Reference(action)) else {
                    break 'plan; // Push's lift rule ended the episode, as in the reference
                };
                step += 1;
                observation = result.observation.flat();
                if result.info.success && run.first_success.is_none() {
                    run.first_success = Some(step);
                }
                if step % self.hold == 0 {
                    let state = env.world_state();
                    let p = |v: &[f64]| [v[0], v[1], v[2]];
                    run.object_position
                        .push(p(&observation[layout::OBJECT_POSITION]));
                    run.grip_site_position
                        .push(p(&observation[layout::EEF_POSITION]));
                    run.grasp.push(state.grasping);
                    run.reward.push(result.reward);
                }
                if result.terminated {
                    break 'plan;
                }
            }
        }
        run
    }
}

/// The committed plans.
pub fn grasp_plans() -> Vec<GraspPlan> {
    let data = load("grasp_plans.json.gz");
    let hold = data["meta"]["hold"].as_u64().expect("hold") as usize;
    data["episodes"]
        .as_array()
        .expect("episodes")
        .iter()
        .map(|e| GraspPlan {
            task: task(e),
            seed: e["seed"].as_u64().expect("seed"),
            targets: rows(&e["targets"])
                .into_iter()
                .map(|t| t.try_into().expect("7 joint targets"))
                .collect(),
            gripper: floats(&e["gripper"]),
            hold,
        })
        .collect()
}

/// The reference's runs of the committed plans, in the plans' order.
pub fn grasp_runs() -> Vec<(TaskSpec, u64, GraspRun)> {
    let data = load("grasp.json.gz");
    let triples = |v: &Value| -> Vec<[f64; 3]> {
        rows(v)
            .into_iter()
            .map(|p| p.try_into().expect("3 values"))
            .collect()
    };
    data["episodes"]
        .as_array()
        .expect("episodes")
        .iter()
        .map(|e| {
            let run = GraspRun {
                object_position: triples(&e["object_pos"]),
                grip_site_position: triples(&e["grip_site_pos"]),
                grasp: bools(&e["grasp"]),
                reward: floats(&e["reward"]),
                first_success: e["first_success_step"].as_u64().map(|s| s as usize),
            };
            (task(e), e["seed"].as_u64().expect("seed"), run)
        })
        .collect()
}
