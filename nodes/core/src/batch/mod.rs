//! A batch of environments stepped together on a thread pool: the piece the Python vector env
//! and the composed node suite both step their environments with.
//!
//! Each environment owns its state and writes only its own row of the outputs, so a batch's
//! results do not depend on how many threads step it or which thread took which environment:
//! one thread and eight give the same bits.
//!
//! ```
//! use composuite_core::batch::{BatchCommand, BatchResults, EnvBatch};
//! use composuite_core::env::{Action, EnvConfig};
//! let tasks = ["IIWA/box/no_obstacle/pick_place".parse().unwrap(),
//!              "Jaco/plate/object_wall/shelf".parse().unwrap()];
//! let mut batch = EnvBatch::new(&tasks, EnvConfig::default(), 2).unwrap();
//! let mut out = BatchResults::new(&batch);
//! batch.run(&[BatchCommand::Reset(0), BatchCommand::Reset(1)], &mut out.view()).unwrap();
//! let step = BatchCommand::Step(Action::Reference([0.0; 8]));
//! batch.run(&[step, step], &mut out.view()).unwrap();
//! assert_eq!(out.steps, [1, 1]);
//! ```

use std::fmt;

use crate::TaskSpec;
use crate::env::{Action, Env, EnvConfig, EnvError};
use crate::obs::{FLAT_SIZE_WITH_TASK, Observation, flat_size};
use crate::rng::Mt19937;

mod pool;
#[cfg(test)]
mod test;

pub use pool::StepPool;

/// Rows of stage values are this wide (the most stages any objective has), padded with 0.
pub use crate::reward::MAX_STAGES;

/// What one environment does in a [`EnvBatch::run`] call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BatchCommand {
    /// Advance one control period with this action.
    Step(Action),
    /// Start an episode with this seed (the reference's `np.random.seed(seed)` episode).
    Reset(u64),
    /// Leave the environment as it is; its output row is not written.
    Idle,
}

/// Why a batch call was refused; nothing was stepped when one is returned.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchError {
    /// The environment whose command was refused.
    pub index: usize,
    /// Why.
    pub error: EnvError,
}

impl fmt::Display for BatchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "environment {}: {}", self.index, self.error)
    }
}

impl std::error::Error for BatchError {}

/// Why a batch could not be built.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BatchBuildError {
    /// No tasks given.
    Empty,
    /// Zero threads asked for.
    NoThreads,
    /// The thread pool could not start.
    ThreadPool(String),
}

impl fmt::Display for BatchBuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BatchBuildError::Empty => write!(f, "a batch needs at least one task"),
            BatchBuildError::NoThreads => write!(f, "threads must be at least 1"),
            BatchBuildError::ThreadPool(e) => write!(f, "could not start the thread pool: {e}"),
        }
    }
}

impl std::error::Error for BatchBuildError {}

/// Where a batch call writes its results: one row per environment, in the caller's buffers
/// (numpy arrays for the Python faces). Rows of [`BatchCommand::Idle`] environments keep what
/// they held.
pub struct BatchOutput<'a> {
    /// `n × observation_size` flat observations.
    pub observations: &'a mut [f64],
    /// Rewards (0 on a reset row).
    pub rewards: &'a mut [f64],
    /// The objective ended the episode.
    pub terminated: &'a mut [bool],
    /// The horizon ended the episode.
    pub truncated: &'a mut [bool],
    /// The step's success test held.
    pub success: &'a mut [bool],
    /// `n × MAX_STAGES` stage values in the objective's order, padded with 0.
    pub stage_values: &'a mut [f64],
    /// Index of the current stage, −1 when every stage is 0 (as `StagedReward.current_stage`).
    pub current_stage: &'a mut [i8],
    /// Control steps taken in the episode (0 after a reset).
    pub steps: &'a mut [u32],
}

/// Buffers owned by Rust for a [`BatchOutput`] (tests, benchmarks, the node container).
#[derive(Debug, Clone, PartialEq)]
pub struct BatchResults {
    /// See [`BatchOutput::observations`].
    pub observations: Vec<f64>,
    /// See [`BatchOutput::rewards`].
    pub rewards: Vec<f64>,
    /// See [`BatchOutput::terminated`].
    pub terminated: Vec<bool>,
    /// See [`BatchOutput::truncated`].
    pub truncated: Vec<bool>,
    /// See [`BatchOutput::success`].
    pub success: Vec<bool>,
    /// See [`BatchOutput::stage_values`].
    pub stage_values: Vec<f64>,
    /// See [`BatchOutput::current_stage`].
    pub current_stage: Vec<i8>,
    /// See [`BatchOutput::steps`].
    pub steps: Vec<u32>,
}

impl BatchResults {
    /// Zeroed buffers sized for `batch`.
    pub fn new(batch: &EnvBatch) -> BatchResults {
        let n = batch.len();
        BatchResults {
            observations: vec![0.0; n * batch.observation_size()],
            rewards: vec![0.0; n],
            terminated: vec![false; n],
            truncated: vec![false; n],
            success: vec![false; n],
            stage_values: vec![0.0; n * MAX_STAGES],
            current_stage: vec![-1; n],
            steps: vec![0; n],
        }
    }

    /// The buffers as a [`BatchOutput`].
    pub fn view(&mut self) -> BatchOutput<'_> {
        BatchOutput {
            observations: &mut self.observations,
            rewards: &mut self.rewards,
            terminated: &mut self.terminated,
            truncated: &mut self.truncated,
            success: &mut self.success,
            stage_values: &mut self.stage_values,
            current_stage: &mut self.current_stage,
            steps: &mut self.steps,
        }
    }
}

/// One environment's result, filled by whichever thread stepped it.
#[derive(Debug, Clone, Copy)]
struct Row {
    observation: [f64; FLAT_SIZE_WITH_TASK],
    reward: f64,
    terminated: bool,
    truncated: bool,
    success: bool,
    stage_values: [f64; MAX_STAGES],
    current_stage: i8,
    steps: u32,
}

impl Default for Row {
    fn default() -> Self {
        Row {
            observation: [0.0; FLAT_SIZE_WITH_TASK],
            reward: 0.0,
            terminated: false,
            truncated: false,
            success: false,
            stage_values: [0.0; MAX_STAGES],
            current_stage: -1,
            steps: 0,
        }
    }
}

impl Row {
    /// The row of a reset: its observation, nothing earned, no stage reached, step 0.
    fn after_reset(observation: &Observation) -> Row {
        let mut row = Row::default();
        write_observation(&mut row.observation, &observation.flat());
        row
    }
}

/// Environments (each its own task) and the thread pool that steps them.
pub struct EnvBatch {
    envs: Vec<Env>,
    pool: StepPool,
    /// Scratch, one per environment, reused every call.
    rows: Vec<Row>,
    observation_size: usize,
}

impl EnvBatch {
    /// One environment per task (tasks may repeat and differ), all with `config`, stepped by
    /// `threads` threads. Call [`EnvBatch::run`] with a reset for each before stepping it.
    pub fn new(
        tasks: &[TaskSpec],
        config: EnvConfig,
        threads: usize,
    ) -> Result<EnvBatch, BatchBuildError> {
        if tasks.is_empty() {
            return Err(BatchBuildError::Empty);
        }
        if threads == 0 {
            return Err(BatchBuildError::NoThreads);
        }
        // The caller steps environments too: it is one of the threads.
        let pool = StepPool::new(threads - 1)?;
        let mut built: Vec<Option<Env>> = tasks.iter().map(|_| None).collect();
        pool.for_each(&mut built, |index, env| {
            *env = Some(Env::new(tasks[index], config.clone()));
        });
        let envs: Vec<Env> = built.into_iter().flatten().collect();
        let observation_size = flat_size(config.task_observation);
        Ok(EnvBatch {
            rows: vec![Row::default(); envs.len()],
            envs,
            pool,
            observation_size,
        })
    }

    /// Number of environments.
    pub fn len(&self) -> usize {
        self.envs.len()
    }

    /// Whether the batch has no environments (never: [`EnvBatch::new`] refuses that).
    pub fn is_empty(&self) -> bool {
        self.envs.is_empty()
    }

    /// Threads stepping the batch.
    pub fn threads(&self) -> usize {
        self.pool.workers() + 1
    }

    /// Values in one flat observation (93 with the task one-hots, 77 without).
    pub fn observation_size(&self) -> usize {
        self.observation_size
    }

    /// Environment `index` (read only; commands go through [`EnvBatch::run`]).
    pub fn env(&self, index: usize) -> &Env {
        &self.envs[index]
    }

    /// A picture of environment `index` as it is now ([`Env::render`]; rendering changes no
    /// state, so the batch's rows stay as they are).
    pub fn render(
        &mut self,
        index: usize,
        camera: &str,
        width: u32,
        height: u32,
    ) -> Result<crate::render::Frame, crate::render::RenderError> {
        self.envs[index].render(camera, width, height)
    }

    /// Every environment, in order.
    pub fn envs(&self) -> &[Env] {
        &self.envs
    }

    /// Give environment `index` another task (a fresh environment: reset it before stepping).
    pub fn set_task(&mut self, index: usize, task: TaskSpec) {
        let config = self.envs[index].config().clone();
        self.envs[index] = Env::new(task, config);
    }

    /// Reset environment `index` alone, with the reference's draws taken from `rng` as it
    /// stands ([`Env::reset_from`]), and write its row of `out`.
    pub fn reset_from(
        &mut self,
        index: usize,
        rng: &mut Mt19937,
        out: &mut BatchOutput<'_>,
    ) -> Result<(), BatchError> {
        self.check_output(out);
        let observation = self.envs[index]
            .reset_from(rng)
            .map_err(|error| BatchError { index, error })?;
        self.rows[index] = Row::after_reset(&observation);
        self.write_rows(&[index], out);
        Ok(())
    }

    /// Carry out one command per environment, in parallel, and write each environment's row of
    /// `out`. Every command is checked first: if one would be refused, nothing is stepped and
    /// the error names the environment.
    ///
    /// # Panics
    /// If `commands` or a buffer of `out` does not have one row per environment.
    pub fn run(
        &mut self,
        commands: &[BatchCommand],
        out: &mut BatchOutput<'_>,
    ) -> Result<(), BatchError> {
        let n = self.envs.len();
        assert_eq!(commands.len(), n, "one command per environment");
        self.check_output(out);
        for (index, (env, command)) in self.envs.iter().zip(commands).enumerate() {
            precheck(env, command).map_err(|error| BatchError { index, error })?;
        }
        let mut slots: Vec<Slot<'_>> = self
            .envs
            .iter_mut()
            .zip(self.rows.iter_mut())
            .map(|(env, row)| (env, row, Ok(())))
            .collect();
        self.pool.for_each(&mut slots, |index, (env, row, result)| {
            *result = carry_out(env, &commands[index], row);
        });
        let results: Vec<Result<(), EnvError>> =
            slots.into_iter().map(|(_, _, result)| result).collect();
        let written: Vec<usize> = (0..n)
            .filter(|&i| !matches!(commands[i], BatchCommand::Idle))
            .collect();
        self.write_rows(&written, out);
        // The prechecks cover every refusal `Env` can make, so this is a safety net: the
        // error still names the environment rather than being lost.
        match results.into_iter().enumerate().find(|(_, r)| r.is_err()) {
            Some((index, Err(error))) => Err(BatchError { index, error }),
            _ => Ok(()),
        }
    }

    fn write_rows(&self, indices: &[usize], out: &mut BatchOutput<'_>) {
        let size = self.observation_size;
        for &index in indices {
            let row = &self.rows[index];
            out.observations[index * size..(index + 1) * size]
                .copy_from_slice(&row.observation[..size]);
            out.rewards[index] = row.reward;
            out.terminated[index] = row.terminated;
            out.truncated[index] = row.truncated;
            out.success[index] = row.success;
            out.stage_values[index * MAX_STAGES..(index + 1) * MAX_STAGES]
                .copy_from_slice(&row.stage_values);
            out.current_stage[index] = row.current_stage;
            out.steps[index] = row.steps;
        }
    }

    fn check_output(&self, out: &BatchOutput<'_>) {
        let n = self.envs.len();
        assert_eq!(
            out.observations.len(),
            n * self.observation_size,
            "observations"
        );
        assert_eq!(out.rewards.len(), n, "rewards");
        assert_eq!(out.terminated.len(), n, "terminated");
        assert_eq!(out.truncated.len(), n, "truncated");
        assert_eq!(out.success.len(), n, "success");
        assert_eq!(out.stage_values.len(), n * MAX_STAGES, "stage_values");
        assert_eq!(out.current_stage.len(), n, "current_stage");
        assert_eq!(out.steps.len(), n, "steps");
    }
}

/// One environment's share of a parallel call: the environment, its row, how its command went.
type Slot<'a> = (&'a mut Env, &'a mut Row, Result<(), EnvError>);

/// Whether `env` would refuse `command`: the same tests `Env` makes, made before any
/// environment moves so a refused batch leaves every environment as it was.
fn precheck(env: &Env, command: &BatchCommand) -> Result<(), EnvError> {
    match command {
        BatchCommand::Idle => Ok(()),
        BatchCommand::Reset(seed) => {
            crate::env::sample_object_start(env.task().obstacle, env.task().object, *seed)
                .map(|_| ())
        }
        BatchCommand::Step(action) => env.check_step(action),
    }
}

fn carry_out(env: &mut Env, command: &BatchCommand, row: &mut Row) -> Result<(), EnvError> {
    match command {
        BatchCommand::Idle => Ok(()),
        BatchCommand::Reset(seed) => {
            *row = Row::after_reset(&env.reset(*seed)?);
            Ok(())
        }
        BatchCommand::Step(action) => {
            let step = env.step(action)?;
            write_observation(&mut row.observation, &step.observation.flat());
            row.reward = step.reward;
            row.terminated = step.terminated;
            row.truncated = step.truncated;
            row.success = step.info.success;
            row.stage_values = [0.0; MAX_STAGES];
            for (slot, stage) in row.stage_values.iter_mut().zip(&step.info.staged.stages) {
                *slot = stage.value;
            }
            row.current_stage = step.info.staged.current_stage().map_or(-1, |i| i as i8);
            row.steps = env.steps();
            Ok(())
        }
    }
}

fn write_observation(slot: &mut [f64; FLAT_SIZE_WITH_TASK], flat: &[f64]) {
    slot[..flat.len()].copy_from_slice(flat);
}
