//! PNG plots drawn with `plotters`, text in DejaVu Sans embedded in the binary (the `dejavu`
//! crate), so a plot looks the same on a machine without fonts.

use std::path::Path;
use std::sync::OnceLock;

use composuite_core::TaskSpec;
use composuite_core::axes::{AxisElement, Object, Obstacle, Robot};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};

/// The font family every plot uses.
const FONT: &str = "sans-serif";

fn register() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
                .map_err(|_| "the embedded DejaVu Sans font did not load".to_string())
        })
        .clone()
}

fn error(path: &Path, e: impl std::fmt::Display) -> String {
    format!("cannot draw {}: {e}", path.display())
}

/// Each episode's staged reward over its steps, one line per episode.
pub fn reward_curves(
    path: &Path,
    title: &str,
    episodes: &[(String, Vec<f64>)],
) -> Result<(), String> {
    register()?;
    let steps = episodes
        .iter()
        .map(|(_, r)| r.len())
        .max()
        .unwrap_or(1)
        .max(1);
    let top = episodes
        .iter()
        .flat_map(|(_, r)| r.iter().copied())
        .fold(1.0_f64, f64::max);
    let root = BitMapBackend::new(path, (1000, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(0usize..steps, 0.0..top * 1.05)
        .map_err(|e| error(path, e))?;
    chart
        .configure_mesh()
        .x_desc("control step")
        .y_desc("staged reward")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(|e| error(path, e))?;
    for (i, (label, rewards)) in episodes.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(
                rewards.iter().enumerate().map(|(k, r)| (k + 1, *r)),
                color.stroke_width(2),
            ))
            .map_err(|e| error(path, e))?
            .label(label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
    }
    if episodes.len() <= 20 {
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(|e| error(path, e))?;
    }
    root.present().map_err(|e| error(path, e))
}

/// Success rate per task (0 to 1), one horizontal bar each.
pub fn success_bars(path: &Path, title: &str, tasks: &[(String, f64)]) -> Result<(), String> {
    register()?;
    let height = 120 + 32 * tasks.len().max(1) as u32;
    let root = BitMapBackend::new(path, (1000, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(330)
        .build_cartesian_2d(0.0..1.0, (0..tasks.len()).into_segmented())
        .map_err(|e| error(path, e))?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("success rate")
        .y_labels(tasks.len().max(1))
        .y_label_formatter(&|v| match v {
            SegmentValue::CenterOf(i) => tasks.get(*i).map(|(t, _)| t.clone()).unwrap_or_default(),
            _ => String::new(),
        })
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(|e| error(path, e))?;
    chart
        .draw_series(tasks.iter().enumerate().map(|(i, (_, rate))| {
            let mut bar = Rectangle::new(
                [
                    (0.0, SegmentValue::Exact(i)),
                    (*rate, SegmentValue::Exact(i + 1)),
                ],
                RGBColor(46, 125, 50).filled(),
            );
            bar.set_margin(4, 4, 0, 0);
            bar
        }))
        .map_err(|e| error(path, e))?;
    root.present().map_err(|e| error(path, e))
}

/// Success rate per task as four 8×8 heatmaps side by side, one per robot: rows are the objects
/// (two rows each), columns the obstacles (two columns each), and each object × obstacle 2×2
/// block holds the four objectives (pick_place push / trash_can shelf). Cells run from white (0)
/// to green (1) with the rate written in them; grey where `rate` has no value (not run).
pub fn success_heatmap(
    path: &Path,
    title: &str,
    rate: &dyn Fn(TaskSpec) -> Option<f64>,
) -> Result<(), String> {
    register()?;
    // Chart units: one cell = 1; a robot's grid spans 8, with 1 between grids; labels to the
    // left (x < 0), above (y > 8) and the key below (y < 0).
    let root = BitMapBackend::new(path, (1600, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 24))
        .margin(10)
        .build_cartesian_2d(-3.0..35.2, -1.2..9.9)
        .map_err(|e| error(path, e))?;
    let centred =
        |size: u32| TextStyle::from((FONT, size)).pos(Pos::new(HPos::Center, VPos::Center));
    let right = TextStyle::from((FONT, 16)).pos(Pos::new(HPos::Right, VPos::Center));
    let mut cells = Vec::new();
    let mut texts: Vec<(String, (f64, f64), TextStyle)> = Vec::new();
    for task in composuite_core::all_tasks() {
        let x0 = 9.0 * task.robot.index() as f64;
        let j = task.objective.index();
        let row = 2 * task.object.index() + j / 2;
        let col = 2 * task.obstacle.index() + j % 2;
        let (x, y) = (x0 + col as f64, 7.0 - row as f64);
        let value = rate(task);
        let fill = match value {
            Some(v) => RGBColor(
                (255.0 * (1.0 - v)) as u8,
                (255.0 - 100.0 * v) as u8,
                (255.0 * (1.0 - v)) as u8,
            ),
            None => RGBColor(200, 200, 200),
        };
        cells.push(Rectangle::new(
            [(x + 0.04, y + 0.04), (x + 0.96, y + 0.96)],
            fill.filled(),
        ));
        if let Some(v) = value {
            let ink: &'static RGBColor = if v > 0.6 { &WHITE } else { &BLACK };
            texts.push((
                format!("{v:.1}"),
                (x + 0.5, y + 0.5),
                centred(13).color(ink),
            ));
        }
    }
    for robot in Robot::all() {
        let x0 = 9.0 * robot.index() as f64;
        texts.push((robot.wire_name().to_string(), (x0 + 4.0, 9.35), centred(20)));
        for obstacle in Obstacle::all() {
            let x = x0 + 2.0 * obstacle.index() as f64 + 1.0;
            texts.push((obstacle.wire_name().to_string(), (x, 8.4), centred(14)));
        }
    }
    for object in Object::all() {
        let y = 7.0 - 2.0 * object.index() as f64;
        texts.push((object.wire_name().to_string(), (-0.2, y), right.clone()));
    }
    texts.push((
        "each 2×2 block: pick_place, push / trash_can, shelf;  grey: not run".to_string(),
        (17.1, -0.6),
        centred(16),
    ));
    chart.draw_series(cells).map_err(|e| error(path, e))?;
    chart
        .draw_series(
            texts
                .into_iter()
                .map(|(text, at, style)| Text::new(text, at, style)),
        )
        .map_err(|e| error(path, e))?;
    root.present().map_err(|e| error(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use composuite_core::axes::Objective;

    /// The RGB pixels of a PNG and its size.
    fn pixels(path: &Path) -> ((u32, u32), Vec<[u8; 3]>) {
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        let rgb = buf[..info.buffer_size()]
            .chunks(info.color_type.samples())
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        ((info.width, info.height), rgb)
    }

    #[test]
    fn the_heatmap_colours_run_tasks_by_rate_and_greys_the_rest() {
        let path = std::env::temp_dir().join(format!("heatmap-{}.png", std::process::id()));
        // Shelf tasks succeed always, push never; the rest were not run.
        let rate = |t: TaskSpec| match t.objective {
            Objective::Shelf => Some(1.0),
            Objective::Push => Some(0.0),
            _ => None,
        };
        success_heatmap(&path, "test", &rate).unwrap();
        let (size, rgb) = pixels(&path);
        std::fs::remove_file(&path).unwrap();
        assert_eq!(size, (1600, 520));
        let count = |c: [u8; 3]| rgb.iter().filter(|p| **p == c).count();
        let (green, grey) = (count([0, 155, 0]), count([200, 200, 200]));
        // 64 cells of each; a grey cell has no text in it, so it has more pixels of its colour.
        assert!(green > 64 * 500, "green pixels: {green}");
        assert!(grey > 128 * 700 && grey > green, "grey pixels: {grey}");
    }
}
