//! The `index` codec's fast layout (SPEC.md §4.6): the same model as §4 —
//! a small index per coded channel into a table — laid out for the fewest
//! instructions per channel. Tables hold final `i32` values (one load per
//! look-up, no shift and no base); index widths are 0, 1, 2, 4, 8 or 16
//! bits, so a group's fields are read from whole bytes with constant shifts;
//! each group's fields start on a byte, so a group needs no bit cursor;
//! a channel's table is found by its position in its group (no per-channel
//! table offset); a channel's only descriptor is its place in the state.

use crate::consts::index::{FAST_GROUP_HEADER_LEN, FLAG_ACCUMULATE};
use crate::error::Error;
use crate::reader::Reader;

/// Flag bits that must be zero in a fast group header's byte 1.
const RESERVED_FLAGS: u8 = !FLAG_ACCUMULATE;

/// A validated view of an `index` section in the fast layout.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FastIndexCodec<'a> {
    key_interval: u32,
    key_set: &'a [u8],
    delta_set: &'a [u8],
    payload: &'a [u8],
    /// Bytes of a key frame's record.
    key_bytes: u32,
    /// Bytes of a delta frame's record.
    delta_bytes: u32,
}

/// What validating one set yields.
struct SetInfo<'a> {
    bytes: &'a [u8],
    record: u64,
    entries: u64,
}

impl<'a> FastIndexCodec<'a> {
    /// Validates the section against the header's channel and frame counts.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize, frames: u32) -> Result<Self, Error> {
        let malformed = |rule| Error::IndexMalformed { rule };
        let short = malformed("section shorter than 4 bytes");
        let mut r = Reader::new(bytes);
        let key_interval = u32::from(r.u16_le().ok_or(short)?);
        let count = usize::from(r.u16_le().ok_or(short)?);
        if count != channels {
            return Err(malformed("channel count differs from the header"));
        }
        let key = check_set(&mut r, channels)?;
        if key.entries < channels as u64 {
            return Err(malformed("key set has fewer entries than channels"));
        }
        let delta = if key_interval > 0 {
            check_set(&mut r, channels)?
        } else {
            SetInfo {
                bytes: &[],
                record: 0,
                entries: 0,
            }
        };
        let payload = r.rest();
        let codec = FastIndexCodec {
            key_interval,
            key_set: key.bytes,
            delta_set: delta.bytes,
            payload,
            key_bytes: u32::try_from(key.record).map_err(|_| malformed("record too long"))?,
            delta_bytes: u32::try_from(delta.record).map_err(|_| malformed("record too long"))?,
        };
        let needed = codec.frame_offset(frames);
        if needed != payload.len() as u64 {
            return Err(Error::IndexPayloadTruncated {
                needed_bits: needed.saturating_mul(8),
                available_bits: (payload.len() as u64).saturating_mul(8),
            });
        }
        Ok(codec)
    }

    /// The key frame at or before `frame`.
    pub(crate) fn key_before(&self, frame: u32) -> u32 {
        if self.key_interval == 0 {
            frame
        } else {
            #[allow(clippy::arithmetic_side_effects)] // key_interval > 0 here
            let r = frame % self.key_interval;
            frame.wrapping_sub(r)
        }
    }

    /// Key frames before frame `i` (§4.4's `keys(i)`), and whether `i`
    /// is one.
    #[inline(always)]
    fn keys_before(&self, frame: u32) -> (u32, bool) {
        match frame.checked_div(self.key_interval) {
            None => (frame, true),
            Some(q) => {
                let r = frame.wrapping_sub(q.wrapping_mul(self.key_interval));
                (q.wrapping_add(u32::from(r != 0)), r == 0)
            }
        }
    }

    /// Byte offset of frame `i`'s record in the payload (§4.6), given
    /// `keys` = `keys(i)`.
    #[inline(always)]
    fn offset(&self, frame: u32, keys: u32) -> u64 {
        let deltas = frame.wrapping_sub(keys);
        u64::from(keys)
            .wrapping_mul(u64::from(self.key_bytes))
            .wrapping_add(u64::from(deltas).wrapping_mul(u64::from(self.delta_bytes)))
    }

    /// Byte offset of frame `i`'s record in the payload (§4.6).
    fn frame_offset(&self, frame: u32) -> u64 {
        self.offset(frame, self.keys_before(frame).0)
    }

    /// Decodes frame `frame` into `state`, which must hold frame `frame - 1`
    /// when `frame` is a delta frame. `None` (with `state` partly written)
    /// only if an invariant of the validated section is broken.
    #[inline(never)]
    pub(crate) fn decode_frame(&self, frame: u32, state: &mut [i32]) -> Option<()> {
        let (keys, key) = self.keys_before(frame);
        let set = if key {
            state.fill(0);
            self.key_set
        } else {
            self.delta_set
        };
        let start = usize::try_from(self.offset(frame, keys)).ok()?;
        decode_set(set, self.payload.get(start..)?, state)
    }
}

/// Applies the groups of `set` to `state` with the record at the start of
/// `record` (§4.6).
#[inline(never)]
fn decode_set(set: &[u8], mut record: &[u8], state: &mut [i32]) -> Option<()> {
    let (groups, mut set) = set.split_first_chunk::<2>()?;
    for _ in 0..u16::from_le_bytes(*groups) {
        let (&[width, flags, c0, c1, s0, s1], rest) =
            set.split_first_chunk::<FAST_GROUP_HEADER_LEN>()?;
        let count = usize::from(u16::from_le_bytes([c0, c1]));
        let stride = usize::from(u16::from_le_bytes([s0, s1]));
        let (dsts, rest) = rest.split_at_checked(count.wrapping_mul(2))?;
        let (table, rest) = rest.split_at_checked(table_len(count, stride)?)?;
        set = rest;
        let (block, rest) = record.split_at_checked(block_len(count, width))?;
        record = rest;
        let g = Group {
            dsts: dsts.as_chunks::<2>().0,
            table: table.as_chunks::<4>().0,
            stride,
        };
        if flags & FLAG_ACCUMULATE != 0 {
            g.decode::<true>(width, block, state);
        } else {
            g.decode::<false>(width, block, state);
        }
    }
    Some(())
}

/// Bytes of a group's table: `count · stride` entries of 4 bytes.
fn table_len(count: usize, stride: usize) -> Option<usize> {
    count.checked_mul(stride)?.checked_mul(4)
}

/// Bytes of a group's fields in a record: `ceil(count · width / 8)`.
fn block_len(count: usize, width: u8) -> usize {
    count
        .wrapping_mul(usize::from(width))
        .wrapping_add(7)
        .wrapping_div(8)
}

/// One group of a set, its bytes split.
struct Group<'a> {
    /// Destinations, `u16` each.
    dsts: &'a [[u8; 2]],
    /// Tables, `i32` entries, `stride` per channel.
    table: &'a [[u8; 4]],
    stride: usize,
}

impl Group<'_> {
    /// One function per width and flag, out of line: each loop gets the
    /// registers to itself, and its shifts and masks are constants.
    #[inline(always)]
    fn decode<const ACC: bool>(&self, width: u8, block: &[u8], state: &mut [i32]) {
        match width {
            0 => self.constant::<ACC>(state),
            1 => self.narrow::<1, 8, 2, ACC>(block, state),
            2 => self.narrow::<2, 4, 4, ACC>(block, state),
            4 => self.narrow::<4, 2, 16, ACC>(block, state),
            8 => self.bytes::<1, ACC>(block, state),
            _ => self.bytes::<2, ACC>(block, state),
        }
    }

    /// Width 0: every channel's value is its one table entry.
    #[inline(never)]
    fn constant<const ACC: bool>(&self, state: &mut [i32]) {
        for (d, e) in self.dsts.iter().zip(self.table) {
            apply::<ACC>(*d, i32::from_le_bytes(*e), state);
        }
    }

    /// Widths `W` of 1, 2 and 4: `PER = 8 / W` fields per byte, LSB first,
    /// and tables of exactly `T = 2^W` entries, so a masked index is always
    /// inside its channel's table.
    #[inline(never)]
    fn narrow<const W: u32, const PER: usize, const T: usize, const ACC: bool>(
        &self,
        block: &[u8],
        state: &mut [i32],
    ) {
        let mask = (1u32 << W).wrapping_sub(1);
        let (dsts, dtail) = self.dsts.as_chunks::<PER>();
        let (tables, ttail) = self.table.as_chunks::<T>().0.as_chunks::<PER>();
        for ((dc, tc), &b) in dsts.iter().zip(tables).zip(block) {
            let b = u32::from(b);
            for (j, (d, t)) in dc.iter().zip(tc).enumerate() {
                let i = (b >> (j as u32).wrapping_mul(W)) & mask;
                if let Some(e) = t.get(i as usize) {
                    apply::<ACC>(*d, i32::from_le_bytes(*e), state);
                }
            }
        }
        let btail = block.get(dsts.len()..).unwrap_or(&[]);
        if let Some(&b) = btail.first() {
            let b = u32::from(b);
            for (j, (d, t)) in dtail.iter().zip(ttail).enumerate() {
                let i = (b >> (j as u32).wrapping_mul(W)) & mask;
                if let Some(e) = t.get(i as usize) {
                    apply::<ACC>(*d, i32::from_le_bytes(*e), state);
                }
            }
        }
    }

    /// Widths 8 and 16: one field per `B` bytes, little-endian, and tables
    /// of `stride` entries; an index past its table changes nothing.
    #[inline(never)]
    fn bytes<const B: usize, const ACC: bool>(&self, block: &[u8], state: &mut [i32]) {
        let tables = self.table.chunks_exact(self.stride.max(1));
        for ((d, f), t) in self.dsts.iter().zip(block.as_chunks::<B>().0).zip(tables) {
            let i = match f.as_slice() {
                [lo, hi] => usize::from(u16::from_le_bytes([*lo, *hi])),
                [lo] => usize::from(*lo),
                _ => 0,
            };
            if let Some(e) = t.get(i) {
                apply::<ACC>(*d, i32::from_le_bytes(*e), state);
            }
        }
    }
}

/// Stores (or adds, `ACC`) `v` into the channel `d` names.
#[inline(always)]
fn apply<const ACC: bool>(d: [u8; 2], v: i32, state: &mut [i32]) {
    if let Some(s) = state.get_mut(usize::from(u16::from_le_bytes(d))) {
        *s = if ACC { s.wrapping_add(v) } else { v };
    }
}

/// Checks one set (§4.6) and returns its bytes, the bytes one record of it
/// needs and its number of entries.
fn check_set<'a>(r: &mut Reader<'a>, channels: usize) -> Result<SetInfo<'a>, Error> {
    let start = r.clone();
    let truncated = Error::IndexMalformed {
        rule: "set truncated",
    };
    let groups = r.u16_le().ok_or(truncated)?;
    let (mut record, mut entries, mut len) = (0u64, 0u64, 2usize);
    for _ in 0..groups {
        let Some(&[width, flags, c0, c1, s0, s1]) = r.take(FAST_GROUP_HEADER_LEN) else {
            return Err(truncated);
        };
        let count = usize::from(u16::from_le_bytes([c0, c1]));
        let stride = u32::from(u16::from_le_bytes([s0, s1]));
        let stride_ok = match width {
            0 => stride == 1,
            1 | 2 | 4 => stride == 1u32 << width,
            8 | 16 => stride >= 1 && stride <= 1u32 << width,
            _ => false,
        };
        if !stride_ok || flags & RESERVED_FLAGS != 0 {
            return Err(Error::IndexMalformed {
                rule: "invalid group header",
            });
        }
        let dsts = r.take(count.wrapping_mul(2)).ok_or(truncated)?;
        let table = table_len(count, stride as usize).ok_or(truncated)?;
        r.take(table).ok_or(truncated)?;
        for d in dsts.chunks_exact(2) {
            if let &[d0, d1] = d {
                let channel = u16::from_le_bytes([d0, d1]);
                if usize::from(channel) >= channels {
                    return Err(Error::IndexDescriptor {
                        channel: u32::from(channel),
                    });
                }
            }
        }
        record = record.wrapping_add(block_len(count, width) as u64);
        entries = entries.wrapping_add(count as u64);
        len = len
            .wrapping_add(FAST_GROUP_HEADER_LEN)
            .wrapping_add(dsts.len())
            .wrapping_add(table);
    }
    let bytes = start.clone().take(len).ok_or(truncated)?;
    Ok(SetInfo {
        bytes,
        record,
        entries,
    })
}
