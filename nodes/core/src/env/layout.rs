//! Where everything of an episode is before the first step: the arena of the task, the object
//! at the start its seed draws, the goal. Pure geometry — no physics world is built — so the
//! task manager can compose a scene exactly as the simulator will lay it out.

use nalgebra::{Isometry3, Point3, UnitQuaternion};

use super::{EnvError, sample_object_start};
use crate::TaskSpec;
use crate::arena::{Placed, arena_parts, goal_marker_parts, goal_position, object_parts};

/// The layout of one episode of `task` started with `seed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeLayout {
    /// The task laid out.
    pub task: TaskSpec,
    /// The episode's seed (it draws the object start).
    pub seed: u64,
    /// Where the object starts (the reference's draw for `seed`).
    pub object_start: Point3<f64>,
    /// The goal marker's position.
    pub goal: Point3<f64>,
}

impl EpisodeLayout {
    /// The layout the environment's `reset(seed)` produces; a seed out of range is an error.
    pub fn new(task: TaskSpec, seed: u64) -> Result<EpisodeLayout, EnvError> {
        Ok(EpisodeLayout {
            task,
            seed,
            object_start: sample_object_start(task.obstacle, task.object, seed)?,
            goal: goal_position(task.objective, task.object),
        })
    }

    /// Every static solid, the object at its start pose, and the goal marker, in the world.
    pub fn parts(&self) -> Vec<Placed> {
        let task = self.task;
        let mut parts = arena_parts(task.objective, task.obstacle);
        let start = Isometry3::from_parts(self.object_start.into(), UnitQuaternion::identity());
        parts.extend(object_parts(task.object).into_iter().map(|p| Placed {
            pose: start * p.pose,
            ..p
        }));
        parts.extend(goal_marker_parts(task.objective, task.object));
        parts
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::all_tasks;
    use crate::env::{Env, EnvConfig};

    #[test]
    fn the_layout_is_where_reset_puts_everything() {
        for task in all_tasks() {
            let mut env = Env::new(task, EnvConfig::default());
            for seed in [0, 7, 123_456] {
                env.reset(seed).unwrap();
                let layout = EpisodeLayout::new(task, seed).unwrap();
                assert_eq!(layout, env.layout(), "{task} seed {seed}");
                assert_eq!(layout.parts(), env.scene_parts(), "{task} seed {seed}");
            }
        }
    }

    #[test]
    fn a_seed_out_of_range_is_refused() {
        let task = "IIWA/box/no_obstacle/pick_place".parse().unwrap();
        assert!(EpisodeLayout::new(task, 1 << 32).is_err());
    }
}
