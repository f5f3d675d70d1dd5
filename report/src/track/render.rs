//! Drawing a Motion Track picture with plotters (SVG or PNG by extension).
//!
//! Dark background as in the paper; key frames are grey squares (one per key
//! frame); each clip is one polyline in its own colour (one path per clip)
//! with a dot per frame whose brightness shows the joint angular speed
//! (dark = slow, white = fast); a legend names the clips.
//!
//! Text is laid out with ab_glyph and the Ubuntu Light font that the
//! `epaint_default_fonts` crate ships, so no system font library is needed.
//! (plotters 0.3.7's ab_glyph text drops each glyph's left side bearing,
//! which leaves a gap after every narrow glyph of a monospaced font such as
//! Hack — "0. 25", "squares:  key"; a proportional font hides it.)

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::Track;
use crate::plot::{with_backend, PlotError};

/// Fill of the key-frame markers.
pub const KEY_COLOUR: RGBColor = RGBColor(0x80, 0x80, 0x80);
/// Background.
pub const BACKGROUND: RGBColor = RGBColor(0x14, 0x14, 0x18);
pub use crate::plot::style::PALETTE;

/// Writes the picture to `path` (`.svg`, else PNG); the view spans the key
/// frames and the tracks.
pub fn render(
    path: &Path,
    title: &str,
    tracks: &[Track],
    key_xy: &[[f64; 2]],
) -> Result<(), PlotError> {
    render_view(path, title, tracks, key_xy, false)
}

/// Like [`render`]; with `zoom` the view spans the tracks only (key frames
/// outside it are left out).
pub fn render_view(
    path: &Path,
    title: &str,
    tracks: &[Track],
    key_xy: &[[f64; 2]],
    zoom: bool,
) -> Result<(), PlotError> {
    with_backend(
        path,
        (1300, 1000),
        |a| draw(a, title, tracks, key_xy, zoom, Stroke::Polyline),
        |a| draw(a, title, tracks, key_xy, zoom, Stroke::Segments),
    )
}

fn lerp(a: RGBColor, b: RGBColor, t: f64) -> RGBColor {
    let f = |x: u8, y: u8| {
        (f64::from(x) + (f64::from(y) - f64::from(x)) * t)
            .round()
            .clamp(0.0, 255.0) as u8
    };
    RGBColor(f(a.0, b.0), f(a.1, b.1), f(a.2, b.2))
}

/// Colour of a frame dot: the clip colour, darker when slow, whiter when fast.
pub fn speed_colour(base: RGBColor, t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let dark = lerp(BACKGROUND, base, 0.25);
    if t < 0.5 {
        lerp(dark, base, t * 2.0)
    } else {
        lerp(base, RGBColor(255, 255, 255), (t - 0.5) * 1.6)
    }
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// How a track's polyline reaches the backend.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Stroke {
    /// One path per clip: the SVG viewer strokes it, joins and all.
    Polyline,
    /// One path per segment. plotters' raster backend turns a path wider
    /// than 1 px into a single polygon with unlimited inner miter joins
    /// (plotters-backend 0.3.7, `rasterizer::polygonize`): where a track
    /// nearly reverses, a join vertex lands far along the bisector and the
    /// filled polygon shoots a spike off the plotting area. Two-point paths
    /// have no joins; the frame dots cover the segment ends.
    Segments,
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    tracks: &[Track],
    key_xy: &[[f64; 2]],
    zoom: bool,
    stroke: Stroke,
) -> DrawResult<(), DB> {
    root.fill(&BACKGROUND)?;
    let (w, h) = root.dim_in_pixel();
    let (plot, side) = root.split_horizontally(h.min(w));
    // Square data range over key frames and tracks.
    let keys_in_view = if zoom { &[][..] } else { key_xy };
    let pts = keys_in_view
        .iter()
        .chain(tracks.iter().flat_map(|t| t.xy.iter()));
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in pts {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (-1.0, 1.0, -1.0, 1.0);
    }
    let half = 0.52 * (x1 - x0).max(y1 - y0).max(1e-9);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let white = RGBColor(235, 235, 235);
    let mut chart = ChartBuilder::on(&plot)
        .margin(20)
        .caption(title, ("sans-serif", 19).into_font().color(&white))
        .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)?;
    // Key frames: one square each.
    chart.draw_series(
        key_xy
            .iter()
            .filter(|p| (p[0] - cx).abs() <= half && (p[1] - cy).abs() <= half)
            .map(|p| {
                EmptyElement::at((p[0], p[1]))
                    + Rectangle::new([(-3, -3), (3, 3)], KEY_COLOUR.filled())
            }),
    )?;
    // Brightness scale: 95th percentile of all speeds is white.
    let mut all: Vec<f64> = tracks
        .iter()
        .flat_map(|t| t.speed.iter().copied())
        .collect();
    let vmax = percentile(&mut all, 0.95).max(1e-9);
    for (i, t) in tracks.iter().enumerate() {
        let base = PALETTE[i % PALETTE.len()];
        let line = base.stroke_width(2);
        let pts: Vec<(f64, f64)> = t.xy.iter().map(|p| (p[0], p[1])).collect();
        match stroke {
            Stroke::Polyline => chart.draw_series(std::iter::once(PathElement::new(pts, line)))?,
            Stroke::Segments => chart.draw_series(
                pts.windows(2)
                    .filter(|s| s[0] != s[1])
                    .map(|s| PathElement::new(s.to_vec(), line)),
            )?,
        };
        chart.draw_series(
            t.xy.iter()
                .zip(&t.speed)
                .map(|(p, &v)| Circle::new((p[0], p[1]), 2, speed_colour(base, v / vmax).filled())),
        )?;
    }
    // Legend on the side panel: what each mark means, then the clips.
    let font = ("sans-serif", 20).into_font().color(&white);
    let small = ("sans-serif", 17).into_font().color(&white);
    let grey = ("sans-serif", 15)
        .into_font()
        .color(&RGBColor(170, 170, 175));
    let mut y = 30;
    side.draw(&Text::new("clips", (10, y), font.clone()))?;
    y += 32;
    for (i, t) in tracks.iter().enumerate() {
        let base = PALETTE[i % PALETTE.len()];
        // A bar, not a path: the SVG keeps one polyline per clip.
        side.draw(&Rectangle::new([(10, y + 9), (40, y + 11)], base.filled()))?;
        side.draw(&Circle::new((25, y + 10), 4, base.filled()))?;
        side.draw(&Text::new(t.name.clone(), (50, y), small.clone()))?;
        y += 28;
    }
    y += 22;
    side.draw(&Rectangle::new(
        [(22, y + 4), (28, y + 10)],
        KEY_COLOUR.filled(),
    ))?;
    side.draw(&Text::new("key frame", (50, y - 2), small.clone()))?;
    y += 34;
    side.draw(&Text::new("dot brightness: mean", (10, y), small.clone()))?;
    y += 22;
    side.draw(&Text::new("joint angular speed", (10, y), small.clone()))?;
    y += 28;
    for s in 0..=10 {
        let t = f64::from(s) / 10.0;
        let c = speed_colour(PALETTE[0], t);
        side.draw(&Rectangle::new(
            [(10 + s * 22, y), (32 + s * 22, y + 14)],
            c.filled(),
        ))?;
    }
    y += 20;
    side.draw(&Text::new("0 °/s", (10, y), grey.clone()))?;
    side.draw(&Text::new(
        format!("≥ {vmax:.0} °/s"),
        (176, y),
        grey.clone(),
    ))?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::style::register_font;

    /// A track that nearly reverses at every frame, drawn to a bitmap: with
    /// one wide polyline plotters' join vertices shoot spikes across the
    /// picture; segment by segment, every track pixel stays near the track.
    #[test]
    fn bitmap_track_stays_within_its_bounds() {
        // Out and back along slightly different lines, as the CMU jump's
        // track does in the eq. 2 picture (pixels (311,263) → (256,456) →
        // (306,279)), within x, y ∈ [0.34, 0.66] of the unit square.
        let xy: Vec<[f64; 2]> = (0..40)
            .map(|i| {
                let e = 0.0015 * f64::from(i / 2);
                if i % 2 == 0 {
                    [0.60 - e, 0.35]
                } else {
                    [0.40, 0.65 - e]
                }
            })
            .collect();
        let track = Track {
            name: "out and back".into(),
            speed: vec![1.0; xy.len()],
            xy,
        };
        let key_xy = [[0.0, 0.0], [1.0, 1.0]];
        register_font();
        let (w, h) = (500u32, 400u32);
        let mut buf = vec![0u8; (w * h * 3) as usize];
        for stroke in [Stroke::Polyline, Stroke::Segments] {
            buf.fill(0);
            {
                let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
                draw(
                    root,
                    "",
                    std::slice::from_ref(&track),
                    &key_xy,
                    false,
                    stroke,
                )
                .unwrap();
            }
            // Pixels in the clip's colour. The track spans x, y ∈ [0.34,
            // 0.66] of the unit square, which fills the plotting area
            // (pixels x < 400);
            // the legend panel (pixels ≥ 400) holds the clip's swatch and
            // the brightness scale above row 240 and nothing below.
            let c = PALETTE[0];
            let hits: Vec<(u32, u32)> = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let i = ((y * w + x) * 3) as usize;
                    buf[i..i + 3] == [c.0, c.1, c.2]
                })
                .collect();
            let plot = || hits.iter().filter(|p| p.0 < 400);
            let top = plot().map(|p| p.1).min().unwrap();
            let bottom = plot().map(|p| p.1).max().unwrap();
            let in_legend = hits.iter().filter(|p| p.0 >= 400 && p.1 >= 240).count();
            let left = plot().map(|p| p.0).min().unwrap();
            let right = plot().map(|p| p.0).max().unwrap();
            let inside = top > 100 && bottom < 300 && left > 100 && right < 300 && in_legend == 0;
            match stroke {
                Stroke::Segments => assert!(inside, "track pixels x {left}..{right}, y {top}..{bottom}, {in_legend} in the legend"),
                // Documents why Segments exists; if plotters fixes its joins
                // this arm may start to fail and Polyline can be used again.
                Stroke::Polyline => assert!(!inside, "plotters joins fixed? x {left}..{right}, y {top}..{bottom}, {in_legend} in the legend"),
            }
        }
    }
}
