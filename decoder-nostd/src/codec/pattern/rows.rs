//! Pattern records in layout 0 (SPEC.md §11.3): per pattern the channels'
//! heads, their `i32` bases, then the codes sample by sample (rows); a
//! value is `base + (code << shift)`. Files written before layout 1 keep
//! decoding through here.

use super::{interpolate, position, taps, u16_at, u32_at, WEIGHT_BITS};

/// Decodes frame `t` of a segment of `n` frames that plays the layout-0
/// record `rec` into the node's `channels` of `out` (§11.4).
pub(super) fn play(
    rec: &[u8],
    channels: &[[u8; 2]],
    t: u32,
    n: u32,
    out: &mut [i32],
) -> Option<()> {
    let Record {
        len,
        row,
        heads,
        bases,
        rows,
    } = record(rec, channels.len())?;
    let (j, frac) = position(t, n, len as u32);
    let p = Samples {
        heads,
        bases: bases.as_chunks::<4>().0,
        channels,
    };
    let at = |k: u32| rows.get((k as usize).wrapping_mul(row)..);
    if frac == 0 {
        let a = at(j)?;
        p.play::<false>([a, a, a, a], [0; 4], out)
    } else {
        let (t, w) = taps(j, len as u32, frac);
        let [t0, t1, t2, t3] = t;
        p.play::<true>([at(t0)?, at(t1)?, at(t2)?, at(t3)?], w, out)
    }
}

/// A pattern record (§11.3), split: its sample count, the bytes of one
/// sample row, the channels' head bytes (shift in bits 0–4, code width `0,
/// 1, 2, 4` bytes in bits 5–6 as `0…3`), their bases (`i32` each) and the
/// rows.
pub(super) struct Record<'a> {
    /// Samples per channel.
    pub(super) len: usize,
    /// Bytes of a row.
    pub(super) row: usize,
    /// The channels' heads.
    pub(super) heads: &'a [u8],
    bases: &'a [u8],
    rows: &'a [u8],
}

/// The record of `nc` channels at the start of `rec`.
pub(super) fn record(rec: &[u8], nc: usize) -> Option<Record<'_>> {
    let len = usize::from(u16_at(rec, 0)?);
    let row = usize::from(u16_at(rec, 2)?);
    let (heads, rest) = rec.get(4..)?.split_at_checked(nc)?;
    let (bases, rest) = rest.split_at_checked(nc.checked_mul(4)?)?;
    let rows = rest.get(..len.checked_mul(row)?)?;
    Some(Record {
        len,
        row,
        heads,
        bases,
        rows,
    })
}

/// A pattern's per-channel parts (§11.3) and the node's channels.
struct Samples<'a> {
    heads: &'a [u8],
    bases: &'a [[u8; 4]],
    channels: &'a [[u8; 2]],
}

impl Samples<'_> {
    /// Writes each channel at a position: sample row `rows[1]`, or with
    /// `CURVE` the curve through the rows of the four taps with weights `w`
    /// (§11.4).
    #[inline(always)]
    fn play<const CURVE: bool>(
        &self,
        rows: [&[u8]; 4],
        w: [i32; 4],
        out: &mut [i32],
    ) -> Option<()> {
        let mut at = 0usize;
        let [r0, r1, r2, r3] = rows;
        for ((&h, base), ch) in self.heads.iter().zip(self.bases).zip(self.channels) {
            let shift = h & 31;
            let v = match h >> 5 {
                1 if CURVE => {
                    let c = |r: &[u8]| r.get(at).map(|&b| i32::from(b));
                    // |Σ w·c| < 5 120 · 2^8: exact in 32 bits.
                    let acc = weigh(w, [c(r0)?, c(r1)?, c(r2)?, c(r3)?]);
                    at = at.wrapping_add(1);
                    curve(*base, shift, acc)
                }
                1 => {
                    let c = u32::from(*r1.get(at)?);
                    at = at.wrapping_add(1);
                    sample(*base, shift, c)
                }
                2 if CURVE => {
                    let c = |r: &[u8]| u16_at(r, at).map(i32::from);
                    // |Σ w·c| < 5 120 · 2^16: exact in 32 bits.
                    let acc = weigh(w, [c(r0)?, c(r1)?, c(r2)?, c(r3)?]);
                    at = at.wrapping_add(2);
                    curve(*base, shift, acc)
                }
                2 => {
                    let c = u32::from(u16_at(r1, at)?);
                    at = at.wrapping_add(2);
                    sample(*base, shift, c)
                }
                3 => {
                    let codes = [
                        u32_at(r0, at)?,
                        u32_at(r1, at)?,
                        u32_at(r2, at)?,
                        u32_at(r3, at)?,
                    ];
                    at = at.wrapping_add(4);
                    if CURVE {
                        interpolate(i32::from_le_bytes(*base), u32::from(shift), codes, w)
                    } else {
                        sample(*base, shift, codes[1])
                    }
                }
                _ => i32::from_le_bytes(*base),
            };
            put(out, ch, v);
        }
        Some(())
    }
}

/// Writes `v` to the output channel `c` (the node's `u16` channel number).
#[inline(always)]
fn put(out: &mut [i32], c: &[u8; 2], v: i32) {
    if let Some(o) = out.get_mut(usize::from(u16::from_le_bytes(*c))) {
        *o = v;
    }
}

/// A sample's value: `base + (code << shift)`, wrapping (§11.3).
#[inline(always)]
fn sample(base: [u8; 4], shift: u8, code: u32) -> i32 {
    i32::from_le_bytes(base).wrapping_add(code.wrapping_shl(u32::from(shift)) as i32)
}

/// `Σ w·c` of four codes in 32-bit arithmetic (exact for codes below 2^16).
#[inline(always)]
fn weigh(w: [i32; 4], c: [i32; 4]) -> i32 {
    w[0].wrapping_mul(c[0])
        .wrapping_add(w[1].wrapping_mul(c[1]))
        .wrapping_add(w[2].wrapping_mul(c[2]))
        .wrapping_add(w[3].wrapping_mul(c[3]))
}

/// The curve's value from the weighed sum `acc` of four codes (§11.4).
#[inline(always)]
fn curve(base: [u8; 4], shift: u8, acc: i32) -> i32 {
    let code = acc.wrapping_add(1 << (WEIGHT_BITS - 1)) >> WEIGHT_BITS;
    i32::from_le_bytes(base).wrapping_add(code.wrapping_shl(u32::from(shift)))
}
