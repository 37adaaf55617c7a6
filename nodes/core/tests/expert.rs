//! The scripted expert solves tasks through the public environment interface alone.

use composuite_core::TaskSpec;
use composuite_core::expert::run_episode;

/// At least one task per objective and per robot, over every obstacle: each succeeds on
/// seeds 0 and 1.
#[test]
fn the_expert_solves_a_subset_of_box_tasks() {
    let tasks = [
        "IIWA/box/no_obstacle/pick_place",
        "Panda/box/object_door/pick_place",
        "IIWA/box/goal_wall/pick_place",
        "Jaco/box/object_wall/push",
        "Gen3/box/goal_wall/push",
        "Gen3/box/goal_wall/trash_can",
        "Jaco/box/object_door/trash_can",
        "Gen3/box/no_obstacle/shelf",
        "IIWA/box/object_wall/shelf",
        "IIWA/box/object_door/shelf",
        "Panda/box/no_obstacle/shelf",
    ];
    let mut failures = Vec::new();
    for name in tasks {
        let task: TaskSpec = name.parse().unwrap();
        for seed in 0..2 {
            let outcome = run_episode(task, seed);
            assert!(
                outcome.length > 0 && outcome.length <= 500,
                "{name} {outcome:?}"
            );
            if !outcome.success {
                failures.push(format!("{name} seed {seed}: {outcome:?}"));
            }
        }
    }
    assert!(failures.is_empty(), "failed: {failures:#?}");
}
