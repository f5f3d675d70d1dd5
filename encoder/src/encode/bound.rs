//! The error bound: `--max-error` values ([`BoundSpec`]), their merge
//! ([`Bound`]) and the per-channel tolerances a bound gives the codecs that
//! work from tolerances.

use std::fmt;
use std::str::FromStr;

use crate::fixed::{FixedChannels, MDEG_PER_DEG};
use crate::metrics::Metrics;

/// A `--max-error` value that does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum BoundError {
    /// No unit after the number.
    #[error("error bound '{0}' needs a unit: e.g. 1deg or 8mm")]
    NoUnit(String),
    /// The number does not parse.
    #[error("error bound '{spec}': '{number}' is not a number")]
    NotANumber {
        /// The value as given.
        spec: String,
        /// Its number part.
        number: String,
    },
    /// Zero, negative or not finite.
    #[error("error bound '{0}' must be a positive number")]
    NotPositive(String),
    /// A unit other than deg, mm or cm.
    #[error("error bound '{spec}': unit '{unit}' is not deg, mm or cm")]
    UnknownUnit {
        /// The value as given.
        spec: String,
        /// Its unit.
        unit: String,
    },
    /// `arms:` followed by an angle.
    #[error("error bound '{0}': ARMS is a length, e.g. arms:10mm")]
    ArmsNotLength(String),
    /// `slide:` followed by something other than a speed.
    #[error("error bound '{0}': the foot slide is a speed, e.g. slide:20mm/s")]
    SlideNotSpeed(String),
}

/// One error bound: degrees on rotation channels or millimetres on joint
/// positions (`1deg`, `0.25deg`, `8mm`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundSpec {
    /// Max wrap-aware error of every rotation channel, degrees.
    Degrees(f64),
    /// Max joint-position error (forward kinematics), millimetres.
    Millimetres(f64),
    /// Mean over frames of the RMS joint-position error (ARMS),
    /// millimetres: `arms:10mm`.
    Arms(f64),
    /// Foot slide: the decoded feet's mean horizontal speed where the
    /// source's are planted, at most this much above the source's own, mm/s
    /// (`slide:20mm/s`; [`crate::contacts`]). On top of the other bounds
    /// (alone, beside the default `1deg`).
    Slide(f64),
}

impl FromStr for BoundSpec {
    type Err = BoundError;

    fn from_str(s: &str) -> Result<Self, BoundError> {
        let t = s.trim();
        if let Some(rest) = t.strip_prefix("slide:") {
            let not_speed = || BoundError::SlideNotSpeed(s.to_string());
            let (length, scale) = [("mm/s", 1.0), ("cm/s", 10.0), ("m/s", 1000.0)]
                .iter()
                .find_map(|(unit, k)| rest.trim().strip_suffix(unit).map(|v| (v, *k)))
                .ok_or_else(not_speed)?;
            return match format!("{length}mm").parse::<BoundSpec>()? {
                BoundSpec::Millimetres(v) => Ok(BoundSpec::Slide(v * scale)),
                _ => Err(not_speed()),
            };
        }
        if let Some(rest) = t.strip_prefix("arms:") {
            return match rest.parse::<BoundSpec>()? {
                BoundSpec::Millimetres(mm) => Ok(BoundSpec::Arms(mm)),
                _ => Err(BoundError::ArmsNotLength(s.to_string())),
            };
        }
        let (num, unit) = t
            .find(|c: char| c.is_ascii_alphabetic())
            .map(|i| t.split_at(i))
            .ok_or_else(|| BoundError::NoUnit(s.to_string()))?;
        let v: f64 = num.trim().parse().map_err(|_| BoundError::NotANumber {
            spec: s.to_string(),
            number: num.to_string(),
        })?;
        if !(v.is_finite() && v > 0.0) {
            return Err(BoundError::NotPositive(s.to_string()));
        }
        match unit {
            "deg" | "°" => Ok(BoundSpec::Degrees(v)),
            "mm" => Ok(BoundSpec::Millimetres(v)),
            "cm" => Ok(BoundSpec::Millimetres(v * 10.0)),
            _ => Err(BoundError::UnknownUnit {
                spec: s.to_string(),
                unit: unit.to_string(),
            }),
        }
    }
}

/// The combined bound of one encode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// Rotation channels, degrees.
    pub angle_deg: Option<f64>,
    /// Joint positions, millimetres.
    pub position_mm: Option<f64>,
    /// ARMS of joint positions, millimetres.
    pub arms_mm: Option<f64>,
    /// Foot slide above the source's, mm/s ([`BoundSpec::Slide`]).
    pub foot_slide_mm_s: Option<f64>,
}

impl Bound {
    /// Translation channels keep this accuracy (mm) when only an angle bound
    /// is given.
    pub const DEFAULT_TRANSLATION_MM: f64 = 1.0;

    /// Merges several `--max-error` values (the tightest of each kind wins).
    pub fn from_specs(specs: &[BoundSpec]) -> Bound {
        let mut b = Bound {
            angle_deg: None,
            position_mm: None,
            arms_mm: None,
            foot_slide_mm_s: None,
        };
        for s in specs {
            match *s {
                BoundSpec::Degrees(d) => b.angle_deg = Some(b.angle_deg.map_or(d, |x| x.min(d))),
                BoundSpec::Millimetres(m) => {
                    b.position_mm = Some(b.position_mm.map_or(m, |x| x.min(m)))
                }
                BoundSpec::Arms(m) => b.arms_mm = Some(b.arms_mm.map_or(m, |x| x.min(m))),
                BoundSpec::Slide(v) => {
                    b.foot_slide_mm_s = Some(b.foot_slide_mm_s.map_or(v, |x| x.min(v)))
                }
            }
        }
        // A slide bound limits the feet only: the rest keeps the default.
        if b.angle_deg.is_none() && !b.positional() && b.foot_slide_mm_s.is_some() {
            b.angle_deg = Some(1.0);
        }
        b
    }

    /// True if measured metrics meet the bound.
    pub fn holds(&self, m: &Metrics) -> bool {
        self.angle_deg.is_none_or(|d| m.angle_max_deg <= d)
            && self.position_mm.is_none_or(|p| m.max_joint_err_mm <= p)
            && self.arms_mm.is_none_or(|p| m.arms_mm <= p)
            && (self.positional() || m.position_max_mm <= Self::DEFAULT_TRANSLATION_MM)
            && self.foot_slide_mm_s.is_none_or(|v| {
                m.foot_pairs == 0 || m.foot_slide_mm_s - m.foot_slide_source_mm_s <= v
            })
    }

    /// True if a bound is on joint positions (max or ARMS).
    pub fn positional(&self) -> bool {
        self.position_mm.is_some() || self.arms_mm.is_some()
    }
}

impl fmt::Display for Bound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        if let Some(a) = self.angle_deg {
            parts.push(format!("{a}°"));
        }
        if let Some(p) = self.position_mm {
            parts.push(format!("{p} mm"));
        }
        if let Some(p) = self.arms_mm {
            parts.push(format!("ARMS {p} mm"));
        }
        if let Some(v) = self.foot_slide_mm_s {
            parts.push(format!("foot slide +{v} mm/s"));
        }
        if parts.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&parts.join(" and "))
        }
    }
}

/// Per-channel tolerances (fixed-point units) for a position budget scale
/// `s_um` (µm; `None` = no position bound).
pub(super) fn tolerances(
    fixed: &FixedChannels,
    bound: &Bound,
    levers_um: &[f64],
    joint_of: &[usize],
    s_um: Option<f64>,
    tighten: f64,
) -> Vec<i64> {
    fixed
        .kinds
        .iter()
        .enumerate()
        .map(|(c, kind)| {
            let mut tol = f64::INFINITY;
            if kind.is_rotation() {
                if let Some(d) = bound.angle_deg {
                    // Half a millidegree is lost to rounding the input.
                    tol = tol.min(d * MDEG_PER_DEG - 1.0);
                }
                if let Some(s) = s_um {
                    let lever = levers_um[joint_of[c]];
                    if lever > 0.0 {
                        tol = tol.min((s / lever).to_degrees() * MDEG_PER_DEG);
                    }
                }
            } else {
                match s_um {
                    Some(s) => tol = tol.min(s),
                    None => tol = tol.min(Bound::DEFAULT_TRANSLATION_MM * 1000.0 - 1.0),
                }
            }
            let t = (tol * tighten).floor();
            if t.is_finite() {
                t.max(0.0) as i64
            } else {
                i64::from(i32::MAX)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<BoundSpec, BoundError> {
        s.parse()
    }

    #[test]
    fn a_slide_bound_is_a_speed() {
        assert_eq!(parse("slide:20mm/s"), Ok(BoundSpec::Slide(20.0)));
        assert_eq!(parse("slide:2cm/s"), Ok(BoundSpec::Slide(20.0)));
        assert_eq!(parse("slide:0.1m/s"), Ok(BoundSpec::Slide(100.0)));
        for bad in ["slide:20mm", "slide:1deg/s", "slide:fast"] {
            assert!(
                matches!(
                    parse(bad),
                    Err(BoundError::SlideNotSpeed(_)) | Err(BoundError::NotANumber { .. })
                ),
                "{bad}: {:?}",
                parse(bad)
            );
        }
        assert!(matches!(
            parse("slide:-3mm/s"),
            Err(BoundError::NotPositive(_))
        ));
    }

    /// Alone, a slide bound keeps the default angle bound beside it; with
    /// others, the tightest slide wins; it holds on the slide above the
    /// source's own, and on a take with no planted foot.
    #[test]
    fn a_slide_bound_holds_on_the_slide_above_the_sources() {
        let alone = Bound::from_specs(&[BoundSpec::Slide(50.0)]);
        assert_eq!(
            (alone.angle_deg, alone.foot_slide_mm_s),
            (Some(1.0), Some(50.0))
        );
        let b = Bound::from_specs(&[
            BoundSpec::Millimetres(50.0),
            BoundSpec::Slide(80.0),
            BoundSpec::Slide(40.0),
        ]);
        assert_eq!((b.angle_deg, b.foot_slide_mm_s), (None, Some(40.0)));
        assert_eq!(b.to_string(), "50 mm and foot slide +40 mm/s");
        let m = |slide: f64, pairs: usize| Metrics {
            bytes: 1,
            ratio_f32: 1.0,
            ratio_file: 0.0,
            arms_mm: 1.0,
            max_joint_err_mm: 10.0,
            max_joint_err_joint: String::new(),
            max_joint_err_frame: 0,
            distortion_pct: 0.0,
            angle_rms_deg: 0.0,
            angle_max_deg: 0.0,
            position_max_mm: 0.0,
            foot_pairs: pairs,
            foot_slide_mm_s: slide,
            foot_slide_source_mm_s: 100.0,
            foot_height_err_mm: 0.0,
            frames: 1,
            channels: 1,
        };
        assert!(b.holds(&m(140.0, 10)));
        assert!(!b.holds(&m(141.0, 10)));
        assert!(b.holds(&m(900.0, 0)), "no planted foot, nothing to slide");
    }
}
