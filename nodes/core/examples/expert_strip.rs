//! The scripted expert solving one task per objective, as a strip of frames per task: a PNG grid
//! whose row r shows task r from its start to its first success (or its end), in `columns`
//! evenly spaced frames. The README's picture (`docs/src/expert_strip.png`) is made with:
//!
//! ```text
//! cargo run --release -p composuite_core --example expert_strip -- docs/src/expert_strip.png
//! ```
//!
//! Optional after the path: frame side in pixels (128), columns (5), camera (frontview), then
//! the tasks (one per objective by default). A task's seed is the first of 0..10 the expert
//! succeeds with (the row is labelled by nothing: the order is the order given).

use std::fs::File;
use std::io::BufWriter;

use composuite_core::TaskSpec;
use composuite_core::env::{Env, EnvConfig};
use composuite_core::expert::Expert;

const TASKS: [&str; 4] = [
    "IIWA/box/no_obstacle/pick_place",
    "Panda/dumbbell/no_obstacle/push",
    "Jaco/plate/object_wall/trash_can",
    "Gen3/hollow_box/no_obstacle/shelf",
];

/// The frames of one expert episode of `task` with `seed`, up to its first success, and whether
/// it succeeded.
fn episode_frames(task: TaskSpec, seed: u64, camera: &str, side: u32) -> (Vec<Vec<u8>>, bool) {
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    let mut expert = Expert::new(task);
    let mut frames = vec![env.render(camera, side, side).expect("render").rgb];
    while env.ended().is_none() {
        let action = expert.act(&env);
        let step = env.step(&action).expect("step");
        frames.push(env.render(camera, side, side).expect("render").rgb);
        if step.info.success {
            return (frames, true);
        }
    }
    (frames, false)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args.get(1).map_or("expert_strip.png", String::as_str);
    let side: u32 = args.get(2).map_or(128, |a| a.parse().expect("side"));
    let columns: usize = args.get(3).map_or(5, |a| a.parse().expect("columns"));
    let camera = args.get(4).map_or("frontview", String::as_str);
    let tasks: Vec<TaskSpec> = if args.len() > 5 {
        args[5..]
            .iter()
            .map(|t| t.parse().expect("a task"))
            .collect()
    } else {
        TASKS.iter().map(|t| t.parse().expect("a task")).collect()
    };
    let width = side as usize * columns;
    let mut image = vec![0u8; width * side as usize * tasks.len() * 3];
    for (row, task) in tasks.iter().enumerate() {
        let (frames, seed) = (0..10)
            .map(|seed| (episode_frames(*task, seed, camera, side), seed))
            .find(|((_, success), _)| *success)
            .map(|((frames, _), seed)| (frames, seed))
            .unwrap_or_else(|| panic!("the expert never solved {task} in seeds 0..10"));
        eprintln!("{task}: seed {seed}, success at step {}", frames.len() - 1);
        for column in 0..columns {
            let index = column * (frames.len() - 1) / (columns - 1).max(1);
            let frame = &frames[index];
            for y in 0..side as usize {
                let src = &frame[y * side as usize * 3..(y + 1) * side as usize * 3];
                let top = (row * side as usize + y) * width * 3;
                let left = column * side as usize * 3;
                image[top + left..top + left + src.len()].copy_from_slice(src);
            }
        }
    }
    let file = BufWriter::new(File::create(out).expect("create the PNG"));
    let mut encoder = png::Encoder::new(file, width as u32, side * tasks.len() as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::High);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(&image).expect("PNG data");
    eprintln!("wrote {out}");
}
