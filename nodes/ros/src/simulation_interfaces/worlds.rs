//! The 256 CompoSuite tasks as `simulation_interfaces` worlds: a world's name and uri are the
//! task in wire names (`IIWA/box/no_obstacle/pick_place`), its tags the four axis elements, so
//! a tag filter picks tasks by element (`["Jaco", "shelf"]` with FILTER_MODE_ALL: the 16 Jaco
//! shelf tasks).

use composuite_core::axes::{AxisElement, Object, Objective, Obstacle, Robot};
use composuite_core::{TaskSpec, all_tasks};
use composuite_msgs::simulation_interfaces::msg::{Resource, TagsFilter, WorldResource};

use super::tags_match;

/// The world of `task`.
pub fn world(task: TaskSpec) -> WorldResource {
    let name = task.to_string();
    WorldResource {
        name: name.clone(),
        world_resource: Resource {
            uri: name,
            resource_string: String::new(),
        },
        description: format!(
            "CompoSuite task: the {} arm, the {}, {}, objective {}",
            task.robot.wire_name(),
            task.object.wire_name(),
            task.obstacle.wire_name(),
            task.objective.wire_name()
        ),
        tags: vec![
            task.robot.wire_name().into(),
            task.object.wire_name().into(),
            task.obstacle.wire_name().into(),
            task.objective.wire_name().into(),
        ],
    }
}

/// Every tag a world can have: the axis elements' wire names.
pub fn all_tags() -> Vec<&'static str> {
    let mut tags: Vec<&str> = Robot::TABLE.iter().map(|r| r.wire).collect();
    tags.extend(Object::TABLE.iter().map(|r| r.wire));
    tags.extend(Obstacle::TABLE.iter().map(|r| r.wire));
    tags.extend(Objective::TABLE.iter().map(|r| r.wire));
    tags
}

/// The worlds whose tags pass `filter`, in the suite's task order; an unknown tag is an
/// error naming the valid ones (it would match nothing, silently).
pub fn available(filter: &TagsFilter) -> Result<Vec<WorldResource>, String> {
    let valid = all_tags();
    let unknown: Vec<&String> = filter
        .tags
        .iter()
        .filter(|t| !valid.iter().any(|v| v.eq_ignore_ascii_case(t)))
        .collect();
    if !unknown.is_empty() {
        return Err(format!(
            "unknown world tag(s) {unknown:?}; a world's tags are its axis elements: {}",
            valid.join(", ")
        ));
    }
    Ok(all_tasks()
        .into_iter()
        .map(world)
        .filter(|w| tags_match(filter, &w.tags))
        .collect())
}
