//! The `pattern` codec (SPEC.md §11): motion pattern indexing after Gu,
//! Peng & Deng (2008). The channels are split into body-part *nodes*; each
//! node's take is cut into segments, and each segment is a reference to a
//! *pattern* of the node (a short, time-normalised piece of motion: a few
//! samples per channel and the curve through them) played stretched to the
//! segment's length. The patterns form a *database*: in
//! the codec section, or in a show's shared model section (§9.2) that
//! every clip of the show reads.
//!
//! Every frame is decoded directly (no history): per node, a binary search
//! over its segments' start frames, the frame's position in the pattern
//! (two integer divisions) and the four weights of a uniform Catmull-Rom
//! curve there, then per channel four codes, weighed and scaled. No state
//! beyond the output.

use crate::error::Error;
use crate::reader::Reader;

/// Bytes of a segment: start frame (u32), pattern (u16).
const SEGMENT: usize = 6;
/// Flag bit 0 of the codec section: the database is a shared model section.
pub const FLAG_SHARED: u8 = 1;
/// Most nodes a database may have.
pub const MAX_NODES: usize = 255;
/// Longest segment, frames (so the position arithmetic stays in 32 bits).
pub const MAX_SEGMENT: u32 = 65_535;

/// A validated view of a `pattern` codec section and its database.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PatternCodec<'a> {
    /// The database's node records, back to back (§11.2).
    nodes: &'a [u8],
    /// The segment lists, one per node (§11.1).
    segments: &'a [u8],
    node_count: usize,
    frames: u32,
}

/// One node of the database.
#[derive(Clone, Copy)]
struct Node<'a> {
    channels: &'a [u8],
    offsets: &'a [u8],
    data: &'a [u8],
    pattern_count: usize,
}

impl Node<'_> {
    /// Its channel count.
    fn channel_count(&self) -> usize {
        self.channels.len() / 2
    }
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    match b.get(at..at.checked_add(2)?)? {
        [x, y] => Some(u16::from_le_bytes([*x, *y])),
        _ => None,
    }
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    match b.get(at..at.checked_add(4)?)? {
        [x, y, z, w] => Some(u32::from_le_bytes([*x, *y, *z, *w])),
        _ => None,
    }
}

/// Reads the database node record at the start of `r` (§11.2).
fn read_node<'a>(r: &mut Reader<'a>) -> Option<Node<'a>> {
    let nc = usize::from(r.u16_le()?);
    let pattern_count = usize::from(r.u16_le()?);
    let data_len = usize::try_from(r.u32_le()?).ok()?;
    Some(Node {
        channels: r.take(nc.checked_mul(2)?)?,
        offsets: r.take(pattern_count.checked_mul(4)?)?,
        data: r.take(data_len)?,
        pattern_count,
    })
}

/// Reads a node's segment list at the start of `r` (§11.1): its count and
/// its segments.
fn read_segments<'a>(r: &mut Reader<'a>) -> Option<(usize, &'a [u8])> {
    let n = usize::from(r.u16_le()?);
    Some((n, r.take(n.checked_mul(SEGMENT)?)?))
}

/// Where frame `t` of a segment of `n` frames falls in a pattern of `len`
/// samples (SPEC.md §11.4): the sample `j` before it and the fraction
/// (16 bits) towards sample `j + 1`. With `q = t·(len − 1)` and
/// `d = n − 1`: `j = q / d`, `frac = ((q mod d) · 2^16) / d`; `(0, 0)` when
/// `n ≤ 1` or `len ≤ 1`. Exact in 32 bits for `n, len ≤ 65 535`.
#[inline]
pub fn position(t: u32, n: u32, len: u32) -> (u32, u32) {
    let d = n.wrapping_sub(1);
    if n <= 1 || len <= 1 {
        return (0, 0);
    }
    let q = t.wrapping_mul(len.wrapping_sub(1));
    let j = q.checked_div(d).unwrap_or(0);
    let r = q.checked_rem(d).unwrap_or(0);
    (j, (r << 16).checked_div(d).unwrap_or(0))
}

/// Bits of the curve weights' fraction (§11.4).
pub const WEIGHT_BITS: u32 = 12;

/// The weights (`2^-12` units) of samples `j − 1, j, j + 1, j + 2` at the
/// fraction `frac` (16 bits) past sample `j`: the uniform Catmull-Rom
/// curve (§11.4). With `u = frac >> 4`, `u2 = u·u >> 12`, `u3 = u2·u >> 12`:
/// `w0 = (2·u2 − u3 − u) >> 1`, `w2 = (4·u2 − 3·u3 + u) >> 1`,
/// `w3 = (u3 − u2) >> 1` (arithmetic shifts) and `w1 = 4096 − w0 − w2 − w3`,
/// so the weights sum to exactly 4096: a constant stays constant.
#[inline]
pub fn weights(frac: u32) -> [i32; 4] {
    let u = (frac >> 4 & 0xfff) as i32;
    let u2 = u.wrapping_mul(u) >> WEIGHT_BITS;
    let u3 = u2.wrapping_mul(u) >> WEIGHT_BITS;
    let w0 = (2i32.wrapping_mul(u2).wrapping_sub(u3).wrapping_sub(u)) >> 1;
    let w2 = (4i32
        .wrapping_mul(u2)
        .wrapping_sub(3i32.wrapping_mul(u3))
        .wrapping_add(u))
        >> 1;
    let w3 = u3.wrapping_sub(u2) >> 1;
    let w1 = 4096i32.wrapping_sub(w0).wrapping_sub(w2).wrapping_sub(w3);
    [w0, w1, w2, w3]
}

/// The samples the curve reads at sample `j` of a pattern of `len` samples
/// and fraction `frac`, and their weights (§11.4): samples `j − 1 … j + 2`
/// with [`weights`], where a sample before the first is `2·p[0] − p[1]`
/// and one after the last `2·p[len−1] − p[len−2]` (the curve leaves its
/// ends along the line through the two end samples), those folded into
/// the weights of the samples that are there. Taps are clamped into
/// `0 … len − 1`; a tap whose weight is folded away has weight 0.
#[inline]
pub fn taps(j: u32, len: u32, frac: u32) -> ([u32; 4], [i32; 4]) {
    let last = len.saturating_sub(1);
    let j = j.min(last);
    let [mut w0, mut w1, mut w2, mut w3] = weights(frac);
    if len < 2 {
        return ([0; 4], [0, 4096, 0, 0]);
    }
    if j == 0 {
        // p[−1] = 2·p[0] − p[1].
        w1 = w1.wrapping_add(w0.wrapping_mul(2));
        w2 = w2.wrapping_sub(w0);
        w0 = 0;
    }
    if j.wrapping_add(1) == last {
        // p[len] = 2·p[last] − p[last − 1]: tap 3 is past the end.
        w2 = w2.wrapping_add(w3.wrapping_mul(2));
        w1 = w1.wrapping_sub(w3);
        w3 = 0;
    }
    // At j = last (frac 0 there) taps 2 and 3 clamp onto tap 1.
    let t = [
        j.saturating_sub(1),
        j,
        j.wrapping_add(1).min(last),
        j.wrapping_add(2).min(last),
    ];
    (t, [w0, w1, w2, w3])
}

/// The value of a channel between its samples: `base + (round(Σ w·c /
/// 4096) << shift)` for the four codes `c` and [`weights`] `w`, the sum
/// exact (64 bits), `round(x) = (x + 2048) >> 12`, the rest wrapping in 32
/// bits (§11.4).
pub fn interpolate(base: i32, shift: u32, codes: [u32; 4], w: [i32; 4]) -> i32 {
    let acc = codes.iter().zip(w).fold(0i64, |a, (&c, w)| {
        a.wrapping_add(i64::from(c).wrapping_mul(i64::from(w)))
    });
    let code = (acc.wrapping_add(1 << (WEIGHT_BITS - 1)) >> WEIGHT_BITS) as i32;
    base.wrapping_add(code.wrapping_shl(shift))
}

/// A pattern record (§11.3), split: its sample count, the bytes of one
/// sample row, the channels' head bytes (shift in bits 0–4, code width `0,
/// 1, 2, 4` bytes in bits 5–6 as `0…3`), their bases (`i32` each) and the
/// rows.
struct Record<'a> {
    len: usize,
    row: usize,
    heads: &'a [u8],
    bases: &'a [u8],
    rows: &'a [u8],
}

fn record(rec: &[u8], nc: usize) -> Option<Record<'_>> {
    let len = usize::from(u16_at(rec, 0)?);
    let row = usize::from(u16_at(rec, 2)?);
    let (heads, rest) = rec.get(4..)?.split_at_checked(nc)?;
    let (bases, rest) = rest.split_at_checked(nc.checked_mul(4)?)?;
    let rows = rest.get(..len.checked_mul(row)?)?;
    Some(Record {
        len,
        row,
        heads,
        bases,
        rows,
    })
}

/// A channel head's code width in bytes.
#[inline(always)]
fn width_of(head: u8) -> usize {
    (1usize << (head >> 5 & 3)) >> 1
}

impl<'a> PatternCodec<'a> {
    /// Validates the section (and the shared database `model`, a show
    /// clip's first model section, if the section says it uses one)
    /// against the header's channel and frame counts (§11.1–§11.3): after
    /// this, decoding a frame reads only bytes that are there and writes
    /// every channel once.
    pub(crate) fn parse(
        bytes: &'a [u8],
        model: Option<&'a [u8]>,
        channels: usize,
        frames: u32,
    ) -> Result<Self, Error> {
        let malformed = |rule| Error::PatternMalformed { rule };
        let (&flags, rest) = bytes.split_first().ok_or(malformed("an empty section"))?;
        if flags & !FLAG_SHARED != 0 {
            return Err(malformed("reserved flags set"));
        }
        let shared = flags & FLAG_SHARED != 0;
        let db = if shared {
            model.ok_or(malformed("a shared database but no model section"))?
        } else {
            rest
        };
        let (node_count, nodes, len) = check_database(db, channels)?;
        // A model section is the database alone; in the codec section the
        // segment lists follow it.
        let segments = if shared {
            if len != db.len() {
                return Err(malformed("bytes after the database's last node"));
            }
            rest
        } else {
            rest.get(len..).unwrap_or(&[])
        };
        let mut r = Reader::new(nodes);
        let mut s = Reader::new(segments);
        for _ in 0..node_count {
            let node = read_node(&mut r).ok_or(malformed("database truncated"))?;
            let (n, list) = read_segments(&mut s).ok_or(malformed("segment list truncated"))?;
            check_segments(n, list, node.pattern_count, frames)?;
        }
        if !s.is_empty() {
            return Err(malformed("bytes after the last segment list"));
        }
        Ok(PatternCodec {
            nodes,
            segments,
            node_count,
            frames,
        })
    }

    /// Decodes frame `f` into `out` (one value per channel). `None` only if
    /// an invariant of the validated section is broken. Out of line: inlined
    /// into the player's frame loop every codec shares, it took the `index`
    /// path 16 more bytes of stack on the M0 (572 against 556).
    #[inline(never)]
    pub(crate) fn decode_frame(&self, f: u32, out: &mut [i32]) -> Option<()> {
        let mut r = Reader::new(self.nodes);
        let mut s = Reader::new(self.segments);
        for _ in 0..self.node_count {
            let node = read_node(&mut r)?;
            let (n, list) = read_segments(&mut s)?;
            self.decode_node(&node, n, list, f, out)?;
        }
        Some(())
    }

    fn decode_node(
        &self,
        node: &Node<'_>,
        count: usize,
        segments: &[u8],
        f: u32,
        out: &mut [i32],
    ) -> Option<()> {
        // The last segment starting at or before f (segment 0 starts at 0).
        let (mut lo, mut hi) = (0usize, count);
        while hi.wrapping_sub(lo) > 1 {
            let mid = lo.wrapping_add(hi.wrapping_sub(lo) / 2);
            if u32_at(segments, mid.wrapping_mul(SEGMENT))? <= f {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let at = lo.wrapping_mul(SEGMENT);
        let start = u32_at(segments, at)?;
        let end = if hi < count {
            u32_at(segments, hi.wrapping_mul(SEGMENT))?
        } else {
            self.frames
        };
        let pattern = usize::from(u16_at(segments, at.wrapping_add(4))?);
        let off = usize::try_from(u32_at(node.offsets, pattern.wrapping_mul(4))?).ok()?;
        let Record {
            len,
            row,
            heads,
            bases,
            rows,
        } = record(node.data.get(off..)?, node.channel_count())?;
        let (j, frac) = position(f.wrapping_sub(start), end.wrapping_sub(start), len as u32);
        let p = Samples {
            heads,
            bases: bases.as_chunks::<4>().0,
            channels: node.channels.as_chunks::<2>().0,
        };
        let at = |k: u32| rows.get((k as usize).wrapping_mul(row)..);
        if frac == 0 {
            let a = at(j)?;
            p.play::<false>([a, a, a, a], [0; 4], out)
        } else {
            let (t, w) = taps(j, len as u32, frac);
            let [t0, t1, t2, t3] = t;
            p.play::<true>([at(t0)?, at(t1)?, at(t2)?, at(t3)?], w, out)
        }
    }
}

/// A pattern's per-channel parts (§11.3) and the node's channels.
struct Samples<'a> {
    heads: &'a [u8],
    bases: &'a [[u8; 4]],
    channels: &'a [[u8; 2]],
}

impl Samples<'_> {
    /// Writes each channel at a position: sample row `rows[1]`, or with
    /// `CURVE` the curve through the rows of the four taps with weights `w`
    /// (§11.4).
    #[inline(always)]
    fn play<const CURVE: bool>(
        &self,
        rows: [&[u8]; 4],
        w: [i32; 4],
        out: &mut [i32],
    ) -> Option<()> {
        let mut at = 0usize;
        let [r0, r1, r2, r3] = rows;
        for ((&h, base), ch) in self.heads.iter().zip(self.bases).zip(self.channels) {
            let shift = h & 31;
            let v = match h >> 5 {
                1 if CURVE => {
                    let c = |r: &[u8]| r.get(at).map(|&b| i32::from(b));
                    // |Σ w·c| < 5 120 · 2^8: exact in 32 bits.
                    let acc = weigh(w, [c(r0)?, c(r1)?, c(r2)?, c(r3)?]);
                    at = at.wrapping_add(1);
                    curve(*base, shift, acc)
                }
                1 => {
                    let c = u32::from(*r1.get(at)?);
                    at = at.wrapping_add(1);
                    sample(*base, shift, c)
                }
                2 if CURVE => {
                    let c = |r: &[u8]| u16_at(r, at).map(i32::from);
                    // |Σ w·c| < 5 120 · 2^16: exact in 32 bits.
                    let acc = weigh(w, [c(r0)?, c(r1)?, c(r2)?, c(r3)?]);
                    at = at.wrapping_add(2);
                    curve(*base, shift, acc)
                }
                2 => {
                    let c = u32::from(u16_at(r1, at)?);
                    at = at.wrapping_add(2);
                    sample(*base, shift, c)
                }
                3 => {
                    let codes = [
                        u32_at(r0, at)?,
                        u32_at(r1, at)?,
                        u32_at(r2, at)?,
                        u32_at(r3, at)?,
                    ];
                    at = at.wrapping_add(4);
                    if CURVE {
                        interpolate(i32::from_le_bytes(*base), u32::from(shift), codes, w)
                    } else {
                        sample(*base, shift, codes[1])
                    }
                }
                _ => i32::from_le_bytes(*base),
            };
            put(out, ch, v);
        }
        Some(())
    }
}

/// Writes `v` to the output channel `c` (the node's `u16` channel number).
#[inline(always)]
fn put(out: &mut [i32], c: &[u8; 2], v: i32) {
    if let Some(o) = out.get_mut(usize::from(u16::from_le_bytes(*c))) {
        *o = v;
    }
}

/// A sample's value: `base + (code << shift)`, wrapping (§11.3).
#[inline(always)]
fn sample(base: [u8; 4], shift: u8, code: u32) -> i32 {
    i32::from_le_bytes(base).wrapping_add(code.wrapping_shl(u32::from(shift)) as i32)
}

/// `Σ w·c` of four codes in 32-bit arithmetic (exact for codes below 2^16).
#[inline(always)]
fn weigh(w: [i32; 4], c: [i32; 4]) -> i32 {
    w[0].wrapping_mul(c[0])
        .wrapping_add(w[1].wrapping_mul(c[1]))
        .wrapping_add(w[2].wrapping_mul(c[2]))
        .wrapping_add(w[3].wrapping_mul(c[3]))
}

/// The curve's value from the weighed sum `acc` of four codes (§11.4).
#[inline(always)]
fn curve(base: [u8; 4], shift: u8, acc: i32) -> i32 {
    let code = acc.wrapping_add(1 << (WEIGHT_BITS - 1)) >> WEIGHT_BITS;
    i32::from_le_bytes(base).wrapping_add(code.wrapping_shl(u32::from(shift)))
}

/// Validates the database at the start of `db` (§11.2–§11.3) for
/// `channels` channels: its node count, its node records and its length.
fn check_database(db: &[u8], channels: usize) -> Result<(usize, &[u8], usize), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    let mut r = Reader::new(db);
    let node_count = usize::from(r.u16_le().ok_or(malformed("database truncated"))?);
    if node_count == 0 || node_count > MAX_NODES {
        return Err(malformed("node count not in 1..=255"));
    }
    let mut total = 0usize;
    for _ in 0..node_count {
        let node = read_node(&mut r).ok_or(malformed("database truncated"))?;
        check_node(&node)?;
        total = total.wrapping_add(node.channel_count());
    }
    let nodes = db.get(2..r.pos()).unwrap_or(&[]);
    if total != channels {
        return Err(malformed("the nodes' channels are not the header's"));
    }
    check_cover(nodes, node_count, channels)?;
    Ok((node_count, nodes, r.pos()))
}

/// The rules of a node's segment list (§11.1).
fn check_segments(count: usize, list: &[u8], patterns: usize, frames: u32) -> Result<(), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    if count == 0 {
        return Err(malformed("a node without segments"));
    }
    let mut last: Option<u32> = None;
    for seg in list.chunks_exact(SEGMENT) {
        let start = u32_at(seg, 0).ok_or(malformed("segment list"))?;
        let pattern = u16_at(seg, 4).ok_or(malformed("segment list"))?;
        match last {
            None if start != 0 => return Err(malformed("the first segment does not start at 0")),
            Some(l) if start <= l || start.wrapping_sub(l) > MAX_SEGMENT => {
                return Err(malformed("segment starts not increasing by 1..=65535"))
            }
            _ => {}
        }
        if usize::from(pattern) >= patterns {
            return Err(malformed("a segment's pattern is not in its node"));
        }
        last = Some(start);
    }
    let last = last.unwrap_or(0);
    if last >= frames || frames.wrapping_sub(last) > MAX_SEGMENT {
        return Err(malformed(
            "the last segment is empty or longer than 65535 frames",
        ));
    }
    Ok(())
}

/// The rules of one database node record (§11.2–§11.3).
fn check_node(node: &Node<'_>) -> Result<(), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    let nc = node.channel_count();
    if nc == 0 || node.pattern_count == 0 {
        return Err(malformed("a node without channels or patterns"));
    }
    let mut prev = None;
    for c in node.channels.as_chunks::<2>().0 {
        let c = u16::from_le_bytes(*c);
        if prev.is_some_and(|p| c <= p) {
            return Err(malformed("a node's channels are not increasing"));
        }
        prev = Some(c);
    }
    for p in 0..node.pattern_count {
        let off = u32_at(node.offsets, p.wrapping_mul(4)).ok_or(malformed("pattern offsets"))?;
        let rec = usize::try_from(off)
            .ok()
            .and_then(|o| node.data.get(o..))
            .ok_or(malformed("a pattern offset past the node's data"))?;
        let Record {
            len, row, heads, ..
        } = record(rec, nc).ok_or(malformed("pattern truncated"))?;
        if len == 0 {
            return Err(malformed("a pattern without samples"));
        }
        if heads.iter().any(|h| h & 0x80 != 0) {
            return Err(malformed("a channel head with bit 7 set"));
        }
        let widths = heads
            .iter()
            .map(|&b| width_of(b))
            .fold(0usize, usize::wrapping_add);
        if widths != row {
            return Err(malformed(
                "a row length that is not the sum of the code widths",
            ));
        }
    }
    Ok(())
}

/// Every channel `0..channels` is in exactly one node: each node's list is
/// increasing, so a binary search per node and channel counts where it is
/// (no memory beyond the stack frame; `O(channels · nodes · log)` once).
fn check_cover(nodes: &[u8], node_count: usize, channels: usize) -> Result<(), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    for c in 0..channels {
        let mut found = 0u32;
        let mut r = Reader::new(nodes);
        for _ in 0..node_count {
            let node = read_node(&mut r).ok_or(malformed("database truncated"))?;
            if node
                .channels
                .as_chunks::<2>()
                .0
                .binary_search_by(|x| usize::from(u16::from_le_bytes(*x)).cmp(&c))
                .is_ok()
            {
                found = found.wrapping_add(1);
            }
        }
        if found != 1 {
            return Err(malformed("a channel in no node or in two"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// SPEC.md §7.7's section: 2 channels, 6 frames.
    const SECTION: [u8; 74] = [
        0x00, 0x01, 0x00, 0x02, 0x00, 0x02, 0x00, 0x25, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00,
        0x00, 0x00, 0x00, 0x00, 0x17, 0x00, 0x00, 0x00, 0x03, 0x00, 0x03, 0x00, 0x22, 0x40, 0xe8,
        0x03, 0x00, 0x00, 0x0c, 0xfe, 0xff, 0xff, 0x00, 0x00, 0x00, 0x64, 0xf4, 0x01, 0xc8, 0xe8,
        0x03, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0xd0, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x05, 0x00, 0x00, 0x00, 0x01, 0x00,
    ];

    fn rule(bytes: &[u8], model: Option<&[u8]>, channels: usize, frames: u32) -> &'static str {
        match PatternCodec::parse(bytes, model, channels, frames) {
            Err(Error::PatternMalformed { rule }) => rule,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_spec_section_plays_and_every_broken_rule_is_named() {
        let codec = PatternCodec::parse(&SECTION, None, 2, 6).unwrap();
        let mut out = [0i32; 2];
        codec.decode_frame(3, &mut out).unwrap();
        assert_eq!(out, [1600, 250]);
        let with = |at: usize, v: u8| {
            let mut b = SECTION.to_vec();
            b[at] = v;
            b
        };
        assert_eq!(rule(&with(0, 2), None, 2, 6), "reserved flags set");
        assert_eq!(
            rule(&with(0, 1), None, 2, 6),
            "a shared database but no model section"
        );
        assert_eq!(
            rule(&SECTION, None, 3, 6),
            "the nodes' channels are not the header's"
        );
        assert_eq!(
            rule(&with(13, 0), None, 2, 6),
            "a node's channels are not increasing"
        );
        assert_eq!(
            rule(&with(27, 0xa2), None, 2, 6),
            "a channel head with bit 7 set"
        );
        assert_eq!(
            rule(&with(25, 4), None, 2, 6),
            "a row length that is not the sum of the code widths"
        );
        assert_eq!(rule(&with(23, 0), None, 2, 6), "a pattern without samples");
        assert_eq!(
            rule(&with(68, 0), None, 2, 6),
            "segment starts not increasing by 1..=65535"
        );
        assert_eq!(
            rule(&with(62, 1), None, 2, 6),
            "the first segment does not start at 0"
        );
        assert_eq!(
            rule(&with(72, 2), None, 2, 6),
            "a segment's pattern is not in its node"
        );
        assert_eq!(
            rule(&SECTION, None, 2, 5),
            "the last segment is empty or longer than 65535 frames"
        );
        assert_eq!(rule(&SECTION[..73], None, 2, 6), "segment list truncated");
        let mut longer: Vec<u8> = SECTION.to_vec();
        longer.push(0);
        assert_eq!(
            rule(&longer, None, 2, 6),
            "bytes after the last segment list"
        );
        // SHARED: the database from the model, the segments in the section.
        let mut shared = std::vec![1u8];
        shared.extend_from_slice(&SECTION[60..]);
        let db = &SECTION[1..60];
        assert!(PatternCodec::parse(&shared, Some(db), 2, 6).is_ok());
        // A channel in two nodes: a second node with channel 1 again.
        let mut two = std::vec![0u8, 2, 0];
        two.extend_from_slice(&SECTION[3..60]);
        two.extend_from_slice(&[
            1, 0, 1, 0, 9, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0,
        ]);
        two.extend_from_slice(&SECTION[60..]);
        two.extend_from_slice(&[1, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(rule(&two, None, 3, 6), "a channel in no node or in two");
    }

    #[test]
    fn position_maps_the_ends_and_stays_in_range() {
        assert_eq!(position(0, 10, 4), (0, 0));
        assert_eq!(position(9, 10, 4), (3, 0));
        assert_eq!(position(3, 10, 4), (1, 0));
        assert_eq!(position(1, 10, 4), (0, 21_845));
        assert_eq!(position(5, 1, 4), (0, 0));
        assert_eq!(position(5, 9, 1), (0, 0));
        for &(n, len) in &[(2u32, 2u32), (65_535, 65_535), (65_535, 2), (3, 65_535)] {
            for t in [0, 1, n / 2, n - 1] {
                let (j, frac) = position(t, n, len);
                assert!(j < len && frac < 65_536, "{t} {n} {len}");
                assert!(j + 1 < len || frac == 0, "{t} {n} {len}");
            }
        }
    }
}
