//! The `index` codec (SPEC.md §4): low-resolution model-based indexing
//! after Chattopadhyay, Bhandarkar & Li (2007). Each channel value is a
//! small index into a table held in the bitstream (so in flash); decoding is
//! one table look-up per coded channel, plus an addition in delta frames.
//!
//! Channels are coded in *groups* that share an index width, a shift and
//! the accumulate flag, so the inner loop has no per-channel parameters but
//! a table offset and a base; channels that do not change in delta frames
//! are simply absent from the delta set and cost nothing there.

use crate::bits::BitReader;
use crate::consts::index::{
    ENTRY_LEN, FLAG_ACCUMULATE, GROUP_HEADER_LEN, MAX_BITS, MAX_SHIFT, SHIFT_MASK,
};
use crate::error::Error;
use crate::reader::Reader;

/// Flag bits that must be zero in group header byte 1.
const RESERVED_FLAGS: u8 = !(FLAG_ACCUMULATE | SHIFT_MASK);

/// A validated view of an `index` codec section.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IndexCodec<'a> {
    key_interval: u32,
    key_set: &'a [u8],
    delta_set: &'a [u8],
    table: &'a [u8],
    payload: &'a [u8],
    key_bits: u64,
    delta_bits: u64,
}

/// What validating one set (§4.2) yields.
struct SetInfo<'a> {
    bytes: &'a [u8],
    bits: u64,
    entries: u64,
}

impl<'a> IndexCodec<'a> {
    /// Validates the section against the header's channel and frame counts.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize, frames: u32) -> Result<Self, Error> {
        let malformed = |rule| Error::IndexMalformed { rule };
        let short = malformed("section shorter than 8 bytes");
        let mut r = Reader::new(bytes);
        let key_interval = u32::from(r.u16_le().ok_or(short)?);
        let count = usize::from(r.u16_le().ok_or(short)?);
        let table_len = r.u32_le().ok_or(short)?;
        if count != channels {
            return Err(malformed("channel count differs from the header"));
        }
        let key = check_set(&mut r, channels, table_len)?;
        // One entry per channel, or several accumulating levels (§4.5).
        if key.entries < channels as u64 {
            return Err(malformed("key set has fewer entries than channels"));
        }
        let delta = if key_interval > 0 {
            check_set(&mut r, channels, table_len)?
        } else {
            SetInfo {
                bytes: &[],
                bits: 0,
                entries: 0,
            }
        };
        let table_bytes = usize::try_from(table_len)
            .ok()
            .and_then(|n| n.checked_mul(2))
            .ok_or(malformed("table too large"))?;
        let table = r.take(table_bytes).ok_or(malformed("table truncated"))?;
        let payload = r.rest();
        let codec = IndexCodec {
            key_interval,
            key_set: key.bytes,
            delta_set: delta.bytes,
            table,
            payload,
            key_bits: key.bits,
            delta_bits: delta.bits,
        };
        let needed_bits = codec.frame_bit_offset(frames);
        let available_bits = (payload.len() as u64).wrapping_mul(8);
        if needed_bits.div_ceil(8) != payload.len() as u64 {
            return Err(Error::IndexPayloadTruncated {
                needed_bits,
                available_bits,
            });
        }
        Ok(codec)
    }

    /// True when frame `i` is a key frame.
    pub(crate) fn is_key(&self, frame: u32) -> bool {
        self.key_interval == 0 || frame.is_multiple_of(self.key_interval)
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

    /// Bit offset of frame `i`'s record in the payload (§4.4).
    fn frame_bit_offset(&self, frame: u32) -> u64 {
        let keys = if self.key_interval == 0 {
            u64::from(frame)
        } else {
            u64::from(frame).div_ceil(u64::from(self.key_interval))
        };
        let deltas = u64::from(frame).wrapping_sub(keys);
        keys.wrapping_mul(self.key_bits)
            .wrapping_add(deltas.wrapping_mul(self.delta_bits))
    }

    /// Decodes frame `frame` into `state`, which must hold frame `frame - 1`
    /// when `frame` is a delta frame (§4.3). `None` (with `state` partly
    /// written) only if an invariant of the validated section is broken.
    pub(crate) fn decode_frame(&self, frame: u32, state: &mut [i32]) -> Option<()> {
        let set = if self.is_key(frame) {
            // A key frame defines every channel from scratch (§4.3).
            state.fill(0);
            self.key_set
        } else {
            self.delta_set
        };
        let mut bits = BitReader::at(self.payload, self.frame_bit_offset(frame));
        let mut r = Reader::new(set);
        let groups = r.u16_le().unwrap_or(0);
        for _ in 0..groups {
            let Some(&[width, shift_flags, c0, c1]) = r.take(GROUP_HEADER_LEN) else {
                return None;
            };
            let count = usize::from(u16::from_le_bytes([c0, c1]));
            let entries = r.take(count.saturating_mul(ENTRY_LEN))?;
            let width = u32::from(width);
            let shift = u32::from(shift_flags & SHIFT_MASK);
            // Two copies of the loop so the accumulate test is per group,
            // not per channel.
            if shift_flags & FLAG_ACCUMULATE != 0 {
                decode_group::<true>(entries, self.table, &mut bits, width, shift, state);
            } else {
                decode_group::<false>(entries, self.table, &mut bits, width, shift, state);
            }
        }
        Some(())
    }
}

/// The inner loop: one index, one table look-up, one store per entry.
#[inline(always)]
fn decode_group<const ACCUMULATE: bool>(
    entries: &[u8],
    table: &[u8],
    bits: &mut BitReader<'_>,
    width: u32,
    shift: u32,
    state: &mut [i32],
) {
    for e in entries.chunks_exact(ENTRY_LEN) {
        let Ok(e) = <&[u8; ENTRY_LEN]>::try_from(e) else {
            continue;
        };
        // Bytes 0-3 as one word: channel | table offset << 16.
        let word = u32::from_le_bytes([e[0], e[1], e[2], e[3]]);
        let base = i32::from_le_bytes([e[4], e[5], e[6], e[7]]);
        let idx = bits.read(width);
        let at = ((word >> 16).wrapping_add(idx) as usize).wrapping_mul(2);
        let entry = match table
            .get(at..at.wrapping_add(2))
            .and_then(|s| <[u8; 2]>::try_from(s).ok())
        {
            Some(pair) => i16::from_le_bytes(pair),
            None => 0,
        };
        let v = base.wrapping_add(i32::from(entry) << shift);
        if let Some(s) = state.get_mut((word & 0xFFFF) as usize) {
            *s = if ACCUMULATE { s.wrapping_add(v) } else { v };
        }
    }
}

/// Checks one set (§4.2) and returns its bytes, the bits one record of it
/// needs and its number of entries.
fn check_set<'a>(
    r: &mut Reader<'a>,
    channels: usize,
    table_len: u32,
) -> Result<SetInfo<'a>, Error> {
    let start = r.clone();
    let truncated = Error::IndexMalformed {
        rule: "set truncated",
    };
    let groups = r.u16_le().ok_or(truncated)?;
    let (mut bits, mut entries, mut len) = (0u64, 0u64, 2usize);
    for _ in 0..groups {
        let Some(&[width, shift_flags, c0, c1]) = r.take(GROUP_HEADER_LEN) else {
            return Err(truncated);
        };
        let count = usize::from(u16::from_le_bytes([c0, c1]));
        let body = r.take(count * ENTRY_LEN).ok_or(truncated)?;
        if width > MAX_BITS
            || shift_flags & SHIFT_MASK > MAX_SHIFT
            || shift_flags & RESERVED_FLAGS != 0
        {
            return Err(Error::IndexMalformed {
                rule: "invalid group header",
            });
        }
        for e in body.chunks_exact(ENTRY_LEN) {
            let [ch0, ch1, o0, o1, ..] = *e else {
                return Err(truncated);
            };
            let channel = u16::from_le_bytes([ch0, ch1]);
            let end = u32::from(u16::from_le_bytes([o0, o1])).wrapping_add(1u32 << width);
            if usize::from(channel) >= channels || end > table_len {
                return Err(Error::IndexDescriptor {
                    channel: u32::from(channel),
                });
            }
        }
        bits = bits.wrapping_add(u64::from(width).wrapping_mul(count as u64));
        entries = entries.wrapping_add(count as u64);
        len = len.wrapping_add(GROUP_HEADER_LEN.wrapping_add(body.len()));
    }
    let bytes = start.clone().take(len).ok_or(truncated)?;
    Ok(SetInfo {
        bytes,
        bits,
        entries,
    })
}
