//! LSB-first bit reader over a byte slice (SPEC.md §4.4). Bits past the end
//! of the slice read as zero, so a read can never go out of bounds; the
//! codecs check payload lengths up front so that never happens on a
//! validated clip.

#[derive(Clone, Debug)]
pub(crate) struct BitReader<'a> {
    bytes: &'a [u8],
    next_byte: usize,
    acc: u32,
    avail: u32,
}

impl<'a> BitReader<'a> {
    /// A reader positioned at absolute bit `bit` of `bytes`.
    pub(crate) fn at(bytes: &'a [u8], bit: u64) -> Self {
        let byte = usize::try_from(bit / 8).unwrap_or(usize::MAX);
        let mut r = BitReader {
            bytes,
            next_byte: byte,
            acc: 0,
            avail: 0,
        };
        let skip = (bit % 8) as u32;
        r.read(skip);
        r
    }

    /// Reads `n` bits, `n <= 24`, first bit in the result's bit 0.
    #[inline(always)]
    pub(crate) fn read(&mut self, n: u32) -> u32 {
        while self.avail < n {
            let b = self.bytes.get(self.next_byte).copied().unwrap_or(0);
            self.acc |= u32::from(b) << self.avail;
            self.next_byte = self.next_byte.wrapping_add(1);
            self.avail += 8;
        }
        let v = self.acc & ((1u32 << n) - 1);
        self.acc = self.acc.checked_shr(n).unwrap_or(0);
        self.avail -= n;
        v
    }
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
