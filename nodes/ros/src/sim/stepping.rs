//! One control period in ros2_control's order (read, update, write), what advanced it, what
//! an episode's end or a refused step does, the sim clock, and the step timing log.

use std::time::{Duration, Instant};

use composuite_core::env::EnvError;

use super::hardware::{Hardware, SimHardware};
use super::{ActionServers, Mode, Sim};
use crate::shared::convert;
use crate::shared::node::Logger;

/// Where a step's time goes, summed until it is logged (at debug level, every
/// [`TIMING_WINDOW`] steps).
#[derive(Default)]
pub(super) struct StepTiming {
    steps: u32,
    physics: Duration,
    publish: Duration,
}

/// Steps per timing log line.
const TIMING_WINDOW: u32 = 1000;

/// What advanced the sim by one period.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Advance {
    /// A direct command (lockstep) or the realtime timer: the period is always simulated.
    Command,
    /// A running goal (lockstep): simulated only while a goal is still undecided after the update.
    Goal,
}

impl Sim {
    /// One control period in ros2_control's order: read the hardware, update the controllers on
    /// that reading, write their commands (the world simulates the period). Advanced by a goal,
    /// the period is simulated only if a goal is still undecided after the update: an N-period
    /// trajectory takes exactly N steps, like N `joint_command`s. True when a period was
    /// simulated and published.
    pub(super) fn advance(&mut self, servers: &ActionServers, by: Advance, log: &Logger) -> bool {
        let time_ns = self.sim_time_ns;
        let Some(run) = &mut self.run else {
            return false;
        };
        let period_ns = Self::period_ns(run);
        let started = Instant::now();
        let mut hardware = SimHardware::new(&mut run.env, time_ns);
        let state = hardware.read();
        let (command, events) = run.controllers.update(&state, period_ns);
        let simulate = by == Advance::Command || run.controllers.running();
        let step = simulate.then(|| {
            self.step_pool.run(|| {
                // The write's outcome is also in `last_step`, with the step's details.
                let _ = hardware.write(&command);
                hardware.last_step.take().expect("a write records its step")
            })
        });
        let physics = started.elapsed();
        self.report(servers, events, log);
        let Some(step) = step else { return false };
        let run = self.run.as_mut().expect("checked above");
        match step {
            Ok(step) => {
                for c in &step.info.clamped {
                    if run.clamp_reported.insert(c.joint.to_string()) {
                        log.warn(format!(
                            "target clamped: {c} (said once per joint and episode)"
                        ));
                    }
                }
                if let Some((terminated, truncated)) = run.env.ended() {
                    log.info(format!(
                        "episode {} over after {} steps ({}), return {:.3}, success {}",
                        run.episode,
                        run.env.steps(),
                        if terminated {
                            "terminated"
                        } else if truncated {
                            "horizon"
                        } else {
                            "?"
                        },
                        run.env.episode_return(),
                        run.env.success_seen()
                    ));
                }
            }
            Err(err @ EnvError::EpisodeOver { .. }) => {
                self.end_all_goals(
                    servers,
                    &format!("{err}; a new episode (reset) goes on"),
                    log,
                );
                let run = self.run.as_mut().expect("checked above");
                if self.mode == Mode::Realtime {
                    // The world stands still until the next episode; time and joint_states go on.
                    let world_msg = convert::world_state(
                        &run.env.world_state(),
                        convert::time_from_nanos(self.sim_time_ns),
                        run.episode,
                        run.env.steps(),
                    );
                    self.advance_clock();
                    self.publish_robot_state(&world_msg);
                } else if !run.over_reported {
                    run.over_reported = true;
                    log.warn(format!("command ignored: {err} (said once per episode)"));
                }
                return false;
            }
            Err(err) => {
                log.warn(format!("command refused: {err}"));
                self.end_all_goals(servers, &format!("the sim refused a command: {err}"), log);
                return false;
            }
        }
        self.advance_clock();
        self.publish_state();
        let t = &mut self.timing;
        t.steps += 1;
        t.physics += physics;
        t.publish += started.elapsed() - physics;
        if t.steps == TIMING_WINDOW {
            log.debug(format!(
                "last {} steps: physics {:.0} µs, publishing {:.0} µs per step",
                t.steps,
                t.physics.as_secs_f64() * 1e6 / t.steps as f64,
                t.publish.as_secs_f64() * 1e6 / t.steps as f64
            ));
            *t = StepTiming::default();
        }
        true
    }

    pub(super) fn advance_clock(&mut self) {
        if let Some(run) = &self.run {
            self.sim_time_ns += Self::period_ns(run);
        }
    }
}
