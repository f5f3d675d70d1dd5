//! The encoder side of the project's one static entropy coder (SPEC.md
//! §10): count symbols, normalise the counts to `M = 2^n` at the cost
//! minimum, write the table, rANS-encode (in reverse) into the bytes
//! `mocap_decoder::entropy` reads.
//!
//! Hand-written, not a crate: the format must be ours (SPEC.md is the
//! bitstream's source of truth) and the decoder must be `no_std`, free of
//! allocation and panics, and read its tables straight from flash. The rANS
//! crates decode through models they build in memory from the counts
//! (`constriction`'s lookup decoder models hold a `Vec<u16>` symbol table
//! and a `Box<[u16]>` slot table; the `no_std` `ans` crate builds a
//! `FrequencyTable` from counts and its batch decoder returns a `Vec`), and
//! none has a serialised table format read in place; a compact table the MCU
//! scans where it lies is the point here, and the coder itself is a few
//! dozen lines.
//!
//! ```text
//! let model = Model::fit(&symbols)?;        // histogram → normalised table, best n
//! let mut bytes = model.table_bytes();      // §10.2
//! bytes.extend(model.encode_symbols(&symbols)?);  // one block: state + renormalisation bytes
//! ```
//!
//! A codec that needs random access codes each block with its own
//! [`Model::encode`] call (one table, many blocks) and stores where each
//! block starts (SPEC.md §10.5).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

pub use mocap_decoder::entropy::{MAX_ALPHABET, MAX_PRECISION, MAX_RAW_BITS, STATE_LOW};

/// What the entropy encoder refuses.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EntropyError {
    /// A symbol the table gives no probability (outside the alphabet or a
    /// count of 0).
    #[error("symbol {symbol} has no probability in the table")]
    NoProbability {
        /// The symbol.
        symbol: u32,
    },
    /// The alphabet is empty or larger than 65 536 symbols.
    #[error("alphabet of {0} symbols (1 … 65 536)")]
    Alphabet(u64),
    /// More raw bits than one step takes (16).
    #[error("{0} raw bits in one step (at most 16)")]
    RawBits(u32),
    /// An escaped value too far above the escape symbol: `value − E + 1`
    /// must be below `2^32`.
    #[error("value {value} too large to escape from symbol {escape}")]
    ValueTooLarge {
        /// The value.
        value: u32,
        /// The escape symbol `E = A − 1`.
        escape: u32,
    },
}

/// One coding step, in decoding order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// A symbol through the table.
    Symbol(u32),
    /// `bits ≤ 16` raw bits of `value` (SPEC.md §10.4).
    Raw {
        /// The value, `< 2^bits`.
        value: u32,
        /// How many bits.
        bits: u32,
    },
}

/// A normalised frequency table: `n`, and counts that add up to `M = 2^n`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Model {
    precision: u32,
    counts: Vec<u32>,
    cum: Vec<u32>,
}

impl Model {
    /// The table (best precision, [`Model::best`]) for `symbols`, its
    /// alphabet `max + 1` (one symbol, `0`, for an empty stream).
    pub fn fit(symbols: &[u32]) -> Result<Model, EntropyError> {
        Model::best(&histogram(symbols))
    }

    /// The table for escaped values (SPEC.md §10.4): values `≥ escape`
    /// count as symbol `escape`, the alphabet is `escape + 1`.
    pub fn fit_values(values: &[u32], escape: u32) -> Result<Model, EntropyError> {
        let a = u64::from(escape) + 1;
        if a > u64::from(MAX_ALPHABET) {
            return Err(EntropyError::Alphabet(a));
        }
        let mut hist = vec![0u64; a as usize];
        for &v in values {
            hist[v.min(escape) as usize] += 1;
        }
        Model::best(&hist)
    }

    /// The escape symbol `E` and table for `values` (SPEC.md §10.4) of
    /// least estimated total size (table, coded symbols, raw bits of the
    /// escapes, state) over `E` = 1, 2, 3, 4, 6, 8, 12, … and `max + 1` (no
    /// escape used): long-tailed values keep a small table.
    pub fn fit_values_best(values: &[u32]) -> Result<(Model, u32), EntropyError> {
        let max = values.iter().copied().max().unwrap_or(0);
        let top = max.saturating_add(1).min(MAX_ALPHABET - 1);
        let mut candidates = vec![top];
        let mut e = 1u32;
        while e < top {
            candidates.push(e);
            if e >= 2 && e + e / 2 < top {
                candidates.push(e + e / 2);
            }
            e *= 2;
        }
        let mut best: Option<(f64, Model, u32)> = None;
        for e in candidates {
            let mut hist = vec![0u64; e as usize + 1];
            let mut raw_bits = 0f64;
            for &v in values {
                hist[v.min(e) as usize] += 1;
                if v >= e {
                    let u = u64::from(v - e) + 1;
                    raw_bits += f64::from(5 + 63 - u.leading_zeros());
                }
            }
            let Ok(m) = Model::best(&hist) else {
                continue;
            };
            let bits = m.table_bytes().len() as f64 * 8.0 + m.coded_bits(&hist) + raw_bits;
            if best.as_ref().is_none_or(|(b, _, _)| bits < *b) {
                best = Some((bits, m, e));
            }
        }
        best.map(|(_, m, e)| (m, e))
            .ok_or(EntropyError::Alphabet(u64::from(top) + 1))
    }

    /// The table of least total size (table bytes + coded symbols + the
    /// 4-byte state) over every precision `n ≤ 15` that holds the present
    /// symbols, for symbol counts `hist` (its length is the alphabet).
    pub fn best(hist: &[u64]) -> Result<Model, EntropyError> {
        check_alphabet(hist.len())?;
        let mut best: Option<(f64, Model)> = None;
        for n in 0..=MAX_PRECISION {
            let Some(m) = Model::with_precision(hist, n) else {
                continue;
            };
            let bits = m.table_bytes().len() as f64 * 8.0 + m.coded_bits(hist) + 32.0;
            if best.as_ref().is_none_or(|(b, _)| bits < *b) {
                best = Some((bits, m));
            }
        }
        // n = 15 always holds ≤ 32 768 present symbols; more cannot be coded.
        best.map(|(_, m)| m)
            .ok_or(EntropyError::Alphabet(hist.len() as u64))
    }

    /// The cost-minimal table at precision `n`: every present symbol gets
    /// at least 1, absent symbols 0, and the counts minimise the coded size
    /// `Σ hist[s] · log2(M / f[s])` (a separable concave maximisation, so
    /// handing out the `M − present` units one by one to the largest gain
    /// `hist[s] · log2((f + 1) / f)` is exact). `None` when `2^n` is below
    /// the number of present symbols or a stored count would need 16 bits.
    pub fn with_precision(hist: &[u64], n: u32) -> Option<Model> {
        if n > MAX_PRECISION || hist.is_empty() || hist.len() > MAX_ALPHABET as usize {
            return None;
        }
        let m = 1u32 << n;
        let present = hist.iter().filter(|&&h| h > 0).count() as u64;
        let mut counts: Vec<u32> = hist.iter().map(|&h| u32::from(h > 0)).collect();
        if present == 0 {
            // An empty stream: everything on symbol 0.
            counts[0] = m;
        } else if present > u64::from(m) {
            return None;
        } else {
            let mut heap: BinaryHeap<Gain> = hist
                .iter()
                .enumerate()
                .filter(|(_, &h)| h > 0)
                .map(|(s, &h)| Gain::new(s, h, 1))
                .collect();
            for _ in 0..(u64::from(m) - present) {
                let g = heap.pop().expect("a present symbol");
                counts[g.symbol] += 1;
                heap.push(Gain::new(g.symbol, hist[g.symbol], counts[g.symbol]));
            }
        }
        let model = Model::from_counts(n, counts)?;
        Some(model)
    }

    /// A table from its counts (they must add up to `2^n`, at most 65 536
    /// of them, all but the last below `2^15`).
    pub fn from_counts(n: u32, counts: Vec<u32>) -> Option<Model> {
        if n > MAX_PRECISION
            || counts.is_empty()
            || counts.len() > MAX_ALPHABET as usize
            || counts.iter().map(|&c| u64::from(c)).sum::<u64>() != 1u64 << n
            || counts[..counts.len() - 1].iter().any(|&c| c >= 1 << 15)
        {
            return None;
        }
        let mut cum = Vec::with_capacity(counts.len() + 1);
        let mut c = 0;
        // Symbol 0 first: its interval is [0, f0) (§10.3).
        for &f in &counts {
            cum.push(c);
            c += f;
        }
        cum.push(c);
        Some(Model {
            precision: n,
            counts,
            cum,
        })
    }

    /// `n` (`M = 2^n`).
    pub fn precision(&self) -> u32 {
        self.precision
    }

    /// The normalised counts, symbol by symbol.
    pub fn counts(&self) -> &[u32] {
        &self.counts
    }

    /// `W`: the bits of the largest stored count (symbols `0 … A − 2`).
    pub fn width(&self) -> u32 {
        let stored = &self.counts[..self.counts.len() - 1];
        let max = stored.iter().copied().max().unwrap_or(0);
        32 - max.leading_zeros()
    }

    /// The table's bytes (SPEC.md §10.2).
    pub fn table_bytes(&self) -> Vec<u8> {
        let big_w = self.width();
        let mut out = vec![(self.precision | (big_w << 4)) as u8];
        let mut v = self.counts.len() as u32;
        // postcard's varint (§3.1).
        while v >= 0x80 {
            out.push((v as u8) | 0x80);
            v >>= 7;
        }
        out.push(v as u8);
        let mut bits = crate::codec::bits::BitWriter::default();
        let mut rem = 1u32 << self.precision;
        for &c in &self.counts[..self.counts.len() - 1] {
            let w = big_w.min(32 - rem.leading_zeros());
            bits.write(c, w as u8);
            rem -= c;
        }
        out.extend(bits.finish());
        out
    }

    /// The ideal size of `hist`'s symbols under this table, in bits
    /// (the coder comes within a fraction of a bit of it per stream, plus
    /// the 4-byte state).
    pub fn coded_bits(&self, hist: &[u64]) -> f64 {
        let m = f64::from(1u32 << self.precision);
        hist.iter()
            .zip(&self.counts)
            .filter(|(&h, _)| h > 0)
            .map(|(&h, &f)| h as f64 * (m / f64::from(f)).log2())
            .sum()
    }

    /// One block of symbols: the stream the decoder reads from its first
    /// byte (state, then the renormalisation bytes).
    pub fn encode_symbols(&self, symbols: &[u32]) -> Result<Vec<u8>, EntropyError> {
        let ops: Vec<Op> = symbols.iter().map(|&s| Op::Symbol(s)).collect();
        self.encode(&ops)
    }

    /// One block of escaped values (SPEC.md §10.4), the escape being the
    /// last symbol `E = A − 1`.
    pub fn encode_values(&self, values: &[u32]) -> Result<Vec<u8>, EntropyError> {
        let escape = (self.counts.len() - 1) as u32;
        let mut ops = Vec::with_capacity(values.len());
        for &v in values {
            push_value(&mut ops, v, escape)?;
        }
        self.encode(&ops)
    }

    /// One block of steps, given in decoding order (rANS encodes them in
    /// reverse). The state starts at `2^23` and is flushed as four bytes,
    /// little-endian, at the stream's start.
    pub fn encode(&self, ops: &[Op]) -> Result<Vec<u8>, EntropyError> {
        let steps = ops
            .iter()
            .map(|&op| self.step(op))
            .collect::<Result<Vec<Step>, EntropyError>>()?;
        Ok(encode_steps(&steps))
    }

    /// The rANS step of `op` under this table.
    pub fn step(&self, op: Op) -> Result<Step, EntropyError> {
        match op {
            Op::Symbol(s) => {
                let f = self.counts.get(s as usize).copied().unwrap_or(0);
                if f == 0 {
                    return Err(EntropyError::NoProbability { symbol: s });
                }
                Ok(Step {
                    f,
                    c: self.cum[s as usize],
                    scale: self.precision,
                })
            }
            Op::Raw { value, bits } => {
                if bits > MAX_RAW_BITS {
                    return Err(EntropyError::RawBits(bits));
                }
                Ok(Step {
                    f: 1,
                    c: value & ((1u32 << bits) - 1),
                    scale: bits,
                })
            }
        }
    }

    /// Appends the steps of the escaped value `v` (SPEC.md §10.4) under
    /// this table, its escape the last symbol: for streams that mix the
    /// steps of several tables ([`encode_steps`]).
    pub fn push_value_steps(&self, out: &mut Vec<Step>, v: u32) -> Result<(), EntropyError> {
        let mut ops = Vec::with_capacity(4);
        push_value(&mut ops, v, (self.counts.len() - 1) as u32)?;
        for op in ops {
            out.push(self.step(op)?);
        }
        Ok(())
    }
}

/// One rANS step: the count `f`, start `c` and scale (`n` of the table, or
/// the raw bits' `k`) of one symbol or raw value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    f: u32,
    c: u32,
    scale: u32,
}

/// One block of steps, in decoding order, of any tables (rANS encodes
/// them in reverse; SPEC.md §10.5). The state starts at `2^23` and is
/// flushed as four bytes, little-endian, at the stream's start.
pub fn encode_steps(steps: &[Step]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut x: u32 = STATE_LOW;
    for &Step { f, c, scale } in steps.iter().rev() {
        // x_max = ((L >> scale) << 8) · f: after the step x < 2^31.
        let x_max = u64::from(f) << (31 - scale);
        while u64::from(x) >= x_max {
            out.push(x as u8);
            x >>= 8;
        }
        x = ((x / f) << scale) + (x % f) + c;
    }
    out.extend_from_slice(&x.to_be_bytes());
    out.reverse();
    out
}

/// Appends the steps of value `v` with escape symbol `escape` (§10.4).
pub fn push_value(ops: &mut Vec<Op>, v: u32, escape: u32) -> Result<(), EntropyError> {
    if v < escape {
        ops.push(Op::Symbol(v));
        return Ok(());
    }
    let u = u64::from(v - escape) + 1;
    if u >= 1 << 32 {
        return Err(EntropyError::ValueTooLarge { value: v, escape });
    }
    let k = 63 - u.leading_zeros();
    let r = (u - (1 << k)) as u32;
    ops.push(Op::Symbol(escape));
    ops.push(Op::Raw { value: k, bits: 5 });
    if k > MAX_RAW_BITS {
        ops.push(Op::Raw {
            value: r & 0xffff,
            bits: MAX_RAW_BITS,
        });
        ops.push(Op::Raw {
            value: r >> MAX_RAW_BITS,
            bits: k - MAX_RAW_BITS,
        });
    } else {
        ops.push(Op::Raw { value: r, bits: k });
    }
    Ok(())
}

/// Symbol counts; the alphabet is `max + 1` (`[0]` for no symbols).
pub fn histogram(symbols: &[u32]) -> Vec<u64> {
    let a = symbols.iter().copied().max().map_or(1, |m| m as usize + 1);
    let mut hist = vec![0u64; a];
    for &s in symbols {
        hist[s as usize] += 1;
    }
    hist
}

/// The Shannon entropy of `hist`'s symbols, in bits (`N · H`).
pub fn shannon_bits(hist: &[u64]) -> f64 {
    let n: u64 = hist.iter().sum();
    if n == 0 {
        return 0.0;
    }
    let n = n as f64;
    hist.iter()
        .filter(|&&h| h > 0)
        .map(|&h| -(h as f64) * (h as f64 / n).log2())
        .sum()
}

/// Table and one block for `symbols`: [`Model::fit`], then
/// `table_bytes ++ encode_symbols` (the form of SPEC.md §7.7).
pub fn encode_all(symbols: &[u32]) -> Result<Vec<u8>, EntropyError> {
    let model = Model::fit(symbols)?;
    let mut out = model.table_bytes();
    out.extend(model.encode_symbols(symbols)?);
    Ok(out)
}

fn check_alphabet(a: usize) -> Result<(), EntropyError> {
    if a == 0 || a > MAX_ALPHABET as usize {
        return Err(EntropyError::Alphabet(a as u64));
    }
    Ok(())
}

/// The gain of one more unit of count for a symbol, ordered by gain, then
/// by the smaller symbol (deterministic bytes).
struct Gain {
    gain: f64,
    symbol: usize,
}

impl Gain {
    fn new(symbol: usize, h: u64, f: u32) -> Gain {
        let gain = h as f64 * (f64::from(f + 1) / f64::from(f)).log2();
        Gain { gain, symbol }
    }
}

impl PartialEq for Gain {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Gain {}
impl PartialOrd for Gain {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Gain {
    fn cmp(&self, o: &Self) -> Ordering {
        self.gain
            .total_cmp(&o.gain)
            .then_with(|| o.symbol.cmp(&self.symbol))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mocap_decoder::entropy::{Decoder, Table};

    fn decode(bytes: &[u8], count: usize) -> Vec<u32> {
        let (t, used) = Table::parse(bytes).unwrap();
        let mut d = Decoder::new(t, &bytes[used..]).unwrap();
        let out = (0..count).map(|_| d.symbol()).collect();
        assert!(d.is_finished(), "stream ends where the encoder began");
        out
    }

    #[test]
    fn roundtrips_small_streams() {
        for s in [
            vec![],
            vec![0],
            vec![5],
            vec![0, 0, 0, 0],
            vec![0, 1, 2, 3, 2, 1, 0],
            vec![7, 7, 7, 1, 7, 7, 0, 7],
        ] {
            let bytes = encode_all(&s).unwrap();
            assert_eq!(decode(&bytes, s.len()), s, "{s:?}");
        }
    }

    #[test]
    fn normaliser_gives_every_present_symbol_a_count() {
        let hist = [1000u64, 0, 1, 1, 500, 0, 1];
        for n in 3..=12 {
            let m = Model::with_precision(&hist, n).unwrap();
            assert_eq!(m.counts().iter().sum::<u32>(), 1 << n);
            for (h, c) in hist.iter().zip(m.counts()) {
                assert_eq!(*h > 0, *c > 0, "n={n}");
            }
        }
        assert!(
            Model::with_precision(&hist, 2).is_none(),
            "5 symbols, M = 4"
        );
    }

    #[test]
    fn normaliser_is_optimal() {
        // Against every allocation of M = 16 over four present symbols.
        for hist in [
            [9u64, 3, 2, 1],
            [100, 1, 1, 1],
            [5, 5, 5, 5],
            [1000, 37, 3, 250],
        ] {
            let greedy = Model::with_precision(&hist, 4).unwrap().coded_bits(&hist);
            let mut best = f64::INFINITY;
            for a in 1..16u32 {
                for b in 1..16 - a {
                    for c in 1..16 - a - b {
                        let m = Model::from_counts(4, vec![a, b, c, 16 - a - b - c]).unwrap();
                        best = best.min(m.coded_bits(&hist));
                    }
                }
            }
            assert!((greedy - best).abs() < 1e-9, "{hist:?}: {greedy} vs {best}");
        }
    }

    #[test]
    fn normaliser_beats_rounding() {
        // Cost of the greedy table never above that of plain rounding with
        // a fix-up on the largest count.
        let hist = [5000u64, 3000, 1000, 500, 300, 100, 50, 30, 10, 5, 3, 1, 1];
        let n = 8;
        let m = Model::with_precision(&hist, n).unwrap();
        let total: u64 = hist.iter().sum();
        let mut rounded: Vec<u32> = hist
            .iter()
            .map(|&h| ((h as f64 * 256.0 / total as f64).round() as u32).max(1))
            .collect();
        let sum: u32 = rounded.iter().sum();
        rounded[0] = rounded[0] + 256 - sum;
        let r = Model::from_counts(n, rounded).unwrap();
        assert!(m.coded_bits(&hist) <= r.coded_bits(&hist));
    }

    #[test]
    fn values_escape_and_roundtrip() {
        let values = [0u32, 1, 2, 3, 4, 100, 70_000, u32::MAX - 3, 3, 0];
        let model = Model::fit_values(&values, 3).unwrap();
        let mut bytes = model.table_bytes();
        bytes.extend(model.encode_values(&values).unwrap());
        let (t, used) = Table::parse(&bytes).unwrap();
        let mut d = Decoder::new(t, &bytes[used..]).unwrap();
        let got: Vec<u32> = values.iter().map(|_| d.value()).collect();
        assert_eq!(got, values);
        assert!(d.is_finished());
        assert_eq!(
            model.encode_values(&[u32::MAX]).err(),
            None,
            "E = 3: u32::MAX − 3 + 1 < 2^32"
        );
        let m0 = Model::fit_values(&[0, 1], 0).unwrap();
        assert!(matches!(
            m0.encode_values(&[u32::MAX]),
            Err(EntropyError::ValueTooLarge { .. })
        ));
    }

    #[test]
    fn best_escape_beats_a_full_table_on_long_tails() {
        // Mostly small values, a long sparse tail.
        let values: Vec<u32> = (0..20_000u32)
            .map(|i| {
                let h = i.wrapping_mul(2_654_435_761);
                if h % 50 == 0 {
                    h % 5000
                } else {
                    (h >> 7) % 4 + (h >> 20) % 3
                }
            })
            .collect();
        let full = encode_all(&values).unwrap();
        let (model, e) = Model::fit_values_best(&values).unwrap();
        let mut bytes = model.table_bytes();
        bytes.extend(model.encode_values(&values).unwrap());
        assert!(
            e < 5000 && bytes.len() < full.len(),
            "E = {e}: {} vs {}",
            bytes.len(),
            full.len()
        );
        let (t, used) = Table::parse(&bytes).unwrap();
        let mut d = Decoder::new(t, &bytes[used..]).unwrap();
        assert!(values.iter().all(|&v| d.value() == v));
        assert!(d.is_finished());
    }

    #[test]
    fn refuses_symbols_without_probability() {
        let model = Model::fit(&[0, 1, 1]).unwrap();
        assert_eq!(
            model.encode_symbols(&[2]),
            Err(EntropyError::NoProbability { symbol: 2 })
        );
        assert!(matches!(
            model.encode(&[Op::Raw { value: 0, bits: 17 }]),
            Err(EntropyError::RawBits(17))
        ));
    }

    #[test]
    fn blocks_restart_at_their_offsets() {
        let symbols: Vec<u32> = (0..3000u32).map(|i| (i * 7 + i / 13) % 5).collect();
        let model = Model::fit(&symbols).unwrap();
        let table = model.table_bytes();
        let blocks: Vec<Vec<u8>> = symbols
            .chunks(256)
            .map(|b| model.encode_symbols(b).unwrap())
            .collect();
        let (t, _) = Table::parse(&table).unwrap();
        // Decode the blocks out of order, each from its own start.
        for (i, b) in blocks.iter().enumerate().rev() {
            let mut d = Decoder::new(t, b).unwrap();
            let chunk = &symbols[i * 256..((i + 1) * 256).min(symbols.len())];
            for &s in chunk {
                assert_eq!(d.symbol(), s);
            }
            assert!(d.is_finished());
        }
    }
}
