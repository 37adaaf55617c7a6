//! A task: one element of each axis.

use std::fmt;
use std::str::FromStr;

use crate::axes::{AxisElement, Object, Objective, Obstacle, Robot, UnknownElement};

/// One of the 256 CompoSuite tasks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TaskSpec {
    /// The arm.
    pub robot: Robot,
    /// The object.
    pub object: Object,
    /// The obstacle.
    pub obstacle: Obstacle,
    /// The objective.
    pub objective: Objective,
}

impl TaskSpec {
    /// A task from its four elements.
    pub fn new(robot: Robot, object: Object, obstacle: Obstacle, objective: Objective) -> Self {
        TaskSpec {
            robot,
            object,
            obstacle,
            objective,
        }
    }

    /// The task named on each axis (any spelling of each element, as the services receive them).
    pub fn from_names(
        robot: &str,
        object: &str,
        obstacle: &str,
        objective: &str,
    ) -> Result<TaskSpec, TaskParseError> {
        Ok(TaskSpec {
            robot: Robot::parse(robot).map_err(TaskParseError::Element)?,
            object: Object::parse(object).map_err(TaskParseError::Element)?,
            obstacle: Obstacle::parse(obstacle).map_err(TaskParseError::Element)?,
            objective: Objective::parse(objective).map_err(TaskParseError::Element)?,
        })
    }

    /// Index in the suite's canonical order: 64·robot + 16·object + 4·obstacle + objective, each
    /// element's index in the suite's axis order (0..256).
    pub fn task_index(&self) -> usize {
        64 * self.robot.index()
            + 16 * self.object.index()
            + 4 * self.obstacle.index()
            + self.objective.index()
    }

    /// Index in the reference benchmark's unshuffled task list (what its `--task-id` selects):
    /// the same formula over the reference's sampling orders.
    pub fn reference_task_id(&self) -> usize {
        64 * self.robot.names().reference_order
            + 16 * self.object.names().reference_order
            + 4 * self.obstacle.names().reference_order
            + self.objective.names().reference_order
    }

    /// The reference benchmark's names, (robot, object, obstacle, objective).
    pub fn reference_names(&self) -> [&'static str; 4] {
        [
            self.robot.names().reference,
            self.object.names().reference,
            self.obstacle.names().reference,
            self.objective.names().reference,
        ]
    }
}

impl fmt::Display for TaskSpec {
    /// `robot/object/obstacle/objective` in wire names, e.g. `IIWA/box/no_obstacle/pick_place`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}/{}/{}/{}",
            self.robot.wire_name(),
            self.object.wire_name(),
            self.obstacle.wire_name(),
            self.objective.wire_name()
        )
    }
}

/// A task string that does not name a task.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TaskParseError {
    /// Not four `/`-separated parts.
    Shape(String),
    /// One part is no element of its axis.
    Element(UnknownElement),
}

impl fmt::Display for TaskParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TaskParseError::Shape(given) => write!(
                f,
                "task {given:?} is not of the form robot/object/obstacle/objective, \
                 e.g. IIWA/box/no_obstacle/pick_place"
            ),
            TaskParseError::Element(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for TaskParseError {}

impl FromStr for TaskSpec {
    type Err = TaskParseError;

    /// Parse `robot/object/obstacle/objective`; every part accepts any spelling of its axis.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = s.split('/').collect();
        let [robot, object, obstacle, objective] = parts.as_slice() else {
            return Err(TaskParseError::Shape(s.to_string()));
        };
        TaskSpec::from_names(robot, object, obstacle, objective)
    }
}

/// All 256 tasks in the suite's canonical order (objective varying fastest).
pub fn all_tasks() -> Vec<TaskSpec> {
    let mut tasks = Vec::with_capacity(256);
    for robot in Robot::all() {
        for object in Object::all() {
            for obstacle in Obstacle::all() {
                for objective in Objective::all() {
                    tasks.push(TaskSpec {
                        robot,
                        object,
                        obstacle,
                        objective,
                    });
                }
            }
        }
    }
    tasks
}
