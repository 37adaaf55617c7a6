//! Task names and episode settings from Python, checked as the core takes them.

use composuite_core::TaskSpec;
use composuite_core::env::EnvConfig;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `robot/object/obstacle/objective` in any spelling the core accepts; a `ValueError` naming
/// what is wrong otherwise.
pub fn parse_task(task: &str) -> PyResult<TaskSpec> {
    task.parse::<TaskSpec>()
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The default settings with `horizon` control steps an episode; a `ValueError` for 0.
pub fn env_config(horizon: u32) -> PyResult<EnvConfig> {
    if horizon == 0 {
        return Err(PyValueError::new_err("horizon must be at least 1 step"));
    }
    Ok(EnvConfig::default().horizon(horizon))
}
