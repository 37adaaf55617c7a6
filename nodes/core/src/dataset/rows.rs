//! Columns of dataset rows, as the offline benchmark's files hold them.

/// Values in one action row: 7 joint-goal deltas (units of 0.05 rad), then the gripper.
pub const ACTION_SIZE: usize = 8;

/// Rows in columns: `observations` is `len × observation_size`, `actions` `len × 8`; the flag
/// columns hold 0 or 1 (the files' `uint8`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Rows {
    /// Values in one observation row (93 with the task one-hots, 77 without).
    pub observation_size: usize,
    /// The observation before each step.
    pub observations: Vec<f32>,
    /// The action of each step, exactly as the environment was stepped with it.
    pub actions: Vec<f32>,
    /// The step's reward.
    pub rewards: Vec<f32>,
    /// The objective ended the episode at this step.
    pub terminals: Vec<u8>,
    /// The horizon (or the row budget) ended the episode at this step.
    pub timeouts: Vec<u8>,
    /// The step's success test held.
    pub successes: Vec<u8>,
}

impl Rows {
    /// No rows yet, each observation `observation_size` wide.
    pub fn new(observation_size: usize) -> Rows {
        Rows {
            observation_size,
            ..Rows::default()
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rewards.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.rewards.is_empty()
    }

    /// Append `other`'s rows after these.
    ///
    /// # Panics
    /// If the observation sizes differ.
    pub fn append(&mut self, other: &Rows) {
        assert_eq!(self.observation_size, other.observation_size);
        self.observations.extend_from_slice(&other.observations);
        self.actions.extend_from_slice(&other.actions);
        self.rewards.extend_from_slice(&other.rewards);
        self.terminals.extend_from_slice(&other.terminals);
        self.timeouts.extend_from_slice(&other.timeouts);
        self.successes.extend_from_slice(&other.successes);
    }

    /// Keep the first `n` rows (all of them when there are fewer).
    pub fn truncate(&mut self, n: usize) {
        self.observations.truncate(n * self.observation_size);
        self.actions.truncate(n * ACTION_SIZE);
        self.rewards.truncate(n);
        self.terminals.truncate(n);
        self.timeouts.truncate(n);
        self.successes.truncate(n);
    }

    /// Add one row.
    pub(super) fn push(
        &mut self,
        observation: &[f64],
        action: &[f32; ACTION_SIZE],
        reward: f64,
        flags: (bool, bool, bool),
    ) {
        let (terminal, timeout, success) = flags;
        // The files store f32: the nearest value, as numpy's astype(float32) rounds.
        self.observations
            .extend(observation.iter().map(|&v| v as f32));
        self.actions.extend_from_slice(action);
        self.rewards.push(reward as f32);
        self.terminals.push(u8::from(terminal));
        self.timeouts.push(u8::from(timeout));
        self.successes.push(u8::from(success));
    }
}
