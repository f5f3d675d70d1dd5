//! Foot contacts: where the source's feet stand on the ground, found from
//! its joint positions, so the metrics can say how much a decoded take's
//! feet slide there (Lin et al. §5.3 record such contacts; we measure them).
//!
//! - **Feet**: the joints named like a foot (`foot`, `toe`, `ankle`); on a
//!   rig that names none, the lowest leaves of the take's first frame
//!   (within 15 % of the figure's height of the lowest joint).
//! - **Up**: the axis (with its sign) from the feet to the body's mean
//!   joint in the take's first frame — Y on BVH as most tools export it,
//!   Z on Z-up rigs.
//! - **Ground**: per foot joint, the 5th percentile of its height over the
//!   take (the paper clusters joint heights; a percentile is the same for a
//!   take that stands and is not fooled by one low frame).
//! - **Contact**: a foot joint is planted on frames `f` and `f + 1` when it
//!   is within 2.5 % of the figure's height of its ground on both and moves
//!   horizontally by less than 0.15 figure heights per second between them
//!   (about 45 mm and 0.25 m/s on a human).

use crate::motion::Skeleton;

/// Name fragments of the joints that touch the ground (lower case).
pub const FOOT_NAMES: [&str; 3] = ["foot", "toe", "ankle"];

/// Whether a joint's name is a foot's.
pub fn is_foot_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    FOOT_NAMES.iter().any(|f| lower.contains(f))
}

/// The source's planted feet.
#[derive(Clone, Debug, PartialEq)]
pub struct Contacts {
    /// Index of the up axis (0 x, 1 y, 2 z).
    pub up: usize,
    /// The foot joints.
    pub feet: Vec<usize>,
    /// `planted[f * feet.len() + i]`: foot `i` stands from frame `f` to
    /// `f + 1`.
    pub planted: Vec<bool>,
}

/// Foot slide and height error of a decoded take on the source's contacts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootError {
    /// Planted foot-frame pairs measured.
    pub pairs: usize,
    /// Mean horizontal speed of the decoded feet where the source's are
    /// planted, mm/s (foot skating).
    pub slide_mm_s: f64,
    /// The same of the source itself (what a perfect decoder shows).
    pub source_slide_mm_s: f64,
    /// Mean vertical error of the decoded feet there, mm.
    pub height_err_mm: f64,
}

/// Sums a decoded take's [`FootError`] a frame at a time.
#[derive(Clone, Debug)]
pub struct FootMeter<'a> {
    contacts: &'a Contacts,
    source: &'a [[f64; 3]],
    joints: usize,
    frame_time: f64,
    last: Vec<[f64; 3]>,
    frame: usize,
    sums: (usize, f64, f64, f64),
}

/// The foot joints of a skeleton: named ones, else the lowest leaves of
/// `pose` (one frame's joint positions).
pub fn foot_joints(skeleton: &Skeleton, pose: &[[f64; 3]]) -> Vec<usize> {
    let named: Vec<usize> = skeleton
        .joints
        .iter()
        .enumerate()
        .filter(|(_, j)| !j.end_site && is_foot_name(&j.name))
        .map(|(i, _)| i)
        .collect();
    if !named.is_empty() || pose.len() < skeleton.joints.len() {
        return named;
    }
    let (up, sign) = up_axis_of(pose, &[]);
    let mut has_child = vec![false; skeleton.joints.len()];
    for j in skeleton.joints.iter().filter(|j| !j.end_site) {
        if let Some(p) = j.parent {
            has_child[p] = true;
        }
    }
    let heights: Vec<f64> = pose.iter().map(|p| sign * p[up]).collect();
    let (lo, hi) = heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
            (lo.min(h), hi.max(h))
        });
    (0..skeleton.joints.len())
        .filter(|&i| {
            let j = &skeleton.joints[i];
            !j.end_site
                && !has_child[i]
                && j.parent.is_some()
                && heights[i] <= lo + 0.15 * (hi - lo)
        })
        .collect()
}

/// Lowest and highest signed height of `points` along `axis`, after the
/// sign is applied by the caller; here along `+axis`.
fn extent(points: &[[f64; 3]], axis: usize) -> (f64, f64) {
    points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[axis]), hi.max(p[axis]))
        })
}

/// `(axis, sign)` of up in one pose: from the mean of `feet` to the
/// mean of every joint (a root may stand on the ground, as iClone's
/// `RL_BoneRoot` does) when feet are given, else the axis of the largest
/// extent, down towards its end farther from the root (a root at the hips
/// is nearer the head than the feet).
fn up_axis_of(pose: &[[f64; 3]], feet: &[usize]) -> (usize, f64) {
    let mean = |set: &mut dyn Iterator<Item = [f64; 3]>| {
        let (mut s, mut n) = ([0.0; 3], 0.0);
        for p in set {
            for k in 0..3 {
                s[k] += p[k];
            }
            n += 1.0;
        }
        s.map(|v| v / f64::max(n, 1.0))
    };
    let body = mean(&mut pose.iter().copied());
    let d: [f64; 3] = if feet.is_empty() {
        let mut d = [0.0; 3];
        for (k, v) in d.iter_mut().enumerate() {
            let (lo, hi) = extent(pose, k);
            let root = pose.first().map_or(0.0, |p| p[k]);
            *v = (hi - lo) * if root - lo >= hi - root { 1.0 } else { -1.0 };
        }
        d
    } else {
        let f = mean(&mut feet.iter().filter_map(|&j| pose.get(j).copied()));
        [body[0] - f[0], body[1] - f[1], body[2] - f[2]]
    };
    let k = (0..3)
        .max_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs()))
        .unwrap_or(1);
    (k, if d[k] < 0.0 { -1.0 } else { 1.0 })
}

impl Contacts {
    /// The contacts of a take from its joint positions (`positions[f *
    /// joints + j]`, mm) and frame time (s).
    pub fn find(skeleton: &Skeleton, positions: &[[f64; 3]], frame_time: f64) -> Contacts {
        let joints = skeleton.joints.len().max(1);
        let frames = positions.len() / joints;
        let first = positions.get(..joints).unwrap_or(&[]);
        let feet = foot_joints(skeleton, first);
        // Up as the take stands (a root may turn a Z-up rest pose Y-up).
        let (up, sign) = if first.is_empty() {
            (1, 1.0)
        } else {
            up_axis_of(first, &feet)
        };
        let mut planted = vec![false; frames.saturating_sub(1) * feet.len()];
        if frames >= 2 {
            // The figure's height from the take itself (mm, whatever the units).
            let (lo, hi) = extent(first, up);
            let height = (hi - lo).max(1.0);
            let near = 0.025 * height;
            let step = 0.15 * height * frame_time.max(1e-6);
            for (i, &j) in feet.iter().enumerate() {
                let h = |f: usize| sign * positions[f * joints + j][up];
                let mut heights: Vec<f64> = (0..frames).map(h).collect();
                let (_, &mut ground, _) =
                    heights.select_nth_unstable_by(frames / 20, f64::total_cmp);
                for f in 0..frames - 1 {
                    let (a, b) = (positions[f * joints + j], positions[(f + 1) * joints + j]);
                    planted[f * feet.len() + i] = h(f) - ground <= near
                        && h(f + 1) - ground <= near
                        && horizontal(a, b, up) <= step;
                }
            }
        }
        Contacts { up, feet, planted }
    }

    /// Per joint of `skeleton` (the one the contacts were found on):
    /// whether it moves a foot — a foot, or one of a foot's ancestors.
    pub fn moving_feet(&self, skeleton: &Skeleton) -> Vec<bool> {
        let mut moves = vec![false; skeleton.joints.len()];
        for &foot in &self.feet {
            let mut j = Some(foot);
            while let Some(i) = j.filter(|&i| !moves[i]) {
                moves[i] = true;
                j = skeleton.joints[i].parent;
            }
        }
        moves
    }

    /// A meter of a decoded take against `source` (the positions the
    /// contacts were found in).
    pub fn meter<'a>(
        &'a self,
        source: &'a [[f64; 3]],
        joints: usize,
        frame_time: f64,
    ) -> FootMeter<'a> {
        FootMeter {
            contacts: self,
            source,
            joints,
            frame_time,
            last: vec![[0.0; 3]; self.feet.len()],
            frame: 0,
            sums: (0, 0.0, 0.0, 0.0),
        }
    }
}

impl FootMeter<'_> {
    /// The next decoded frame's joint positions (mm), frames in order from 0.
    pub fn frame(&mut self, positions: &[[f64; 3]]) {
        let (c, n, up) = (self.contacts, self.contacts.feet.len(), self.contacts.up);
        let f = self.frame;
        for (i, &j) in c.feet.iter().enumerate() {
            let now = positions.get(j).copied().unwrap_or([0.0; 3]);
            if f >= 1 && c.planted.get((f - 1) * n + i) == Some(&true) {
                let was = self.last[i];
                let (a, b) = (
                    self.source[(f - 1) * self.joints + j],
                    self.source[f * self.joints + j],
                );
                self.sums.0 += 1;
                self.sums.1 += horizontal(was, now, up);
                self.sums.2 += horizontal(a, b, up);
                self.sums.3 += (was[up] - a[up]).abs();
            }
            self.last[i] = now;
        }
        self.frame += 1;
    }

    /// What the frames so far measure.
    pub fn error(&self) -> FootError {
        let (n, slide, src, height) = self.sums;
        if n == 0 {
            return FootError::default();
        }
        let per_s = 1.0 / self.frame_time.max(1e-9) / n as f64;
        FootError {
            pairs: n,
            slide_mm_s: slide * per_s,
            source_slide_mm_s: src * per_s,
            height_err_mm: height / n as f64,
        }
    }
}

/// Distance from `a` to `b` across the up axis.
fn horizontal(a: [f64; 3], b: [f64; 3], up: usize) -> f64 {
    (0..3)
        .filter(|&k| k != up)
        .map(|k| (a[k] - b[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Joint;

    fn skeleton(names: [&str; 4]) -> Skeleton {
        let joint = |i: usize, parent| Joint {
            name: names[i].to_string(),
            parent,
            offset: [0.0; 3],
            channels: Vec::new(),
            end_site: false,
        };
        Skeleton {
            joints: vec![
                joint(0, None),
                joint(1, Some(0)),
                joint(2, Some(0)),
                joint(3, Some(0)),
            ],
        }
    }

    const FPS: f64 = 100.0;

    /// 100 frames, Y up: hips, head, a left foot planted but for frames
    /// 40–59 (a step of 300 mm, lifted 200 mm), a right foot on the ground
    /// sliding at 1 m/s (never planted).
    fn walk(up: usize) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        let at = |x: f64, h: f64| {
            let mut p = [x, 0.0, 0.0];
            p[up] = h;
            p
        };
        for f in 0..100 {
            let t = f as f64;
            let (lx, lh) = match f {
                0..=39 => (0.0, 20.0),
                40..=59 => (
                    300.0 * (t - 39.0) / 21.0,
                    20.0 + 200.0 * ((t - 39.0) / 21.0 * std::f64::consts::PI).sin(),
                ),
                _ => (300.0, 20.0),
            };
            out.extend([
                at(150.0, 1000.0),
                at(150.0, 1700.0),
                at(lx, lh),
                at(10.0 * t, 20.0),
            ]);
        }
        out
    }

    #[test]
    fn a_planted_foot_is_found_on_either_up_axis() {
        for up in [1, 2] {
            let c = Contacts::find(
                &skeleton(["Hips", "Head", "LeftFoot", "RightFoot"]),
                &walk(up),
                1.0 / FPS,
            );
            assert_eq!((c.up, c.feet.clone()), (up, vec![2, 3]));
            // Left: 0→1 … 38→39 and 60→61 … 98→99 (the lift's first
            // and last steps move 14 mm, more than 0.15 × 1680 / 100).
            let left: Vec<usize> = (0..99).filter(|&f| c.planted[f * 2]).collect();
            let want: Vec<usize> = (0..39).chain(60..99).collect();
            assert_eq!(left, want);
            assert!(
                (0..99).all(|f| !c.planted[f * 2 + 1]),
                "a sliding foot is not planted"
            );
        }
    }

    #[test]
    fn the_lowest_leaves_are_feet_on_a_rig_that_names_none() {
        let pose = &walk(1)[..4];
        assert_eq!(
            foot_joints(&skeleton(["a", "b", "c", "d"]), pose),
            vec![2, 3]
        );
    }

    #[test]
    fn slide_and_height_are_measured_on_the_planted_frames() {
        let source = walk(1);
        let c = Contacts::find(
            &skeleton(["Hips", "Head", "LeftFoot", "RightFoot"]),
            &source,
            1.0 / FPS,
        );
        let run = |shift: &dyn Fn(usize) -> [f64; 3]| {
            let mut meter = c.meter(&source, 4, 1.0 / FPS);
            for f in 0..100 {
                let mut pose = source[f * 4..f * 4 + 4].to_vec();
                let d = shift(f);
                for k in 0..3 {
                    pose[2][k] += d[k];
                }
                meter.frame(&pose);
            }
            meter.error()
        };
        let same = run(&|_| [0.0; 3]);
        assert_eq!(same.pairs, 78);
        assert_eq!(
            (same.slide_mm_s, same.source_slide_mm_s, same.height_err_mm),
            (0.0, 0.0, 0.0)
        );
        // ±1 mm along x every other frame, 3 mm up: 2 mm a frame at 100 Hz.
        let jitter = run(&|f| [if f % 2 == 0 { 1.0 } else { -1.0 }, 3.0, 0.0]);
        assert!((jitter.slide_mm_s - 200.0).abs() < 1e-9, "{jitter:?}");
        assert!((jitter.height_err_mm - 3.0).abs() < 1e-9, "{jitter:?}");
    }
}
