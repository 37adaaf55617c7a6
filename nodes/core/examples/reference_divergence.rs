//! How far the port drifts from the reference benchmark under the same actions: replays the 32
//! recorded reference episodes (`tests/reference/data/trajectories.json.gz`) and prints, per
//! objective and per object, the mean |Δ| of the joint angles, the grip site and the object
//! after 10, 30 and 100 steps, and the step-0 observation check over all 256 tasks × 5 seeds.
//!
//! `cargo run --release -p composuite_core --example reference_divergence [-- --list]`
//! (`--list`: every step-0 value that differs by more than 1e-4, on stderr).

#[path = "../tests/reference/mod.rs"]
mod reference;

use std::collections::BTreeMap;

use composuite_core::axes::AxisElement;
use composuite_core::env::EnvConfig;
use reference::{Divergence, divergence, layout};

const CHECKPOINTS: [usize; 3] = [10, 30, 100];

fn main() {
    let started = std::time::Instant::now();
    let trajectories = reference::trajectories();
    // key → per checkpoint (sum, count)
    let mut table: BTreeMap<String, [(Divergence, usize); 3]> = BTreeMap::new();
    for trajectory in &trajectories {
        let ours = trajectory.replay(EnvConfig::default()).observations;
        let task = trajectory.task;
        for key in [
            format!("objective {}", task.objective.wire_name()),
            format!("object {}", task.object.wire_name()),
            "all".to_string(),
        ] {
            let row = table.entry(key).or_default();
            for (slot, &step) in CHECKPOINTS.iter().enumerate() {
                if let (Some(a), Some(b)) = (ours.get(step), trajectory.observations.get(step)) {
                    let d = divergence(a, b);
                    let (sum, n) = &mut row[slot];
                    sum.joints += d.joints;
                    sum.eef += d.eef;
                    sum.object += d.object;
                    *n += 1;
                }
            }
        }
    }
    println!(
        "mean |Δ| after 10 / 30 / 100 steps of the same actions ({} reference episodes)",
        trajectories.len()
    );
    println!(
        "{:<22} {:>26} {:>26} {:>26}",
        "", "joints (mrad)", "grip site (mm)", "object (mm)"
    );
    for (key, row) in &table {
        let cell = |f: fn(&Divergence) -> f64, scale: f64| {
            row.iter()
                .map(|(sum, n)| format!("{:7.2}", scale * f(sum) / (*n).max(1) as f64))
                .collect::<Vec<_>>()
                .join(" ")
        };
        println!(
            "{key:<22} {:>26} {:>26} {:>26}",
            cell(|d| d.joints, 1e3),
            cell(|d| d.eef, 1e3),
            cell(|d| d.object, 1e3)
        );
    }

    if reference::data_dir().join("step0.json.gz").exists() {
        let cases = reference::step0();
        let list = std::env::args().any(|a| a == "--list");
        let mut worst_by_field: BTreeMap<&str, f64> = BTreeMap::new();
        let mut unequal = 0;
        let mut half_turns: BTreeMap<String, (usize, usize)> = BTreeMap::new();
        for case in &cases {
            let ours = case.ours();
            let mut any = false;
            for (i, (a, b)) in ours.iter().zip(&case.observation).enumerate() {
                let d = (a - b).abs();
                let worst = worst_by_field.entry(layout::field(i)).or_default();
                *worst = worst.max(d);
                any |= d > 1e-4;
                if d > 1e-4 && list {
                    eprintln!(
                        "{} seed {} [{i}] {} ours {a:.7} ref {b:.7}",
                        case.task,
                        case.seed,
                        layout::field(i)
                    );
                }
            }
            unequal += usize::from(any);
            // Half turns: the reference's w is 0 to 7 decimals, its sign comes from LAPACK.
            for block in layout::RELATIVE_QUATERNIONS {
                if case.observation[block.end - 1].abs() < 1e-6 {
                    let same = block
                        .clone()
                        .all(|i| (ours[i] - case.observation[i]).abs() <= 1e-4);
                    let key = format!(
                        "{} {}",
                        case.task.robot.wire_name(),
                        layout::field(block.start)
                    );
                    let (n, agree) = half_turns.entry(key).or_default();
                    *n += 1;
                    *agree += usize::from(same);
                }
            }
        }
        println!(
            "\nstep-0 observations: {unequal} of {} differ by more than 1e-4 somewhere",
            cases.len()
        );
        for (field, worst) in worst_by_field {
            println!("  {field:<22} worst |Δ| {worst:.2e}");
        }
        println!("half turns (reference |w| < 1e-6): cases, same sign as the reference");
        for (key, (n, agree)) in half_turns {
            println!("  {key:<36} {n:5} {agree:5}");
        }
    }
    println!("({:.1} s)", started.elapsed().as_secs_f64());
}
