//! Who chooses a dataset episode's actions: always the reference's 8 numbers, as `f32` (what a
//! file stores), so a stored episode replays exactly.

use crate::TaskSpec;
use crate::env::Env;
use crate::expert::PlannedExpert;
use crate::rng::Mt19937;

use super::rows::ACTION_SIZE;

/// Chooses each step's action from the environment as an agent sees it.
pub trait ActionSource {
    /// The action of the step `env` is about to take.
    fn action(&mut self, env: &Env) -> [f32; ACTION_SIZE];
}

/// The policies a dataset can be generated with inside the core (no per-step Python).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DatasetPolicy {
    /// Every value uniform in [−1, 1]: the offline benchmark's `random` type.
    Random,
    /// The planned expert, which acts in the reference's action space; with `noise` > 0 each of
    /// its 7 joint values gets Gaussian noise of that standard deviation (in action units, then
    /// clipped to [−1, 1]): the `expert` type without noise, the `medium` type with the noise
    /// calibrated per task to a success rate.
    Expert {
        /// Standard deviation of the noise on each joint value (0: none).
        noise: f64,
    },
}

impl DatasetPolicy {
    /// Every policy, in the order `--help` lists them (the expert without noise).
    pub const ALL: [DatasetPolicy; 2] = [DatasetPolicy::Random, DatasetPolicy::EXPERT];

    /// The expert without noise.
    pub const EXPERT: DatasetPolicy = DatasetPolicy::Expert { noise: 0.0 };

    /// The name `parse` takes.
    pub fn name(self) -> &'static str {
        match self {
            DatasetPolicy::Random => "random",
            DatasetPolicy::Expert { .. } => "expert",
        }
    }

    /// The policy called `name`, with `noise` on its actions (only the expert takes noise).
    pub fn parse(name: &str, noise: f64) -> Result<DatasetPolicy, String> {
        let policy = DatasetPolicy::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| {
                let valid: Vec<_> = DatasetPolicy::ALL.iter().map(|p| p.name()).collect();
                format!("policy {name:?} is unknown; valid: {}", valid.join(", "))
            })?;
        match policy {
            _ if !(noise.is_finite() && noise >= 0.0) => Err(format!(
                "noise {noise} is not a standard deviation: it must be 0 or more"
            )),
            DatasetPolicy::Expert { .. } => Ok(DatasetPolicy::Expert { noise }),
            DatasetPolicy::Random if noise > 0.0 => Err(format!(
                "the random policy takes no noise (got {noise}); only the expert does"
            )),
            DatasetPolicy::Random => Ok(policy),
        }
    }

    /// This policy's actions for the episode of `task` that starts with `seed`. The episode's
    /// draws depend on the task and the seed only, so an episode is the same whichever thread
    /// plays it and whatever was played before.
    pub fn source(self, task: TaskSpec, seed: u64) -> Box<dyn ActionSource + Send> {
        match self {
            DatasetPolicy::Random => Box::new(RandomActions::new(task, seed)),
            DatasetPolicy::Expert { noise } => Box::new(ExpertActions::new(task, seed, noise)),
        }
    }
}

/// A Mersenne Twister keyed by one of the policies' streams, the task and an episode's seed.
fn episode_rng(stream: u32, task: TaskSpec, seed: u64) -> Mt19937 {
    let key = [
        stream,
        task.task_index() as u32,
        seed as u32,
        (seed >> 32) as u32,
    ];
    Mt19937::init_by_array(&key)
}

/// Uniform actions in [−1, 1] from a Mersenne Twister keyed by the task and the episode's seed.
pub struct RandomActions {
    rng: Mt19937,
}

/// Tells the random policy's key apart from keys other draws of the same task and seed use.
const RANDOM_STREAM: u32 = 0x7261_6e64; // "rand"

impl RandomActions {
    /// The draws of `task`'s episode with `seed`.
    pub fn new(task: TaskSpec, seed: u64) -> RandomActions {
        RandomActions {
            rng: episode_rng(RANDOM_STREAM, task, seed),
        }
    }
}

impl ActionSource for RandomActions {
    fn action(&mut self, _env: &Env) -> [f32; ACTION_SIZE] {
        // The nearest f32 of a double in [−1, 1) stays in [−1, 1].
        std::array::from_fn(|_| self.rng.uniform(-1.0, 1.0) as f32)
    }
}

/// The planned expert's actions, rounded to `f32`, with optional Gaussian noise on the joint
/// values drawn from a Mersenne Twister keyed by the task and the episode's seed. The expert
/// chooses from what the environment shows, so it steers back from the noise as from any
/// disturbance; its gripper value is left as it is (the gripper's level is what the expert
/// counts its own commands by).
pub struct ExpertActions {
    expert: PlannedExpert,
    noise: f64,
    rng: Mt19937,
}

/// Tells the expert's noise key apart from the random policy's.
const NOISE_STREAM: u32 = 0x6e6f_6973; // "nois"

impl ExpertActions {
    /// The expert of `task`'s episode with `seed`, `noise` the standard deviation on each joint
    /// value (0: none).
    pub fn new(task: TaskSpec, seed: u64, noise: f64) -> ExpertActions {
        ExpertActions {
            expert: PlannedExpert::new(task),
            noise,
            rng: episode_rng(NOISE_STREAM, task, seed),
        }
    }
}

impl ActionSource for ExpertActions {
    fn action(&mut self, env: &Env) -> [f32; ACTION_SIZE] {
        let mut action = self.expert.reference_action(env);
        if self.noise > 0.0 {
            for value in &mut action[..ACTION_SIZE - 1] {
                *value = (*value + self.noise * self.rng.standard_normal()).clamp(-1.0, 1.0);
            }
        }
        // The nearest f32 of a value in [−1, 1] stays in [−1, 1].
        action.map(|v| v as f32)
    }
}

/// Actions read back from a stored episode, `ACTION_SIZE` values a row.
pub struct StoredActions<'a> {
    rows: std::slice::ChunksExact<'a, f32>,
}

impl<'a> StoredActions<'a> {
    /// The rows of `actions` in order.
    ///
    /// # Panics
    /// If `actions` is not whole rows.
    pub fn new(actions: &'a [f32]) -> StoredActions<'a> {
        assert_eq!(actions.len() % ACTION_SIZE, 0, "actions come in rows of 8");
        StoredActions {
            rows: actions.chunks_exact(ACTION_SIZE),
        }
    }

    /// Rows not yet taken.
    pub fn remaining(&self) -> usize {
        self.rows.len()
    }
}

impl ActionSource for StoredActions<'_> {
    /// # Panics
    /// When every stored row has been taken (the player stops at the stored length).
    fn action(&mut self, _env: &Env) -> [f32; ACTION_SIZE] {
        let row = self.rows.next().expect("no stored action left");
        std::array::from_fn(|i| row[i])
    }
}
