//! The in-process reference the ROS integration tests compare the node suite against.
//!
//! ```text
//! env_replay run < episode.json      # JSON lines: step 0 (reset), then one line per command
//! env_replay expert TASK SEED        # JSON: the scripted expert's commands and its outcome
//! ```
//!
//! `episode.json` is `{"task": "R/O/B/J", "seed": S, "horizon": H?, "task_observation": B?,
//! "reward_shaping": B?, "reward_scale": X?,
//! "commands": [{"joints": [7 rad], "gripper": [opening m, effort N] | null, "finger": q?}, ...]}`
//! — the same commands an agent sends as `joint_command` (+ `gripper_command` before it; or
//! `finger`, the `l_finger_joint` target (m) put into `joint_command` itself), or
//! `{"reference": [8 values]}`, what an agent sends as `reference_action`. Each output line is
//! `{"step", "flat", "reward", "success", "terminated", "truncated"}`; floats print with
//! round-trip precision, so Python reads back the exact bits.

use std::io::Read;

use composuite_core::TaskSpec;
use composuite_core::env::{Action, Env, EnvConfig};
use composuite_core::expert::Expert;
use serde_json::{Value, json};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>()
        .as_slice()
    {
        ["run"] => run(),
        ["expert", task, seed] => expert(task, seed),
        _ => Err("usage: env_replay run < episode.json | env_replay expert TASK SEED".into()),
    };
    if let Err(e) = result {
        eprintln!("env_replay: {e}");
        std::process::exit(2);
    }
}

fn task_of(text: &str) -> Result<TaskSpec, String> {
    text.parse()
        .map_err(|e: composuite_core::TaskParseError| e.to_string())
}

fn run() -> Result<(), String> {
    let mut input = String::new();
    std::io::stdin()
        .read_to_string(&mut input)
        .map_err(|e| e.to_string())?;
    let spec: Value = serde_json::from_str(&input).map_err(|e| e.to_string())?;
    let task = task_of(spec["task"].as_str().ok_or("`task` missing")?)?;
    let seed = spec["seed"].as_u64().ok_or("`seed` missing")?;
    let mut config = EnvConfig::default();
    if let Some(h) = spec["horizon"].as_u64() {
        config = config.horizon(h as u32);
    }
    if let Some(t) = spec["task_observation"].as_bool() {
        config = config.task_observation(t);
    }
    if let Some(on) = spec["reward_shaping"].as_bool() {
        config = config.reward_shaping(on);
    }
    if let Some(scale) = spec["reward_scale"].as_f64() {
        config = config.reward_scale(scale);
    }
    let mut env = Env::new(task, config);
    let first = env.reset(seed).map_err(|e| e.to_string())?;
    println!(
        "{}",
        json!({"step": 0, "flat": first.flat(), "reward": 0.0, "success": false,
               "terminated": false, "truncated": false})
    );
    for (i, command) in spec["commands"]
        .as_array()
        .ok_or("`commands` missing")?
        .iter()
        .enumerate()
    {
        let action = match &command["reference"] {
            Value::Null => absolute_action(i, command)?,
            values => {
                let values: [f64; 8] = serde_json::from_value(values.clone())
                    .map_err(|e| format!("command {i}: reference: 8 numbers expected: {e}"))?;
                Action::Reference(values)
            }
        };
        let step = env.step(&action).map_err(|e| format!("command {i}: {e}"))?;
        println!(
            "{}",
            json!({"step": i + 1, "flat": step.observation.flat(), "reward": step.reward,
                   "success": step.info.success, "terminated": step.terminated,
                   "truncated": step.truncated})
        );
        if step.terminated || step.truncated {
            break;
        }
    }
    Ok(())
}

/// A `{"joints", "gripper"?, "finger"?}` command as the sim node turns it into an action.
fn absolute_action(i: usize, command: &Value) -> Result<Action, String> {
    let joints: Vec<f64> = serde_json::from_value(command["joints"].clone())
        .map_err(|e| format!("command {i}: joints: {e}"))?;
    let joints: [f64; 7] = joints
        .try_into()
        .map_err(|_| format!("command {i}: 7 joints expected"))?;
    let gripper = match &command["gripper"] {
        // A finger joint target in joint_command: the sim turns it into this opening.
        Value::Null if command["finger"].is_f64() => Some((
            composuite_core::physics::pad_gap(command["finger"].as_f64().unwrap_or(0.0)),
            0.0,
        )),
        Value::Null => None,
        g => {
            let g: [f64; 2] =
                serde_json::from_value(g.clone()).map_err(|e| format!("command {i}: {e}"))?;
            Some((g[0], g[1]))
        }
    };
    Ok(Action::Absolute { joints, gripper })
}

fn expert(task: &str, seed: &str) -> Result<(), String> {
    let task = task_of(task)?;
    let seed: u64 = seed
        .parse()
        .map_err(|_| format!("seed `{seed}` is not a number"))?;
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).map_err(|e| e.to_string())?;
    let mut expert = Expert::new(task);
    let mut commands = Vec::new();
    let mut success_step = None;
    while env.ended().is_none() {
        let action = expert.act(&env);
        let Action::Absolute { joints, gripper } = action else {
            return Err("the expert acted with a reference action".into());
        };
        commands.push(json!({"joints": joints, "gripper": gripper.map(|(w, e)| [w, e])}));
        let step = env.step(&action).map_err(|e| e.to_string())?;
        if step.info.success && success_step.is_none() {
            success_step = Some(env.steps());
        }
    }
    println!(
        "{}",
        json!({"task": task.to_string(), "seed": seed, "commands": commands,
               "success_step": success_step, "steps": env.steps()})
    );
    Ok(())
}
