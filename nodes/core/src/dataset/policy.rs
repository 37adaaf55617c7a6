//! Who chooses a dataset episode's actions: always the reference's 8 numbers, as `f32` (what a
//! file stores), so a stored episode replays exactly.

use crate::TaskSpec;
use crate::env::Env;
use crate::rng::Mt19937;

use super::rows::ACTION_SIZE;

/// Chooses each step's action from the environment as an agent sees it.
pub trait ActionSource {
    /// The action of the step `env` is about to take.
    fn action(&mut self, env: &Env) -> [f32; ACTION_SIZE];
}

/// The policies a dataset can be generated with inside the core (no per-step Python).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DatasetPolicy {
    /// Every value uniform in [−1, 1]: the offline benchmark's `random` type.
    Random,
}

impl DatasetPolicy {
    /// Every policy, in the order `--help` lists them.
    pub const ALL: [DatasetPolicy; 1] = [DatasetPolicy::Random];

    /// The name `parse` takes.
    pub fn name(self) -> &'static str {
        match self {
            DatasetPolicy::Random => "random",
        }
    }

    /// The policy called `name`.
    pub fn parse(name: &str) -> Result<DatasetPolicy, String> {
        DatasetPolicy::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| {
                let valid: Vec<_> = DatasetPolicy::ALL.iter().map(|p| p.name()).collect();
                format!("policy {name:?} is unknown; valid: {}", valid.join(", "))
            })
    }

    /// This policy's actions for the episode of `task` that starts with `seed`. The episode's
    /// draws depend on the task and the seed only, so an episode is the same whichever thread
    /// plays it and whatever was played before.
    pub fn source(self, task: TaskSpec, seed: u64) -> Box<dyn ActionSource + Send> {
        match self {
            DatasetPolicy::Random => Box::new(RandomActions::new(task, seed)),
        }
    }
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
        let key = [
            RANDOM_STREAM,
            task.task_index() as u32,
            seed as u32,
            (seed >> 32) as u32,
        ];
        RandomActions {
            rng: Mt19937::init_by_array(&key),
        }
    }
}

impl ActionSource for RandomActions {
    fn action(&mut self, _env: &Env) -> [f32; ACTION_SIZE] {
        // The nearest f32 of a double in [−1, 1) stays in [−1, 1].
        std::array::from_fn(|_| self.rng.uniform(-1.0, 1.0) as f32)
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
