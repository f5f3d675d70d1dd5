//! The ratio of every codec against the size of a show (the `pattern`
//! codec's database size, Gu, Peng & Deng 2008 Fig. 10/11): one panel per
//! corpus and bound, one line per codec (`report/examples/pattern_db.rs`).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::PALETTE;
use super::{distinct, with_backend, PlotError};

/// One line: a codec's ratio at each show size in one panel.
#[derive(Clone, Debug)]
pub struct Series {
    /// The panel (corpus and bound).
    pub panel: String,
    /// The codec.
    pub codec: String,
    /// (clips in the show, ratio against 32-bit floats).
    pub points: Vec<(usize, f64)>,
}

/// Draws `series`, panels side by side (two per row), x the show sizes of
/// the panel, evenly spaced.
pub fn database_plot(path: &Path, series: &[Series]) -> Result<(), PlotError> {
    let panels = distinct(series.iter().map(|s| s.panel.as_str()));
    let rows = panels.len().div_ceil(2).max(1) as u32;
    with_backend(
        path,
        (1400, 420 * rows),
        |a| draw(a, series, &panels),
        |a| draw(a, series, &panels),
    )
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    series: &[Series],
    panels: &[&str],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let rows = panels.len().div_ceil(2).max(1);
    let areas = root.split_evenly((rows, 2));
    let codecs = distinct(series.iter().map(|s| s.codec.as_str()));
    for (panel, area) in panels.iter().zip(&areas) {
        let lines: Vec<&Series> = series.iter().filter(|s| s.panel == *panel).collect();
        let mut sizes: Vec<usize> = lines
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
            .collect();
        sizes.sort_unstable();
        sizes.dedup();
        let at = |n: usize| sizes.iter().position(|&m| m == n).unwrap_or(0) as f64;
        let xmax = sizes.len().saturating_sub(1).max(1) as f64;
        let ymax = lines
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .fold(1.0, f64::max)
            * 1.15;
        let mut chart = ChartBuilder::on(area)
            .margin(15)
            .caption(
                format!("{panel}: ratio vs f32 against clips in the show"),
                ("sans-serif", 17),
            )
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(-0.1..xmax + 0.1, 0.0..ymax)?;
        let label = |x: &f64| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                sizes
                    .get(i as usize)
                    .map_or(String::new(), |n| n.to_string())
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_desc("clips in the show")
            .y_desc("ratio")
            .x_labels(sizes.len() * 10 + 1)
            .x_label_formatter(&label)
            .label_style(("sans-serif", 14))
            .draw()?;
        for s in lines {
            let i = codecs.iter().position(|c| *c == s.codec).unwrap_or(0);
            let colour = PALETTE[i % PALETTE.len()];
            let pts: Vec<(f64, f64)> = s.points.iter().map(|&(n, r)| (at(n), r)).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
                .label(s.codec.clone())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.filled())
                });
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 4, colour.filled())))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()?;
    }
    root.present()?;
    Ok(())
}
