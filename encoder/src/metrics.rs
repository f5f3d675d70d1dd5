//! Error and size metrics (METHODS.md "Metrics"): ARMS, max joint error,
//! distortion rate d, angle RMS/max, compression ratios. Positions come
//! from forward kinematics of the input skeleton, in millimetres.

use serde::Serialize;

use crate::contacts::Contacts;
use crate::fixed::wrap_degrees;
use crate::kinematics;
use crate::motion::Motion;

/// Everything `mocap eval --json` prints.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Metrics {
    /// Clip size in bytes.
    pub bytes: usize,
    /// frames × channels × 4 / bytes.
    pub ratio_f32: f64,
    /// Input file bytes / clip bytes (0 when the input size is unknown).
    pub ratio_file: f64,
    /// Mean over frames of the RMS joint-position error, mm.
    pub arms_mm: f64,
    /// Largest joint-position error over all frames and joints, mm.
    pub max_joint_err_mm: f64,
    /// Where it occurs: joint name.
    pub max_joint_err_joint: String,
    /// Where it occurs: frame index.
    pub max_joint_err_frame: usize,
    /// Distortion rate d = 100·‖A − Ã‖/‖A − E(A)‖ over joint positions, %.
    pub distortion_pct: f64,
    /// RMS of wrap-aware rotation-channel errors, degrees.
    pub angle_rms_deg: f64,
    /// Largest wrap-aware rotation-channel error, degrees.
    pub angle_max_deg: f64,
    /// Largest translation-channel error, mm.
    pub position_max_mm: f64,
    /// Foot-frame pairs where the source's feet are planted
    /// ([`crate::contacts`]); the three foot figures are means over them.
    pub foot_pairs: usize,
    /// Mean horizontal speed of the decoded feet there, mm/s (foot slide).
    pub foot_slide_mm_s: f64,
    /// The source's own, mm/s (what a lossless decode shows).
    pub foot_slide_source_mm_s: f64,
    /// Mean vertical error of the decoded feet there, mm.
    pub foot_height_err_mm: f64,
    /// Frames.
    pub frames: usize,
    /// Channels per frame.
    pub channels: usize,
}

/// Positions of every joint for every frame, in millimetres.
pub fn positions_mm(m: &Motion, metres_per_unit: f64) -> Vec<[f64; 3]> {
    let mm = metres_per_unit * 1000.0;
    let mut all = Vec::with_capacity(m.frames() * m.skeleton.joints.len());
    let mut one = Vec::new();
    for f in 0..m.frames() {
        kinematics::joint_positions(&m.skeleton, m.frame(f), &mut one);
        all.extend(one.iter().map(|p| p.map(|v| v * mm)));
    }
    all
}

/// The source side of a comparison, measured once: every joint's position
/// (mm, as [`positions_mm`]) and the planted feet ([`Contacts`]).
#[derive(Clone, Debug)]
pub struct Source {
    /// `positions[f * joints + j]`, mm.
    pub positions: Vec<[f64; 3]>,
    /// Where the feet stand.
    pub contacts: Contacts,
}

impl Source {
    /// Measures `m` with `metres_per_unit` metres per length unit.
    pub fn of(m: &Motion, metres_per_unit: f64) -> Source {
        let positions = positions_mm(m, metres_per_unit);
        let contacts = Contacts::find(&m.skeleton, &positions, m.frame_time);
        Source {
            positions,
            contacts,
        }
    }
}

/// Compares `decoded` with `original` (same skeleton and frame count).
/// `source` ([`Source::of`] the original) may be passed in to skip
/// measuring it again.
pub fn compare(
    original: &Motion,
    decoded: &Motion,
    metres_per_unit: f64,
    source: Option<&Source>,
    bytes: usize,
    input_bytes: usize,
) -> Metrics {
    compare_frames(
        original,
        &decoded.skeleton,
        decoded.frames(),
        |f, out| {
            out.clear();
            out.extend_from_slice(decoded.frame(f));
        },
        metres_per_unit,
        source,
        bytes,
        input_bytes,
    )
}

/// [`compare`] with the decoded motion given a frame at a time:
/// `decoded_frame(f, out)` fills `out` with frame `f`'s channel values (of
/// the skeleton `decoded_skeleton`, the original's or one with its channel
/// layout), for `f < decoded_frames`. Nothing as long as
/// the clip is held besides the original's positions, so the proof of a
/// long take needs no decoded copy of it in floating point.
#[allow(clippy::too_many_arguments)] // compare's arguments and the frame source
pub fn compare_frames(
    original: &Motion,
    decoded_skeleton: &crate::motion::Skeleton,
    decoded_frames: usize,
    mut decoded_frame: impl FnMut(usize, &mut Vec<f64>),
    metres_per_unit: f64,
    source: Option<&Source>,
    bytes: usize,
    input_bytes: usize,
) -> Metrics {
    let frames = original.frames().min(decoded_frames);
    let channels = original.channels();
    let own;
    let source = match source {
        Some(s) => s,
        None => {
            own = Source::of(original, metres_per_unit);
            &own
        }
    };
    let a = &source.positions;
    let joints = original.skeleton.joints.len().max(1);
    let mm = metres_per_unit * 1000.0;
    let kinds = original.skeleton.channel_kinds();
    let mut feet = source.contacts.meter(a, joints, original.frame_time);
    let mut b_mm = Vec::with_capacity(joints);

    let mut arms_sum = 0.0;
    let mut max_err = 0.0f64;
    let mut max_at = (0usize, 0usize);
    let mut err_sq = 0.0;
    let (mut ang_sq, mut ang_n, mut ang_max, mut pos_max) = (0.0, 0usize, 0.0f64, 0.0f64);
    // The decoded frame and its positions one frame at a time (as
    // positions_mm computes them), not arrays as long as the clip.
    let (mut y, mut b) = (Vec::with_capacity(channels), Vec::with_capacity(joints));
    for f in 0..frames {
        decoded_frame(f, &mut y);
        kinematics::joint_positions(decoded_skeleton, &y, &mut b);
        b_mm.clear();
        b_mm.extend(b.iter().map(|p| p.map(|v| v * mm)));
        feet.frame(&b_mm);
        let mut frame_sq = 0.0;
        for j in 0..joints {
            let (p, q) = (a[f * joints + j], b_mm[j]);
            let d2: f64 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum();
            frame_sq += d2;
            if d2.sqrt() > max_err {
                max_err = d2.sqrt();
                max_at = (f, j);
            }
        }
        err_sq += frame_sq;
        arms_sum += (frame_sq / joints as f64).sqrt();
        let x = original.frame(f);
        for (c, kind) in kinds.iter().enumerate() {
            if kind.is_rotation() {
                let d = wrap_degrees(y[c] - x[c]).abs();
                ang_sq += d * d;
                ang_n += 1;
                ang_max = ang_max.max(d);
            } else {
                pos_max = pos_max.max((y[c] - x[c]).abs() * metres_per_unit * 1000.0);
            }
        }
    }
    // ‖A − E(A)‖ with E(A) the per-coordinate mean over frames.
    let mut spread = 0.0;
    for j in 0..joints {
        #[allow(clippy::needless_range_loop)] // k indexes both the mean and the points
        for k in 0..3 {
            let mean =
                (0..frames).map(|f| a[f * joints + j][k]).sum::<f64>() / frames.max(1) as f64;
            spread += (0..frames)
                .map(|f| (a[f * joints + j][k] - mean).powi(2))
                .sum::<f64>();
        }
    }

    let raw = frames * channels * 4;
    let foot = feet.error();
    Metrics {
        bytes,
        ratio_f32: raw as f64 / bytes.max(1) as f64,
        ratio_file: if input_bytes > 0 {
            input_bytes as f64 / bytes.max(1) as f64
        } else {
            0.0
        },
        arms_mm: arms_sum / frames.max(1) as f64,
        max_joint_err_mm: max_err,
        max_joint_err_joint: original.skeleton.joints[max_at.1].name.clone(),
        max_joint_err_frame: max_at.0,
        distortion_pct: if spread > 0.0 {
            100.0 * (err_sq / spread).sqrt()
        } else {
            0.0
        },
        angle_rms_deg: if ang_n > 0 {
            (ang_sq / ang_n as f64).sqrt()
        } else {
            0.0
        },
        angle_max_deg: ang_max,
        position_max_mm: pos_max,
        foot_pairs: foot.pairs,
        foot_slide_mm_s: foot.slide_mm_s,
        foot_slide_source_mm_s: foot.source_slide_mm_s,
        foot_height_err_mm: foot.height_err_mm,
        frames,
        channels,
    }
}
