//! The codecs of the encoder, one module each, plus the shared pieces: the
//! codec choice, the codecs' errors and the text `mocap info` prints for
//! each codec's section (beside that codec's section inspector).

pub mod bits;
pub mod index;
pub mod pattern;
pub mod pca_spline;
pub mod predictive;
pub mod quantizer;
pub mod rma;

use std::str::FromStr;

use mocap_decoder::{consts, Header};

/// Which codec to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CodecChoice {
    /// Low-resolution model-based indexing (SPEC.md §4).
    Index,
    /// Segment PCA + key-frame splines (SPEC.md §5).
    PcaSpline,
    /// Prediction from the last two values, residuals range-coded (SPEC.md §5b).
    Predictive,
    /// Motion pattern indexing: body-part nodes, segments as references to
    /// time-normalised patterns (SPEC.md §11).
    Pattern,
    /// Repeated motion: primary clips as splines, repeated clips as a
    /// reference map into their primary plus residuals (SPEC.md §12).
    Rma,
    /// Every codec; keep the smallest clip that meets the bound.
    Auto,
}

impl CodecChoice {
    /// Every choice, in command-line order.
    pub const ALL: [CodecChoice; 6] = [
        CodecChoice::Index,
        CodecChoice::PcaSpline,
        CodecChoice::Predictive,
        CodecChoice::Pattern,
        CodecChoice::Rma,
        CodecChoice::Auto,
    ];

    /// The command-line name (`index`, `pca-spline`, `predictive`, `pattern`, `rma`, `auto`).
    pub fn name(self) -> &'static str {
        match self {
            CodecChoice::Index => "index",
            CodecChoice::PcaSpline => "pca-spline",
            CodecChoice::Predictive => "predictive",
            CodecChoice::Pattern => "pattern",
            CodecChoice::Rma => "rma",
            CodecChoice::Auto => "auto",
        }
    }
}

/// A name that is not a codec.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown codec '{0}' (index, pca-spline, predictive, pattern, rma, auto)")]
pub struct UnknownCodec(pub String);

impl FromStr for CodecChoice {
    type Err = UnknownCodec;

    fn from_str(s: &str) -> Result<Self, UnknownCodec> {
        CodecChoice::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| UnknownCodec(s.to_string()))
    }
}

/// Why a codec could not code a clip.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CodecError {
    /// The input has no frames.
    #[error("no frames")]
    NoFrames,
    /// The predictive codec got channels of different lengths or tolerances.
    #[error("internal error: predictive input shape")]
    PredictiveShape,
    /// The predictive codec found no step for a frame.
    #[error("internal error: no predictive step")]
    NoPredictiveStep,
    /// The index codec's table pool is too large for its 16-bit offsets.
    #[error(
        "index codec: {entries} table entries exceed the format's 65535 (loosen the error bound)"
    )]
    IndexTableTooLarge {
        /// Entries needed.
        entries: usize,
    },
    /// A pca-spline key coefficient does not fit the format.
    #[error("component coefficient {value} out of range for channels {channels:?}")]
    CoefficientOutOfRange {
        /// The coefficient.
        value: f64,
        /// The group's channels.
        channels: Vec<usize>,
    },
    /// A pca-spline key value range needs more bits than the format has.
    #[error("key value range too wide")]
    KeyRangeTooWide,
    /// The pattern codec needs 1..=255 body-part nodes.
    #[error("pattern codec: {0} body-part nodes (the format has 1..=255)")]
    PatternNodes(usize),
    /// A node of the pattern codec has more segments or patterns than the format's 65535.
    #[error("pattern codec: a node has {segments} segments and {patterns} patterns (the format has at most 65535 of each)")]
    PatternTooMany {
        /// Segments of the node.
        segments: usize,
        /// Patterns of the node.
        patterns: usize,
    },
    /// A body-part node names a joint the skeleton does not have.
    #[error("pattern codec: node {node} names joint '{joint}', which the skeleton does not have (its joints: {known})")]
    PatternNodeJoint {
        /// The node (0-based, in the order given).
        node: usize,
        /// The name given.
        joint: String,
        /// The skeleton's joints with channels.
        known: String,
    },
    /// A joint is in two body-part nodes.
    #[error("pattern codec: joint '{joint}' is in nodes {first} and {second}")]
    PatternNodeTwice {
        /// The joint.
        joint: String,
        /// The nodes (0-based).
        first: usize,
        /// The second node.
        second: usize,
    },
}

/// The lines `mocap info` prints under a codec section (`None` for other
/// sections or a section its codec cannot read).
pub fn describe_section(
    id: u8,
    section: &[u8],
    header: &Header<'_>,
    channels: bool,
) -> Option<String> {
    match id {
        consts::SECTION_CODEC_INDEX => Some(index::inspect(section)?.describe(header, channels)),
        consts::SECTION_CODEC_INDEX_FAST => Some(format!(
            "  layout: fast (SPEC §4.6; bits are field widths)\n{}",
            index::inspect_fast(section)?.describe(header, channels)
        )),
        consts::SECTION_CODEC_PCA_SPLINE => Some(pca_spline::inspect(section)?.describe()),
        consts::SECTION_CODEC_PREDICTIVE => Some(predictive::inspect(section)?.describe()),
        consts::SECTION_CODEC_PATTERN => Some(pattern::inspect(section)?.describe()),
        consts::SECTION_CODEC_RMA => Some(rma::section::inspect(section)?.describe()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codec_names_parse_back() {
        for c in CodecChoice::ALL {
            assert_eq!(c.name().parse::<CodecChoice>(), Ok(c));
        }
        assert_eq!(
            "pca".parse::<CodecChoice>().unwrap_err().to_string(),
            "unknown codec 'pca' (index, pca-spline, predictive, pattern, rma, auto)"
        );
    }
}
