//! Primary, repeated and unique clips (Lin et al. 2011, §4.2.2): the
//! endpoints of the similar-posture paths, projected on the time axis, cut
//! the take into candidate intervals; greedily, the free interval with the
//! largest gain (eq. 5) becomes a primary clip and the free frames its
//! paths map it onto become its repeated clips, each frame with its
//! reference frame `Ref(t)` in the primary; what is left becomes unique
//! clips. Repeated clips shorter than [`Params::min_clip_s`] go back to the
//! unique ones.
//!
//! Costs, in the projected coefficients' units ([`Features::dist`]):
//! `PriCost(s, e) = stdev(Dist(m, f), f = s…e) · (e − s + 1) + Dist(m, s)`
//! (eq. 2; `m` the middle frame, the clip's first frame as its initial
//! posture) and `RepCost = stdev(Dist(Ref(f), f)) · length` (eq. 3), plus
//! the paper's "small constants" for a clip's overhead:
//! [`PRIMARY_OVERHEAD`] and [`REPEATED_OVERHEAD`] times the coefficients'
//! spread.

use super::{Features, Params, Path};

/// Most neighbouring intervals a candidate primary clip spans.
pub const SPAN: usize = 4;

/// A primary clip's overhead, in units of [`Features::spread`].
pub const PRIMARY_OVERHEAD: f64 = 0.5;
/// A repeated clip's overhead, in units of [`Features::spread`].
pub const REPEATED_OVERHEAD: f64 = 0.25;

/// What a clip is.
#[derive(Clone, Debug, PartialEq)]
pub enum ClipKind {
    /// Coded on its own; repeated clips refer to it.
    Primary,
    /// Coded as residuals against a primary clip.
    Repeated {
        /// Index of the primary clip in [`super::Analysis::clips`].
        primary: usize,
        /// For each frame of the clip, its reference frame (a source frame
        /// of the primary clip).
        reference: Vec<usize>,
    },
    /// Coded on its own; nothing refers to it.
    Unique,
}

/// A clip: source frames `start..end`.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// First source frame.
    pub start: usize,
    /// One past the last source frame.
    pub end: usize,
    /// Its kind.
    pub kind: ClipKind,
}

/// One direction of a path: frames `start..start + refs.len()` (the
/// repeated side) each with the frame it looks like (the reference side,
/// non-decreasing); the first reference of each frame where the path
/// moves along the reference side only.
struct Map {
    start: usize,
    refs: Vec<usize>,
}

impl Map {
    fn of(path: &Path, flip: bool) -> Map {
        let pairs = path
            .points
            .iter()
            .map(|&(i, j)| if flip { (i, j) } else { (j, i) });
        let mut start = None;
        let mut refs = Vec::new();
        for (y, x) in pairs {
            let s = *start.get_or_insert(y);
            if y - s == refs.len() {
                refs.push(x);
            }
        }
        Map {
            start: start.unwrap_or(0),
            refs,
        }
    }

    fn end(&self) -> usize {
        self.start + self.refs.len()
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Label {
    Free,
    /// Primary clip `n` (in the order found).
    Primary(usize),
    /// Repeated, with its reference analysis frame.
    Repeated(usize),
}

fn stdev(v: impl Iterator<Item = f64> + Clone) -> f64 {
    let n = v.clone().count().max(1) as f64;
    let mean = v.clone().sum::<f64>() / n;
    (v.map(|x| (x - mean) * (x - mean)).sum::<f64>() / n).sqrt()
}

fn primary_cost(f: &Features, s: usize, e: usize) -> f64 {
    let m = (s + e - 1) / 2;
    stdev((s..e).map(|t| f.dist(m, t))) * (e - s) as f64
        + f.dist(m, s)
        + PRIMARY_OVERHEAD * f.spread
}

/// A repeated run: `(frame, reference frame)` pairs, frames consecutive.
type Run = Vec<(usize, usize)>;

fn repeated_cost(f: &Features, run: &[(usize, usize)]) -> f64 {
    stdev(run.iter().map(|&(t, r)| f.dist(r, t))) * run.len() as f64 + REPEATED_OVERHEAD * f.spread
}

/// Analysis frames per block of [`MapIndex`].
const BLOCK: usize = 64;

/// Which maps touch which analysis frames, by blocks of [`BLOCK`] frames:
/// the maps whose reference side and whose repeated side meet each block,
/// so that a candidate's images and a labelled frame's dependants are
/// looked up among the maps nearby, not among all of them.
struct MapIndex {
    by_ref: Vec<Vec<usize>>,
    by_frame: Vec<Vec<usize>>,
}

impl MapIndex {
    fn new(maps: &[Map], len: usize) -> MapIndex {
        let blocks = len.div_ceil(BLOCK).max(1);
        let mut by_ref = vec![Vec::new(); blocks];
        let mut by_frame = vec![Vec::new(); blocks];
        for (n, m) in maps.iter().enumerate() {
            if let (Some(&lo), Some(&hi)) = (m.refs.first(), m.refs.last()) {
                for b in &mut by_ref[lo / BLOCK..=hi / BLOCK] {
                    b.push(n);
                }
                for b in &mut by_frame[m.start / BLOCK..=(m.end() - 1) / BLOCK] {
                    b.push(n);
                }
            }
        }
        MapIndex { by_ref, by_frame }
    }

    /// The maps that may refer into `s..e`, in order.
    fn referring_into(&self, s: usize, e: usize) -> Vec<usize> {
        let mut ids: Vec<usize> = self.by_ref[s / BLOCK..=(e - 1) / BLOCK]
            .iter()
            .flatten()
            .copied()
            .collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    }
}

/// The repeated runs `[(frame, reference)]` that `maps` give the interval
/// `s..e`: free frames outside it whose reference lies in it, each taken
/// once (the maps in order), in runs of consecutive frames of at least
/// `min` frames.
fn images(
    maps: &[Map],
    index: &MapIndex,
    label: &[Label],
    s: usize,
    e: usize,
    min: usize,
) -> Vec<Run> {
    let mut taken = std::collections::HashSet::new();
    let mut runs: Vec<Run> = Vec::new();
    for m in index.referring_into(s, e).into_iter().map(|n| &maps[n]) {
        // References are non-decreasing: the frames referring into s..e
        // are one range.
        let first = m.refs.partition_point(|&x| x < s);
        let last = m.refs.partition_point(|&x| x < e);
        let before = runs.len();
        let mut run: Vec<(usize, usize)> = Vec::new();
        for (k, &x) in m.refs.iter().enumerate().take(last).skip(first) {
            let y = m.start + k;
            let ok = !(s..e).contains(&y) && label[y] == Label::Free && !taken.contains(&y);
            if ok {
                run.push((y, x));
            } else if !run.is_empty() {
                if run.len() >= min {
                    runs.push(std::mem::take(&mut run));
                } else {
                    run.clear();
                }
            }
        }
        if run.len() >= min {
            runs.push(run);
        }
        for r in &runs[before..] {
            taken.extend(r.iter().map(|&(y, _)| y));
        }
    }
    runs
}

/// A candidate primary clip's standing in the greedy search.
#[derive(Clone, Copy)]
enum Standing {
    /// Overlaps a labelled frame: never a candidate again.
    Out,
    /// Its images changed since its gain was computed.
    Stale,
    /// Its gain (eq. 5), if it has repetitions worth the coding.
    Gain(Option<f64>),
}

/// The gain (eq. 5) of taking `s..e` as a primary clip with `runs` as its
/// repeated clips, if it is one.
fn gain(f: &Features, s: usize, e: usize, runs: &[Run]) -> Option<f64> {
    if runs.is_empty() {
        return None;
    }
    let pri = primary_cost(f, s, e);
    let original: f64 = pri
        + runs
            .iter()
            .map(|r| primary_cost(f, r[0].0, r[r.len() - 1].0 + 1))
            .sum::<f64>();
    let improved: f64 = pri + runs.iter().map(|r| repeated_cost(f, r)).sum::<f64>();
    let gain = original / improved.max(f64::MIN_POSITIVE);
    (gain > 1.0).then_some(gain)
}

/// The clips of a take of `frames` source frames (see the module
/// documentation).
///
/// The greedy search keeps every candidate's gain between rounds and
/// recomputes only those whose images a round's labels touched (found
/// through the maps near the labelled frames), so a long take costs time
/// near-linear in its length; the result is the same as recomputing every
/// gain every round.
pub fn extract(f: &Features, paths: &[Path], p: &Params, frames: usize) -> Vec<Clip> {
    extract_with(f, paths, p, frames, false)
}

/// [`extract`], recomputing every gain every round if `exhaustive` (the
/// plain greedy search, which the tests hold the kept gains against).
pub(super) fn extract_with(
    f: &Features,
    paths: &[Path],
    p: &Params,
    frames: usize,
    exhaustive: bool,
) -> Vec<Clip> {
    let len = f.len;
    let min = f.frames_of(p.min_clip_s);
    let maps: Vec<Map> = paths
        .iter()
        .flat_map(|path| [Map::of(path, false), Map::of(path, true)])
        .collect();
    let index = MapIndex::new(&maps, len);
    let mut cuts: Vec<usize> = vec![0, len];
    for m in &maps {
        cuts.push(m.start);
        cuts.push(m.end());
    }
    cuts.sort_unstable();
    cuts.dedup();
    // Candidate primaries: the intervals between neighbouring cuts, and
    // runs of up to SPAN of them (where paths are many, single intervals
    // are shorter than the repetitions they could carry). Candidate
    // `a * SPAN + (b − a − 1)` is `cuts[a]..cuts[b]`.
    let candidate = |n: usize| {
        let a = n / SPAN;
        let b = a + 1 + n % SPAN;
        (b < cuts.len()).then(|| (cuts[a], cuts[b]))
    };
    let count = cuts.len() * SPAN;
    let mut standing: Vec<Standing> = (0..count)
        .map(|n| match candidate(n) {
            Some((s, e)) if e - s >= min => Standing::Stale,
            _ => Standing::Out,
        })
        .collect();
    // The candidates holding analysis frame `t`.
    let holding = |t: usize| {
        let k = cuts.partition_point(|&c| c <= t).saturating_sub(1);
        (k.saturating_sub(SPAN - 1)..=k)
            .flat_map(move |a| (k + 1..a + 1 + SPAN).map(move |b| a * SPAN + (b - a - 1)))
    };
    let mut label = vec![Label::Free; len];
    let mut primaries = 0;
    loop {
        let mut best: Option<(f64, usize)> = None;
        for (n, st) in standing.iter_mut().enumerate() {
            if exhaustive && matches!(st, Standing::Gain(_)) {
                *st = Standing::Stale;
            }
            if let Standing::Stale = st {
                let (s, e) = candidate(n).unwrap_or((0, 0));
                *st = Standing::Gain(gain(f, s, e, &images(&maps, &index, &label, s, e, min)));
            }
            if let Standing::Gain(Some(g)) = *st {
                if best.is_none_or(|b| g > b.0) {
                    best = Some((g, n));
                }
            }
        }
        let Some((_, n)) = best else {
            break;
        };
        let (s, e) = candidate(n).unwrap_or((0, 0));
        let runs = images(&maps, &index, &label, s, e, min);
        let mut labelled: Vec<usize> = (s..e).collect();
        for l in &mut label[s..e] {
            *l = Label::Primary(primaries);
        }
        primaries += 1;
        for r in runs {
            for (y, x) in r {
                label[y] = Label::Repeated(x);
                labelled.push(y);
            }
        }
        // The candidates holding a labelled frame are out; those whose
        // images held one (a map's reference of it lies in them) are stale.
        for &y in &labelled {
            for m in index.by_frame[y / BLOCK].iter().map(|&m| &maps[m]) {
                if (m.start..m.end()).contains(&y) {
                    for c in holding(m.refs[y - m.start]) {
                        if let Some(st @ Standing::Gain(_)) = standing.get_mut(c) {
                            *st = Standing::Stale;
                        }
                    }
                }
            }
        }
        for &y in &labelled {
            for c in holding(y) {
                if let Some(st) = standing.get_mut(c) {
                    *st = Standing::Out;
                }
            }
        }
    }
    to_clips(f, &label, min, frames)
}

/// Runs of equal kind → clips at source resolution; repeated runs shorter
/// than `min` analysis frames become unique, and a repeated run is split
/// where its references leave one primary clip.
fn to_clips(f: &Features, label: &[Label], min: usize, frames: usize) -> Vec<Clip> {
    let len = label.len();
    let mut label = label.to_vec();
    // Which primary each repeated frame refers to.
    let primary_of = |l: Label, label: &[Label]| match l {
        Label::Repeated(x) => match label[x] {
            Label::Primary(n) => Some(n),
            _ => None,
        },
        _ => None,
    };
    // Short repeated runs → free (unique).
    let mut s = 0;
    while s < len {
        let key = |t: usize, label: &[Label]| match label[t] {
            Label::Repeated(_) => Some(primary_of(label[t], label)),
            _ => None,
        };
        let k = key(s, &label);
        let mut e = s + 1;
        while e < len && k.is_some() && key(e, &label) == k {
            e += 1;
        }
        if k.is_some() && (e - s < min || k == Some(None)) {
            for l in &mut label[s..e] {
                *l = Label::Free;
            }
        }
        s = e;
    }
    // Analysis runs → source clips.
    let step = f.step;
    let mut clips: Vec<Clip> = Vec::new();
    let mut primary_index: Vec<Option<usize>> = Vec::new();
    let mut s = 0;
    while s < len {
        let class = |l: Label| match l {
            Label::Free => (0, 0),
            Label::Primary(n) => (1, n),
            Label::Repeated(_) => (2, primary_of(l, &label).unwrap_or(0)),
        };
        let c = class(label[s]);
        let mut e = s + 1;
        while e < len && class(label[e]) == c {
            e += 1;
        }
        let (start, end) = (s * step, (e * step).min(frames));
        let kind = match c.0 {
            0 => ClipKind::Unique,
            1 => {
                if primary_index.len() <= c.1 {
                    primary_index.resize(c.1 + 1, None);
                }
                primary_index[c.1] = Some(clips.len());
                ClipKind::Primary
            }
            _ => ClipKind::Repeated {
                primary: c.1, // the primary's number, resolved below
                reference: (start..end)
                    .map(|t| {
                        let a = (t / step).min(len - 1);
                        match label[a] {
                            Label::Repeated(x) => (x * step + t % step).min(frames - 1),
                            _ => t,
                        }
                    })
                    .collect(),
            },
        };
        clips.push(Clip { start, end, kind });
        s = e;
    }
    // Primary numbers → clip indices; a repeated clip whose primary clip is
    // gone (cannot happen: primaries are never unlabelled) becomes unique.
    for c in &mut clips {
        if let ClipKind::Repeated { primary, .. } = &mut c.kind {
            match primary_index.get(*primary).copied().flatten() {
                Some(i) => *primary = i,
                None => c.kind = ClipKind::Unique,
            }
        }
    }
    // Merge neighbouring unique clips.
    let mut merged: Vec<Clip> = Vec::new();
    let mut remap = vec![0; clips.len()];
    for (i, c) in clips.into_iter().enumerate() {
        if let Some(last) = merged.last_mut() {
            if last.kind == ClipKind::Unique && c.kind == ClipKind::Unique {
                last.end = c.end;
                remap[i] = merged.len() - 1;
                continue;
            }
        }
        remap[i] = merged.len();
        merged.push(c);
    }
    for c in &mut merged {
        if let ClipKind::Repeated { primary, .. } = &mut c.kind {
            *primary = remap[*primary];
        }
    }
    merged
}
