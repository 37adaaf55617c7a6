//! `composuite demo`: a headless session of the whole suite. It launches the three nodes of one
//! lockstep environment and drives them over ROS 2 — reset through the `reset` service, one
//! `joint_command` per step, the step's `observation`, `reward` and `episode` awaited by
//! (episode, step) — with the scripted expert choosing the commands. Per episode it prints the
//! outcome, and checks every observation and reward against the in-process `Env` given the same
//! commands (bit for bit): the suite is exactly the core library behind ROS.

use clap::Args;
use composuite_core::TaskSpec;

use crate::drive::{EpisodeOutcome, Plan, PolicyKind, drive};
use crate::launch::{LaunchArgs, Suite};

/// Run the scripted expert through the ROS 2 node suite, headless.
///
/// Starts one lockstep environment (task_manager, sim, reward as child processes, in a
/// namespace of its own), then plays `--episodes` episodes with the scripted expert as the
/// agent over ROS 2 topics and services. Prints each episode's outcome and whether every
/// observation and reward equalled the in-process environment's (they must, bit for bit).
/// DDS settings come from the environment (ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE).
///
/// Example: composuite demo --task Gen3/box/object_wall/trash_can --episodes 2
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Task, robot/object/obstacle/objective.
    #[arg(long, default_value = composuite_ros::task_manager::DEFAULT_TASK)]
    task: String,
    /// Episodes to play.
    #[arg(long, default_value_t = 3)]
    episodes: u32,
    /// Seed of the first episode (then +1 per episode).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print one JSON object per episode instead of text.
    #[arg(long)]
    json: bool,
    /// The suite's security enclave (with ROS_SECURITY_ENABLE=true; see `composuite security`).
    /// [default: /]
    #[arg(long, value_name = "NAME")]
    enclave: Option<String>,
    /// The agent's security enclave (e.g. one whose permissions allow less than the suite's).
    /// [default: /]
    #[arg(long, value_name = "NAME")]
    agent_enclave: Option<String>,
}

/// Play the episodes; an error if the suite fails or differs from the in-process environment.
pub fn run(args: &DemoArgs) -> Result<(), String> {
    let task: TaskSpec = args
        .task
        .parse()
        .map_err(|e: composuite_core::TaskParseError| format!("--task: {e}"))?;
    if args.episodes == 0 {
        return Err("--episodes must be at least 1".into());
    }
    let namespace = format!("/demo_{}", std::process::id());
    let signals = composuite_ros::shared::node::shutdown_signal()
        .map_err(|e| format!("cannot watch for SIGINT/SIGTERM: {e}"))?;
    let launch = LaunchArgs::one_environment(&args.task, &namespace, "warn")
        .with_enclave(args.enclave.clone());
    let mut suite = Suite::start(&launch)?;
    let plan = Plan {
        namespace,
        tasks: vec![task],
        episodes: args.episodes,
        seed: args.seed,
        policy: PolicyKind::Expert,
        wait_for_recorder: false,
        signals: Some(signals),
        enclave: args.agent_enclave.clone(),
    };
    let result = drive(&plan, &mut suite, |o| report(o, args.json));
    let clean = suite.stop();
    let driven = result?;
    let outcomes = driven.outcomes;
    if !clean {
        return Err("some nodes did not shut down cleanly (see above)".into());
    }
    if let Some(signal) = driven.interrupted {
        return Err(format!(
            "stopped by signal {signal} after {} of {} episodes",
            outcomes.len(),
            args.episodes
        ));
    }
    if outcomes.iter().any(|o| !o.identical) {
        return Err("the suite's observations differ from the in-process environment".into());
    }
    Ok(())
}

fn report(o: &EpisodeOutcome, json: bool) {
    if json {
        println!(
            "{}",
            serde_json::json!({"episode": o.episode, "seed": o.seed, "steps": o.steps,
                "return": o.episode_return, "success": o.first_success.is_some(),
                "first_success_step": o.first_success, "identical_to_in_process": o.identical,
                "steps_per_s": o.steps_per_s})
        );
    } else {
        println!(
            "episode {} (seed {}): {}, return {:.2} over {} steps, {:.0} steps/s; observations {} the in-process env",
            o.episode,
            o.seed,
            match o.first_success {
                Some(step) => format!("success at step {step}"),
                None => "no success".into(),
            },
            o.episode_return,
            o.steps,
            o.steps_per_s,
            if o.identical {
                "identical to"
            } else {
                "DIFFERENT from"
            }
        );
    }
}
