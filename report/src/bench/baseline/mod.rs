//! What a user would pick instead of our codecs: the size references of
//! `mocap bench` (issue 15). They are not MCU bitstreams and not codecs of
//! the format (those live in the encoder's `codec/`); each is a concrete
//! serialisation with its own decoder here, so the bench counts real bytes
//! and measures the motion decoded *from those bytes*:
//!
//! - [`Baseline::Raw16`] ([`raw16`]): what servo exporters store — every
//!   channel of every frame as a 16-bit integer at a fixed-point step that
//!   fits the channel's range. Not tuned to the bound: its error is what it
//!   is, and the bench reports whether the bound holds.
//! - [`Baseline::QuantZstd`], [`Baseline::QuantXz`] ([`quant`]): every
//!   channel quantised uniformly at a step from the bound, frame-to-frame
//!   differences as varints, the whole stream compressed by zstd (level 19)
//!   or xz (preset 9, extreme).
//! - [`Baseline::KeyframeLinear`] ([`keyframe`]): what game engines default
//!   to — per channel, the keys a greedy reduction keeps so that linear
//!   interpolation between them stays within the channel's tolerance; keys
//!   as (frame gap, quantised value) varints.
//!
//! The tuned ones take their per-channel tolerances from the encode
//! pipeline's own search ([`search_tolerances`]: tightened under an angle
//! bound, the position budget bisected under a millimetre bound) and every
//! try is measured by [`Reference::measure`] and checked by
//! [`Bound::holds`] — the measurement and the bound of our codecs' proof.
//!
//! Every serialisation starts with `varint frames, varint channels`
//! (postcard varints, SPEC.md §3.1); the per-channel parameters each needs
//! follow and are counted in its bytes. Values are the encoder's fixed-point
//! channels (SPEC.md §3.3: millidegrees, unwrapped; micrometres).

pub mod keyframe;
pub mod quant;
pub mod raw16;

use mocap_encoder::container::ByteCursor;
use mocap_encoder::encode::{search_tolerances, Bound, EncodeError, Reference, Trial};
use mocap_encoder::metrics::Metrics;
use mocap_encoder::motion::Motion;

/// A size reference of the bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Baseline {
    /// Every value as 16 bits at a step fitting the channel's range.
    Raw16,
    /// Uniform quantisation at the bound + zstd.
    QuantZstd,
    /// Uniform quantisation at the bound + xz.
    QuantXz,
    /// Greedy key reduction with linear interpolation, keys quantised.
    KeyframeLinear,
}

impl Baseline {
    /// Every baseline, in the bench's order.
    pub const ALL: [Baseline; 4] = [
        Baseline::Raw16,
        Baseline::QuantZstd,
        Baseline::QuantXz,
        Baseline::KeyframeLinear,
    ];

    /// The name in tables and JSON rows.
    pub fn name(self) -> &'static str {
        match self {
            Baseline::Raw16 => "raw16",
            Baseline::QuantZstd => "quant+zstd",
            Baseline::QuantXz => "quant+xz",
            Baseline::KeyframeLinear => "keyframe-linear",
        }
    }

    /// Whether it is tuned to the bound (all but `raw16`).
    pub fn tuned(self) -> bool {
        self != Baseline::Raw16
    }

    /// Serialises `values` (`[channel][frame]`, all channels the same
    /// length) at the per-channel tolerances `tol` (fixed-point units;
    /// `raw16` ignores them).
    pub fn encode(self, values: &[Vec<i32>], tol: &[i64]) -> Result<Vec<u8>, BaselineError> {
        match self {
            Baseline::Raw16 => Ok(raw16::encode(values)),
            Baseline::QuantZstd => quant::encode(values, tol, quant::Compressor::Zstd),
            Baseline::QuantXz => quant::encode(values, tol, quant::Compressor::Xz),
            Baseline::KeyframeLinear => Ok(keyframe::encode(values, tol)),
        }
    }

    /// Decodes what [`Baseline::encode`] wrote.
    pub fn decode(self, bytes: &[u8]) -> Result<Decoded, BaselineError> {
        match self {
            Baseline::Raw16 => raw16::decode(bytes),
            Baseline::QuantZstd => quant::decode(bytes, quant::Compressor::Zstd),
            Baseline::QuantXz => quant::decode(bytes, quant::Compressor::Xz),
            Baseline::KeyframeLinear => keyframe::decode(bytes),
        }
    }
}

/// A decoded baseline: fixed-point values, frame-major as the decoder gives
/// a clip's frames.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decoded {
    /// Frames.
    pub frames: usize,
    /// Channels per frame.
    pub channels: usize,
    /// `values[frame * channels + channel]`.
    pub values: Vec<i32>,
}

impl Decoded {
    /// Channel `c` over all frames.
    pub fn channel(&self, c: usize) -> Vec<i32> {
        self.values
            .iter()
            .skip(c)
            .step_by(self.channels.max(1))
            .copied()
            .collect()
    }
}

/// Why a baseline could not be coded or decoded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BaselineError {
    /// The bytes do not decode (a bug when they are the bench's own).
    #[error("{baseline}: malformed at byte {at}: {what}")]
    Malformed {
        /// The format.
        baseline: &'static str,
        /// Byte offset (in the decompressed stream for `quant+…`).
        at: usize,
        /// What was expected.
        what: &'static str,
    },
    /// A value does not fit the format.
    #[error("{baseline}: {what}")]
    OutOfRange {
        /// The format.
        baseline: &'static str,
        /// What.
        what: String,
    },
    /// zstd or xz failed.
    #[error("{compressor}: {source}")]
    Compressor {
        /// `zstd` or `xz`.
        compressor: &'static str,
        /// Its error.
        source: std::io::Error,
    },
    /// The decoded shape is not the motion's (a bug).
    #[error("internal error: {baseline} decoded {frames} frames × {channels} channels, not the motion's {want_frames} × {want_channels}")]
    Shape {
        /// The format.
        baseline: &'static str,
        /// Decoded frames.
        frames: usize,
        /// Decoded channels.
        channels: usize,
        /// The motion's frames.
        want_frames: usize,
        /// The motion's channels.
        want_channels: usize,
    },
    /// The search found no tolerances at which the bound holds.
    #[error(transparent)]
    Bound(#[from] EncodeError),
}

/// One coded baseline: its bytes, its metrics (measured on the motion
/// decoded from the bytes) and the tries its search made.
#[derive(Clone, Debug)]
pub struct Coded {
    /// The serialisation (compressed for `quant+…`), without the skeleton
    /// header.
    pub bytes: Vec<u8>,
    /// Metrics; `metrics.bytes` = `bytes.len()` + the header size given to
    /// [`code`], and the ratios with it.
    pub metrics: Metrics,
    /// Tries of the search (1 for `raw16`).
    pub tries: usize,
}

impl Trial for Coded {
    fn size(&self) -> usize {
        self.bytes.len()
    }

    fn metrics(&self) -> &Metrics {
        &self.metrics
    }
}

/// Codes `m` with `baseline` at `bound` (ignored by `raw16`), measured
/// against `reference` (made from `m`). `header_bytes` is added to the
/// bytes the metrics' ratios see (the skeleton header a clip would carry).
pub fn code(
    baseline: Baseline,
    m: &Motion,
    reference: &Reference,
    bound: &Bound,
    header_bytes: usize,
) -> Result<Coded, BaselineError> {
    let one = |tol: &[i64]| -> Result<Coded, BaselineError> {
        let bytes = baseline.encode(&reference.fixed().values, tol)?;
        let d = baseline.decode(&bytes)?;
        if (d.frames, d.channels) != (m.frames(), m.channels()) {
            return Err(BaselineError::Shape {
                baseline: baseline.name(),
                frames: d.frames,
                channels: d.channels,
                want_frames: m.frames(),
                want_channels: m.channels(),
            });
        }
        let metrics = reference.measure(m, &d.values, bytes.len() + header_bytes);
        Ok(Coded {
            bytes,
            metrics,
            tries: 1,
        })
    };
    if !baseline.tuned() {
        return one(&[]);
    }
    let (mut best, tries) = search_tolerances(reference, bound, one)?;
    best.tries = tries;
    Ok(best)
}

/// `num / den` rounded to the nearest integer, halves towards +∞
/// (`den > 0`): the one rounding of every baseline's coder and decoder.
pub(crate) fn round_div(num: i64, den: i64) -> i64 {
    (2 * num + den).div_euclid(2 * den)
}

/// A fixed-point value back in `i32` (saturating: a decoder never wraps).
pub(crate) fn saturate(v: i64) -> i32 {
    v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

/// The common start of every serialisation: frames and channels.
pub(crate) fn write_shape(out: &mut Vec<u8>, values: &[Vec<i32>]) {
    use mocap_encoder::container::varint;
    let frames = values.first().map_or(0, Vec::len);
    varint(out, u32::try_from(frames).unwrap_or(u32::MAX));
    varint(out, u32::try_from(values.len()).unwrap_or(u32::MAX));
}

/// Reading a serialisation, with the offset in errors.
pub(crate) struct Reader<'a> {
    cursor: ByteCursor<'a>,
    bytes: &'a [u8],
    baseline: &'static str,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(bytes: &'a [u8], baseline: &'static str) -> Self {
        Reader {
            cursor: ByteCursor::new(bytes),
            bytes,
            baseline,
        }
    }

    pub(crate) fn malformed(&self, what: &'static str) -> BaselineError {
        BaselineError::Malformed {
            baseline: self.baseline,
            at: self.cursor.pos(),
            what,
        }
    }

    pub(crate) fn varint(&mut self, what: &'static str) -> Result<u32, BaselineError> {
        self.cursor.varint().ok_or_else(|| self.malformed(what))
    }

    pub(crate) fn zigzag(&mut self, what: &'static str) -> Result<i32, BaselineError> {
        self.varint(what).map(mocap_decoder::wire::zigzag_decode)
    }

    pub(crate) fn u16_le(&mut self, what: &'static str) -> Result<u16, BaselineError> {
        let at = self.cursor.pos();
        let b = self
            .bytes
            .get(at..at + 2)
            .ok_or_else(|| self.malformed(what))?;
        let v = u16::from_le_bytes([b[0], b[1]]);
        self.cursor.skip(2).ok_or_else(|| self.malformed(what))?;
        Ok(v)
    }

    /// `varint frames, varint channels`, refusing a count that the bytes
    /// left cannot hold `min_bytes_per_value` per value of.
    pub(crate) fn shape(
        &mut self,
        min_bytes_per_value: usize,
    ) -> Result<(usize, usize), BaselineError> {
        let frames = self.varint("frame count")? as usize;
        let channels = self.varint("channel count")? as usize;
        let left = self.bytes.len() - self.cursor.pos();
        if frames
            .checked_mul(channels)
            .and_then(|n| n.checked_mul(min_bytes_per_value))
            .is_none_or(|n| n > left)
        {
            return Err(self.malformed("more values than bytes"));
        }
        Ok((frames, channels))
    }

    /// Whether every byte was read.
    pub(crate) fn finish(&self) -> Result<(), BaselineError> {
        if self.cursor.pos() == self.bytes.len() {
            Ok(())
        } else {
            Err(self.malformed("bytes after the end"))
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use mocap_encoder::encode::BoundSpec;
    use mocap_encoder::motion::{ChannelKind, Joint, Skeleton};

    /// A small synthetic motion: a root with position and rotation channels
    /// and a chain of three rotating joints with an End Site, 90 frames of
    /// smooth motion with one constant channel and one jump.
    pub(crate) fn synthetic() -> Motion {
        let rot = vec![
            ChannelKind::Zrotation,
            ChannelKind::Yrotation,
            ChannelKind::Xrotation,
        ];
        let mut joints = vec![Joint {
            name: "Hips".into(),
            parent: None,
            offset: [0.0; 3],
            channels: [
                vec![
                    ChannelKind::Xposition,
                    ChannelKind::Yposition,
                    ChannelKind::Zposition,
                ],
                rot.clone(),
            ]
            .concat(),
            end_site: false,
        }];
        for (i, name) in ["Spine", "Arm", "Hand"].iter().enumerate() {
            joints.push(Joint {
                name: (*name).into(),
                parent: Some(i),
                offset: [0.0, 30.0, 0.0],
                channels: rot.clone(),
                end_site: false,
            });
        }
        joints.push(Joint {
            name: "Hand_End".into(),
            parent: Some(3),
            offset: [0.0, 10.0, 0.0],
            channels: vec![],
            end_site: true,
        });
        let skeleton = Skeleton { joints };
        let n = skeleton.channel_count();
        let mut values = Vec::new();
        for f in 0..90 {
            let t = f as f64 / 30.0;
            for c in 0..n {
                let v = match c {
                    0 => 100.0 * t,
                    1 => 90.0 + 3.0 * (2.0 * t).sin(),
                    2 => -5.0,
                    5 => 170.0 + 20.0 * t, // crosses ±180°
                    7 if f >= 45 => 25.0,  // a jump
                    _ => 30.0 * (t * (1.0 + c as f64 * 0.3)).sin(),
                };
                values.push(if c == 5 {
                    mocap_encoder::fixed::wrap_degrees(v)
                } else {
                    v
                });
            }
        }
        Motion {
            skeleton,
            frame_time: 1.0 / 30.0,
            values,
        }
    }

    pub(crate) fn bound(specs: &[&str]) -> Bound {
        let specs: Vec<BoundSpec> = specs.iter().map(|s| s.parse().unwrap()).collect();
        Bound::from_specs(&specs)
    }

    /// Every tuned baseline meets every bound on the synthetic motion, its
    /// metrics measured on the motion decoded from its bytes; `raw16`
    /// reports its own error; the bytes are the serialisation's.
    #[test]
    fn every_baseline_round_trips_within_the_bound() {
        let m = synthetic();
        let mpu = 0.01; // centimetres
        let reference = Reference::new(&m, mpu);
        for spec in [
            &["1deg"][..],
            &["0.25deg"],
            &["20mm"],
            &["50mm", "arms:10mm"],
        ] {
            let b = bound(spec);
            for baseline in Baseline::ALL {
                let c = code(baseline, &m, &reference, &b, 100).unwrap();
                assert_eq!(c.metrics.bytes, c.bytes.len() + 100, "{baseline:?}");
                let d = baseline.decode(&c.bytes).unwrap();
                let again = reference.measure(&m, &d.values, c.metrics.bytes);
                assert_eq!(again, c.metrics, "{baseline:?} {spec:?}");
                if baseline.tuned() {
                    assert!(
                        b.holds(&c.metrics),
                        "{baseline:?} {spec:?}: {:?}",
                        c.metrics
                    );
                    assert!(c.tries >= 1);
                }
            }
        }
    }

    /// A looser bound never costs a tuned baseline more bytes here (a
    /// search that ignored the bound would fail this).
    #[test]
    fn looser_bounds_give_fewer_bytes() {
        let m = synthetic();
        let reference = Reference::new(&m, 0.01);
        for baseline in [
            Baseline::QuantZstd,
            Baseline::QuantXz,
            Baseline::KeyframeLinear,
        ] {
            let tight = code(baseline, &m, &reference, &bound(&["0.1deg"]), 0).unwrap();
            let loose = code(baseline, &m, &reference, &bound(&["5deg"]), 0).unwrap();
            assert!(
                loose.bytes.len() < tight.bytes.len(),
                "{baseline:?}: {} !< {}",
                loose.bytes.len(),
                tight.bytes.len()
            );
        }
    }

    #[test]
    fn round_div_rounds_halves_up() {
        assert_eq!(round_div(5, 2), 3);
        assert_eq!(round_div(-5, 2), -2);
        assert_eq!(round_div(4, 3), 1);
        assert_eq!(round_div(-4, 3), -1);
        assert_eq!(round_div(0, 7), 0);
    }
}
