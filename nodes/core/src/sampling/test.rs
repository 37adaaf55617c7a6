use std::collections::BTreeSet;

use super::*;
use crate::all_tasks;

fn split(experiment: Experiment, num_train: usize, element: Option<&str>, seed: u64) -> Split {
    sample_tasks(experiment, num_train, element, seed, false).expect("valid request")
}

fn names(tasks: &[TaskSpec]) -> Vec<String> {
    tasks.iter().map(|t| t.to_string()).collect()
}

/// Train and test together are exactly `universe`, each task once.
fn assert_partition(s: &Split, universe: &[TaskSpec]) {
    let all: Vec<TaskSpec> = s.train.iter().chain(&s.test).copied().collect();
    let unique: BTreeSet<TaskSpec> = all.iter().copied().collect();
    assert_eq!(unique.len(), all.len(), "a task appears twice");
    assert_eq!(unique, universe.iter().copied().collect::<BTreeSet<_>>());
}

#[test]
fn reference_tasks_are_indexed_by_reference_task_id() {
    let tasks = reference_tasks();
    assert_eq!(tasks.len(), 256);
    for (k, task) in tasks.iter().enumerate() {
        assert_eq!(task.reference_task_id(), k);
    }
    // docs/src/reference-facts.md §7.2 step 3: objective fastest, then obstacle, object, robot, in
    // reference order.
    assert_eq!(
        names(&tasks[..6]),
        [
            "IIWA/box/no_obstacle/pick_place",
            "IIWA/box/no_obstacle/push",
            "IIWA/box/no_obstacle/shelf",
            "IIWA/box/no_obstacle/trash_can",
            "IIWA/box/goal_wall/pick_place",
            "IIWA/box/goal_wall/push",
        ]
    );
    assert_eq!(
        tasks[16].to_string(),
        "IIWA/dumbbell/no_obstacle/pick_place"
    );
    assert_eq!(tasks[128].to_string(), "Gen3/box/no_obstacle/pick_place");
    assert_eq!(
        tasks[255].to_string(),
        "Panda/hollow_box/object_wall/trash_can"
    );
}

#[test]
fn default_splits_all_256() {
    for num_train in [0, 1, 100, 255, 256] {
        let s = split(Experiment::Default, num_train, None, 3);
        assert_eq!((s.train.len(), s.test.len()), (num_train, 256 - num_train));
        assert_partition(&s, &all_tasks());
    }
}

#[test]
fn smallscale_keeps_the_64_tasks_of_its_element() {
    for (element, fixed) in [
        ("Jaco", AnyElement::Robot(Robot::Jaco)),
        ("hollow_box", AnyElement::Object(Object::HollowBox)),
        ("None", AnyElement::Obstacle(Obstacle::NoObstacle)),
        ("trash_can", AnyElement::Objective(Objective::TrashCan)),
    ] {
        let universe: Vec<TaskSpec> = all_tasks().into_iter().filter(|t| fixed.is_in(t)).collect();
        assert_eq!(universe.len(), 64);
        for num_train in [0, 10, 64] {
            let s = split(Experiment::Smallscale, num_train, Some(element), 11);
            assert_eq!((s.train.len(), s.test.len()), (num_train, 64 - num_train));
            assert_partition(&s, &universe);
        }
    }
}

#[test]
fn holdout_puts_the_elements_one_task_last() {
    for element in ["Panda", "plate", "object_door", "Shelf"] {
        let held_out = AnyElement::parse(element).unwrap();
        for num_train in [1, 2, 50, 193] {
            for seed in [0, 5, 1 << 40] {
                let s = split(Experiment::Holdout, num_train, Some(element), seed);
                assert_eq!((s.train.len(), s.test.len()), (num_train, 63));
                let (last, rest) = s.train.split_last().unwrap();
                assert!(held_out.is_in(last), "{element}: last train task {last}");
                assert!(
                    rest.iter().all(|t| !held_out.is_in(t)),
                    "{element}: {rest:?}"
                );
                assert!(s.test.iter().all(|t| held_out.is_in(t)));
                // The test set is every task with the element except the trained one.
                let with: BTreeSet<TaskSpec> = all_tasks()
                    .into_iter()
                    .filter(|t| held_out.is_in(t))
                    .collect();
                let mut seen: BTreeSet<TaskSpec> = s.test.iter().copied().collect();
                seen.insert(*last);
                assert_eq!(seen, with);
            }
        }
    }
    // 193 = all 192 tasks without the element, then the one with it.
    let s = split(Experiment::Holdout, 193, Some("IIWA"), 9);
    assert_eq!(s.train.iter().filter(|t| t.robot == Robot::Iiwa).count(), 1);
}

#[test]
fn no_shuffle_keeps_the_reference_order() {
    let reference = reference_tasks();
    for seed in [0, 42] {
        let s = sample_tasks(Experiment::Default, 7, None, seed, true).unwrap();
        assert_eq!(s.train, reference[..7]);
        assert_eq!(s.test, reference[7..]);

        let s = sample_tasks(Experiment::Smallscale, 3, Some("Gen3"), seed, true).unwrap();
        assert_eq!(s.train, reference[128..131]);
        assert_eq!(s.test, reference[131..192]);

        // Holdout: the first tasks without goal_wall, then the first one with it.
        let s = sample_tasks(Experiment::Holdout, 3, Some("goal_wall"), seed, true).unwrap();
        assert_eq!(
            names(&s.train),
            [
                "IIWA/box/no_obstacle/pick_place",
                "IIWA/box/no_obstacle/push",
                "IIWA/box/goal_wall/pick_place",
            ]
        );
        assert_eq!(s.test[0].to_string(), "IIWA/box/goal_wall/push");
    }
}

/// Pinned splits. Computed with CPython 3.11.7 running the docs/src/reference-facts.md §7.2
/// algorithm as written in `tests/py/test_splits_reference.py` (`reference_split(...)`, names
/// mapped to wire names).
#[test]
fn pinned_splits_match_cpython() {
    let s = split(Experiment::Default, 5, None, 42);
    assert_eq!(
        names(&s.train),
        [
            "Panda/plate/object_door/shelf",
            "IIWA/box/object_door/push",
            "Jaco/plate/goal_wall/trash_can",
            "IIWA/hollow_box/object_wall/pick_place",
            "IIWA/box/goal_wall/push",
        ]
    );
    assert_eq!(s.test[0].to_string(), "Jaco/box/object_wall/trash_can");
    assert_eq!(s.test[250].to_string(), "IIWA/hollow_box/object_door/push");

    let s = split(Experiment::Default, 3, None, 0);
    assert_eq!(
        names(&s.train),
        [
            "IIWA/box/no_obstacle/push",
            "Jaco/dumbbell/object_door/pick_place",
            "Gen3/box/goal_wall/pick_place",
        ]
    );

    // A seed above 2³² (a two-word key).
    let s = split(Experiment::Default, 3, None, (1 << 40) + 7);
    assert_eq!(
        names(&s.train),
        [
            "Panda/plate/object_door/shelf",
            "IIWA/hollow_box/no_obstacle/trash_can",
            "Jaco/plate/object_door/push",
        ]
    );

    let s = split(Experiment::Smallscale, 4, Some("Kinova3"), 1);
    assert_eq!(
        names(&s.train),
        [
            "Gen3/dumbbell/goal_wall/shelf",
            "Gen3/box/object_wall/pick_place",
            "Gen3/hollow_box/goal_wall/pick_place",
            "Gen3/box/no_obstacle/trash_can",
        ]
    );
    assert_eq!(
        s.test.last().unwrap().to_string(),
        "Gen3/dumbbell/no_obstacle/push"
    );

    let s = split(Experiment::Holdout, 4, Some("ObjectWall"), 7);
    assert_eq!(
        names(&s.train),
        [
            "Jaco/plate/object_door/shelf",
            "Gen3/hollow_box/no_obstacle/shelf",
            "Gen3/hollow_box/object_door/shelf",
            "Panda/hollow_box/object_wall/shelf",
        ]
    );
    assert_eq!(
        names(&s.test[..3]),
        [
            "Gen3/plate/object_wall/push",
            "Panda/hollow_box/object_wall/trash_can",
            "IIWA/dumbbell/object_wall/pick_place",
        ]
    );

    let s = split(Experiment::Holdout, 1, Some("Plate"), 2024);
    assert_eq!(names(&s.train), ["IIWA/plate/object_wall/trash_can"]);
    assert_eq!(
        s.test.last().unwrap().to_string(),
        "IIWA/plate/object_wall/shelf"
    );
}

#[test]
fn experiments_parse_and_list_the_valid_ones() {
    assert_eq!("default".parse(), Ok(Experiment::Default));
    assert_eq!("SmallScale".parse(), Ok(Experiment::Smallscale));
    assert_eq!("holdout".parse(), Ok(Experiment::Holdout));
    let err = "uniform".parse::<Experiment>().unwrap_err();
    assert_eq!(
        err.to_string(),
        "unknown split \"uniform\"; valid: default, smallscale, holdout"
    );
}

#[test]
fn num_train_out_of_range_names_the_range() {
    for (experiment, bad, range) in [
        (Experiment::Default, 257, "0 to 256"),
        (Experiment::Smallscale, 65, "0 to 64"),
        (Experiment::Holdout, 0, "1 to 193"),
        (Experiment::Holdout, 194, "1 to 193"),
    ] {
        let element = experiment.needs_element().then_some("IIWA");
        let err = sample_tasks(experiment, bad, element, 0, false).unwrap_err();
        assert_eq!(
            err,
            SplitError::NumTrain {
                experiment,
                given: bad
            }
        );
        assert!(err.to_string().contains(range), "{err}");
        assert!(err.to_string().contains(experiment.name()), "{err}");
    }
}

#[test]
fn element_errors_list_the_valid_elements() {
    for experiment in [Experiment::Smallscale, Experiment::Holdout] {
        let err = sample_tasks(experiment, 1, None, 0, false).unwrap_err();
        assert_eq!(err, SplitError::MissingElement(experiment));
        let message = err.to_string();
        assert!(message.contains(experiment.name()), "{message}");
        assert!(
            message.contains(
                "robot IIWA, Jaco, Gen3, Panda; object box, hollow_box, plate, dumbbell; \
                 obstacle no_obstacle, object_wall, object_door, goal_wall; \
                 objective pick_place, push, trash_can, shelf"
            ),
            "{message}"
        );

        let err = sample_tasks(experiment, 1, Some("sphere"), 0, false).unwrap_err();
        assert_eq!(err, SplitError::UnknownElement("sphere".into()));
        assert!(
            err.to_string()
                .contains("unknown element \"sphere\"; valid: robot IIWA")
        );
    }
    let err = sample_tasks(Experiment::Default, 1, Some("IIWA"), 0, false).unwrap_err();
    assert_eq!(err, SplitError::ElementNotUsed("IIWA".into()));
}

/// `AnyElement::parse` takes the first axis that knows a name, which is only right if no
/// spelling belongs to two axes.
#[test]
fn no_spelling_names_elements_of_two_axes() {
    fn spellings<E: AxisElement>() -> Vec<&'static str> {
        E::TABLE
            .iter()
            .flat_map(|r| {
                [r.wire, r.reference]
                    .into_iter()
                    .chain(r.aliases.iter().copied())
            })
            .collect()
    }
    let all: Vec<&str> = [
        spellings::<Robot>(),
        spellings::<Object>(),
        spellings::<Obstacle>(),
        spellings::<Objective>(),
    ]
    .concat();
    for name in all {
        let axes = [
            Robot::parse(name).is_ok(),
            Object::parse(name).is_ok(),
            Obstacle::parse(name).is_ok(),
            Objective::parse(name).is_ok(),
        ];
        assert_eq!(axes.iter().filter(|&&ok| ok).count(), 1, "{name}");
    }
    assert_eq!(
        AnyElement::parse("Kinova3"),
        Ok(AnyElement::Robot(Robot::Gen3))
    );
    assert_eq!(AnyElement::parse("none").unwrap().axis(), Axis::Obstacle);
    assert_eq!(
        AnyElement::parse("Trashcan").unwrap().to_string(),
        "trash_can"
    );
}
