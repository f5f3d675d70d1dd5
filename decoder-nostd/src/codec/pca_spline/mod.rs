//! The `pca-spline` codec (SPEC.md §5), after Liu & McMillan (2006): the
//! clip is cut into segments; in each segment every channel group is a
//! mean plus a few principal components whose coefficients follow a
//! key-frame spline. A pose at any time costs one spline evaluation per
//! group (four control points) and `k` multiply-adds per channel; nothing
//! depends on earlier frames.
//!
//! This module holds the section's view, its record readers and the entry
//! points; by job: [`validate`] (once, at parse), [`cursor`] (segment and
//! patch position), [`cache`] (the player's key-interval cache and the hot
//! channel loops), [`eval`] (poses from the records, blending).

pub(crate) mod cache;
mod cursor;
mod eval;
mod validate;

use crate::bits::{bits_at, bits_at64, BitReader};
use crate::codec::spline;
use crate::consts::pca::{
    BASIS_SHIFT, FRAC_BITS, MAX_COMPONENTS, MAX_MEAN_SHIFT, MAX_SEGMENT_FRAMES, MAX_TIME_BITS,
    MAX_VALUE_BITS, MAX_VALUE_SHIFT,
};
use crate::error::Error;
use crate::reader::Reader;
use crate::wire;
pub(crate) use cursor::Cursor;
use cursor::*;
use eval::*;
use validate::*;

const K_MAX: usize = MAX_COMPONENTS as usize;

/// A validated view of a `pca-spline` section.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PcaSplineCodec<'a> {
    channels: usize,
    /// Bytes per channel index: 1 or 2.
    wide: bool,
    group_count: u32,
    /// The group table (§5.1), after the group count.
    groups: &'a [u8],
    const_count: u32,
    /// Constant channels: indices then zigzag values (§5.1).
    consts: &'a [u8],
    /// The segment blocks (§5.2), after the segment count.
    segments: &'a [u8],
}

/// What every group of a pose needs: the segment's body, the position
/// relative to its start (§5.4), the output.
struct Pose<'a, 'o> {
    body: &'a [u8],
    rel: u32,
    out: &'o mut [i32],
}

/// One segment's header and its group data.
#[derive(Clone, Copy, Debug)]
struct Segment<'a> {
    start: u32,
    end: u32,
    body: &'a [u8],
    /// Sparse corrections (§5.5).
    patches: &'a [u8],
    /// Offset of the next segment header.
    next: usize,
}

/// The per-group parameters read before the key bits (§5.3). Small on
/// purpose: it is rebuilt for every group of every pose.
struct GroupHead<'a> {
    k: usize,
    mean_shift: u32,
    mean: &'a [u8],
    basis: &'a [u8],
    keys: u32,
    time_bits: u32,
    /// The `k` (width, shift, offset) records, still encoded.
    comps: &'a [u8],
    /// Σ width: bits per key row.
    row_bits: u32,
    bits: &'a [u8],
}

fn malformed(rule: &'static str) -> Error {
    Error::PcaMalformed { rule }
}

/// A 1- or 2-byte little-endian channel index.
#[inline(always)]
fn index_of(ix: &[u8]) -> usize {
    match ix {
        [lo] => usize::from(*lo),
        [lo, hi] => usize::from(*lo) | usize::from(*hi) << 8,
        _ => usize::MAX,
    }
}

/// A mean: `i16` little-endian.
#[inline(always)]
fn mean_of(m: &[u8]) -> i32 {
    match m {
        [a, b] => i32::from(i16::from_le_bytes([*a, *b])),
        _ => 0,
    }
}

/// Reads one group's fields (§5.3) from a segment body.
fn read_group<'a>(r: &mut Reader<'a>, n: usize) -> Option<GroupHead<'a>> {
    let k = r.u8()?;
    let mean_shift = r.u8()?;
    if k > MAX_COMPONENTS || mean_shift > MAX_MEAN_SHIFT {
        return None;
    }
    let k = usize::from(k);
    // k = 0: n zigzag varints (a constant pose is often mostly zeros);
    // k > 0: n × i16, read on every pose.
    let mean = if k == 0 {
        let at = r.clone();
        for _ in 0..n {
            r.zigzag_i32()?;
        }
        let len = r.pos().wrapping_sub(at.pos());
        at.clone().take(len)?
    } else {
        r.take(n.checked_mul(2)?)?
    };
    let mut head = GroupHead {
        k,
        mean_shift: u32::from(mean_shift),
        mean,
        basis: &[],
        keys: 0,
        time_bits: 0,
        comps: &[],
        row_bits: 0,
        bits: &[],
    };
    if k == 0 {
        return Some(head);
    }
    head.basis = r.take(n.checked_mul(k)?)?;
    head.keys = r.varint_u32()?;
    let time_bits = r.u8()?;
    if time_bits == 0 || time_bits > MAX_TIME_BITS {
        return None;
    }
    head.time_bits = u32::from(time_bits);
    let comps_at = r.clone();
    let mut row_bits = 0u32;
    for _ in 0..k {
        let (w, s, _, len) = comp_at(r.clone().rest(), 0)?;
        r.take(len)?;
        if w > u32::from(MAX_VALUE_BITS) || s > u32::from(MAX_VALUE_SHIFT) {
            return None;
        }
        row_bits = row_bits.wrapping_add(w);
    }
    head.comps = comps_at
        .clone()
        .take(r.pos().wrapping_sub(comps_at.pos()))?;
    head.row_bits = row_bits;
    let total = u64::from(head.keys).wrapping_mul(u64::from(head.time_bits.wrapping_add(row_bits)));
    head.bits = r.take(usize::try_from(total.div_ceil(8)).ok()?)?;
    Some(head)
}

/// Channel indices stored as 1- or 2-byte little-endian integers.
#[derive(Clone, Debug)]
struct Indices<'a> {
    bytes: core::slice::Iter<'a, u8>,
    wide: bool,
}

impl<'a> Indices<'a> {
    fn new(bytes: &'a [u8], wide: bool) -> Self {
        Indices {
            bytes: bytes.iter(),
            wide,
        }
    }
}

impl Iterator for Indices<'_> {
    type Item = usize;

    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        let lo = usize::from(*self.bytes.next()?);
        if self.wide {
            Some(lo | usize::from(*self.bytes.next()?) << 8)
        } else {
            Some(lo)
        }
    }
}

/// The component record (§5.3: u8 width, u8 shift, zigzag offset) at byte
/// `p` of `comps`: width, shift, offset and the byte after it. Offsets of
/// up to three bytes (almost all) are matched in the same slice pattern as
/// the width and shift: one bounds check, no call (going through
/// [`wire::varint_u32_unrolled`] on the rest costs the sequential refill a
/// second slice and its checks, and its out-of-line slow path registers).
#[inline(always)]
fn comp_at(comps: &[u8], p: usize) -> Option<(u32, u32, i32, usize)> {
    let zigzag = wire::zigzag_decode;
    match *comps.get(p..)? {
        [wd, sh, o, ..] if o < 0x80 => {
            Some((wd.into(), sh.into(), zigzag(o.into()), p.wrapping_add(3)))
        }
        [wd, sh, o, o2, ..] if o2 < 0x80 => {
            let u = u32::from(o & 0x7F) | u32::from(o2) << 7;
            Some((wd.into(), sh.into(), zigzag(u), p.wrapping_add(4)))
        }
        [wd, sh, o, o2, o3, ..] if o3 < 0x80 => {
            let u = u32::from(o & 0x7F) | u32::from(o2 & 0x7F) << 7 | u32::from(o3) << 14;
            Some((wd.into(), sh.into(), zigzag(u), p.wrapping_add(5)))
        }
        [wd, sh, ..] => {
            // Inlined whole (no call: a call would cost the hot loops
            // that read these records registers even when not taken).
            let (u, next) = wire::varint_u32_any(comps, p.wrapping_add(2))?;
            Some((wd.into(), sh.into(), zigzag(u), next))
        }
        _ => None,
    }
}

impl<'a> PcaSplineCodec<'a> {
    /// Validates the section against the header's channel and frame counts.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize, frames: u32) -> Result<Self, Error> {
        let truncated = malformed("section truncated");
        let mut r = Reader::new(bytes);
        let wide = match r.u8().ok_or(truncated)? {
            1 => false,
            2 => true,
            _ => return Err(malformed("index width must be 1 or 2")),
        };
        if !wide && channels > 256 {
            return Err(malformed("1-byte indices for more than 256 channels"));
        }
        let group_count = r.varint_u32().ok_or(truncated)?;
        let groups_at = r.pos();
        let mut covered: u64 = 0;
        for _ in 0..group_count {
            let n = r.varint_u32().ok_or(truncated)?;
            if n == 0 {
                return Err(malformed("empty group"));
            }
            covered = covered.wrapping_add(u64::from(n));
            check_indices(&mut r, n, wide, channels)?;
        }
        let groups = bytes.get(groups_at..r.pos()).ok_or(truncated)?;
        let const_count = r.varint_u32().ok_or(truncated)?;
        let consts_at = r.pos();
        check_indices(&mut r, const_count, wide, channels)?;
        for _ in 0..const_count {
            r.zigzag_i32().ok_or(truncated)?;
        }
        let consts = bytes.get(consts_at..r.pos()).ok_or(truncated)?;
        covered = covered.wrapping_add(u64::from(const_count));
        if covered != channels as u64 {
            return Err(malformed(
                "groups and constants do not cover every channel once",
            ));
        }
        let segment_count = r.varint_u32().ok_or(truncated)?;
        let segments = bytes.get(r.pos()..).unwrap_or(&[]);
        let codec = PcaSplineCodec {
            channels,
            wide,
            group_count,
            groups,
            const_count,
            consts,
            segments,
        };
        codec.check_disjoint()?;
        codec.check_segments(segment_count, frames)?;
        Ok(codec)
    }

    /// Channel list `i` (groups first, then the constants) as an index
    /// iterator.
    fn list(&self, i: usize) -> Indices<'a> {
        let mut r = Reader::new(self.groups);
        for g in 0..self.group_count as usize {
            let n = r.varint_u32().unwrap_or(0) as usize;
            let bytes = r.take(n.wrapping_mul(self.width())).unwrap_or(&[]);
            if g == i {
                return Indices::new(bytes, self.wide);
            }
        }
        let mut c = Reader::new(self.consts);
        let bytes = c
            .take((self.const_count as usize).wrapping_mul(self.width()))
            .unwrap_or(&[]);
        Indices::new(bytes, self.wide)
    }

    fn width(&self) -> usize {
        if self.wide {
            2
        } else {
            1
        }
    }

    /// Decodes the pose at `pos` (frames, 16.16; at most the last frame)
    /// into `out`. `cursor` remembers the segment and the patch scan for the
    /// next call; `cache` (any length, its content is the decoder's own)
    /// keeps each group's record offset and current key interval (control
    /// points, tangent ratios) so that a pose inside an interval reads no
    /// bits and parses no varint (§6: the output never depends on it).
    /// `None` only if an invariant of the validated section is broken.
    pub(crate) fn decode_at(
        &self,
        pos: u64,
        cursor: &mut Cursor<'a>,
        out: &mut [i32],
        cache: &mut [i32],
    ) -> Option<()> {
        let frame = u32::try_from(pos >> FRAC_BITS).unwrap_or(u32::MAX);
        let cur = self.locate(frame, cursor)?;
        self.eval(&cur, pos, out, cache)?;
        // A blend window (§5.2) around the start of `cur` or of the next
        // segment: blend the other segment's values into `out`.
        if cursor
            .prev_end
            .is_some_and(|e| pos < (u64::from(e) + 1) << FRAC_BITS)
        {
            if let Some(prev) = cursor.previous.and_then(|p| self.segment_at(p)) {
                self.blend(&prev, &cur, pos, false, out);
            }
        } else if cursor
            .next_start
            .is_some_and(|s| pos > u64::from(s.saturating_sub(1)) << FRAC_BITS)
        {
            if let Some(next) = self.segment_at(cur.next) {
                self.blend(&cur, &next, pos, true, out);
            }
        }
        // Patches at the two frames around pos, each weighted by its hat
        // function (§5.5).
        let one = 1i64 << FRAC_BITS;
        let frac = (pos & ((1 << FRAC_BITS) - 1)) as i64;
        let rel = frame.wrapping_sub(cur.start);
        cursor.patch = self.patches_at(&cur, cursor.patch, rel, one.wrapping_sub(frac), out);
        if frac > 0 {
            let after = frame.saturating_add(1);
            if cursor.next_start == Some(after) {
                if let Some(next) = self.segment_at(cur.next) {
                    self.patches_at(&next, PatchScan::default(), 0, frac, out);
                }
            } else {
                cursor.patch = self.patches_at(&cur, cursor.patch, rel.wrapping_add(1), frac, out);
            }
        }
        Some(())
    }
}
