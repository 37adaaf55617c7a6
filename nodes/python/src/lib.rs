//! `composuite_ros._native`: the in-process face of `composuite_core` for Python.
//!
//! One class, `Batch`: a `composuite_core::batch::EnvBatch` with its inputs and outputs as
//! numpy arrays it owns. Python writes the commands into `modes`, `seeds` and `actions`, calls
//! `run()` (one call, the GIL released while the environments step on the batch's threads),
//! and reads the rows back. The Gymnasium envs of `composuite_ros.native` are built on it; this
//! crate converts and releases the GIL, and decides nothing about environments. `StateRenderer`
//! (`render.rs`) draws a scene from an observation alone, for the env over ROS. `Collector` and
//! `replay` (`dataset.rs`) play and replay offline datasets' episodes inside the core, for
//! `composuite_ros.datasets`.

mod dataset;
mod render;
mod task;

use composuite_core::TaskSpec;
use composuite_core::axes::AxisElement;
use composuite_core::batch::{BatchCommand, BatchError, BatchOutput, EnvBatch, MAX_STAGES};
use composuite_core::env::{Action, EnvError};
use composuite_core::physics::{ARM_DOF, pad_gap};
use composuite_core::rng::{MT_STATE_WORDS, Mt19937};
use numpy::prelude::*;
use numpy::{PyArray1, PyArray2, PyArray3, PyReadonlyArray1};
use pyo3::exceptions::{PyIndexError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use task::{env_config, parse_task};

/// `modes[i]`: environment i is left as it is.
const MODE_IDLE: u8 = 0;
/// `modes[i]`: environment i steps with `actions[i]`.
const MODE_STEP: u8 = 1;
/// `modes[i]`: environment i starts an episode with `seeds[i]`.
const MODE_RESET: u8 = 2;

/// Values in one action row: 7 arm joints, then the gripper.
const ACTION_SIZE: usize = ARM_DOF + 1;

/// How an action row is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ActionMode {
    /// The reference's 8 normalised values in [-1, 1].
    Reference,
    /// 7 absolute joint targets (rad), then the left finger joint's target (m).
    Absolute,
}

/// Environments stepped together, with their buffers (see the module docs).
#[pyclass(module = "composuite_ros._native")]
struct Batch {
    batch: EnvBatch,
    mode: ActionMode,
    commands: Vec<BatchCommand>,
    modes: Py<PyArray1<u8>>,
    seeds: Py<PyArray1<u64>>,
    actions: Py<PyArray2<f64>>,
    out: OutputBuffers,
}

/// The rows a batch writes, as numpy arrays (see `composuite_core::batch::BatchOutput`).
struct OutputBuffers {
    observations: Py<PyArray2<f64>>,
    rewards: Py<PyArray1<f64>>,
    terminated: Py<PyArray1<bool>>,
    truncated: Py<PyArray1<bool>>,
    success: Py<PyArray1<bool>>,
    stage_values: Py<PyArray2<f64>>,
    current_stage: Py<PyArray1<i8>>,
    steps: Py<PyArray1<u32>>,
}

impl OutputBuffers {
    fn new(py: Python<'_>, n: usize, observation_size: usize) -> OutputBuffers {
        OutputBuffers {
            observations: PyArray2::zeros(py, [n, observation_size], false).unbind(),
            rewards: PyArray1::zeros(py, n, false).unbind(),
            terminated: PyArray1::zeros(py, n, false).unbind(),
            truncated: PyArray1::zeros(py, n, false).unbind(),
            success: PyArray1::zeros(py, n, false).unbind(),
            stage_values: PyArray2::zeros(py, [n, MAX_STAGES], false).unbind(),
            current_stage: PyArray1::from_vec(py, vec![-1i8; n]).unbind(),
            steps: PyArray1::zeros(py, n, false).unbind(),
        }
    }

    /// Run `f` on the arrays' memory as a `BatchOutput` (a `TypeError` if Python replaced one
    /// with an array that is not contiguous or writeable).
    fn with<R>(&self, py: Python<'_>, f: impl FnOnce(&mut BatchOutput<'_>) -> R) -> PyResult<R> {
        let mut observations = self.observations.bind(py).readwrite();
        let mut rewards = self.rewards.bind(py).readwrite();
        let mut terminated = self.terminated.bind(py).readwrite();
        let mut truncated = self.truncated.bind(py).readwrite();
        let mut success = self.success.bind(py).readwrite();
        let mut stage_values = self.stage_values.bind(py).readwrite();
        let mut current_stage = self.current_stage.bind(py).readwrite();
        let mut steps = self.steps.bind(py).readwrite();
        let mut out = BatchOutput {
            observations: observations.as_slice_mut()?,
            rewards: rewards.as_slice_mut()?,
            terminated: terminated.as_slice_mut()?,
            truncated: truncated.as_slice_mut()?,
            success: success.as_slice_mut()?,
            stage_values: stage_values.as_slice_mut()?,
            current_stage: current_stage.as_slice_mut()?,
            steps: steps.as_slice_mut()?,
        };
        Ok(f(&mut out))
    }
}

/// A refused command as the Python exception that fits it: bad values are a `ValueError`,
/// stepping an environment that has no running episode a `RuntimeError`.
fn batch_error(err: BatchError) -> PyErr {
    let message = err.to_string();
    match err.error {
        EnvError::NotReset | EnvError::EpisodeOver { .. } | EnvError::NoClearStart { .. } => {
            PyRuntimeError::new_err(message)
        }
        EnvError::BadSeed(_)
        | EnvError::Arm(_)
        | EnvError::Gripper(_)
        | EnvError::BadReferenceAction { .. } => PyValueError::new_err(message),
    }
}

#[pymethods]
impl Batch {
    /// One environment per task (`robot/object/obstacle/objective`, any accepted spelling),
    /// stepped by `threads` threads.
    #[new]
    // Each argument is one of Python's keyword arguments; a struct would only move them.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (tasks, *, threads = 1, horizon = 500, use_task_id_obs = true,
                        reward_shaping = true, reward_scale = 1.0, action_mode = "reference"))]
    fn new(
        py: Python<'_>,
        tasks: Vec<String>,
        threads: usize,
        horizon: u32,
        use_task_id_obs: bool,
        reward_shaping: bool,
        reward_scale: f64,
        action_mode: &str,
    ) -> PyResult<Batch> {
        let mode = match action_mode {
            "reference" => ActionMode::Reference,
            "absolute" => ActionMode::Absolute,
            other => {
                return Err(PyValueError::new_err(format!(
                    "action_mode {other:?} is not one of reference, absolute"
                )));
            }
        };
        let config = env_config(horizon)?;
        if !reward_scale.is_finite() {
            return Err(PyValueError::new_err(format!(
                "reward_scale is {reward_scale}; it must be a finite number"
            )));
        }
        let specs = tasks
            .iter()
            .map(|t| parse_task(t))
            .collect::<PyResult<Vec<_>>>()?;
        let config = config
            .task_observation(use_task_id_obs)
            .reward_shaping(reward_shaping)
            .reward_scale(reward_scale);
        let batch = py
            .detach(|| EnvBatch::new(&specs, config, threads))
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let n = batch.len();
        let size = batch.observation_size();
        Ok(Batch {
            mode,
            commands: vec![BatchCommand::Idle; n],
            modes: PyArray1::zeros(py, n, false).unbind(),
            seeds: PyArray1::zeros(py, n, false).unbind(),
            actions: PyArray2::zeros(py, [n, ACTION_SIZE], false).unbind(),
            out: OutputBuffers::new(py, n, size),
            batch,
        })
    }

    /// Carry out `modes[i]` for every environment i (0 idle, 1 step with `actions[i]`, 2 reset
    /// with `seeds[i]`) and write the rows of the output arrays. Every command is checked
    /// first: a refused one raises (naming the environment) and nothing moves.
    fn run(&mut self, py: Python<'_>) -> PyResult<()> {
        {
            let modes = self.modes.bind(py).readonly();
            let seeds = self.seeds.bind(py).readonly();
            let actions = self.actions.bind(py).readonly();
            let modes = modes.as_slice()?;
            let seeds = seeds.as_slice()?;
            let actions = actions.as_slice()?;
            for (i, command) in self.commands.iter_mut().enumerate() {
                let row = &actions[i * ACTION_SIZE..(i + 1) * ACTION_SIZE];
                *command = match modes[i] {
                    MODE_IDLE => BatchCommand::Idle,
                    MODE_RESET => BatchCommand::Reset(seeds[i]),
                    MODE_STEP => BatchCommand::Step(match self.mode {
                        ActionMode::Reference => Action::Reference(std::array::from_fn(|j| row[j])),
                        ActionMode::Absolute => Action::Absolute {
                            joints: std::array::from_fn(|j| row[j]),
                            gripper: Some((pad_gap(row[ARM_DOF]), 0.0)),
                        },
                    }),
                    other => {
                        return Err(PyValueError::new_err(format!(
                            "modes[{i}] is {other}; valid: {MODE_IDLE} idle, {MODE_STEP} step, \
                             {MODE_RESET} reset"
                        )));
                    }
                };
            }
        }
        let batch = &mut self.batch;
        let commands = &self.commands;
        self.out
            .with(py, |out| py.detach(|| batch.run(commands, out)))?
            .map_err(batch_error)
    }

    /// Reset environment `index` with the reference's draws taken from numpy's legacy global
    /// generator in the state `np.random.get_state()` gave (`key`, `pos`, `has_gauss`,
    /// `cached_gaussian`), and write its rows. Returns the state to put back with
    /// `np.random.set_state(("MT19937", key, pos, has_gauss, cached_gaussian))`: where the
    /// reference's own `reset()` leaves numpy.
    fn reset_numpy_state<'py>(
        &mut self,
        py: Python<'py>,
        index: usize,
        key: PyReadonlyArray1<'py, u32>,
        pos: usize,
        has_gauss: bool,
        cached_gaussian: f64,
    ) -> PyResult<(Bound<'py, PyArray1<u32>>, usize, bool, f64)> {
        self.check_index(index)?;
        let words: [u32; MT_STATE_WORDS] = key.as_slice()?.try_into().map_err(|_| {
            PyValueError::new_err(format!(
                "the MT19937 key has {} words; numpy's has {MT_STATE_WORDS}",
                key.len()
            ))
        })?;
        let mut rng = Mt19937::from_numpy_state(words, pos, has_gauss.then_some(cached_gaussian))
            .ok_or_else(|| {
            PyValueError::new_err(format!(
                "the MT19937 position is {pos}; valid: 0..={MT_STATE_WORDS}"
            ))
        })?;
        let batch = &mut self.batch;
        self.out
            .with(py, |out| batch.reset_from(index, &mut rng, out))?
            .map_err(batch_error)?;
        let (key, pos, gauss) = rng.numpy_state();
        Ok((
            PyArray1::from_slice(py, &key),
            pos,
            gauss.is_some(),
            gauss.unwrap_or(0.0),
        ))
    }

    /// Give environment `index` another task (its episode ends: reset it before stepping).
    /// Returns the task in wire names.
    fn set_task(&mut self, index: usize, task: &str) -> PyResult<String> {
        self.check_index(index)?;
        let spec = parse_task(task)?;
        self.batch.set_task(index, spec);
        Ok(spec.to_string())
    }

    /// The tasks, in wire names (`IIWA/box/no_obstacle/pick_place`).
    fn tasks(&self) -> Vec<String> {
        self.batch
            .envs()
            .iter()
            .map(|e| e.task().to_string())
            .collect()
    }

    /// The stage names of environment `index`'s objective, in the order of `stage_values`.
    fn stage_names(&self, index: usize) -> PyResult<Vec<&'static str>> {
        self.check_index(index)?;
        let objective = self.batch.env(index).task().objective;
        Ok(composuite_core::reward::stage_specs(objective)
            .iter()
            .map(|s| s.name)
            .collect())
    }

    /// `(name, lower, upper)` of environment `index`'s 7 arm joints, then its left finger
    /// joint: the absolute action mode's bounds (rad, m), from the robot's URDF.
    fn joint_limits(&self, index: usize) -> PyResult<Vec<(String, f64, f64)>> {
        self.check_index(index)?;
        let model = self.batch.env(index).world().model;
        Ok(model.joints[..ACTION_SIZE]
            .iter()
            .map(|j| {
                let (lower, upper) = j.limits.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
                (j.name.clone(), lower, upper)
            })
            .collect())
    }

    /// Episode counter of environment `index` (1 for its first episode; 0 before any reset).
    fn episode(&self, index: usize) -> PyResult<u32> {
        self.check_index(index)?;
        Ok(self.batch.env(index).episode())
    }

    /// An RGB picture of environment `index` as it is now, from one of the reference's cameras
    /// (`frontview`, `agentview`, `birdview`, `sideview`, `eye_in_hand`): a `(height, width, 3)`
    /// uint8 array, rows from the top.
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        index: usize,
        camera: &str,
        width: u32,
        height: u32,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        self.check_index(index)?;
        let frame = self
            .batch
            .render(index, camera, width, height)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        PyArray1::from_vec(py, frame.rgb).reshape([height as usize, width as usize, 3])
    }

    /// The robot of environment `index` (wire name).
    fn robot(&self, index: usize) -> PyResult<&'static str> {
        self.check_index(index)?;
        Ok(self.batch.env(index).task().robot.wire_name())
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.batch.len()
    }

    /// Threads stepping the environments.
    #[getter]
    fn threads(&self) -> usize {
        self.batch.threads()
    }

    /// Values in one observation (93 with the task one-hots, 77 without).
    #[getter]
    fn observation_size(&self) -> usize {
        self.batch.observation_size()
    }

    /// Episode length limit (control steps).
    #[getter]
    fn horizon(&self) -> u32 {
        self.batch.env(0).config().horizon
    }

    /// One control step in integer nanoseconds (the sim node's clock advances by this).
    #[getter]
    fn control_period_ns(&self) -> u64 {
        (self.batch.env(0).config().control_period() * 1e9).round() as u64
    }

    /// Input: what each environment does on `run()` (0 idle, 1 step, 2 reset).
    #[getter]
    fn modes(&self, py: Python<'_>) -> Py<PyArray1<u8>> {
        self.modes.clone_ref(py)
    }

    /// Input: the seed of each resetting environment.
    #[getter]
    fn seeds(&self, py: Python<'_>) -> Py<PyArray1<u64>> {
        self.seeds.clone_ref(py)
    }

    /// Input: `num_envs × 8` actions.
    #[getter]
    fn actions(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.actions.clone_ref(py)
    }

    /// Output: `num_envs × observation_size` flat observations.
    #[getter]
    fn observations(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.out.observations.clone_ref(py)
    }

    /// Output: rewards (0 on a reset row).
    #[getter]
    fn rewards(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.out.rewards.clone_ref(py)
    }

    /// Output: the objective ended the episode.
    #[getter]
    fn terminated(&self, py: Python<'_>) -> Py<PyArray1<bool>> {
        self.out.terminated.clone_ref(py)
    }

    /// Output: the horizon ended the episode.
    #[getter]
    fn truncated(&self, py: Python<'_>) -> Py<PyArray1<bool>> {
        self.out.truncated.clone_ref(py)
    }

    /// Output: the step's success test held.
    #[getter]
    fn success(&self, py: Python<'_>) -> Py<PyArray1<bool>> {
        self.out.success.clone_ref(py)
    }

    /// Output: `num_envs × MAX_STAGES` stage values, padded with 0.
    #[getter]
    fn stage_values(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.out.stage_values.clone_ref(py)
    }

    /// Output: index of the current stage, −1 when every stage is 0.
    #[getter]
    fn current_stage(&self, py: Python<'_>) -> Py<PyArray1<i8>> {
        self.out.current_stage.clone_ref(py)
    }

    /// Output: control steps taken in the episode (0 after a reset).
    #[getter]
    fn steps(&self, py: Python<'_>) -> Py<PyArray1<u32>> {
        self.out.steps.clone_ref(py)
    }
}

impl Batch {
    fn check_index(&self, index: usize) -> PyResult<()> {
        if index < self.batch.len() {
            Ok(())
        } else {
            Err(PyIndexError::new_err(format!(
                "environment {index} does not exist; valid: 0..{}",
                self.batch.len() - 1
            )))
        }
    }
}

/// The termination reason's text (the task manager's `reason_text` when an objective ends an
/// episode) and the horizon's, for `horizon` steps.
#[pyfunction]
fn end_reasons(horizon: u32) -> (String, String) {
    (
        composuite_core::reward::Termination::ObjectLifted
            .reason()
            .to_string(),
        composuite_core::reward::horizon_reason(horizon),
    )
}

/// The reference's train/test split (`composuite.sample_tasks`), as the task manager's
/// `sample_tasks` service draws it: `(train, test)` in wire names. `element` "" for none.
#[pyfunction]
#[pyo3(signature = (experiment, num_train, element = "", seed = 0, no_shuffle = false))]
fn sample_tasks(
    experiment: &str,
    num_train: usize,
    element: &str,
    seed: u64,
    no_shuffle: bool,
) -> PyResult<(Vec<String>, Vec<String>)> {
    use composuite_core::sampling::Experiment;
    let experiment: Experiment = experiment
        .parse()
        .map_err(|e: composuite_core::sampling::SplitError| PyValueError::new_err(e.to_string()))?;
    let element = Some(element).filter(|e| !e.is_empty());
    let split =
        composuite_core::sampling::sample_tasks(experiment, num_train, element, seed, no_shuffle)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let names = |tasks: &[TaskSpec]| tasks.iter().map(TaskSpec::to_string).collect();
    Ok((names(&split.train), names(&split.test)))
}

/// The native module.
#[pymodule]
mod _native {
    #[pymodule_export]
    use super::Batch;
    #[pymodule_export]
    use super::dataset::Collector;
    #[pymodule_export]
    use super::dataset::dataset_policies;
    #[pymodule_export]
    use super::dataset::reference_task_names;
    #[pymodule_export]
    use super::dataset::replay;
    #[pymodule_export]
    use super::end_reasons;
    #[pymodule_export]
    use super::render::StateRenderer;
    #[pymodule_export]
    use super::render::check_render;
    #[pymodule_export]
    use super::render::task_of_one_hots;
    #[pymodule_export]
    use super::sample_tasks;

    /// The planned expert's revision: which version of its actions (on this physics) the
    /// `expert` and `medium` policies play; the medium noise table records it per task.
    #[pymodule_export]
    const PLANNED_EXPERT_REVISION: u32 = composuite_core::expert::PLANNED_EXPERT_REVISION;
    /// Width of a `stage_values` row.
    #[pymodule_export]
    const MAX_STAGES: usize = super::MAX_STAGES;
    /// `modes` values.
    #[pymodule_export]
    const MODE_IDLE: u8 = super::MODE_IDLE;
    #[pymodule_export]
    const MODE_STEP: u8 = super::MODE_STEP;
    #[pymodule_export]
    const MODE_RESET: u8 = super::MODE_RESET;
}
