//! Train/test task splits, identical to the reference benchmark's `sample_tasks`
//! (docs/src/reference-facts.md §7.2), so a seed gives the paper's experiments the same task lists.
//!
//! Three experiments: `default` (uniform over the 256 tasks), `smallscale` (only the 64 tasks
//! containing one element) and `holdout` (train on tasks without an element plus exactly one
//! with it; test on the other 63 with it).

use std::fmt;
use std::ops::RangeInclusive;
use std::str::FromStr;

use crate::TaskSpec;
use crate::axes::{Axis, AxisElement, Object, Objective, Obstacle, Robot};
use crate::rng::Mt19937;

/// The kind of split, as the reference's `experiment_type`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Experiment {
    /// Uniform: the first `num_train` shuffled tasks train, the rest test.
    Default,
    /// Only the 64 tasks containing one element, split like `Default`.
    Smallscale,
    /// Train on tasks without one element plus a single task with it; test on the other tasks
    /// with it.
    Holdout,
}

impl Experiment {
    /// All experiments, in the order errors list them.
    pub const ALL: [Experiment; 3] = [
        Experiment::Default,
        Experiment::Smallscale,
        Experiment::Holdout,
    ];

    /// The name used on the command line, in messages and by the reference.
    pub fn name(self) -> &'static str {
        match self {
            Experiment::Default => "default",
            Experiment::Smallscale => "smallscale",
            Experiment::Holdout => "holdout",
        }
    }

    /// The valid `num_train` values (the reference's bounds): holdout needs at least one
    /// training task (the one with the element) and at most the 192 tasks without it plus that one.
    pub fn num_train_range(self) -> RangeInclusive<usize> {
        match self {
            Experiment::Default => 0..=256,
            Experiment::Smallscale => 0..=64,
            Experiment::Holdout => 1..=193,
        }
    }

    /// Whether the experiment is built around one element.
    pub fn needs_element(self) -> bool {
        !matches!(self, Experiment::Default)
    }
}

impl fmt::Display for Experiment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Experiment {
    type Err = SplitError;

    /// `default`, `smallscale` or `holdout`, case-insensitively.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Experiment::ALL
            .into_iter()
            .find(|e| e.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| SplitError::UnknownExperiment(s.to_string()))
    }
}

/// An element of any of the four axes (what `smallscale` fixes and `holdout` holds out).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AnyElement {
    /// A robot.
    Robot(Robot),
    /// An object.
    Object(Object),
    /// An obstacle.
    Obstacle(Obstacle),
    /// An objective.
    Objective(Objective),
}

impl AnyElement {
    /// Parse any accepted spelling of any axis' element (wire, reference or alias,
    /// case-insensitively). No spelling is shared between axes, so at most one axis matches.
    pub fn parse(name: &str) -> Result<Self, SplitError> {
        Robot::parse(name)
            .map(AnyElement::Robot)
            .or_else(|_| Object::parse(name).map(AnyElement::Object))
            .or_else(|_| Obstacle::parse(name).map(AnyElement::Obstacle))
            .or_else(|_| Objective::parse(name).map(AnyElement::Objective))
            .map_err(|_| SplitError::UnknownElement(name.to_string()))
    }

    /// The axis the element belongs to.
    pub fn axis(self) -> Axis {
        match self {
            AnyElement::Robot(_) => Axis::Robot,
            AnyElement::Object(_) => Axis::Object,
            AnyElement::Obstacle(_) => Axis::Obstacle,
            AnyElement::Objective(_) => Axis::Objective,
        }
    }

    /// The suite's wire name.
    pub fn wire_name(self) -> &'static str {
        match self {
            AnyElement::Robot(e) => e.wire_name(),
            AnyElement::Object(e) => e.wire_name(),
            AnyElement::Obstacle(e) => e.wire_name(),
            AnyElement::Objective(e) => e.wire_name(),
        }
    }

    /// Whether `task` has this element on its axis.
    pub fn is_in(self, task: &TaskSpec) -> bool {
        match self {
            AnyElement::Robot(e) => task.robot == e,
            AnyElement::Object(e) => task.object == e,
            AnyElement::Obstacle(e) => task.obstacle == e,
            AnyElement::Objective(e) => task.objective == e,
        }
    }
}

impl fmt::Display for AnyElement {
    /// The wire name.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.wire_name())
    }
}

/// A train/test split.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Split {
    /// Training tasks, in the reference's order.
    pub train: Vec<TaskSpec>,
    /// Test tasks, in the reference's order.
    pub test: Vec<TaskSpec>,
}

/// A split request that names no split. Every message says what is valid.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SplitError {
    /// The experiment is none of `default`, `smallscale`, `holdout`.
    UnknownExperiment(String),
    /// `num_train` is outside the experiment's range.
    NumTrain {
        /// The experiment asked for.
        experiment: Experiment,
        /// The `num_train` given.
        given: usize,
    },
    /// `smallscale` or `holdout` without an element.
    MissingElement(Experiment),
    /// An element that no axis knows.
    UnknownElement(String),
    /// An element given to `default`, which has no use for one.
    ElementNotUsed(String),
}

/// Every element's wire name, axis by axis, for error messages.
fn valid_elements() -> String {
    fn row<E: AxisElement>() -> String {
        let names: Vec<&str> = E::TABLE.iter().map(|r| r.wire).collect();
        format!("{} {}", E::AXIS.name(), names.join(", "))
    }
    format!(
        "{}; {}; {}; {} (reference spellings such as Kinova3, Hollowbox, None or Trashcan are \
         accepted too, case-insensitively)",
        row::<Robot>(),
        row::<Object>(),
        row::<Obstacle>(),
        row::<Objective>()
    )
}

impl fmt::Display for SplitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SplitError::UnknownExperiment(given) => {
                let valid: Vec<&str> = Experiment::ALL.iter().map(|e| e.name()).collect();
                write!(f, "unknown split {given:?}; valid: {}", valid.join(", "))
            }
            SplitError::NumTrain { experiment, given } => {
                let range = experiment.num_train_range();
                write!(
                    f,
                    "num_train {given} is out of range for the {experiment} split; valid: {} to {}",
                    range.start(),
                    range.end()
                )
            }
            SplitError::MissingElement(experiment) => write!(
                f,
                "the {experiment} split needs an element; valid: {}",
                valid_elements()
            ),
            SplitError::UnknownElement(given) => {
                write!(f, "unknown element {given:?}; valid: {}", valid_elements())
            }
            SplitError::ElementNotUsed(given) => write!(
                f,
                "the default split takes no element (got {given:?}); elements are for the \
                 smallscale and holdout splits"
            ),
        }
    }
}

impl std::error::Error for SplitError {}

/// One axis' elements in the reference's sampling order (its `AVAILABLE_*` list).
fn in_reference_order<E: AxisElement>() -> Vec<E> {
    let mut rows: Vec<_> = E::TABLE.iter().collect();
    rows.sort_by_key(|row| row.reference_order);
    rows.into_iter().map(|row| row.element).collect()
}

/// The 256 tasks in the reference's unshuffled order: the Cartesian product of the axes in their
/// reference sampling orders, objective varying fastest, then obstacle, object, robot. Position
/// `k` holds the task whose [`TaskSpec::reference_task_id`] is `k`.
///
/// This order, not the suite's canonical one, is what the reference shuffles, so a split is only
/// reference-identical if it starts from here.
pub fn reference_tasks() -> Vec<TaskSpec> {
    let objects = in_reference_order::<Object>();
    let obstacles = in_reference_order::<Obstacle>();
    let objectives = in_reference_order::<Objective>();
    let mut tasks = Vec::with_capacity(256);
    for robot in in_reference_order::<Robot>() {
        for &object in &objects {
            for &obstacle in &obstacles {
                for &objective in &objectives {
                    tasks.push(TaskSpec::new(robot, object, obstacle, objective));
                }
            }
        }
    }
    tasks
}

/// The reference's `sample_tasks(experiment, num_train, smallscale_elem / holdout_elem,
/// shuffling_seed = seed, no_shuffle)`, task for task (docs/src/reference-facts.md §7.2):
///
/// 1. List the tasks in [`reference_tasks`] order; `smallscale` keeps only the 64 with
///    `element` (the same as reducing its axis to that one element).
/// 2. Unless `no_shuffle`, shuffle that list with CPython's `random.shuffle` after
///    `random.seed(seed)` ([`Mt19937::python_seed`]).
/// 3. `default`, `smallscale`: train = the first `num_train`, test = the rest. `holdout`: of the
///    shuffled 256, E = the tasks with `element`, N = those without; train = the first
///    `num_train − 1` of N followed by E's first task (so the element's one training task is
///    always **last**), test = the other 63 of E.
///
/// `element` takes any spelling of any axis' element (the reference only knows its own
/// spellings). Where the reference silently does something odd, this is stricter and returns an
/// error instead:
///
/// * the seed is required — the reference shuffles unseeded (not reproducibly) when it is `None`;
/// * `num_train` is always checked — the reference checks it with `assert`, which `python -O`
///   skips;
/// * `default` with an element is an error — the reference warns and ignores it;
/// * `smallscale` without an element is an error — the reference's check for it is dead code,
///   and the missing element (Python `None`) is then found in its obstacle list, which holds
///   both `None` and `"None"`, giving the 64 no-obstacle tasks;
/// * `holdout` without an element, or with one it does not know, is an error — the reference
///   matches nothing and returns `num_train − 1` training tasks and an empty test set;
/// * an unknown element is an error for `smallscale` as in the reference, but the message lists
///   the valid elements.
pub fn sample_tasks(
    experiment: Experiment,
    num_train: usize,
    element: Option<&str>,
    seed: u64,
    no_shuffle: bool,
) -> Result<Split, SplitError> {
    if !experiment.num_train_range().contains(&num_train) {
        return Err(SplitError::NumTrain {
            experiment,
            given: num_train,
        });
    }
    let element = match (experiment.needs_element(), element) {
        (false, None) => None,
        (false, Some(given)) => return Err(SplitError::ElementNotUsed(given.to_string())),
        (true, None) => return Err(SplitError::MissingElement(experiment)),
        (true, Some(given)) => Some(AnyElement::parse(given)?),
    };

    let mut tasks = reference_tasks();
    if let (Experiment::Smallscale, Some(fixed)) = (experiment, element) {
        tasks.retain(|task| fixed.is_in(task));
    }
    if !no_shuffle {
        Mt19937::python_seed(seed).shuffle(&mut tasks);
    }

    match (experiment, element) {
        (Experiment::Holdout, Some(held_out)) => {
            let (mut with, without): (Vec<TaskSpec>, Vec<TaskSpec>) =
                tasks.into_iter().partition(|task| held_out.is_in(task));
            let mut train: Vec<TaskSpec> = without.into_iter().take(num_train - 1).collect();
            // Every element is in 64 tasks, so `with` is never empty.
            train.push(with.remove(0));
            Ok(Split { train, test: with })
        }
        _ => {
            let test = tasks.split_off(num_train);
            Ok(Split { train: tasks, test })
        }
    }
}

#[cfg(test)]
mod test;
