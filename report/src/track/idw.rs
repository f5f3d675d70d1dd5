//! Placing a frame in the 2-D reference space (Hu et al. §3.2): the
//! weighted mean of the key frames' 2-D positions, with weights from the
//! frame's high-dimensional distances `h_i` to the key frames (Shepard's
//! inverse distance weighting). `R` is the distance to the farthest key frame.
//!
//! - eq. 2: `w_i ∝ h_i^−p`
//! - eq. 3: `w_i ∝ ((R − h_i) / (R·h_i))^p`
//! - eq. 4: `w_i ∝ exp(((R − h_i) / R)^p)` (Gaussian smoothing; the paper's
//!   smoothest track with p = 2)
//!
//! All weights are normalised to sum to one. A frame that coincides with a
//! key frame (`h_i = 0`) takes that key frame's position under eq. 2 and 3.

use std::fmt;
use std::str::FromStr;

/// The weighting scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Eq. 2, inverse distance to the power p.
    Eq2,
    /// Eq. 3, inverse distance relative to the farthest key frame.
    Eq3,
    /// Eq. 4, Gaussian-smoothed (default).
    Eq4,
}

impl Scheme {
    /// The paper's p for this scheme (Fig. 6: p = 8 for eq. 2, 2 otherwise).
    pub fn default_p(self) -> f64 {
        match self {
            Scheme::Eq2 => 8.0,
            Scheme::Eq3 | Scheme::Eq4 => 2.0,
        }
    }
}

/// A `--weights` name that is not a scheme.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown weighting {0:?} (eq2, eq3, eq4)")]
pub struct UnknownScheme(pub String);

impl FromStr for Scheme {
    type Err = UnknownScheme;
    fn from_str(s: &str) -> Result<Self, UnknownScheme> {
        match s.to_ascii_lowercase().as_str() {
            "eq2" | "2" => Ok(Scheme::Eq2),
            "eq3" | "3" => Ok(Scheme::Eq3),
            "eq4" | "4" | "gauss" | "gaussian" => Ok(Scheme::Eq4),
            _ => Err(UnknownScheme(s.to_string())),
        }
    }
}

impl fmt::Display for Scheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Scheme::Eq2 => "eq2",
            Scheme::Eq3 => "eq3",
            Scheme::Eq4 => "eq4",
        })
    }
}

/// Weights of the key frames at distances `h` (all ≥ 0), summing to one.
///
/// The weights are formed as logarithms and normalised against the largest,
/// so no power can overflow or underflow to a non-finite or all-zero sum: a
/// frame at (or within 1e-12 of) a key frame takes that key frame's position
/// under eq. 2 and 3, `R = 0` (all distances zero) gives equal weights.
pub fn weights(h: &[f64], scheme: Scheme, p: f64) -> Vec<f64> {
    let n = h.len();
    if n == 0 {
        return Vec::new();
    }
    if scheme != Scheme::Eq4 {
        if let Some(i) = h.iter().position(|&d| d <= 1e-12) {
            let mut w = vec![0.0; n];
            w[i] = 1.0;
            return w;
        }
    }
    let r = h.iter().copied().fold(0.0f64, f64::max);
    // ln of the unnormalised weight; −∞ for a zero weight.
    let log_w: Vec<f64> = match scheme {
        Scheme::Eq2 => h.iter().map(|&d| -p * d.ln()).collect(),
        Scheme::Eq3 => h
            .iter()
            .map(|&d| {
                let v = (r - d) / (r * d);
                if v > 0.0 {
                    p * v.ln()
                } else {
                    f64::NEG_INFINITY
                }
            })
            .collect(),
        Scheme::Eq4 => h
            .iter()
            .map(|&d| {
                if r > 0.0 {
                    ((r - d) / r).max(0.0).powf(p)
                } else {
                    0.0
                }
            })
            .collect(),
    };
    let top = log_w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !top.is_finite() {
        // Every weight zero (eq. 3 with all key frames at distance R).
        return vec![1.0 / n as f64; n];
    }
    let raw: Vec<f64> = log_w.iter().map(|&l| (l - top).exp()).collect();
    let sum: f64 = raw.iter().sum(); // ≥ 1 (the largest term is 1) unless a distance is NaN
    if sum.is_finite() {
        raw.iter().map(|w| w / sum).collect()
    } else {
        vec![1.0 / n as f64; n]
    }
}

/// The 2-D position of a frame: `Σ w_i · y_i` over key frames `y`.
pub fn place(h: &[f64], key_xy: &[[f64; 2]], scheme: Scheme, p: f64) -> [f64; 2] {
    let w = weights(h, scheme, p);
    let mut out = [0.0; 2];
    for (wi, y) in w.iter().zip(key_xy) {
        out[0] += wi * y[0];
        out[1] += wi * y[1];
    }
    out
}
