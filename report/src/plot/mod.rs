//! Plots users want beside the tables: the rate–distortion plot of
//! `mocap bench --plot` and the per-frame error plot of `mocap eval --plot`.
//! plotters, SVG or PNG by the file's extension; text uses the font bundled
//! by [`style::register_font`] (no system font library).

pub mod database;
pub mod rma;
pub mod style;

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::bench::Row;
use mocap_encoder::metrics::positions_mm;
use mocap_encoder::motion::Motion;
use style::{register_font, PALETTE};

/// What plotters reports when an SVG picture cannot be drawn or written.
pub type SvgError = DrawingAreaErrorKind<<SVGBackend<'static> as DrawingBackend>::ErrorType>;
/// What plotters reports when a PNG picture cannot be drawn or written.
pub type BitmapError = DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>;

/// A picture that could not be drawn or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// An SVG picture.
    #[error("{}: {source}", path.display())]
    Svg {
        /// The picture's file.
        path: PathBuf,
        /// What plotters reported.
        source: SvgError,
    },
    /// A PNG picture.
    #[error("{}: {source}", path.display())]
    Bitmap {
        /// The picture's file.
        path: PathBuf,
        /// What plotters reported.
        source: BitmapError,
    },
}

impl PlotError {
    /// The picture's file.
    pub fn path(&self) -> &Path {
        match self {
            PlotError::Svg { path, .. } | PlotError::Bitmap { path, .. } => path,
        }
    }
}

/// Draws one picture with `svg` or `bitmap` by the file's extension.
pub(crate) fn with_backend(
    path: &Path,
    size: (u32, u32),
    svg: impl FnOnce(DrawingArea<SVGBackend, Shift>) -> Result<(), SvgError>,
    bitmap: impl FnOnce(DrawingArea<BitMapBackend, Shift>) -> Result<(), BitmapError>,
) -> Result<(), PlotError> {
    register_font();
    let path_buf = || path.to_path_buf();
    if is_svg(path) {
        svg(SVGBackend::new(path, size).into_drawing_area()).map_err(|source| PlotError::Svg {
            path: path_buf(),
            source,
        })
    } else {
        bitmap(BitMapBackend::new(path, size).into_drawing_area()).map_err(|source| {
            PlotError::Bitmap {
                path: path_buf(),
                source,
            }
        })
    }
}

/// Per-frame joint-position error of `decoded` against `original` (same
/// skeleton), millimetres: `(rms over joints, max over joints)` per frame.
/// The mean of the first components is the ARMS of [`mocap_encoder::metrics::compare`].
pub fn per_frame_errors(
    original: &Motion,
    decoded: &Motion,
    metres_per_unit: f64,
) -> Vec<(f64, f64)> {
    let frames = original.frames().min(decoded.frames());
    let joints = original.skeleton.joints.len().max(1);
    let a = positions_mm(original, metres_per_unit);
    let b = positions_mm(decoded, metres_per_unit);
    (0..frames)
        .map(|f| {
            let (mut sq, mut max) = (0.0, 0.0f64);
            for j in 0..joints {
                let (p, q) = (a[f * joints + j], b[f * joints + j]);
                let d2: f64 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum();
                sq += d2;
                max = max.max(d2.sqrt());
            }
            ((sq / joints as f64).sqrt(), max)
        })
        .collect()
}

fn is_svg(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
}

/// `mocap eval --plot`: RMS and max joint error per frame.
pub fn frame_error_plot(
    path: &Path,
    original: &Motion,
    decoded: &Motion,
    metres_per_unit: f64,
    name: &str,
) -> Result<(), PlotError> {
    let errs = per_frame_errors(original, decoded, metres_per_unit);
    let dt = original.frame_time;
    let name = Path::new(name)
        .file_name()
        .map_or(name.to_string(), |n| n.to_string_lossy().into_owned());
    let name = name.as_str();
    with_backend(
        path,
        (1200, 500),
        |a| draw_frame_errors(a, &errs, dt, name),
        |a| draw_frame_errors(a, &errs, dt, name),
    )
}

fn draw_frame_errors<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    errs: &[(f64, f64)],
    dt: f64,
    name: &str,
) -> DrawResult<(), DB> {
    root.fill(&WHITE)?;
    let t1 = (errs.len().max(2) - 1) as f64 * dt;
    let ymax = errs.iter().map(|x| x.1).fold(0.0, f64::max).max(1e-6) * 1.1;
    let arms = errs.iter().map(|x| x.0).sum::<f64>() / errs.len().max(1) as f64;
    let mut chart = ChartBuilder::on(&root)
        .margin(15)
        .caption(
            format!("{name}: joint-position error per frame (ARMS {arms:.2} mm)"),
            ("sans-serif", 18),
        )
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t1, 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("error (mm)")
        .label_style(("sans-serif", 15))
        .draw()?;
    type Pick = fn(&(f64, f64)) -> f64;
    let series: [(&str, RGBColor, Pick); 2] = [
        ("max over joints", PALETTE[3], |x| x.1),
        ("RMS over joints", PALETTE[0], |x| x.0),
    ];
    for (label, colour, pick) in series {
        chart
            .draw_series(LineSeries::new(
                errs.iter()
                    .enumerate()
                    .map(|(i, x)| (i as f64 * dt, pick(x))),
                colour.stroke_width(1),
            ))?
            .label(label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    root.present()?;
    Ok(())
}

/// `mocap bench --plot`: on the left the rate–distortion plot — ratio vs
/// 32-bit floats (with header) against ARMS, one point per file, colour =
/// codec or baseline, marker = bound; on the right the aggregate ratio of
/// every method at every bound as bars (all files of the run pooled: total
/// f32 bytes over total bytes with header).
pub fn rate_distortion_plot(path: &Path, rows: &[Row]) -> Result<(), PlotError> {
    with_backend(
        path,
        (1600, 720),
        |a| draw_bench(a, rows),
        |a| draw_bench(a, rows),
    )
}

/// The distinct values of `key` over `rows`, in the order they first appear.
fn first_seen(rows: &[Row], key: fn(&Row) -> &str) -> Vec<&str> {
    distinct(rows.iter().map(key))
}

/// The distinct items, in the order they first appear.
pub(crate) fn distinct<'a>(items: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for i in items {
        if !out.contains(&i) {
            out.push(i);
        }
    }
    out
}

fn draw_bench<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    rows: &[Row],
) -> DrawResult<(), DB> {
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(860);
    let methods = first_seen(rows, |r| r.codec.as_str());
    let bounds = first_seen(rows, |r| r.bound.as_str());
    draw_rd(&left, rows, &methods, &bounds)?;
    draw_bars(&right, rows, &methods, &bounds)?;
    root.present()?;
    Ok(())
}

fn draw_rd<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[Row],
    methods: &[&str],
    bounds: &[&str],
) -> DrawResult<(), DB> {
    let xmax = rows
        .iter()
        .map(|r| r.metrics.arms_mm)
        .fold(0.0, f64::max)
        .max(1e-6)
        * 1.1;
    let ymax = rows
        .iter()
        .map(|r| r.metrics.ratio_f32)
        .fold(0.0, f64::max)
        .max(1.0)
        * 1.4; // room for the legend above the points
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .caption(
            "rate–distortion: ratio vs 32-bit floats (with header) against ARMS",
            ("sans-serif", 18),
        )
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..xmax, 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc("ARMS (mm)")
        .y_desc("compression ratio (f32 / bytes)")
        .label_style(("sans-serif", 15))
        .draw()?;
    // Colour = method, marker = bound: circle, triangle, square, cross.
    for (i, m) in methods.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        for (k, b) in bounds.iter().enumerate() {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.codec == *m && r.bound == *b)
                .map(|r| (r.metrics.arms_mm, r.metrics.ratio_f32))
                .collect();
            let fill = colour.filled();
            match k % 4 {
                0 => chart.draw_series(pts.iter().map(|&p| Circle::new(p, 5, fill)))?,
                1 => chart.draw_series(pts.iter().map(|&p| TriangleMarker::new(p, 6, fill)))?,
                2 => chart
                    .draw_series(pts.iter().map(|&p| {
                        EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], fill)
                    }))?,
                _ => chart.draw_series(
                    pts.iter()
                        .map(|&p| Cross::new(p, 5, colour.stroke_width(2))),
                )?,
            };
        }
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            .label(*m)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.filled()));
    }
    for (k, b) in bounds.iter().enumerate() {
        let anno = chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
            .label(format!("@ {b}"));
        let ink = BLACK.filled();
        match k % 4 {
            0 => anno.legend(move |(x, y)| Circle::new((x + 7, y), 5, ink)),
            1 => anno.legend(move |(x, y)| TriangleMarker::new((x + 7, y), 6, ink)),
            2 => anno.legend(move |(x, y)| Rectangle::new([(x + 3, y - 4), (x + 11, y + 4)], ink)),
            _ => anno.legend(move |(x, y)| Cross::new((x + 7, y), 5, BLACK.stroke_width(2))),
        };
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

fn draw_bars<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[Row],
    methods: &[&str],
    bounds: &[&str],
) -> DrawResult<(), DB> {
    // Aggregate ratio (with header) of each bound and method.
    let ratio = |b: &str, m: &str| {
        let sel = rows.iter().filter(|r| r.bound == b && r.codec == m);
        let (f32b, bytes) = sel.fold((0usize, 0usize), |(f, c), r| {
            (f + r.f32_bytes, c + r.metrics.bytes)
        });
        (bytes > 0).then(|| f32b as f64 / bytes as f64)
    };
    let ymax = bounds
        .iter()
        .flat_map(|b| methods.iter().filter_map(move |m| ratio(b, m)))
        .fold(1.0, f64::max)
        * 1.15;
    let groups = bounds.len().max(1) as f64;
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .caption(
            "aggregate ratio vs f32 (with header), all files",
            ("sans-serif", 18),
        )
        .x_label_area_size(10)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..groups, 0.0..ymax)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc("compression ratio")
        .label_style(("sans-serif", 15))
        .draw()?;
    let width = 0.8 / methods.len().max(1) as f64;
    for (g, b) in bounds.iter().enumerate() {
        chart.draw_series(std::iter::once(Text::new(
            format!("@ {b}"),
            (g as f64 + 0.1, ymax * 0.97),
            ("sans-serif", 16),
        )))?;
        for (i, m) in methods.iter().enumerate() {
            let Some(v) = ratio(b, m) else { continue };
            let x0 = g as f64 + 0.1 + i as f64 * width;
            let colour = PALETTE[i % PALETTE.len()];
            chart.draw_series(std::iter::once(Rectangle::new(
                [(x0, 0.0), (x0 + width * 0.9, v)],
                colour.filled(),
            )))?;
            chart.draw_series(std::iter::once(Text::new(
                format!("{v:.1}"),
                (x0, v + ymax * 0.01),
                ("sans-serif", 12),
            )))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A picture that cannot be written names its file, then what plotters
    /// reported, for either backend.
    #[test]
    fn unwritable_picture_names_its_file() {
        for name in ["rd.svg", "rd.png"] {
            let path = Path::new("/nonexistent-mocap-dir").join(name);
            let e = rate_distortion_plot(&path, &[]).unwrap_err();
            assert_eq!(e.path(), path);
            let text = e.to_string();
            let want = format!("{}: backend error: ", path.display());
            assert!(text.starts_with(&want), "{text}");
            assert!(std::error::Error::source(&e).is_some());
        }
    }
}
