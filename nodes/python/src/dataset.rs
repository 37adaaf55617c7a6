//! The offline datasets' native half (`composuite_ros.datasets` is the rest): episodes played
//! by a policy inside the core on all its threads (`Collector`), stored episodes played again
//! (`replay`), and the task names in the reference's spellings (`reference_task_names`). Rows
//! come back as numpy arrays of the files' dtypes.

use composuite_core::TaskSpec;
use composuite_core::all_tasks;
use composuite_core::dataset::{self, ACTION_SIZE, DatasetPolicy, Rows};
use numpy::prelude::*;
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::task::{env_config, parse_task};

/// Rows as a dict of numpy arrays named as the files' keys.
fn rows_dict<'py>(py: Python<'py>, rows: Rows) -> PyResult<Bound<'py, PyDict>> {
    let n = rows.len();
    let dict = PyDict::new(py);
    let observations =
        PyArray1::from_vec(py, rows.observations).reshape([n, rows.observation_size])?;
    dict.set_item("observations", observations)?;
    dict.set_item(
        "actions",
        PyArray1::from_vec(py, rows.actions).reshape([n, ACTION_SIZE])?,
    )?;
    dict.set_item("rewards", PyArray1::from_vec(py, rows.rewards))?;
    dict.set_item("terminals", PyArray1::from_vec(py, rows.terminals))?;
    dict.set_item("timeouts", PyArray1::from_vec(py, rows.timeouts))?;
    dict.set_item("successes", PyArray1::from_vec(py, rows.successes))?;
    Ok(dict)
}

/// Episodes of one task played by a built-in policy (`random`, or `expert` with `noise` on its
/// joint values), seed after seed from `first_seed`, on `threads` threads; the rows do not depend on the thread count.
#[pyclass(module = "composuite_ros._native")]
pub struct Collector {
    inner: dataset::Collector,
}

#[pymethods]
impl Collector {
    #[new]
    #[pyo3(signature = (task, policy, *, noise = 0.0, first_seed = 0, threads = 1, horizon = 500))]
    fn new(
        py: Python<'_>,
        task: &str,
        policy: &str,
        noise: f64,
        first_seed: u64,
        threads: usize,
        horizon: u32,
    ) -> PyResult<Collector> {
        let task = parse_task(task)?;
        let policy = DatasetPolicy::parse(policy, noise).map_err(PyValueError::new_err)?;
        let config = env_config(horizon)?;
        let inner = py
            .detach(|| dataset::Collector::new(task, config, policy, first_seed, threads))
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Collector { inner })
    }

    /// Play up to `max_episodes` more episodes, stopping at `max_rows` rows (an episode running
    /// at the last row ends there as a timeout). Returns the rows as a dict of arrays plus
    /// `episode_starts` (first row of each episode, int64), `episode_seeds` (uint64) and
    /// `episode_final_observations` (the observation after each episode's last step).
    fn collect<'py>(
        &mut self,
        py: Python<'py>,
        max_episodes: usize,
        max_rows: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let inner = &mut self.inner;
        let chunk = py
            .detach(|| inner.collect(max_episodes, max_rows))
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let starts: Vec<i64> = chunk.episodes.iter().map(|e| e.row as i64).collect();
        let seeds: Vec<u64> = chunk.episodes.iter().map(|e| e.seed).collect();
        let size = chunk.rows.observation_size;
        let dict = rows_dict(py, chunk.rows)?;
        dict.set_item("episode_starts", PyArray1::from_vec(py, starts))?;
        dict.set_item("episode_seeds", PyArray1::from_vec(py, seeds))?;
        let finals = PyArray1::from_vec(py, chunk.final_observations);
        let episodes = finals.len() / size;
        dict.set_item(
            "episode_final_observations",
            finals.reshape([episodes, size])?,
        )?;
        Ok(dict)
    }

    /// Play `episodes` more episodes only as far as their first successful step: whether each
    /// succeeded (a list of bools, in seed order), with no rows kept.
    fn successes(&mut self, py: Python<'_>, episodes: usize) -> PyResult<Vec<bool>> {
        let inner = &mut self.inner;
        py.detach(|| inner.successes(episodes))
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// The seed the next episode starts from (seeds the task cannot start with are skipped).
    #[getter]
    fn next_seed(&self) -> u64 {
        self.inner.next_seed()
    }
}

/// Play stored episodes of `task` again: episode i starts with `seeds[i]` and is stepped with
/// the rows `starts[i]` up to the next start (or the end) of `actions` (float32, n × 8). Returns
/// the replayed rows, one episode after another, `lengths` (rows each replayed: fewer than
/// stored where the environment ended the episode earlier) and `episode_final_observations`.
#[pyfunction]
#[pyo3(signature = (task, seeds, starts, actions, *, threads = 1, horizon = 500))]
pub fn replay<'py>(
    py: Python<'py>,
    task: &str,
    seeds: PyReadonlyArray1<'py, u64>,
    starts: PyReadonlyArray1<'py, i64>,
    actions: PyReadonlyArray2<'py, f32>,
    threads: usize,
    horizon: u32,
) -> PyResult<Bound<'py, PyDict>> {
    let task: TaskSpec = parse_task(task)?;
    let config = env_config(horizon)?;
    let seeds = seeds.as_slice()?;
    let starts = starts.as_slice()?;
    if actions.shape()[1] != ACTION_SIZE {
        return Err(PyValueError::new_err(format!(
            "actions have {} columns; the reference's action space has {ACTION_SIZE}",
            actions.shape()[1]
        )));
    }
    let rows = actions.shape()[0];
    let actions = actions.as_slice()?;
    if seeds.len() != starts.len() {
        return Err(PyValueError::new_err(format!(
            "{} seeds but {} episode starts",
            seeds.len(),
            starts.len()
        )));
    }
    let mut bounds = Vec::with_capacity(starts.len());
    for (i, &start) in starts.iter().enumerate() {
        let end = starts.get(i + 1).map_or(rows as i64, |&next| next);
        if start < 0 || end <= start || end > rows as i64 {
            return Err(PyValueError::new_err(format!(
                "episode {i} spans rows {start}..{end}: starts must rise from 0 within the \
                 {rows} rows"
            )));
        }
        bounds.push((start as usize, end as usize));
    }
    if starts.first().is_some_and(|&s| s != 0) {
        return Err(PyValueError::new_err(
            "the first episode must start at row 0",
        ));
    }
    let episodes: Vec<(u64, &[f32])> = seeds
        .iter()
        .zip(&bounds)
        .map(|(&seed, &(a, b))| (seed, &actions[a * ACTION_SIZE..b * ACTION_SIZE]))
        .collect();
    let replayed = py
        .detach(|| dataset::replay_episodes(task, &config, &episodes, threads))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let size = composuite_core::obs::flat_size(true);
    let mut all = Rows::new(size);
    let mut lengths = Vec::with_capacity(replayed.len());
    let mut finals = Vec::with_capacity(replayed.len() * size);
    for (i, result) in replayed.into_iter().enumerate() {
        let played = result
            .map_err(|e| PyValueError::new_err(format!("episode {i} (seed {}): {e}", seeds[i])))?;
        lengths.push(played.rows.len() as i64);
        all.append(&played.rows);
        finals.extend(played.final_observation);
    }
    let episodes = lengths.len();
    let dict = rows_dict(py, all)?;
    dict.set_item("lengths", PyArray1::from_vec(py, lengths))?;
    let finals = PyArray1::from_vec(py, finals).reshape([episodes, size])?;
    dict.set_item("episode_final_observations", finals)?;
    Ok(dict)
}

/// Every task as `(suite name, (robot, object, obstacle, objective) in the reference's
/// spellings)`, in the suite's order: the one table both spellings come from.
#[pyfunction]
pub fn reference_task_names() -> Vec<(String, [&'static str; 4])> {
    all_tasks()
        .iter()
        .map(|t| (t.to_string(), t.reference_names()))
        .collect()
}

/// The policies `Collector` plays.
#[pyfunction]
pub fn dataset_policies() -> Vec<&'static str> {
    DatasetPolicy::ALL.iter().map(|p| p.name()).collect()
}
