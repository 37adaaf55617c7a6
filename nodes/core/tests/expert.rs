//! The scripted expert solves tasks through the public environment interface alone.

use composuite_core::TaskSpec;
use composuite_core::expert::run_episode;

/// Every objective, robot, object and obstacle at least once: each task succeeds on seeds 0
/// and 1.
#[test]
fn the_expert_solves_a_subset_of_tasks() {
    let tasks = [
        "IIWA/box/no_obstacle/pick_place",
        "Panda/box/object_door/pick_place",
        "IIWA/dumbbell/object_wall/pick_place",
        "Gen3/box/goal_wall/push",
        "Jaco/box/object_door/trash_can",
        "IIWA/box/object_wall/shelf",
        "Panda/box/no_obstacle/shelf",
        "IIWA/hollow_box/no_obstacle/pick_place",
        "IIWA/plate/object_door/pick_place",
        "Jaco/plate/object_door/trash_can",
        "IIWA/dumbbell/no_obstacle/push",
        "Panda/dumbbell/object_wall/shelf",
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
