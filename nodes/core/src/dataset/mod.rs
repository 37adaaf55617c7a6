//! Offline datasets' rows: episodes played by a policy that acts in the reference's action space
//! (the 8 numbers an agent has), recorded the way CompoSuite's offline benchmark stores them, and
//! the same episodes played again from their seeds and stored actions.
//!
//! Row `t` of an episode holds the observation before step `t`, the action of step `t` (as the
//! `f32` values a file stores; the environment is stepped with exactly those values), and the
//! reward and flags of step `t`: `terminal` where the objective ended the episode (Push: the
//! object lifted), `timeout` where the horizon did — or where the caller's row budget ran out
//! inside the episode (a file of N rows ends its last episode there). `success` is the step's
//! success test, which holds exactly where the reward is 1.
//!
//! ```
//! use composuite_core::dataset::{Collector, DatasetPolicy};
//! use composuite_core::env::EnvConfig;
//! let task = "IIWA/box/no_obstacle/push".parse().unwrap();
//! let mut collector =
//!     Collector::new(task, EnvConfig::default().horizon(20), DatasetPolicy::Random, 0, 1).unwrap();
//! let chunk = collector.collect(2, 30).unwrap();
//! assert_eq!(chunk.rows.len(), 30);              // 20 rows, then 10 of the second episode
//! assert_eq!(chunk.episodes.len(), 2);
//! assert_eq!(chunk.rows.timeouts[29], 1);        // cut by the row budget: a timeout
//! ```

mod collector;
mod policy;
mod rows;
#[cfg(test)]
mod test;

pub use collector::{
    Chunk, CollectError, Collector, EpisodeStart, Played, play_episode, replay_episode,
    replay_episodes,
};
pub use policy::{ActionSource, DatasetPolicy, ExpertActions, RandomActions, StoredActions};
pub use rows::{ACTION_SIZE, Rows};
