//! Where segments start: at jumps (a pose that changes abruptly and
//! stays changed, like CMU's reference first frame) and where the motion
//! changes behaviour, found by probabilistic PCA (Barbič et al. 2004, as
//! used by Liu & McMillan): model the first K frames of a segment by a
//! Gaussian, measure the mean Mahalanobis distance H of the next T frames,
//! grow K by Δ, and cut at the peak that follows a valley once H has risen
//! by more than R.

use nalgebra::{DMatrix, SymmetricEigen};

/// PPCA segmentation parameters, in frames at the clip's own rate.
#[derive(Clone, Copy, Debug)]
pub struct Ppca {
    /// Frames of the first model (paper: 200 at 120 Hz).
    pub k0: usize,
    /// Frames whose distance is measured (paper: 150).
    pub t: usize,
    /// Growth step (paper: 10).
    pub delta: usize,
    /// Variance the kept components explain (paper: 0.95).
    pub tau: f64,
    /// Rise of H from its valley that makes a cut (paper: 500).
    pub r: f64,
}

impl Ppca {
    /// The paper's values scaled from 120 Hz to `fps`.
    pub fn paper(fps: f64) -> Ppca {
        let s = |frames: f64| ((frames * fps / 120.0).round() as usize).max(2);
        Ppca {
            k0: s(200.0),
            t: s(150.0),
            delta: s(10.0).max(1),
            tau: 0.95,
            r: 500.0,
        }
    }
}

/// Frames where a new segment must start because the pose jumps: the step
/// from `f - 1` to `f` is over `ratio` times the median step and the pose
/// does not come back at `f + 1` (a one-frame spike is not a jump).
/// `y` is `len × n` row-major in weighted units.
pub fn jumps(y: &[f64], n: usize, ratio: f64, floor: f64) -> Vec<usize> {
    let len = y.len() / n.max(1);
    if len < 3 || n == 0 {
        return Vec::new();
    }
    let dist = |a: usize, b: usize| -> f64 {
        (0..n)
            .map(|c| (y[a * n + c] - y[b * n + c]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let steps: Vec<f64> = (1..len).map(|f| dist(f, f - 1)).collect();
    let mut sorted = steps.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let limit = (median * ratio).max(floor);
    (1..len)
        .filter(|&f| {
            // Not the way into a spike, nor the way out of one.
            let stays = f + 1 >= len || dist(f + 1, f - 1) > limit / 2.0;
            let lasts = f < 2 || dist(f, f - 2) > limit / 2.0;
            steps[f - 1] > limit && stays && lasts
        })
        .collect()
}

/// PPCA cut points inside `[start, end)` of `y` (`len × n`). A model
/// window never grows past `max_len` frames: where it would without a cut,
/// the segment is cut at the window's end (at the rise's peak if H was
/// rising), so no segment is longer and each step's work is bounded.
pub fn ppca_cuts(
    y: &[f64],
    n: usize,
    start: usize,
    end: usize,
    p: &Ppca,
    max_len: usize,
) -> Vec<usize> {
    let mut cuts = Vec::new();
    let mut s = start;
    if n == 0 {
        return cuts;
    }
    'segments: while s + p.k0 + p.t <= end {
        let mut k = p.k0;
        let mut valley = f64::INFINITY;
        let mut rising: Option<(usize, f64)> = None;
        while s + k + p.t <= end {
            if k > max_len && k > p.k0 {
                let at = rising.map_or(s + k - p.delta, |(at, _)| at);
                cuts.push(at);
                s = at;
                continue 'segments;
            }
            let h = distance(y, n, s, s + k, s + k + p.t, p.tau);
            if let Some((at, peak)) = rising {
                if h < peak {
                    cuts.push(at);
                    s = at;
                    continue 'segments;
                }
                rising = Some((s + k, h));
            } else if h - valley > p.r {
                rising = Some((s + k, h));
            }
            valley = valley.min(h);
            k += p.delta;
        }
        if let Some((at, _)) = rising {
            if at + p.delta < end {
                cuts.push(at);
                s = at;
                continue;
            }
        }
        break;
    }
    cuts
}

/// Mean Mahalanobis distance of frames `[from, to)` to the PPCA model of
/// frames `[s, from)`.
fn distance(y: &[f64], n: usize, s: usize, from: usize, to: usize, tau: f64) -> f64 {
    let count = (from - s) as f64;
    let mut mean = vec![0.0; n];
    for f in s..from {
        for c in 0..n {
            mean[c] += y[f * n + c] / count;
        }
    }
    let centred = DMatrix::from_fn(from - s, n, |f, c| y[(s + f) * n + c] - mean[c]);
    let cov = centred.transpose() * &centred / count;
    let eig = SymmetricEigen::new(cov);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let values: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i].max(0.0)).collect();
    let total: f64 = values.iter().sum();
    let mut r = 0;
    let mut acc = 0.0;
    while r < n && acc < tau * total {
        acc += values[r];
        r += 1;
    }
    let rest = n - r;
    // σ²: mean discarded variance, floored so rank-deficient models
    // (more channels than frames) stay finite.
    let floor = (total / n as f64) * 1e-3 + 1e-12;
    let sigma2 = if rest > 0 {
        (values[r..].iter().sum::<f64>() / rest as f64).max(floor)
    } else {
        floor
    };
    let mut h = 0.0;
    for f in from..to {
        let d: Vec<f64> = (0..n).map(|c| y[f * n + c] - mean[c]).collect();
        let norm2: f64 = d.iter().map(|v| v * v).sum();
        let mut inside = 0.0;
        let mut m = 0.0;
        for (i, &oi) in order.iter().take(r).enumerate() {
            let u = eig.eigenvectors.column(oi);
            let p: f64 = u.iter().zip(&d).map(|(a, b)| a * b).sum();
            inside += p * p;
            m += p * p / values[i].max(floor);
        }
        m += (norm2 - inside).max(0.0) / sigma2;
        h += m;
    }
    h / (to - from) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_jump_and_ignores_a_spike() {
        let n = 2;
        let mut y: Vec<f64> = (0..100).flat_map(|f| [f as f64 * 0.1, 0.0]).collect();
        for f in 40..100 {
            y[f * n + 1] = 50.0; // jump at 40, stays
        }
        y[70 * n] += 30.0; // spike at 70
        assert_eq!(jumps(&y, n, 20.0, 1.0), vec![40]);
    }

    #[test]
    fn ppca_cuts_between_two_behaviours() {
        // 3 channels: first 400 frames move in channel 0, then in channel 1-2.
        let n = 3;
        let y: Vec<f64> = (0..800)
            .flat_map(|f| {
                let t = f as f64 * 0.05;
                if f < 400 {
                    [t.sin() * 10.0, 0.1 * t.cos(), 0.0]
                } else {
                    [0.1 * t.sin(), t.cos() * 10.0, (t * 0.7).sin() * 8.0]
                }
            })
            .collect();
        let cuts = ppca_cuts(&y, n, 0, 800, &Ppca::paper(120.0), usize::MAX);
        assert!(!cuts.is_empty(), "no cut");
        assert!(cuts.iter().any(|&c| (350..=450).contains(&c)), "{cuts:?}");
    }

    #[test]
    fn ppca_window_is_bounded() {
        // One behaviour throughout: no cut, unless the window is bounded.
        let n = 2;
        let y: Vec<f64> = (0..3000)
            .flat_map(|f| {
                let t = f as f64 * 0.05;
                [t.sin() * 10.0, t.cos() * 5.0]
            })
            .collect();
        let p = Ppca::paper(120.0);
        assert!(ppca_cuts(&y, n, 0, 3000, &p, usize::MAX).is_empty());
        let cuts = ppca_cuts(&y, n, 0, 3000, &p, 600);
        assert!(!cuts.is_empty());
        let mut last = 0;
        for &c in cuts.iter().chain([3000].iter()) {
            assert!(c - last <= 600 + p.t, "{cuts:?}");
            last = c;
        }
    }
}
