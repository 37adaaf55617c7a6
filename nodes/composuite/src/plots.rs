//! PNG plots drawn with `plotters`, text in DejaVu Sans embedded in the binary (the `dejavu`
//! crate), so a plot looks the same on a machine without fonts.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
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
