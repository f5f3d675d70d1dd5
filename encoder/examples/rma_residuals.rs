//! Issue 14's open question, measured before the bitstream: how many spline
//! keys a repeated clip's residual against its (reconstructed) primary
//! needs, against the keys the same frames need coded on their own. Per
//! take: the analysis's clips (`codec::rma`), the body's PCA coefficients
//! at the source rate, and `pca_spline::keys::select` (the key search the
//! `pca-spline` codec uses) at a tolerance `TOL` on the coefficient vector
//! (Euclidean, degrees of the PCA space); also the knots a piecewise-linear
//! Ref(t) needs to stay within one frame.
//!
//! ```sh
//! KNOT_EVERY=16 cargo run --release -p mocap-encoder --example rma_residuals -- 3 ../shared/data/cmu ../shared/data/cmu-long
//! ```
//!
//! `KNOT_EVERY=N` (default 1: Ref(t) as found, frame by frame) smooths
//! Ref(t) to a line between its values every N frames, the primary then
//! read at fractional frames; `QUANTILE=q` sets the analysis's threshold
//! quantile (default 0.15). The last column compares the residual's range
//! with the clip's own (per component, summed): below 1 the residual's key
//! values need fewer bits.

use std::path::PathBuf;

use mocap_encoder::codec::pca_spline::keys;
use mocap_encoder::codec::rma::{self, ClipKind, Params};
use mocap_encoder::input;

/// Range (max − min) of component `j` of `data` (`len × k`).
fn range(data: &[f64], k: usize, j: usize) -> f64 {
    let v = data.iter().skip(j).step_by(k);
    v.clone().fold(f64::MIN, |a, &b| a.max(b)) - v.fold(f64::MAX, |a, &b| a.min(b))
}

fn norm(d: &[f64]) -> f64 {
    d.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Keys and the reconstruction of `data` (`len × k`) at `tol`.
fn fit(data: &[f64], k: usize, tol: f64) -> (usize, Vec<f64>) {
    let len = data.len() / k;
    if len < 2 {
        return (len, data.to_vec());
    }
    let (times, controls) = keys::select(data, k, tol, norm);
    let back = keys::evaluate(&times, &controls, k, len);
    (times.len(), back)
}

/// Knots of a piecewise-linear approximation of `r` within one frame
/// (greedy: extend each line while every frame stays within 1).
fn knots(r: &[usize]) -> usize {
    let mut n = 1;
    let mut a = 0;
    while a + 1 < r.len() {
        let mut b = a + 1;
        while b + 1 < r.len() {
            let c = b + 1;
            let ok = (a..=c).all(|t| {
                let x = r[a] as f64 + (r[c] as f64 - r[a] as f64) * (t - a) as f64 / (c - a) as f64;
                (x - r[t] as f64).abs() <= 1.0
            });
            if !ok {
                break;
            }
            b = c;
        }
        n += 1;
        a = b;
    }
    n
}

/// `r` smoothed: linear between its values every `every` frames (and at
/// its last frame), fractional.
fn smooth_ref(r: &[usize], every: usize) -> Vec<f64> {
    if every <= 1 || r.len() < 3 {
        return r.iter().map(|&x| x as f64).collect();
    }
    let mut knots: Vec<usize> = (0..r.len()).step_by(every).collect();
    if knots.last() != Some(&(r.len() - 1)) {
        knots.push(r.len() - 1);
    }
    let mut out = Vec::with_capacity(r.len());
    for w in knots.windows(2) {
        let (a, b) = (w[0], w[1]);
        for t in a..b {
            out.push(r[a] as f64 + (r[b] as f64 - r[a] as f64) * (t - a) as f64 / (b - a) as f64);
        }
    }
    out.push(r[r.len() - 1] as f64);
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let tol: f64 = args
        .next()
        .ok_or("usage: rma_residuals TOL FOLDER_OR_FILE...")?
        .parse()?;
    let knot_every: usize = std::env::var("KNOT_EVERY")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let paths: Vec<PathBuf> = args.map(PathBuf::from).collect();
    println!("| file | k | frames P/R/U | keys all on their own | keys with residuals | repeated frames: own keys | residual keys | Ref knots | residual range / own range |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut tot = [0usize; 5];
    for f in input::expand(&paths)? {
        let m = input::read_motion(&f, None)?.motion;
        let mut p = Params::default();
        if let Some(q) = std::env::var("QUANTILE").ok().and_then(|v| v.parse().ok()) {
            p.threshold_quantile = q;
        }
        let a = rma::analyse(&m, &p);
        let full = rma::features(
            &m,
            &Params {
                rate_hz: 1.0 / m.frame_time,
                ..p.clone()
            },
        );
        let k = full.k.max(1);
        let clip_data = |s: usize, e: usize| full.coef[s * k..e * k].to_vec();
        // Every clip on its own; the primaries' reconstructions kept.
        let mut own = 0;
        let mut rebuilt = vec![Vec::new(); a.clips.len()];
        let (mut rep_own, mut rep_res, mut ref_knots) = (0, 0, 0);
        let (mut range_own, mut range_res) = (0.0, 0.0);
        for (i, c) in a.clips.iter().enumerate() {
            let (n, back) = fit(&clip_data(c.start, c.end), k, tol);
            own += n;
            if let ClipKind::Repeated { .. } = c.kind {
                rep_own += n;
            } else {
                rebuilt[i] = back;
            }
        }
        let mut with = own - rep_own;
        for c in &a.clips {
            let ClipKind::Repeated { primary, reference } = &c.kind else {
                continue;
            };
            let pc = &a.clips[*primary];
            let mut res = clip_data(c.start, c.end);
            let smooth = smooth_ref(reference, knot_every);
            let plen = pc.end - pc.start;
            for (t, &r) in smooth.iter().enumerate() {
                // The primary's reconstruction at the fractional frame r.
                let x = (r - pc.start as f64).clamp(0.0, (plen - 1) as f64);
                let (i0, w) = (x.floor() as usize, x - x.floor());
                let i1 = (i0 + 1).min(plen - 1);
                for j in 0..k {
                    let v = rebuilt[*primary][i0 * k + j] * (1.0 - w)
                        + rebuilt[*primary][i1 * k + j] * w;
                    res[t * k + j] -= v;
                }
            }
            let (n, _) = fit(&res, k, tol);
            let own_data = clip_data(c.start, c.end);
            range_own += (0..k).map(|j| range(&own_data, k, j)).sum::<f64>();
            range_res += (0..k).map(|j| range(&res, k, j)).sum::<f64>();
            rep_res += n;
            with += n;
            ref_knots += knots(reference);
        }
        let [pf, rf, uf] = a.frames_by_kind();
        for (t, v) in tot.iter_mut().zip([own, with, rep_own, rep_res, ref_knots]) {
            *t += v;
        }
        println!(
            "| {} | {} | {pf}/{rf}/{uf} | {own} | {with} | {rep_own} | {rep_res} | {ref_knots} | {:.2} |",
            f.file_name().unwrap_or_default().to_string_lossy(),
            full.k,
            range_res / range_own.max(f64::MIN_POSITIVE)
        );
    }
    println!(
        "| all | | | {} | {} | {} | {} | {} | |",
        tot[0], tot[1], tot[2], tot[3], tot[4]
    );
    Ok(())
}
