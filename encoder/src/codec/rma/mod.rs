//! Repeated motion analysis (Lin et al., TVCG 2011; METHODS.md §3), the
//! analysis half of the `rma` codec: which stretches of a take repeat
//! which. [`section`] turns the clips into the bitstream's plan (SPEC.md
//! §12: the body coded once as pca-spline, each repeated clip a
//! piecewise-linear map into it plus a residual); `encode::rma` writes it.
//!
//! 1. [`features`]: the posture of every frame without the root (the body's
//!    rotation channels, unwrapped), reduced by PCA to the components that
//!    hold [`Params::variance`] of its variance — the paper's projected
//!    coefficients; analysed at about 30 frames per second.
//! 2. [`paths`]: the self-distance plot of those coefficients in a band
//!    around the diagonal ([`Params::window_s`], so the work grows linearly
//!    with the take), and the similar-posture paths in it.
//! 3. [`clips`]: the greedy extraction of primary, repeated and unique clips
//!    maximising the gain of eq. 5 with the costs of eq. 2 and eq. 3.

pub mod clips;
pub mod matches;
pub mod paths;
pub mod section;

use nalgebra::{DMatrix, SymmetricEigen};

use crate::fixed::unwrap_degrees;
use crate::motion::Motion;

pub use clips::{Clip, ClipKind};
pub use paths::Path;
pub use section::{Plan, Repeated};

/// The analysis's parameters: the paper's values where it gives them.
#[derive(Clone, Debug)]
pub struct Params {
    /// Share of the posture variance the components keep (the paper: 95 %).
    pub variance: f64,
    /// Analysis rate, frames per second (the take is sampled down to it).
    pub rate_hz: f64,
    /// How far apart two frames may be and still be compared, seconds: the
    /// width of the self-distance band.
    pub window_s: f64,
    /// Pixels above this share of the band's distances are suppressed.
    pub threshold_quantile: f64,
    /// Longest bridge joining two paths (the paper: 300 ms).
    pub bridge_s: f64,
    /// Shortest path kept, Manhattan length (the paper: 600 ms).
    pub min_path_s: f64,
    /// Shortest repeated or unique clip (the paper merges shorter: 200 ms).
    pub min_clip_s: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            variance: 0.95,
            rate_hz: 30.0,
            window_s: 60.0,
            threshold_quantile: 0.15,
            bridge_s: 0.3,
            min_path_s: 0.6,
            min_clip_s: 0.2,
        }
    }
}

/// The projected coefficients of a take, sampled at the analysis rate.
#[derive(Clone, Debug)]
pub struct Features {
    /// Components per frame.
    pub k: usize,
    /// `len × k`, row-major.
    pub coef: Vec<f64>,
    /// Source frames per analysis frame.
    pub step: usize,
    /// Analysis frames.
    pub len: usize,
    /// Analysis frames per second.
    pub rate: f64,
    /// RMS distance of a frame's coefficients from their mean: the scale
    /// the costs' overheads are given in.
    pub spread: f64,
}

impl Features {
    /// `seconds` in analysis frames (at least 1).
    pub fn frames_of(&self, seconds: f64) -> usize {
        ((seconds * self.rate).round() as usize).max(1)
    }

    /// Coefficients of analysis frame `f`.
    pub fn row(&self, f: usize) -> &[f64] {
        &self.coef[f * self.k..(f + 1) * self.k]
    }

    /// Distance between analysis frames `a` and `b`.
    pub fn dist(&self, a: usize, b: usize) -> f64 {
        self.row(a)
            .iter()
            .zip(self.row(b))
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    }
}

/// The body's rotation channels: every rotation channel of a joint with a
/// parent (the posture without the root).
pub fn body_channels(m: &Motion) -> Vec<usize> {
    let joints = m.skeleton.channel_joints();
    m.skeleton
        .channel_kinds()
        .iter()
        .enumerate()
        .filter(|&(c, kind)| kind.is_rotation() && m.skeleton.joints[joints[c]].parent.is_some())
        .map(|(c, _)| c)
        .collect()
}

/// The body's rotation channels ([`body_channels`]), unwrapped, sampled every `step` frames, centred and projected
/// on the principal components that keep `variance` of their variance.
pub fn features(m: &Motion, p: &Params) -> Features {
    let frame_rate = if m.frame_time > 0.0 {
        1.0 / m.frame_time
    } else {
        p.rate_hz
    };
    let step = ((frame_rate / p.rate_hz).round() as usize).max(1);
    let body = body_channels(m);
    let len = m.frames().div_ceil(step);
    let n = body.len();
    let mut x = DMatrix::<f64>::zeros(len, n.max(1));
    for (col, &c) in body.iter().enumerate() {
        let mut series = m.channel(c);
        unwrap_degrees(&mut series);
        let picked: Vec<f64> = series.iter().step_by(step).copied().collect();
        let mean = picked.iter().sum::<f64>() / len.max(1) as f64;
        for (f, v) in picked.iter().enumerate() {
            x[(f, col)] = v - mean;
        }
    }
    if n == 0 || len == 0 {
        return Features {
            k: 0,
            coef: Vec::new(),
            step,
            len,
            rate: frame_rate / step as f64,
            spread: 0.0,
        };
    }
    let cov = x.transpose() * &x;
    let eig = SymmetricEigen::new(cov);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let total: f64 = eig.eigenvalues.iter().map(|v| v.max(0.0)).sum();
    let mut k = 0;
    let mut kept = 0.0;
    while k < n && (k == 0 || kept < p.variance * total) {
        kept += eig.eigenvalues[order[k]].max(0.0);
        k += 1;
    }
    let mut coef = vec![0.0; len * k];
    for f in 0..len {
        for (i, &o) in order[..k].iter().enumerate() {
            coef[f * k + i] = (0..n).map(|c| x[(f, c)] * eig.eigenvectors[(c, o)]).sum();
        }
    }
    Features {
        k,
        coef,
        step,
        len,
        rate: frame_rate / step as f64,
        spread: (kept / len as f64).sqrt(),
    }
}

/// What the analysis found in a take.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The projected coefficients.
    pub features: Features,
    /// The similar-posture paths (analysis frames).
    pub paths: Vec<Path>,
    /// The clips, in time order, covering every source frame once.
    pub clips: Vec<Clip>,
    /// The clips of the paths' longest matches ([`matches`]), likewise.
    pub matches: Vec<Clip>,
}

impl Analysis {
    /// Source frames in primary, repeated and unique clips.
    pub fn frames_by_kind(&self) -> [usize; 3] {
        let mut n = [0; 3];
        for c in &self.clips {
            let i = match c.kind {
                ClipKind::Primary => 0,
                ClipKind::Repeated { .. } => 1,
                ClipKind::Unique => 2,
            };
            n[i] += c.end - c.start;
        }
        n
    }
}

/// Runs the analysis on `m`.
pub fn analyse(m: &Motion, p: &Params) -> Analysis {
    let features = features(m, p);
    let paths = paths::find(&features, p);
    let clips = clips::extract(&features, &paths, p, m.frames());
    let matches = matches::extract(&features, &paths, p, m.frames());
    Analysis {
        features,
        paths,
        clips,
        matches,
    }
}

#[cfg(test)]
mod tests;
