//! The uniform random policy on the port against the reference benchmark: for each of the 16
//! tasks of `tests/reference/data/random_returns.json` (every element of every axis 4 times),
//! the reference's 10 episodes replayed with the very same seeds and actions (numpy's
//! `default_rng(1000 + e).uniform(-1, 1, 8)` per step, re-implemented bit for bit), and the mean
//! episode return, ours against the reference's, per task and per objective.
//!
//! `cargo run --release -p composuite_core --example reference_random_returns`

#[path = "../tests/reference/mod.rs"]
mod reference;

use std::collections::BTreeMap;

use composuite_core::axes::AxisElement;

/// Sums for a mean: (ours, reference, episodes, our successes, reference successes).
#[derive(Default)]
struct Sums {
    ours: f64,
    reference: f64,
    episodes: usize,
    our_successes: usize,
    reference_successes: usize,
}

impl Sums {
    fn row(&self, name: &str) -> String {
        let n = self.episodes as f64;
        let (ours, reference) = (self.ours / n, self.reference / n);
        format!(
            "| {name} | {} | {ours:.3} | {reference:.3} | {:+.1} % | {} / {} |",
            self.episodes,
            100.0 * (ours - reference) / reference,
            self.our_successes,
            self.reference_successes
        )
    }
}

fn main() {
    let started = std::time::Instant::now();
    let tasks = reference::random_returns();
    let mut by_task: Vec<(String, Sums)> = Vec::new();
    let mut by_objective: BTreeMap<&str, Sums> = BTreeMap::new();
    let mut all = Sums::default();
    let mut steps = 0u64;
    for t in &tasks {
        let mut sums = Sums::default();
        for e in &t.episodes {
            let (ours, success, length) = reference::random_episode(t.task, e);
            steps += length as u64;
            for s in [
                &mut sums,
                by_objective
                    .entry(t.task.objective.wire_name())
                    .or_default(),
                &mut all,
            ] {
                s.ours += ours;
                s.reference += e.episode_return;
                s.episodes += 1;
                s.our_successes += success as usize;
                s.reference_successes += e.success as usize;
            }
        }
        eprintln!("{}", sums.row(&t.task.to_string()));
        by_task.push((t.task.to_string(), sums));
    }
    let header = "| | episodes | mean return, ours | reference | difference | successes (ours / reference) |\n|---|---|---|---|---|---|";
    println!("{header}");
    for (name, sums) in &by_task {
        println!("{}", sums.row(name));
    }
    println!("\n{header}");
    for (objective, sums) in &by_objective {
        println!("{}", sums.row(objective));
    }
    println!("{}", all.row("all"));
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "\n{steps} steps in {seconds:.1} s ({:.0} steps/s, one core)",
        steps as f64 / seconds
    );
}
