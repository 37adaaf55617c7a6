//! Follows one episode of the scripted expert step by step: phase, object, grip site.
//! With `--planned` first, the planned expert (issue 49): its stage, and the largest joint
//! action and the gripper's sign of each step.
//!
//! `cargo run --release -p composuite_core --example expert_trace -- [--planned] IIWA/plate/goal_wall/push 0 [EVERY]`

use composuite_core::TaskSpec;
use composuite_core::env::Action;
use composuite_core::env::{Env, EnvConfig};
use composuite_core::expert::{Expert, PlannedExpert};

/// Either expert, asked for its next action and where it stands.
enum Driver {
    Scripted(Box<Expert>),
    Planned(Box<PlannedExpert>),
}

impl Driver {
    fn act(&mut self, env: &Env) -> Action {
        match self {
            Driver::Scripted(e) => e.act(env),
            Driver::Planned(e) => e.act(env),
        }
    }

    fn phase(&self) -> String {
        match self {
            Driver::Scripted(e) => format!("{:?}", e.phase()),
            Driver::Planned(e) => format!("{:?}", e.stage()),
        }
    }
}

fn main() {
    let mut args = std::env::args().skip(1).peekable();
    let usage = "usage: expert_trace [--planned] ROBOT/OBJECT/OBSTACLE/OBJECTIVE SEED [EVERY]";
    let planned = args.next_if(|a| a == "--planned").is_some();
    let task: TaskSpec = args.next().expect(usage).parse().expect("a task name");
    let seed: u64 = args.next().map_or(0, |s| s.parse().expect("a seed"));
    let every: u32 = args
        .next()
        .map_or(5, |s| s.parse().expect("steps between lines"));
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    let mut expert = if planned {
        Driver::Planned(Box::new(PlannedExpert::new(task)))
    } else {
        Driver::Scripted(Box::new(Expert::new(task)))
    };
    let mut last_phase = None;
    while env.ended().is_none() {
        let action = expert.act(&env);
        let step = env.step(&action).expect("step");
        let obs = env.observation();
        let o = obs.object.position;
        let [qx, qy, qz, qw] = obs.object.orientation;
        let rotation =
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(qw, qx, qy, qz));
        // The object's tilt: the angle between its z axis and the world's.
        let tilt = (rotation * nalgebra::Vector3::z())
            .z
            .clamp(-1.0, 1.0)
            .acos();
        let g = env.world().grip_site_pose().translation.vector;
        let phase = expert.phase();
        // The planned expert's actions: the largest joint action and the gripper's sign.
        let acting = match action {
            Action::Reference(a) => format!(
                " a {:.2} grip {:+.0}",
                a[..7].iter().fold(0.0_f64, |m, x| m.max(x.abs())),
                a[7]
            ),
            Action::Absolute { .. } => String::new(),
        };
        if last_phase.as_ref() != Some(&phase)
            || env.steps().is_multiple_of(every)
            || step.info.success
        {
            println!(
                "{:4} {:10} obj ({:+.3} {:+.3} {:+.3}) grip ({:+.3} {:+.3} {:+.3}) r {:.3} tilt {:.3}{acting}{}",
                env.steps(),
                phase,
                o[0],
                o[1],
                o[2],
                g.x,
                g.y,
                g.z,
                step.reward,
                tilt,
                if step.info.success { " SUCCESS" } else { "" }
            );
        }
        last_phase = Some(phase);
    }
    println!("ended {:?} return {:.1}", env.ended(), env.episode_return());
}
