//! Marker clips: position-channel clips without a skeleton (C3D, [`crate::c3d`]).
//!
//! A marker is a root joint with `Xposition Yposition Zposition` and offset 0,
//! so its joint position *is* the marker position and the encoder's
//! millimetre bound (forward kinematics) is a bound on marker position error.
//! Missing samples are never invented silently: [`fill`] gives the codecs a
//! motion without holes (linear between the nearest present samples of the
//! marker, held at the ends, zeros for a marker never present) so they stay
//! efficient, the proof holds the bound on every sample of that filled
//! motion — which equals the data wherever it is present — and the clip
//! carries the mask as the ancillary section `0x81` (SPEC.md §3.7), which
//! the decoder exposes as `Clip::missing`.

use mocap_decoder::{consts, Clip};

use crate::container::{assemble, varint};
use crate::encode::{self, EncodeError, EncodeOptions, Encoded};
use crate::metrics;
use crate::motion::{ChannelKind, Joint, Motion, Skeleton};
use crate::units::LengthUnit;

/// Which samples (frame × marker) are missing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MissingMask {
    /// Frames.
    pub frames: usize,
    /// Markers (the motion's joints).
    pub markers: usize,
    /// `missing[frame * markers + marker]`.
    pub missing: Vec<bool>,
}

impl MissingMask {
    /// A mask with nothing missing.
    pub fn none(frames: usize, markers: usize) -> MissingMask {
        MissingMask {
            frames,
            markers,
            missing: vec![false; frames * markers],
        }
    }

    /// Whether marker `marker` is missing at frame `frame`.
    pub fn is_missing(&self, frame: usize, marker: usize) -> bool {
        self.missing
            .get(frame * self.markers + marker)
            .copied()
            .unwrap_or(false)
    }

    /// Missing samples in all.
    pub fn count(&self) -> usize {
        self.missing.iter().filter(|&&m| m).count()
    }

    /// Runs of missing samples over all markers.
    pub fn runs(&self) -> usize {
        (0..self.markers)
            .map(|k| {
                (0..self.frames)
                    .filter(|&f| self.is_missing(f, k) && (f == 0 || !self.is_missing(f - 1, k)))
                    .count()
            })
            .sum()
    }

    /// The payload of section `0x81` (SPEC.md §3.7): the marker count, then
    /// per marker its run count (0: never missing) and the run lengths,
    /// alternately present and missing, starting with a present run (0 when
    /// the marker is missing at frame 0).
    pub fn to_section(&self) -> Vec<u8> {
        let mut out = Vec::new();
        varint(&mut out, self.markers as u32);
        for k in 0..self.markers {
            let mut runs: Vec<u32> = Vec::new();
            let mut state = false; // present
            let mut len = 0u32;
            for f in 0..self.frames {
                let m = self.is_missing(f, k);
                if m != state {
                    runs.push(len);
                    state = m;
                    len = 0;
                }
                len += 1;
            }
            runs.push(len);
            if runs.len() == 1 {
                runs.clear(); // never missing
            }
            varint(&mut out, runs.len() as u32);
            for r in runs {
                varint(&mut out, r);
            }
        }
        out
    }

    /// The mask a clip carries (`None` without section `0x81`).
    pub fn of_clip(clip: &Clip<'_>) -> Option<MissingMask> {
        let m = clip.missing()?;
        let (frames, markers) = (m.frames() as usize, m.markers() as usize);
        let mut mask = MissingMask::none(frames, markers);
        for k in 0..markers {
            for (start, len) in m.runs(k as u32) {
                for f in start..start + len {
                    if let Some(v) = mask.missing.get_mut(f as usize * markers + k) {
                        *v = true;
                    }
                }
            }
        }
        Some(mask)
    }
}

/// A marker clip as a reader gives it: the motion (0 at missing samples),
/// the missing mask and the length unit of its values.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerClip {
    /// One root joint per marker with its three position channels.
    pub motion: Motion,
    /// Missing samples.
    pub missing: MissingMask,
    /// The unit of the values (from the file, never guessed).
    pub unit: LengthUnit,
}

/// `m` with every missing sample of `mask` replaced: linearly between the
/// nearest present samples of the same marker (joint), held before the
/// first and after the last, 0 for a marker never present. The channels of
/// joint `k` are filled where `mask` says marker `k` is missing; present
/// samples are untouched.
pub fn fill(m: &Motion, mask: &MissingMask) -> Motion {
    let mut out = m.clone();
    let n = m.channels();
    let frames = m.frames();
    let mut first_channel = 0;
    for (k, joint) in m.skeleton.joints.iter().enumerate() {
        let channels = first_channel..first_channel + joint.channels.len();
        first_channel = channels.end;
        let present: Vec<usize> = (0..frames).filter(|&f| !mask.is_missing(f, k)).collect();
        for f in (0..frames).filter(|&f| mask.is_missing(f, k)) {
            let after = present.partition_point(|&p| p < f);
            let before = after.checked_sub(1).map(|i| present[i]);
            let next = present.get(after).copied();
            for c in channels.clone() {
                out.values[f * n + c] = match (before, next) {
                    (Some(a), Some(b)) => {
                        let t = (f - a) as f64 / (b - a) as f64;
                        let (va, vb) = (m.values[a * n + c], m.values[b * n + c]);
                        va + (vb - va) * t
                    }
                    (Some(a), None) => m.values[a * n + c],
                    (None, Some(b)) => m.values[b * n + c],
                    (None, None) => 0.0,
                };
            }
        }
    }
    out
}

/// Why a mask cannot go with a clip.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MarkerError {
    /// The clip does not parse.
    #[error("the coded clip is rejected: {0}")]
    ClipRejected(mocap_decoder::Error),
    /// The mask's shape is not the clip's.
    #[error("the mask has {mask_frames} frames × {mask_markers} markers, the clip {frames} frames × {joints} joints")]
    Shape {
        /// Frames of the mask.
        mask_frames: usize,
        /// Markers of the mask.
        mask_markers: usize,
        /// Frames of the clip.
        frames: usize,
        /// Joints of the clip.
        joints: usize,
    },
    /// The clip already carries a mask.
    #[error("the clip already has a missing-sample section")]
    AlreadyMasked,
    /// The clip with the mask is rejected (a bug).
    #[error("internal error: the clip with its mask is rejected: {0}")]
    MaskedClipRejected(mocap_decoder::Error),
    /// Encoding failed.
    #[error(transparent)]
    Encode(#[from] EncodeError),
    /// The ARMS bound, proven over the filled motion, still fails over the
    /// present samples after [`ARMS_RETRIES`] tighter encodes.
    #[error("ARMS over the present samples is {got:.3} mm, over the bound's {want} mm, after {ARMS_RETRIES} tighter encodes")]
    ArmsOverPresent {
        /// The bound's ARMS, mm.
        want: f64,
        /// The last encode's ARMS over the present samples, mm.
        got: f64,
    },
}

/// Adds the mask to a coded clip as its last section (`0x81`, SPEC.md §3.7)
/// and seals the CRC again; a mask with nothing missing leaves the clip's
/// bytes as they are.
pub fn attach_missing(clip: &[u8], mask: &MissingMask) -> Result<Vec<u8>, MarkerError> {
    let parsed = Clip::parse(clip).map_err(MarkerError::ClipRejected)?;
    let h = parsed.header();
    if mask.frames != h.frame_count() as usize || mask.markers != h.joint_count() {
        return Err(MarkerError::Shape {
            mask_frames: mask.frames,
            mask_markers: mask.markers,
            frames: h.frame_count() as usize,
            joints: h.joint_count(),
        });
    }
    if parsed.missing().is_some() {
        return Err(MarkerError::AlreadyMasked);
    }
    if mask.count() == 0 {
        return Ok(clip.to_vec());
    }
    let mut sections: Vec<(u8, Vec<u8>)> = parsed
        .sections()
        .map(|s| (s.id, s.bytes.to_vec()))
        .collect();
    sections.push((consts::SECTION_MISSING, mask.to_section()));
    let bytes = assemble(&sections);
    Clip::parse(&bytes).map_err(MarkerError::MaskedClipRejected)?;
    Ok(bytes)
}

/// An encoded marker clip.
#[derive(Clone, Debug)]
pub struct EncodedMarkers {
    /// The clip (with its mask when a sample is missing) and the encoder's
    /// metrics over the filled motion (every sample; `bytes` the clip's).
    pub encoded: Encoded,
    /// Marker position error over the present samples.
    pub error: MarkerMetrics,
}

/// Fills the missing samples ([`fill`]), encodes with [`encode::encode`] and
/// attaches the mask. The bound is proven on every sample of the filled
/// motion, so its largest error holds on every present sample; an ARMS
/// bound is then checked again over the present samples alone (a frame's
/// filled markers no longer lower its RMS) and, where it does not hold
/// there, the encode is repeated with the ARMS budget scaled down by the
/// excess (at most [`ARMS_RETRIES`] times). `opts.metres_per_unit` is used
/// as given (the clip's own unit: `clip.unit.metres()`).
pub fn encode_markers(
    clip: &MarkerClip,
    opts: &EncodeOptions,
) -> Result<EncodedMarkers, MarkerError> {
    let filled = fill(&clip.motion, &clip.missing);
    let mut o = opts.clone();
    let mut tries = 0;
    loop {
        let enc = encode_filled(clip, &filled, &o)?;
        let (Some(want), Some(budget)) = (opts.bound.arms_mm, o.bound.arms_mm) else {
            return Ok(enc);
        };
        let got = enc.error.arms_mm;
        if got <= want {
            return Ok(enc);
        }
        if tries == ARMS_RETRIES {
            return Err(MarkerError::ArmsOverPresent { want, got });
        }
        tries += 1;
        o.bound.arms_mm = Some(budget * want / got * 0.98);
    }
}

/// How often [`encode_markers`] tightens the ARMS budget before it gives up.
pub const ARMS_RETRIES: usize = 4;

/// One encode of the filled motion, its mask attached, measured over the
/// present samples.
fn encode_filled(
    clip: &MarkerClip,
    filled: &Motion,
    opts: &EncodeOptions,
) -> Result<EncodedMarkers, MarkerError> {
    let mut enc = encode::encode(filled, opts)?;
    enc.bytes = attach_missing(&enc.bytes, &clip.missing)?;
    enc.metrics.bytes = enc.bytes.len();
    enc.metrics.ratio_f32 =
        (enc.metrics.frames * enc.metrics.channels * 4) as f64 / enc.bytes.len().max(1) as f64;
    let decoded = Clip::parse(&enc.bytes).map_err(MarkerError::MaskedClipRejected)?;
    let frames = crate::clipfile::decode_all(&decoded).map_err(EncodeError::OwnClipUndecodable)?;
    let back = crate::fixed::from_fixed(
        &filled.skeleton,
        filled.frame_time,
        &frames,
        opts.metres_per_unit,
    );
    let error = marker_errors(&clip.motion, &back, &clip.missing, opts.metres_per_unit);
    Ok(EncodedMarkers {
        encoded: enc,
        error,
    })
}

/// Marker position error over the present samples.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MarkerMetrics {
    /// Present samples compared.
    pub present: usize,
    /// Missing samples (not compared).
    pub missing: usize,
    /// Largest position error, mm.
    pub max_mm: f64,
    /// Where: marker name.
    pub max_marker: String,
    /// Where: frame.
    pub max_frame: usize,
    /// RMS of the position errors, mm.
    pub rms_mm: f64,
    /// ARMS over the present samples, mm: the mean over the frames with a
    /// present marker of the RMS of that frame's present markers' errors
    /// (the ARMS of a skeleton clip, [`metrics::Metrics::arms_mm`], with
    /// the missing samples left out).
    pub arms_mm: f64,
    /// Mean position error, mm.
    pub mean_mm: f64,
}

/// Position error (forward kinematics, so any skeleton works; for markers
/// the marker positions) of `decoded` against `original`, in mm, over the
/// samples `mask` does not mark missing.
pub fn marker_errors(
    original: &Motion,
    decoded: &Motion,
    mask: &MissingMask,
    metres_per_unit: f64,
) -> MarkerMetrics {
    let a = metrics::positions_mm(original, metres_per_unit);
    let b = metrics::positions_mm(decoded, metres_per_unit);
    let joints = original.skeleton.joints.len().max(1);
    let frames = original.frames().min(decoded.frames());
    let (mut n, mut sum, mut sq, mut max, mut at) = (0usize, 0.0, 0.0, 0.0f64, (0, 0));
    let mut missing = 0;
    let (mut arms_sum, mut arms_frames) = (0.0, 0usize);
    for f in 0..frames {
        let (mut frame_n, mut frame_sq) = (0usize, 0.0);
        for j in 0..original.skeleton.joints.len() {
            if mask.is_missing(f, j) {
                missing += 1;
                continue;
            }
            let (p, q) = (a[f * joints + j], b[f * joints + j]);
            let d = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
            n += 1;
            sum += d;
            sq += d * d;
            frame_n += 1;
            frame_sq += d * d;
            if d > max {
                max = d;
                at = (f, j);
            }
        }
        if frame_n > 0 {
            arms_sum += (frame_sq / frame_n as f64).sqrt();
            arms_frames += 1;
        }
    }
    MarkerMetrics {
        present: n,
        missing,
        max_mm: max,
        max_marker: original
            .skeleton
            .joints
            .get(at.1)
            .map(|j| j.name.clone())
            .unwrap_or_default(),
        max_frame: at.0,
        rms_mm: (sq / n.max(1) as f64).sqrt(),
        arms_mm: arms_sum / arms_frames.max(1) as f64,
        mean_mm: sum / n.max(1) as f64,
    }
}

/// The skeleton of a marker clip: one root joint per marker name, with the
/// channels Xposition Yposition Zposition, offset 0, no End Sites.
pub fn marker_skeleton(names: impl IntoIterator<Item = String>) -> Skeleton {
    Skeleton {
        joints: names
            .into_iter()
            .map(|name| Joint {
                name,
                parent: None,
                offset: [0.0; 3],
                channels: vec![
                    ChannelKind::Xposition,
                    ChannelKind::Yposition,
                    ChannelKind::Zposition,
                ],
                end_site: false,
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn markers(k: usize, values: Vec<f64>) -> Motion {
        Motion {
            skeleton: marker_skeleton((0..k).map(|i| format!("M{i}"))),
            frame_time: 0.01,
            values,
        }
    }

    #[test]
    fn fill_interpolates_holds_and_zeroes() {
        // Two markers, five frames; marker 0 present at 1 and 4, marker 1 never.
        let mut v = Vec::new();
        for f in 0..5 {
            v.extend([f as f64 * 10.0, 1.0, 2.0, 99.0, 99.0, 99.0]);
        }
        let m = markers(2, v);
        let mut mask = MissingMask::none(5, 2);
        for f in [0, 2, 3] {
            mask.missing[f * 2] = true;
        }
        for f in 0..5 {
            mask.missing[f * 2 + 1] = true;
        }
        let out = fill(&m, &mask);
        let x: Vec<f64> = (0..5).map(|f| out.values[f * 6]).collect();
        assert_eq!(x, [10.0, 10.0, 20.0, 30.0, 40.0]);
        assert!((0..5).all(|f| out.values[f * 6 + 3..f * 6 + 6] == [0.0; 3]));
        assert_eq!(out.values[6 + 1], 1.0);
    }

    #[test]
    fn section_runs() {
        let mut mask = MissingMask::none(6, 3);
        // marker 0: never; marker 1: missing 0–1 and 4; marker 2: missing at the end.
        for f in [0, 1, 4] {
            mask.missing[f * 3 + 1] = true;
        }
        mask.missing[5 * 3 + 2] = true;
        assert_eq!(mask.count(), 4);
        assert_eq!(mask.runs(), 3);
        assert_eq!(mask.to_section(), [3, 0, 5, 0, 2, 2, 1, 1, 2, 5, 1]);
    }
}
