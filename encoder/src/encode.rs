//! The encode pipeline: tolerances from the error bound, the codec, the
//! container, then a decode with the `no_std` decoder that proves the bound
//! before anything is written (tightening and retrying if it does not hold).

use std::fmt;
use std::str::FromStr;

use mocap_decoder::consts;
use mocap_decoder::Clip;

use crate::clipfile;
use crate::codec::index;
use crate::container::{assemble, HeaderWire};
use crate::fixed::{self, FixedChannels, MDEG_PER_DEG};
use crate::kinematics;
use crate::metrics::{self, Metrics};
use crate::motion::Motion;

/// One error bound: degrees on rotation channels or millimetres on joint
/// positions (`1deg`, `0.25deg`, `8mm`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoundSpec {
    /// Max wrap-aware error of every rotation channel, degrees.
    Degrees(f64),
    /// Max joint-position error (forward kinematics), millimetres.
    Millimetres(f64),
}

impl FromStr for BoundSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        let (num, unit) = t
            .find(|c: char| c.is_ascii_alphabetic())
            .map(|i| t.split_at(i))
            .ok_or_else(|| format!("error bound '{s}' needs a unit: e.g. 1deg or 8mm"))?;
        let v: f64 = num
            .trim()
            .parse()
            .map_err(|_| format!("error bound '{s}': '{num}' is not a number"))?;
        if !(v.is_finite() && v > 0.0) {
            return Err(format!("error bound '{s}' must be a positive number"));
        }
        match unit {
            "deg" | "°" => Ok(BoundSpec::Degrees(v)),
            "mm" => Ok(BoundSpec::Millimetres(v)),
            "cm" => Ok(BoundSpec::Millimetres(v * 10.0)),
            _ => Err(format!(
                "error bound '{s}': unit '{unit}' is not deg, mm or cm"
            )),
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
        };
        for s in specs {
            match *s {
                BoundSpec::Degrees(d) => b.angle_deg = Some(b.angle_deg.map_or(d, |x| x.min(d))),
                BoundSpec::Millimetres(m) => {
                    b.position_mm = Some(b.position_mm.map_or(m, |x| x.min(m)))
                }
            }
        }
        b
    }

    /// True if measured metrics meet the bound.
    pub fn holds(&self, m: &Metrics) -> bool {
        self.angle_deg.is_none_or(|d| m.angle_max_deg <= d)
            && self.position_mm.is_none_or(|p| m.max_joint_err_mm <= p)
            && (self.position_mm.is_some() || m.position_max_mm <= Self::DEFAULT_TRANSLATION_MM)
    }
}

impl fmt::Display for Bound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.angle_deg, self.position_mm) {
            (Some(a), Some(p)) => write!(f, "{a}° and {p} mm"),
            (Some(a), None) => write!(f, "{a}°"),
            (None, Some(p)) => write!(f, "{p} mm"),
            (None, None) => f.write_str("none"),
        }
    }
}

/// Which codec to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CodecChoice {
    /// Low-resolution model-based indexing (SPEC.md §4).
    Index,
}

/// Options of one encode.
#[derive(Clone, Debug)]
pub struct EncodeOptions {
    /// The codec.
    pub codec: CodecChoice,
    /// The error bound.
    pub bound: Bound,
    /// Metres per source length unit.
    pub metres_per_unit: f64,
    /// Force a key-frame interval (index codec); `None` = smallest clip.
    pub key_interval: Option<u16>,
}

/// An encoded clip and its measured quality.
#[derive(Clone, Debug)]
pub struct Encoded {
    /// The `.mcb` bytes.
    pub bytes: Vec<u8>,
    /// Metrics measured by decoding `bytes` with the decoder.
    pub metrics: Metrics,
    /// Key-frame interval chosen.
    pub key_interval: u16,
    /// Encode attempts (tightening rounds) needed.
    pub attempts: usize,
}

/// Per-channel tolerances (fixed-point units) for a position budget scale
/// `s_um` (µm; `None` = no position bound).
fn tolerances(
    fixed: &FixedChannels,
    opts: &EncodeOptions,
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
                if let Some(d) = opts.bound.angle_deg {
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

/// The result of one attempt at fixed tolerances.
struct Attempt {
    bytes: Vec<u8>,
    metrics: Metrics,
    key_interval: u16,
}

fn attempt(
    m: &Motion,
    fixed: &FixedChannels,
    tol: &[i64],
    opts: &EncodeOptions,
    original_mm: &[[f64; 3]],
) -> Result<Attempt, String> {
    let intervals: Vec<u16> = match opts.key_interval {
        Some(k) => vec![k],
        None => index::KEY_INTERVALS.to_vec(),
    };
    let enc = index::encode(&fixed.values, tol, &intervals).map_err(|e| {
        format!(
            "channel {} ({}) cannot meet the error bound with 12-bit codes",
            e.channel,
            m.skeleton.channel_names()[e.channel]
        )
    })?;
    let decoded = FixedChannels {
        kinds: fixed.kinds.clone(),
        values: enc.decoded(),
    };
    let header = HeaderWire::new(m, opts.metres_per_unit, &decoded);
    let bytes = assemble(&[
        (consts::SECTION_HEADER, header.to_bytes()),
        (consts::SECTION_CODEC_INDEX, enc.to_section()?),
    ]);
    // Prove it with the real decoder.
    let clip =
        Clip::parse(&bytes).map_err(|e| format!("internal error: own clip rejected: {e}"))?;
    let frames = clipfile::decode_all(&clip).map_err(|e| format!("internal error: {e}"))?;
    let n = fixed.kinds.len();
    for (c, ch) in decoded.values.iter().enumerate() {
        for (f, &v) in ch.iter().enumerate() {
            if frames[f * n + c] != v {
                return Err(format!(
                    "internal error: decoder and encoder disagree at frame {f}, channel {c}"
                ));
            }
        }
    }
    let back = fixed::from_fixed(&m.skeleton, m.frame_time, &frames, opts.metres_per_unit);
    let metrics = metrics::compare(
        m,
        &back,
        opts.metres_per_unit,
        Some(original_mm),
        bytes.len(),
        0,
    );
    Ok(Attempt {
        bytes,
        metrics,
        key_interval: enc.key_interval,
    })
}

/// Encodes `m`, proving the bound by decoding; errors say why it cannot.
pub fn encode(m: &Motion, opts: &EncodeOptions) -> Result<Encoded, String> {
    if m.frames() == 0 || m.channels() == 0 {
        return Err("the motion has no frames or no channels".into());
    }
    if m.channels() > usize::from(u16::MAX) {
        return Err(format!(
            "{} channels exceed the format's 65535",
            m.channels()
        ));
    }
    let fixed = fixed::to_fixed(m, opts.metres_per_unit);
    let original_mm = metrics::positions_mm(m, opts.metres_per_unit);
    let levers_um: Vec<f64> = kinematics::lever_arms(&m.skeleton)
        .into_iter()
        .map(|l| l * opts.metres_per_unit * 1e6)
        .collect();
    let joint_of = m.skeleton.channel_joints();
    let mut attempts = 0;
    let mut tighten = 1.0;
    let run = |s_um: Option<f64>, tighten: f64| {
        let tol = tolerances(&fixed, opts, &levers_um, &joint_of, s_um, tighten);
        attempt(m, &fixed, &tol, opts, &original_mm)
    };
    let best = match opts.bound.position_mm {
        None => loop {
            attempts += 1;
            let a = run(None, tighten)?;
            if opts.bound.holds(&a.metrics) {
                break a;
            }
            if attempts >= 8 {
                return Err(format!(
                    "could not meet the bound {} after {attempts} attempts",
                    opts.bound
                ));
            }
            tighten *= 0.8;
        },
        Some(p) => {
            // Bisect the position budget: errors of every joint up the chain
            // add up, so the budget per channel is a fraction of the bound.
            let bound_um = p * 1000.0;
            let (mut lo, mut hi) = (bound_um * 1e-3, bound_um);
            let mut best: Option<Attempt> = None;
            for _ in 0..14 {
                attempts += 1;
                let s = (lo * hi).sqrt();
                let a = run(Some(s), 1.0)?;
                if opts.bound.holds(&a.metrics) {
                    lo = s;
                    if best.as_ref().is_none_or(|b| a.bytes.len() <= b.bytes.len()) {
                        best = Some(a);
                    }
                } else {
                    hi = s;
                }
                if hi / lo < 1.03 {
                    break;
                }
            }
            match best {
                Some(b) => b,
                None => {
                    attempts += 1;
                    let a = run(Some(lo), 1.0)?;
                    if !opts.bound.holds(&a.metrics) {
                        return Err(format!("could not meet the bound {}", opts.bound));
                    }
                    a
                }
            }
        }
    };
    Ok(Encoded {
        bytes: best.bytes,
        metrics: best.metrics,
        key_interval: best.key_interval,
        attempts,
    })
}
