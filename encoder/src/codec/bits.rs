//! The bit writer shared by the codecs: little-endian, LSB first, the
//! mirror of the decoder's `BitReader` (SPEC.md §4.4).

/// Little-endian, LSB-first bit writer.
#[derive(Default)]
pub struct BitWriter {
    bytes: Vec<u8>,
    bit: u64,
}

impl BitWriter {
    /// Appends the low `n` bits of `v`.
    pub fn write(&mut self, v: u32, n: u8) {
        for i in 0..n {
            if self.bit.is_multiple_of(8) {
                self.bytes.push(0);
            }
            if (v >> i) & 1 != 0 {
                *self.bytes.last_mut().expect("pushed above") |= 1 << (self.bit % 8);
            }
            self.bit += 1;
        }
    }

    /// The bytes written, the last one zero-padded.
    pub fn finish(self) -> Vec<u8> {
        self.bytes
    }
}
