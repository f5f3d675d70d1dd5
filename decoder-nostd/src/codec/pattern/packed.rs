//! Pattern records in layout 2 (SPEC.md §11.3c): layout 1's columns with
//! each channel's codes bit-packed at the width the pattern needs (0 … 32
//! bits), the shifts once per node. A code is read from the four bytes at
//! its first byte (the encoder ends a node's records with 3 bytes so this
//! never reads past them); a value is `(base + code) << shift`.

use super::columns::{round, round32, split_head, steps, Run, Scatter, Sink};
use super::{position, u16_at, window, WIDE_BASE_2};

/// Decodes frame `t` of a segment of `n` frames that plays the layout-2
/// record `rec` into the node's `channels` of `out`, with the node's
/// per-channel `shifts` (§11.3c, §11.4).
pub(super) fn play(
    rec: &[u8],
    channels: &[[u8; 2]],
    shifts: &[u8],
    t: u32,
    n: u32,
    out: &mut [i32],
) -> Option<()> {
    let count = channels.len();
    let first = usize::from(u16::from_le_bytes(*channels.first()?));
    let last = usize::from(u16::from_le_bytes(*channels.last()?));
    if last.wrapping_sub(first).wrapping_add(1) == count {
        let run = out.get_mut(first..last.wrapping_add(1))?;
        play_into(rec, shifts, t, n, Run(run.iter_mut()))
    } else {
        let channels = channels.iter();
        play_into(rec, shifts, t, n, Scatter { out, channels })
    }
}

#[inline(always)]
fn play_into<S: Sink>(rec: &[u8], shifts: &[u8], t: u32, n: u32, sink: S) -> Option<()> {
    let len = u16_at(rec, 0)?;
    let rest = rec.get(2..)?;
    let (j, frac) = position(t, n, u32::from(len));
    let len = usize::from(len);
    if frac == 0 {
        return curve::<1, S>(rest, shifts, j as usize, [4096, 0, 0, 0], len, sink);
    }
    let (s0, w) = window(j, len as u32, frac);
    let s0 = s0 as usize;
    match len {
        2 => curve::<2, S>(rest, shifts, s0, w, len, sink),
        3 => curve::<3, S>(rest, shifts, s0, w, len, sink),
        _ => curve::<4, S>(rest, shifts, s0, w, len, sink),
    }
}

/// The 4 bytes at byte `at` of `col`, as a little-endian word.
#[inline(always)]
fn word(col: &[u8], at: usize) -> Option<u32> {
    col.get(at..at.wrapping_add(4))?
        .first_chunk::<4>()
        .map(|w| u32::from_le_bytes(*w))
}

/// The `b`-bit code whose first bit is bit `bit` of `col` (§11.3c), from
/// the 4 (or, past 25 bits, 5) bytes at its first byte.
#[inline(always)]
fn code_at(col: &[u8], bit: usize, b: u32, mask: u32) -> Option<u32> {
    let at = bit >> 3;
    let sh = (bit & 7) as u32;
    if b <= 25 {
        Some(word(col, at)?.wrapping_shr(sh) & mask)
    } else {
        let w = col.get(at..at.wrapping_add(5))?.first_chunk::<5>()?;
        let x = u64::from(u32::from_le_bytes([w[0], w[1], w[2], w[3]])) | u64::from(w[4]) << 32;
        Some(((x >> sh) as u32) & mask)
    }
}

/// `K` consecutive `b`-bit codes from bit `bit` of `col`: one word read
/// when they fit in it with their first bit's offset (`K·b + 7 ≤ 32`), a
/// word per two codes when two fit, else a read per code. Every read
/// starts at a code's first byte (§11.3c's closing bytes keep it inside).
#[inline(always)]
fn codes<const K: usize>(col: &[u8], bit: usize, b: u32) -> Option<[u32; K]> {
    let mask = u32::MAX.wrapping_shr(32u32.wrapping_sub(b));
    let bits = b as usize;
    let mut out = [0u32; K];
    if (K as u32).wrapping_mul(b) <= 25 {
        let x = word(col, bit >> 3)?.wrapping_shr((bit & 7) as u32);
        let mut sh = 0u32;
        for o in out.iter_mut() {
            *o = x.wrapping_shr(sh) & mask;
            sh = sh.wrapping_add(b);
        }
    } else if b <= 12 {
        let mut at = bit;
        for pair in out.chunks_mut(2) {
            let x = word(col, at >> 3)?.wrapping_shr((at & 7) as u32);
            let mut sh = 0u32;
            for o in pair.iter_mut() {
                *o = x.wrapping_shr(sh) & mask;
                sh = sh.wrapping_add(b);
            }
            at = at.wrapping_add(bits.wrapping_mul(2));
        }
    } else {
        let mut at = bit;
        for o in out.iter_mut() {
            *o = code_at(col, at, b, mask)?;
            at = at.wrapping_add(bits);
        }
    }
    Some(out)
}

/// Every channel on the curve through its `K` codes from sample `s0` with
/// the weights `w` (§11.4); `K = 1` with weight 4096 is the sample itself.
fn curve<const K: usize, S: Sink>(
    mut rest: &[u8],
    shifts: &[u8],
    s0: usize,
    w: [i32; 4],
    len: usize,
    mut sink: S,
) -> Option<()> {
    let mut shifts = shifts.iter();
    while let Some(o) = sink.slot() {
        let s = *shifts.next()?;
        let (base, h, col) = split_head(rest, WIDE_BASE_2)?;
        let b = u32::from(h & 63);
        let code = if b == 0 {
            0
        } else {
            let c = codes::<K>(col, s0.wrapping_mul(b as usize), b)?;
            if K == 1 {
                c.first().map_or(0, |&c| c as i32)
            } else if b <= 16 {
                // |Σ w·c| < 5 120 · 2^16: exact in 32 bits.
                let acc = c
                    .iter()
                    .zip(w)
                    .fold(0i32, |a, (&c, w)| a.wrapping_add(w.wrapping_mul(c as i32)));
                round32(acc)
            } else {
                let acc = c.iter().zip(w).fold(0i64, |a, (&c, w)| {
                    a.wrapping_add(i64::from(c).wrapping_mul(i64::from(w)))
                });
                round(acc)
            }
        };
        *o = steps(base, s, code);
        rest = col.get(len.wrapping_mul(b as usize).wrapping_add(7) >> 3..)?;
    }
    Some(())
}
