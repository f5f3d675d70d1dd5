//! Length units of BVH skeletons and their detection.
//!
//! BVH files do not state their length unit. The CMU conversion uses
//! 1/0.45 inch ("cmu" units, the hips ~17 units high), game rigs use
//! centimetres, others metres, millimetres or inches. [`detect`] picks the
//! unit that gives the figure a human-like height.

use crate::kinematics;
use crate::motion::Motion;
use std::fmt;
use std::str::FromStr;

/// A length unit of skeleton OFFSETs and position channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LengthUnit {
    /// Millimetres.
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Inches.
    In,
    /// The CMU database's BVH unit: 1/0.45 inch (≈ 5.644 cm).
    Cmu,
}

impl LengthUnit {
    /// Every unit, in the order [`detect`] considers them.
    pub const ALL: [LengthUnit; 5] = [
        LengthUnit::Mm,
        LengthUnit::Cm,
        LengthUnit::M,
        LengthUnit::In,
        LengthUnit::Cmu,
    ];

    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Mm => 0.001,
            LengthUnit::Cm => 0.01,
            LengthUnit::M => 1.0,
            LengthUnit::In => 0.0254,
            LengthUnit::Cmu => 0.0254 / 0.45,
        }
    }

    /// Micrometres per unit, rounded to the nearest integer (cmu: 56444).
    pub fn micrometres(self) -> u32 {
        match self {
            LengthUnit::Mm => 1_000,
            LengthUnit::Cm => 10_000,
            LengthUnit::M => 1_000_000,
            LengthUnit::In => 25_400,
            // 25400 / 0.45 = 56444.4…
            LengthUnit::Cmu => 56_444,
        }
    }

    /// The short name: `mm`, `cm`, `m`, `in` or `cmu`.
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::Cm => "cm",
            LengthUnit::M => "m",
            LengthUnit::In => "in",
            LengthUnit::Cmu => "cmu",
        }
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Error of parsing a [`LengthUnit`] name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseLengthUnitError {
    /// The rejected text.
    pub found: String,
}

impl fmt::Display for ParseLengthUnitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown length unit '{}' (expected one of: mm, cm, m, in, inch, cmu)",
            self.found
        )
    }
}

impl std::error::Error for ParseLengthUnitError {}

impl FromStr for LengthUnit {
    type Err = ParseLengthUnitError;

    /// Accepts `mm`, `cm`, `m`, `in`, `inch` and `cmu` (ASCII
    /// case-insensitive, surrounding whitespace ignored).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        let unit = if t.eq_ignore_ascii_case("mm") {
            LengthUnit::Mm
        } else if t.eq_ignore_ascii_case("cm") {
            LengthUnit::Cm
        } else if t.eq_ignore_ascii_case("m") {
            LengthUnit::M
        } else if t.eq_ignore_ascii_case("in") || t.eq_ignore_ascii_case("inch") {
            LengthUnit::In
        } else if t.eq_ignore_ascii_case("cmu") {
            LengthUnit::Cmu
        } else {
            return Err(ParseLengthUnitError {
                found: s.to_owned(),
            });
        };
        Ok(unit)
    }
}

/// The figure's height in skeleton units: the largest extent, over the
/// three axes, of the joint positions (End Sites included) in the rest pose
/// (all channels zero). Rigs are Y-up or Z-up, so the longest axis is taken
/// rather than a fixed one. If the rest pose is degenerate (extent below
/// 1e-9), the first frame is used instead.
pub fn skeleton_height(m: &Motion) -> f64 {
    let rest = vec![0.0; m.channels()];
    let h = extent(m, &rest);
    if h < 1e-9 && m.frames() > 0 {
        extent(m, m.frame(0))
    } else {
        h
    }
}

fn extent(m: &Motion, frame: &[f64]) -> f64 {
    let mut pos = Vec::new();
    kinematics::joint_positions(&m.skeleton, frame, &mut pos);
    (0..3)
        .map(|axis| {
            let (lo, hi) = pos
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[axis]), hi.max(p[axis]))
                });
            if hi >= lo {
                hi - lo
            } else {
                0.0
            }
        })
        .fold(0.0, f64::max)
}

/// The height, in metres, a human-like figure is assumed to have.
pub const EXPECTED_HEIGHT_M: f64 = 1.7;

/// Guesses the length unit: the one that makes [`skeleton_height`] closest,
/// in log space, to [`EXPECTED_HEIGHT_M`]. A skeleton without extent (all
/// joints at one point in the rest pose and in the first frame) gives
/// [`LengthUnit::M`].
pub fn detect(m: &Motion) -> LengthUnit {
    let h = skeleton_height(m);
    if !(h.is_finite() && h > 1e-9) {
        return LengthUnit::M;
    }
    let score = |u: LengthUnit| (h * u.metres() / EXPECTED_HEIGHT_M).ln().abs();
    LengthUnit::ALL
        .into_iter()
        .min_by(|a, b| score(*a).total_cmp(&score(*b)))
        .unwrap_or(LengthUnit::M)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{ChannelKind, Joint, Skeleton};

    #[test]
    fn conversions() {
        assert_eq!(LengthUnit::Cmu.micrometres(), 56_444);
        for u in LengthUnit::ALL {
            assert_eq!(u.micrometres(), (u.metres() * 1e6).round() as u32);
        }
        assert!((LengthUnit::Cmu.metres() - 0.056444).abs() < 1e-6);
    }

    #[test]
    fn parse_and_display() {
        for (s, u) in [
            ("mm", LengthUnit::Mm),
            ("cm", LengthUnit::Cm),
            ("m", LengthUnit::M),
            ("in", LengthUnit::In),
            ("inch", LengthUnit::In),
            ("cmu", LengthUnit::Cmu),
            (" CM ", LengthUnit::Cm),
        ] {
            assert_eq!(s.parse::<LengthUnit>(), Ok(u));
        }
        for u in LengthUnit::ALL {
            assert_eq!(u.to_string().parse::<LengthUnit>(), Ok(u));
        }
        let e = "feet".parse::<LengthUnit>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown length unit 'feet' (expected one of: mm, cm, m, in, inch, cmu)"
        );
    }

    /// A stick figure `height` units tall along `axis`.
    fn stick(height: f64, axis: usize, channels: usize) -> Motion {
        let mut offset = [0.0; 3];
        offset[axis] = height;
        let kinds = &ChannelKind::ALL[..channels];
        Motion {
            skeleton: Skeleton {
                joints: vec![
                    Joint {
                        name: "Root".into(),
                        parent: None,
                        offset: [0.0; 3],
                        channels: kinds.to_vec(),
                        end_site: false,
                    },
                    Joint {
                        name: "Root_End".into(),
                        parent: Some(0),
                        offset,
                        channels: vec![],
                        end_site: true,
                    },
                ],
            },
            frame_time: 0.01,
            values: vec![0.0; channels],
        }
    }

    #[test]
    fn detects_by_height() {
        for (h, u) in [
            (1.75, LengthUnit::M),
            (170.0, LengthUnit::Cm),
            (1700.0, LengthUnit::Mm),
            (66.0, LengthUnit::In),
            (30.0, LengthUnit::Cmu),
        ] {
            for axis in [1, 2] {
                let m = stick(h, axis, 3);
                assert!((skeleton_height(&m) - h).abs() < 1e-9);
                assert_eq!(detect(&m), u, "height {h} on axis {axis}");
            }
        }
    }

    #[test]
    fn degenerate_rest_pose_uses_first_frame() {
        // Every joint at the origin in the rest pose; the first frame moves
        // the child 170 units up through its position channel.
        let mut m = stick(0.0, 1, 6);
        m.skeleton.joints[1] = Joint {
            name: "Child".into(),
            parent: Some(0),
            offset: [0.0; 3],
            channels: vec![ChannelKind::Yposition],
            end_site: false,
        };
        m.values = vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 170.0];
        assert_eq!(skeleton_height(&m), 170.0);
        assert_eq!(detect(&m), LengthUnit::Cm);
        m.values[6] = 0.0;
        assert_eq!(detect(&m), LengthUnit::M);
    }
}
