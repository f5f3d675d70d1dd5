//! The `pca-spline` codec (SPEC.md §5) after Liu & McMillan (SCA 2006):
//! segments found by PPCA, per-segment weighted PCA of the body channels,
//! adaptive key frames on the component coefficients, root translation and
//! heading as separate key-framed curves, blending across segment borders.
//!
//! All thresholds derive from one tolerance `τ` in weighted units (the
//! caller's channel weights turn channel errors into millimetres or
//! degrees): PCA keeps components until every frame's residual is under
//! `pca_share·τ`, keys are added until the spline error is under
//! `key_share·τ`, and key values are quantised so their error stays near
//! `quant_share·τ`. The encode pipeline (encode/) measures the decoded
//! clip and moves `τ` until the bound holds.

pub mod keys;
pub mod pca;
pub mod section;
pub mod segment;
pub mod weights;

use std::collections::HashMap;
use std::sync::Mutex;

use mocap_decoder::consts::pca::{
    MAX_COMPONENTS, MAX_MEAN_SHIFT, MAX_SEGMENT_FRAMES, MAX_VALUE_BITS, MAX_VALUE_SHIFT,
};
use rayon::prelude::*;

pub use section::{inspect, SectionInfo};
pub use segment::Ppca;
pub use weights::{pca_groups, pca_weights};

use super::CodecError;

/// Encoder parameters; [`Params::new`] gives the defaults.
#[derive(Clone, Debug)]
pub struct Params {
    /// `τ`, in weighted units.
    pub tolerance: f64,
    /// Share of `τ` left to the PCA residual.
    pub pca_share: f64,
    /// Share of `τ` left to the spline.
    pub key_share: f64,
    /// Share of `τ` left to key-value quantisation.
    pub quant_share: f64,
    /// Most components per group and segment.
    pub max_components: usize,
    /// PPCA segmentation; `None` keeps one segment between jumps.
    pub ppca: Option<Ppca>,
    /// Frames blended across a PPCA cut (`h` of the paper; 0 = none).
    pub blend: usize,
    /// A step this many times the median step is a jump.
    pub jump_ratio: f64,
    /// Share of `τ` above which a one-frame spike is taken out of the
    /// smooth model, and above which a decoded value gets a patch.
    pub patch_share: f64,
    /// Longest segment the encoder makes, frames ([`MAX_FIT_SECONDS`]).
    pub max_segment: usize,
    /// Keep the groups as given: a channel constant in this input stays in
    /// its group, and the constants are exactly the channels of no group
    /// (the `rma` codec models stretches of one clip separately, under the
    /// clip's one group table).
    pub fixed_groups: bool,
    /// Uniform key quantisation (the Table 4 baseline of Lin et al.):
    /// every component's keys in a segment at the finest power-of-two step
    /// that spans their range in this many bits. `None`: the step from
    /// `quant_share · τ`, the width from the range (range-aware, adaptive).
    pub key_bits: Option<u8>,
}

/// Longest segment the encoder makes, in seconds (the format allows 32 768
/// frames): choosing a segment's key frames costs the square of its key
/// count (each key dropped is tried by a fit of the whole segment) and the
/// PPCA window grows with the segment, so a long stretch without a change
/// of behaviour — a steady walk of minutes — is cut every
/// `MAX_FIT_SECONDS` at most and the encode time grows linearly with the
/// clip. Keys follow the motion, not the frame rate, hence seconds. No
/// segment of the corpus comes near (the longest: 570 frames at 120 Hz,
/// 4.75 s; the iclone files are at most 517 frames at 60 Hz).
pub const MAX_FIT_SECONDS: f64 = 10.0;

impl Params {
    /// Defaults for a clip at `fps`: the paper's segmentation values scaled
    /// from 120 Hz, a blend of 10 frames at 120 Hz.
    pub fn new(tolerance: f64, fps: f64) -> Params {
        Params {
            tolerance,
            pca_share: 0.6,
            key_share: 0.75,
            quant_share: 0.1,
            key_bits: None,
            max_components: usize::from(MAX_COMPONENTS),
            ppca: Some(Ppca::paper(fps)),
            blend: ((10.0 * fps / 120.0).round() as usize).max(1),
            jump_ratio: 10.0,
            patch_share: 1.0,
            max_segment: ((MAX_FIT_SECONDS * fps).round() as usize).max(64),
            fixed_groups: false,
        }
    }
}

/// What to code: channel-major fixed-point values, a weight per channel
/// (error units per fixed-point unit) and the channel groups, each with
/// its own PCA and key frames (a one-channel group is a plain key-framed
/// curve: root translation and heading). Every channel should be in one
/// group; constant channels are taken out of their group.
pub struct Input<'a> {
    /// `values[channel][frame]`.
    pub values: &'a [Vec<i32>],
    /// Weight of each channel.
    pub weights: &'a [f64],
    /// Channel groups.
    pub groups: &'a [Vec<usize>],
}

/// The model of one clip, ready to be written (SPEC.md §5).
#[derive(Clone, Debug, Default)]
pub struct Model {
    /// Channel lists of the groups.
    pub groups: Vec<Vec<usize>>,
    /// Constant channels and their values.
    pub consts: Vec<(usize, i32)>,
    /// Segments in order.
    pub segments: Vec<SegmentModel>,
}

/// One segment.
#[derive(Clone, Debug)]
pub struct SegmentModel {
    /// First frame.
    pub start: u32,
    /// Last frame (inclusive); past the next segment's start when blending.
    pub end: u32,
    /// One entry per group, in group order.
    pub groups: Vec<GroupModel>,
    /// Sparse corrections: (frame relative to `start`, channel, value),
    /// sorted (SPEC.md §5.5).
    pub patches: Vec<(u32, usize, i32)>,
}

/// One group in one segment.
#[derive(Clone, Debug, Default)]
pub struct GroupModel {
    /// Components.
    pub k: usize,
    /// Means are stored `>> mean_shift`.
    pub mean_shift: u8,
    /// Stored means, one per channel.
    pub mean: Vec<i16>,
    /// `n × k` basis.
    pub basis: Vec<i8>,
    /// Key times, relative to the segment start.
    pub times: Vec<u32>,
    /// Per component: bit width, shift, offset.
    pub comps: Vec<(u8, u8, i32)>,
    /// `m × k` codes.
    pub codes: Vec<u32>,
}

/// What [`model_with`] keeps between models of one input at different
/// tolerances: the PPCA cuts of each stretch of the body's motion, which
/// only change where the despiked frames do. Use one cache per input.
#[derive(Default)]
pub struct Cache {
    /// (first frame, end, the body's despiked values in it) → cuts.
    ppca: Mutex<HashMap<PpcaKey, Vec<usize>>>,
}

/// A stretch of frames and the despiked values in it: (frame, body
/// channel, value), sorted.
type PpcaKey = (usize, usize, Vec<(usize, usize, i32)>);

/// Builds the model of a clip.
pub fn model(input: &Input<'_>, p: &Params) -> Result<Model, CodecError> {
    model_with(input, p, &Cache::default(), &|_, _| {})
}

/// [`model`], reusing what `cache` holds from models of the same input,
/// calling `on_fit(done, total)` as group fits finish (from the fitting
/// threads). Segments are fitted in parallel (rayon); the model is the
/// same for any number of threads.
pub fn model_with(
    input: &Input<'_>,
    p: &Params,
    cache: &Cache,
    on_fit: &(dyn Fn(usize, usize) + Sync),
) -> Result<Model, CodecError> {
    let channels = input.values.len();
    let frames = input.values.first().map_or(0, Vec::len);
    if frames == 0 {
        return Err(CodecError::NoFrames);
    }
    let original = input.values;
    // Model the motion without its one-frame spikes; patches restore them.
    let clean: Vec<Vec<i32>> = input
        .values
        .iter()
        .zip(input.weights)
        .map(|(v, &w)| despike(v, w, p.patch_share * p.tolerance))
        .collect();
    let input = &Input {
        values: &clean,
        weights: input.weights,
        groups: input.groups,
    };
    let constant =
        |c: usize| !p.fixed_groups && input.values[c].iter().all(|&x| x == input.values[c][0]);
    let mut consts: Vec<(usize, i32)> = (0..channels)
        .filter(|&c| constant(c) || !input.groups.iter().any(|g| g.contains(&c)))
        .map(|c| (c, input.values[c][0]))
        .collect();
    consts.sort_unstable();
    let groups: Vec<Vec<usize>> = input
        .groups
        .iter()
        .map(|g| {
            let mut g: Vec<usize> = g.iter().copied().filter(|&c| !constant(c)).collect();
            g.sort_unstable();
            g
        })
        .filter(|g| !g.is_empty())
        .collect();
    // Segmentation looks at the pose, not at the separate curves.
    let mut body: Vec<usize> = groups
        .iter()
        .filter(|g| g.len() > 1)
        .flatten()
        .copied()
        .collect();
    body.sort_unstable();
    let mut despiked: Vec<(usize, usize, i32)> = body
        .iter()
        .enumerate()
        .flat_map(|(i, &c)| {
            let (a, b) = (&original[c], &clean[c]);
            (0..frames)
                .filter(move |&f| a[f] != b[f])
                .map(move |f| (f, i, b[f]))
        })
        .collect();
    despiked.sort_unstable();
    let mut starts = segment_starts(input, &body, frames, p, cache, &despiked);
    // Fit every segment; a segment whose coefficients leave the format's
    // range (a root travelling tens of metres in one segment) is halved
    // until they fit.
    let mut fitted: HashMap<(usize, usize), Vec<GroupModel>> = HashMap::new();
    let ends = loop {
        let ends = segment_ends(&starts, frames, p.blend);
        let todo: Vec<(usize, usize)> = starts
            .iter()
            .zip(&ends)
            .map(|(&(s, _), &e)| (s, e))
            .filter(|span| !fitted.contains_key(span))
            .collect();
        let jobs: Vec<(usize, usize, usize)> = todo
            .iter()
            .flat_map(|&(s, e)| (0..groups.len()).map(move |g| (s, e, g)))
            .collect();
        let done = std::sync::atomic::AtomicUsize::new(0);
        let fits: Vec<Result<GroupModel, CodecError>> = jobs
            .par_iter()
            .map(|&(s, e, g)| {
                let fit = fit_group(input, &groups[g], s, e, p);
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                on_fit(d, jobs.len());
                fit
            })
            .collect();
        let mut fits = fits.into_iter();
        let mut halve = Vec::new();
        for &(s, e) in &todo {
            let one: Vec<_> = fits.by_ref().take(groups.len()).collect();
            match one.into_iter().collect::<Result<Vec<_>, CodecError>>() {
                Ok(g) => {
                    fitted.insert((s, e), g);
                }
                Err(err) => {
                    let i = starts.partition_point(|&(x, _)| x < s);
                    let next = starts.get(i + 1).map_or(frames, |&(x, _)| x);
                    let splittable = matches!(
                        err,
                        CodecError::CoefficientOutOfRange { .. } | CodecError::KeyRangeTooWide
                    );
                    if !splittable || next - s < 4 {
                        return Err(err);
                    }
                    halve.push((s + (next - s) / 2, false));
                }
            }
        }
        if halve.is_empty() {
            break ends;
        }
        starts.extend(halve);
        starts.sort_unstable();
    };
    let segments = starts
        .iter()
        .zip(&ends)
        .map(|(&(start, _), &end)| SegmentModel {
            start: start as u32,
            end: end as u32,
            groups: fitted.remove(&(start, end)).unwrap_or_default(),
            patches: Vec::new(),
        })
        .collect();
    Ok(Model {
        groups,
        consts,
        segments,
    })
}

/// `v` with every one-frame spike (a frame off its neighbours' mean by
/// more than `tol` weighted units while the neighbours agree better with
/// each other) replaced by that mean.
fn despike(v: &[i32], w: f64, tol: f64) -> Vec<i32> {
    let mut out = v.to_vec();
    for f in 1..v.len().saturating_sub(1) {
        let (a, x, b) = (f64::from(v[f - 1]), f64::from(v[f]), f64::from(v[f + 1]));
        let mid = (a + b) / 2.0;
        let dev = ((x - mid) * w).abs();
        if dev > tol && ((b - a) * w).abs() < dev {
            out[f] = mid.round() as i32;
        }
    }
    out
}

/// Segment starts, each with whether it follows a jump (no blending).
/// `despiked` lists the body's despiked values (frame, body channel,
/// value), sorted: with the input, they decide the PPCA cuts `cache` holds.
fn segment_starts(
    input: &Input<'_>,
    body: &[usize],
    frames: usize,
    p: &Params,
    cache: &Cache,
    despiked: &[(usize, usize, i32)],
) -> Vec<(usize, bool)> {
    let weighted = |chs: &[usize]| -> Vec<f64> {
        (0..frames)
            .flat_map(|f| {
                chs.iter()
                    .map(move |&c| f64::from(input.values[c][f]) * input.weights[c])
            })
            .collect()
    };
    // Jumps of the body pose (the root travels steadily, so its steps
    // would hide them).
    let y = weighted(body);
    let jumps = segment::jumps(&y, body.len(), p.jump_ratio, 4.0 * p.tolerance);
    let mut starts = vec![(0usize, true)];
    starts.extend(jumps.iter().map(|&j| (j, true)));
    // Respect the format's longest segment, and the encoder's.
    let max = (MAX_SEGMENT_FRAMES as usize - p.blend - 2).min(p.max_segment.max(1));
    let mut out = Vec::new();
    for (i, &(s, jump)) in starts.iter().enumerate() {
        let e = starts.get(i + 1).map_or(frames, |&(n, _)| n);
        out.push((s, jump));
        let mut cuts = match &p.ppca {
            Some(pp) if !body.is_empty() => {
                let lo = despiked.partition_point(|&(f, _, _)| f < s);
                let hi = despiked.partition_point(|&(f, _, _)| f < e);
                let key = (s, e, despiked[lo..hi].to_vec());
                let known = cache.ppca.lock().ok().and_then(|c| c.get(&key).cloned());
                match known {
                    Some(cuts) => cuts,
                    None => {
                        let cuts = segment::ppca_cuts(&y, body.len(), s, e, pp, max);
                        if let Ok(mut c) = cache.ppca.lock() {
                            c.insert(key, cuts.clone());
                        }
                        cuts
                    }
                }
            }
            _ => Vec::new(),
        };
        // Stretches longer than `max`: cut evenly.
        let mut last = s;
        cuts.push(e);
        for c in cuts {
            let pieces = (c - last).div_ceil(max);
            for q in 1..pieces {
                out.push((last + (c - last) * q / pieces, false));
            }
            if c < e {
                out.push((c, false));
            }
            last = c;
        }
    }
    out
}

/// Last frame of each segment: just before the next start after a jump,
/// `blend` frames past it after a PPCA cut, never so far that two blend
/// windows touch (SPEC.md §5.2).
fn segment_ends(starts: &[(usize, bool)], frames: usize, blend: usize) -> Vec<usize> {
    (0..starts.len())
        .map(|i| match starts.get(i + 1) {
            None => frames - 1,
            Some(&(next, jump)) => {
                let mut end = next - 1;
                if !jump && blend > 0 {
                    end = next + blend - 1;
                    if let Some(&(after, _)) = starts.get(i + 2) {
                        end = end.min(after.saturating_sub(2)).max(next - 1);
                    }
                    end = end.min(frames - 1);
                }
                end
            }
        })
        .collect()
}

fn fit_group(
    input: &Input<'_>,
    chans: &[usize],
    start: usize,
    end: usize,
    p: &Params,
) -> Result<GroupModel, CodecError> {
    let n = chans.len();
    let len = end - start + 1;
    let w: Vec<f64> = chans.iter().map(|&c| input.weights[c]).collect();
    // Means, stored as i16 << shift.
    let means: Vec<f64> = chans
        .iter()
        .map(|&c| {
            input.values[c][start..=end]
                .iter()
                .map(|&v| f64::from(v))
                .sum::<f64>()
                / len as f64
        })
        .collect();
    let peak = means.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut shift = 0u8;
    while shift < MAX_MEAN_SHIFT && (peak / f64::from(1u32 << shift)).round() > 32767.0 {
        shift += 1;
    }
    let mean: Vec<i16> = means
        .iter()
        .map(|m| {
            (m / f64::from(1u32 << shift))
                .round()
                .clamp(-32768.0, 32767.0) as i16
        })
        .collect();
    let mq: Vec<f64> = mean
        .iter()
        .map(|&m| f64::from(i32::from(m) << shift))
        .collect();
    let mut g = GroupModel {
        k: 0,
        mean_shift: shift,
        mean,
        ..GroupModel::default()
    };
    if len < 2 {
        return Ok(g);
    }
    let x: Vec<f64> = (start..=end)
        .flat_map(|f| {
            let mq = &mq;
            chans
                .iter()
                .enumerate()
                .map(move |(i, &c)| f64::from(input.values[c][f]) - mq[i])
        })
        .collect();
    let fit = pca::fit(&x, n, &w, p.pca_share * p.tolerance, p.max_components);
    let k = fit.k;
    if k == 0 {
        return Ok(g);
    }
    let gram = fit.gram.clone();
    let (times, controls) = keys::select(&fit.coef, k, p.key_share * p.tolerance, |d| {
        pca::weighted_norm(&gram, d)
    });
    // Quantisation step per component: equal shares of quant_share·τ.
    let limit = f64::from(i32::MAX) / (128.0 * k as f64) / 2.0;
    let m = times.len();
    let mut comps = Vec::with_capacity(k);
    let mut codes = vec![0u32; m * k];
    for j in 0..k {
        let gj = fit.gram[j * k + j].sqrt().max(1e-300);
        let s = match p.key_bits {
            None => {
                let step = p.quant_share * p.tolerance * 12f64.sqrt() / (gj * (k as f64).sqrt());
                step.max(1.0).log2().floor()
            }
            Some(bits) => {
                let v = (0..m).map(|r| controls[r * k + j]);
                let range = v.clone().fold(f64::MIN, f64::max) - v.fold(f64::MAX, f64::min);
                let levels = f64::from((1u32 << bits.min(30)) - 1).max(1.0);
                // The finest power of two whose codes span the range in `bits`.
                (range / levels).max(1.0).log2().ceil()
            }
        }
        .clamp(0.0, f64::from(MAX_VALUE_SHIFT)) as u8;
        let unit = f64::from(1u32 << s);
        let col: Vec<i64> = (0..m)
            .map(|r| (controls[r * k + j] / unit).round() as i64)
            .collect();
        let lo = *col.iter().min().unwrap_or(&0);
        let hi = *col.iter().max().unwrap_or(&0);
        if (lo as f64 * unit).abs() > limit || (hi as f64 * unit).abs() > limit {
            return Err(CodecError::CoefficientOutOfRange {
                value: lo.abs().max(hi.abs()) as f64 * unit,
                channels: chans.to_vec(),
            });
        }
        let span = (hi - lo) as u64;
        let width = 64 - span.leading_zeros() as u8;
        if width > MAX_VALUE_BITS {
            return Err(CodecError::KeyRangeTooWide);
        }
        comps.push((width, s, (lo << s) as i32));
        for r in 0..m {
            codes[r * k + j] = (col[r] - lo) as u32;
        }
    }
    g.k = k;
    g.basis = fit.basis;
    g.times = times;
    g.comps = comps;
    g.codes = codes;
    Ok(g)
}

impl Model {
    /// Adds a patch wherever the decoded value (`decoded[channel][frame]`,
    /// from the real decoder) misses the input by more than `tol` weighted
    /// units; returns how many were added. Each patch goes to the segment
    /// whose own range (up to the next start) holds its frame.
    pub fn add_patches(&mut self, input: &Input<'_>, decoded: &[Vec<i32>], tol: f64) -> usize {
        let mut added = 0;
        let starts: Vec<u32> = self.segments.iter().map(|s| s.start).collect();
        // New patches per segment, merged into the sorted lists at the end
        // (inserting one by one costs the square of their number).
        let mut new: Vec<Vec<(u32, usize, i32)>> = vec![Vec::new(); self.segments.len()];
        for (c, (orig, dec)) in input.values.iter().zip(decoded).enumerate() {
            for (f, (&o, &d)) in orig.iter().zip(dec).enumerate() {
                let err = f64::from(o) - f64::from(d);
                if (err * input.weights[c]).abs() <= tol || err == 0.0 {
                    continue;
                }
                let s = starts.partition_point(|&st| st as usize <= f) - 1;
                let rel = f as u32 - self.segments[s].start;
                let delta =
                    (i64::from(o) - i64::from(d)).clamp(i32::MIN.into(), i32::MAX.into()) as i32;
                new[s].push((rel, c, delta));
                added += 1;
            }
        }
        for (seg, mut new) in self.segments.iter_mut().zip(new) {
            if new.is_empty() {
                continue;
            }
            // Each (frame, channel) comes at most once per call.
            new.sort_unstable_by_key(|&(r, c, _)| (r, c));
            let old = std::mem::take(&mut seg.patches);
            let mut merged = Vec::with_capacity(old.len() + new.len());
            let (mut a, mut b) = (old.into_iter().peekable(), new.into_iter().peekable());
            loop {
                let next = match (a.peek(), b.peek()) {
                    (Some(x), Some(y)) if (x.0, x.1) == (y.0, y.1) => {
                        let (x, y) = (a.next(), b.next());
                        x.zip(y).map(|(x, y)| (x.0, x.1, x.2.wrapping_add(y.2)))
                    }
                    (Some(x), Some(y)) if (x.0, x.1) < (y.0, y.1) => a.next(),
                    (Some(_), Some(_)) => b.next(),
                    (Some(_), None) => a.next(),
                    (None, _) => b.next(),
                };
                match next {
                    Some(p) => merged.push(p),
                    None => break,
                }
            }
            seg.patches = merged;
        }
        added
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_leave_blend_windows_apart() {
        let starts = [
            (0, true),
            (1, true),
            (100, false),
            (105, false),
            (300, false),
        ];
        let ends = segment_ends(&starts, 400, 10);
        assert_eq!(ends, vec![0, 103, 114, 309, 399]);
        for j in 0..starts.len() - 2 {
            assert!(ends[j] + 2 <= starts[j + 2].0);
        }
    }

    /// Uniform key quantisation (`key_bits`, the Table 4 baseline): every
    /// component's keys span their range in the bits given (one more at
    /// most, from rounding to the step), whatever the tolerance; adaptive
    /// keys follow the tolerance instead.
    #[test]
    fn uniform_keys_span_their_range_in_the_bits_given() {
        let frames = 240;
        let values: Vec<Vec<i32>> = (0..3)
            .map(|c| {
                (0..frames)
                    .map(|f| {
                        let t = f as f64 / 30.0 + c as f64;
                        (20_000.0 * t.sin() + 7_000.0 * (2.3 * t).cos()) as i32
                    })
                    .collect()
            })
            .collect();
        let input = Input {
            values: &values,
            weights: &[1.0; 3],
            groups: &[vec![0, 1, 2]],
        };
        let widths = |key_bits: Option<u8>, tolerance: f64| -> Vec<u8> {
            let p = Params {
                key_bits,
                ppca: None,
                ..Params::new(tolerance, 120.0)
            };
            let m = model(&input, &p).unwrap();
            m.segments
                .iter()
                .flat_map(|s| s.groups.iter().flat_map(|g| g.comps.iter().map(|c| c.0)))
                .collect()
        };
        for bits in [5u8, 9] {
            for tolerance in [2.0, 200.0] {
                let w = widths(Some(bits), tolerance);
                assert!(
                    !w.is_empty() && w.iter().all(|&x| x <= bits + 1),
                    "{bits}: {w:?}"
                );
                assert!(w.iter().any(|&x| x >= bits), "{bits}: {w:?}");
            }
        }
        let (fine, coarse) = (widths(None, 2.0), widths(None, 200.0));
        assert!(
            fine.iter().sum::<u8>() > coarse.iter().sum::<u8>(),
            "{fine:?} {coarse:?}"
        );
    }
}
