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
    let out = composuite(&["tasks", "--json"]);
    assert!(out.status.success());
    let value: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
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
    let out = composuite(&[
        "tasks",
        "--robot",
        "Kinova3",
        "--obstacle",
        "None",
        "--objective",
        "Trashcan",
        "--json",
    ]);
    assert!(out.status.success());
    let value: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
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
