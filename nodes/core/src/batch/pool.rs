//! The threads that step environments: one pool, used two ways.
//!
//! - A batch ([`EnvBatch`](super::EnvBatch), the Python vector env) hands the pool every
//!   environment at once ([`StepPool::for_each`]) and works on them itself meanwhile: a batch of
//!   `threads` threads is its caller and `threads − 1` workers.
//! - The composed node suite's sims each hand over their own environment's step from their
//!   node's thread ([`StepPool::run`]) whenever their lockstep chain asks for one, and wait for
//!   it. Such jobs wait in one queue and a free worker takes the oldest: a slow environment
//!   occupies one worker, never holds another environment's step, and no environment waits for
//!   the others to be ready (a queue, not a barrier). However many environments a process
//!   holds, their physics runs on its workers, so the cores are not shared out among dozens of
//!   busy threads. One exception: a job handed over while no other job is running or waiting
//!   runs at once on its caller's thread — an environment stepped alone skips the hand-over to
//!   a worker and back (two thread wake-ups per step). So at most one job runs outside the
//!   workers, and at most `workers + 1` at once.
//!
//! An environment's step does the same arithmetic on whichever thread runs it, so results do
//! not depend on the number of threads.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::BatchBuildError;

/// Worker threads stepping environments (see the module's documentation).
pub struct StepPool {
    /// `None` without workers: callers then do their jobs themselves.
    workers: Option<rayon::ThreadPool>,
    /// [`StepPool::run`] jobs running or waiting: a job that finds none runs on its caller.
    in_flight: AtomicUsize,
}

/// A pool without workers: every job runs on the thread that hands it over (a node that
/// steps its one environment itself).
impl Default for StepPool {
    fn default() -> StepPool {
        StepPool {
            workers: None,
            in_flight: AtomicUsize::new(0),
        }
    }
}

impl StepPool {
    /// A pool of `workers` threads; with 0, every job runs on the thread that hands it over.
    pub fn new(workers: usize) -> Result<StepPool, BatchBuildError> {
        let pool = match workers {
            0 => None,
            n => Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    // Short enough for a thread's 15-character name (`/proc/PID/task/*/comm`).
                    .thread_name(|i| format!("env-step-{i}"))
                    .build()
                    .map_err(|e| BatchBuildError::ThreadPool(e.to_string()))?,
            ),
        };
        Ok(StepPool {
            workers: pool,
            in_flight: AtomicUsize::new(0),
        })
    }

    /// Worker threads (callers not counted).
    pub fn workers(&self) -> usize {
        self.workers
            .as_ref()
            .map_or(0, rayon::ThreadPool::current_num_threads)
    }

    /// Run `job` on a worker and return what it gives; the calling thread (outside the pool)
    /// waits for it. Jobs of many callers queue up and are taken oldest first by whichever
    /// worker is free. A job that finds no other job running or waiting, and every job of a
    /// pool without workers, runs on the calling thread instead. A panic in `job` is raised
    /// again in the caller.
    pub fn run<R: Send>(&self, job: impl FnOnce() -> R + Send) -> R {
        let Some(workers) = &self.workers else {
            return job();
        };
        // Counted until the job ends, also when it panics.
        let counted = InFlight::enter(&self.in_flight);
        if counted.first {
            job()
        } else {
            workers.install(job)
        }
    }

    /// Call `work(i, &mut items[i])` once for every item, in parallel: the caller's thread and
    /// every worker take items one at a time from a shared counter, so a slow item holds only
    /// the thread working on it and the others take the rest. The caller works rather than
    /// waits: with as many threads as cores, no core idles while a blocked caller and busy
    /// workers share them. Returns when every item is done.
    pub fn for_each<T: Send>(&self, items: &mut [T], work: impl Fn(usize, &mut T) + Sync) {
        let Some(workers) = &self.workers else {
            for (index, item) in items.iter_mut().enumerate() {
                work(index, item);
            }
            return;
        };
        let next = AtomicUsize::new(0);
        // The counter hands out each index once, so every lock is taken by one thread only:
        // they are never contended, they only make the hand-over safe.
        let slots: Vec<Mutex<&mut T>> = items.iter_mut().map(Mutex::new).collect();
        let take_items = || {
            loop {
                let index = next.fetch_add(1, Ordering::Relaxed);
                let Some(slot) = slots.get(index) else { break };
                let mut item = slot.lock().expect("an item's work panicked");
                work(index, &mut item);
            }
        };
        workers.in_place_scope(|scope| {
            for _ in 0..workers.current_num_threads() {
                scope.spawn(|_| take_items());
            }
            take_items();
        });
    }
}

/// One [`StepPool::run`] job counted in flight while this lives.
struct InFlight<'a> {
    count: &'a AtomicUsize,
    /// No other job was running or waiting when this one came.
    first: bool,
}

impl<'a> InFlight<'a> {
    fn enter(count: &'a AtomicUsize) -> InFlight<'a> {
        let first = count.fetch_add(1, Ordering::AcqRel) == 0;
        InFlight { count, first }
    }
}

impl Drop for InFlight<'_> {
    fn drop(&mut self) {
        self.count.fetch_sub(1, Ordering::AcqRel);
    }
}

#[cfg(test)]
mod test {
    use std::sync::mpsc;
    use std::time::Duration;

    use super::*;
    use crate::env::{Action, Env, EnvConfig};

    /// Long enough that a pool which serialised its jobs would surely time out here, short
    /// enough that the test ends if it does.
    const PATIENCE: Duration = Duration::from_secs(20);

    // Two environments' chains on two threads: the first env's job runs until the second
    // env's job has run. A pool that let one job hold the others (one thread, or a barrier
    // waiting for both callers) would never run the second job and time out.
    #[test]
    fn a_long_job_does_not_hold_another_callers_job() {
        let pool = StepPool::new(2).unwrap();
        let (second_ran, wait_for_second) = mpsc::channel();
        let (first_started, wait_for_first) = mpsc::channel();
        std::thread::scope(|s| {
            let pool = &pool;
            let slow = s.spawn(move || {
                pool.run(move || {
                    first_started.send(()).unwrap();
                    wait_for_second.recv_timeout(PATIENCE)
                })
            });
            wait_for_first.recv_timeout(PATIENCE).unwrap();
            let quick = s.spawn(move || pool.run(move || second_ran.send(())));
            quick.join().unwrap().unwrap();
            assert_eq!(
                slow.join().unwrap(),
                Ok(()),
                "the second job ran while the first ran"
            );
        });
    }

    #[test]
    fn without_workers_the_caller_runs_its_job() {
        let caller = std::thread::current().id();
        for pool in [StepPool::new(0).unwrap(), StepPool::default()] {
            assert_eq!(pool.workers(), 0);
            assert_eq!(pool.run(|| std::thread::current().id()), caller);
        }
    }

    // Stepped alone, an environment's job runs where it was asked for: no hand-over.
    #[test]
    fn a_job_that_finds_no_other_runs_on_its_callers_thread() {
        let pool = StepPool::new(2).unwrap();
        let caller = std::thread::current().id();
        for _ in 0..3 {
            assert_eq!(pool.run(|| std::thread::current().id()), caller);
        }
    }

    // While one caller's job runs on its own thread, another caller's job goes to a worker.
    #[test]
    fn a_job_that_finds_another_running_goes_to_a_worker() {
        let pool = StepPool::new(1).unwrap();
        let (release, wait_for_release) = mpsc::channel::<()>();
        let (started, wait_for_start) = mpsc::channel();
        std::thread::scope(|s| {
            let pool = &pool;
            let first = s.spawn(move || {
                let caller = std::thread::current().id();
                pool.run(move || {
                    started.send(()).unwrap();
                    wait_for_release.recv_timeout(PATIENCE).unwrap();
                    std::thread::current().id() == caller
                })
            });
            wait_for_start.recv_timeout(PATIENCE).unwrap();
            let second = pool.run(|| std::thread::current().name().map(str::to_string));
            release.send(()).unwrap();
            assert!(
                first.join().unwrap(),
                "the first job ran on its caller's thread"
            );
            assert_eq!(second.as_deref(), Some("env-step-0"));
        });
    }

    // A job that panics is no longer counted: the next one again runs on its caller's thread.
    #[test]
    fn a_panicking_job_is_no_longer_counted() {
        let pool = StepPool::new(1).unwrap();
        let panicked =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| pool.run(|| panic!("boom"))));
        assert!(panicked.is_err());
        let caller = std::thread::current().id();
        assert_eq!(pool.run(|| std::thread::current().id()), caller);
    }

    #[test]
    fn for_each_visits_every_item_once() {
        for workers in [0, 2] {
            let pool = StepPool::new(workers).unwrap();
            let mut items = vec![0u32; 37];
            pool.for_each(&mut items, |index, item| *item += index as u32 + 1);
            assert_eq!(items, (1..=37).collect::<Vec<u32>>(), "{workers} workers");
        }
    }

    /// `job` run by `pool`, or on the caller's thread without one.
    fn on<R: Send>(pool: Option<&StepPool>, job: impl FnOnce() -> R + Send) -> R {
        match pool {
            Some(pool) => pool.run(job),
            None => job(),
        }
    }

    /// The bits of `steps` steps' observations and rewards of an environment (task and actions
    /// from `seed`), each reset and step run by `pool` (or on the caller's thread).
    fn trajectory_on(pool: Option<&StepPool>, seed: u64, steps: u32) -> Vec<u64> {
        let task = [
            "IIWA/box/no_obstacle/pick_place",
            "Jaco/plate/object_wall/shelf",
        ][seed as usize % 2]
            .parse()
            .unwrap();
        let mut env = Env::new(task, EnvConfig::default());
        let mut bits: Vec<u64> = Vec::new();
        let observation = on(pool, || env.reset(seed).unwrap());
        bits.extend(observation.flat().iter().map(|v| v.to_bits()));
        for step in 0..steps {
            let push = (step as f64 * 0.37 + seed as f64).sin();
            let action = Action::Reference([push, -push, 0.5 * push, 0.2, -0.3, push, 0.1, 1.0]);
            let result = on(pool, || env.step(&action).unwrap());
            bits.extend(result.observation.flat().iter().map(|v| v.to_bits()));
            bits.push(result.reward.to_bits());
        }
        bits
    }

    // Three environments stepped at once from three callers, on one worker and on three: every
    // trajectory is the one the environment gives stepped alone on the test's thread.
    #[test]
    fn trajectories_are_the_same_bits_on_one_thread_and_on_three() {
        let steps = 12;
        let alone: Vec<Vec<u64>> = (0..3)
            .map(|seed| trajectory_on(None, seed, steps))
            .collect();
        for workers in [1, 3] {
            let pool = StepPool::new(workers).unwrap();
            let together: Vec<Vec<u64>> = std::thread::scope(|s| {
                let callers: Vec<_> = (0..3)
                    .map(|seed| {
                        let pool = &pool;
                        s.spawn(move || trajectory_on(Some(pool), seed, steps))
                    })
                    .collect();
                callers.into_iter().map(|c| c.join().unwrap()).collect()
            });
            assert!(
                together == alone,
                "{workers} worker(s) changed a trajectory"
            );
        }
    }
}
