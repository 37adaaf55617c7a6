//! Renders one task's scene from every camera and writes the frames as PNG files.
//!
//! ```text
//! cargo run -p composuite_core --example render_frames -- IIWA/box/no_obstacle/pick_place 256 256 /tmp/frames [seed]
//! ```
//! Writes `<dir>/<camera>.png` (colour) and `<dir>/<camera>_depth.png` (depth, near = light).

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use composuite_core::env::{Env, EnvConfig};
use composuite_core::render::CAMERAS;

fn write_png(path: &Path, width: u32, height: u32, colour: png::ColorType, data: &[u8]) {
    let file = BufWriter::new(File::create(path).expect("create the PNG file"));
    let mut encoder = png::Encoder::new(file, width, height);
    encoder.set_color(colour);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(data).expect("PNG data");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let task = args
        .get(1)
        .map_or("IIWA/box/no_obstacle/pick_place", String::as_str)
        .parse()
        .expect("a task: robot/object/obstacle/objective");
    let width: u32 = args.get(2).map_or(256, |a| a.parse().expect("width"));
    let height: u32 = args.get(3).map_or(256, |a| a.parse().expect("height"));
    let dir = Path::new(args.get(4).map_or("frames", String::as_str));
    let seed: u64 = args.get(5).map_or(0, |a| a.parse().expect("seed"));
    std::fs::create_dir_all(dir).expect("create the output directory");
    let mut env = Env::new(task, EnvConfig::default());
    env.reset(seed).expect("reset");
    for camera in &CAMERAS {
        let frame = env.render(camera.name, width, height).expect("render");
        write_png(
            &dir.join(format!("{}.png", camera.name)),
            width,
            height,
            png::ColorType::Rgb,
            &frame.rgb,
        );
        // Depth as grey: the nearest surface white, the farthest drawn one black, sky black.
        let finite = frame.depth.iter().filter(|d| d.is_finite());
        let near = finite.clone().fold(f32::MAX, |a, &d| a.min(d));
        let far = finite.fold(0.0f32, |a, &d| a.max(d));
        let grey: Vec<u8> = frame
            .depth
            .iter()
            .map(|&d| {
                if d.is_finite() {
                    (255.0 * (far - d) / (far - near).max(1e-6)) as u8
                } else {
                    0
                }
            })
            .collect();
        write_png(
            &dir.join(format!("{}_depth.png", camera.name)),
            width,
            height,
            png::ColorType::Grayscale,
            &grey,
        );
        println!("{}: depth {near:.3}–{far:.3} m", camera.name);
    }
}
