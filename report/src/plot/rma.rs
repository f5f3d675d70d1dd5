//! The picture for people who tune the repeated motion analysis (issue 14):
//! the self-distance plot of the projected coefficients (darker = more
//! alike), the similar-posture paths found in it (upper half, and mirrored
//! in the lower half), and under it the clips on the time axis — each
//! primary clip in its colour, its repeated clips in the same colour,
//! lighter, unique clips grey. Given the clip the encoder wrote, it also
//! draws what was kept: each repeated clip's `Ref(t)` as a red line on the
//! plot, and a last strip with the repeated clips and the frames they
//! refer to (the encoder keeps a repetition only where it pays, and may
//! read the paths as long matches rather than the paper's clips).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::PALETTE;
use super::{with_backend, PlotError};
use mocap_encoder::codec::rma::section::Repeated;
use mocap_encoder::codec::rma::{Analysis, ClipKind};

/// Pixels of the plot's side (the analysis frames are sampled down to it).
const SIDE: u32 = 600;

/// Draws `a` (of a take called `name`) into `path` (PNG, or SVG by the
/// extension), with `kept`, the repeated clips of the encoded clip (none:
/// the analysis alone).
pub fn self_distance_plot(
    path: &Path,
    a: &Analysis,
    kept: Option<&[Repeated]>,
    name: &str,
) -> Result<(), PlotError> {
    let size = (SIDE + 40, SIDE + if kept.is_some() { 230 } else { 150 });
    with_backend(
        path,
        size,
        |r| draw(r, a, kept, name),
        |r| draw(r, a, kept, name),
    )
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    a: &Analysis,
    kept: Option<&[Repeated]>,
    name: &str,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let f = &a.features;
    let [pri, rep, uni] = a.frames_by_kind();
    let total = (pri + rep + uni).max(1);
    root.draw(&Text::new(
        format!(
            "{name}: self-distance, {} paths; frames primary {:.0} %, repeated {:.0} %, unique {:.0} %",
            a.paths.len(),
            100.0 * pri as f64 / total as f64,
            100.0 * rep as f64 / total as f64,
            100.0 * uni as f64 / total as f64
        ),
        (20, 8),
        ("sans-serif", 15),
    ))?;
    let (x0, y0) = (20i32, 36i32);
    let n = f.len.max(1);
    let side = SIDE.min(n as u32).max(1);
    let px = SIDE as f64 / side as f64;
    // The plot, sampled down to `side` × `side` cells.
    let at = |c: u32| ((c as f64 + 0.5) * n as f64 / side as f64) as usize;
    let mut d = vec![0.0f64; (side * side) as usize];
    let mut max = 0.0f64;
    if f.k > 0 {
        for y in 0..side {
            for x in 0..side {
                let v = f.dist(at(x).min(n - 1), at(y).min(n - 1));
                d[(y * side + x) as usize] = v;
                max = max.max(v);
            }
        }
    }
    let max = max.max(f64::MIN_POSITIVE);
    for y in 0..side {
        for x in 0..side {
            let g = (255.0 * (d[(y * side + x) as usize] / max).sqrt()) as u8;
            let (cx, cy) = (x0 + (x as f64 * px) as i32, y0 + (y as f64 * px) as i32);
            let w = (px.ceil() as i32).max(1);
            root.draw(&Rectangle::new(
                [(cx, cy), (cx + w, cy + w)],
                RGBColor(g, g, g).filled(),
            ))?;
        }
    }
    // The paths, in both halves.
    let to_px = |v: usize| (v as f64 * SIDE as f64 / n as f64) as i32;
    for (i, p) in a.paths.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let upper: Vec<(i32, i32)> = p
            .points
            .iter()
            .map(|&(i, j)| (x0 + to_px(j), y0 + to_px(i)))
            .collect();
        let lower: Vec<(i32, i32)> = p
            .points
            .iter()
            .map(|&(i, j)| (x0 + to_px(i), y0 + to_px(j)))
            .collect();
        root.draw(&PathElement::new(upper, colour.stroke_width(2)))?;
        root.draw(&PathElement::new(lower, colour.stroke_width(2)))?;
    }
    // The clips under the plot, on the same time axis.
    let frames = a.clips.last().map_or(1, |c| c.end).max(1);
    let tx = |t: usize| x0 + (t as f64 * SIDE as f64 / frames as f64) as i32;
    let strip = y0 + SIDE as i32 + 20;
    let mut colour_of = vec![None; a.clips.len()];
    let mut next = 0;
    for (i, c) in a.clips.iter().enumerate() {
        if c.kind == ClipKind::Primary {
            colour_of[i] = Some(PALETTE[next % PALETTE.len()]);
            next += 1;
        }
    }
    for (i, c) in a.clips.iter().enumerate() {
        let (fill, label) = match &c.kind {
            ClipKind::Primary => (colour_of[i].unwrap_or(BLACK), "P"),
            ClipKind::Repeated { primary, .. } => (
                colour_of
                    .get(*primary)
                    .copied()
                    .flatten()
                    .map_or(RGBColor(160, 160, 160), lighten),
                "R",
            ),
            ClipKind::Unique => (RGBColor(200, 200, 200), ""),
        };
        root.draw(&Rectangle::new(
            [(tx(c.start), strip), (tx(c.end), strip + 40)],
            fill.filled(),
        ))?;
        root.draw(&Rectangle::new(
            [(tx(c.start), strip), (tx(c.end), strip + 40)],
            BLACK.stroke_width(1),
        ))?;
        if tx(c.end) - tx(c.start) > 12 {
            root.draw(&Text::new(
                label,
                (tx(c.start) + 3, strip + 12),
                ("sans-serif", 13),
            ))?;
        }
    }
    root.draw(&Text::new(
        "analysis: P primary (its colour), R repeated (its primary's colour, lighter), grey unique",
        (x0, strip + 52),
        ("sans-serif", 13),
    ))?;
    if let Some(kept) = kept {
        draw_kept(&root, kept, (x0, y0), n, f.step.max(1), frames, strip + 80)?;
    }
    root.present()?;
    Ok(())
}

fn lighten(c: RGBColor) -> RGBColor {
    let l = |v: u8| (u16::from(v) + (255 - u16::from(v)) / 2) as u8;
    RGBColor(l(c.0), l(c.1), l(c.2))
}

/// The encoded clip's repeated clips: `Ref(t)` on the plot (analysis
/// frames: source frames / `step`, `n` of them) and a strip at `strip` on
/// the time axis of `frames` source frames.
fn draw_kept<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    kept: &[Repeated],
    (x0, y0): (i32, i32),
    n: usize,
    step: usize,
    frames: usize,
    strip: i32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let red = RGBColor(220, 30, 30);
    let to_px = |source: f64| (source / step as f64 * SIDE as f64 / n as f64) as i32;
    let tx = |t: f64| x0 + (t * SIDE as f64 / frames as f64) as i32;
    for (i, c) in kept.iter().enumerate() {
        let along: Vec<(f64, f64)> = (0..=c.last - c.start)
            .step_by(step)
            .chain(std::iter::once(c.last - c.start))
            .map(|t| (f64::from(c.start + t), c.reference_at(t)))
            .collect();
        let upper = along.iter().map(|&(f, r)| (x0 + to_px(f), y0 + to_px(r)));
        let lower = along.iter().map(|&(f, r)| (x0 + to_px(r), y0 + to_px(f)));
        root.draw(&PathElement::new(
            upper.collect::<Vec<_>>(),
            red.stroke_width(3),
        ))?;
        root.draw(&PathElement::new(
            lower.collect::<Vec<_>>(),
            red.stroke_width(3),
        ))?;
        let colour = PALETTE[i % PALETTE.len()];
        let (lo, hi) = (f64::from(c.primary.0), f64::from(c.primary.1));
        let span = |a: f64, b: f64, fill: RGBColor| {
            Rectangle::new(
                [(tx(a), strip), (tx(b + 1.0).max(tx(a) + 1), strip + 40)],
                fill.filled(),
            )
        };
        root.draw(&span(lo, hi, lighten(colour)))?;
        root.draw(&span(f64::from(c.start), f64::from(c.last), colour))?;
    }
    root.draw(&Rectangle::new(
        [(x0, strip), (x0 + SIDE as i32, strip + 40)],
        BLACK.stroke_width(1),
    ))?;
    root.draw(&Text::new(
        format!(
            "kept in the clip: {} repeated clip{} (red on the plot: Ref(t)); each in its colour, lighter where it refers",
            kept.len(),
            if kept.len() == 1 { "" } else { "s" }
        ),
        (x0, strip + 52),
        ("sans-serif", 13),
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use mocap_encoder::codec::rma::{self, Params};

    /// The demo clip's analysis draws as PNG and SVG; an unwritable file
    /// is named in the error.
    #[test]
    fn draws_the_demo_and_names_a_bad_file() {
        let m = mocap_encoder::generate::animatronic_demo();
        let a = rma::analyse(&m, &Params::default());
        let dir = std::env::temp_dir().join(format!("mocap-rma-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, kept) in [("demo.png", None), ("demo.svg", Some(&[][..]))] {
            let path = dir.join(name);
            self_distance_plot(&path, &a, kept, "demo").unwrap();
            assert!(std::fs::metadata(&path).unwrap().len() > 1000, "{name}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
        let bad = Path::new("/nonexistent-mocap-dir/rma.png");
        let e = self_distance_plot(bad, &a, None, "demo").unwrap_err();
        assert_eq!(e.path(), bad);
    }
}
