//! The patterns of one node: the segments time-normalised to their mean
//! length, grouped by adaptive k-means (K grows until every segment is
//! within the threshold of its centre: the paper's MaxError, eq. 2), then
//! each group's pattern stored at the fewest samples, quantised, that play
//! every member within the channels' tolerances — a member that its group's
//! pattern cannot carry becomes a pattern of its own, which always can.

use mocap_decoder::pattern::{
    interpolate, position, taps, HEAD_WIDE_BASE, LAYOUT_COLUMNS, WIDE_BASE_2,
};

/// One node's motion: its channels' values and tolerances.
pub struct NodeInput<'a> {
    /// `[channel][frame]`, fixed point.
    pub values: Vec<&'a [i32]>,
    /// Per channel, its tolerance (fixed-point units, ≥ 0).
    pub tol: Vec<i64>,
    /// How far a segment may be from its pattern, in tolerances.
    pub accept: Accept,
}

/// How far a segment may be from the pattern that plays it, in
/// tolerances: the paper's MaxError (eq. 2) and AveError (eq. 1), here the
/// largest error of any channel and the RMS over the segment's channels
/// and frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Accept {
    /// Largest error of a channel (≥ 1).
    pub max: f64,
    /// RMS error over the segment.
    pub rms: f64,
}

impl Accept {
    /// Every value within its tolerance: what an angle bound needs.
    pub const STRICT: Accept = Accept { max: 1.0, rms: 1.0 };
    /// Under a joint-position bound, where errors that average out along
    /// the chain and over the frames matter less than the largest: a
    /// channel may reach 5 tolerances if the segment's RMS stays under
    /// 0.6 (measured on 35_01, 05_04 and 01_14 at 50 mm + ARMS 10 mm:
    /// 21 %, 18 % and 18 % smaller than [`Accept::STRICT`]; the search then
    /// proves the bound by decoding).
    pub const POSITIONAL: Accept = Accept { max: 5.0, rms: 0.6 };
}

/// A pattern: `len` samples per channel, each `(base + code) << shift`
/// (SPEC.md §11.3b).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pattern {
    /// Samples per channel.
    pub len: usize,
    /// Per channel: base (in steps of `2^shift`), shift, code width in
    /// bytes (0, 1, 2 or 4; 0 when every code is 0).
    pub heads: Vec<(i32, u8, u8)>,
    /// Per channel, `len` codes.
    pub codes: Vec<Vec<u32>>,
}

impl Pattern {
    /// Plays channel `c` for frame `t` of a segment of `n` frames, exactly
    /// as the decoder does (SPEC.md §11.4, layout 1).
    pub fn play(&self, c: usize, t: usize, n: usize) -> i32 {
        let (j, frac) = position(t as u32, n as u32, self.len as u32);
        let (base, shift, _) = self.heads[c];
        let codes = &self.codes[c];
        let (t, w) = taps(j, self.len as u32, frac);
        interpolate(base, 0, t.map(|i| codes[i as usize]), w).wrapping_shl(u32::from(shift))
    }

    /// Its record in the section in `layout` (§11.3b or §11.3c).
    pub fn record(&self, layout: u8) -> Vec<u8> {
        if layout == LAYOUT_COLUMNS {
            self.record_columns()
        } else {
            self.record_packed()
        }
    }

    /// Its record in layout 1 (§11.3b): sample count, then per channel its
    /// head, its base (`i16` where it fits) and its codes in whole bytes.
    fn record_columns(&self) -> Vec<u8> {
        let mut out = (self.len as u16).to_le_bytes().to_vec();
        for (codes, &(base, shift, width)) in self.codes.iter().zip(&self.heads) {
            let code = match width {
                0 => 0,
                1 => 1,
                2 => 2,
                _ => 3,
            };
            let narrow = i16::try_from(base).ok();
            let wide = if narrow.is_some() { 0 } else { HEAD_WIDE_BASE };
            out.push(shift | code << 5 | wide);
            match narrow {
                Some(b) => out.extend(b.to_le_bytes()),
                None => out.extend(base.to_le_bytes()),
            }
            for c in codes {
                out.extend(&c.to_le_bytes()[..usize::from(width)]);
            }
        }
        out
    }

    /// Its record in layout 2 (§11.3c): sample count, then per channel its
    /// head (code width in bits, wide-base flag), its base (`i16` where it
    /// fits) and its codes bit-packed, LSB first.
    fn record_packed(&self) -> Vec<u8> {
        let mut out = (self.len as u16).to_le_bytes().to_vec();
        for (codes, &(base, _, _)) in self.codes.iter().zip(&self.heads) {
            let bits = codes
                .iter()
                .map(|&c| 32 - c.leading_zeros())
                .max()
                .unwrap_or(0);
            let narrow = i16::try_from(base).ok();
            let wide = if narrow.is_some() { 0 } else { WIDE_BASE_2 };
            out.push(bits as u8 | wide);
            match narrow {
                Some(b) => out.extend(b.to_le_bytes()),
                None => out.extend(base.to_le_bytes()),
            }
            let mut column = vec![0u8; (self.len * bits as usize).div_ceil(8)];
            for (k, &c) in codes.iter().enumerate() {
                for i in 0..bits as usize {
                    if c >> i & 1 == 1 {
                        let at = k * bits as usize + i;
                        column[at / 8] |= 1 << (at % 8);
                    }
                }
            }
            out.extend(column);
        }
        out
    }
}

/// What clustering a node gave: the patterns and each segment's pattern.
pub struct NodePatterns {
    /// The patterns.
    pub patterns: Vec<Pattern>,
    /// Per segment, its pattern.
    pub of_segment: Vec<usize>,
}

impl NodePatterns {
    /// The patterns numbered in the order the segments first play them
    /// (SPEC.md §11.1b codes each segment's pattern as its change from
    /// the one after the last: in this order a new pattern costs nothing).
    /// The same segments play the same patterns.
    pub fn in_order_of_use(self) -> NodePatterns {
        let mut new_of = vec![usize::MAX; self.patterns.len()];
        let mut order = Vec::with_capacity(self.patterns.len());
        for &p in &self.of_segment {
            if new_of[p] == usize::MAX {
                new_of[p] = order.len();
                order.push(p);
            }
        }
        // Patterns no segment plays (none from the clustering) keep their
        // place after the rest.
        for (p, n) in new_of.iter_mut().enumerate() {
            if *n == usize::MAX {
                *n = order.len();
                order.push(p);
            }
        }
        let mut patterns: Vec<Option<Pattern>> = self.patterns.into_iter().map(Some).collect();
        NodePatterns {
            patterns: order.iter().filter_map(|&p| patterns[p].take()).collect(),
            of_segment: self.of_segment.iter().map(|&p| new_of[p]).collect(),
        }
    }
}

/// The k-means threshold: a segment may differ from its centre by this
/// share of a channel's tolerance in the time-normalised space (the rest
/// is left to resampling to its own length and to quantisation).
const THRESHOLD: f64 = 0.6;
/// Lloyd iterations after each growth of K.
const LLOYD: usize = 3;

/// Linear resampling of `x[a..a + n]` to `m` samples (ends kept): the
/// time normalisation the k-means compares segments in.
fn resample(x: &[i32], a: usize, n: usize, m: usize) -> impl Iterator<Item = f64> + '_ {
    (0..m).map(move |i| {
        if n <= 1 || m <= 1 {
            return f64::from(x[a]);
        }
        let u = i as f64 * (n - 1) as f64 / (m - 1) as f64;
        let j = (u.floor() as usize).min(n - 2);
        let f = u - j as f64;
        f64::from(x[a + j]) * (1.0 - f) + f64::from(x[a + j + 1]) * f
    })
}

/// The node's patterns for the segments `spans` (first frame, frames) of
/// its values.
pub fn patterns(node: &NodeInput<'_>, spans: &[(usize, usize)]) -> NodePatterns {
    let groups = kmeans(node, spans);
    let mut patterns = Vec::new();
    let mut of_segment = vec![0; spans.len()];
    for members in groups {
        let mut left = members;
        while !left.is_empty() {
            let (pattern, fits) = fit(node, spans, &left);
            let id = patterns.len();
            patterns.push(pattern);
            let mut rest = Vec::new();
            for (&s, ok) in left.iter().zip(fits) {
                if ok {
                    of_segment[s] = id;
                } else {
                    rest.push(s);
                }
            }
            // A lone segment always fits its own pattern; several that do
            // not fit their group's are tried one by one.
            if rest.len() == left.len() {
                for s in rest.drain(..) {
                    let (p, fits) = fit(node, spans, &[s]);
                    debug_assert!(fits[0], "a segment must fit its own pattern");
                    of_segment[s] = patterns.len();
                    patterns.push(p);
                }
            }
            left = rest;
        }
    }
    NodePatterns {
        patterns,
        of_segment,
    }
}

/// Adaptive k-means on the time-normalised segments (tolerance units):
/// the groups of segment indices.
fn kmeans(node: &NodeInput<'_>, spans: &[(usize, usize)]) -> Vec<Vec<usize>> {
    let mean_len = spans.iter().map(|s| s.1).sum::<usize>() as f64 / spans.len() as f64;
    let m = (mean_len.round() as usize).max(2);
    let scale: Vec<f64> = node.tol.iter().map(|&t| 1.0 / (t.max(1) as f64)).collect();
    let norm: Vec<Vec<f64>> = spans
        .iter()
        .map(|&(a, n)| {
            node.values
                .iter()
                .zip(&scale)
                .flat_map(|(x, &k)| resample(x, a, n, m).map(move |v| v * k))
                .collect()
        })
        .collect();
    let dim = norm[0].len();
    let sq = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>();
    let maxd = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    };
    let nearest = |centres: &[Vec<f64>], v: &[f64]| {
        let mut best = (0, f64::INFINITY);
        for (i, c) in centres.iter().enumerate() {
            let d = sq(c, v);
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    };
    let mut centres: Vec<Vec<f64>> =
        vec![mean_of(&norm, &(0..norm.len()).collect::<Vec<_>>(), dim)];
    let mut assign = vec![0usize; norm.len()];
    loop {
        for _ in 0..LLOYD {
            for (s, v) in norm.iter().enumerate() {
                assign[s] = nearest(&centres, v);
            }
            let mut members = vec![Vec::new(); centres.len()];
            for (s, &c) in assign.iter().enumerate() {
                members[c].push(s);
            }
            for (c, mem) in members.iter().enumerate() {
                if !mem.is_empty() {
                    centres[c] = mean_of(&norm, mem, dim);
                }
            }
        }
        for (s, v) in norm.iter().enumerate() {
            assign[s] = nearest(&centres, v);
        }
        let Accept {
            max: max_k,
            rms: rms_k,
        } = node.accept;
        let rmsd = |a: &[f64], b: &[f64]| (sq(a, b) / a.len().max(1) as f64).sqrt();
        let mut violators: Vec<(f64, usize)> = norm
            .iter()
            .enumerate()
            .map(|(s, v)| {
                let c = &centres[assign[s]];
                ((maxd(v, c) / max_k).max(rmsd(v, c) / rms_k), s)
            })
            .filter(|&(d, _)| d > THRESHOLD)
            .collect();
        if violators.is_empty() {
            break;
        }
        // Grow K: the worst violators, each far from those already added.
        violators.sort_by(|a, b| b.0.total_cmp(&a.0));
        let first = centres.len();
        for &(_, s) in &violators {
            if centres[first..]
                .iter()
                .all(|c| maxd(c, &norm[s]) > THRESHOLD)
            {
                centres.push(norm[s].clone());
            }
        }
    }
    let mut groups = vec![Vec::new(); centres.len()];
    for (s, &c) in assign.iter().enumerate() {
        groups[c].push(s);
    }
    groups.retain(|g| !g.is_empty());
    groups
}

fn mean_of(v: &[Vec<f64>], members: &[usize], dim: usize) -> Vec<f64> {
    let mut m = vec![0.0; dim];
    for &s in members {
        for (a, b) in m.iter_mut().zip(&v[s]) {
            *a += b;
        }
    }
    let k = 1.0 / members.len().max(1) as f64;
    m.iter_mut().for_each(|a| *a *= k);
    m
}

/// The pattern of the segments `members` at the fewest samples that play
/// them within tolerance (a geometric search, then a bisection between the
/// last count that fails and the first that holds), and for each member
/// whether it does; at the longest member's length when none plays all.
fn fit(node: &NodeInput<'_>, spans: &[(usize, usize)], members: &[usize]) -> (Pattern, Vec<bool>) {
    let longest = members
        .iter()
        .map(|&s| spans[s].1)
        .max()
        .unwrap_or(1)
        .max(1);
    let attempt = |len: usize| {
        let p = quantise(node, spans, members, len);
        let fits: Vec<bool> = members
            .iter()
            .map(|&s| plays_within(node, &p, spans[s]))
            .collect();
        (p, fits)
    };
    let holds = |f: &[bool]| f.iter().all(|&x| x);
    let mut fail = 0usize;
    let mut len = 2usize.min(longest);
    let mut found = loop {
        let a = attempt(len);
        if holds(&a.1) {
            break Some((len, a));
        }
        if len >= longest {
            break None;
        }
        fail = len;
        len = (len * 2).min(longest);
    };
    match &mut found {
        None => attempt(longest),
        Some((ok, best)) => {
            while *ok - fail > 1 {
                let mid = (fail + *ok) / 2;
                let a = attempt(mid);
                if holds(&a.1) {
                    *ok = mid;
                    *best = a;
                } else {
                    fail = mid;
                }
            }
            best.clone()
        }
    }
}

/// Whether pattern `p` plays the segment `(a, n)` within `node.accept`.
fn plays_within(node: &NodeInput<'_>, p: &Pattern, (a, n): (usize, usize)) -> bool {
    let Accept {
        max: max_k,
        rms: rms_k,
    } = node.accept;
    let mut sum = 0.0;
    let ok = node
        .values
        .iter()
        .zip(&node.tol)
        .enumerate()
        .all(|(c, (x, &tol))| {
            let lim = (tol as f64 * max_k).floor() as i64;
            (0..n).all(|t| {
                let e = (i64::from(p.play(c, t, n)) - i64::from(x[a + t])).abs();
                let u = e as f64 / tol.max(1) as f64;
                sum += u * u;
                e <= lim.max(tol)
            })
        });
    let count = (n * node.values.len()).max(1) as f64;
    ok && (sum / count).sqrt() <= rms_k
}

/// Samples at `len` points whose curve (§11.4), stretched to each
/// member's length, is closest to the members in the least-squares sense.
/// A frame depends on four neighbouring samples, so the normal equations
/// are banded (three diagonals each side) and solved by a banded Cholesky
/// factorisation.
fn least_squares(x: &[i32], spans: &[(usize, usize)], members: &[usize], len: usize) -> Vec<f64> {
    const B: usize = 3;
    // band[i][k] = A[i][i + k], k = 0..=B.
    let mut band = vec![[0.0f64; B + 1]; len];
    let mut rhs = vec![0.0f64; len];
    for &s in members {
        let (a, n) = spans[s];
        for t in 0..n {
            let (j, frac) = position(t as u32, n as u32, len as u32);
            let (taps, w) = taps(j, len as u32, frac);
            let w = w.map(|w| f64::from(w) / 4096.0);
            let taps = taps.map(|i| i as usize);
            // The frame's row of the design matrix: duplicate taps add.
            let mut row: Vec<(usize, f64)> = Vec::with_capacity(4);
            for (&i, &wi) in taps.iter().zip(&w) {
                match row.iter_mut().find(|(k, _)| *k == i) {
                    Some(e) => e.1 += wi,
                    None => row.push((i, wi)),
                }
            }
            let v = f64::from(x[a + t]);
            for &(i, wi) in &row {
                rhs[i] += wi * v;
                for &(k, wk) in &row {
                    if k >= i {
                        band[i][k - i] += wi * wk;
                    }
                }
            }
        }
    }
    // A faint tie between neighbouring samples keeps the system solvable
    // when a sample no frame touches (it takes its neighbours' value).
    let eps = 1e-6 * band.iter().map(|b| b[0]).sum::<f64>() / len as f64 + 1e-12;
    for j in 0..len.saturating_sub(1) {
        band[j][0] += eps;
        band[j + 1][0] += eps;
        band[j][1] -= eps;
    }
    if len == 1 {
        return vec![rhs[0] / band[0][0]];
    }
    // Banded Cholesky: A = L·Lᵀ, l[i][k] = L[i][i − k].
    let mut l = vec![[0.0f64; B + 1]; len];
    for i in 0..len {
        for k in (0..=B.min(i)).rev() {
            let jj = i - k;
            // A[i][jj] − Σ L[i][m]·L[jj][m] over m < jj within the band.
            let mut sum = band[jj][k];
            for m in 1..=B {
                if k + m <= B && m <= jj {
                    sum -= l[i][k + m] * l[jj][m];
                }
            }
            if k == 0 {
                l[i][0] = sum.max(1e-300).sqrt();
            } else {
                l[i][k] = sum / l[jj][0];
            }
        }
    }
    let mut y = vec![0.0f64; len];
    for i in 0..len {
        let mut sum = rhs[i];
        for k in 1..=B.min(i) {
            sum -= l[i][k] * y[i - k];
        }
        y[i] = sum / l[i][0];
    }
    let mut out = vec![0.0f64; len];
    for i in (0..len).rev() {
        let mut sum = y[i];
        for k in 1..=B {
            if i + k < len {
                sum -= l[i + k][k] * out[i + k];
            }
        }
        out[i] = sum / l[i][0];
    }
    out
}

/// The members' least-squares pattern at `len` samples per channel,
/// quantised with the coarsest power-of-two step at most a third of the
/// channel's tolerance.
fn quantise(
    node: &NodeInput<'_>,
    spans: &[(usize, usize)],
    members: &[usize],
    len: usize,
) -> Pattern {
    let mut heads = Vec::new();
    let mut codes = Vec::new();
    for (x, &tol) in node.values.iter().zip(&node.tol) {
        let mean = least_squares(x, spans, members, len);
        let mut shift = 0u8;
        while shift < 31 && (1i64 << (shift + 1)) <= (tol / 3).max(0) {
            shift += 1;
        }
        // Each sample to the nearest multiple of the step, in steps.
        let step = f64::from(1u32 << shift);
        let lim = f64::from(i32::MAX >> shift);
        let at: Vec<i64> = mean
            .iter()
            .map(|&v| (v / step).round().clamp(-lim - 1.0, lim) as i64)
            .collect();
        let lo = at.iter().copied().min().unwrap_or(0);
        let hi = at.iter().copied().max().unwrap_or(0);
        let range = (hi - lo) as u64;
        let width: u8 = if range == 0 {
            0
        } else if range < 256 {
            1
        } else if range < 65_536 {
            2
        } else {
            4
        };
        codes.push(at.iter().map(|&v| (v - lo) as u32).collect());
        heads.push((lo as i32, shift, width));
    }
    Pattern { len, heads, codes }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeated_cycles_share_one_pattern_within_tolerance() {
        // A sine of period 30 over 300 frames, cut every 30 frames.
        let x: Vec<i32> = (0..300)
            .map(|t| (10_000.0 * (t as f64 * std::f64::consts::TAU / 30.0).sin()) as i32)
            .collect();
        let node = NodeInput {
            values: vec![&x],
            tol: vec![200],
            accept: Accept::STRICT,
        };
        let starts: Vec<usize> = (0..10).map(|i| i * 30).collect();
        let spans: Vec<(usize, usize)> = starts.iter().map(|&a| (a, 30)).collect();
        let np = patterns(&node, &spans);
        assert_eq!(np.patterns.len(), 1);
        assert!(np.of_segment.iter().all(|&p| p == 0));
        for (i, &a) in starts.iter().enumerate() {
            assert!(plays_within(&node, &np.patterns[np.of_segment[i]], (a, 30)));
        }
    }

    #[test]
    fn every_segment_is_played_within_tolerance_even_noise() {
        let mut s = 0x9e37_79b9u32;
        let x: Vec<i32> = (0..200)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                (s % 100_000) as i32 - 50_000
            })
            .collect();
        for tol in [0, 1, 37, 5_000] {
            let node = NodeInput {
                values: vec![&x],
                tol: vec![tol],
                accept: Accept::STRICT,
            };
            let starts = [0, 13, 50, 51, 120];
            let spans: Vec<(usize, usize)> = starts
                .iter()
                .enumerate()
                .map(|(i, &a)| (a, starts.get(i + 1).copied().unwrap_or(200) - a))
                .collect();
            let np = patterns(&node, &spans);
            for (i, &a) in starts.iter().enumerate() {
                let n = starts.get(i + 1).copied().unwrap_or(200) - a;
                assert!(
                    plays_within(&node, &np.patterns[np.of_segment[i]], (a, n)),
                    "{tol} {i}"
                );
            }
        }
    }
}
