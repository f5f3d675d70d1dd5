//! LSB-first bit reading over a byte slice (SPEC.md §4.4): the sequential
//! [`BitReader`] and the random-access [`bits_at`] (the `pca-spline` key
//! rows). Bits past the end of the slice read as zero, so a read can never
//! go out of bounds; the codecs check payload lengths up front so that
//! never happens on a validated clip.

#[derive(Clone, Debug)]
pub(crate) struct BitReader<'a> {
    /// The bytes not yet in `acc`.
    rest: &'a [u8],
    acc: u32,
    avail: u32,
}

impl<'a> BitReader<'a> {
    /// A reader positioned at absolute bit `bit` of `bytes`.
    pub(crate) fn at(bytes: &'a [u8], bit: u64) -> Self {
        let byte = usize::try_from(bit / 8).unwrap_or(usize::MAX);
        let mut r = BitReader {
            rest: bytes.get(byte..).unwrap_or(&[]),
            acc: 0,
            avail: 0,
        };
        let skip = (bit % 8) as u32;
        r.read(skip);
        r
    }

    /// Reads `n` bits, `n <= 15` (larger `n` are reduced modulo 16), first
    /// bit in the result's bit 0. One 16-bit refill at most per read keeps
    /// the hot path to a compare, a mask and two shifts.
    #[inline(always)]
    pub(crate) fn read(&mut self, n: u32) -> u32 {
        let n = n & 15;
        if self.avail < 16 {
            let half = match *self.rest {
                [lo, hi, ref rest @ ..] => {
                    self.rest = rest;
                    u32::from(u16::from_le_bytes([lo, hi]))
                }
                [lo] => {
                    self.rest = &[];
                    u32::from(lo)
                }
                [] => 0,
            };
            self.acc |= half << self.avail;
            self.avail = self.avail.wrapping_add(16);
        }
        let v = self.acc & (1u32 << n).wrapping_sub(1);
        self.acc >>= n;
        self.avail = self.avail.wrapping_sub(n);
        v
    }
}

/// `n ≤ 30` bits of `bytes` from bit `bit`, LSB-first (§4.4); bits past
/// the end read as zero, like [`BitReader`].
#[inline(always)]
#[cfg(feature = "codec-pca-spline")]
pub(crate) fn bits_at(bytes: &[u8], bit: usize, n: u32) -> u32 {
    let at = bit >> 3;
    if n <= 25 {
        // 25 bits past a shift of at most 7 fit in one 32-bit window.
        if let Some(quad) = bytes
            .get(at..at.wrapping_add(4))
            .and_then(|s| <[u8; 4]>::try_from(s).ok())
        {
            let word = u32::from_le_bytes(quad);
            return (word >> (bit & 7)) & 1u32.wrapping_shl(n).wrapping_sub(1);
        }
    }
    let word = match bytes
        .get(at..at.wrapping_add(8))
        .and_then(|s| <[u8; 8]>::try_from(s).ok())
    {
        Some(octet) => u64::from_le_bytes(octet),
        _ => tail_word(bytes, at),
    };
    ((word >> (bit & 7)) as u32) & 1u32.wrapping_shl(n).wrapping_sub(1)
}

/// [`bits_at`] at a 64-bit bit position.
#[inline(always)]
#[cfg(feature = "codec-pca-spline")]
pub(crate) fn bits_at64(bytes: &[u8], bit: u64, n: u32) -> u32 {
    match usize::try_from(bit) {
        Ok(bit) if bit < usize::MAX - 64 => bits_at(bytes, bit, n),
        _ => 0,
    }
}

/// The eight bytes of `bytes` from `at` as a little-endian word, zeros past
/// the end.
#[inline(never)]
#[cfg(feature = "codec-pca-spline")]
fn tail_word(bytes: &[u8], at: usize) -> u64 {
    let mut word = 0u64;
    for i in 0..8 {
        let b = at
            .checked_add(i)
            .and_then(|j| bytes.get(j))
            .copied()
            .unwrap_or(0);
        word |= u64::from(b) << i.wrapping_mul(8);
    }
    word
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_lsb_first_across_bytes() {
        // 0b1010_1100, 0b0000_0011: fields 4, 4, 3 bits from bit 0.
        let bytes = [0b1010_1100u8, 0b0000_0011];
        let mut r = BitReader::at(&bytes, 0);
        assert_eq!(r.read(4), 0b1100);
        assert_eq!(r.read(4), 0b1010);
        assert_eq!(r.read(3), 0b011);
        let mut r = BitReader::at(&bytes, 6);
        assert_eq!(r.read(5), 0b01110);
        assert_eq!(r.read(0), 0);
        // Past the end reads zeros, never panics.
        let mut r = BitReader::at(&bytes, 1 << 40);
        assert_eq!(r.read(12), 0);
    }
}
