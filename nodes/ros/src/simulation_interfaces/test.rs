use super::*;

#[test]
fn every_interface_is_named_once_and_features_come_from_the_table() {
    let mut seen: Vec<&str> = INTERFACES.iter().map(|i| i.name).collect();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen.len(), INTERFACES.len());
    let listed = features().features;
    assert!(listed.windows(2).all(|w| w[0] < w[1]));
    // Nothing the suite only refuses is claimed.
    for refused in [
        F::SPAWNING,
        F::DELETING,
        F::WORLD_UNLOADING,
        F::SIMULATION_RESET_TIME,
    ] {
        assert!(
            !listed.contains(&u16::from(refused)),
            "{refused} is claimed"
        );
    }
    assert!(listed.contains(&u16::from(F::STEP_SIMULATION_ACTION)));
}

#[test]
fn tag_filters_follow_the_mode() {
    use composuite_msgs::simulation_interfaces::msg::TagsFilter;
    let tags = vec!["IIWA".to_string(), "robot".to_string()];
    let filter = |tags: &[&str], mode| TagsFilter {
        tags: tags.iter().map(|t| t.to_string()).collect(),
        filter_mode: mode,
    };
    assert!(tags_match(&filter(&[], TagsFilter::FILTER_MODE_ALL), &tags));
    assert!(tags_match(
        &filter(&["iiwa", "x"], TagsFilter::FILTER_MODE_ANY),
        &tags
    ));
    assert!(!tags_match(
        &filter(&["iiwa", "x"], TagsFilter::FILTER_MODE_ALL),
        &tags
    ));
    assert!(tags_match(
        &filter(&["iiwa", "robot"], TagsFilter::FILTER_MODE_ALL),
        &tags
    ));
}

#[test]
fn the_book_lists_every_interface_with_its_type_and_node() {
    let page = include_str!("../../../../docs/src/simulation-interfaces.md");
    for i in INTERFACES {
        let row = format!("| `{}` | `{}` | {} |", i.name, i.type_name, i.node.name());
        assert!(
            page.contains(&row),
            "docs/src/simulation-interfaces.md lacks the row {row}"
        );
        // Its features, by their constant names, in the row.
        let line = page
            .lines()
            .find(|l| l.starts_with(&row))
            .expect("found above");
        assert_eq!(
            line.matches("`SIMULATION_").count()
                + line.matches("`STEP_").count()
                + line.matches("`ENTITY_").count()
                + line.matches("`WORLD_").count()
                + line.matches("`AVAILABLE_").count(),
            i.features.len(),
            "{line}"
        );
    }
}

#[test]
fn the_worlds_are_the_256_tasks_and_tags_select_them() {
    use composuite_msgs::simulation_interfaces::msg::TagsFilter;
    assert_eq!(
        worlds::available(&TagsFilter::default()).unwrap().len(),
        256
    );
    let jaco_shelf = TagsFilter {
        tags: vec!["Jaco".into(), "shelf".into()],
        filter_mode: TagsFilter::FILTER_MODE_ALL,
    };
    assert_eq!(worlds::available(&jaco_shelf).unwrap().len(), 16);
    let typo = TagsFilter {
        tags: vec!["Jacko".into()],
        filter_mode: TagsFilter::FILTER_MODE_ANY,
    };
    assert!(worlds::available(&typo).unwrap_err().contains("Jaco"));
}

#[test]
fn each_task_has_its_entities_and_every_static_one_a_box() {
    for task in composuite_core::all_tasks() {
        let list = entities::entities(task);
        let names: Vec<&str> = list.iter().map(|e| e.name).collect();
        assert_eq!(&names[..4], ["robot", "object", "bin1", "bin2"]);
        let fixture = matches!(
            task.objective,
            composuite_core::axes::Objective::TrashCan | composuite_core::axes::Objective::Shelf
        );
        let obstacle = task.obstacle != composuite_core::axes::Obstacle::NoObstacle;
        assert_eq!(
            names.len(),
            4 + usize::from(fixture) + usize::from(obstacle),
            "{task}"
        );
        for e in &list[1..] {
            let (lo, hi) = e.bounds().expect("every body but the arm has a box");
            assert!((0..3).all(|k| lo[k] < hi[k]), "{task}: {}", e.name);
        }
        assert!(list[0].bounds().is_none());
    }
}
