//! Prints, per arm, its `robot_description` and the world pose of every URDF link after a few
//! steps (arm bent, gripper closing), as one JSON object per line: what an independent URDF
//! parser's forward kinematics is checked against (tests/py/test_urdf_visuals.py).
//!
//! ```text
//! cargo run -p composuite_core --example link_poses
//! ```
//! Fields: `robot`, `urdf` (text), `joints` (name → position, rad or m), `links`
//! (name → `[x, y, z, qw, qx, qy, qz]` in the world).

use composuite_core::axes::{AxisElement, Robot};
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::physics::robot_description;
use serde_json::{Map, Value, json};

fn main() {
    for robot in Robot::all() {
        let task = format!("{}/box/no_obstacle/pick_place", robot.wire_name());
        let mut env = Env::new(task.parse().expect("task"), EnvConfig::default());
        env.reset(0).expect("reset");
        for _ in 0..4 {
            env.step(&Action::Reference([
                0.8, -0.5, 0.6, 0.7, -0.9, 0.5, 1.0, 1.0,
            ]))
            .expect("step");
        }
        let world = env.world();
        let joints: Map<String, Value> = world
            .model
            .joints
            .iter()
            .enumerate()
            .map(|(j, joint)| (joint.name.clone(), json!(world.joint_position(j))))
            .collect();
        let mut names: Vec<&String> = world.model.links.keys().collect();
        names.sort();
        let links: Map<String, Value> = names
            .into_iter()
            .map(|name| {
                let pose = world.link_world_pose(name).expect("a model link");
                let t = pose.translation.vector;
                let q = pose.rotation.quaternion();
                (name.clone(), json!([t.x, t.y, t.z, q.w, q.i, q.j, q.k]))
            })
            .collect();
        let line = json!({
            "robot": robot.wire_name(),
            "urdf": robot_description(robot),
            "joints": joints,
            "links": links,
        });
        println!("{line}");
    }
}
