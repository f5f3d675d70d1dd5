//! Pattern records in layout 1 (SPEC.md §11.3b): per channel its head, its
//! base in steps of `2^shift` (`i16`, or `i32` with head bit 7) and its
//! codes, so the four samples the curve reads are next to each other; a
//! value is `(base + code) << shift`.
//!
//! The loops are written for the registers of a Cortex-M: a node whose
//! channels are consecutive writes its values in order (no channel
//! numbers read), and each loop knows its window length.

use super::{position, u16_at, window, HEAD_WIDE_BASE, WEIGHT_BITS};

/// Where a node's values go, one after the other: consecutive outputs,
/// or the node's channel numbers. The loops run until it has no more.
pub(super) trait Sink {
    fn slot(&mut self) -> Option<&mut i32>;
}

/// A node's channels `first … first + C − 1`: its part of the output.
pub(super) struct Run<'o>(pub(super) core::slice::IterMut<'o, i32>);

impl Sink for Run<'_> {
    #[inline(always)]
    fn slot(&mut self) -> Option<&mut i32> {
        self.0.next()
    }
}

/// Any channels: the output and the node's channel numbers.
pub(super) struct Scatter<'o, 'c> {
    pub(super) out: &'o mut [i32],
    pub(super) channels: core::slice::Iter<'c, [u8; 2]>,
}

impl Sink for Scatter<'_, '_> {
    #[inline(always)]
    fn slot(&mut self) -> Option<&mut i32> {
        let c = self.channels.next()?;
        self.out.get_mut(usize::from(u16::from_le_bytes(*c)))
    }
}

/// Decodes frame `t` of a segment of `n` frames that plays the layout-1
/// record `rec` into the node's `channels` of `out` (§11.3b, §11.4).
pub(super) fn play(
    rec: &[u8],
    channels: &[[u8; 2]],
    t: u32,
    n: u32,
    out: &mut [i32],
) -> Option<()> {
    let count = channels.len();
    let first = usize::from(u16::from_le_bytes(*channels.first()?));
    let last = usize::from(u16::from_le_bytes(*channels.last()?));
    // Channels increase (§11.2): consecutive when the span is the count.
    if last.wrapping_sub(first).wrapping_add(1) == count {
        let run = out.get_mut(first..last.wrapping_add(1))?;
        play_into(rec, t, n, Run(run.iter_mut()))
    } else {
        let channels = channels.iter();
        play_into(rec, t, n, Scatter { out, channels })
    }
}

#[inline(always)]
fn play_into<S: Sink>(rec: &[u8], t: u32, n: u32, sink: S) -> Option<()> {
    let len = u16_at(rec, 0)?;
    let rest = rec.get(2..)?;
    let (j, frac) = position(t, n, u32::from(len));
    let len = usize::from(len);
    if frac == 0 {
        return at_sample(rest, j as usize, len, sink);
    }
    let (s0, w) = window(j, len as u32, frac);
    let s0 = s0 as usize;
    match len {
        2 => curve::<2, S>(rest, s0, w, len, sink),
        3 => curve::<3, S>(rest, s0, w, len, sink),
        _ => curve::<4, S>(rest, s0, w, len, sink),
    }
}

/// Every channel at its sample `j`.
fn at_sample<S: Sink>(mut rest: &[u8], j: usize, len: usize, mut sink: S) -> Option<()> {
    while let Some(o) = sink.slot() {
        let (base, h, col) = split_head(rest, HEAD_WIDE_BASE)?;
        let (code, next) = match h >> 5 & 3 {
            0 => (0, col),
            1 => (i32::from(*col.get(j)?), col.get(len..)?),
            2 => (
                i32::from(u16_at(col, j.wrapping_mul(2))?),
                col.get(len.wrapping_mul(2)..)?,
            ),
            _ => {
                let c = col.get(j.wrapping_mul(4)..)?.first_chunk::<4>()?;
                (i32::from_le_bytes(*c), col.get(len.wrapping_mul(4)..)?)
            }
        };
        *o = steps(base, h, code);
        rest = next;
    }
    Some(())
}

/// Every channel on the curve through its `K` samples `s0 … s0 + K − 1`
/// with the weights `w` (§11.4): `K = 4`, or the whole pattern when it
/// has 2 or 3 samples.
fn curve<const K: usize, S: Sink>(
    mut rest: &[u8],
    s0: usize,
    w: [i32; 4],
    len: usize,
    mut sink: S,
) -> Option<()> {
    while let Some(o) = sink.slot() {
        let (base, h, col) = split_head(rest, HEAD_WIDE_BASE)?;
        let (code, next) = match h >> 5 & 3 {
            0 => (0, col),
            1 => {
                let c = col.get(s0..)?.first_chunk::<K>()?;
                // |Σ w·c| < 5 120 · 2^8: exact in 32 bits.
                let acc = c.iter().zip(w).fold(0i32, |a, (&c, w)| {
                    a.wrapping_add(w.wrapping_mul(i32::from(c)))
                });
                (round32(acc), col.get(len..)?)
            }
            2 => {
                let at = s0.wrapping_mul(2);
                let c = col.get(at..at.wrapping_add(K.wrapping_mul(2)))?;
                // |Σ w·c| < 5 120 · 2^16: exact in 32 bits.
                let acc = c
                    .as_chunks::<2>()
                    .0
                    .iter()
                    .take(K)
                    .zip(w)
                    .fold(0i32, |a, (c, w)| {
                        a.wrapping_add(w.wrapping_mul(i32::from(u16::from_le_bytes(*c))))
                    });
                (round32(acc), col.get(len.wrapping_mul(2)..)?)
            }
            _ => {
                let c = col.get(s0.wrapping_mul(4)..)?;
                let acc = c
                    .as_chunks::<4>()
                    .0
                    .iter()
                    .take(K)
                    .zip(w)
                    .fold(0i64, |a, (c, w)| {
                        a.wrapping_add(i64::from(u32::from_le_bytes(*c)).wrapping_mul(i64::from(w)))
                    });
                (round(acc), col.get(len.wrapping_mul(4)..)?)
            }
        };
        *o = steps(base, h, code);
        rest = next;
    }
    Some(())
}

/// The channel at the start of `rest`: its base (in steps), its head and
/// the bytes from its codes on; `wide` is the head bit that makes the base
/// an `i32` (layout 1: bit 7, layout 2: bit 6).
#[inline(always)]
pub(super) fn split_head(rest: &[u8], wide: u8) -> Option<(i32, u8, &[u8])> {
    let (&[h, b0, b1], r) = rest.split_first_chunk::<3>()?;
    if h & wide == 0 {
        Some((i32::from(i16::from_le_bytes([b0, b1])), h, r))
    } else {
        let (base, r) = wide_base(rest)?;
        Some((base, h, r))
    }
}

/// A channel whose base is an `i32` (layout 1 head bit 7, layout 2 bit 6):
/// the base and the bytes after it. Out of line and cold, so that the
/// common `i16` path keeps the base in one register (merged, the compiler
/// rebuilt it from its bytes every channel).
#[cold]
#[inline(never)]
fn wide_base(rest: &[u8]) -> Option<(i32, &[u8])> {
    let (&[_, b0, b1, b2, b3], r) = rest.split_first_chunk::<5>()?;
    Some((i32::from_le_bytes([b0, b1, b2, b3]), r))
}

/// A value: `(base + code) << shift`, wrapping (§11.3b).
#[inline(always)]
pub(super) fn steps(base: i32, head: u8, code: i32) -> i32 {
    base.wrapping_add(code).wrapping_shl(u32::from(head & 31))
}

/// `(acc + 2048) >> 12` of an exact 64-bit sum of weighed codes.
#[inline(always)]
pub(super) fn round(acc: i64) -> i32 {
    (acc.wrapping_add(1 << (WEIGHT_BITS - 1)) >> WEIGHT_BITS) as i32
}

/// `(acc + 2048) >> 12` of a sum exact in 32 bits.
#[inline(always)]
pub(super) fn round32(acc: i32) -> i32 {
    acc.wrapping_add(1 << (WEIGHT_BITS - 1)) >> WEIGHT_BITS
}
