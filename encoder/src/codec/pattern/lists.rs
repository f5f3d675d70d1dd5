//! A clip's segment lists (SPEC.md §11.1): plain (`u32` start, `u16`
//! pattern per segment) or entropy coded (§11.1b: each segment's length and
//! its pattern's change from "the one after the last", rANS-coded with the
//! project's one coder, §10, in blocks that a player can seek to). The
//! encoder writes the smaller.

use crate::entropy::{encode_steps, EntropyError, Model, Step};
use mocap_decoder::pattern::FLAG_CODED;

/// Segments per block of a coded list: `2^6`. A seek decodes at most one
/// block; a block costs its 10-byte index entry and 4-byte state.
pub const BLOCK_BITS: u8 = 6;

/// One node's segments in one take.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NodeList {
    /// Each segment's first frame (the first is 0, increasing).
    pub starts: Vec<u32>,
    /// Each segment's pattern.
    pub patterns: Vec<u16>,
}

/// The section's flag bit for the form written ([`FLAG_CODED`] or 0) and
/// the lists' bytes (after the database, or after the flags of a section
/// that reads a shared one): the smaller of the two forms, coded in blocks
/// of `2^bits` segments.
pub fn write(lists: &[NodeList], frames: u32, bits: u8) -> (u8, Vec<u8>) {
    let plain = plain(lists);
    match coded(
        lists,
        frames,
        bits.min(mocap_decoder::pattern::MAX_BLOCK_BITS),
    ) {
        Ok(c) if c.len() < plain.len() => (FLAG_CODED, c),
        _ => (0, plain),
    }
}

/// The plain form (§11.1): per node `u16` count, then `u32` start and
/// `u16` pattern per segment.
pub fn plain(lists: &[NodeList]) -> Vec<u8> {
    let mut out = Vec::new();
    for l in lists {
        out.extend((l.starts.len() as u16).to_le_bytes());
        for (&s, &p) in l.starts.iter().zip(&l.patterns) {
            out.extend(s.to_le_bytes());
            out.extend(p.to_le_bytes());
        }
    }
    out
}

/// `zigzag(p − (q + 1))`: the pattern `p` after pattern `q` (§11.1b).
fn pattern_value(p: u16, q: u16) -> u32 {
    let d = i64::from(p) - i64::from(q) - 1;
    ((d << 1) ^ (d >> 63)) as u32
}

/// Segment `i`'s length − 1 (the last one ends at `frames`).
fn length_value(l: &NodeList, i: usize, frames: u32) -> u32 {
    let end = l.starts.get(i + 1).copied().unwrap_or(frames);
    end - l.starts[i] - 1
}

/// Each segment's length − 1, and the pattern values of the segments that
/// are not a block's first, over all nodes.
fn values(lists: &[NodeList], frames: u32, bits: u8) -> (Vec<u32>, Vec<u32>) {
    let (mut lengths, mut patterns) = (Vec::new(), Vec::new());
    for l in lists {
        for i in 0..l.starts.len() {
            lengths.push(length_value(l, i, frames));
            if i % (1usize << bits) != 0 {
                patterns.push(pattern_value(l.patterns[i], l.patterns[i - 1]));
            }
        }
    }
    (lengths, patterns)
}

/// The lengths' and the pattern values' tables.
fn models(lengths: &[u32], patterns: &[u32]) -> Result<(Model, Model), EntropyError> {
    let (len_model, _) = Model::fit_values_best(lengths)?;
    // No pattern values (every block one segment): any table does.
    let (pat_model, _) = Model::fit_values_best(if patterns.is_empty() { &[0] } else { patterns })?;
    Ok((len_model, pat_model))
}

/// The coded form (§11.1b) with blocks of `2^bits` segments: the lengths'
/// and the patterns' tables, then per node its count, `bits`, the block
/// index and the blocks' streams.
pub fn coded(lists: &[NodeList], frames: u32, bits: u8) -> Result<Vec<u8>, EntropyError> {
    let (lengths, patterns) = values(lists, frames, bits);
    coded_with(lists, frames, bits, &models(&lengths, &patterns)?)
}

/// [`coded`] with its two tables.
fn coded_with(
    lists: &[NodeList],
    frames: u32,
    bits: u8,
    (len_model, pat_model): &(Model, Model),
) -> Result<Vec<u8>, EntropyError> {
    let mut out = len_model.table_bytes();
    out.extend(pat_model.table_bytes());
    let block = 1usize << bits;
    for l in lists {
        out.extend((l.starts.len() as u16).to_le_bytes());
        out.push(bits);
        let mut index = Vec::new();
        let mut streams = Vec::new();
        for (k, chunk) in l.starts.chunks(block).enumerate() {
            let first = k * block;
            let mut steps: Vec<Step> = Vec::new();
            for i in first..first + chunk.len() {
                if i > first {
                    let v = pattern_value(l.patterns[i], l.patterns[i - 1]);
                    pat_model.push_value_steps(&mut steps, v)?;
                }
                len_model.push_value_steps(&mut steps, length_value(l, i, frames))?;
            }
            streams.extend(encode_steps(&steps));
            index.extend(chunk[0].to_le_bytes());
            index.extend(l.patterns[first].to_le_bytes());
            index.extend((streams.len() as u32).to_le_bytes());
        }
        out.extend(index);
        out.extend(streams);
    }
    Ok(out)
}

/// What a coded list costs, beside the Shannon entropy of its values.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Segments over all nodes.
    pub segments: usize,
    /// Bytes of the plain form.
    pub plain: usize,
    /// Bytes of the coded form, in all.
    pub coded: usize,
    /// Of which the two tables.
    pub tables: usize,
    /// Of which the nodes' counts, block sizes and block indexes.
    pub index: usize,
    /// Of which the streams (states and renormalisation bytes).
    pub streams: usize,
    /// The lengths' and the pattern values' Shannon entropy (each value
    /// its own symbol, the empirical distribution), bytes.
    pub shannon_lengths: f64,
    /// See `shannon_lengths`.
    pub shannon_patterns: f64,
}

/// The coded form of `lists` in blocks of `2^bits` segments taken apart
/// ([`Report`]).
pub fn report(lists: &[NodeList], frames: u32, bits: u8) -> Result<Report, EntropyError> {
    let (lengths, patterns) = values(lists, frames, bits);
    let shannon =
        |v: &[u32]| crate::entropy::shannon_bits(&crate::entropy::histogram(v)) / 8.0 + 0.0;
    let m = models(&lengths, &patterns)?;
    let coded = coded_with(lists, frames, bits, &m)?;
    let tables = m.0.table_bytes().len() + m.1.table_bytes().len();
    let segments: usize = lists.iter().map(|l| l.starts.len()).sum();
    let blocks: usize = lists
        .iter()
        .map(|l| l.starts.len().div_ceil(1 << bits))
        .sum();
    let index = lists.len() * 3 + blocks * 10;
    Ok(Report {
        segments,
        plain: plain(lists).len(),
        tables,
        index,
        streams: coded.len() - tables - index,
        coded: coded.len(),
        shannon_lengths: shannon(&lengths),
        shannon_patterns: shannon(&patterns),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lists() -> Vec<NodeList> {
        vec![
            NodeList {
                starts: (0..150).map(|i| i * 7).collect(),
                patterns: (0..150).map(|i| (i % 9) as u16).collect(),
            },
            NodeList {
                starts: vec![0, 400, 401],
                patterns: vec![2, 0, 1],
            },
        ]
    }

    /// The coded form is the smaller here, and the decoder reads every
    /// node's segments back from it at every block size.
    #[test]
    fn coded_lists_are_smaller_and_read_back_by_the_decoder() {
        let l = lists();
        let frames = 1050;
        let p = plain(&l);
        let c = coded(&l, frames, BLOCK_BITS).unwrap();
        assert!(c.len() < p.len(), "{} vs {}", c.len(), p.len());
        assert_eq!(write(&l, frames, BLOCK_BITS).0, FLAG_CODED);
        for bits in [0u8, 1, 6, 15] {
            let c = coded(&l, frames, bits).unwrap();
            let (lt, a) = mocap_decoder::entropy::Table::parse(&c).unwrap();
            let (pt, b) = mocap_decoder::entropy::Table::parse(&c[a..]).unwrap();
            let rest = &c[a + b..];
            let mut at = 0;
            for want in &l {
                let mut got = NodeList::default();
                let mut last = 0;
                mocap_decoder::pattern::for_each_coded_segment(rest, at, lt, pt, |s, e, p| {
                    got.starts.push(s);
                    got.patterns.push(p as u16);
                    last = e;
                })
                .unwrap();
                assert_eq!((&got, last), (want, frames), "bits {bits}");
                let (n, len) = mocap_decoder::pattern::coded_extent(rest, at).unwrap();
                assert_eq!(n, want.starts.len());
                at += len;
            }
            assert_eq!(at, rest.len(), "bits {bits}");
        }
    }

    #[test]
    fn pattern_values_zigzag_the_change_from_the_next() {
        assert_eq!(pattern_value(5, 4), 0);
        assert_eq!(pattern_value(4, 4), 1);
        assert_eq!(pattern_value(6, 4), 2);
        assert_eq!(pattern_value(0, 65535), 2 * 65536 - 1);
    }
}
