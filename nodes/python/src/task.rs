//! Task names from Python, as the core parses them.

use composuite_core::TaskSpec;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `robot/object/obstacle/objective` in any spelling the core accepts; a `ValueError` naming
/// what is wrong otherwise.
pub fn parse_task(task: &str) -> PyResult<TaskSpec> {
    task.parse::<TaskSpec>()
        .map_err(|e| PyValueError::new_err(e.to_string()))
}
