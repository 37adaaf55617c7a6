//! Staged rewards, success and early termination of the four objectives, as the reference
//! implements them (docs/src/reference-facts.md §6, including every place where its code differs
//! from the paper).
//!
//! Each objective is one file computing its stages from a [`WorldSnapshot`]; this module holds
//! what they share. The reward of a step is 1 on success, else the *maximum* over the stage
//! values (not their sum, docs/src/reference-facts.md §1); every stage's maximum is below 1, so the
//! reward is 1 exactly on success. Scene constants (bin 2, trash can, shelf, goal marker) come from
//! [`crate::arena`]; the constants here are the reward's own shaping gains and thresholds.

mod pick_place;
mod push;
mod shelf;
mod trash_can;

pub(crate) use pick_place::in_bin2;

use nalgebra::{Point3, Vector3};

use crate::axes::{Object, Objective};

/// What the reward needs to know about the world after a control step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldSnapshot {
    /// World position of the object's body origin (m).
    pub object_position: Point3<f64>,
    /// World position of the gripper's grip site, the end-effector point (m).
    pub grip_site_position: Point3<f64>,
    /// The hand body's local z axis expressed in the world frame (unit vector).
    pub hand_z_axis: Vector3<f64>,
    /// The benchmark's grasp test (both pads touch the object; looser for the plate).
    pub grasping: bool,
    /// The last gripper action in the reference convention, in [−1, 1]: > 0 close,
    /// < 0 open, 0 hold.
    pub last_gripper_action: f64,
}

/// A stage's fixed description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageSpec {
    /// Stage name, e.g. `reach`.
    pub name: &'static str,
    /// The largest value the stage can take.
    pub max: f64,
}

/// One stage's value at a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stage {
    /// Stage name, e.g. `reach`.
    pub name: &'static str,
    /// Value (≥ 0, ≤ `max`).
    pub value: f64,
    /// The largest value the stage can take.
    pub max: f64,
}

/// The most stages any objective has (pick-place, trash can and shelf have 5, push 3).
pub const MAX_STAGES: usize = 5;

/// An objective's stages in its order, held inline: computing a step's reward allocates
/// nothing. Reads as a slice of [`Stage`].
#[derive(Clone, Copy)]
pub struct Stages {
    slots: [Stage; MAX_STAGES],
    len: usize,
}

impl std::ops::Deref for Stages {
    type Target = [Stage];
    fn deref(&self) -> &[Stage] {
        &self.slots[..self.len]
    }
}

impl<'a> IntoIterator for &'a Stages {
    type Item = &'a Stage;
    type IntoIter = std::slice::Iter<'a, Stage>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl PartialEq for Stages {
    fn eq(&self, other: &Stages) -> bool {
        **self == **other
    }
}

impl std::fmt::Debug for Stages {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// The staged reward of one step, every stage exposed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StagedReward {
    /// The objective.
    pub objective: Objective,
    /// Every stage in the objective's order.
    pub stages: Stages,
    /// The reward: 1 on success, else the maximum stage value; in [0, 1].
    pub total: f64,
    /// Whether the objective's success test holds.
    pub success: bool,
}

impl StagedReward {
    /// Assembles a reward from the stage values (in `specs` order) and the success test.
    fn new<const N: usize>(
        objective: Objective,
        specs: &[StageSpec; N],
        values: [f64; N],
        success: bool,
    ) -> Self {
        const { assert!(N <= MAX_STAGES) };
        let unused = Stage {
            name: "",
            value: 0.0,
            max: 0.0,
        };
        let mut stages = Stages {
            slots: [unused; MAX_STAGES],
            len: N,
        };
        for ((slot, spec), value) in stages.slots.iter_mut().zip(specs).zip(values) {
            *slot = Stage {
                name: spec.name,
                value,
                max: spec.max,
            };
        }
        let best = stages.iter().map(|s| s.value).fold(0.0, f64::max);
        StagedReward {
            objective,
            stages,
            total: if success { 1.0 } else { best },
            success,
        }
    }

    /// Index of the stage giving the maximum (the latest on ties), or `None` when every stage
    /// is 0.
    pub fn current_stage(&self) -> Option<usize> {
        let mut current = None;
        let mut best = 0.0;
        for (i, stage) in self.stages.iter().enumerate() {
            if stage.value > 0.0 && stage.value >= best {
                best = stage.value;
                current = Some(i);
            }
        }
        current
    }

    /// The stage called `name`, if the objective has one.
    pub fn stage(&self, name: &str) -> Option<&Stage> {
        self.stages.iter().find(|stage| stage.name == name)
    }
}

/// How the staged reward becomes the number an agent gets: the reference's `make()` options
/// `reward_shaping` and `reward_scale`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RewardConfig {
    /// Shaped (the default): 1 on success, else the best stage. Sparse (`false`): 1 on success,
    /// else 0.
    pub shaping: bool,
    /// Multiplies the reward (the reference's default is 1).
    pub scale: f64,
}

impl Default for RewardConfig {
    fn default() -> Self {
        RewardConfig {
            shaping: true,
            scale: 1.0,
        }
    }
}

impl RewardConfig {
    /// The reward an agent gets for `staged`, as the reference's `reward()` computes it.
    pub fn reward(&self, staged: &StagedReward) -> f64 {
        let reward = if staged.success {
            1.0
        } else if self.shaping {
            staged.total
        } else {
            0.0
        };
        reward * self.scale
    }
}

/// Why an episode ended before its horizon.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// Push: the object rose more than 10 cm above the table height
    /// (docs/src/reference-facts.md §1, §6).
    ObjectLifted,
}

impl Termination {
    /// A short reason, as the episode status reports it.
    pub fn reason(self) -> &'static str {
        match self {
            Termination::ObjectLifted => "object lifted",
        }
    }
}

/// Why an episode that ran to its horizon of `horizon` control steps ended (the episode
/// status's reason text, as the task manager sends it and the Python envs report it).
pub fn horizon_reason(horizon: u32) -> String {
    format!("the horizon of {horizon} steps was reached")
}

/// The stages of an objective, in order (docs/src/reference-facts.md §6).
pub fn stage_specs(objective: Objective) -> &'static [StageSpec] {
    match objective {
        Objective::PickPlace => &pick_place::STAGES,
        Objective::Push => &push::STAGES,
        Objective::TrashCan => &trash_can::STAGES,
        Objective::Shelf => &shelf::STAGES,
    }
}

/// The staged reward of `objective` with `object` in the world `snapshot` describes. The
/// object matters only to Push, whose goal marker height depends on it.
pub fn staged_reward(
    objective: Objective,
    object: Object,
    snapshot: &WorldSnapshot,
) -> StagedReward {
    match objective {
        Objective::PickPlace => pick_place::staged_reward(snapshot),
        Objective::Push => push::staged_reward(object, snapshot),
        Objective::TrashCan => trash_can::staged_reward(snapshot),
        Objective::Shelf => shelf::staged_reward(snapshot),
    }
}

/// Whether the episode ends early in this state. Only Push ends early
/// (docs/src/reference-facts.md §1).
pub fn termination(objective: Objective, snapshot: &WorldSnapshot) -> Option<Termination> {
    match objective {
        Objective::Push => push::termination(snapshot),
        Objective::PickPlace | Objective::TrashCan | Objective::Shelf => None,
    }
}

/// The reference's "tanh-shaped closeness" 1 − tanh(gain · distance): 1 at 0, falling to 0.
fn closeness(gain: f64, distance: f64) -> f64 {
    1.0 - (gain * distance).tanh()
}

/// The reach stage shared by every objective: 10 is the reference's gain
/// (docs/src/reference-facts.md §6).
const REACH_GAIN: f64 = 10.0;

/// Grip site to object origin (m), the `d_reach` of docs/src/reference-facts.md §6.
fn reach_distance(snapshot: &WorldSnapshot) -> f64 {
    nalgebra::distance(&snapshot.grip_site_position, &snapshot.object_position)
}

/// Horizontal distance between a point and a reference xy (m).
fn xy_distance(p: &Point3<f64>, x: f64, y: f64) -> f64 {
    let dx = x - p.x;
    let dy = y - p.y;
    (dx * dx + dy * dy).sqrt()
}

/// `low < value < high`: the reference's "in region" tests are strict
/// (docs/src/reference-facts.md §6).
fn strictly_between(value: f64, low: f64, high: f64) -> bool {
    low < value && value < high
}

#[cfg(test)]
mod test;
