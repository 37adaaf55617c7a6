//! What the planned expert's survey examples share: tasks × seeds from the command line, and
//! one episode per (task, seed) run on a pool of threads.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use composuite_core::{TaskSpec, all_tasks};

/// The episodes asked for, the threads to run them on, and the switches given.
pub struct Episodes {
    pub jobs: Vec<(TaskSpec, u64)>,
    pub threads: usize,
    // Read by the examples that take switches only.
    #[allow(dead_code)]
    pub switches: Vec<String>,
}

/// `[--seeds N] [--first S] [--threads T] [SWITCH...] [TASK...]` (every task when none is
/// named, seeds `S..S+N`, default one seed from 0 on all cores); `switches` are the `--x`
/// arguments without a value the example takes.
pub fn from_args(switches: &[&str]) -> Episodes {
    let (mut seeds, mut first) = (1u64, 0u64);
    let mut threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (mut names, mut given) = (Vec::new(), Vec::new());
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = |flag: &str| -> u64 {
            let v = args
                .next()
                .unwrap_or_else(|| panic!("{flag} needs a number"));
            v.parse()
                .unwrap_or_else(|_| panic!("{flag} {v}: not a number"))
        };
        match arg.as_str() {
            "--seeds" => seeds = value("--seeds"),
            "--first" => first = value("--first"),
            "--threads" => threads = value("--threads") as usize,
            s if switches.contains(&s) => given.push(arg),
            s if s.starts_with("--") => {
                panic!("{s}: not an option (--seeds, --first, --threads, {switches:?})")
            }
            _ => names.push(arg),
        }
    }
    let tasks: Vec<TaskSpec> = if names.is_empty() {
        all_tasks()
    } else {
        names
            .iter()
            .map(|n| n.parse().unwrap_or_else(|e| panic!("{n}: {e}")))
            .collect()
    };
    Episodes {
        jobs: tasks
            .iter()
            .flat_map(|&t| (first..first + seeds).map(move |s| (t, s)))
            .collect(),
        threads: threads.max(1),
        switches: given,
    }
}

impl Episodes {
    /// `run` on every (task, seed), on the threads; the results sorted by task name and seed.
    pub fn run<R: Send>(&self, run: impl Fn(TaskSpec, u64) -> R + Sync) -> Vec<(TaskSpec, u64, R)> {
        let next = AtomicUsize::new(0);
        let results = Mutex::new(Vec::new());
        std::thread::scope(|scope| {
            for _ in 0..self.threads {
                scope.spawn(|| {
                    while let Some(&(task, seed)) =
                        self.jobs.get(next.fetch_add(1, Ordering::Relaxed))
                    {
                        let result = run(task, seed);
                        results.lock().unwrap().push((task, seed, result));
                    }
                });
            }
        });
        let mut results = results.into_inner().unwrap();
        results.sort_by_cached_key(|(task, seed, _)| (task.to_string(), *seed));
        results
    }
}
