//! What touches what in one episode of the planned expert: at the chosen control steps, every
//! contact pair whose shapes are within 2 mm, each collider named (arm body, gripper, finger,
//! pad, object, arena part), and optionally a frame from each camera given — the quickest way
//! to see why a leg stalled (the wrist on a door post, the object on a bin's wall).
//!
//! ```text
//! cargo run --profile session -p composuite_core --example expert_contacts -- \
//!     Jaco/plate/object_door/push 0 275,300 [OUT_DIR [CAMERA...]]
//! ```
//!
//! Frames go to `OUT_DIR/<step>_<camera>.png` (400 × 400) when a directory and cameras are
//! given (frontview, agentview, birdview, sideview, eye_in_hand).

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use composuite_core::TaskSpec;
use composuite_core::arena::arena_parts;
use composuite_core::env::{Env, EnvConfig};
use composuite_core::expert::PlannedExpert;
use composuite_core::physics::ColliderTag;
use rapier3d::prelude::{ColliderHandle, PairContacts};

/// Contacts further apart than this (m) are left out (rapier keeps speculative ones).
const SHOWN_WITHIN: f32 = 0.002;
/// Side of a written frame (pixels).
const FRAME_SIDE: u32 = 400;

/// A collider's name: its tag, with the arm body's or arena part's own name.
fn name(env: &Env, arena: &[String], collider: ColliderHandle) -> String {
    let world = env.world();
    let tag = ColliderTag::decode(world.physics.colliders[collider].user_data);
    match tag {
        Some(ColliderTag::Arm(i)) => format!("arm {}", world.model.bodies[i as usize].name),
        Some(ColliderTag::Arena(i)) => format!("arena {}", arena[i as usize]),
        Some(other) => format!("{other:?}"),
        None => "untagged".to_string(),
    }
}

fn write_frame(env: &mut Env, camera: &str, path: &Path) {
    let frame = env
        .render(camera, FRAME_SIDE, FRAME_SIDE)
        .unwrap_or_else(|e| panic!("{e}"));
    let file = BufWriter::new(File::create(path).expect("create the PNG file"));
    let mut encoder = png::Encoder::new(file, FRAME_SIDE, FRAME_SIDE);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(&frame.rgb).expect("PNG data");
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: expert_contacts TASK SEED STEP[,STEP...] [OUT_DIR [CAMERA...]]";
    let [task, seed, steps, rest @ ..] = args.as_slice() else {
        panic!("{usage}");
    };
    let task: TaskSpec = task.parse().unwrap_or_else(|e| panic!("{e}; {usage}"));
    let seed: u64 = seed.parse().expect("SEED: a whole number");
    let steps: Vec<u64> = steps
        .split(',')
        .map(|s| s.parse().expect("STEP: whole numbers, comma-separated"))
        .collect();
    let (out, cameras) = match rest {
        [out, cameras @ ..] => (Some(Path::new(out)), cameras),
        [] => (None, &[][..]),
    };
    let arena: Vec<String> = arena_parts(task.objective, task.obstacle)
        .iter()
        .map(|p| p.name.to_string())
        .collect();
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    let mut expert = PlannedExpert::new(task);
    let mut step = 0;
    while env.ended().is_none() {
        let action = expert.act(&env);
        env.step(&action).expect("step");
        step += 1;
        if !steps.contains(&step) {
            continue;
        }
        println!("step {step} ({:?}):", expert.stage());
        for pair in env.world().physics.narrow_phase.contact_pairs() {
            let PairContacts::Rigid(rigid) = &pair.contacts else {
                continue;
            };
            let nearest = rigid
                .manifolds
                .iter()
                .flat_map(|m| m.points.iter().map(|p| p.dist))
                .fold(f32::INFINITY, f32::min);
            if nearest <= SHOWN_WITHIN {
                let a = name(&env, &arena, pair.collider1);
                let b = name(&env, &arena, pair.collider2);
                println!("  {a} - {b}: {:.1} mm", nearest * 1000.0);
            }
        }
        if let Some(out) = out {
            for camera in cameras {
                write_frame(&mut env, camera, &out.join(format!("{step}_{camera}.png")));
            }
        }
    }
}
