use super::*;
use crate::{TaskSpec, all_tasks};

/// Checks one axis table: four rows, the wire names of the design, one-hot and sampling
/// positions each a permutation of 0..4.
fn check_table<E: AxisElement>(wire: [&str; 4]) {
    assert_eq!(E::TABLE.iter().map(|r| r.wire).collect::<Vec<_>>(), wire);
    let mut one_hot: Vec<usize> = E::TABLE.iter().map(|r| r.one_hot_index).collect();
    let mut order: Vec<usize> = E::TABLE.iter().map(|r| r.reference_order).collect();
    one_hot.sort();
    order.sort();
    assert_eq!(one_hot, [0, 1, 2, 3]);
    assert_eq!(order, [0, 1, 2, 3]);
    for (i, row) in E::TABLE.iter().enumerate() {
        assert_eq!(row.element.index(), i);
        assert_eq!(E::parse(row.wire), Ok(row.element));
        assert_eq!(E::parse(row.reference), Ok(row.element));
        assert_eq!(E::parse(&row.wire.to_uppercase()), Ok(row.element));
    }
}

/// Wire names as docs/src/tasks-and-environment.md lists them; the reference orders from
/// docs/src/reference-facts.md §5 and §7.2.
#[test]
fn tables_match_the_design_and_the_reference() {
    check_table::<Robot>(["IIWA", "Jaco", "Gen3", "Panda"]);
    check_table::<Object>(["box", "hollow_box", "plate", "dumbbell"]);
    check_table::<Obstacle>(["no_obstacle", "object_wall", "object_door", "goal_wall"]);
    check_table::<Objective>(["pick_place", "push", "trash_can", "shelf"]);

    let by_one_hot = |names: Vec<(usize, &'static str)>| {
        let mut names = names;
        names.sort();
        names.into_iter().map(|(_, n)| n).collect::<Vec<_>>()
    };
    let robot_one_hot = by_one_hot(
        Robot::TABLE
            .iter()
            .map(|r| (r.one_hot_index, r.reference))
            .collect(),
    );
    assert_eq!(robot_one_hot, ["IIWA", "Jaco", "Panda", "Kinova3"]);
    let object_one_hot = by_one_hot(
        Object::TABLE
            .iter()
            .map(|r| (r.one_hot_index, r.reference))
            .collect(),
    );
    assert_eq!(object_one_hot, ["Box", "Dumbbell", "Plate", "Hollowbox"]);
    let obstacle_one_hot = by_one_hot(
        Obstacle::TABLE
            .iter()
            .map(|r| (r.one_hot_index, r.reference))
            .collect(),
    );
    assert_eq!(
        obstacle_one_hot,
        ["None", "ObjectWall", "ObjectDoor", "GoalWall"]
    );
    let objective_one_hot = by_one_hot(
        Objective::TABLE
            .iter()
            .map(|r| (r.one_hot_index, r.reference))
            .collect(),
    );
    assert_eq!(
        objective_one_hot,
        ["PickPlace", "Push", "Shelf", "Trashcan"]
    );
    let obstacle_order = by_one_hot(
        Obstacle::TABLE
            .iter()
            .map(|r| (r.reference_order, r.reference))
            .collect(),
    );
    assert_eq!(
        obstacle_order,
        ["None", "GoalWall", "ObjectDoor", "ObjectWall"]
    );
    let robot_order = by_one_hot(
        Robot::TABLE
            .iter()
            .map(|r| (r.reference_order, r.reference))
            .collect(),
    );
    assert_eq!(robot_order, ["IIWA", "Jaco", "Kinova3", "Panda"]);
}

#[test]
fn reference_and_paper_spellings_are_accepted() {
    assert_eq!(Robot::parse("kinova3"), Ok(Robot::Gen3));
    assert_eq!(Objective::parse("pick-and-place"), Ok(Objective::PickPlace));
    assert_eq!(Objective::parse("Trashcan"), Ok(Objective::TrashCan));
    assert_eq!(Objective::parse("TRASH_CAN"), Ok(Objective::TrashCan));
    assert_eq!(Obstacle::parse("None"), Ok(Obstacle::NoObstacle));
    assert_eq!(Obstacle::parse("ObjectWall"), Ok(Obstacle::ObjectWall));
    assert_eq!(Object::parse("Hollowbox"), Ok(Object::HollowBox));
}

#[test]
fn unknown_names_list_the_valid_ones() {
    let err = Robot::parse("UR5").unwrap_err();
    assert_eq!(
        err.to_string().split(';').next().unwrap(),
        "unknown robot \"UR5\""
    );
    assert!(
        err.to_string().contains("valid: IIWA, Jaco, Gen3, Panda"),
        "{err}"
    );
    let err = "IIWA/box/wall/pick_place".parse::<TaskSpec>().unwrap_err();
    assert!(
        err.to_string()
            .contains("valid: no_obstacle, object_wall, object_door, goal_wall"),
        "{err}"
    );
    let err = "IIWA/box".parse::<TaskSpec>().unwrap_err();
    assert!(
        err.to_string().contains("robot/object/obstacle/objective"),
        "{err}"
    );
}

#[test]
fn the_256_tasks_and_their_indices() {
    let tasks = all_tasks();
    assert_eq!(tasks.len(), 256);
    for (i, task) in tasks.iter().enumerate() {
        assert_eq!(task.task_index(), i);
        assert_eq!(task.to_string().parse::<TaskSpec>(), Ok(*task));
    }
    let mut reference_ids: Vec<usize> = tasks.iter().map(|t| t.reference_task_id()).collect();
    reference_ids.sort();
    assert_eq!(reference_ids, (0..256).collect::<Vec<_>>());
    // docs/src/reference-facts.md §7.2: index = 64·robot + 16·object + 4·obstacle + objective over
    // the reference lists.
    let first: TaskSpec = "IIWA/Box/None/PickPlace".parse().unwrap();
    assert_eq!(first.reference_task_id(), 0);
    let t: TaskSpec = "Kinova3/Dumbbell/GoalWall/Shelf".parse().unwrap();
    assert_eq!(t.reference_task_id(), 64 * 2 + 16 + 4 + 2);
    assert_eq!(t.to_string(), "Gen3/dumbbell/goal_wall/shelf");
    assert_eq!(
        t.reference_names(),
        ["Kinova3", "Dumbbell", "GoalWall", "Shelf"]
    );
    let last: TaskSpec = "Panda/Hollowbox/ObjectWall/Trashcan".parse().unwrap();
    assert_eq!(last.reference_task_id(), 255);
}
