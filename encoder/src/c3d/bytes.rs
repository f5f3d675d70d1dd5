//! Reading numbers out of a C3D file in its processor's encoding, every read
//! bounds-checked: past the end of the file is a [`C3dError`] at the offset
//! of the value, never a panic.

use super::{C3dError, Processor};

/// The whole file and its number encoding.
pub(super) struct Bytes<'a> {
    pub(super) data: &'a [u8],
    pub(super) file: &'a str,
    pub(super) processor: Processor,
}

impl<'a> Bytes<'a> {
    /// An error at byte `offset`.
    pub(super) fn err(&self, offset: usize, message: impl Into<String>) -> C3dError {
        C3dError::at(self.file, offset, message)
    }

    /// `n` bytes at `at`, or a truncation error naming `what`.
    pub(super) fn take(&self, at: usize, n: usize, what: &str) -> Result<&'a [u8], C3dError> {
        self.take_named(at, n, || what.to_string())
    }

    /// [`Bytes::take`] with the name made only for an error.
    pub(super) fn take_named(
        &self,
        at: usize,
        n: usize,
        what: impl Fn() -> String,
    ) -> Result<&'a [u8], C3dError> {
        at.checked_add(n)
            .and_then(|end| self.data.get(at..end))
            .ok_or_else(|| {
                let what = what();
                self.err(
                    at,
                    format!(
                        "file ends inside {what} ({n} bytes at byte {at}, the file has {})",
                        self.data.len()
                    ),
                )
            })
    }

    pub(super) fn u8(&self, at: usize, what: &str) -> Result<u8, C3dError> {
        Ok(self.take(at, 1, what)?.first().copied().unwrap_or(0))
    }

    pub(super) fn i8(&self, at: usize, what: &str) -> Result<i8, C3dError> {
        Ok(self.u8(at, what)? as i8)
    }

    fn two(&self, at: usize, what: &str) -> Result<[u8; 2], C3dError> {
        let b = self.take(at, 2, what)?;
        Ok([
            b.first().copied().unwrap_or(0),
            b.get(1).copied().unwrap_or(0),
        ])
    }

    fn four(&self, at: usize, what: impl Fn() -> String) -> Result<[u8; 4], C3dError> {
        let b = self.take_named(at, 4, what)?;
        let mut out = [0u8; 4];
        for (o, v) in out.iter_mut().zip(b) {
            *o = *v;
        }
        Ok(out)
    }

    /// A 16-bit word as unsigned (Intel and DEC: little-endian; MIPS: big-endian).
    pub(super) fn u16(&self, at: usize, what: &str) -> Result<u16, C3dError> {
        let b = self.two(at, what)?;
        Ok(match self.processor {
            Processor::Intel | Processor::Dec => u16::from_le_bytes(b),
            Processor::Mips => u16::from_be_bytes(b),
        })
    }

    /// A 16-bit word as signed.
    pub(super) fn i16(&self, at: usize, what: &str) -> Result<i16, C3dError> {
        Ok(self.u16(at, what)? as i16)
    }

    /// A 32-bit float in the processor's format, exactly as an `f64`; a value
    /// that is no number (IEEE NaN or infinity, DEC's reserved operand) is an
    /// error naming `what`.
    pub(super) fn f32(&self, at: usize, what: &str) -> Result<f64, C3dError> {
        self.f32_named(at, || what.to_string())
    }

    /// [`Bytes::f32`] with the value's name made only for an error (the
    /// data section's millions of reads build no string).
    pub(super) fn f32_named(&self, at: usize, what: impl Fn() -> String) -> Result<f64, C3dError> {
        let b = self.four(at, &what)?;
        decode_f32(self.processor, b)
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.err(at, format!("{} is not a number (bytes {b:02x?})", what())))
    }
}

/// A 32-bit float of `processor` (`None` for DEC's reserved operand; IEEE
/// NaN and infinities come back as they are).
pub(super) fn decode_f32(processor: Processor, b: [u8; 4]) -> Option<f64> {
    match processor {
        Processor::Intel => Some(f64::from(f32::from_le_bytes(b))),
        Processor::Mips => Some(f64::from(f32::from_be_bytes(b))),
        Processor::Dec => dec_f32(b),
    }
}

/// A VAX F-format float (C3D's DEC processor type), converted exactly.
///
/// In memory it is two little-endian 16-bit words, the first holding the
/// sign (bit 15), the excess-128 exponent (bits 14–7) and the top 7 bits of
/// the fraction, the second the low 16 bits of the fraction. The value is
/// `0.1fff… × 2^(exponent − 128)` with a hidden leading 1 after the binary
/// point — a quarter of the IEEE value of the same bits with the words
/// swapped. Computed in `f64`, which holds every F-format value exactly
/// (exponents 2^-128 … 2^126, beyond `f32`'s normal range at both ends).
/// Exponent 0 is zero whatever the fraction ("dirty zero") when the sign is
/// clear, and the reserved operand (`None`) when it is set.
pub(super) fn dec_f32(b: [u8; 4]) -> Option<f64> {
    let [b0, b1, b2, b3] = b;
    let hi = u16::from_le_bytes([b0, b1]);
    let lo = u16::from_le_bytes([b2, b3]);
    let negative = hi & 0x8000 != 0;
    let exponent = i32::from((hi >> 7) & 0xff);
    if exponent == 0 {
        return (!negative).then_some(0.0);
    }
    let mantissa = (u32::from(hi & 0x7f) << 16) | u32::from(lo) | 0x80_0000;
    let v = f64::from(mantissa) * 2f64.powi(exponent - 128 - 24);
    Some(if negative { -v } else { v })
}

/// The DEC bytes of `v` (tests' writer): the inverse of [`dec_f32`] for
/// normal `f32` values whose quadruple is normal too.
#[cfg(test)]
pub(super) fn dec_bytes(v: f32) -> [u8; 4] {
    if v == 0.0 {
        return [0; 4];
    }
    let bits = (v * 4.0).to_bits();
    [
        (bits >> 16) as u8,
        (bits >> 24) as u8,
        bits as u8,
        (bits >> 8) as u8,
    ]
}
