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
    for refused in [F::SPAWNING, F::DELETING, F::WORLD_UNLOADING, F::SIMULATION_RESET_TIME] {
        assert!(!listed.contains(&u16::from(refused)), "{refused} is claimed");
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
    assert!(tags_match(&filter(&["iiwa", "x"], TagsFilter::FILTER_MODE_ANY), &tags));
    assert!(!tags_match(&filter(&["iiwa", "x"], TagsFilter::FILTER_MODE_ALL), &tags));
    assert!(tags_match(&filter(&["iiwa", "robot"], TagsFilter::FILTER_MODE_ALL), &tags));
}
