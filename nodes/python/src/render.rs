//! `composuite_ros._native.StateRenderer`: frames of a task's scene drawn from an observation
//! alone (`composuite_core::render::StateRenderer`), for an env that has no simulated world in
//! this process — `CompoSuiteRosEnv` renders the observations the suite sends it.

use composuite_core::TaskSpec;
use composuite_core::render::{SceneState, StateRenderer as CoreRenderer};
use numpy::prelude::*;
use numpy::{PyArray1, PyArray3, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Draws one task's scene from flat observations (93 or 77 values).
#[pyclass(module = "composuite_ros._native")]
pub struct StateRenderer {
    renderer: CoreRenderer,
}

#[pymethods]
impl StateRenderer {
    /// The renderer of `task` (`robot/object/obstacle/objective`, any accepted spelling).
    #[new]
    fn new(task: &str) -> PyResult<StateRenderer> {
        let task: TaskSpec = task
            .parse()
            .map_err(|e: composuite_core::TaskParseError| PyValueError::new_err(e.to_string()))?;
        Ok(StateRenderer {
            renderer: CoreRenderer::new(task),
        })
    }

    /// The task it draws (wire names).
    #[getter]
    fn task(&self) -> String {
        self.renderer.task().to_string()
    }

    /// The scene in the state `observation` (a flat observation vector) describes, from one of
    /// the reference's cameras: a `(height, width, 3)` uint8 array, rows from the top.
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        observation: PyReadonlyArray1<'py, f64>,
        camera: &str,
        width: u32,
        height: u32,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let state =
            SceneState::from_flat(observation.as_slice()?).map_err(PyValueError::new_err)?;
        let renderer = &mut self.renderer;
        let frame = py
            .detach(|| renderer.render(&state, camera, width, height))
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        PyArray1::from_vec(py, frame.rgb).reshape([height as usize, width as usize, 3])
    }
}

/// The task named by the 16 task one-hots of an observation, in the flat vector's order (object,
/// robot, obstacle, objective), as `robot/object/obstacle/objective`.
#[pyfunction]
pub fn task_of_one_hots(one_hots: Vec<f64>) -> PyResult<String> {
    let Ok(values) = <[f64; 16]>::try_from(one_hots.as_slice()) else {
        return Err(PyValueError::new_err(format!(
            "16 task one-hots (object, robot, obstacle, objective), not {}",
            one_hots.len()
        )));
    };
    let four = |at: usize| -> [f64; 4] { std::array::from_fn(|i| values[at + i]) };
    let factor = composuite_core::obs::TaskFactor {
        object_id: four(0),
        robot_id: four(4),
        obstacle_id: four(8),
        objective_id: four(12),
    };
    factor.task().map(|t| t.to_string()).ok_or_else(|| {
        PyValueError::new_err(format!(
            "{values:?} are not four one-hots: each group of 4 must be one 1 and three 0s"
        ))
    })
}

/// Refuse a camera name or frame size `render` would refuse, with what is valid.
#[pyfunction]
pub fn check_render(camera: &str, width: u32, height: u32) -> PyResult<()> {
    use composuite_core::render::{MAX_SIDE, RenderError, camera_spec};
    camera_spec(camera).map_err(|e| PyValueError::new_err(e.to_string()))?;
    if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
        return Err(PyValueError::new_err(
            RenderError::BadSize { width, height }.to_string(),
        ));
    }
    Ok(())
}
