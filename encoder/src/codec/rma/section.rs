//! The `rma` codec's section (SPEC.md §12): which frames are repeated, the
//! piecewise-linear reference map `Ref(t)` of each repeated clip into its
//! primary, and which channels add the primary's value; the `pca-spline`
//! body that follows is written by [`crate::codec::pca_spline`].

use mocap_decoder::rma::{FORM, MAX_KNOT_GAP, REF_FRAC_BITS};

use super::{Clip, ClipKind};
use crate::container::{varint, zigzag};

/// A repeated clip as the section codes it.
#[derive(Clone, Debug, PartialEq)]
pub struct Repeated {
    /// First frame.
    pub start: u32,
    /// Last frame (inclusive).
    pub last: u32,
    /// Knots of `Ref(t)`: frame relative to `start` (the first 0,
    /// increasing) and the reference in `1/256` frames.
    pub knots: Vec<(u32, i32)>,
    /// Its primary's first and last frame (the encoder keeps `Ref(t)`
    /// inside; not written).
    pub primary: (u32, u32),
}

impl Repeated {
    /// `Ref(t)` at frame `t` of the clip, in frames.
    pub fn reference_at(&self, t: u32) -> f64 {
        at_knots(&self.knots, t) / f64::from(1u32 << REF_FRAC_BITS)
    }
}

/// What the section says besides its body.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Plan {
    /// Channels that add the primary's value in a repeated clip, sorted.
    pub added: Vec<usize>,
    /// Repeated clips in time order.
    pub repeated: Vec<Repeated>,
}

impl Plan {
    /// The plan of an analysis: every repeated clip, its reference map a
    /// line between the analysis's reference frames every `knot_every`
    /// frames (and at its last frame), kept inside its primary clip; the
    /// frame-by-frame references of the 30 fps analysis step like stairs,
    /// and a residual against a stair-stepped reading costs more keys than
    /// the clip on its own (BENCHMARKS.md §9).
    pub fn new(clips: &[Clip], added: Vec<usize>, knot_every: usize) -> Plan {
        let every = knot_every.clamp(1, MAX_KNOT_GAP as usize - 1);
        let repeated = clips
            .iter()
            .filter_map(|c| {
                let ClipKind::Repeated { primary, reference } = &c.kind else {
                    return None;
                };
                let p = clips.get(*primary)?;
                let (lo, hi) = (p.start as i64, p.end.saturating_sub(1) as i64);
                let len = c.end - c.start;
                let mut at: Vec<usize> = (0..len).step_by(every).collect();
                if at.last() != Some(&(len - 1)) {
                    at.push(len - 1);
                }
                let knots = at
                    .into_iter()
                    .map(|t| {
                        let r = reference.get(t).map_or(lo, |&r| r as i64).clamp(lo, hi);
                        (t as u32, (r << REF_FRAC_BITS) as i32)
                    })
                    .collect();
                Some(Repeated {
                    start: c.start as u32,
                    last: (c.end - 1) as u32,
                    knots,
                    primary: (lo as u32, hi as u32),
                })
            })
            .collect();
        Plan { added, repeated }
    }

    /// Refines every clip's `Ref(t)`: each repeated frame's reference
    /// moves to the primary frame nearest its posture within `radius`
    /// frames of where the knots put it (the analysis's coarser rate), to
    /// a fraction of a frame by a parabola through the distances around
    /// the best; the knots are then the fewest whose line stays within
    /// `tolerance` frames of those references (Douglas–Peucker), so a
    /// clip that repeats at one speed costs two knots and the residual is
    /// what the repetition does differently, not the analysis's step.
    /// Distances are over `channels` of `values` (`[channel][frame]`),
    /// each scaled by its weight.
    pub fn refine(
        &mut self,
        values: &[Vec<i32>],
        weights: &[f64],
        channels: &[usize],
        radius: usize,
        tolerance: f64,
    ) {
        let dist = |a: usize, b: usize| -> f64 {
            channels
                .iter()
                .map(|&c| (f64::from(values[c][a] - values[c][b]) * weights[c]).powi(2))
                .sum()
        };
        let unit = f64::from(1u32 << REF_FRAC_BITS);
        for r in &mut self.repeated {
            let (lo, hi) = (r.primary.0 as usize, r.primary.1 as usize);
            let len = (r.last - r.start) as usize + 1;
            let best: Vec<f64> = (0..len)
                .map(|t| {
                    let guess = (at_knots(&r.knots, t as u32) / unit).round().max(0.0) as usize;
                    let frame = r.start as usize + t;
                    let from = guess.saturating_sub(radius).max(lo);
                    let to = (guess + radius).min(hi);
                    let Some(best) =
                        (from..=to).min_by(|&a, &b| dist(frame, a).total_cmp(&dist(frame, b)))
                    else {
                        return guess.clamp(lo, hi) as f64;
                    };
                    let mut at = best as f64;
                    // (An exact match stays on its frame.)
                    if best > lo && best < hi && dist(frame, best) > 0.0 {
                        let (a, m, b) = (
                            dist(frame, best - 1),
                            dist(frame, best),
                            dist(frame, best + 1),
                        );
                        let curve = a - 2.0 * m + b;
                        if curve > 0.0 {
                            at += (0.5 * (a - b) / curve).clamp(-0.5, 0.5);
                        }
                    }
                    at
                })
                .collect();
            let mut keep = vec![false; len];
            keep[0] = true;
            keep[len - 1] = true;
            simplify(&best, 0, len - 1, tolerance, &mut keep);
            r.knots = (0..len)
                .filter(|&t| keep[t])
                .map(|t| (t as u32, (best[t] * unit).round() as i32))
                .collect();
        }
    }

    /// The stretches of frames outside every repeated clip (first, last).
    pub fn own_stretches(&self, frames: usize) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut next = 0usize;
        for r in &self.repeated {
            if (r.start as usize) > next {
                out.push((next, r.start as usize - 1));
            }
            next = r.last as usize + 1;
        }
        if next < frames {
            out.push((next, frames - 1));
        }
        out
    }

    /// Whether frame `f` is in a repeated clip.
    pub fn repeated_at(&self, f: usize) -> bool {
        let i = self.repeated.partition_point(|r| (r.last as usize) < f);
        self.repeated.get(i).is_some_and(|r| r.start as usize <= f)
    }

    /// The section: the plan, then `body` (a `pca-spline` section, §5).
    pub fn to_section(&self, body: &[u8]) -> Vec<u8> {
        let mut out = vec![FORM];
        // Without repeated clips no channel adds anything.
        let runs = if self.repeated.is_empty() {
            Vec::new()
        } else {
            runs(&self.added)
        };
        varint(&mut out, runs.len() as u32);
        let mut next = 0;
        for (s, len) in runs {
            varint(&mut out, s - next);
            varint(&mut out, len);
            next = s + len;
        }
        varint(&mut out, self.repeated.len() as u32);
        let mut base = 0;
        for r in &self.repeated {
            varint(&mut out, r.start - base);
            varint(&mut out, r.last - r.start);
            varint(&mut out, r.knots.len() as u32);
            let (mut t0, mut v0) = (0, (r.start as i32) << REF_FRAC_BITS);
            for &(t, v) in &r.knots {
                varint(&mut out, t - t0);
                zigzag(&mut out, v.wrapping_sub(v0));
                (t0, v0) = (t, v);
            }
            base = r.last + 1;
        }
        out.extend_from_slice(body);
        out
    }
}

/// Figures of an `rma` section for `mocap info`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SectionInfo {
    /// Channels that add the primary's value.
    pub added: usize,
    /// Repeated clips.
    pub repeated: usize,
    /// Frames in repeated clips.
    pub repeated_frames: usize,
    /// Knots of their reference maps.
    pub knots: usize,
    /// Bytes before the body (the channel runs and the clip records).
    pub plan_bytes: usize,
    /// The repeated clips as written (`primary` is where their references
    /// reach: the lowest and highest whole frame of `Ref`).
    pub clips: Vec<Repeated>,
    /// The body.
    pub body: crate::codec::pca_spline::SectionInfo,
}

impl SectionInfo {
    /// The lines `mocap info` prints for the section.
    pub fn describe(&self) -> String {
        format!(
            "  rma codec: {} repeated clips ({} frames, {} knots), {} channels add the primary, {} bytes before the body\n{}",
            self.repeated,
            self.repeated_frames,
            self.knots,
            self.added,
            self.plan_bytes,
            self.body.describe()
        )
    }
}

/// Reads the figures back from a section (already validated by the
/// decoder); `None` if it does not parse.
pub fn inspect(section: &[u8]) -> Option<SectionInfo> {
    let mut r = crate::container::ByteCursor::new(section);
    r.u8()?;
    let mut info = SectionInfo::default();
    for _ in 0..r.varint()? {
        r.varint()?;
        info.added += r.varint()? as usize;
    }
    info.repeated = r.varint()? as usize;
    let mut base = 0u32;
    for _ in 0..info.repeated {
        let start = base.checked_add(r.varint()?)?;
        let last = start.checked_add(r.varint()?)?;
        info.repeated_frames += (last - start) as usize + 1;
        let m = r.varint()? as usize;
        info.knots += m;
        let (mut t, mut v) = (0u32, (start as i32).wrapping_shl(REF_FRAC_BITS));
        let mut knots = Vec::with_capacity(m.min(1 << 16));
        for _ in 0..m {
            t = t.checked_add(r.varint()?)?;
            v = v.wrapping_add(mocap_decoder::wire::zigzag_decode(r.varint()?));
            knots.push((t, v));
        }
        let whole = |v: i32| (v >> REF_FRAC_BITS).max(0) as u32;
        let lo = knots.iter().map(|k| whole(k.1)).min().unwrap_or(0);
        let hi = knots.iter().map(|k| whole(k.1)).max().unwrap_or(0);
        info.clips.push(Repeated {
            start,
            last,
            knots,
            primary: (lo, hi),
        });
        base = last + 1;
    }
    info.plan_bytes = r.pos();
    info.body = crate::codec::pca_spline::inspect(section.get(r.pos()..)?)?;
    Some(info)
}

/// The figures of a clip's `rma` section (the clip's bytes); `None` for a
/// clip of another codec or one that does not parse.
pub fn inspect_clip(clip: &[u8]) -> Option<SectionInfo> {
    let clip = mocap_decoder::Clip::parse(clip).ok()?;
    let section = clip
        .sections()
        .find(|s| s.id == mocap_decoder::consts::SECTION_CODEC_RMA)?;
    inspect(section.bytes)
}

/// Sorted channel indices as runs (first, length).
pub fn runs(channels: &[usize]) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = Vec::new();
    for &c in channels {
        let c = c as u32;
        match out.last_mut() {
            Some((s, len)) if *s + *len == c => *len += 1,
            _ => out.push((c, 1)),
        }
    }
    out
}

/// `Ref(t)` of `knots` at `t` (in 1/256 frames; held past the last knot).
fn at_knots(knots: &[(u32, i32)], t: u32) -> f64 {
    let i = knots.partition_point(|k| k.0 <= t);
    match (i.checked_sub(1).and_then(|i| knots.get(i)), knots.get(i)) {
        (Some(&(t0, v0)), Some(&(t1, v1))) => {
            let w = f64::from(t - t0) / f64::from(t1 - t0);
            f64::from(v0) + w * f64::from(v1 - v0)
        }
        (Some(&(_, v)), None) | (None, Some(&(_, v))) => f64::from(v),
        (None, None) => 0.0,
    }
}

/// Douglas–Peucker on `y[a..=b]` (`a` and `b` kept): marks in `keep` the
/// points that hold every other point within `tolerance` of the lines
/// between kept points. Iterative, so a long clip cannot overflow the stack.
fn simplify(y: &[f64], a: usize, b: usize, tolerance: f64, keep: &mut [bool]) {
    let mut todo = vec![(a, b)];
    while let Some((a, b)) = todo.pop() {
        if b <= a + 1 {
            continue;
        }
        let line = |t: usize| y[a] + (y[b] - y[a]) * (t - a) as f64 / (b - a) as f64;
        let (far, off) = (a + 1..b)
            .map(|t| (t, (y[t] - line(t)).abs()))
            .fold((a, 0.0), |m, x| if x.1 > m.1 { x } else { m });
        if off > tolerance {
            keep[far] = true;
            todo.push((a, far));
            todo.push((far, b));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_join_neighbours() {
        assert_eq!(runs(&[0, 1, 2, 5, 7, 8]), vec![(0, 3), (5, 1), (7, 2)]);
        assert!(runs(&[]).is_empty());
    }

    #[test]
    fn own_stretches_are_the_complement() {
        let plan = Plan {
            added: vec![],
            repeated: vec![
                Repeated {
                    start: 3,
                    last: 5,
                    knots: vec![(0, 0)],
                    primary: (0, 2),
                },
                Repeated {
                    start: 6,
                    last: 9,
                    knots: vec![(0, 0)],
                    primary: (0, 2),
                },
            ],
        };
        assert_eq!(plan.own_stretches(12), vec![(0, 2), (10, 11)]);
        assert_eq!(plan.own_stretches(10), vec![(0, 2)]);
        assert!(plan.repeated_at(3) && plan.repeated_at(9) && !plan.repeated_at(10));
        assert!(!plan.repeated_at(2));
    }

    #[test]
    fn simplify_keeps_the_corners_only() {
        let line: Vec<f64> = (0..50).map(|t| 100.0 + 0.8 * t as f64).collect();
        let mut keep = vec![false; 50];
        (keep[0], keep[49]) = (true, true);
        simplify(&line, 0, 49, 0.5, &mut keep);
        assert_eq!(keep.iter().filter(|&&k| k).count(), 2);
        let kink: Vec<f64> = (0..50).map(|t| (t as f64).min(20.0)).collect();
        let mut keep = vec![false; 50];
        (keep[0], keep[49]) = (true, true);
        simplify(&kink, 0, 49, 0.5, &mut keep);
        let kept: Vec<usize> = (0..50).filter(|&t| keep[t]).collect();
        assert_eq!(kept, vec![0, 20, 49]);
    }

    #[test]
    fn refine_finds_an_exact_repetition_in_two_knots() {
        // Frames 100..189 repeat frames 10..99 exactly; the analysis's
        // guess is off by three frames and stair-stepped.
        let wave = |f: usize| ((f as f64 * 0.05).sin() * 300.0 + f as f64 * 20.0) as i32;
        let values: Vec<Vec<i32>> = (0..2)
            .map(|c| {
                (0..200)
                    .map(|f| if f >= 100 { wave(f - 90) } else { wave(f) } + c * 7)
                    .collect()
            })
            .collect();
        let mut plan = Plan {
            added: vec![0, 1],
            repeated: vec![Repeated {
                start: 100,
                last: 189,
                knots: (0..90)
                    .step_by(16)
                    .chain([89])
                    .map(|t| (t, ((13 + t / 2 * 2) as i32) << REF_FRAC_BITS))
                    .collect(),
                primary: (0, 99),
            }],
        };
        plan.refine(&values, &[1.0, 1.0], &[0, 1], 4, 0.5);
        let r = &plan.repeated[0];
        assert_eq!(r.knots.len(), 2, "{:?}", r.knots);
        for t in 0..90 {
            let at = r.reference_at(t);
            assert!((at - (10 + t) as f64).abs() < 0.5, "Ref({t}) = {at}");
        }
    }
}
