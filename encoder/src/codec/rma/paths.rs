//! The self-distance plot and its similar-posture paths (Lin et al. 2011,
//! §4.2.1): pixel `(i, j)`, `i < j`, is the distance between the projected
//! coefficients of analysis frames `i` and `j`. Only the upper half is
//! computed (the plot is symmetric), and of it only a band: `j − i` from the
//! shortest path kept (nearer pairs are the same movement, not a
//! repetition) up to [`Params::window_s`], so the plot of a take of any
//! length costs time and memory linear in its length.
//!
//! 1. Suppress pixels above the band's [`Params::threshold_quantile`].
//! 2. Label the 1-D minima (along `i` or along `j`) and 2-D minima (both).
//! 3. From each 2-D minimum not yet on a path, in increasing distance, grow
//!    a minimum-cost path through labelled pixels towards the lower right
//!    (`i + 1`, `j + 1` or both) and the upper left.
//! 4. Join a path's end to another's start by a bridge of at most
//!    [`Params::bridge_s`] (Manhattan), nearest first.
//! 5. Drop paths shorter than [`Params::min_path_s`] (Manhattan).

use super::{Features, Params};

/// A similar-posture path: analysis-frame pairs `(i, j)`, `i < j`, with `i`
/// and `j` non-decreasing and each step moving one or both by one — frame
/// `i` looks like frame `j`.
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    /// The pixels, in order.
    pub points: Vec<(usize, usize)>,
}

impl Path {
    /// First pixel.
    pub fn start(&self) -> (usize, usize) {
        self.points[0]
    }

    /// Last pixel.
    pub fn end(&self) -> (usize, usize) {
        self.points[self.points.len() - 1]
    }

    /// Manhattan length, analysis frames.
    pub fn manhattan(&self) -> usize {
        let (s, e) = (self.start(), self.end());
        (e.0 - s.0) + (e.1 - s.1)
    }
}

/// The band of the self-distance plot.
struct Band {
    len: usize,
    /// Smallest `j − i` in the band.
    gap: usize,
    /// Columns per row: `j − i` from `gap` to `gap + width − 1`.
    width: usize,
    d: Vec<f32>,
}

impl Band {
    fn new(f: &Features, gap: usize, width: usize) -> Band {
        let len = f.len;
        let mut d = vec![f32::INFINITY; len * width];
        for i in 0..len {
            for w in 0..width {
                let j = i + gap + w;
                if j >= len {
                    break;
                }
                d[i * width + w] = f.dist(i, j) as f32;
            }
        }
        Band { len, gap, width, d }
    }

    fn at(&self, i: usize, j: usize) -> Option<usize> {
        (j >= i + self.gap && j < self.len && j - i - self.gap < self.width)
            .then(|| i * self.width + (j - i - self.gap))
    }

    fn get(&self, i: isize, j: isize) -> f32 {
        if i < 0 || j < 0 {
            return f32::INFINITY;
        }
        self.at(i as usize, j as usize)
            .map_or(f32::INFINITY, |k| self.d[k])
    }
}

/// The similar-posture paths of `f` (see the module documentation).
pub fn find(f: &Features, p: &Params) -> Vec<Path> {
    let min_path = f.frames_of(p.min_path_s);
    let gap = min_path;
    let width = f.frames_of(p.window_s);
    if f.len <= gap || f.k == 0 {
        return Vec::new();
    }
    let band = Band::new(f, gap, width);
    // 1. The threshold: a quantile of the band's finite distances.
    let Some(threshold) = quantile(&band.d, p.threshold_quantile) else {
        return Vec::new();
    };
    // 2. Labels: bit 0 a minimum along i, bit 1 along j (both: 2-D);
    // USED once on a path.
    let mut label = vec![0u8; band.d.len()];
    let mut seeds = Vec::new();
    for i in 0..band.len {
        for w in 0..band.width {
            let j = i + band.gap + w;
            let k = i * band.width + w;
            let v = band.d[k];
            if j >= band.len || v > threshold {
                continue;
            }
            let (ii, jj) = (i as isize, j as isize);
            let along_i = v <= band.get(ii - 1, jj) && v <= band.get(ii + 1, jj);
            let along_j = v <= band.get(ii, jj - 1) && v <= band.get(ii, jj + 1);
            label[k] = u8::from(along_i) | (u8::from(along_j) << 1);
            if label[k] == 3 {
                seeds.push((v, i, j));
            }
        }
    }
    seeds.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
    // 3. Grow a path both ways from every 2-D minimum not yet on one.
    let mut paths = Vec::new();
    for &(_, i, j) in &seeds {
        let k = band.at(i, j).unwrap_or(0);
        if label[k] & USED != 0 {
            continue;
        }
        label[k] |= USED;
        let forward = grow(&band, &mut label, (i, j), 1);
        let backward = grow(&band, &mut label, (i, j), -1);
        let mut points: Vec<(usize, usize)> = backward.into_iter().rev().collect();
        points.push((i, j));
        points.extend(forward);
        paths.push(Path { points });
    }
    // 4. Bridges, 5. length.
    let paths = bridge(paths, f.frames_of(p.bridge_s));
    paths
        .into_iter()
        .filter(|p| p.manhattan() >= min_path)
        .collect()
}

/// The `q` quantile of the finite values of `d` (non-negative), the
/// `⌊(n − 1) q⌋`-th smallest: selected by two counting passes over the
/// values' bits (non-negative floats order as their bit patterns), high
/// half then low half, so the band is not copied.
fn quantile(d: &[f32], q: f64) -> Option<f32> {
    let finite = || d.iter().filter(|v| v.is_finite()).map(|v| v.to_bits());
    let n = finite().count();
    let mut rank = (n.checked_sub(1)? as f64 * q) as usize;
    let mut counts = vec![0usize; 1 << 16];
    for b in finite() {
        counts[(b >> 16) as usize] += 1;
    }
    let high = pick(&counts, &mut rank);
    counts.fill(0);
    for b in finite().filter(|b| b >> 16 == high) {
        counts[(b & 0xffff) as usize] += 1;
    }
    let low = pick(&counts, &mut rank);
    Some(f32::from_bits(high << 16 | low))
}

/// The bucket holding the `rank`-th value of `counts`; `rank` becomes the
/// rank within it.
fn pick(counts: &[usize], rank: &mut usize) -> u32 {
    for (bucket, &c) in counts.iter().enumerate() {
        if *rank < c {
            return bucket as u32;
        }
        *rank -= c;
    }
    0
}

/// A pixel's label bit: on a path.
const USED: u8 = 4;

/// The pixels from `from` (excluded) following the cheapest labelled,
/// unused neighbour in direction `dir` (+1: lower right, −1: upper left).
fn grow(band: &Band, label: &mut [u8], from: (usize, usize), dir: isize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let (mut i, mut j) = (from.0 as isize, from.1 as isize);
    loop {
        let mut best: Option<(f32, isize, isize, usize)> = None;
        for (di, dj) in [(dir, dir), (dir, 0), (0, dir)] {
            let (ni, nj) = (i + di, j + dj);
            if ni < 0 || nj < 0 {
                continue;
            }
            let Some(k) = band.at(ni as usize, nj as usize) else {
                continue;
            };
            if label[k] & 3 == 0 || label[k] & USED != 0 {
                continue;
            }
            let v = band.d[k];
            if best.is_none_or(|b| v < b.0) {
                best = Some((v, ni, nj, k));
            }
        }
        let Some((_, ni, nj, k)) = best else {
            return out;
        };
        label[k] |= USED;
        (i, j) = (ni, nj);
        out.push((i as usize, j as usize));
    }
}

/// Joins a path's end to the nearest start of another path lying to its
/// lower right within `max` (Manhattan), through a straight bridge, until
/// no join is left.
fn bridge(mut paths: Vec<Path>, max: usize) -> Vec<Path> {
    paths.sort_by_key(|p| p.start());
    let mut a = 0;
    while a < paths.len() {
        let (ia, ja) = paths[a].end();
        let mut best: Option<(usize, usize)> = None;
        // Paths stay sorted by start (a join keeps the head's): the
        // candidates start at rows ia..=ia + max.
        let from = paths.partition_point(|p| p.start().0 < ia);
        let to = paths.partition_point(|p| p.start().0 <= ia + max);
        for (b, pb) in paths.iter().enumerate().take(to).skip(from) {
            let (ib, jb) = pb.start();
            if b == a || ib < ia || jb < ja || (ib, jb) == (ia, ja) {
                continue;
            }
            let d = (ib - ia) + (jb - ja);
            if d <= max && best.is_none_or(|x| d < x.0) {
                best = Some((d, b));
            }
        }
        let Some((_, b)) = best else {
            a += 1;
            continue;
        };
        let tail = paths.remove(b);
        if b < a {
            a -= 1;
        }
        let (ib, jb) = tail.start();
        // The bridge: one step at a time, diagonal while both still move.
        let (mut i, mut j) = (ia, ja);
        while (i, j) != (ib, jb) {
            let (di, dj) = (ib - i, jb - j);
            if di > 0 && (dj == 0 || di * 2 >= dj) {
                i += 1;
            }
            if dj > 0 && (di == 0 || dj * 2 >= di) {
                j += 1;
            }
            if (i, j) != (ib, jb) {
                paths[a].points.push((i, j));
            }
        }
        paths[a].points.extend(tail.points);
    }
    paths
}

#[cfg(test)]
mod tests {
    use super::quantile;

    #[test]
    fn quantile_is_the_selected_value() {
        let mut x = 12345u64;
        let mut d: Vec<f32> = (0..5000)
            .map(|i| {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                match i % 7 {
                    0 => f32::INFINITY,
                    1 => 0.0,
                    2 => 3.5,
                    _ => (x >> 40) as f32 / 1000.0,
                }
            })
            .collect();
        for q in [0.0, 0.02, 0.15, 0.5, 0.999, 1.0] {
            let mut finite: Vec<f32> = d.iter().copied().filter(|v| v.is_finite()).collect();
            let k = ((finite.len() - 1) as f64 * q) as usize;
            let (_, &mut want, _) = finite.select_nth_unstable_by(k, f32::total_cmp);
            assert_eq!(quantile(&d, q), Some(want), "q {q}");
        }
        d.retain(|v| !v.is_finite());
        assert_eq!(quantile(&d, 0.5), None);
        assert_eq!(quantile(&[], 0.5), None);
    }
}
