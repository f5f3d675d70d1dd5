//! Wire primitives shared by the decoder and the encoder (SPEC.md §2.3,
//! §3.1): postcard's varint and zigzag, and the CRC-32 of the container.
//! Public for the encoder only (`#[doc(hidden)]`, outside semver): it
//! writes with exactly the parameters this module reads with.

/// The CRC of SPEC.md §2.3: CRC-32/ISO-HDLC (the zlib/PNG CRC; polynomial
/// `0x04C11DB7` reflected, init and xorout `0xFFFFFFFF`).
pub const CRC_ALGORITHM: &crc::Algorithm<u32> = &crc::CRC_32_ISO_HDLC;

/// [`CRC_ALGORITHM`] with a 1 KB table in flash (the `crc-table` feature):
/// about six times faster than the bitwise form, which costs no table.
const CRC32: crc::Crc<u32, CrcImpl> = crc::Crc::<u32, CrcImpl>::new(CRC_ALGORITHM);

/// The CRC-32 of `bytes` (SPEC.md §2.3).
pub fn crc32(bytes: &[u8]) -> u32 {
    CRC32.checksum(bytes)
}

/// [`crc32`] over bytes given piece by piece.
pub struct Crc32Digest(crc::Digest<'static, u32, CrcImpl>);

#[cfg(feature = "crc-table")]
type CrcImpl = crc::Table<1>;
#[cfg(not(feature = "crc-table"))]
type CrcImpl = crc::NoTable;

impl Crc32Digest {
    /// An empty digest.
    pub fn new() -> Self {
        Crc32Digest(CRC32.digest())
    }

    /// Adds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        self.0.update(bytes);
    }

    /// The CRC of everything added.
    pub fn finalize(self) -> u32 {
        self.0.finalize()
    }
}

impl Default for Crc32Digest {
    fn default() -> Self {
        Self::new()
    }
}

/// Zigzag: `i32` to the `u32` a varint carries (`(n << 1) ^ (n >> 31)`).
#[inline(always)]
pub const fn zigzag_encode(v: i32) -> u32 {
    (v.wrapping_shl(1) ^ (v >> 31)) as u32
}

/// The inverse of [`zigzag_encode`].
#[inline(always)]
pub const fn zigzag_decode(u: u32) -> i32 {
    ((u >> 1) as i32) ^ (0i32.wrapping_sub((u & 1) as i32))
}

/// Most bytes of a `u32` varint.
pub const VARINT_MAX_LEN: usize = 5;

/// The `u32` varint (LEB128, postcard's `varint(u32)`) at byte `at` of
/// `bytes` and the offset after it. At most [`VARINT_MAX_LEN`] bytes, the
/// fifth at most `0x0F`; over-long forms within that are accepted, as
/// postcard accepts them (SPEC.md §3.1's canonical-vs-accepted table).
#[inline]
pub fn varint_u32(bytes: &[u8], at: usize) -> Option<(u32, usize)> {
    // One-byte values (most lengths, counts and small numbers) first.
    if let Some(&b) = bytes.get(at) {
        if b < 0x80 {
            return Some((u32::from(b), at.wrapping_add(1)));
        }
    }
    varint_long(bytes, at)
}

/// [`varint_u32`] with its two- and three-byte forms read without a loop
/// too, for hot paths whose varints are often that long (the `pca-spline`
/// component offsets); the same values, the same rules.
#[inline(always)]
pub fn varint_u32_unrolled(bytes: &[u8], at: usize) -> Option<(u32, usize)> {
    match *bytes.get(at..)? {
        [b, ..] if b < 0x80 => Some((u32::from(b), at.wrapping_add(1))),
        [b, b2, ..] if b2 < 0x80 => {
            let u = u32::from(b & 0x7F) | u32::from(b2) << 7;
            Some((u, at.wrapping_add(2)))
        }
        [b, b2, b3, ..] if b3 < 0x80 => {
            let u = u32::from(b & 0x7F) | u32::from(b2 & 0x7F) << 7 | u32::from(b3) << 14;
            Some((u, at.wrapping_add(3)))
        }
        _ => varint_long(bytes, at),
    }
}

/// [`varint_u32`] of any length, out of line: the one-byte fast path stays
/// small where it is inlined.
#[inline(never)]
fn varint_long(bytes: &[u8], at: usize) -> Option<(u32, usize)> {
    varint_u32_any(bytes, at)
}

/// [`varint_u32`] as one loop, inlined: for a caller's own out-of-line
/// slow path (the decoder's `Reader`), which then needs no second call.
#[inline(always)]
pub(crate) fn varint_u32_any(bytes: &[u8], at: usize) -> Option<(u32, usize)> {
    let mut value: u32 = 0;
    for (i, &b) in (0u32..).zip(bytes.get(at..)?.iter().take(VARINT_MAX_LEN)) {
        let chunk = u32::from(b & 0x7F);
        if i == 4 && chunk > 0x0F {
            return None;
        }
        value |= chunk << i.wrapping_mul(7);
        if b & 0x80 == 0 {
            return Some((value, at.wrapping_add(i as usize).wrapping_add(1)));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn zigzag_round_trips() {
        for (v, u) in [(0, 0), (-1, 1), (1, 2), (-2, 3), (i32::MAX, u32::MAX - 1)] {
            assert_eq!(zigzag_encode(v), u);
            assert_eq!(zigzag_decode(u), v);
        }
        assert_eq!(zigzag_decode(u32::MAX), i32::MIN);
    }

    #[test]
    fn unrolled_varint_agrees() {
        let cases: [&[u8]; 8] = [
            &[0x00],
            &[0x7F, 0x01],
            &[0xAC, 0x02],
            &[0xFF, 0xFF, 0x7F],
            &[0x80, 0x80, 0x80, 0x01],
            &[0xFF, 0xFF, 0xFF, 0xFF, 0x0F],
            &[0xFF, 0xFF, 0xFF, 0xFF, 0x10],
            &[0x80, 0x80],
        ];
        for bytes in cases {
            for at in 0..bytes.len() {
                assert_eq!(varint_u32_unrolled(bytes, at), varint_u32(bytes, at));
            }
        }
    }

    #[test]
    fn varint_lengths() {
        assert_eq!(varint_u32(&[0x7F], 0), Some((127, 1)));
        assert_eq!(varint_u32(&[9, 0x80, 0x01], 1), Some((128, 3)));
        assert_eq!(varint_u32(&[0xFF, 0xFF, 0x7F], 0), Some((0x1F_FFFF, 3)));
        assert_eq!(varint_u32(&[0x80, 0x80, 0x80, 0x01], 0), Some((1 << 21, 4)));
        assert_eq!(varint_u32(&[0x7F], 1), None);
    }
}
