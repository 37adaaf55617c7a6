//! A fingerprint of the planned expert's episodes, bit for bit, and the time it spent choosing
//! its actions: for each task and seed, every action's 8 numbers hashed by their bits. A change
//! meant to make the expert faster without changing what it does (its clearance checks, its
//! kinematics) must leave every digest as it was; the time says what it gained.
//!
//! ```text
//! cargo run --profile session -p composuite_core --example planned_digest -- [--seeds N] [--threads T] [TASK...]
//! ```
//! Default: every one of the 256 tasks, seed 0, on all cores. Prints one line per episode
//! (sorted), then the digest of all of them and the expert's total and median time; the five
//! episodes that took longest (expert and physics) go to standard error.

use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::expert::PlannedExpert;

#[path = "common/episodes.rs"]
mod episodes;

/// FNV-1a over the bytes of 64-bit words.
struct Digest(u64);

impl Digest {
    fn new() -> Digest {
        Digest(0xcbf2_9ce4_8422_2325)
    }

    fn add(&mut self, x: u64) {
        for byte in x.to_le_bytes() {
            self.0 = (self.0 ^ byte as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// One episode: the digest of its actions, whether it succeeded, the expert's seconds.
fn run(task: TaskSpec, seed: u64) -> (u64, bool, f64) {
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    let mut expert = PlannedExpert::new(task);
    let mut digest = Digest::new();
    let (mut success, mut seconds) = (false, 0.0);
    while env.ended().is_none() {
        let started = std::time::Instant::now();
        let action = expert.act(&env);
        seconds += started.elapsed().as_secs_f64();
        match action {
            Action::Reference(a) => a.iter().for_each(|x| digest.add(x.to_bits())),
            other => panic!("the planned expert acted with {other:?}"),
        }
        success |= env.step(&action).expect("step").info.success;
    }
    digest.add(success as u64);
    (digest.0, success, seconds)
}

fn main() {
    let episodes = episodes::from_args(&[]);
    let started = std::time::Instant::now();
    let mut results: Vec<_> = episodes
        .run(|task, seed| {
            let started = std::time::Instant::now();
            let (digest, success, seconds) = run(task, seed);
            (digest, success, seconds, started.elapsed().as_secs_f64())
        })
        .into_iter()
        .map(|(task, seed, (digest, success, seconds, wall))| {
            let line = format!("{task} seed {seed}: {digest:016x} success {success}");
            (line, digest, success, seconds, wall)
        })
        .collect();
    results.sort_by(|a, b| a.0.cmp(&b.0));
    let mut all = Digest::new();
    for (line, digest, _, _, _) in &results {
        println!("{line}");
        all.add(*digest);
    }
    // The episodes that took longest, whole (the expert and the physics).
    let mut slowest: Vec<_> = results.iter().collect();
    slowest.sort_by(|a, b| b.4.total_cmp(&a.4));
    for r in slowest.iter().take(5) {
        eprintln!("slow: {} — {:.1} s, expert {:.1} s", r.0, r.4, r.3);
    }
    let mut times: Vec<f64> = results.iter().map(|r| r.3).collect();
    times.sort_by(f64::total_cmp);
    let successes = results.iter().filter(|r| r.2).count();
    println!(
        "{} episodes, {successes} successes, digest {:016x}; expert time total {:.1} s, median {:.0} ms, max {:.0} ms; wall {:.1} s",
        results.len(),
        all.0,
        times.iter().sum::<f64>(),
        1e3 * times[times.len() / 2],
        1e3 * times[times.len() - 1],
        started.elapsed().as_secs_f64()
    );
}
