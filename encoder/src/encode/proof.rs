//! The proof: a codec section in a clip, decoded by the `no_std` decoder
//! the MCU runs, measured against the input before anything is written.

use mocap_decoder::{consts, Clip};

use super::reference::Reference;
use super::search::Trial;
use super::{EncodeError, EncodeOptions};
use crate::clipfile;
use crate::container::{assemble, HeaderWire};
use crate::fixed::FixedChannels;
use crate::metrics::Metrics;
use crate::motion::Motion;

/// The result of one attempt at fixed tolerances.
pub(super) struct Attempt {
    pub bytes: Vec<u8>,
    pub metrics: Metrics,
    pub key_interval: u16,
    /// Decoded values, `[channel][frame]`.
    pub decoded: Vec<Vec<i32>>,
}

/// Assembles a clip around a codec section, decodes it with the `no_std`
/// decoder, writes the decoded ranges into the header and measures it.
/// `expected` (the encoder's own idea of the decoded values) is checked
/// bit for bit when given.
pub(super) fn prove(
    m: &Motion,
    input: &Reference,
    section: (u8, Vec<u8>),
    expected: Option<&FixedChannels>,
    opts: &EncodeOptions,
) -> Result<Attempt, EncodeError> {
    let fixed = &input.fixed;
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
    let clip = Clip::parse(&draft).map_err(EncodeError::OwnClipRejected)?;
    let frames = clipfile::decode_all(&clip).map_err(EncodeError::OwnClipUndecodable)?;
    let n = fixed.kinds.len();
    let decoded = FixedChannels {
        kinds: fixed.kinds.clone(),
        values: (0..n)
            .map(|c| frames.iter().skip(c).step_by(n).copied().collect())
            .collect(),
    };
    if let Some(e) = expected {
        if let Some((c, f)) = first_difference(&e.values, &decoded.values) {
            return Err(EncodeError::DecoderDisagrees {
                frame: f,
                channel: c,
            });
        }
    }
    let bytes = if expected.is_some() {
        draft
    } else {
        build(&decoded)
    };
    let metrics = input.measure(m, &frames, bytes.len());
    Ok(Attempt {
        bytes,
        metrics,
        key_interval: 0,
        decoded: decoded.values,
    })
}

impl Trial for Attempt {
    fn size(&self) -> usize {
        self.bytes.len()
    }

    fn metrics(&self) -> &Metrics {
        &self.metrics
    }
}

fn first_difference(a: &[Vec<i32>], b: &[Vec<i32>]) -> Option<(usize, usize)> {
    a.iter()
        .zip(b)
        .enumerate()
        .find_map(|(c, (x, y))| x.iter().zip(y).position(|(p, q)| p != q).map(|f| (c, f)))
}
