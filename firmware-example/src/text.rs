//! Decimal text without `core::fmt` (which would cost several KiB of flash).

use crate::board::Write;

/// Text output on top of a byte sink.
pub struct Text<W: Write>(pub W);

impl<W: Write> Text<W> {
    pub fn str(&mut self, s: &str) -> &mut Self {
        for &b in s.as_bytes() {
            self.0.write_byte(b);
        }
        self
    }

    pub fn u64(&mut self, mut n: u64) -> &mut Self {
        // u64::MAX has 20 digits. Filled from the end by iterating the array itself, so no
        // store can be out of bounds (an index left a `panic_bounds_check` in the ELF).
        let mut digits = [0u8; 20];
        let mut start = digits.len();
        for slot in digits.iter_mut().rev() {
            *slot = b'0' + (n % 10) as u8;
            start -= 1;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        self.bytes(digits.iter().skip(start))
    }

    pub fn u32(&mut self, n: u32) -> &mut Self {
        // A 32-bit loop: u64 division is a library call on Cortex-M.
        let mut n = n;
        let mut digits = [0u8; 10]; // u32::MAX has 10 digits
        let mut start = digits.len();
        for slot in digits.iter_mut().rev() {
            *slot = b'0' + (n % 10) as u8;
            start -= 1;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        self.bytes(digits.iter().skip(start))
    }

    fn bytes<'a>(&mut self, bytes: impl Iterator<Item = &'a u8>) -> &mut Self {
        for &b in bytes {
            self.0.write_byte(b);
        }
        self
    }

    /// Same text as Rust's `{}` for an `i32` (e.g. `-2147483648`, `0`, `17`).
    pub fn i32(&mut self, n: i32) -> &mut Self {
        if n < 0 {
            self.0.write_byte(b'-');
        }
        self.u32(n.unsigned_abs())
    }

    /// `# key=value` statistics line helper: writes ` key=value` (leading space).
    pub fn kv(&mut self, key: &str, value: u64) -> &mut Self {
        self.str(" ").str(key).str("=").u64(value)
    }

    pub fn nl(&mut self) -> &mut Self {
        self.0.write_byte(b'\n');
        self
    }
}
