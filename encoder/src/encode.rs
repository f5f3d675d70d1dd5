//! The encode pipeline: tolerances from the error bound, the codec, the
//! container, then a decode with the `no_std` decoder that proves the bound
//! before anything is written (tightening and retrying if it does not hold).

use std::fmt;
use std::str::FromStr;

use mocap_decoder::consts;
use mocap_decoder::Clip;

use crate::clipfile;
use crate::codec::{index, pca_spline, predictive};
use crate::container::{assemble, HeaderWire};
use crate::fixed::{self, FixedChannels, MDEG_PER_DEG};
use crate::kinematics;
use crate::metrics::{self, Metrics};
use crate::motion::{ChannelKind, Motion};

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
}

impl FromStr for BoundSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        if let Some(rest) = t.strip_prefix("arms:") {
            return match rest.parse::<BoundSpec>()? {
                BoundSpec::Millimetres(mm) => Ok(BoundSpec::Arms(mm)),
                _ => Err(format!(
                    "error bound '{s}': ARMS is a length, e.g. arms:10mm"
                )),
            };
        }
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
    /// ARMS of joint positions, millimetres.
    pub arms_mm: Option<f64>,
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
        };
        for s in specs {
            match *s {
                BoundSpec::Degrees(d) => b.angle_deg = Some(b.angle_deg.map_or(d, |x| x.min(d))),
                BoundSpec::Millimetres(m) => {
                    b.position_mm = Some(b.position_mm.map_or(m, |x| x.min(m)))
                }
                BoundSpec::Arms(m) => b.arms_mm = Some(b.arms_mm.map_or(m, |x| x.min(m))),
            }
        }
        b
    }

    /// True if measured metrics meet the bound.
    pub fn holds(&self, m: &Metrics) -> bool {
        self.angle_deg.is_none_or(|d| m.angle_max_deg <= d)
            && self.position_mm.is_none_or(|p| m.max_joint_err_mm <= p)
            && self.arms_mm.is_none_or(|p| m.arms_mm <= p)
            && (self.positional() || m.position_max_mm <= Self::DEFAULT_TRANSLATION_MM)
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
        if parts.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&parts.join(" and "))
        }
    }
}

/// Which codec to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CodecChoice {
    /// Low-resolution model-based indexing (SPEC.md §4).
    Index,
    /// Segment PCA + key-frame splines (SPEC.md §5).
    PcaSpline,
    /// Prediction from the last two values, residuals range-coded (SPEC.md §5b).
    Predictive,
    /// Every codec; keep the smallest clip that meets the bound.
    Auto,
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
    /// Force a key-frame interval (index codec) or block length
    /// (predictive codec); `None` = smallest clip (index) or
    /// [`predictive::DEFAULT_BLOCK_SECONDS`] (predictive).
    pub key_interval: Option<u16>,
}

/// An encoded clip and its measured quality.
#[derive(Clone, Debug)]
pub struct Encoded {
    /// The `.mcb` bytes.
    pub bytes: Vec<u8>,
    /// Metrics measured by decoding `bytes` with the decoder.
    pub metrics: Metrics,
    /// The codec that made the clip (never `Auto`).
    pub codec: CodecChoice,
    /// Key-frame interval chosen (index codec; 0 otherwise).
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
    /// Decoded values, `[channel][frame]`.
    decoded: Vec<Vec<i32>>,
}

fn attempt(
    m: &Motion,
    fixed: &FixedChannels,
    tol: &[i64],
    opts: &EncodeOptions,
    original_mm: &[[f64; 3]],
) -> Result<Attempt, String> {
    if opts.codec == CodecChoice::Predictive {
        let block = match opts.key_interval {
            Some(k) => u32::from(k.max(1)),
            None => ((predictive::DEFAULT_BLOCK_SECONDS / m.frame_time).round() as u32).max(1),
        };
        let enc = predictive::encode(&fixed.values, tol, block)?;
        let expected = FixedChannels {
            kinds: fixed.kinds.clone(),
            values: enc.decoded,
        };
        let mut a = prove(
            m,
            fixed,
            (consts::SECTION_CODEC_PREDICTIVE, enc.section),
            Some(&expected),
            opts,
            original_mm,
        )?;
        a.key_interval = block.min(u32::from(u16::MAX)) as u16;
        return Ok(a);
    }
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
    let expected = FixedChannels {
        kinds: fixed.kinds.clone(),
        values: enc.decoded(),
    };
    let mut a = prove(
        m,
        fixed,
        (consts::SECTION_CODEC_INDEX, enc.to_section()?),
        Some(&expected),
        opts,
        original_mm,
    )?;
    a.key_interval = enc.key_interval;
    Ok(a)
}

/// Assembles a clip around a codec section, decodes it with the `no_std`
/// decoder, writes the decoded ranges into the header and measures it.
/// `expected` (the encoder's own idea of the decoded values) is checked
/// bit for bit when given.
fn prove(
    m: &Motion,
    fixed: &FixedChannels,
    section: (u8, Vec<u8>),
    expected: Option<&FixedChannels>,
    opts: &EncodeOptions,
    original_mm: &[[f64; 3]],
) -> Result<Attempt, String> {
    let build = |ranges: &FixedChannels| {
        let header = HeaderWire::new(m, opts.metres_per_unit, ranges);
        assemble(&[
            (consts::SECTION_HEADER_COMPACT, header.to_compact()),
            section.clone(),
        ])
    };
    // Decoding does not read the header's ranges: decode once with the
    // input's, then write the decoded ones.
    let draft = build(expected.unwrap_or(fixed));
    let clip =
        Clip::parse(&draft).map_err(|e| format!("internal error: own clip rejected: {e}"))?;
    let frames = clipfile::decode_all(&clip).map_err(|e| format!("internal error: {e}"))?;
    let n = fixed.kinds.len();
    let decoded = FixedChannels {
        kinds: fixed.kinds.clone(),
        values: (0..n)
            .map(|c| frames.iter().skip(c).step_by(n).copied().collect())
            .collect(),
    };
    if let Some(e) = expected {
        if let Some((c, f)) = first_difference(&e.values, &decoded.values) {
            return Err(format!(
                "internal error: decoder and encoder disagree at frame {f}, channel {c}"
            ));
        }
    }
    let bytes = if expected.is_some() {
        draft
    } else {
        build(&decoded)
    };
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
        key_interval: 0,
        decoded: decoded.values,
    })
}

fn first_difference(a: &[Vec<i32>], b: &[Vec<i32>]) -> Option<(usize, usize)> {
    a.iter()
        .zip(b)
        .enumerate()
        .find_map(|(c, (x, y))| x.iter().zip(y).position(|(p, q)| p != q).map(|f| (c, f)))
}

/// A log-bisection for the largest parameter in `[lo, hi]` whose attempt
/// meets the bound (size falls as the parameter grows): at most `steps`
/// rounds, stopping once `hi / lo < ratio`. Returns the smallest holding
/// attempt seen (if any), the largest holding parameter found (`lo`) and
/// the attempts made.
fn bisect(
    bound: &Bound,
    (mut lo, mut hi): (f64, f64),
    steps: usize,
    ratio: f64,
    mut run: impl FnMut(f64) -> Result<Attempt, String>,
) -> Result<(Option<Attempt>, f64, usize), String> {
    let mut best: Option<Attempt> = None;
    let mut attempts = 0;
    for _ in 0..steps {
        attempts += 1;
        let x = (lo * hi).sqrt();
        let a = run(x)?;
        if bound.holds(&a.metrics) {
            lo = x;
            if best.as_ref().is_none_or(|b| a.bytes.len() <= b.bytes.len()) {
                best = Some(a);
            }
        } else {
            hi = x;
        }
        if hi / lo < ratio {
            break;
        }
    }
    Ok((best, lo, attempts))
}

/// Channel weights for the `pca-spline` tolerance: millimetres of joint
/// movement per fixed-point unit under a position bound (rotation: the
/// joint's lever arm, blended with its RMS lever under an ARMS bound; feet
/// and toes count double, as in the paper), else degrees per millidegree
/// and millimetres per micrometre.
pub fn pca_weights(
    m: &Motion,
    levers_um: &[f64],
    joint_of: &[usize],
    kinds: &[ChannelKind],
    mm: bool,
    arms: bool,
) -> Vec<f64> {
    let longest = levers_um.iter().fold(0.0f64, |a, &b| a.max(b));
    // Under an ARMS bound a channel also counts by how many joints it
    // moves: blend in its RMS lever (scaled to the same total).
    let beta = if arms { 0.3 } else { 0.0 };
    let rms = kinematics::rms_levers(&m.skeleton);
    let (sl, sr): (f64, f64) = (levers_um.iter().sum(), rms.iter().sum());
    let kappa = if sr > 0.0 { sl / sr } else { 0.0 };
    kinds
        .iter()
        .enumerate()
        .map(|(c, kind)| {
            if !kind.is_rotation() {
                // Translations move every joint and weigh on ARMS: an
                // eighth of the tolerance (root curves are cheap).
                return 8e-3;
            }
            if !mm {
                return 1e-3;
            }
            let j = joint_of[c];
            let name = m.skeleton.joints[j].name.to_ascii_lowercase();
            let foot = ["foot", "toe", "ankle"].iter().any(|f| name.contains(f));
            // Joints that move nothing measured still get a small weight
            // so they do not wander.
            let mixed = (1.0 - beta) * levers_um[j] + beta * kappa * rms[j];
            let lever_mm = (mixed / 1000.0).max(longest / 1000.0 * 0.02);
            let w = lever_mm * std::f64::consts::PI / 180.0 / 1000.0;
            if foot {
                2.0 * w
            } else {
                w
            }
        })
        .collect()
}

/// Channel groups of the `pca-spline` codec: the roots' translations and
/// heading (Y rotation: BVH is Y-up) each alone, then one group per limb —
/// a chain of joints between branchings — with chains of fewer than
/// `min_channels` channels (fingers, thumbs) merged into the chain they
/// branch from.
pub fn pca_groups(m: &Motion, min_channels: usize) -> Vec<Vec<usize>> {
    let joints = &m.skeleton.joints;
    let mut children = vec![0usize; joints.len()];
    for joint in joints.iter().filter(|j| !j.end_site) {
        if let Some(p) = joint.parent {
            children[p] += 1;
        }
    }
    // Chain of each joint: a joint continues its parent's chain when it is
    // the parent's only child.
    let mut chain: Vec<usize> = Vec::with_capacity(joints.len());
    let mut parent_chain: Vec<Option<usize>> = Vec::new();
    for joint in joints {
        match joint.parent {
            Some(p) if children[p] == 1 && joints[p].parent.is_some() => chain.push(chain[p]),
            Some(p) => {
                chain.push(parent_chain.len());
                parent_chain.push(Some(chain[p]));
            }
            None => {
                chain.push(parent_chain.len());
                parent_chain.push(None);
            }
        }
    }
    let mut size = vec![0usize; parent_chain.len()];
    for (joint, &c) in joints.iter().zip(&chain) {
        size[c] += joint.channels.len();
    }
    // Merge small chains upwards (children come after parents, so walk
    // backwards).
    let mut target: Vec<usize> = (0..parent_chain.len()).collect();
    for c in (0..parent_chain.len()).rev() {
        if size[c] < min_channels {
            if let Some(p) = parent_chain[c] {
                size[p] += size[c];
                target[c] = p;
            }
        }
    }
    let resolve = |mut c: usize| {
        while target[c] != c {
            c = target[c];
        }
        c
    };
    let mut groups: Vec<Vec<usize>> = vec![Vec::new(); parent_chain.len()];
    let mut tracks = Vec::new();
    let mut ch = 0;
    for (joint, &c) in joints.iter().zip(&chain) {
        for kind in &joint.channels {
            if joint.parent.is_none() && (!kind.is_rotation() || *kind == ChannelKind::Yrotation) {
                tracks.push(vec![ch]);
            } else {
                groups[resolve(c)].push(ch);
            }
            ch += 1;
        }
    }
    tracks.extend(groups.into_iter().filter(|g| !g.is_empty()));
    tracks
}

/// What every codec's search starts from, computed once per encode.
struct Prepared {
    /// The motion in fixed point.
    fixed: FixedChannels,
    /// Joint positions of the input, mm (`[joint][xyz]` per frame).
    original_mm: Vec<[f64; 3]>,
    /// Lever arm of each joint, µm.
    levers_um: Vec<f64>,
    /// Joint of each channel.
    joint_of: Vec<usize>,
}

/// Encodes with `pca-spline`, searching the tolerance `τ` (log-bisection)
/// for the smallest clip whose decoded output meets the bound.
fn encode_pca(m: &Motion, input: &Prepared, opts: &EncodeOptions) -> Result<Encoded, String> {
    let Prepared {
        fixed,
        original_mm,
        levers_um,
        joint_of,
    } = input;
    let mm = opts.bound.positional();
    let weights = pca_weights(
        m,
        levers_um,
        joint_of,
        &fixed.kinds,
        mm,
        opts.bound.arms_mm.is_some(),
    );
    let groups = pca_groups(m, 9);
    let input = pca_spline::Input {
        values: &fixed.values,
        weights: &weights,
        groups: &groups,
    };
    let scale = match (
        opts.bound.position_mm.or(opts.bound.arms_mm),
        opts.bound.angle_deg,
    ) {
        (Some(p), _) => p,
        (None, Some(d)) => d,
        (None, None) => Bound::DEFAULT_TRANSLATION_MM,
    };
    let fps = 1.0 / m.frame_time;
    let run = |tau: f64| -> Result<Attempt, String> {
        let params = pca_spline::Params::new(tau, fps);
        let mut model = pca_spline::model(&input, &params)?;
        let try_model = |model: &pca_spline::Model| {
            let section = model.to_section(fixed.kinds.len());
            prove(
                m,
                fixed,
                (consts::SECTION_CODEC_PCA_SPLINE, section),
                None,
                opts,
                original_mm,
            )
        };
        let first = try_model(&model)?;
        // What the smooth model misses by more than τ (glitches, spikes)
        // becomes sparse patches.
        if model.add_patches(&input, &first.decoded, params.patch_share * tau) == 0 {
            return Ok(first);
        }
        try_model(&model)
    };
    let (mut best, lo, mut attempts) =
        bisect(&opts.bound, (scale / 256.0, scale * 2.0), 20, 1.02, run)?;
    // Size and error are not quite monotonic in τ: probe a little above
    // the boundary too and keep the smallest clip that holds.
    for i in 1..=6 {
        attempts += 1;
        let a = run(lo * (1.0 + 0.03 * i as f64))?;
        if opts.bound.holds(&a.metrics)
            && best.as_ref().is_none_or(|b| a.bytes.len() < b.bytes.len())
        {
            best = Some(a);
        }
    }
    let best = match best {
        Some(b) => b,
        None => {
            attempts += 1;
            let a = run(lo)?;
            if !opts.bound.holds(&a.metrics) {
                return Err(format!(
                    "pca-spline could not meet the bound {} (max joint error {:.2} mm, angle {:.3}° at the finest tolerance)",
                    opts.bound, a.metrics.max_joint_err_mm, a.metrics.angle_max_deg
                ));
            }
            a
        }
    };
    Ok(Encoded {
        bytes: best.bytes,
        metrics: best.metrics,
        codec: CodecChoice::PcaSpline,
        key_interval: 0,
        attempts,
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
    let input = Prepared {
        fixed: fixed::to_fixed(m, opts.metres_per_unit),
        original_mm: metrics::positions_mm(m, opts.metres_per_unit),
        levers_um: kinematics::lever_arms(&m.skeleton)
            .into_iter()
            .map(|l| l * opts.metres_per_unit * 1e6)
            .collect(),
        joint_of: m.skeleton.channel_joints(),
    };
    let with = |codec| {
        let one = EncodeOptions {
            codec,
            ..opts.clone()
        };
        match codec {
            CodecChoice::PcaSpline => encode_pca(m, &input, &one),
            _ => encode_by_tolerance(m, &input, &one),
        }
    };
    if opts.codec != CodecChoice::Auto {
        return with(opts.codec);
    }
    // Every codec; the smallest clip that meets the bound.
    let mut errors = Vec::new();
    let mut best: Option<Encoded> = None;
    for codec in [
        CodecChoice::Index,
        CodecChoice::PcaSpline,
        CodecChoice::Predictive,
    ] {
        match with(codec) {
            Ok(e) if best.as_ref().is_none_or(|b| e.bytes.len() < b.bytes.len()) => best = Some(e),
            Ok(_) => {}
            Err(e) => errors.push(format!("{}: {e}", crate::bench::codec_name(codec))),
        }
    }
    best.ok_or_else(|| errors.join("; "))
}

/// Encodes with a codec driven by per-channel tolerances (`index`,
/// `predictive`): tightens an angle bound, or bisects the position budget
/// of a millimetre bound, until the decoded clip meets the bound.
fn encode_by_tolerance(
    m: &Motion,
    input: &Prepared,
    opts: &EncodeOptions,
) -> Result<Encoded, String> {
    let Prepared {
        fixed,
        original_mm,
        levers_um,
        joint_of,
    } = input;
    let mut attempts = 0;
    let mut tighten = 1.0;
    let run = |s_um: Option<f64>, tighten: f64| {
        let tol = tolerances(fixed, opts, levers_um, joint_of, s_um, tighten);
        attempt(m, fixed, &tol, opts, original_mm)
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
            let (best, lo, n) = bisect(&opts.bound, (bound_um * 1e-3, bound_um), 14, 1.03, |s| {
                run(Some(s), 1.0)
            })?;
            attempts += n;
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
        codec: opts.codec,
        key_interval: best.key_interval,
        attempts,
    })
}
