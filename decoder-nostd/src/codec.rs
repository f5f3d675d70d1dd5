//! The `index` codec (SPEC.md §4): low-resolution model-based indexing
//! after Chattopadhyay, Bhandarkar & Li (2007). Each channel value is a
//! small index into a table held in the bitstream (so in flash); decoding is
//! one table look-up per channel, plus an addition in delta frames.

use crate::bits::BitReader;
use crate::consts::index::{DESCRIPTOR_LEN, FLAG_ACCUMULATE, MAX_BITS, MAX_SHIFT, SHIFT_MASK};
use crate::error::Error;
use crate::reader::Reader;

/// Flag bits that must be zero in descriptor byte 1.
const RESERVED_FLAGS: u8 = !(FLAG_ACCUMULATE | SHIFT_MASK);

/// A validated view of an `index` codec section.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IndexCodec<'a> {
    key_interval: u32,
    key_desc: &'a [u8],
    delta_desc: &'a [u8],
    table: &'a [u8],
    payload: &'a [u8],
    key_bits: u64,
    delta_bits: u64,
}

impl<'a> IndexCodec<'a> {
    /// Validates the section against the header's channel and frame counts.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize, frames: u32) -> Result<Self, Error> {
        let malformed = |rule| Error::IndexMalformed { rule };
        let mut r = Reader::new(bytes);
        let key_interval = u32::from(r.u16_le().ok_or(malformed("section shorter than 8 bytes"))?);
        let count = usize::from(r.u16_le().ok_or(malformed("section shorter than 8 bytes"))?);
        let table_len = r.u32_le().ok_or(malformed("section shorter than 8 bytes"))?;
        if count != channels {
            return Err(malformed("channel count differs from the header"));
        }
        let desc_len = channels
            .checked_mul(DESCRIPTOR_LEN)
            .ok_or(malformed("descriptor table too large"))?;
        let key_desc = r.take(desc_len).ok_or(malformed("descriptors truncated"))?;
        let delta_desc = if key_interval > 0 {
            r.take(desc_len).ok_or(malformed("delta descriptors truncated"))?
        } else {
            &[]
        };
        let table_bytes = usize::try_from(table_len)
            .ok()
            .and_then(|n| n.checked_mul(2))
            .ok_or(malformed("table too large"))?;
        let table = r.take(table_bytes).ok_or(malformed("table truncated"))?;
        let payload = r.rest();
        let key_bits = check_descriptors(key_desc, table_len, false)?;
        let delta_bits = check_descriptors(delta_desc, table_len, true)?;
        let codec = IndexCodec {
            key_interval,
            key_desc,
            delta_desc,
            table,
            payload,
            key_bits,
            delta_bits,
        };
        let needed_bits = codec.frame_bit_offset(frames);
        let available_bits = (payload.len() as u64) * 8;
        if needed_bits.div_ceil(8) != payload.len() as u64 {
            return Err(Error::IndexPayloadTruncated {
                needed_bits,
                available_bits,
            });
        }
        Ok(codec)
    }

    /// True when frame `i` is coded with absolute (key) descriptors.
    pub(crate) fn is_key(&self, frame: u32) -> bool {
        self.key_interval == 0 || frame.is_multiple_of(self.key_interval)
    }

    /// The key frame at or before `frame`.
    pub(crate) fn key_before(&self, frame: u32) -> u32 {
        if self.key_interval == 0 {
            frame
        } else {
            frame - frame % self.key_interval
        }
    }

    /// Bit offset of frame `i`'s record in the payload (§4.4).
    fn frame_bit_offset(&self, frame: u32) -> u64 {
        let keys = if self.key_interval == 0 {
            u64::from(frame)
        } else {
            u64::from(frame).div_ceil(u64::from(self.key_interval))
        };
        let deltas = u64::from(frame) - keys;
        keys * self.key_bits + deltas * self.delta_bits
    }

    /// Decodes frame `frame` into `state`, which must hold frame `frame - 1`
    /// when `frame` is a delta frame (§4.3).
    #[inline]
    pub(crate) fn decode_frame(&self, frame: u32, state: &mut [i32]) {
        let desc = if self.is_key(frame) {
            self.key_desc
        } else {
            self.delta_desc
        };
        let mut bits = BitReader::at(self.payload, self.frame_bit_offset(frame));
        let table = self.table;
        for (d, value) in desc.chunks_exact(DESCRIPTOR_LEN).zip(state.iter_mut()) {
            let Ok(d) = <&[u8; DESCRIPTOR_LEN]>::try_from(d) else {
                continue;
            };
            // Bytes 0-3 as one word: width | shift+flags << 8 | table << 16.
            let word = u32::from_le_bytes([d[0], d[1], d[2], d[3]]);
            let base = i32::from_le_bytes([d[4], d[5], d[6], d[7]]);
            let idx = bits.read(word & 0xFF);
            let at = (((word >> 16) + idx) as usize) * 2;
            let entry = match table.get(at..at + 2) {
                Some(&[lo, hi]) => i16::from_le_bytes([lo, hi]),
                _ => 0,
            };
            let v = base.wrapping_add(i32::from(entry) << ((word >> 8) & u32::from(SHIFT_MASK)));
            // All ones when the accumulate flag (bit 15 of the word) is set.
            let keep = ((word << 16) as i32) >> 31;
            *value = v.wrapping_add(*value & keep);
        }
    }
}

/// Checks every descriptor of one set (§4.2) and returns the bits one frame
/// record of that set needs.
fn check_descriptors(desc: &[u8], table_len: u32, delta: bool) -> Result<u64, Error> {
    let mut total = 0u64;
    for (channel, d) in desc.chunks_exact(DESCRIPTOR_LEN).enumerate() {
        let bad = Error::IndexDescriptor {
            channel: channel as u32,
        };
        let [width, shift_flags, o0, o1, ..] = *d else {
            return Err(bad);
        };
        let shift = shift_flags & SHIFT_MASK;
        let accumulate = shift_flags & FLAG_ACCUMULATE != 0;
        if width > MAX_BITS
            || shift > MAX_SHIFT
            || shift_flags & RESERVED_FLAGS != 0
            || (accumulate && !delta)
        {
            return Err(bad);
        }
        let end = u32::from(u16::from_le_bytes([o0, o1])) + (1u32 << width);
        if end > table_len {
            return Err(bad);
        }
        total += u64::from(width);
    }
    Ok(total)
}
