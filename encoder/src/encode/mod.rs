//! The encode pipeline: tolerances from the error bound (`bound`), the
//! codec and its search (`search`), the container, then a decode with the
//! `no_std` decoder that proves the bound before anything is written
//! (`proof`), tightening and retrying if it does not hold.

mod bound;
mod proof;
mod reference;
mod rma;
mod search;
mod shared;

pub use crate::codec::CodecChoice;
pub use bound::{Bound, BoundError, BoundSpec};
pub use reference::Reference;
pub use search::{search_tolerances, Trial};
pub use shared::{encode_pattern_shared, SharedPatterns};

use crate::codec::CodecError;
use crate::metrics::Metrics;
use crate::motion::Motion;
use search::{encode_by_tolerance, encode_pca};

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
    /// [`crate::codec::predictive::DEFAULT_BLOCK_SECONDS`] (predictive).
    pub key_interval: Option<u16>,
    /// The `index` codec's section layout (SPEC.md §4.1 or §4.6).
    pub index_layout: crate::codec::index::IndexLayout,
    /// The `pattern` codec's settings: its body-part nodes (empty: the
    /// skeleton's limbs, [`crate::codec::pattern::nodes`]) and its layout.
    pub pattern: crate::codec::pattern::PatternOptions,
    /// Uniform key quantisation for `pca-spline` and `rma`, the paper's
    /// Table 4 baseline (Lin et al.: 9 bits for primary clips, 7 for
    /// repeated ones): `(own, residual)` bits, every spline component's keys
    /// in a segment at the finest power-of-two step that spans their range
    /// in that many bits (`own` for `pca-spline` and `rma`'s own stretches,
    /// `residual` for `rma`'s repeated clips). `None`, the default: the
    /// range-aware adaptive quantisation, each component's step from the
    /// tolerance and its width from its range.
    pub key_bits: Option<(u8, u8)>,
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

/// Why a clip could not be encoded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EncodeError {
    /// The motion is empty.
    #[error("the motion has no frames or no channels")]
    Empty,
    /// More channels than the format's 16-bit count.
    #[error("{0} channels exceed the format's 65535")]
    TooManyChannels(usize),
    /// The codec could not code the clip.
    #[error(transparent)]
    Codec(#[from] CodecError),
    /// An index-codec channel needs more than 12-bit codes for its tolerance.
    #[error("channel {channel} ({name}) cannot meet the error bound with 12-bit codes")]
    ToleranceTooTight {
        /// The channel.
        channel: usize,
        /// Its name (`Joint.Kind`).
        name: String,
    },
    /// The bound does not hold after every tightening round.
    #[error("could not meet the bound {bound} after {attempts} attempts")]
    BoundNotMetAfter {
        /// The bound.
        bound: Bound,
        /// Attempts made.
        attempts: usize,
    },
    /// The bisection found no holding position budget.
    #[error("could not meet the bound {bound}")]
    BoundNotMet {
        /// The bound.
        bound: Bound,
    },
    /// `pca-spline` or `rma` misses the bound at its finest tolerance.
    #[error("{} could not meet the bound {bound} (max joint error {max_joint_err_mm:.2} mm, angle {angle_max_deg:.3}° at the finest tolerance)", codec.name())]
    PcaBoundNotMet {
        /// The codec.
        codec: CodecChoice,
        /// The bound.
        bound: Bound,
        /// Max joint error measured, mm.
        max_joint_err_mm: f64,
        /// Max angle error measured, degrees.
        angle_max_deg: f64,
    },
    /// The decoder rejected the encoder's own clip (a bug).
    #[error("internal error: own clip rejected: {0}")]
    OwnClipRejected(mocap_decoder::Error),
    /// The decoder could not decode the encoder's own clip (a bug).
    #[error("internal error: {0}")]
    OwnClipUndecodable(mocap_decoder::Error),
    /// The decoder and the encoder's model of it differ (a bug).
    #[error("internal error: decoder and encoder disagree at frame {frame}, channel {channel}")]
    DecoderDisagrees {
        /// First differing frame.
        frame: usize,
        /// Its channel.
        channel: usize,
    },
    /// `auto`: every codec failed (each codec and its error).
    #[error("{}", joined(.0))]
    EveryCodecFailed(Vec<(CodecChoice, EncodeError)>),
}

/// `index: …; pca-spline: …` — each codec's error.
fn joined(errors: &[(CodecChoice, EncodeError)]) -> String {
    let each: Vec<String> = errors
        .iter()
        .map(|(c, e)| format!("{}: {e}", c.name()))
        .collect();
    each.join("; ")
}

/// What an encode reports while it runs, for a progress bar: the library
/// never prints (the `mocap` command line draws the bar). Methods are
/// called from the encoding threads.
pub trait Progress: Sync {
    /// The search of `codec` starts its round `round` (from 1) of about
    /// `rounds`; each round encodes, decodes and measures the whole clip.
    fn round(&self, codec: CodecChoice, round: usize, rounds: usize) {
        let _ = (codec, round, rounds);
    }

    /// Within the current round, `done` of `total` pieces of work are
    /// finished (`pca-spline`: segment fits; `predictive`: channels).
    fn work(&self, done: usize, total: usize) {
        let _ = (done, total);
    }
}

/// No progress reports.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}

/// Encodes `m`, proving the bound by decoding; errors say why it cannot.
pub fn encode(m: &Motion, opts: &EncodeOptions) -> Result<Encoded, EncodeError> {
    encode_with(m, opts, &Silent)
}

/// [`encode`], reporting its progress to `progress`.
pub fn encode_with(
    m: &Motion,
    opts: &EncodeOptions,
    progress: &dyn Progress,
) -> Result<Encoded, EncodeError> {
    if m.frames() == 0 || m.channels() == 0 {
        return Err(EncodeError::Empty);
    }
    if m.channels() > usize::from(u16::MAX) {
        return Err(EncodeError::TooManyChannels(m.channels()));
    }
    let input = Reference::new(m, opts.metres_per_unit);
    let with = |codec| {
        let one = EncodeOptions {
            codec,
            ..opts.clone()
        };
        match codec {
            CodecChoice::PcaSpline => encode_pca(m, &input, &one, progress),
            CodecChoice::Rma => rma::encode_rma(m, &input, &one, progress),
            _ => encode_by_tolerance(m, &input, &one, progress),
        }
    };
    if opts.codec != CodecChoice::Auto {
        return with(opts.codec);
    }
    smallest(AUTO_CODECS.iter().map(|&codec| (codec, with(codec))))
}

/// The codecs `auto` encodes with, in this order.
pub const AUTO_CODECS: [CodecChoice; 5] = [
    CodecChoice::Index,
    CodecChoice::PcaSpline,
    CodecChoice::Predictive,
    CodecChoice::Pattern,
    CodecChoice::Rma,
];

/// `auto`'s choice among the codecs' results (in [`AUTO_CODECS`] order): the
/// smallest clip that meets the bound, the first of equal sizes; every
/// codec's error when none does.
pub fn smallest(
    results: impl IntoIterator<Item = (CodecChoice, Result<Encoded, EncodeError>)>,
) -> Result<Encoded, EncodeError> {
    let mut errors = Vec::new();
    let mut best: Option<Encoded> = None;
    for (codec, result) in results {
        match result {
            Ok(e) if best.as_ref().is_none_or(|b| e.bytes.len() < b.bytes.len()) => best = Some(e),
            Ok(_) => {}
            Err(e) => errors.push((codec, e)),
        }
    }
    best.ok_or(EncodeError::EveryCodecFailed(errors))
}
