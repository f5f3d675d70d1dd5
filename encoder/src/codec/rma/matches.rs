//! Long matches: an extraction of repeated clips for the codec rather than
//! for the paper's gain. The paper's greedy (see [`super::clips`]) takes
//! the interval of largest gain as a primary, which on a take made of a
//! short movement repeated inside a longer one cuts the long repetition
//! into pieces that each point at a different short primary — and each
//! piece then costs a residual segment of its own. Here the similar-posture
//! paths are taken longest first, like the longest match of a dictionary
//! coder: a path's later side becomes a repeated clip referring to its
//! earlier side wherever neither side is taken yet, the references of a
//! clip lie before its first frame (so a clip never refers to itself, and
//! the body read there is the take's own motion, SPEC.md §12.3), and a
//! frame that is referred to is never made a repeated one afterwards; a
//! path into a repeated stretch refers to what that stretch refers to, so
//! the third playing of a movement points at the first like the second.

use super::clips::{Clip, ClipKind};
use super::{Features, Params, Path};

/// The clips of the longest matches of `paths` over `frames` source frames:
/// the stretches between repeated clips are primary clips (unique if
/// nothing refers to them).
pub fn extract(f: &Features, paths: &[Path], p: &Params, frames: usize) -> Vec<Clip> {
    let len = f.len;
    if len == 0 || frames == 0 {
        return vec![Clip {
            start: 0,
            end: frames,
            kind: ClipKind::Unique,
        }];
    }
    let min = ((p.min_path_s * f.rate).ceil() as usize).max(2);
    // Each path as (first repeated analysis frame, its references).
    let mut maps: Vec<(usize, Vec<usize>)> = paths.iter().map(map_of).collect();
    maps.sort_by_key(|m| std::cmp::Reverse(m.1.len()));
    let mut repeated: Vec<Option<usize>> = vec![None; len];
    let mut referred = vec![false; len];
    for (start, refs) in &maps {
        let mut t = 0;
        while t < refs.len() {
            // The longest run from t: free frames whose references are free
            // of repetition and lie before the run's first frame.
            let s = start + t;
            // A reference into a repeated frame goes on to that frame's
            // own reference (one step: references are never repeated).
            let resolve = |r: usize| repeated.get(r).copied().flatten().unwrap_or(r);
            let ok = |u: usize| {
                let frame = start + u;
                frame < len && repeated[frame].is_none() && !referred[frame] && resolve(refs[u]) < s
            };
            if !ok(t) {
                t += 1;
                continue;
            }
            let mut e = t + 1;
            while e < refs.len() && ok(e) {
                e += 1;
            }
            if e - t >= min {
                let resolved: Vec<usize> = refs[t..e].iter().map(|&r| resolve(r)).collect();
                for (u, r) in (t..e).zip(resolved) {
                    repeated[start + u] = Some(r);
                    referred[r] = true;
                }
            }
            t = e;
        }
    }
    to_clips(&repeated, f.step, frames)
}

/// A path's later side with, for each of its frames, the first earlier
/// frame it looks like; without the path's ends where its earlier side
/// stands still (a held reference is a pause the later side does not
/// repeat: the residual there would be the motion itself).
fn map_of(path: &Path) -> (usize, Vec<usize>) {
    let points = &path.points;
    let moving = |k: usize| points[k].0 != points[k + 1].0;
    let first = (0..points.len().saturating_sub(1))
        .find(|&k| moving(k))
        .unwrap_or(0);
    let last = (0..points.len().saturating_sub(1))
        .rev()
        .find(|&k| moving(k))
        .map_or(points.len().saturating_sub(1), |k| k + 1);
    let mut start = None;
    let mut refs = Vec::new();
    for &(i, j) in points.get(first..=last).unwrap_or(&[]) {
        let s = *start.get_or_insert(j);
        if j - s == refs.len() {
            refs.push(i);
        }
    }
    (start.unwrap_or(0), refs)
}

/// Analysis-frame labels → source clips in time order.
fn to_clips(repeated: &[Option<usize>], step: usize, frames: usize) -> Vec<Clip> {
    let len = repeated.len();
    // Runs: (first, end, repeated?) in analysis frames; a repeated run
    // ends where its references stop being consecutive-or-equal.
    let mut runs: Vec<(usize, usize, bool)> = Vec::new();
    let mut s = 0;
    while s < len {
        let mut e = s + 1;
        match repeated[s] {
            None => {
                while e < len && repeated[e].is_none() {
                    e += 1;
                }
            }
            Some(_) => {
                while e < len
                    && matches!((repeated[e - 1], repeated[e]), (Some(a), Some(b)) if b + 1 >= a && b <= a + 4)
                {
                    e += 1;
                }
            }
        }
        runs.push((s, e, repeated[s].is_some()));
        s = e;
    }
    let source = |a: usize| (a * step).min(frames);
    let mut clips: Vec<Clip> = runs
        .iter()
        .map(|&(s, e, _)| Clip {
            start: source(s),
            end: if e == len { frames } else { source(e) },
            kind: ClipKind::Unique,
        })
        .collect();
    for (n, &(s, _, rep)) in runs.iter().enumerate() {
        if !rep {
            continue;
        }
        let (start, end) = (clips[n].start, clips[n].end);
        let reference: Vec<usize> = (start..end)
            .map(|t| {
                let a = (t / step).min(len - 1);
                let r = repeated[a].unwrap_or(repeated[s].unwrap_or(0));
                (r * step + t % step).min(frames - 1)
            })
            .collect();
        // Its primary: the own stretch holding its first reference.
        let first = reference[0];
        let Some(primary) = clips.iter().position(|c| (c.start..c.end).contains(&first)) else {
            continue;
        };
        if matches!(clips[primary].kind, ClipKind::Repeated { .. }) {
            continue;
        }
        // References past the primary's end are held at its last frame.
        let last = clips[primary].end - 1;
        let reference = reference.into_iter().map(|r| r.min(last)).collect();
        clips[primary].kind = ClipKind::Primary;
        clips[n].kind = ClipKind::Repeated { primary, reference };
    }
    clips
}
