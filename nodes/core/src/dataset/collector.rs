//! Playing dataset episodes: one at a time ([`play_episode`], [`replay_episode`]) or many in
//! parallel on a thread pool ([`Collector`], [`replay_episodes`]).

use std::fmt;

use crate::TaskSpec;
use crate::batch::{BatchBuildError, StepPool};
use crate::env::{Action, Env, EnvConfig, EnvError, MAX_SEED, sample_object_start};
use crate::obs::flat_size;

use super::policy::{ActionSource, DatasetPolicy, StoredActions};
use super::rows::Rows;

/// Episodes a collector plays at once per thread: more than one, so a thread that finishes a
/// short episode (Push ends early) takes another instead of waiting for the round to end.
const EPISODES_PER_THREAD: usize = 4;

/// Why episodes could not be collected.
#[derive(Debug, Clone, PartialEq)]
pub enum CollectError {
    /// The thread pool could not be built.
    Build(BatchBuildError),
    /// The next seed is past the largest the reference's seeding takes.
    SeedsExhausted {
        /// The seed that would have been next.
        next: u64,
    },
    /// The environment refused a step (a bug: the policies' actions are always valid).
    Env {
        /// The episode's seed.
        seed: u64,
        /// What was refused.
        error: EnvError,
    },
}

impl fmt::Display for CollectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CollectError::Build(e) => write!(f, "{e}"),
            CollectError::SeedsExhausted { next } => write!(
                f,
                "no seeds left: the next episode's seed would be {next}, past the largest \
                 ({MAX_SEED}); start from a smaller first seed"
            ),
            CollectError::Env { seed, error } => write!(f, "episode with seed {seed}: {error}"),
        }
    }
}

impl std::error::Error for CollectError {}

/// Where an episode starts in a [`Chunk`], and the seed `Env::reset` started it with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EpisodeStart {
    /// Its first row.
    pub row: usize,
    /// Its seed.
    pub seed: u64,
}

/// Whole episodes (the last one possibly cut by the row budget), in seed order.
#[derive(Debug, Clone, PartialEq)]
pub struct Chunk {
    /// Their rows, one episode after another.
    pub rows: Rows,
    /// Where each starts.
    pub episodes: Vec<EpisodeStart>,
    /// The observation after each one's last step, one row of `rows.observation_size` each.
    pub final_observations: Vec<f32>,
}

/// Plays episodes of one task with one policy, seed after seed, on a thread pool. Episode
/// `k` is started with the `k`-th seed from `first_seed` on that the task can start with
/// (seeds whose start the reference's sampler cannot place are skipped, as the reference would
/// fail them); the rows do not depend on the number of threads.
pub struct Collector {
    task: TaskSpec,
    policy: DatasetPolicy,
    envs: Vec<Env>,
    pool: StepPool,
    next_seed: u64,
}

impl Collector {
    /// A collector of `task`'s episodes under `config` (its horizon ends episodes), playing
    /// `policy`, starting at seed `first_seed`, on `threads` threads (the caller is one).
    pub fn new(
        task: TaskSpec,
        config: EnvConfig,
        policy: DatasetPolicy,
        first_seed: u64,
        threads: usize,
    ) -> Result<Collector, CollectError> {
        if threads == 0 {
            return Err(CollectError::Build(BatchBuildError::NoThreads));
        }
        let pool = StepPool::new(threads - 1).map_err(CollectError::Build)?;
        let envs = (0..threads * EPISODES_PER_THREAD)
            .map(|_| Env::new(task, config.clone()))
            .collect();
        Ok(Collector {
            task,
            policy,
            envs,
            pool,
            next_seed: first_seed,
        })
    }

    /// The seed the next episode will be started with (or a seed the task skips before it).
    pub fn next_seed(&self) -> u64 {
        self.next_seed
    }

    /// Play up to `max_episodes` more episodes, stopping once `max_rows` rows are reached; an
    /// episode still running at the budget's last row ends there as a timeout.
    pub fn collect(&mut self, max_episodes: usize, max_rows: usize) -> Result<Chunk, CollectError> {
        let size = self.envs[0].config().task_observation;
        let mut chunk = Chunk {
            rows: Rows::new(flat_size(size)),
            episodes: Vec::new(),
            final_observations: Vec::new(),
        };
        while chunk.episodes.len() < max_episodes && chunk.rows.len() < max_rows {
            let round = (max_episodes - chunk.episodes.len()).min(self.envs.len());
            let budget = max_rows - chunk.rows.len();
            for (seed, played) in self.play_round(round, |env, seed, source| {
                play_episode(env, seed, budget, source)
            })? {
                let left = max_rows - chunk.rows.len();
                chunk.episodes.push(EpisodeStart {
                    row: chunk.rows.len(),
                    seed,
                });
                // Where the budget ends inside (or exactly at the end of) this episode, keep its
                // first `left` rows — what playing with that budget gives — and hand the seeds
                // after it back, unplayed.
                let budget_ends = played.rows.len() >= left;
                let (rows, final_observation) = cut(played, left);
                chunk.rows.append(&rows);
                chunk
                    .final_observations
                    .extend_from_slice(&final_observation);
                if budget_ends {
                    self.next_seed = seed + 1;
                    return Ok(chunk);
                }
            }
        }
        Ok(chunk)
    }

    /// Play `episodes` more episodes only as far as their first successful step (or their end,
    /// without one): whether each succeeded, in seed order, with no rows kept. The same seeds
    /// and actions as [`Collector::collect`] would play, so an episode succeeds here exactly
    /// where its rows would hold a success; a calibration counting successes needs no more.
    pub fn successes(&mut self, episodes: usize) -> Result<Vec<bool>, CollectError> {
        let mut won = Vec::with_capacity(episodes);
        while won.len() < episodes {
            let round = (episodes - won.len()).min(self.envs.len());
            let played = self.play_round(round, play_until_success)?;
            won.extend(played.into_iter().map(|(_, succeeded)| succeeded));
        }
        Ok(won)
    }

    /// Play the next `n` seeds the task can start with, each by `play` in an environment of its
    /// own on the pool: `(seed, what play gave)`, in seed order.
    fn play_round<T: Send>(
        &mut self,
        n: usize,
        play: impl Fn(&mut Env, u64, &mut dyn ActionSource) -> Result<T, EnvError> + Sync,
    ) -> Result<Vec<(u64, T)>, CollectError> {
        let seeds = self.take_seeds(n)?;
        let (task, policy) = (self.task, self.policy);
        let mut slots: Vec<Slot<'_, T>> = self
            .envs
            .iter_mut()
            .zip(&seeds)
            .map(|(env, &seed)| (env, seed, None))
            .collect();
        self.pool.for_each(&mut slots, |_, (env, seed, outcome)| {
            let mut source = policy.source(task, *seed);
            *outcome = Some(play(env, *seed, source.as_mut()));
        });
        slots
            .into_iter()
            .map(|(_, seed, outcome)| {
                let outcome = outcome.expect("every slot is played");
                outcome
                    .map(|value| (seed, value))
                    .map_err(|error| CollectError::Env { seed, error })
            })
            .collect()
    }

    /// The next `n` seeds the task can start with.
    fn take_seeds(&mut self, n: usize) -> Result<Vec<u64>, CollectError> {
        let mut seeds = Vec::with_capacity(n);
        while seeds.len() < n {
            let seed = self.next_seed;
            match sample_object_start(self.task.obstacle, self.task.object, seed) {
                Ok(_) => seeds.push(seed),
                Err(EnvError::NoClearStart { .. }) => {}
                Err(_) => return Err(CollectError::SeedsExhausted { next: seed }),
            }
            self.next_seed = seed + 1;
        }
        Ok(seeds)
    }
}

/// One episode of a round: the environment that plays it, its seed, and what it gave.
type Slot<'a, T> = (&'a mut Env, u64, Option<Result<T, EnvError>>);

/// The first `n` rows of an episode, the last flagged a timeout unless the episode ended there,
/// and the observation after row `n − 1`'s step (row `n`'s observation).
fn cut(played: Played, n: usize) -> (Rows, Vec<f32>) {
    let Played {
        mut rows,
        final_observation,
    } = played;
    if rows.len() <= n {
        return (rows, final_observation);
    }
    let size = rows.observation_size;
    let next = rows.observations[n * size..(n + 1) * size].to_vec();
    rows.truncate(n);
    rows.timeouts[n - 1] = 1;
    (rows, next)
}

/// One played episode: its rows, and the observation after its last step (which no row holds:
/// row t's next state is row t+1's observation).
#[derive(Debug, Clone, PartialEq)]
pub struct Played {
    /// The rows.
    pub rows: Rows,
    /// The observation after the last step (the start's, with no rows).
    pub final_observation: Vec<f32>,
}

/// Play one episode of `env`'s task from `seed` with `source`'s actions, at most `max_rows`
/// steps; a step that reaches `max_rows` before the episode ends is flagged a timeout.
pub fn play_episode(
    env: &mut Env,
    seed: u64,
    max_rows: usize,
    source: &mut dyn ActionSource,
) -> Result<Played, EnvError> {
    let mut rows = Rows::new(flat_size(env.config().task_observation));
    let mut observation = env.reset(seed)?.flat();
    while rows.len() < max_rows {
        let action = source.action(env);
        let step = env.step(&Action::Reference(action.map(f64::from)))?;
        let budget_ends = rows.len() + 1 == max_rows;
        let timeout = step.truncated || (budget_ends && !step.terminated);
        rows.push(
            &observation,
            &action,
            step.reward,
            (step.terminated, timeout, step.info.success),
        );
        observation = step.observation.flat();
        if step.terminated || step.truncated {
            break;
        }
    }
    Ok(Played {
        rows,
        final_observation: observation.iter().map(|&v| v as f32).collect(),
    })
}

/// Play an episode of `env`'s task from `seed` with `source`'s actions until a step succeeds
/// (true) or the episode ends (false).
fn play_until_success(
    env: &mut Env,
    seed: u64,
    source: &mut dyn ActionSource,
) -> Result<bool, EnvError> {
    env.reset(seed)?;
    loop {
        let action = source.action(env);
        let step = env.step(&Action::Reference(action.map(f64::from)))?;
        if step.info.success {
            return Ok(true);
        }
        if step.terminated || step.truncated {
            return Ok(false);
        }
    }
}

/// Play a stored episode again: `env`'s task from `seed`, stepped with `actions` (rows of 8).
/// Stops where the environment ends the episode or the actions run out, whichever is first, so
/// the rows compare with the stored ones row for row (fewer rows when the episode ended early;
/// the final observation is the one after the last step replayed).
pub fn replay_episode(env: &mut Env, seed: u64, actions: &[f32]) -> Result<Played, EnvError> {
    let mut source = StoredActions::new(actions);
    let n = source.remaining();
    play_episode(env, seed, n, &mut source)
}

/// [`replay_episode`] for many episodes of one task in parallel on `threads` threads, in order.
pub fn replay_episodes(
    task: TaskSpec,
    config: &EnvConfig,
    episodes: &[(u64, &[f32])],
    threads: usize,
) -> Result<Vec<Result<Played, EnvError>>, CollectError> {
    if threads == 0 {
        return Err(CollectError::Build(BatchBuildError::NoThreads));
    }
    let pool = StepPool::new(threads - 1).map_err(CollectError::Build)?;
    let mut slots: Vec<Option<Result<Played, EnvError>>> = vec![None; episodes.len()];
    pool.for_each(&mut slots, |index, replayed| {
        let (seed, actions) = episodes[index];
        let mut env = Env::new(task, config.clone());
        *replayed = Some(replay_episode(&mut env, seed, actions));
    });
    Ok(slots
        .into_iter()
        .map(|r| r.expect("every episode is replayed"))
        .collect())
}
