//! Contact-rich behaviour against the reference: the port's scripted expert's plan for a task and
//! seed (joint targets and gripper commands per control step) played in both engines through the
//! reference's own controller, slowed down 4× (that controller moves a joint at most ~0.2 rad/s:
//! kp·0.05 rad / kd), each side closing the loop on its own observation
//! (`tests/reference/mod.rs`, `tracking_action`). The arms then follow the same path; what
//! differs is how each engine's contacts grasp, carry, push and release the object.
//!
//! `cargo run --release -p composuite_core --example reference_grasp` prints the comparison
//! with the reference's recorded runs (`tests/reference/data/grasp.json.gz`, written by
//! `scripts/reference-data --only grasp`).
//!
//! `... --example reference_grasp -- --write-plans` writes the plans the generator plays
//! (`tests/reference/data/grasp_plans.json.gz`, or `$COMPOSUITE_REFERENCE_DATA`): run it only to
//! change the task list; the committed plans are what both sides play.

#[path = "../tests/reference/mod.rs"]
mod reference;

use std::io::Write;

use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::expert::Expert;
use serde_json::json;

/// Every robot, object, obstacle and objective at least twice.
const TASKS: [&str; 12] = [
    "IIWA/box/no_obstacle/pick_place",
    "IIWA/hollow_box/goal_wall/pick_place",
    "IIWA/dumbbell/no_obstacle/trash_can",
    "Jaco/hollow_box/no_obstacle/trash_can",
    "Jaco/plate/no_obstacle/push",
    "Jaco/dumbbell/object_wall/shelf",
    "Gen3/box/goal_wall/push",
    "Gen3/plate/no_obstacle/shelf",
    "Gen3/hollow_box/object_door/push",
    "Panda/dumbbell/no_obstacle/pick_place",
    "Panda/box/object_door/shelf",
    "Panda/plate/object_wall/trash_can",
];
const SEEDS: [u64; 2] = [0, 1];
/// Control steps each plan step is held for.
const HOLD: usize = 4;
/// A commanded opening below this (m) is a grasp: gripper action +1 (close), else −1 (open).
const CLOSED_BELOW: f64 = 0.02;

fn main() {
    if std::env::args().any(|a| a == "--write-plans") {
        write_plans();
    } else {
        compare();
    }
}

/// The expert's absolute commands of one episode, as (joint targets, gripper action) per step.
fn expert_plan(task: TaskSpec, seed: u64) -> (Vec<[f64; 7]>, Vec<f64>) {
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    let mut expert = Expert::new(task);
    let (mut targets, mut gripper, mut closing) = (Vec::new(), Vec::new(), -1.0);
    while env.ended().is_none() {
        let action = expert.act(&env);
        let Action::Absolute { joints, gripper: g } = &action else {
            unreachable!("the expert commands absolute joint targets")
        };
        if let Some((opening, _)) = g {
            closing = if *opening < CLOSED_BELOW { 1.0 } else { -1.0 };
        }
        targets.push(joints.map(|q| (q * 1e6).round() / 1e6));
        gripper.push(closing);
        env.step(&action).expect("step");
    }
    (targets, gripper)
}

fn write_plans() {
    let mut episodes = Vec::new();
    for name in TASKS {
        let task: TaskSpec = name.parse().expect("a task");
        for seed in SEEDS {
            let (targets, gripper) = expert_plan(task, seed);
            eprintln!("{name} seed {seed}: {} plan steps", targets.len());
            episodes
                .push(json!({"name": name, "seed": seed, "targets": targets, "gripper": gripper}));
        }
    }
    let payload = json!({
        "meta": {
            "what": "the port's scripted expert's joint targets (rad, rounded to 1e-6) and gripper \
                     actions (+1 close when the commanded opening is below 2 cm, else -1) per \
                     control step of one episode (default config, absolute mode)",
            "hold": HOLD,
            "law": "each plan step is held for `hold` control steps; every control step the action \
                    is a[j] = clip(wrap(target[j] - q[j]) / 0.05, -1, 1) for the 7 joints, q from \
                    the observation's joint cos/sin (atan2), wrap to [-pi, pi), and a[7] = gripper",
            "horizon": "len(targets) * hold control steps, or until Push's lift rule ends the episode",
        },
        "episodes": episodes,
    });
    let path = reference::data_dir().join("grasp_plans.json.gz");
    let file = std::fs::File::create(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut gz = flate2::write::GzEncoder::new(file, flate2::Compression::best());
    gz.write_all(payload.to_string().as_bytes()).expect("write");
    gz.finish().expect("write");
    eprintln!("wrote {}", path.display());
}

fn compare() {
    let plans = reference::grasp_plans();
    let runs = reference::grasp_runs();
    println!(
        "| task | seed | success step, reference | ours | grasped share, reference | ours | \
         grasp flags equal | object Δ, median (mm) | at the end (mm) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let (mut samples, mut samples_equal, mut alike, mut steps_apart) = (0, 0, 0, Vec::new());
    for (plan, (task, seed, theirs)) in plans.iter().zip(&runs) {
        assert_eq!(
            (plan.task, plan.seed),
            (*task, *seed),
            "plans and runs in one order"
        );
        let ours = plan.ours();
        let (n, equal) = ours.grasp_flags_equal(theirs);
        samples += n;
        samples_equal += equal;
        alike += usize::from(ours.first_success.is_some() == theirs.first_success.is_some());
        if let (Some(o), Some(t)) = (ours.first_success, theirs.first_success) {
            steps_apart.push(o.abs_diff(t));
        }
        let gaps = ours.sorted_object_gaps(theirs);
        let end = (ours.object_position.last(), theirs.object_position.last());
        let end = match end {
            (Some(a), Some(b)) => {
                1e3 * (nalgebra::Point3::from(*a) - nalgebra::Point3::from(*b)).norm()
            }
            _ => f64::NAN,
        };
        let step = |s: Option<usize>| s.map_or("—".to_string(), |s| s.to_string());
        println!(
            "| {task} | {seed} | {} | {} | {:.2} | {:.2} | {:.0} % | {:.1} | {:.1} |",
            step(theirs.first_success),
            step(ours.first_success),
            theirs.grasp_share(),
            ours.grasp_share(),
            100.0 * equal as f64 / n.max(1) as f64,
            1e3 * gaps.get(gaps.len() / 2).copied().unwrap_or(f64::NAN),
            end,
        );
    }
    steps_apart.sort();
    println!(
        "\n{alike} of {} episodes end alike; first successes {:?} control steps apart; grasp flags \
         equal at {:.1} % of {samples} samples",
        plans.len(),
        steps_apart,
        100.0 * samples_equal as f64 / samples.max(1) as f64
    );
}
