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

/// A frame's four control rows and their weights ([`row`]).
type Rw = ([usize; 4], [f64; 4]);

/// Midpoint insertion overshoots: drop every key whose removal keeps the
/// worst error within `max(tol, the current worst)`.
///
/// Each key is tried by the least-squares fit of the whole curve without
/// it, exactly as [`fit`] computes it, but from the fit that holds: a
/// frame whose four keys do not include the dropped one keeps its weights,
/// so only the normal equations' rows near the key are summed again (the
/// same terms in the same order), the Cholesky factor and forward solution
/// are kept above them, and a candidate is rejected at the first frame over
/// the limit, looked for near the key first.
fn prune(
    data: &[f64],
    k: usize,
    tol: f64,
    error: &impl Fn(&[f64]) -> f64,
    times: Vec<u32>,
    controls: Vec<f64>,
) -> (Vec<u32>, Vec<f64>) {
    let (now, _) = worst(data, k, &times, error);
    let limit = tol.max(now);
    let mut sys = System::new(data, k, times, controls);
    let mut trial = Trial::default();
    let mut i = 1;
    while i + 1 < sys.times.len() {
        trial.without(&sys, data, k, i);
        if trial.within(&sys, data, k, i, limit, error) {
            sys.accept(&mut trial, i);
        } else {
            i += 1;
        }
    }
    (sys.times, sys.controls)
}

/// The fit at the kept keys, with what a trial reuses.
struct System {
    times: Vec<u32>,
    /// Each frame's rows and weights.
    rw: Vec<Rw>,
    /// The normal equations as summed (band rows), and their right-hand
    /// sides (`m × k`).
    a: Vec<[f64; 4]>,
    b: Vec<f64>,
    /// The ridge scale, Cholesky factor and forward solution of `a`, `b`.
    scale: f64,
    l: Vec<[f64; 4]>,
    y: Vec<f64>,
    controls: Vec<f64>,
}

impl System {
    fn new(data: &[f64], k: usize, times: Vec<u32>, controls: Vec<f64>) -> System {
        let len = data.len() / k;
        let m = times.len();
        let rw: Vec<Rw> = (0..len).map(|f| row(&times, f as u32)).collect();
        let mut band = Band::new(m);
        let mut b = vec![0.0; m * k];
        for (f, (rows, w)) in rw.iter().enumerate() {
            for a in 0..4 {
                for q in 0..4 {
                    band.add(rows[a], rows[q], w[a] * w[q]);
                }
                for j in 0..k {
                    b[rows[a] * k + j] += w[a] * data[f * k + j];
                }
            }
        }
        let a = band.a;
        let scale = ridge_scale(&a);
        let mut l = a.clone();
        factor(&mut l, 0, scale);
        let mut y = b.clone();
        forward(&l, &mut y, k, 0);
        System {
            times,
            rw,
            a,
            b,
            scale,
            l,
            y,
            controls,
        }
    }

    /// Takes the trial that dropped key `r`.
    fn accept(&mut self, t: &mut Trial, r: usize) {
        self.times.remove(r);
        for (f, rw) in self.rw.iter_mut().enumerate() {
            if (t.aff.0..t.aff.1).contains(&f) {
                *rw = t.new_rows[f - t.aff.0];
            } else {
                rw.0 = shift(rw.0, r);
            }
        }
        std::mem::swap(&mut self.a, &mut t.a);
        std::mem::swap(&mut self.b, &mut t.b);
        std::mem::swap(&mut self.l, &mut t.l);
        std::mem::swap(&mut self.y, &mut t.y);
        std::mem::swap(&mut self.controls, &mut t.x);
        self.scale = t.scale;
    }
}

/// Rows past the dropped key `r` move one up.
fn shift(rows: [usize; 4], r: usize) -> [usize; 4] {
    rows.map(|q| if q > r { q - 1 } else { q })
}

/// The fit without one key.
#[derive(Default)]
struct Trial {
    fewer: Vec<u32>,
    /// Frames whose four keys include the dropped one, and their new rows
    /// and weights.
    aff: (usize, usize),
    new_rows: Vec<Rw>,
    /// Frames whose rows meet the rows summed again.
    near: (usize, usize),
    a: Vec<[f64; 4]>,
    b: Vec<f64>,
    scale: f64,
    l: Vec<[f64; 4]>,
    y: Vec<f64>,
    x: Vec<f64>,
    delta: Vec<f64>,
}

impl Trial {
    fn rows(&self, sys: &System, f: usize, r: usize) -> Rw {
        if (self.aff.0..self.aff.1).contains(&f) {
            self.new_rows[f - self.aff.0]
        } else {
            let (rows, w) = sys.rw[f];
            (shift(rows, r), w)
        }
    }

    /// The fit of `sys` without key `r` (`0 < r < m − 1`).
    fn without(&mut self, sys: &System, data: &[f64], k: usize, r: usize) {
        let m = sys.times.len() - 1;
        let len = sys.rw.len();
        self.fewer.clear();
        self.fewer.extend_from_slice(&sys.times[..r]);
        self.fewer.extend_from_slice(&sys.times[r + 1..]);
        // Rows are monotone in the frame: the frames that used key r are
        // one run.
        let fa = sys.rw.partition_point(|(rows, _)| rows[3] < r);
        let fb = sys.rw.partition_point(|(rows, _)| rows[0] <= r);
        self.aff = (fa, fb);
        self.new_rows.clear();
        let fewer = &self.fewer;
        self.new_rows.extend((fa..fb).map(|f| row(fewer, f as u32)));
        // Band rows r − 3 ..= r + 2 (in the new numbering) are the ones
        // those frames touch, now or before; every other row sums the same
        // terms as it did.
        let (lo, hi) = (r.saturating_sub(3), (r + 2).min(m - 1));
        self.a.clear();
        self.a.extend_from_slice(&sys.a[..r]);
        self.a.extend_from_slice(&sys.a[r + 1..]);
        self.b.clear();
        self.b.extend_from_slice(&sys.b[..r * k]);
        self.b.extend_from_slice(&sys.b[(r + 1) * k..]);
        for x in lo..=hi {
            self.a[x] = [0.0; 4];
            self.b[x * k..(x + 1) * k].fill(0.0);
        }
        // Frames of the intervals lo − 2 ..= hi + 1.
        let f0 = self.fewer[lo.saturating_sub(2)] as usize;
        let f1 = (self.fewer[(hi + 2).min(m - 1)] as usize + 1).min(len);
        self.near = (f0, f1);
        for f in f0..f1 {
            let (rows, w) = self.rows(sys, f, r);
            for a in 0..4 {
                let x = rows[a];
                if x < lo || x > hi {
                    continue;
                }
                for q in 0..4 {
                    if rows[q] <= x {
                        self.a[x][x - rows[q]] += w[a] * w[q];
                    }
                }
                for j in 0..k {
                    self.b[x * k + j] += w[a] * data[f * k + j];
                }
            }
        }
        // The factor and forward solution hold above row lo when the ridge
        // is the same.
        self.scale = ridge_scale(&self.a);
        let from = if self.scale.to_bits() == sys.scale.to_bits() {
            lo
        } else {
            0
        };
        self.l.clear();
        self.l.extend_from_slice(&sys.l[..from]);
        self.l.extend_from_slice(&self.a[from..]);
        factor(&mut self.l, from, self.scale);
        self.y.clear();
        self.y.extend_from_slice(&sys.y[..from * k]);
        self.y.extend_from_slice(&self.b[from * k..]);
        forward(&self.l, &mut self.y, k, from);
        self.x.clone_from(&self.y);
        backward(&self.l, &mut self.x, k);
    }

    /// True if no frame's error exceeds `limit` ([`worst`]'s figures).
    fn within(
        &mut self,
        sys: &System,
        data: &[f64],
        k: usize,
        r: usize,
        limit: f64,
        error: &impl Fn(&[f64]) -> f64,
    ) -> bool {
        let len = sys.rw.len();
        self.delta.resize(k, 0.0);
        let (lo, hi) = self.near;
        for f in (lo..hi).chain(0..lo).chain(hi..len) {
            let (rows, w) = self.rows(sys, f, r);
            for j in 0..k {
                // `evaluate`'s sum, term for term.
                let fitted: f64 = (0..4).map(|a| w[a] * self.x[rows[a] * k + j]).sum();
                self.delta[j] = data[f * k + j] - fitted;
            }
            if error(&self.delta) > limit {
                return false;
            }
        }
        true
    }
}

/// The ridge [`Band::solve`] adds: a tiny share of the largest diagonal.
fn ridge_scale(a: &[[f64; 4]]) -> f64 {
    a.iter().map(|r| r[0]).fold(0.0f64, f64::max).max(1e-300)
}

/// Adds the ridge to rows `from..` of `l` (the summed band rows) and
/// factors them in place, rows above `from` being factored already.
fn factor(l: &mut [[f64; 4]], from: usize, scale: f64) {
    let m = l.len();
    for r in &mut l[from..] {
        r[0] += scale * 1e-12;
    }
    for i in from..m {
        for d in (0..=3.min(i)).rev() {
            let j = i - d;
            let mut s = l[i][d];
            for e in 1..=3 {
                // Σ_{q < j} L[i][q] L[j][q], q = j - e.
                if e > j || d + e > 3 {
                    continue;
                }
                s -= l[i][d + e] * l[j][e];
            }
            if d == 0 {
                l[i][0] = s.max(1e-300).sqrt();
            } else {
                l[i][d] = s / l[j][0];
            }
        }
    }
}

/// `L y = b` for rows `from..` (`y` holds `b` there and `y` above), `k`
/// right-hand sides.
fn forward(l: &[[f64; 4]], y: &mut [f64], k: usize, from: usize) {
    for c in 0..k {
        for i in from..l.len() {
            let mut s = y[i * k + c];
            for d in 1..=3.min(i) {
                s -= l[i][d] * y[(i - d) * k + c];
            }
            y[i * k + c] = s / l[i][0];
        }
    }
}

/// `Lᵀ x = y` in place.
fn backward(l: &[[f64; 4]], x: &mut [f64], k: usize) {
    let m = l.len();
    for c in 0..k {
        for i in (0..m).rev() {
            let mut s = x[i * k + c];
            for d in 1..=3 {
                if i + d < m {
                    s -= l[i + d][d] * x[(i + d) * k + c];
                }
            }
            x[i * k + c] = s / l[i][0];
        }
    }
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
        debug_assert_eq!(self.a.len(), self.m);
        // A tiny ridge keeps rows of keys no frame weighs positive.
        let scale = ridge_scale(&self.a);
        factor(&mut self.a, 0, scale);
        forward(&self.a, rhs, k, 0);
        backward(&self.a, rhs, k);
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
