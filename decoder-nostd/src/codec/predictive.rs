//! The `predictive` codec (SPEC.md §5b): every channel predicted from its
//! last two decoded values, the quantised residual coded with an adaptive
//! binary range coder (LZMA-style probabilities, no tables in the clip).
//! Frames come in blocks that restart the coder, so random access decodes
//! at most one block; sequential playback decodes each frame once.
//!
//! Player state (`3·C + 19` words): the current frame `v1`, the one before
//! `v2`, each channel's context, the probabilities (two per word) and the
//! coder (range, code, read position, block end).

use crate::consts::predictive::{
    CONTEXTS, MAGNITUDE_STEPS, MAX_ESCAPE_BITS, MAX_STEP, MODE_CONSTANT, MODE_STEP_SHIFT,
    MOVE_BITS, PREDICTOR_WEIGHTS, PROBS_PER_CONTEXT, PROB_BITS, PROB_INIT, STATE_EXTRA_WORDS, TOP,
};
use crate::error::Error;
use crate::reader::Reader;
use core::num::NonZeroU32;

/// Probabilities in the state.
const PROBS: usize = CONTEXTS * PROBS_PER_CONTEXT;
/// Words of packed probabilities.
const PROB_WORDS: usize = PROBS / 2;
/// Mode bits that must be 0 on a constant channel.
const CONSTANT_RESERVED: u32 = !MODE_CONSTANT;

/// A validated view of a `predictive` codec section.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PredictiveCodec<'a> {
    channels: usize,
    /// Frames per block, validated non-zero: dividing by it cannot panic.
    block_frames: NonZeroU32,
    unit: u32,
    /// The `C` channel records.
    modes: &'a [u8],
    /// The block lengths (varints).
    lengths: &'a [u8],
    /// The blocks' bytes, concatenated.
    data: &'a [u8],
}

impl<'a> PredictiveCodec<'a> {
    /// Validates the section against the header's channel and frame counts.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize, frames: u32) -> Result<Self, Error> {
        let bad = |rule| Error::PredictiveMalformed { rule };
        let mut r = Reader::new(bytes);
        let count = r.varint_u32().ok_or(bad("truncated"))?;
        if count as usize != channels {
            return Err(bad("channel count differs from the header"));
        }
        let block_frames = r.varint_u32().ok_or(bad("truncated"))?;
        let unit = r.varint_u32().ok_or(bad("truncated"))?;
        let (Some(block_frames), true) = (NonZeroU32::new(block_frames), unit != 0) else {
            return Err(bad("block length and unit must be positive"));
        };
        let at = r.pos();
        for _ in 0..channels {
            let mode = r.varint_u32().ok_or(bad("truncated channel record"))?;
            if mode & MODE_CONSTANT != 0 {
                if mode & CONSTANT_RESERVED != 0 {
                    return Err(bad("constant channel with other mode bits"));
                }
                r.zigzag_i32().ok_or(bad("truncated channel record"))?;
            } else {
                let m = mode >> MODE_STEP_SHIFT;
                if m == 0 || u64::from(m).wrapping_mul(u64::from(unit)) > u64::from(MAX_STEP) {
                    return Err(bad("step must be 1 ..= 2^30"));
                }
            }
        }
        let modes = bytes.get(at..r.pos()).ok_or(bad("truncated"))?;
        let blocks = r.varint_u32().ok_or(bad("truncated"))?;
        if blocks != frames.div_ceil(block_frames.get()) {
            return Err(bad("block count must be ceil(frames / block length)"));
        }
        let at = r.pos();
        let mut total: u64 = 0;
        for _ in 0..blocks {
            total = total.wrapping_add(u64::from(
                r.varint_u32().ok_or(bad("truncated block table"))?,
            ));
        }
        let lengths = bytes.get(at..r.pos()).ok_or(bad("truncated"))?;
        let data = r.rest();
        if total != data.len() as u64 {
            return Err(bad("block lengths must add up to the rest of the section"));
        }
        Ok(PredictiveCodec {
            channels,
            block_frames,
            unit,
            modes,
            lengths,
            data,
        })
    }

    /// Player state words this clip needs.
    pub(crate) fn state_words(&self) -> usize {
        self.channels
            .wrapping_mul(3)
            .wrapping_add(STATE_EXTRA_WORDS)
    }

    /// The first frame of the block holding `frame`.
    pub(crate) fn key_before(&self, frame: u32) -> u32 {
        let r = frame % self.block_frames;
        frame.wrapping_sub(r)
    }

    /// Byte range of block `b` in `data`.
    fn block(&self, b: u32) -> (u32, u32) {
        let mut r = Reader::new(self.lengths);
        let mut start: u32 = 0;
        for _ in 0..b {
            start = start.saturating_add(r.varint_u32().unwrap_or(0));
        }
        let len = r.varint_u32().unwrap_or(0);
        (start, start.saturating_add(len))
    }

    /// Decodes frame `frame` into `state` (at least [`Self::state_words`]
    /// words), which must hold frame `frame − 1` unless `frame` starts a
    /// block. The frame's values are `state[..C]`. `None` only if the state
    /// is smaller than [`Self::state_words`] (`Player::new` refuses that).
    pub(crate) fn decode_frame(&self, frame: u32, state: &mut [i32]) -> Option<()> {
        let c = self.channels;
        let (v1, rest) = state.split_at_mut_checked(c)?;
        let (v2, rest) = rest.split_at_mut_checked(c)?;
        let (ctx, rest) = rest.split_at_mut_checked(c)?;
        let (probs, coder) = rest.split_at_mut_checked(PROB_WORDS)?;
        let j = frame % self.block_frames;
        let mut rc = if j == 0 {
            probs.fill(i32::from(PROB_INIT).wrapping_mul(0x1_0001));
            ctx.fill(0);
            let (start, end) = self.block(frame / self.block_frames);
            RangeDecoder::start(self.data, start, end)
        } else {
            RangeDecoder::load(self.data, coder)
        };
        let mut modes = Reader::new(self.modes);
        let unit = i64::from(self.unit);
        for ((x1, x2), cx) in v1.iter_mut().zip(v2.iter_mut()).zip(ctx.iter_mut()) {
            let mode = modes.varint_u32().unwrap_or(MODE_CONSTANT);
            if mode & MODE_CONSTANT != 0 {
                let k = modes.zigzag_i32().unwrap_or(0);
                *x1 = k;
                *x2 = k;
                continue;
            }
            let step = i64::from(mode >> MODE_STEP_SHIFT).wrapping_mul(unit);
            let pred = predict(j, *x1, *x2, (mode & 3) as usize);
            let q = rc.residual(probs, (*cx as usize).min(CONTEXTS - 1));
            *x2 = *x1;
            *x1 = value(pred, q, step);
            *cx = q.unsigned_abs().min(2) as i32;
        }
        rc.store(coder);
        Some(())
    }
}

/// The prediction of a coded channel at frame `j` of its block from its
/// last two values and predictor `weight` (mode bits 0–1), SPEC.md §5b.
#[inline(always)]
pub fn predict(j: u32, v1: i32, v2: i32, weight: usize) -> i64 {
    let (p1, p2) = (i64::from(v1), i64::from(v2));
    match j {
        0 => 0,
        1 => p1,
        _ => {
            let a = PREDICTOR_WEIGHTS.get(weight).copied().unwrap_or(0);
            p1.wrapping_add(a.wrapping_mul(p1.wrapping_sub(p2)) >> 2)
        }
    }
}

/// The value residual `q` gives: `pred + q · step` wrapped into `i32`
/// (two's complement), SPEC.md §5b. Most residuals are 0, which needs no
/// 64-bit multiply.
#[inline(always)]
pub fn value(pred: i64, q: i64, step: i64) -> i32 {
    if q == 0 {
        pred as i32
    } else {
        pred.wrapping_add(q.wrapping_mul(step)) as i32
    }
}

/// The adaptive binary range decoder of SPEC.md §5b.
struct RangeDecoder<'a> {
    data: &'a [u8],
    range: u32,
    code: u32,
    pos: u32,
    end: u32,
}

impl<'a> RangeDecoder<'a> {
    /// A fresh decoder on `data[start..end]`: `code` is its first four
    /// bytes, big-endian (bytes past `end` read as 0).
    fn start(data: &'a [u8], start: u32, end: u32) -> Self {
        let mut d = RangeDecoder {
            data,
            range: u32::MAX,
            code: 0,
            pos: start,
            end,
        };
        for _ in 0..4 {
            d.code = (d.code << 8) | u32::from(d.byte());
        }
        d
    }

    /// The decoder saved by [`Self::store`].
    fn load(data: &'a [u8], coder: &[i32]) -> Self {
        let word = |i: usize| coder.get(i).copied().unwrap_or(0) as u32;
        RangeDecoder {
            data,
            range: word(0),
            code: word(1),
            pos: word(2),
            end: word(3),
        }
    }

    fn store(&self, coder: &mut [i32]) {
        for (w, v) in coder
            .iter_mut()
            .zip([self.range, self.code, self.pos, self.end])
        {
            *w = v as i32;
        }
    }

    fn byte(&mut self) -> u8 {
        let b = if self.pos < self.end {
            self.data.get(self.pos as usize).copied().unwrap_or(0)
        } else {
            0
        };
        self.pos = self.pos.saturating_add(1);
        b
    }

    #[inline(always)]
    fn normalize(&mut self) {
        // Three shifts bring any non-zero range back above TOP.
        for _ in 0..4 {
            if self.range >= TOP {
                break;
            }
            self.range <<= 8;
            self.code = (self.code << 8) | u32::from(self.byte());
        }
    }

    /// One bit with probability `i` of the packed `probs`, which it adapts.
    #[inline(always)]
    fn bit(&mut self, probs: &mut [i32], i: usize) -> u32 {
        let Some(word) = probs.get_mut(i / 2) else {
            return 0;
        };
        let shift = ((i % 2) as u32).wrapping_mul(16);
        let mut p = ((*word as u32) >> shift) & 0xFFFF;
        let bound = (self.range >> PROB_BITS).wrapping_mul(p);
        let bit = if self.code < bound {
            self.range = bound;
            p = p.wrapping_add((1u32 << PROB_BITS).wrapping_sub(p) >> MOVE_BITS);
            0
        } else {
            self.code = self.code.wrapping_sub(bound);
            self.range = self.range.wrapping_sub(bound);
            p = p.wrapping_sub(p >> MOVE_BITS);
            1
        };
        *word = (((*word as u32) & !(0xFFFF << shift)) | (p << shift)) as i32;
        self.normalize();
        bit
    }

    /// One bit with probability one half.
    fn direct(&mut self) -> u32 {
        self.range >>= 1;
        let bit = if self.code >= self.range {
            self.code = self.code.wrapping_sub(self.range);
            1
        } else {
            0
        };
        self.normalize();
        bit
    }

    /// A residual in context `cx` (SPEC.md §5b binarisation).
    fn residual(&mut self, probs: &mut [i32], cx: usize) -> i64 {
        let base = cx.wrapping_mul(PROBS_PER_CONTEXT);
        if self.bit(probs, base) == 0 {
            return 0;
        }
        let negative = self.bit(probs, base.wrapping_add(1)) == 1;
        let mut a: u32 = 1;
        while a <= MAGNITUDE_STEPS
            && self.bit(probs, base.wrapping_add(1).wrapping_add(a as usize)) == 1
        {
            a = a.wrapping_add(1);
        }
        let mut magnitude = i64::from(a);
        if a > MAGNITUDE_STEPS {
            let mut n = 0;
            while n < MAX_ESCAPE_BITS && self.direct() == 1 {
                n = n.wrapping_add(1);
            }
            let mut r: i64 = 0;
            for _ in 0..n {
                r = (r << 1) | i64::from(self.direct());
            }
            magnitude = magnitude.wrapping_add((1i64 << n).wrapping_sub(1).wrapping_add(r));
        }
        if negative {
            magnitude.wrapping_neg()
        } else {
            magnitude
        }
    }
}
