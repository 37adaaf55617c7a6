//! The `composuite` binary as a user runs it.

use std::process::Command;

fn composuite(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_composuite"))
        .args(args)
        .output()
        .expect("runs")
}

#[test]
fn tasks_json_lists_all_256_in_order() {
    let value = json_of(&["tasks", "--json"]);
    let tasks = value["tasks"].as_array().unwrap();
    assert_eq!(tasks.len(), 256);
    assert_eq!(tasks[0]["task"], "IIWA/box/no_obstacle/pick_place");
    assert_eq!(tasks[255]["task"], "Panda/dumbbell/goal_wall/shelf");
    assert_eq!(
        tasks[255]["reference"],
        serde_json::json!(["Panda", "Dumbbell", "GoalWall", "Shelf"])
    );
}

#[test]
fn filters_accept_reference_spellings() {
    let value = json_of(&[
        "tasks",
        "--robot",
        "Kinova3",
        "--obstacle",
        "None",
        "--objective",
        "Trashcan",
        "--json",
    ]);
    let names: Vec<&str> = value["tasks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["task"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "Gen3/box/no_obstacle/trash_can",
            "Gen3/hollow_box/no_obstacle/trash_can",
            "Gen3/plate/no_obstacle/trash_can",
            "Gen3/dumbbell/no_obstacle/trash_can"
        ]
    );
}

#[test]
fn a_bad_filter_is_a_clear_error() {
    let out = composuite(&["tasks", "--object", "sphere"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("unknown object \"sphere\""), "{stderr}");
    assert!(
        stderr.contains("valid: box, hollow_box, plate, dumbbell"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
}

/// Run a command that must succeed and print JSON; its parsed output.
fn json_of(args: &[&str]) -> serde_json::Value {
    let out = composuite(args);
    assert!(
        out.status.success(),
        "composuite {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn split_json(args: &[&str]) -> (Vec<String>, Vec<String>) {
    let value = json_of(args);
    let object = value.as_object().unwrap();
    assert_eq!(object.keys().collect::<Vec<_>>(), ["test", "train"]);
    let list = |key: &str| -> Vec<String> {
        value[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t.as_str().unwrap().to_string())
            .collect()
    };
    (list("train"), list("test"))
}

/// Pinned with CPython 3.11.7 running the reference algorithm (see
/// tests/py/test_splits_reference.py, which checks many more seeds against this binary).
#[test]
fn split_json_is_train_and_test_in_wire_names() {
    let out = composuite(&[
        "tasks",
        "--split",
        "default",
        "--num-train",
        "2",
        "--seed",
        "42",
        "--json",
    ]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.starts_with("{\"train\":[\"Panda/plate/object_door/shelf\","),
        "{text}"
    );
    let (train, test) = split_json(&[
        "tasks",
        "--split",
        "default",
        "--num-train",
        "5",
        "--seed",
        "42",
        "--json",
    ]);
    assert_eq!(
        train,
        [
            "Panda/plate/object_door/shelf",
            "IIWA/box/object_door/push",
            "Jaco/plate/goal_wall/trash_can",
            "IIWA/hollow_box/object_wall/pick_place",
            "IIWA/box/goal_wall/push",
        ]
    );
    assert_eq!(test.len(), 251);
}

#[test]
fn holdout_split_accepts_reference_spellings_and_ends_train_with_the_element() {
    let (train, test) = split_json(&[
        "tasks",
        "--split",
        "holdout",
        "--num-train",
        "4",
        "--element",
        "ObjectWall",
        "--seed",
        "7",
        "--json",
    ]);
    assert_eq!(
        train,
        [
            "Jaco/plate/object_door/shelf",
            "Gen3/hollow_box/no_obstacle/shelf",
            "Gen3/hollow_box/object_door/shelf",
            "Panda/hollow_box/object_wall/shelf",
        ]
    );
    assert_eq!(test.len(), 63);
    assert!(test.iter().all(|t| t.contains("/object_wall/")));
    let wire = split_json(&[
        "tasks",
        "--split",
        "holdout",
        "--num-train",
        "4",
        "--element",
        "object_wall",
        "--seed",
        "7",
        "--json",
    ]);
    assert_eq!(wire, (train, test));
}

#[test]
fn smallscale_no_shuffle_is_the_reference_order() {
    let (train, test) = split_json(&[
        "tasks",
        "--split",
        "smallscale",
        "--num-train",
        "2",
        "--element",
        "plate",
        "--no-shuffle",
        "--json",
    ]);
    assert_eq!(
        train,
        [
            "IIWA/plate/no_obstacle/pick_place",
            "IIWA/plate/no_obstacle/push"
        ]
    );
    assert_eq!(test.len(), 62);
    assert_eq!(test[0], "IIWA/plate/no_obstacle/shelf");
}

#[test]
fn split_human_output_has_both_lists_with_counts() {
    let out = composuite(&[
        "tasks",
        "--split",
        "smallscale",
        "--num-train",
        "3",
        "--element",
        "Jaco",
        "--seed",
        "1",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "train (3 task(s)):");
    assert_eq!(lines[4], "test (61 task(s)):");
    assert_eq!(lines.len(), 2 + 64);
    assert!(
        lines[1..4].iter().all(|l| l.starts_with("  Jaco/")),
        "{text}"
    );
}

#[test]
fn split_errors_say_what_is_valid() {
    let cases: [(&[&str], &str); 6] = [
        (
            &["--split", "uniform", "--num-train", "1", "--seed", "0"],
            "unknown split \"uniform\"; valid: default, smallscale, holdout",
        ),
        (
            &["--split", "default", "--num-train", "257", "--seed", "0"],
            "num_train 257 is out of range for the default split; valid: 0 to 256",
        ),
        (
            &[
                "--split",
                "holdout",
                "--num-train",
                "0",
                "--element",
                "Jaco",
                "--seed",
                "0",
            ],
            "valid: 1 to 193",
        ),
        (
            &["--split", "holdout", "--num-train", "3", "--seed", "0"],
            "the holdout split needs an element; valid: robot IIWA, Jaco, Gen3, Panda;",
        ),
        (
            &[
                "--split",
                "smallscale",
                "--num-train",
                "3",
                "--element",
                "sphere",
                "--seed",
                "0",
            ],
            "unknown element \"sphere\"; valid: robot IIWA",
        ),
        (
            &["--split", "default", "--num-train", "3"],
            "--split default needs --seed S",
        ),
    ];
    for (args, expected) in cases {
        let out = composuite(&[&["tasks"], args].concat());
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn split_options_need_split_and_exclude_filters() {
    for args in [
        &["tasks", "--seed", "3"][..],
        &[
            "tasks",
            "--split",
            "default",
            "--num-train",
            "1",
            "--seed",
            "0",
            "--robot",
            "IIWA",
        ],
    ] {
        let out = composuite(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn help_shows_a_split_example() {
    let out = composuite(&["tasks", "--help"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("composuite tasks --split default --num-train 56 --seed 42"),
        "{text}"
    );
    assert!(text.contains("--element <E>"), "{text}");
}

#[test]
fn bench_reports_each_task_as_json() {
    let rows = json_of(&[
        "bench",
        "--tasks",
        "Panda/box/no_obstacle/push",
        "Kinova3/Plate/None/Shelf",
        "--steps",
        "30",
        "--json",
    ]);
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[1]["task"], "Gen3/plate/no_obstacle/shelf");
    for row in rows {
        assert!(row["steps_per_s"].as_f64().unwrap() > 0.0);
        assert!(row["reset_us"].as_f64().unwrap() > 0.0);
        assert!(row["rss_mb"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn bench_runs_with_a_horizon_shorter_than_its_warm_up() {
    // The warm-up episode (20 steps) ends at a 5-step horizon instead of stepping past it.
    let rows = json_of(&[
        "bench",
        "--tasks",
        "IIWA/box/no_obstacle/pick_place",
        "--steps",
        "12",
        "--horizon",
        "5",
        "--json",
    ]);
    assert_eq!(rows.as_array().unwrap().len(), 1);
    assert!(rows[0]["steps_per_s"].as_f64().unwrap() > 0.0);
}

#[test]
fn bench_names_a_bad_task() {
    let out = composuite(&["bench", "--tasks", "IIWA/box/wall/push"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown obstacle \"wall\""));
}

#[test]
fn expert_writes_its_table_csv_and_heatmap() {
    let out_dir = std::env::temp_dir().join(format!("composuite-expert-{}", std::process::id()));
    let value = json_of(&[
        "expert",
        "--tasks",
        "IIWA/box/no_obstacle/pick_place",
        "Gen3/box/no_obstacle/trash_can",
        "--episodes",
        "1",
        "--out",
        out_dir.to_str().unwrap(),
        "--json",
    ]);
    let tasks = value["tasks"].as_array().unwrap();
    assert_eq!(tasks.len(), 2);
    assert_eq!(tasks[0]["task"], "IIWA/box/no_obstacle/pick_place");
    assert_eq!(
        tasks[0]["success_rate"], 1.0,
        "the expert solves this task on seed 0"
    );
    assert!(value["mean_success"].as_f64().unwrap() > 0.0);
    let csv = std::fs::read_to_string(out_dir.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3);
    assert!(csv.starts_with("task,robot,object,obstacle,objective,episodes,success_rate"));
    let png = std::fs::read(out_dir.join("success.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let summary = std::fs::read_to_string(out_dir.join("summary.txt")).unwrap();
    assert!(
        summary.contains("by objective: pick_place 1.00, trash_can"),
        "{summary}"
    );
    std::fs::remove_dir_all(out_dir).unwrap();
}

#[test]
fn the_planned_expert_runs_from_the_command_line() {
    let out_dir = std::env::temp_dir().join(format!("composuite-planned-{}", std::process::id()));
    let value = json_of(&[
        "expert",
        "--planned",
        "--tasks",
        "Jaco/hollow_box/no_obstacle/shelf",
        "--episodes",
        "1",
        "--out",
        out_dir.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(
        value["tasks"][0]["success_rate"], 1.0,
        "the planned expert solves this task on seed 0: {value}"
    );
    let (median, max) = (
        value["expert_seconds_median"].as_f64().unwrap(),
        value["expert_seconds_max"].as_f64().unwrap(),
    );
    assert!(median > 0.0 && median <= max, "{value}");
    let summary = std::fs::read_to_string(out_dir.join("summary.txt")).unwrap();
    assert!(
        summary.contains("expert time per episode (choosing actions, planning included): median"),
        "{summary}"
    );
    std::fs::remove_dir_all(out_dir).unwrap();
}

#[test]
fn expert_refuses_an_empty_selection() {
    let out = composuite(&[
        "expert",
        "--tasks",
        "IIWA/box/no_obstacle/push",
        "--objective",
        "shelf",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no task matches"));
}
