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
        let mut digits = [0u8; 20]; // u64::MAX has 20 digits
        let mut len = 0;
        loop {
            digits[len] = b'0' + (n % 10) as u8;
            len += 1;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        while len > 0 {
            len -= 1;
            self.0.write_byte(digits[len]);
        }
        self
    }

    pub fn u32(&mut self, n: u32) -> &mut Self {
        // A 32-bit loop: u64 division is a library call on Cortex-M.
        let mut n = n;
        let mut digits = [0u8; 10];
        let mut len = 0;
        loop {
            digits[len] = b'0' + (n % 10) as u8;
            len += 1;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        while len > 0 {
            len -= 1;
            self.0.write_byte(digits[len]);
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
