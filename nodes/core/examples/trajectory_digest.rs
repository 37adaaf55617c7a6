//! A fingerprint of whole trajectories, bit for bit: for each task, one episode from seed 0
//! driven by seeded random reference actions, and one by the scripted expert (stiff servos,
//! grasps), each observation's every `f64` hashed by its bits. Two builds whose physics give the
//! same digests step the same trajectories exactly; a change that only reorders floating-point
//! sums shows here first, and `reference_divergence` then says by how much.
//!
//! ```text
//! cargo run --release -p composuite_core --example trajectory_digest -- [STEPS] [TASK...]
//! ```
//! Default: 200 steps on the reference's four tasks and Panda/box/no_obstacle/pick_place.

use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::expert::Expert;
use rand::{Rng, SeedableRng};

const DEFAULT_TASKS: [&str; 5] = [
    "IIWA/box/no_obstacle/pick_place",
    "Jaco/dumbbell/object_door/shelf",
    "Panda/plate/goal_wall/trash_can",
    "Gen3/hollow_box/object_wall/push",
    "Panda/box/no_obstacle/pick_place",
];

/// FNV-1a over 64-bit words.
struct Digest(u64);

impl Digest {
    fn add(&mut self, x: f64) {
        for byte in x.to_bits().to_le_bytes() {
            self.0 = (self.0 ^ byte as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
}

fn run(task: TaskSpec, steps: u32, expert: bool) -> (u64, f64) {
    let mut env = Env::new(task, EnvConfig::default().horizon(steps));
    env.reset(0).expect("reset");
    let mut rng = rand::rngs::StdRng::seed_from_u64(0);
    let mut policy = Expert::new(task);
    let mut digest = Digest(0xcbf2_9ce4_8422_2325);
    while env.ended().is_none() {
        let action = if expert {
            policy.act(&env)
        } else {
            Action::Reference(std::array::from_fn(|_| rng.random_range(-1.0..1.0)))
        };
        let step = env.step(&action).expect("step");
        env.observation().flat().iter().for_each(|&x| digest.add(x));
        digest.add(step.reward);
    }
    (digest.0, env.episode_return())
}

fn main() {
    let mut args = std::env::args().skip(1).peekable();
    let steps: u32 = match args.peek().map(|a| a.parse()) {
        Some(Ok(n)) => {
            args.next();
            n
        }
        _ => 200,
    };
    let mut tasks: Vec<String> = args.collect();
    if tasks.is_empty() {
        tasks = DEFAULT_TASKS.iter().map(|t| t.to_string()).collect();
    }
    for name in tasks {
        let task: TaskSpec = name.parse().unwrap_or_else(|e| panic!("{name}: {e}"));
        let (random, random_return) = run(task, steps, false);
        let (scripted, scripted_return) = run(task, steps, true);
        println!(
            "{name:40} random {random:016x} (return {random_return:8.3})  expert {scripted:016x} (return {scripted_return:8.3})"
        );
    }
}
