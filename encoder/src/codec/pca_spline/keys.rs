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
/// it, the very numbers [`fit`] computes, but worked out from the fit that
/// holds (a [`System`]): a frame whose four keys do not include the dropped
/// one keeps its weights, so only the normal equations' rows near the key
/// are summed again (the same terms in the same order); the Cholesky
/// factor, forward and backward solutions are computed outwards from there
/// only until three rows in a row come out bit for bit as before (the
/// recurrences then give the old rows everywhere further out); and only the
/// frames whose rows or controls changed are measured — every other frame's
/// error is what it was, within the limit. A candidate is rejected at the
/// first frame over the limit. The cost of a trial is local, so pruning a
/// segment is linear in its keys.
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
    let mut sys = System::new(data, k, times);
    debug_assert!(sys.x == controls, "the system solves as fit does");
    let mut trial = Trial::default();
    let mut i = 1;
    while i + 1 < sys.times.len() {
        trial.without(&sys, data, k, i);
        if trial.within(&sys, data, k, i, limit, error) {
            sys.accept(&mut trial, k, i);
        } else {
            i += 1;
        }
    }
    (sys.times, sys.x)
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
    /// The ridge scale of `a`, and the largest diagonal of `a` before row
    /// `i` (`pre[i]`) and from row `i` on (`suf[i]`).
    scale: f64,
    pre: Vec<f64>,
    suf: Vec<f64>,
    /// The Cholesky factor, forward and backward solutions (`x`: the
    /// controls).
    l: Vec<[f64; 4]>,
    y: Vec<f64>,
    x: Vec<f64>,
}

impl System {
    fn new(data: &[f64], k: usize, times: Vec<u32>) -> System {
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
        factor(&mut l, scale);
        let mut y = b.clone();
        forward(&l, &mut y, k);
        let mut x = y.clone();
        backward(&l, &mut x, k);
        let mut sys = System {
            times,
            rw,
            a,
            b,
            scale,
            pre: Vec::new(),
            suf: Vec::new(),
            l,
            y,
            x,
        };
        sys.diagonal_maxima();
        sys
    }

    fn diagonal_maxima(&mut self) {
        let m = self.a.len();
        self.pre = vec![0.0; m + 1];
        self.suf = vec![0.0; m + 1];
        for i in 0..m {
            self.pre[i + 1] = self.pre[i].max(self.a[i][0]);
        }
        for i in (0..m).rev() {
            self.suf[i] = self.suf[i + 1].max(self.a[i][0]);
        }
    }

    /// Takes the trial that dropped key `r`.
    fn accept(&mut self, t: &mut Trial, k: usize, r: usize) {
        self.times.remove(r);
        for (f, rw) in self.rw.iter_mut().enumerate() {
            if (t.aff.0..t.aff.1).contains(&f) {
                *rw = t.new_rows[f - t.aff.0];
            } else {
                rw.0 = shift(rw.0, r);
            }
        }
        self.a.remove(r);
        self.b.drain(r * k..(r + 1) * k);
        self.a[t.lo..t.lo + t.arows.len()].copy_from_slice(&t.arows);
        self.b[t.lo * k..(t.lo * k + t.brows.len())].copy_from_slice(&t.brows);
        self.scale = t.scale;
        self.diagonal_maxima();
        self.l.remove(r);
        self.l[t.from..t.from + t.lnew.len()].copy_from_slice(&t.lnew);
        self.y.drain(r * k..(r + 1) * k);
        self.y[t.from * k..t.from * k + t.ynew.len()].copy_from_slice(&t.ynew);
        self.x.drain(r * k..(r + 1) * k);
        self.x[t.xstart * k..t.xstart * k + t.xnew.len()].copy_from_slice(&t.xnew);
    }
}

/// Rows past the dropped key `r` move one up.
fn shift(rows: [usize; 4], r: usize) -> [usize; 4] {
    rows.map(|q| if q > r { q - 1 } else { q })
}

/// The fit without one key, as what differs from the [`System`]'s.
#[derive(Default)]
struct Trial {
    fewer: Vec<u32>,
    /// Frames whose four keys include the dropped one, and their new rows
    /// and weights.
    aff: (usize, usize),
    new_rows: Vec<Rw>,
    /// Band rows summed again (`lo..lo + arows.len()`, new numbering).
    lo: usize,
    arows: Vec<[f64; 4]>,
    brows: Vec<f64>,
    scale: f64,
    /// Factor and forward rows computed (`from..`); backward rows computed
    /// (`xstart..`). Past them every row is the system's (one row up).
    from: usize,
    lnew: Vec<[f64; 4]>,
    ynew: Vec<f64>,
    xstart: usize,
    xnew: Vec<f64>,
    /// Frames to measure.
    frames: (usize, usize),
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
        self.lo = lo;
        self.arows.clear();
        self.arows.resize(hi - lo + 1, [0.0; 4]);
        self.brows.clear();
        self.brows.resize((hi - lo + 1) * k, 0.0);
        // Frames of the intervals lo − 2 ..= hi + 1.
        let f0 = self.fewer[lo.saturating_sub(2)] as usize;
        let f1 = (self.fewer[(hi + 2).min(m - 1)] as usize + 1).min(len);
        for f in f0..f1 {
            let (rows, w) = self.rows(sys, f, r);
            for a in 0..4 {
                let x = rows[a];
                if x < lo || x > hi {
                    continue;
                }
                for q in 0..4 {
                    if rows[q] <= x {
                        self.arows[x - lo][x - rows[q]] += w[a] * w[q];
                    }
                }
                for j in 0..k {
                    self.brows[(x - lo) * k + j] += w[a] * data[f * k + j];
                }
            }
        }
        let a_of = |i: usize| -> [f64; 4] {
            if i < lo {
                sys.a[i]
            } else if i <= hi {
                self.arows[i - lo]
            } else {
                sys.a[i + 1]
            }
        };
        let b_of = |i: usize| -> &[f64] {
            if i < lo {
                &sys.b[i * k..(i + 1) * k]
            } else if i <= hi {
                &self.brows[(i - lo) * k..(i - lo + 1) * k]
            } else {
                &sys.b[(i + 1) * k..(i + 2) * k]
            }
        };
        // The ridge: the largest diagonal, as `ridge_scale` finds it.
        let mut biggest = sys.pre[lo].max(sys.suf[(hi + 2).min(m + 1)]);
        for row in &self.arows {
            biggest = biggest.max(row[0]);
        }
        self.scale = biggest.max(1e-300);
        // With the same ridge, every factor row above lo is the system's.
        let same = self.scale.to_bits() == sys.scale.to_bits();
        let from = if same { lo } else { 0 };
        self.from = from;
        // Factor rows from `from`, until three in a row are the system's.
        self.lnew.clear();
        let mut lend = m;
        let mut run = 0;
        for i in from..m {
            let mut ridged = a_of(i);
            ridged[0] += self.scale * 1e-12;
            let lnew = &self.lnew;
            let row = factor_row(
                i,
                ridged,
                |j| {
                    if j < from {
                        sys.l[j]
                    } else {
                        lnew[j - from]
                    }
                },
            );
            self.lnew.push(row);
            if same && i > hi && bits_eq(&row, &sys.l[i + 1]) {
                run += 1;
                if run == 3 && i + 1 >= 4 {
                    lend = i + 1;
                    break;
                }
            } else {
                run = 0;
            }
        }
        let l_of = |i: usize| -> &[f64; 4] {
            if i < from {
                &sys.l[i]
            } else if i < lend {
                &self.lnew[i - from]
            } else {
                &sys.l[i + 1]
            }
        };
        // Forward rows from `from`, until three in a row are the system's
        // past the factor's new rows.
        self.ynew.clear();
        let mut yend = m;
        run = 0;
        let mut out = vec![0.0; k];
        for i in from..m {
            let ynew = &self.ynew;
            forward_row(i, l_of(i), b_of(i), &mut out, |j| {
                if j < from {
                    &sys.y[j * k..(j + 1) * k]
                } else {
                    &ynew[(j - from) * k..(j - from + 1) * k]
                }
            });
            self.ynew.extend_from_slice(&out);
            if same && i > hi && i + 1 >= lend && bits_eq(&out, &sys.y[(i + 1) * k..(i + 2) * k]) {
                run += 1;
                if run == 3 && i + 1 >= 4 {
                    yend = i + 1;
                    break;
                }
            } else {
                run = 0;
            }
        }
        let y_of = |i: usize| -> &[f64] {
            if i < from {
                &sys.y[i * k..(i + 1) * k]
            } else if i < yend {
                &self.ynew[(i - from) * k..(i - from + 1) * k]
            } else {
                &sys.y[(i + 1) * k..(i + 2) * k]
            }
        };
        // Backward rows from yend down (past it: the system's), until
        // three in a row below lo are the system's.
        let mut xs: Vec<f64> = Vec::new(); // rows yend − 1, yend − 2, … down
        let mut xstart = 0;
        run = 0;
        for i in (0..yend).rev() {
            let done = yend - 1 - i;
            let x_at = |j: usize| -> &[f64] {
                if j >= yend {
                    &sys.x[(j + 1) * k..(j + 2) * k]
                } else {
                    let at = (yend - 1 - j) * k;
                    &xs[at..at + k]
                }
            };
            let mut row_out = vec![0.0; k];
            backward_row(i, m, &l_of, y_of(i), &mut row_out, x_at);
            debug_assert_eq!(xs.len(), done * k);
            let old = &sys.x[i * k..(i + 1) * k];
            let equal = bits_eq(&row_out, old);
            xs.extend_from_slice(&row_out);
            if same && i + 2 < lo && equal {
                run += 1;
                if run == 3 {
                    xstart = i;
                    break;
                }
            } else {
                run = 0;
            }
        }
        // xs holds rows yend − 1 down to xstart: store them upwards.
        self.xstart = xstart;
        self.xnew.clear();
        for c in xs.chunks(k).rev() {
            self.xnew.extend_from_slice(c);
        }
        debug_assert_eq!(self.xnew.len(), (yend - xstart) * k);
        // Frames whose rows meet a changed control (in the system's
        // numbering: rows xstart ..= yend), and those that lost the key.
        let ga = sys.rw.partition_point(|(rows, _)| rows[3] < xstart);
        let gb = sys.rw.partition_point(|(rows, _)| rows[0] <= yend);
        self.frames = (ga.min(fa), gb.max(fb));
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
        self.delta.resize(k, 0.0);
        let (lo, hi) = self.frames;
        let from = self.xstart;
        let to = from + self.xnew.len() / k;
        for f in lo..hi {
            let (rows, w) = self.rows(sys, f, r);
            for j in 0..k {
                let x = |q: usize| {
                    if q < from {
                        sys.x[q * k + j]
                    } else if q < to {
                        self.xnew[(q - from) * k + j]
                    } else {
                        sys.x[(q + 1) * k + j]
                    }
                };
                // `evaluate`'s sum, term for term.
                let fitted: f64 = (0..4).map(|a| w[a] * x(rows[a])).sum();
                self.delta[j] = data[f * k + j] - fitted;
            }
            if error(&self.delta) > limit {
                return false;
            }
        }
        true
    }
}

fn bits_eq(a: &[f64], b: &[f64]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The ridge [`Band::solve`] adds: a tiny share of the largest diagonal.
fn ridge_scale(a: &[[f64; 4]]) -> f64 {
    a.iter().map(|r| r[0]).fold(0.0f64, f64::max).max(1e-300)
}

/// Row `i` of the Cholesky factor from its band row (ridge added) and the
/// factor's rows above it (`prev(j)`, `j < i`).
#[inline]
fn factor_row(i: usize, mut row: [f64; 4], prev: impl Fn(usize) -> [f64; 4]) -> [f64; 4] {
    for d in (0..=3.min(i)).rev() {
        let j = i - d;
        let mut s = row[d];
        // Row j of L: the one being factored itself when d = 0.
        let lj = if d > 0 { prev(j) } else { row };
        for e in 1..=3 {
            // Σ_{q < j} L[i][q] L[j][q], q = j - e.
            if e > j || d + e > 3 {
                continue;
            }
            s -= row[d + e] * lj[e];
        }
        if d == 0 {
            row[0] = s.max(1e-300).sqrt();
        } else {
            row[d] = s / lj[0];
        }
    }
    row
}

/// Adds the ridge to `l` (the summed band rows) and factors it in place.
fn factor(l: &mut [[f64; 4]], scale: f64) {
    let m = l.len();
    for r in l.iter_mut() {
        r[0] += scale * 1e-12;
    }
    for i in 0..m {
        let (done, rest) = l.split_at_mut(i);
        rest[0] = factor_row(i, rest[0], |j| done[j]);
    }
}

/// Row `i` of `L y = b`: `out` from `b` (row i), `L[i]` and the rows above
/// (`prev(j)`).
#[inline]
fn forward_row<'a>(
    i: usize,
    li: &[f64; 4],
    b: &[f64],
    out: &mut [f64],
    prev: impl Fn(usize) -> &'a [f64],
) {
    for (c, o) in out.iter_mut().enumerate() {
        let mut s = b[c];
        for (d, l) in li.iter().enumerate().take(3.min(i) + 1).skip(1) {
            s -= l * prev(i - d)[c];
        }
        *o = s / li[0];
    }
}

/// `L y = b` in place (`y` holds `b`), `k` right-hand sides.
fn forward(l: &[[f64; 4]], y: &mut [f64], k: usize) {
    let mut out = vec![0.0; k];
    for (i, li) in l.iter().enumerate() {
        let (done, rest) = y.split_at_mut(i * k);
        forward_row(i, li, &rest[..k], &mut out, |j| &done[j * k..(j + 1) * k]);
        rest[..k].copy_from_slice(&out);
    }
}

/// Row `i` of `Lᵀ x = y` (`m` rows): `out` from `y` (row i), the factor
/// (`l(j)`) and the rows below (`next(j)`, `j > i`).
#[inline]
fn backward_row<'a, 'b>(
    i: usize,
    m: usize,
    l: &impl Fn(usize) -> &'b [f64; 4],
    y: &[f64],
    out: &mut [f64],
    next: impl Fn(usize) -> &'a [f64],
) {
    for (c, o) in out.iter_mut().enumerate() {
        let mut s = y[c];
        for d in 1..=3 {
            if i + d < m {
                s -= l(i + d)[d] * next(i + d)[c];
            }
        }
        *o = s / l(i)[0];
    }
}

/// `Lᵀ x = y` in place.
fn backward(l: &[[f64; 4]], x: &mut [f64], k: usize) {
    let m = l.len();
    let mut out = vec![0.0; k];
    for i in (0..m).rev() {
        let (head, done) = x.split_at_mut((i + 1) * k);
        backward_row(i, m, &|j| &l[j], &head[i * k..], &mut out, |j| {
            &done[(j - i - 1) * k..(j - i) * k]
        });
        head[i * k..].copy_from_slice(&out);
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
        factor(&mut self.a, scale);
        forward(&self.a, rhs, k);
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

    /// The pruning as it was: every trial a full fit of the whole curve.
    fn prune_by_full_fits(
        data: &[f64],
        k: usize,
        tol: f64,
        error: &impl Fn(&[f64]) -> f64,
        mut times: Vec<u32>,
        mut controls: Vec<f64>,
    ) -> (Vec<u32>, Vec<f64>) {
        let (now, _) = worst(data, k, &times, error);
        let limit = tol.max(now);
        let mut i = 1;
        while i + 1 < times.len() {
            let mut fewer = times.clone();
            fewer.remove(i);
            let (w, c) = worst(data, k, &fewer, error);
            if w <= limit {
                times = fewer;
                controls = c;
            } else {
                i += 1;
            }
        }
        (times, controls)
    }

    #[test]
    fn local_pruning_gives_the_full_fits_numbers() {
        // Smooth curves with bumps, glitches and a step: many keys, many
        // dropped, some kept; every tolerance from loose to tight.
        for (len, k) in [(40, 1), (300, 2), (700, 3)] {
            let data: Vec<f64> = (0..len)
                .flat_map(|f| {
                    let t = f as f64 / 60.0;
                    (0..k).map(move |j| {
                        let glitch = if f % 97 == 13 { 40.0 } else { 0.0 };
                        let step = if f > len / 2 { 25.0 * j as f64 } else { 0.0 };
                        300.0 * (t * (1.3 + j as f64)).sin()
                            + 80.0 * (t * 7.1).cos().powi(3)
                            + glitch
                            + step
                    })
                })
                .collect();
            let error = |d: &[f64]| d.iter().map(|x| x * x).sum::<f64>().sqrt();
            for tol in [0.05, 0.5, 2.0, 8.0, 30.0] {
                let last = (len - 1) as u32;
                let mut times: Vec<u32> = (0..=last).step_by(3).collect();
                if times.last() != Some(&last) {
                    times.push(last);
                }
                let controls = fit(&times, &data, k);
                let (t1, c1) = prune(&data, k, tol, &error, times.clone(), controls.clone());
                let (t2, c2) = prune_by_full_fits(&data, k, tol, &error, times.clone(), controls);
                assert_eq!(t1, t2, "len {len} k {k} tol {tol}");
                assert!(
                    c1.iter().zip(&c2).all(|(a, b)| a.to_bits() == b.to_bits()),
                    "len {len} k {k} tol {tol}: controls differ"
                );
                assert!(
                    t1.len() < times.len(),
                    "len {len} k {k} tol {tol}: none dropped"
                );
            }
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
