//! Frame time per camera: the whole scene (arena, arm with gripper, object, goal marker) of
//! one task per arm, rendered at 84×84, 256×256 and 640×480 on one thread.
//!
//! ```text
//! cargo bench -p composuite_core --bench render
//! ```
//! Prints, per arm, camera and size, the median and best frame time in µs over a run of frames
//! (the machine may be shared, so the best is the steadier figure), plus the triangle count and
//! the one-time cost of tessellating the scene. Asserts nothing.

use std::time::Instant;

use composuite_core::axes::{AxisElement, Robot};
use composuite_core::env::{Env, EnvConfig};
use composuite_core::render::{CAMERAS, SceneRenderer};

const SIZES: [(u32, u32); 3] = [(84, 84), (256, 256), (640, 480)];

fn main() {
    println!("arm    camera        size      median_us  best_us");
    for robot in Robot::all() {
        let task: composuite_core::TaskSpec =
            format!("{}/box/no_obstacle/pick_place", robot.wire_name())
                .parse()
                .expect("task");
        let mut env = Env::new(task, EnvConfig::default());
        env.reset(0).expect("reset");
        let start = Instant::now();
        env.render("frontview", 1, 1).expect("render");
        let build_us = start.elapsed().as_secs_f64() * 1e6;
        for camera in &CAMERAS {
            for (width, height) in SIZES {
                // Enough frames for a steady median, fewer for the big size.
                let frames = if width * height > 100_000 { 60 } else { 200 };
                let mut times: Vec<f64> = (0..frames)
                    .map(|_| {
                        let start = Instant::now();
                        let frame = env.render(camera.name, width, height).expect("render");
                        std::hint::black_box(&frame);
                        start.elapsed().as_secs_f64() * 1e6
                    })
                    .collect();
                times.sort_by(f64::total_cmp);
                println!(
                    "{:<6} {:<13} {:<9} {:>9.0} {:>8.0}",
                    robot.wire_name(),
                    camera.name,
                    format!("{width}x{height}"),
                    times[times.len() / 2],
                    times[0]
                );
            }
        }
        let triangles = SceneRenderer::new(task, env.world().model).triangle_count();
        println!(
            "{}: {triangles} triangles, scene tessellated in {build_us:.0} µs (first render, 1×1)",
            robot.wire_name()
        );
    }
}
