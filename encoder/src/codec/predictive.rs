//! The `predictive` codec's encoder (SPEC.md §5b): per channel a predictor
//! and a quantisation step no larger than the tolerance allows, a beam
//! search for the residuals that cost the fewest bits while every value
//! stays within the tolerance, and the adaptive binary range coder the
//! decoder mirrors.

use mocap_decoder::consts::predictive::{
    CONTEXTS, MAGNITUDE_STEPS, MAX_ESCAPE_BITS, MAX_STEP, MODE_CONSTANT, MODE_STEP_SHIFT,
    MOVE_BITS, PREDICTOR_WEIGHTS, PROBS_PER_CONTEXT, PROB_BITS, PROB_INIT, TOP,
};

use mocap_decoder::predictive::{predict, value};

use rayon::prelude::*;

use super::CodecError;
use crate::container::{varint, zigzag, ByteCursor};

/// Frames per block when the caller does not choose: about this many
/// seconds (random access decodes at most one block).
pub const DEFAULT_BLOCK_SECONDS: f64 = 10.0;
/// States the residual search keeps per frame.
const BEAM: usize = 24;
/// Step candidates, eighths of the largest step `2·tol + 1`.
const STEP_EIGHTHS: [i64; 5] = [8, 7, 6, 5, 4];

/// An encoded section and the values the decoder will produce.
#[derive(Clone, Debug)]
pub struct Encoded {
    /// The section bytes.
    pub section: Vec<u8>,
    /// Decoded values, `[channel][frame]`.
    pub decoded: Vec<Vec<i32>>,
    /// Bytes of the range-coded blocks.
    pub payload_bytes: usize,
}

/// How one channel is coded.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Constant(i32),
    Predicted { weight: usize, multiplier: u32 },
}

impl Mode {
    fn bits(self) -> u32 {
        match self {
            Mode::Constant(_) => MODE_CONSTANT,
            Mode::Predicted { weight, multiplier } => {
                (multiplier << MODE_STEP_SHIFT) | weight as u32
            }
        }
    }
}

/// Encodes `values` (`[channel][frame]`, all the same length ≥ 1) with
/// every decoded value within `tol[c]` of the input, in blocks of
/// `block_frames` frames.
pub fn encode(values: &[Vec<i32>], tol: &[i64], block_frames: u32) -> Result<Encoded, CodecError> {
    encode_with(values, tol, block_frames, &|_, _| {})
}

/// [`encode`], calling `on_channel(done, total)` as channels are searched
/// (from the encoding threads; twice per channel: its step, its residuals).
pub fn encode_with(
    values: &[Vec<i32>],
    tol: &[i64],
    block_frames: u32,
    on_channel: &(dyn Fn(usize, usize) + Sync),
) -> Result<Encoded, CodecError> {
    let done = std::sync::atomic::AtomicUsize::new(0);
    let total = 2 * values.len();
    let tick = || {
        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        on_channel(d, total);
    };
    let frames = values.first().map_or(0, Vec::len);
    if frames == 0 || values.iter().any(|v| v.len() != frames) || tol.len() != values.len() {
        return Err(CodecError::PredictiveShape);
    }
    let block = block_frames.max(1) as usize;
    // Largest usable tolerance: the step 2·tol + 1 must fit MAX_STEP.
    let max_tol = i64::from(MAX_STEP - 1) / 2;
    let tol: Vec<i64> = tol.iter().map(|&t| t.clamp(0, max_tol)).collect();
    let constant: Vec<Option<i32>> = values
        .iter()
        .zip(&tol)
        .map(|(v, &t)| {
            let (lo, hi) = min_max(v);
            (i64::from(hi) - i64::from(lo) <= 2 * t)
                .then(|| ((i64::from(lo) + i64::from(hi)).div_euclid(2)) as i32)
        })
        .collect();
    let unit = values
        .iter()
        .zip(&tol)
        .zip(&constant)
        .filter(|(_, c)| c.is_none())
        .map(|((_, &t), _)| ((2 * t + 1) / 8).max(1))
        .min()
        .unwrap_or(1);
    // Per channel, the predictor and step whose greedy residuals cost the
    // least (each channel alone, a fresh model: a proxy for the shared one).
    // Channels are independent: in parallel, in channel order.
    let chosen: Vec<Result<(Mode, Vec<i64>), CodecError>> = values
        .par_iter()
        .zip(&tol)
        .zip(&constant)
        .map(|((v, &t), c)| {
            tick();
            if let Some(k) = c {
                return Ok((Mode::Constant(*k), Vec::new()));
            }
            let mut best: Option<(f64, Mode, Vec<i64>)> = None;
            for m in multipliers(t, unit) {
                for weight in 0..PREDICTOR_WEIGHTS.len() {
                    let q = quantise_greedy(v, t, m as i64 * unit, weight, block);
                    let cost = adaptive_cost(&q, block);
                    if best.as_ref().is_none_or(|b| cost < b.0) {
                        best = Some((
                            cost,
                            Mode::Predicted {
                                weight,
                                multiplier: m,
                            },
                            q,
                        ));
                    }
                }
            }
            let (_, mode, q) = best.ok_or(CodecError::NoPredictiveStep)?;
            Ok((mode, q))
        })
        .collect();
    let mut modes = Vec::with_capacity(values.len());
    let mut greedy = Vec::with_capacity(values.len());
    for one in chosen {
        let (mode, q) = one?;
        modes.push(mode);
        greedy.push(q);
    }
    // Residuals by beam search under static costs learnt from the greedy
    // residuals of every channel.
    let costs = StaticCosts::learn(&greedy, block);
    let residuals: Vec<Vec<i64>> = values
        .par_iter()
        .zip(&tol)
        .zip(&modes)
        .map(|((v, &t), mode)| {
            tick();
            match *mode {
                Mode::Constant(_) => Vec::new(),
                Mode::Predicted { weight, multiplier } => {
                    beam_search(v, t, i64::from(multiplier) * unit, weight, block, &costs)
                }
            }
        })
        .collect();
    // The stream, block by block, frame-major as the decoder reads it.
    let mut blocks = Vec::new();
    for start in (0..frames).step_by(block) {
        let end = (start + block).min(frames);
        let mut enc = RangeEncoder::new();
        let mut probs = [PROB_INIT; CONTEXTS * PROBS_PER_CONTEXT];
        let mut ctx = vec![0usize; values.len()];
        for f in start..end {
            for (c, q) in residuals.iter().enumerate() {
                if let Some(&q) = q.get(f) {
                    enc.residual(&mut probs, ctx[c], q);
                    ctx[c] = context(q);
                }
            }
        }
        blocks.push(enc.finish());
    }
    let decoded: Vec<Vec<i32>> = modes
        .iter()
        .zip(&residuals)
        .map(|(mode, q)| match *mode {
            Mode::Constant(k) => vec![k; frames],
            Mode::Predicted { weight, multiplier } => {
                reconstruct(q, i64::from(multiplier) * unit, weight, block)
            }
        })
        .collect();
    let mut out = Vec::new();
    varint(&mut out, values.len() as u32);
    varint(&mut out, block as u32);
    varint(&mut out, unit as u32);
    for mode in &modes {
        varint(&mut out, mode.bits());
        if let Mode::Constant(k) = mode {
            zigzag(&mut out, *k);
        }
    }
    varint(&mut out, blocks.len() as u32);
    for b in &blocks {
        varint(&mut out, b.len() as u32);
    }
    let payload_bytes = blocks.iter().map(Vec::len).sum();
    for b in blocks {
        out.extend_from_slice(&b);
    }
    Ok(Encoded {
        section: out,
        decoded,
        payload_bytes,
    })
}

/// What `mocap info` shows of a predictive section.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionInfo {
    /// Coded channels.
    pub coded: usize,
    /// Constant channels.
    pub constant: usize,
    /// Frames per block.
    pub block_frames: u32,
    /// Blocks.
    pub blocks: u32,
    /// Bytes of the range-coded blocks.
    pub payload_bytes: usize,
    /// Coded channels per predictor weight 0, 2, 3, 4 (quarters).
    pub weights: [usize; 4],
    /// Player state words the clip needs.
    pub state_words: usize,
}

/// Reads the structure of a predictive section (`None` if malformed).
pub fn inspect(section: &[u8]) -> Option<SectionInfo> {
    let mut r = ByteCursor::new(section);
    let mut next = || r.varint();
    let channels = next()? as usize;
    let block_frames = next()?;
    let _unit = next()?;
    let (mut constant, mut weights) = (0, [0usize; 4]);
    for _ in 0..channels {
        let mode = next()?;
        if mode & MODE_CONSTANT != 0 {
            constant += 1;
            next()?;
        } else {
            weights[(mode & 3) as usize] += 1;
        }
    }
    let blocks = next()?;
    let mut payload_bytes = 0;
    for _ in 0..blocks {
        payload_bytes += next()? as usize;
    }
    Some(SectionInfo {
        coded: channels - constant,
        constant,
        block_frames,
        blocks,
        payload_bytes,
        weights,
        state_words: 3 * channels + mocap_decoder::consts::predictive::STATE_EXTRA_WORDS,
    })
}

impl SectionInfo {
    /// The lines `mocap info` prints for the section.
    pub fn describe(&self) -> String {
        format!(
            "  predictive codec: {} coded + {} constant channels, blocks of {} frames, {} blocks, {} bytes of range-coded residuals, state {} words\n  predictor weights (of 4) 0/2/3/4: {:?} channels\n",
            self.coded,
            self.constant,
            self.block_frames,
            self.blocks,
            self.payload_bytes,
            self.state_words,
            self.weights
        )
    }
}

fn min_max(v: &[i32]) -> (i32, i32) {
    v.iter()
        .fold((i32::MAX, i32::MIN), |(lo, hi), &x| (lo.min(x), hi.max(x)))
}

/// Step multipliers to try for tolerance `t`: eighths of `2t + 1`, in
/// `unit`s, at least 1 and small enough for the mode varint. Every step is
/// at most `2t + 1` (`unit` is at most an eighth of it, or 1).
fn multipliers(t: i64, unit: i64) -> Vec<u32> {
    let s0 = 2 * t + 1;
    let cap = i64::from(u32::MAX >> MODE_STEP_SHIFT);
    let mut m: Vec<u32> = STEP_EIGHTHS
        .iter()
        .map(|&e| ((s0 * e / 8) / unit).clamp(1, cap) as u32)
        .collect();
    m.dedup();
    m
}

/// Residuals `k` at which the value stays within `tol` of `x`.
fn candidates(x: i32, pred: i64, step: i64, tol: i64) -> impl Iterator<Item = i64> {
    let lo = (i64::from(x) - tol - pred).div_euclid(step);
    let hi = (i64::from(x) + tol - pred).div_euclid(step) + 1;
    (lo..=hi).filter(move |&k| (i64::from(value(pred, k, step)) - i64::from(x)).abs() <= tol)
}

fn context(q: i64) -> usize {
    q.unsigned_abs().min(CONTEXTS as u64 - 1) as usize
}

/// Closed-loop quantisation taking, at every frame, the smallest residual
/// that keeps the value within `tol`.
fn quantise_greedy(x: &[i32], tol: i64, step: i64, weight: usize, block: usize) -> Vec<i64> {
    let (mut v1, mut v2) = (0i32, 0i32);
    let mut q = Vec::with_capacity(x.len());
    for (f, &xf) in x.iter().enumerate() {
        let pred = predict((f % block) as u32, v1, v2, weight);
        let k = candidates(xf, pred, step, tol)
            .min_by_key(|k| k.unsigned_abs())
            .unwrap_or_else(|| (i64::from(xf) - pred).div_euclid(step));
        q.push(k);
        v2 = v1;
        v1 = value(pred, k, step);
    }
    q
}

/// The values residuals `q` decode to.
fn reconstruct(q: &[i64], step: i64, weight: usize, block: usize) -> Vec<i32> {
    let (mut v1, mut v2) = (0i32, 0i32);
    q.iter()
        .enumerate()
        .map(|(f, &k)| {
            let v = value(predict((f % block) as u32, v1, v2, weight), k, step);
            v2 = v1;
            v1 = v;
            v
        })
        .collect()
}

/// Bits of `x` with probability-of-zero `p` (of 2^PROB_BITS).
fn bit_cost(p: u16, bit: u32) -> f64 {
    // Every (p, bit) computed once: the step search asks for them for every
    // decision of every candidate.
    static TABLE: std::sync::OnceLock<Vec<[f64; 2]>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=1u32 << PROB_BITS)
            .map(|p| [0, 1].map(|b| bit_cost_of(p as u16, b)))
            .collect()
    });
    match table.get(usize::from(p)) {
        Some(c) => c[usize::from(bit != 0)],
        None => bit_cost_of(p, bit),
    }
}

fn bit_cost_of(p: u16, bit: u32) -> f64 {
    let p0 = f64::from(p) / f64::from(1u32 << PROB_BITS);
    -(if bit == 0 { p0 } else { 1.0 - p0 }).log2()
}

fn adapt(p: &mut u16, bit: u32) {
    if bit == 0 {
        *p += ((1u16 << PROB_BITS) - *p) >> MOVE_BITS;
    } else {
        *p -= *p >> MOVE_BITS;
    }
}

/// The binary decisions of residual `q` (SPEC.md §5b): (probability index
/// within the context, bit), then the escape's direct bits.
fn decisions(q: i64, mut emit: impl FnMut(Option<usize>, u32)) {
    if q == 0 {
        emit(Some(0), 0);
        return;
    }
    emit(Some(0), 1);
    emit(Some(1), u32::from(q < 0));
    let a = q.unsigned_abs();
    for k in 1..=u64::from(MAGNITUDE_STEPS) {
        let more = u32::from(a > k);
        emit(Some(1 + k as usize), more);
        if more == 0 {
            return;
        }
    }
    // Exp-Golomb of r = a − MAGNITUDE_STEPS − 1 in direct bits.
    let r = a - u64::from(MAGNITUDE_STEPS) - 1;
    let n = (63 - (r + 1).leading_zeros()).min(MAX_ESCAPE_BITS);
    for _ in 0..n {
        emit(None, 1);
    }
    if n < MAX_ESCAPE_BITS {
        emit(None, 0);
    }
    let rest = r + 1 - (1u64 << n);
    for i in (0..n).rev() {
        emit(None, ((rest >> i) & 1) as u32);
    }
}

/// Bits the adaptive coder spends on `q` of one channel alone.
fn adaptive_cost(q: &[i64], block: usize) -> f64 {
    let mut probs = [PROB_INIT; CONTEXTS * PROBS_PER_CONTEXT];
    let mut bits = 0.0;
    let mut ctx = 0;
    for (f, &k) in q.iter().enumerate() {
        if f % block == 0 {
            probs = [PROB_INIT; CONTEXTS * PROBS_PER_CONTEXT];
            ctx = 0;
        }
        let base = ctx * PROBS_PER_CONTEXT;
        decisions(k, |i, b| match i {
            Some(i) => {
                let p = &mut probs[base + i];
                bits += bit_cost(*p, b);
                adapt(p, b);
            }
            None => bits += 1.0,
        });
        ctx = context(k);
    }
    bits
}

/// Static bit costs of a residual per context, from observed residuals.
struct StaticCosts {
    counts: Vec<std::collections::HashMap<i64, f64>>,
    totals: Vec<f64>,
    /// [`StaticCosts::cost`] of the residuals `-NEAR..=NEAR` per context,
    /// computed once (the search asks for them millions of times).
    near: Vec<Vec<f64>>,
}

/// Residuals whose costs [`StaticCosts`] keeps in a table.
const NEAR: i64 = 64;

impl StaticCosts {
    fn learn(residuals: &[Vec<i64>], block: usize) -> Self {
        let mut counts = vec![std::collections::HashMap::new(); CONTEXTS];
        let mut totals = vec![0.0; CONTEXTS];
        for q in residuals {
            let mut ctx = 0;
            for (f, &k) in q.iter().enumerate() {
                if f % block == 0 {
                    ctx = 0;
                }
                *counts[ctx].entry(k).or_insert(0.0) += 1.0;
                totals[ctx] += 1.0;
                ctx = context(k);
            }
        }
        let mut costs = StaticCosts {
            counts,
            totals,
            near: Vec::new(),
        };
        costs.near = (0..CONTEXTS)
            .map(|ctx| (-NEAR..=NEAR).map(|q| costs.compute(ctx, q)).collect())
            .collect();
        costs
    }

    fn cost(&self, ctx: usize, q: i64) -> f64 {
        if (-NEAR..=NEAR).contains(&q) {
            return self.near[ctx][(q + NEAR) as usize];
        }
        self.compute(ctx, q)
    }

    fn compute(&self, ctx: usize, q: i64) -> f64 {
        let seen = self.counts[ctx].get(&q).copied().unwrap_or(0.0);
        // Unseen residuals cost about what their escape code would.
        let unseen = 2.0 * (q.unsigned_abs() as f64 + 1.0).log2();
        -((seen + 0.3) / (self.totals[ctx] + 8.0)).log2() + if seen == 0.0 { unseen } else { 0.0 }
    }
}

/// One state of the residual search.
#[derive(Clone, Copy)]
struct Node {
    v1: i32,
    v2: i32,
    ctx: usize,
    cost: f64,
    back: usize,
    q: i64,
}

/// The residuals of one channel minimising the static cost, every value
/// within `tol`: a beam of [`BEAM`] states `(v1, v2, context)` per frame.
fn beam_search(
    x: &[i32],
    tol: i64,
    step: i64,
    weight: usize,
    block: usize,
    costs: &StaticCosts,
) -> Vec<i64> {
    // Per frame, each kept state's (predecessor, residual): all the way
    // back is all the search needs of a layer.
    let mut layers: Vec<Vec<(usize, i64)>> = Vec::with_capacity(x.len());
    let root = Node {
        v1: 0,
        v2: 0,
        ctx: 0,
        cost: 0.0,
        back: 0,
        q: 0,
    };
    let mut prev = vec![root];
    for (f, &xf) in x.iter().enumerate() {
        let j = f % block;
        let mut next: Vec<Node> = Vec::new();
        for (i, n) in prev.iter().enumerate() {
            let ctx = if j == 0 { 0 } else { n.ctx };
            let pred = predict(j as u32, n.v1, n.v2, weight);
            for k in candidates(xf, pred, step, tol) {
                let node = Node {
                    v1: value(pred, k, step),
                    v2: n.v1,
                    ctx: context(k),
                    cost: n.cost + costs.cost(ctx, k),
                    back: i,
                    q: k,
                };
                // States that predict alike: keep the cheaper.
                let twin = next.iter_mut().find(|m| {
                    m.v1 == node.v1
                        && m.ctx == node.ctx
                        && (weight == 0 || j + 1 == block || j == 0 || m.v2 == node.v2)
                });
                match twin {
                    Some(m) if m.cost <= node.cost => {}
                    Some(m) => *m = node,
                    None => next.push(node),
                }
            }
        }
        if next.is_empty() {
            // Unreachable for step <= 2·tol + 1; fall back to greedy.
            return quantise_greedy(x, tol, step, weight, block);
        }
        next.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        next.truncate(BEAM);
        layers.push(next.iter().map(|n| (n.back, n.q)).collect());
        prev = next;
    }
    let mut q = vec![0; x.len()];
    let mut at = 0;
    for (f, layer) in layers.iter().enumerate().rev() {
        (at, q[f]) = layer[at];
    }
    q
}

/// The encoder side of the adaptive binary range coder (LZMA's scheme).
struct RangeEncoder {
    low: u64,
    range: u32,
    cache: u8,
    cache_size: u64,
    out: Vec<u8>,
}

impl RangeEncoder {
    fn new() -> Self {
        RangeEncoder {
            low: 0,
            range: u32::MAX,
            cache: 0,
            cache_size: 1,
            out: Vec::new(),
        }
    }

    fn shift_low(&mut self) {
        if (self.low as u32) < 0xFF00_0000 || (self.low >> 32) != 0 {
            let carry = (self.low >> 32) as u8;
            let mut temp = self.cache;
            loop {
                self.out.push(temp.wrapping_add(carry));
                temp = 0xFF;
                self.cache_size -= 1;
                if self.cache_size == 0 {
                    break;
                }
            }
            self.cache = ((self.low >> 24) & 0xFF) as u8;
        }
        self.cache_size += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    fn normalize(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    fn bit(&mut self, p: &mut u16, bit: u32) {
        let bound = (self.range >> PROB_BITS) * u32::from(*p);
        if bit == 0 {
            self.range = bound;
        } else {
            self.low += u64::from(bound);
            self.range -= bound;
        }
        adapt(p, bit);
        self.normalize();
    }

    fn direct(&mut self, bit: u32) {
        self.range >>= 1;
        if bit == 1 {
            self.low += u64::from(self.range);
        }
        self.normalize();
    }

    fn residual(&mut self, probs: &mut [u16], ctx: usize, q: i64) {
        let base = ctx * PROBS_PER_CONTEXT;
        decisions(q, |i, b| match i {
            Some(i) => self.bit(&mut probs[base + i], b),
            None => self.direct(b),
        });
    }

    /// The coded bytes: the final value is taken, within the last
    /// interval, with as many trailing zero bytes as possible (the decoder
    /// reads zeros past the end, so they are dropped), and the first byte —
    /// always the initial cache, 0 — is left out (the decoder starts with
    /// the next four).
    fn finish(mut self) -> Vec<u8> {
        let top = self.low + u64::from(self.range);
        for shift in (8..=32).rev().step_by(8) {
            let mask = (1u64 << shift) - 1;
            let v = (self.low + mask) & !mask;
            if v < top {
                self.low = v;
                break;
            }
        }
        for _ in 0..5 {
            self.shift_low();
        }
        let mut out = self.out;
        debug_assert_eq!(out.first(), Some(&0));
        out.remove(0);
        while out.last() == Some(&0) {
            out.pop();
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_codes_round_trip_through_the_binarisation() {
        for q in [0, 1, -1, 8, -8, 9, 10, 100, -1000, 1 << 20, -(1 << 30)] {
            let mut seen = Vec::new();
            decisions(q, |i, b| seen.push((i, b)));
            // Rebuild q from the decisions as the decoder does.
            let mut it = seen.into_iter();
            let z = it.next().unwrap();
            if z.1 == 0 {
                assert_eq!(q, 0);
                continue;
            }
            let neg = it.next().unwrap().1 == 1;
            let mut a = 1u64;
            while a <= u64::from(MAGNITUDE_STEPS) && it.next().unwrap().1 == 1 {
                a += 1;
            }
            if a > u64::from(MAGNITUDE_STEPS) {
                let mut n = 0;
                while n < MAX_ESCAPE_BITS && it.next().unwrap().1 == 1 {
                    n += 1;
                }
                let mut r = 0u64;
                for _ in 0..n {
                    r = (r << 1) | u64::from(it.next().unwrap().1);
                }
                a += (1 << n) - 1 + r;
            }
            assert!(it.next().is_none());
            assert_eq!(if neg { -(a as i64) } else { a as i64 }, q);
        }
    }

    #[test]
    fn every_value_is_within_its_tolerance() {
        let x: Vec<i32> = (0..400)
            .map(|i| ((i as f64 * 0.05).sin() * 40_000.0 + (i % 7) as f64 * 300.0) as i32)
            .collect();
        let flat = vec![1234; 400];
        let enc = encode(&[x.clone(), flat.clone()], &[499, 10], 150).unwrap();
        for (f, (&a, &b)) in x.iter().zip(&enc.decoded[0]).enumerate() {
            assert!((a - b).abs() <= 499, "frame {f}: {a} vs {b}");
        }
        assert_eq!(enc.decoded[1], flat);
        assert!(enc.payload_bytes < 400, "{} bytes", enc.payload_bytes);
    }
}
