//! The input of an encode, measured once ([`Reference`]), and the one
//! measurement of a decoded motion against it: the proof of every codec's
//! clip and `mocap bench`'s baselines go through [`Reference::measure`] and
//! take their per-channel tolerances from [`Reference::tolerances`].

use super::bound::{self, Bound};
use crate::fixed::{self, FixedChannels};
use crate::kinematics;
use crate::metrics::{self, Metrics};
use crate::motion::Motion;

/// What every search starts from and every measurement compares with,
/// computed once per motion and unit.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The motion in fixed point (SPEC.md §3.3).
    pub(super) fixed: FixedChannels,
    /// Joint positions of the input (mm) and its planted feet.
    pub(super) source: metrics::Source,
    /// Lever arm of each joint, µm.
    pub(super) levers_um: Vec<f64>,
    /// Joint of each channel.
    pub(super) joint_of: Vec<usize>,
    /// Whether each channel moves a foot: its joint is a foot
    /// ([`crate::contacts::foot_joints`]) or one of a foot's ancestors.
    pub(super) moves_feet: Vec<bool>,
    /// Metres per source length unit.
    pub(super) metres_per_unit: f64,
}

impl Reference {
    /// Measures `m` once: its fixed-point channels, joint positions and
    /// lever arms, with `metres_per_unit` metres per source length unit.
    pub fn new(m: &Motion, metres_per_unit: f64) -> Reference {
        let source = metrics::Source::of(m, metres_per_unit);
        let moves = source.contacts.moving_feet(&m.skeleton);
        let joint_of = m.skeleton.channel_joints();
        Reference {
            fixed: fixed::to_fixed(m, metres_per_unit),
            moves_feet: joint_of.iter().map(|&j| moves[j]).collect(),
            source,
            levers_um: kinematics::lever_arms(&m.skeleton)
                .into_iter()
                .map(|l| l * metres_per_unit * 1e6)
                .collect(),
            joint_of,
            metres_per_unit,
        }
    }

    /// The motion in fixed point: what the codecs code, `[channel][frame]`.
    pub fn fixed(&self) -> &FixedChannels {
        &self.fixed
    }

    /// Metres per source length unit.
    pub fn metres_per_unit(&self) -> f64 {
        self.metres_per_unit
    }

    /// Per-channel tolerances (fixed-point units) of `bound` for a position
    /// budget `s_um` (µm; `None` = no position bound), scaled by `tighten`:
    /// the tolerances the encode pipeline gives its own codecs.
    pub fn tolerances(&self, bound: &Bound, s_um: Option<f64>, tighten: f64) -> Vec<i64> {
        self.tolerances_with_feet(bound, s_um, tighten, 1.0)
    }

    /// [`Self::tolerances`] with the channels that move a foot scaled by
    /// `feet` (≤ 1: the feet held tighter than the rest, for a slide bound).
    pub fn tolerances_with_feet(
        &self,
        bound: &Bound,
        s_um: Option<f64>,
        tighten: f64,
        feet: f64,
    ) -> Vec<i64> {
        let mut t = bound::tolerances(
            &self.fixed,
            bound,
            &self.levers_um,
            &self.joint_of,
            s_um,
            tighten,
        );
        if feet < 1.0 {
            for (t, _) in t.iter_mut().zip(&self.moves_feet).filter(|(_, &m)| m) {
                *t = (*t as f64 * feet).floor() as i64;
            }
        }
        t
    }

    /// Measures decoded frames (frame-major `frames × channels` fixed-point
    /// values, as the decoder gives them) against `m`, the motion this
    /// reference was made from: the metrics a bound is checked on. `bytes`
    /// is the size the ratios are computed with.
    pub fn measure(&self, m: &Motion, frames: &[i32], bytes: usize) -> Metrics {
        // A frame at a time (fixed::from_fixed's arithmetic): no decoded
        // copy of the clip in floating point.
        let kinds = m.skeleton.channel_kinds();
        let width = kinds.len().max(1);
        metrics::compare_frames(
            m,
            &m.skeleton,
            frames.len() / width,
            |f, out| {
                out.clear();
                let frame = frames.get(f * width..(f + 1) * width).unwrap_or(&[]);
                fixed::extend_from_fixed(&kinds, frame, self.metres_per_unit, out);
            },
            self.metres_per_unit,
            Some(&self.source),
            bytes,
            0,
        )
    }
}
