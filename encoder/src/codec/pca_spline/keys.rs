//! Adaptive key frames for the coefficient curves (METHODS.md §2): start
//! from the ends and the thirds, fit the spline by least squares, insert
//! the middle frame of every interval whose error exceeds the tolerance,
//! repeat. The spline is the decoder's own (`mocap_decoder::spline`), so
//! the fit sees exactly the weights the MCU will use.

use mocap_decoder::spline;

/// Control-point rows and weights of the spline at integer frame `f`
/// (SPEC.md §5.4).
pub fn row(times: &[u32], f: u32) -> ([usize; 4], [f64; 4]) {
    let m = times.len();
    let last = m.saturating_sub(1);
    // Largest i <= m - 2 with t[i] <= f.
    let i = times[..last.max(1)]
        .partition_point(|&t| t <= f)
        .saturating_sub(1);
    let rows = [i.saturating_sub(1), i, (i + 1).min(last), (i + 2).min(last)];
    let t = rows.map(|r| times[r]);
    let w = spline::weights(t, u64::from(f) << 16);
    (rows, w.map(|w| f64::from(w) / 65536.0))
}

/// Least-squares control points (`m × k`, row-major) for the curves
/// `data` (`len × k`, row-major) at key `times`.
pub fn fit(times: &[u32], data: &[f64], k: usize) -> Vec<f64> {
    let m = times.len();
    let len = data.len() / k.max(1);
    let mut band = Band::new(m);
    let mut rhs = vec![0.0; m * k];
    for f in 0..len {
        let (rows, w) = row(times, f as u32);
        for a in 0..4 {
            for b in 0..4 {
                band.add(rows[a], rows[b], w[a] * w[b]);
            }
            for j in 0..k {
                rhs[rows[a] * k + j] += w[a] * data[f * k + j];
            }
        }
    }
    band.solve(&mut rhs, k);
    rhs
}

/// The curves the controls produce, `len × k`.
pub fn evaluate(times: &[u32], controls: &[f64], k: usize, len: usize) -> Vec<f64> {
    let mut out = vec![0.0; len * k];
    for f in 0..len {
        let (rows, w) = row(times, f as u32);
        for j in 0..k {
            out[f * k + j] = (0..4).map(|a| w[a] * controls[rows[a] * k + j]).sum();
        }
    }
    out
}

/// Chooses key times for `data` (`len × k`, `len >= 2`) so that
/// `error(frame residual)` stays within `tol` wherever an interval can still
/// be split; returns the times and the fitted controls.
pub fn select(
    data: &[f64],
    k: usize,
    tol: f64,
    error: impl Fn(&[f64]) -> f64,
) -> (Vec<u32>, Vec<f64>) {
    let len = data.len() / k;
    let last = (len - 1) as u32;
    let mut times: Vec<u32> = vec![0, last / 3, 2 * last / 3, last];
    times.dedup();
    let mut delta = vec![0.0; k];
    loop {
        let controls = fit(&times, data, k);
        let fitted = evaluate(&times, &controls, k, len);
        let mut worst = vec![0.0f64; times.len()];
        for f in 0..len {
            for j in 0..k {
                delta[j] = data[f * k + j] - fitted[f * k + j];
            }
            let e = error(&delta);
            // The interval(s) holding f.
            let i = times.partition_point(|&t| t <= f as u32).saturating_sub(1);
            let i = i.min(times.len() - 2);
            worst[i] = worst[i].max(e);
            if i > 0 && times[i] == f as u32 {
                worst[i - 1] = worst[i - 1].max(e);
            }
        }
        let mut next = Vec::with_capacity(times.len() * 2);
        for i in 0..times.len() - 1 {
            next.push(times[i]);
            if worst[i] > tol && times[i + 1] - times[i] >= 2 {
                next.push((times[i] + times[i + 1]) / 2);
            }
        }
        next.push(last);
        if next.len() == times.len() {
            return prune(data, k, tol, &error, times, controls);
        }
        times = next;
    }
}

/// Worst frame error of the fit at `times`, and the controls.
fn worst(data: &[f64], k: usize, times: &[u32], error: &impl Fn(&[f64]) -> f64) -> (f64, Vec<f64>) {
    let len = data.len() / k;
    let controls = fit(times, data, k);
    let fitted = evaluate(times, &controls, k, len);
    let mut delta = vec![0.0; k];
    let mut w = 0.0f64;
    for f in 0..len {
        for j in 0..k {
            delta[j] = data[f * k + j] - fitted[f * k + j];
        }
        w = w.max(error(&delta));
    }
    (w, controls)
}

/// Each frame's control rows and weights at `times` ([`row`]).
fn rows_of(times: &[u32], len: usize) -> Vec<([usize; 4], [f64; 4])> {
    (0..len).map(|f| row(times, f as u32)).collect()
}

/// The rows and weights at `times` without key `r`, from those at `times`
/// (`rw`): a frame whose four keys do not include `r` keeps its weights
/// (the same four key times), its rows past `r` one lower; the others are
/// computed anew.
fn rows_without(
    rw: &[([usize; 4], [f64; 4])],
    fewer: &[u32],
    r: usize,
    into: &mut Vec<([usize; 4], [f64; 4])>,
) {
    into.clear();
    into.extend(rw.iter().enumerate().map(|(f, &(rows, w))| {
        if rows.contains(&r) {
            row(fewer, f as u32)
        } else {
            (rows.map(|q| if q > r { q - 1 } else { q }), w)
        }
    }));
}

/// [`fit`] from each frame's rows and weights (the same sums in the same
/// order, so the same controls).
fn fit_rows(rw: &[([usize; 4], [f64; 4])], m: usize, data: &[f64], k: usize) -> Vec<f64> {
    let mut band = Band::new(m);
    let mut rhs = vec![0.0; m * k];
    for (f, (rows, w)) in rw.iter().enumerate() {
        for a in 0..4 {
            for b in 0..4 {
                band.add(rows[a], rows[b], w[a] * w[b]);
            }
            for j in 0..k {
                rhs[rows[a] * k + j] += w[a] * data[f * k + j];
            }
        }
    }
    band.solve(&mut rhs, k);
    rhs
}

/// The controls of the fit at the keys `rw` stands for, if no frame's
/// error exceeds `limit` ([`worst`]'s figures, with frames between
/// `near.0` and `near.1` looked at first: where a dropped key shows).
fn fit_within(
    data: &[f64],
    k: usize,
    rw: &[([usize; 4], [f64; 4])],
    m: usize,
    near: (usize, usize),
    limit: f64,
    error: &impl Fn(&[f64]) -> f64,
) -> Option<Vec<f64>> {
    let len = rw.len();
    let controls = fit_rows(rw, m, data, k);
    let mut delta = vec![0.0; k];
    let (lo, hi) = (near.0.min(len), near.1.min(len));
    for f in (lo..hi).chain(0..lo).chain(hi..len) {
        let (rows, w) = &rw[f];
        for j in 0..k {
            // `evaluate`'s sum, term for term.
            let fitted: f64 = (0..4).map(|a| w[a] * controls[rows[a] * k + j]).sum();
            delta[j] = data[f * k + j] - fitted;
        }
        if error(&delta) > limit {
            return None;
        }
    }
    Some(controls)
}

/// Midpoint insertion overshoots: drop every key whose removal keeps the
/// worst error within `max(tol, the current worst)`.
fn prune(
    data: &[f64],
    k: usize,
    tol: f64,
    error: &impl Fn(&[f64]) -> f64,
    mut times: Vec<u32>,
    mut controls: Vec<f64>,
) -> (Vec<u32>, Vec<f64>) {
    let len = data.len() / k;
    let (now, _) = worst(data, k, &times, error);
    let limit = tol.max(now);
    let mut rw = rows_of(&times, len);
    let mut trial = Vec::with_capacity(len);
    let mut i = 1;
    while i + 1 < times.len() {
        let mut fewer = times.clone();
        fewer.remove(i);
        rows_without(&rw, &fewer, i, &mut trial);
        let near = (
            times[i.saturating_sub(2)] as usize,
            times[(i + 2).min(times.len() - 1)] as usize + 1,
        );
        match fit_within(data, k, &trial, fewer.len(), near, limit, error) {
            Some(c) => {
                times = fewer;
                controls = c;
                std::mem::swap(&mut rw, &mut trial);
            }
            None => i += 1,
        }
    }
    (times, controls)
}

/// A symmetric positive-definite matrix with half-bandwidth 3 (the normal
/// equations of a four-point spline), solved by banded Cholesky.
struct Band {
    m: usize,
    /// `a[i][d]` = element (i, i - d), d = 0..=3.
    a: Vec<[f64; 4]>,
}

impl Band {
    fn new(m: usize) -> Band {
        Band {
            m,
            a: vec![[0.0; 4]; m],
        }
    }

    fn add(&mut self, i: usize, j: usize, v: f64) {
        if j <= i {
            self.a[i][i - j] += v;
        }
    }

    /// Solves in place for `k` right-hand sides (`rhs` is `m × k`).
    fn solve(mut self, rhs: &mut [f64], k: usize) {
        let m = self.m;
        // A tiny ridge keeps rows of keys no frame weighs positive.
        let scale = self
            .a
            .iter()
            .map(|r| r[0])
            .fold(0.0f64, f64::max)
            .max(1e-300);
        for r in &mut self.a {
            r[0] += scale * 1e-12;
        }
        // L in place.
        for i in 0..m {
            for d in (0..=3.min(i)).rev() {
                let j = i - d;
                let mut s = self.a[i][d];
                for e in 1..=3 {
                    // Σ_{q < j} L[i][q] L[j][q], q = j - e.
                    if e > j || d + e > 3 {
                        continue;
                    }
                    s -= self.a[i][d + e] * self.a[j][e];
                }
                if d == 0 {
                    self.a[i][0] = s.max(1e-300).sqrt();
                } else {
                    self.a[i][d] = s / self.a[j][0];
                }
            }
        }
        for c in 0..k {
            // L y = b
            for i in 0..m {
                let mut s = rhs[i * k + c];
                for d in 1..=3.min(i) {
                    s -= self.a[i][d] * rhs[(i - d) * k + c];
                }
                rhs[i * k + c] = s / self.a[i][0];
            }
            // Lᵀ x = y
            for i in (0..m).rev() {
                let mut s = rhs[i * k + c];
                for d in 1..=3 {
                    if i + d < m {
                        s -= self.a[i + d][d] * rhs[(i + d) * k + c];
                    }
                }
                rhs[i * k + c] = s / self.a[i][0];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_solver_matches_dense() {
        // Fit with keys at every frame: the spline interpolates exactly.
        let data: Vec<f64> = (0..9).map(|f| ((f * f) % 7) as f64).collect();
        let times: Vec<u32> = (0..9).collect();
        let c = fit(&times, &data, 1);
        for (a, b) in c.iter().zip(&data) {
            assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        }
    }

    #[test]
    fn smooth_curve_needs_few_keys() {
        let len = 240;
        let data: Vec<f64> = (0..len)
            .flat_map(|f| {
                let t = f as f64 / 120.0;
                [1000.0 * (t * 3.0).sin(), 500.0 * (t * 1.3).cos()]
            })
            .collect();
        let tol = 5.0;
        let (times, controls) = select(&data, 2, tol, |d| {
            d.iter().map(|x| x * x).sum::<f64>().sqrt()
        });
        eprintln!("{} keys", times.len());
        assert!(times.len() < 30, "{} keys", times.len());
        let fitted = evaluate(&times, &controls, 2, len);
        let worst = data
            .iter()
            .zip(&fitted)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst <= tol, "{worst}");
    }
}
