//! The `pattern` codec (SPEC.md §11): motion pattern indexing after Gu,
//! Peng & Deng (2008). The channels are split into body-part *nodes*; each
//! node's take is cut into segments, and each segment is a reference to a
//! *pattern* of the node (a short, time-normalised piece of motion: a few
//! samples per channel and the curve through them) played stretched to the
//! segment's length. The patterns form a *database*: in
//! the codec section, or in a show's shared model section (§9.2) that
//! every clip of the show reads.
//!
//! Every frame is decoded directly (no history): per node its segment, the
//! frame's position in the pattern (two integer divisions) and the four
//! weights of a uniform Catmull-Rom curve there, then per channel four
//! codes, weighed and scaled. The player keeps a cursor per node (its place
//! in the database and its last segment, [`CURSOR_WORDS`] words) so that
//! the next frame needs no search; without one, a binary search over the
//! segments' start frames finds the same segment.

mod columns;
mod lists;
mod packed;
mod rows;

use crate::entropy::Table;
use crate::error::Error;
use crate::reader::Reader;
pub use lists::{coded_extent, for_each_coded_segment, MAX_BLOCK_BITS};
use lists::{CodedList, Tables};

/// Bytes of a segment: start frame (u32), pattern (u16).
const SEGMENT: usize = 6;
/// Flag bit 0 of the codec section: the database is a shared model section.
pub const FLAG_SHARED: u8 = 1;
/// Flag bit 1 of the codec section: the segment lists are entropy coded
/// (§11.1b).
pub const FLAG_CODED: u8 = 2;
/// Most nodes a database may have.
pub const MAX_NODES: usize = 255;
/// Longest segment, frames (so the position arithmetic stays in 32 bits).
pub const MAX_SEGMENT: u32 = 65_535;
/// Record layout 0 (§11.3): per pattern, the heads, the `i32` bases, then
/// the codes sample by sample (rows).
pub const LAYOUT_ROWS: u8 = 0;
/// Record layout 1 (§11.3b): per channel its head, its base in steps
/// (`i16`, or `i32`), then its codes (a column): the four samples the curve
/// reads are next to each other.
pub const LAYOUT_COLUMNS: u8 = 1;
/// Head bit 7 in layout 1: the channel's base is an `i32` (else an `i16`).
pub const HEAD_WIDE_BASE: u8 = 0x80;
/// Record layout 2 (§11.3c): layout 1 with each channel's codes
/// bit-packed at the pattern's width (0 … 32 bits), the channels' shifts
/// once per node.
pub const LAYOUT_PACKED: u8 = 2;
/// Head bit 6 in layout 2: the channel's base is an `i32` (else an `i16`);
/// bits 0–5 are the code width in bits.
pub const WIDE_BASE_2: u8 = 0x40;
/// Bytes a node's records end with in layout 2, so that a code's four
/// bytes from its first are always there.
pub const PACKED_TAIL: usize = 3;

/// A validated view of a `pattern` codec section and its database.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PatternCodec<'a> {
    /// The database's node records, back to back (§11.2).
    nodes: &'a [u8],
    /// The segment lists, one per node (§11.1).
    segments: &'a [u8],
    node_count: usize,
    frames: u32,
    /// The records' layout: [`LAYOUT_ROWS`] or [`LAYOUT_COLUMNS`] (§11.2).
    layout: u8,
    /// Coded segment lists (§11.1b): the bytes of their two tables
    /// (validated by [`PatternCodec::parse`], read again where needed:
    /// two slices in the player, not two parsed tables).
    tables: Option<(&'a [u8], &'a [u8])>,
}

/// One node of the database.
#[derive(Clone, Copy)]
struct Node<'a> {
    channels: &'a [u8],
    /// Layout 2: the channels' shifts.
    shifts: &'a [u8],
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
fn read_node<'a>(r: &mut Reader<'a>, layout: u8) -> Option<Node<'a>> {
    let nc = usize::from(r.u16_le()?);
    let pattern_count = usize::from(r.u16_le()?);
    let data_len = usize::try_from(r.u32_le()?).ok()?;
    let channels = r.take(nc.checked_mul(2)?)?;
    let shifts = if layout == LAYOUT_PACKED {
        r.take(nc)?
    } else {
        &[]
    };
    Some(Node {
        channels,
        shifts,
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

/// The samples the curve reads as one window (§11.3b): its first sample
/// `s0` and the weights of samples `s0 … s0 + 3` — [`taps`]' weights added
/// up per sample, so `Σ W·code` is exactly `Σ w·code` over the taps. The
/// window starts at the first tap and stays inside the pattern when it has
/// 4 samples or more (`s0 ≤ len − 4`); a shorter pattern's window is the
/// pattern, its weights past the end 0.
#[inline]
pub fn window(j: u32, len: u32, frac: u32) -> (u32, [i32; 4]) {
    let w = weights(frac);
    if j >= 1 && j.wrapping_add(2) < len {
        // Inside the pattern: the taps j − 1 … j + 2, nothing folded.
        return (j.wrapping_sub(1), w);
    }
    if len < 2 {
        return (0, [4096, 0, 0, 0]);
    }
    // At an end: taps()'s folding, the taps added up per sample.
    let [mut w0, mut w1, mut w2, mut w3] = w;
    let last = len.wrapping_sub(1);
    let j = j.min(last);
    if j == 0 {
        w1 = w1.wrapping_add(w0.wrapping_mul(2));
        w2 = w2.wrapping_sub(w0);
        w0 = 0;
    }
    if j.wrapping_add(1) == last {
        w2 = w2.wrapping_add(w3.wrapping_mul(2));
        w1 = w1.wrapping_sub(w3);
        w3 = 0;
    }
    let t = [
        j.saturating_sub(1),
        j,
        j.wrapping_add(1).min(last),
        j.wrapping_add(2).min(last),
    ];
    let s0 = t[0].min(len.saturating_sub(4));
    let mut out = [0i32; 4];
    for (&t, w) in t.iter().zip([w0, w1, w2, w3]) {
        // Every tap is within s0 … s0 + 3.
        if let Some(x) = out.get_mut((t.wrapping_sub(s0) & 3) as usize) {
            *x = x.wrapping_add(w);
        }
    }
    (s0, out)
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
        if flags & !(FLAG_SHARED | FLAG_CODED) != 0 {
            return Err(malformed("reserved flags set"));
        }
        let shared = flags & FLAG_SHARED != 0;
        let db = if shared {
            model.ok_or(malformed("a shared database but no model section"))?
        } else {
            rest
        };
        let (node_count, layout, nodes, len) = check_database(db, channels)?;
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
        let (tables, checked, segments) = if flags & FLAG_CODED != 0 {
            let (lengths, a) = Table::parse(segments)?;
            let (l, rest) = segments.split_at_checked(a).unwrap_or((&[], &[]));
            let (patterns, b) = Table::parse(rest)?;
            let (p, rest) = rest.split_at_checked(b).unwrap_or((&[], &[]));
            (Some((l, p)), Some(Tables { lengths, patterns }), rest)
        } else {
            (None, None, segments)
        };
        let mut r = Reader::new(nodes);
        let mut s = Reader::new(segments);
        for _ in 0..node_count {
            let node = read_node(&mut r, layout).ok_or(malformed("database truncated"))?;
            if let Some(t) = &checked {
                if segments.get(s.pos().wrapping_add(2)) > Some(&MAX_BLOCK_BITS) {
                    return Err(malformed("a block size over 2^15 segments"));
                }
                let (list, len) = CodedList::read(segments, s.pos())
                    .ok_or(malformed("segment list truncated"))?;
                list.check(t, node.pattern_count, frames)?;
                s.take(len).ok_or(malformed("segment list truncated"))?;
            } else {
                let (n, list) = read_segments(&mut s).ok_or(malformed("segment list truncated"))?;
                check_segments(n, list, node.pattern_count, frames)?;
            }
        }
        if !s.is_empty() {
            return Err(malformed("bytes after the last segment list"));
        }
        Ok(PatternCodec {
            nodes,
            segments,
            node_count,
            frames,
            layout,
            tables,
        })
    }

    /// Decodes frame `f` into `out` (one value per channel), with no
    /// state: every node's segment by a binary search.
    #[cfg(test)]
    pub(crate) fn decode_frame(&self, f: u32, out: &mut [i32]) -> Option<()> {
        self.decode(f, out, &mut [])
    }

    /// Decodes frame `f` into `out` (one value per channel). `cursors`
    /// holds [`CURSOR_WORDS`] per node that remember each node's place in
    /// the database and its segment from the last call (all 0 at first:
    /// filled on this call): the next frame is in the same segment or the
    /// next one, no search. Without room for every node's cursor (e.g.
    /// empty) each node finds its segment by a binary search.
    /// `None` only if an invariant of the validated section is broken.
    /// Out of line: inlined into the player's frame loop every codec
    /// shares, it took the `index` path 16 more bytes of stack on the M0.
    #[inline(never)]
    pub(crate) fn decode(&self, f: u32, out: &mut [i32], cursors: &mut [i32]) -> Option<()> {
        let need = self.node_count.wrapping_mul(CURSOR_WORDS);
        if let Some(c) = cursors.get_mut(..need) {
            let c = c.as_chunks_mut::<CURSOR_WORDS>().0;
            if c.first()?[DATA_END] == 0 {
                self.init_cursors(c)?;
            }
            for c in c.iter_mut() {
                self.play_node(c, f, out)?;
            }
        } else {
            // No room: each node's cursor for this frame alone.
            let (mut at, mut s) = (0usize, 0usize);
            for _ in 0..self.node_count {
                let mut c = [0i32; CURSOR_WORDS];
                (at, s) = self.cursor_of(at, s, &mut c)?;
                self.play_node(&mut c, f, out)?;
            }
        }
        Some(())
    }

    /// Fills every node's cursor (no segment yet) by walking the database
    /// and the segment lists once.
    #[inline(never)]
    fn init_cursors(&self, cursors: &mut [[i32; CURSOR_WORDS]]) -> Option<()> {
        let (mut at, mut s) = (0usize, 0usize);
        for c in cursors {
            (at, s) = self.cursor_of(at, s, c)?;
        }
        Some(())
    }

    /// The cursor of the node whose record starts at `at` in the database
    /// and whose segment list starts at `s` (§11.1–§11.2), no segment yet;
    /// where the next node's record and list start.
    fn cursor_of(
        &self,
        at: usize,
        s: usize,
        c: &mut [i32; CURSOR_WORDS],
    ) -> Option<(usize, usize)> {
        let node = NodeAt::read(self.nodes, at, self.layout)?;
        let count = usize::from(u16_at(self.segments, s)?);
        *c = [0; CURSOR_WORDS];
        c[DATA_END] = node.data_end as i32;
        c[CH_AT] = node.ch_at as i32;
        c[NC] = node.nc as i32;
        c[NODE_AT] = at as i32;
        c[LIST_AT] = s as i32;
        let next = if self.tables.is_some() {
            s.wrapping_add(CodedList::read(self.segments, s)?.1)
        } else {
            s.wrapping_add(2).wrapping_add(count.wrapping_mul(SEGMENT))
        };
        Some((node.data_end, next))
    }

    /// Decodes frame `f` of the node of cursor `c` into its channels of
    /// `out`, moving the cursor to the frame's segment.
    #[inline(always)]
    fn play_node(&self, c: &mut [i32; CURSOR_WORDS], f: u32, out: &mut [i32]) -> Option<()> {
        if !((c[START] as u32) <= f && f < (c[END] as u32)) {
            self.advance(c, f)?;
        }
        let [start, end, rec_at, data_end, ch_at, nc, ..] = c.map(|w| w as u32 as usize);
        let ch_end = ch_at.wrapping_add(nc.wrapping_mul(2));
        let channels = self.nodes.get(ch_at..ch_end)?.as_chunks::<2>().0;
        let rec = self.nodes.get(rec_at..data_end)?;
        let t = f.wrapping_sub(start as u32);
        let n = end.wrapping_sub(start) as u32;
        match self.layout {
            LAYOUT_PACKED => {
                let shifts = self.nodes.get(ch_end..ch_end.wrapping_add(nc))?;
                packed::play(rec, channels, shifts, t, n, out)
            }
            LAYOUT_COLUMNS => columns::play(rec, channels, t, n, out),
            _ => rows::play(rec, channels, t, n, out),
        }
    }

    /// Moves cursor `c` to the segment of frame `f`: the next one, or
    /// found by a binary search over the starts (§11.4).
    #[inline(never)]
    fn advance(&self, c: &mut [i32; CURSOR_WORDS], f: u32) -> Option<()> {
        let node = NodeAt::read(self.nodes, c[NODE_AT] as u32 as usize, self.layout)?;
        let s = c[LIST_AT] as u32 as usize;
        if let Some((l, p)) = self.tables {
            let t = Tables {
                lengths: Table::reread(l),
                patterns: Table::reread(p),
            };
            return self.advance_coded(c, f, &node, s, &t);
        }
        let count = usize::from(u16_at(self.segments, s)?);
        let list_at = s.wrapping_add(2);
        let list = self
            .segments
            .get(list_at..list_at.wrapping_add(count.wrapping_mul(SEGMENT)))?;
        let next = c[NEXT] as u32 as usize;
        let i = if f >= c[END] as u32
            && next < count
            && f < end_of(list, next.wrapping_add(1), self.frames)?
        {
            next
        } else {
            // The last segment starting at or before f (segment 0 starts at 0).
            let (mut lo, mut hi) = (0usize, count);
            while hi.wrapping_sub(lo) > 1 {
                let mid = lo.wrapping_add(hi.wrapping_sub(lo) / 2);
                if u32_at(list, mid.wrapping_mul(SEGMENT))? <= f {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let at = i.wrapping_mul(SEGMENT);
        let pattern = usize::from(u16_at(list, at.wrapping_add(4))?);
        let off = u32_at(
            self.nodes,
            node.off_at.wrapping_add(pattern.wrapping_mul(4)),
        )?;
        c[START] = u32_at(list, at)? as i32;
        c[END] = end_of(list, i.wrapping_add(1), self.frames)? as i32;
        c[REC_AT] = node.data_at.wrapping_add(off as usize) as i32;
        c[NEXT] = i.wrapping_add(1) as i32;
        Some(())
    }

    /// [`PatternCodec::advance`] on a coded list (§11.1b): the segment
    /// after the cursor's, decoded from the state the cursor keeps, or
    /// found by a binary search over the blocks and a walk through one.
    fn advance_coded(
        &self,
        c: &mut [i32; CURSOR_WORDS],
        f: u32,
        node: &NodeAt,
        s: usize,
        t: &Tables<'_>,
    ) -> Option<()> {
        let (list, _) = CodedList::read(self.segments, s)?;
        let next = c[NEXT] as u32 as usize;
        let here = lists::Seg {
            start: c[START] as u32,
            end: c[END] as u32,
            pattern: c[PAT] as u32,
            i: next.wrapping_sub(1),
            x: c[X] as u32,
            pos: c[POS] as u32 as usize,
        };
        let seg = match (f >= here.end && next > 0)
            .then(|| list.next(&here, t))
            .flatten()
        {
            Some(n) if f < n.end => n,
            _ => list.find(f, t)?,
        };
        let off = u32_at(
            self.nodes,
            node.off_at
                .wrapping_add((seg.pattern as usize).wrapping_mul(4)),
        )?;
        c[START] = seg.start as i32;
        c[END] = seg.end as i32;
        c[REC_AT] = node.data_at.wrapping_add(off as usize) as i32;
        c[NEXT] = seg.i.wrapping_add(1) as i32;
        c[X] = seg.x as i32;
        c[POS] = seg.pos as i32;
        c[PAT] = seg.pattern as i32;
        Some(())
    }
}

/// Player-state words per node: where the node is in the database and
/// the segment it played last (§11.4), so that the next frame reads no
/// header and searches no list.
pub(crate) const CURSOR_WORDS: usize = 12;
/// Cursor words: the segment's start and end frames, its pattern record
/// and the end of the node's records (offsets in the database's nodes;
/// `DATA_END` = 0 before the cursors are filled), the node's channel list
/// and channel count, the segment's number + 1, the node record and its
/// segment list (offset of its count in the segment lists).
const START: usize = 0;
const END: usize = 1;
const REC_AT: usize = 2;
const DATA_END: usize = 3;
const CH_AT: usize = 4;
const NC: usize = 5;
const NEXT: usize = 6;
const NODE_AT: usize = 7;
const LIST_AT: usize = 8;
/// Coded lists (§11.1b) only: the rANS state after the segment's steps,
/// the offset of the stream's next byte in the node's streams, the
/// segment's pattern.
const X: usize = 9;
const POS: usize = 10;
const PAT: usize = 11;

/// Where a node record's parts are (§11.2), as offsets in the nodes.
struct NodeAt {
    ch_at: usize,
    nc: usize,
    off_at: usize,
    data_at: usize,
    data_end: usize,
}

impl NodeAt {
    fn read(nodes: &[u8], at: usize, layout: u8) -> Option<NodeAt> {
        let &[c0, c1, p0, p1, d0, d1, d2, d3] = nodes.get(at..)?.first_chunk::<8>()?;
        let nc = usize::from(u16::from_le_bytes([c0, c1]));
        let np = usize::from(u16::from_le_bytes([p0, p1]));
        let d = u32::from_le_bytes([d0, d1, d2, d3]) as usize;
        let ch_at = at.wrapping_add(8);
        let shifts = if layout == LAYOUT_PACKED { nc } else { 0 };
        let off_at = ch_at.wrapping_add(nc.wrapping_mul(2)).wrapping_add(shifts);
        let data_at = off_at.wrapping_add(np.wrapping_mul(4));
        Some(NodeAt {
            ch_at,
            nc,
            off_at,
            data_at,
            data_end: data_at.wrapping_add(d),
        })
    }
}

/// Where segment `i − 1` ends: segment `i`'s start, or the frame count
/// past the last.
#[inline(always)]
fn end_of(list: &[u8], i: usize, frames: u32) -> Option<u32> {
    if i.wrapping_mul(SEGMENT) < list.len() {
        u32_at(list, i.wrapping_mul(SEGMENT))
    } else {
        Some(frames)
    }
}

/// Validates the database at the start of `db` (§11.2–§11.3b) for
/// `channels` channels: its node count, its records' layout, its node
/// records and its length.
fn check_database(db: &[u8], channels: usize) -> Result<(usize, u8, &[u8], usize), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    let mut r = Reader::new(db);
    let node_count = usize::from(r.u8().ok_or(malformed("database truncated"))?);
    let layout = r.u8().ok_or(malformed("database truncated"))?;
    if node_count == 0 {
        return Err(malformed("node count not in 1..=255"));
    }
    if layout > LAYOUT_PACKED {
        return Err(malformed("an unknown record layout"));
    }
    let mut total = 0usize;
    for _ in 0..node_count {
        let node = read_node(&mut r, layout).ok_or(malformed("database truncated"))?;
        check_node(&node, layout)?;
        total = total.wrapping_add(node.channel_count());
    }
    let nodes = db.get(2..r.pos()).unwrap_or(&[]);
    if total != channels {
        return Err(malformed("the nodes' channels are not the header's"));
    }
    check_cover(nodes, node_count, channels, layout)?;
    Ok((node_count, layout, nodes, r.pos()))
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

/// The rules of one database node record (§11.2–§11.3b).
fn check_node(node: &Node<'_>, layout: u8) -> Result<(), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    let nc = node.channel_count();
    if nc == 0 || node.pattern_count == 0 {
        return Err(malformed("a node without channels or patterns"));
    }
    if node.shifts.iter().any(|&sh| sh > 31) {
        return Err(malformed("a shift over 31"));
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
        if layout == LAYOUT_COLUMNS {
            check_columns(rec, nc)?;
            continue;
        }
        if layout == LAYOUT_PACKED {
            check_packed(rec, nc)?;
            continue;
        }
        let rows::Record {
            len, row, heads, ..
        } = rows::record(rec, nc).ok_or(malformed("pattern truncated"))?;
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

/// The rules of a layout-1 record (§11.3b) of `nc` channels at the start
/// of `rec`: samples, and every channel's head, base and codes there.
fn check_columns(rec: &[u8], nc: usize) -> Result<(), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    let len = usize::from(u16_at(rec, 0).ok_or(malformed("pattern truncated"))?);
    if len == 0 {
        return Err(malformed("a pattern without samples"));
    }
    let mut rest = rec.get(2..).unwrap_or(&[]);
    for _ in 0..nc {
        let (_, h, col) =
            columns::split_head(rest, HEAD_WIDE_BASE).ok_or(malformed("pattern truncated"))?;
        rest = len
            .checked_mul(width_of(h))
            .and_then(|b| col.get(b..))
            .ok_or(malformed("pattern truncated"))?;
    }
    Ok(())
}

/// The rules of a layout-2 record (§11.3c) of `nc` channels at the start
/// of `rec` (the node's records from it on): samples, every channel's
/// head, base and codes, and the node's 3 closing bytes after it.
fn check_packed(rec: &[u8], nc: usize) -> Result<(), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    let len = usize::from(u16_at(rec, 0).ok_or(malformed("pattern truncated"))?);
    if len == 0 {
        return Err(malformed("a pattern without samples"));
    }
    let mut rest = rec.get(2..).unwrap_or(&[]);
    for _ in 0..nc {
        let (&h, r) = rest.split_first().ok_or(malformed("pattern truncated"))?;
        if h & 0x80 != 0 || h & 63 > 32 {
            return Err(malformed(
                "a channel head with bit 7 set or a width over 32 bits",
            ));
        }
        let base = if h & WIDE_BASE_2 == 0 { 2 } else { 4 };
        let bytes = len
            .checked_mul(usize::from(h & 63))
            .and_then(|b| b.checked_add(7))
            .map(|b| b >> 3)
            .and_then(|b| b.checked_add(base))
            .ok_or(malformed("pattern truncated"))?;
        rest = r.get(bytes..).ok_or(malformed("pattern truncated"))?;
    }
    if rest.len() < PACKED_TAIL {
        return Err(malformed(
            "a node's records do not end with 3 bytes after the last code",
        ));
    }
    Ok(())
}

/// Every channel `0..channels` is in exactly one node: each node's list is
/// increasing, so a binary search per node and channel counts where it is
/// (no memory beyond the stack frame; `O(channels · nodes · log)` once).
fn check_cover(nodes: &[u8], node_count: usize, channels: usize, layout: u8) -> Result<(), Error> {
    let malformed = |rule| Error::PatternMalformed { rule };
    for c in 0..channels {
        let mut found = 0u32;
        let mut r = Reader::new(nodes);
        for _ in 0..node_count {
            let node = read_node(&mut r, layout).ok_or(malformed("database truncated"))?;
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
            // Anything else (accepted, another error) matches no rule.
            _ => "",
        }
    }

    #[test]
    fn the_spec_section_plays_and_every_broken_rule_is_named() -> Result<(), Error> {
        let codec = PatternCodec::parse(&SECTION, None, 2, 6)?;
        let mut out = [0i32; 2];
        codec
            .decode_frame(3, &mut out)
            .ok_or(Error::PlayerInvariant { frame: 3 })?;
        assert_eq!(out, [1600, 250]);
        let with = |at: usize, v: u8| {
            let mut b = SECTION.to_vec();
            b[at] = v;
            b
        };
        assert_eq!(rule(&with(0, 4), None, 2, 6), "reserved flags set");
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
        Ok(())
    }

    /// SPEC.md §7.9b's section: §7.9's clip with its segment list coded.
    const CODED: [u8; 76] = [
        0x02, 0x01, 0x02, 0x02, 0x00, 0x02, 0x00, 0x1c, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00,
        0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0f, 0x00, 0x00, 0x00, 0x03, 0x00, 0x08, 0xfa, 0x00,
        0x00, 0x64, 0xc8, 0x0a, 0x0c, 0xfe, 0x00, 0xd0, 0x87, 0x3e, 0x01, 0x00, 0x40, 0xf4, 0x01,
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x11, 0x06, 0x11, 0x10, 0x02, 0x01, 0x02,
        0x00, 0x06, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x04, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00,
        0x02,
    ];

    #[test]
    fn the_coded_section_plays_and_its_rules_are_named() -> Result<(), Error> {
        let codec = PatternCodec::parse(&CODED, None, 2, 6)?;
        let expected = [
            [1000, -500],
            [1200, -250],
            [1400, 0],
            [1600, 250],
            [1800, 500],
            [2000, 0],
        ];
        // With cursors (in order, then backwards) and without.
        let mut cursors = [0i32; CURSOR_WORDS];
        for f in (0..6).chain((0..6).rev()) {
            let mut out = [0i32; 2];
            codec
                .decode(f, &mut out, &mut cursors)
                .ok_or(Error::PlayerInvariant { frame: f })?;
            assert_eq!(out, expected[f as usize], "frame {f}");
            codec
                .decode_frame(f, &mut out)
                .ok_or(Error::PlayerInvariant { frame: f })?;
            assert_eq!(out, expected[f as usize], "frame {f} without cursors");
        }
        let with = |at: usize, v: u8| {
            let mut b = CODED.to_vec();
            b[at] = v;
            b
        };
        const L: usize = 53;
        assert_eq!(rule(&with(0, 6), None, 2, 6), "reserved flags set");
        assert_eq!(
            rule(&with(L + 8, 16), None, 2, 6),
            "a block size over 2^15 segments"
        );
        // The stream's state below 2^23.
        assert_eq!(
            rule(&with(L + 22, 0), None, 2, 6),
            "a block's stream state out of range"
        );
        // A length of 5 + 2: past the last frame.
        assert_eq!(
            rule(&with(L + 19, 0x03), None, 2, 6),
            "a segment of 0 or over 65535 frames, or past the last frame"
        );
        // The block starting at frame 1.
        assert_eq!(
            rule(&with(L + 9, 1), None, 2, 6),
            "a block does not start where the segments before it end"
        );
        // The first pattern 2: not in the node.
        assert_eq!(
            rule(&with(L + 13, 2), None, 2, 6),
            "a segment's pattern is not in its node"
        );
        // One frame more than the segments cover.
        assert_eq!(
            rule(&CODED, None, 2, 7),
            "the segments do not end at the last frame"
        );
        // A byte more in the stream, counted in its end: not where the
        // encoder started.
        let mut longer = CODED.to_vec();
        longer[L + 15] = 5;
        longer.push(0);
        assert_eq!(
            rule(&longer, None, 2, 6),
            "a block's stream does not end where its encoder started"
        );
        assert_eq!(rule(&CODED[..75], None, 2, 6), "segment list truncated");
        Ok(())
    }

    /// SPEC.md §7.8's section: §7.7's clip in layout 1 (columns).
    const COLUMNS: [u8; 64] = [
        0x00, 0x01, 0x01, 0x02, 0x00, 0x02, 0x00, 0x1b, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00,
        0x00, 0x00, 0x00, 0x00, 0x11, 0x00, 0x00, 0x00, 0x03, 0x00, 0x22, 0xfa, 0x00, 0x00, 0x64,
        0xc8, 0x40, 0x0c, 0xfe, 0x00, 0x00, 0xf4, 0x01, 0xe8, 0x03, 0x01, 0x00, 0x80, 0xd0, 0x07,
        0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x05, 0x00,
        0x00, 0x00, 0x01, 0x00,
    ];

    #[test]
    fn the_columns_section_plays_and_its_rules_are_named() -> Result<(), Error> {
        let codec = PatternCodec::parse(&COLUMNS, None, 2, 6)?;
        let expected = [
            [1000, -500],
            [1200, -250],
            [1400, 0],
            [1600, 250],
            [1800, 500],
            [2000, 0],
        ];
        for (f, want) in expected.iter().enumerate() {
            let mut out = [0i32; 2];
            codec
                .decode_frame(f as u32, &mut out)
                .ok_or(Error::PlayerInvariant { frame: f as u32 })?;
            assert_eq!(&out, want, "frame {f}");
        }
        let with = |at: usize, v: u8| {
            let mut b = COLUMNS.to_vec();
            b[at] = v;
            b
        };
        assert_eq!(rule(&with(2, 3), None, 2, 6), "an unknown record layout");
        assert_eq!(rule(&with(1, 0), None, 2, 6), "node count not in 1..=255");
        // Pattern 1's Zrotation with a 4-byte code: past the node's data.
        assert_eq!(rule(&with(47, 0x60), None, 2, 6), "pattern truncated");
        Ok(())
    }

    /// SPEC.md §7.9's section: §7.7's clip in layout 2 (bit-packed).
    const PACKED: [u8; 67] = [
        0x00, 0x01, 0x02, 0x02, 0x00, 0x02, 0x00, 0x1c, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00,
        0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0f, 0x00, 0x00, 0x00, 0x03, 0x00, 0x08, 0xfa, 0x00,
        0x00, 0x64, 0xc8, 0x0a, 0x0c, 0xfe, 0x00, 0xd0, 0x87, 0x3e, 0x01, 0x00, 0x40, 0xf4, 0x01,
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x05, 0x00, 0x00, 0x00, 0x01, 0x00,
    ];

    #[test]
    fn the_packed_section_plays_and_its_rules_are_named() -> Result<(), Error> {
        let codec = PatternCodec::parse(&PACKED, None, 2, 6)?;
        let expected = [
            [1000, -500],
            [1200, -250],
            [1400, 0],
            [1600, 250],
            [1800, 500],
            [2000, 0],
        ];
        for (f, want) in expected.iter().enumerate() {
            let mut out = [0i32; 2];
            codec
                .decode_frame(f as u32, &mut out)
                .ok_or(Error::PlayerInvariant { frame: f as u32 })?;
            assert_eq!(&out, want, "frame {f}");
        }
        let with = |at: usize, v: u8| {
            let mut b = PACKED.to_vec();
            b[at] = v;
            b
        };
        assert_eq!(rule(&with(2, 3), None, 2, 6), "an unknown record layout");
        assert_eq!(rule(&with(15, 32), None, 2, 6), "a shift over 31");
        assert_eq!(
            rule(&with(27, 0x88), None, 2, 6),
            "a channel head with bit 7 set or a width over 32 bits"
        );
        assert_eq!(
            rule(&with(27, 33), None, 2, 6),
            "a channel head with bit 7 set or a width over 32 bits"
        );
        // Zrotation of pattern 1 at 32 bits: its code runs past the node's
        // records.
        assert_eq!(rule(&with(47, 32), None, 2, 6), "pattern truncated");
        // Zrotation of pattern 1 at 16 bits: its 2 bytes eat the closing
        // bytes, fewer than 3 are left.
        assert_eq!(
            rule(&with(47, 16), None, 2, 6),
            "a node's records do not end with 3 bytes after the last code"
        );
        Ok(())
    }

    /// The window's weights are taps()' weights added up per sample: the
    /// same weighed sum of any codes, never a weight past the pattern.
    #[test]
    fn window_weighs_as_the_taps_do() {
        let codes: Vec<i64> = (0..12).map(|k| (k * 37 % 11) as i64 - 3).collect();
        for len in 1..10u32 {
            for j in 0..len {
                for frac in [0u32, 1, 4_096, 21_845, 32_768, 65_535] {
                    let (t, w) = taps(j, len, frac);
                    let want: i64 = t
                        .iter()
                        .zip(w)
                        .map(|(&t, w)| codes[t as usize] * i64::from(w))
                        .sum();
                    let (s0, ww) = window(j, len, frac);
                    let got: i64 = ww
                        .iter()
                        .enumerate()
                        .map(|(k, &w)| {
                            let at = s0 as usize + k;
                            assert!(at < len as usize || w == 0, "{len} {j} {frac}");
                            codes.get(at).copied().unwrap_or(0) * i64::from(w)
                        })
                        .sum();
                    assert_eq!(got, want, "len {len} j {j} frac {frac}");
                }
            }
        }
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
