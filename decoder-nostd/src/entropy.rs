//! The project's one static entropy coder (SPEC.md §10): rANS with a
//! frequency table normalised to `M = 2^n` (`n ≤ 15`), a 32-bit state and
//! byte-wise renormalisation.
//!
//! Nothing is built in RAM: [`Table`] borrows the table's bytes (in flash on
//! an MCU) and is validated once by [`Table::parse`]; a [`Decoder`] is the
//! table, the state `x` (one `u32`) and the unread stream bytes. Decoding a
//! symbol is a mask, a scan of the fixed-width counts from symbol 0 (symbol
//! 0's count is kept by the table: the most frequent value of a zigzag
//! residual costs one compare), a multiply-add and at most two byte reads.
//! For wide alphabets a caller with `2A + 2` bytes of RAM to spare builds
//! the cumulative counts once ([`Table::index`]) and decodes with
//! [`Decoder::symbol_in`]: a binary search, the same symbols and states.
//! No division, no loop without a bound, no panic on any input: a stream
//! that does not come from the encoder decodes to garbage symbols, never
//! out of bounds.
//!
//! Random access: a codec cuts its symbols into blocks and codes each block
//! as its own stream (the encoder flushes its state at the end of each block,
//! which the decoder reads as its first four bytes); [`Decoder::new`] at a
//! block's byte offset restarts there (SPEC.md §10.5).
//!
//! Public for the encoder and the workspace tests only (`#[doc(hidden)]`,
//! outside semver): codecs use it inside the crate.

use crate::error::Error;
use crate::reader::Reader;

/// The state's lower bound `L`: between two symbols `L ≤ x < 2^31`.
pub const STATE_LOW: u32 = 1 << 23;
/// The largest precision `n` (`M = 2^n`).
pub const MAX_PRECISION: u32 = 15;
/// The largest alphabet (symbols are `0 … A − 1`, `A ≤ 2^16`).
pub const MAX_ALPHABET: u32 = 1 << 16;
/// Raw bits [`Decoder::raw`] reads in one step.
pub const MAX_RAW_BITS: u32 = 16;

/// A validated frequency table borrowed from the bitstream (SPEC.md §10.2).
#[derive(Clone, Copy, Debug)]
pub struct Table<'a> {
    /// `n`: `M = 2^n`.
    precision: u32,
    /// Alphabet size `A ≥ 1`.
    alphabet: u32,
    /// Symbol 0's count.
    count0: u32,
    /// The scan of the counts right after symbol 0's (the hot loop starts
    /// here when the slot is past symbol 0).
    after0: Scan<'a>,
}

fn malformed(rule: &'static str) -> Error {
    Error::EntropyTable { rule }
}

impl<'a> Table<'a> {
    /// Parses and validates the table at the start of `bytes` (SPEC.md
    /// §10.2); returns it and the number of bytes it takes.
    pub fn parse(bytes: &'a [u8]) -> Result<(Table<'a>, usize), Error> {
        let mut r = Reader::new(bytes);
        let head = r.u8().ok_or(malformed("table ends early"))?;
        let precision = u32::from(head & 0x0f);
        let width = u32::from(head >> 4);
        let alphabet = r
            .varint_u32()
            .ok_or(malformed("table ends early or bad varint"))?;
        if alphabet == 0 {
            return Err(malformed("alphabet of 0 symbols"));
        }
        if alphabet > MAX_ALPHABET {
            return Err(malformed("alphabet above 65536 symbols"));
        }
        let counts = r.rest();
        let m = 1u32 << precision;
        let mut scan = Scan::new(counts, width, m);
        let mut count0 = m;
        let mut after0 = scan;
        // Symbols 0 … A − 2 are stored; the last one has what is left.
        for s in 0..alphabet.wrapping_sub(1) {
            let left = scan.rem;
            let f = scan.next();
            if f > left {
                return Err(malformed("a count is above what is left of M"));
            }
            if s == 0 {
                count0 = f;
                after0 = scan;
            }
        }
        if scan.short {
            return Err(malformed("table ends early"));
        }
        if scan.acc != 0 {
            return Err(malformed("padding bits of the counts are not zero"));
        }
        let used = counts.len().wrapping_sub(scan.bytes.len());
        let after0 = Scan {
            // The hot loop never reads past the table's bytes.
            bytes: after0
                .bytes
                .get(..after0.bytes.len().wrapping_sub(scan.bytes.len()))
                .unwrap_or(&[]),
            ..after0
        };
        let table = Table {
            precision,
            alphabet,
            count0,
            after0,
        };
        Ok((table, r.pos().wrapping_sub(counts.len()).wrapping_add(used)))
    }

    /// A table [`Table::parse`] accepted, read again from its bytes (`bytes`
    /// exactly its bytes) in a few steps — its head, its alphabet and its
    /// first count — for codecs that keep only where their tables lie
    /// between calls: the same table as `parse` gave. On bytes that were
    /// never validated it gives some table, never a panic.
    pub fn reread(bytes: &'a [u8]) -> Table<'a> {
        let mut r = Reader::new(bytes);
        let head = r.u8().unwrap_or(0);
        let precision = u32::from(head & 0x0f);
        let alphabet = r.varint_u32().unwrap_or(1).clamp(1, MAX_ALPHABET);
        let m = 1u32 << precision;
        let mut scan = Scan::new(r.rest(), u32::from(head >> 4), m);
        let count0 = if alphabet > 1 { scan.next() } else { m };
        Table {
            precision,
            alphabet,
            count0,
            after0: scan,
        }
    }

    /// `n` (`M = 2^n`).
    pub fn precision(&self) -> u32 {
        self.precision
    }

    /// The alphabet size `A`.
    pub fn alphabet(&self) -> u32 {
        self.alphabet
    }

    /// Symbol `s`'s normalised count (0 past the alphabet); a scan, not for
    /// hot loops.
    pub fn count(&self, s: u32) -> u32 {
        if s >= self.alphabet {
            return 0;
        }
        if s == 0 {
            return self.count0;
        }
        let mut scan = self.after0;
        for _ in 1..s {
            scan.next();
        }
        if s == self.alphabet.wrapping_sub(1) {
            scan.rem
        } else {
            scan.next()
        }
    }

    /// The cumulative counts of the table written into `buf` (the caller's
    /// RAM, `A + 1` entries: `2A + 2` bytes), for [`Decoder::symbol_in`]:
    /// a binary search instead of the scan, for wide alphabets (the scan
    /// costs about 15 instructions per symbol it passes; the search about
    /// as much per halving). `EntropyTable` if `buf` is shorter than `A + 1`.
    pub fn index<'c>(&self, buf: &'c mut [u16]) -> Result<Index<'c>, Error> {
        let a = self.alphabet as usize;
        let cum = buf
            .get_mut(..a.wrapping_add(1))
            .ok_or(malformed("index buffer shorter than the alphabet + 1"))?;
        let mut scan = self.after0;
        let mut at = 0u32;
        let last = self.alphabet.wrapping_sub(1);
        for (s, c) in (0u32..).zip(cum.iter_mut()) {
            // M ≤ 2^15: every cumulative count fits 16 bits.
            *c = at as u16;
            let f = match s {
                0 => self.count0,
                s if s < last => scan.next(),
                s if s == last => scan.rem,
                _ => 0,
            };
            at = at.wrapping_add(f);
        }
        Ok(Index {
            cum,
            alphabet: self.alphabet,
            precision: self.precision,
        })
    }

    /// The symbol whose interval `[cum, cum + f)` holds `slot < M`, with
    /// `cum` and `f` (always found on a validated table). The scan of
    /// [`Scan::next`] in locals, without its end-of-input bookkeeping: the
    /// table was read to its end once by [`Table::parse`], and bytes past
    /// `after0`'s (none on a validated table) read as zero.
    #[inline(always)]
    fn find(&self, slot: u32) -> (u32, u32, u32) {
        if slot < self.count0 {
            return (0, 0, self.count0);
        }
        let a = &self.after0;
        let (mut bytes, mut acc, mut avail, mut rem, mut width) =
            (a.bytes, a.acc, a.avail, a.rem, a.width);
        let mut cum = self.count0;
        let last = self.alphabet.wrapping_sub(1);
        let mut s = 1;
        while s < last {
            // `width ≤ 15`: two bytes at most.
            if avail < width {
                acc |= u32::from(pop(&mut bytes)) << avail;
                avail = avail.wrapping_add(8);
                if avail < width {
                    acc |= u32::from(pop(&mut bytes)) << avail;
                    avail = avail.wrapping_add(8);
                }
            }
            let f = acc & ((1u32 << width).wrapping_sub(1));
            let next = cum.wrapping_add(f);
            if slot < next {
                return (s, cum, f);
            }
            acc >>= width;
            avail = avail.wrapping_sub(width);
            cum = next;
            rem = rem.wrapping_sub(f);
            while rem < (1u32 << width) >> 1 {
                width = width.wrapping_sub(1);
            }
            s = s.wrapping_add(1);
        }
        (last, cum, rem)
    }
}

/// The next byte of `bytes` (0 past the end).
#[inline(always)]
fn pop(bytes: &mut &[u8]) -> u8 {
    match **bytes {
        [b, ref rest @ ..] => {
            *bytes = rest;
            b
        }
        [] => 0,
    }
}

/// The stored counts read in order (§10.2): each field is
/// `min(W, bits(rem))` bits wide, LSB first (§4.4's order), `rem` being what
/// is left of `M`; zeros past the end (`short` then says so).
#[derive(Clone, Copy, Debug)]
struct Scan<'a> {
    bytes: &'a [u8],
    acc: u32,
    avail: u32,
    /// `M` minus the counts read.
    rem: u32,
    /// The next field's width.
    width: u32,
    short: bool,
}

impl<'a> Scan<'a> {
    fn new(bytes: &'a [u8], width: u32, m: u32) -> Self {
        let mut scan = Scan {
            bytes,
            acc: 0,
            avail: 0,
            rem: m,
            width: width & 15,
            short: false,
        };
        scan.narrow();
        scan
    }

    /// `width = min(width, bits(rem))`: `rem` only shrinks, so the width
    /// only narrows, at most 15 times over a whole scan.
    #[inline(always)]
    fn narrow(&mut self) {
        while self.rem < (1u32 << self.width) >> 1 {
            self.width = self.width.wrapping_sub(1);
        }
    }

    /// The next count (`rem` takes it off, wrapping: a validated table
    /// never goes below 0).
    #[inline(always)]
    fn next(&mut self) -> u32 {
        // `width ≤ 15`: at most two bytes, `avail ≤ 30`.
        while self.avail < self.width {
            let b = match *self.bytes {
                [b, ref rest @ ..] => {
                    self.bytes = rest;
                    b
                }
                [] => {
                    self.short = true;
                    // Past 8 · 2 bytes: stop pulling zeros.
                    self.avail = self.width;
                    break;
                }
            };
            self.acc |= u32::from(b) << self.avail;
            self.avail = self.avail.wrapping_add(8);
        }
        let v = self.acc & ((1u32 << self.width).wrapping_sub(1));
        self.acc >>= self.width;
        self.avail = self.avail.wrapping_sub(self.width);
        self.rem = self.rem.wrapping_sub(v);
        self.narrow();
        v
    }
}

/// A table's cumulative counts in the caller's RAM ([`Table::index`]):
/// `cum[s]` is the sum of the counts of the symbols below `s`, `cum[A] = M`.
#[derive(Debug)]
pub struct Index<'c> {
    cum: &'c [u16],
    alphabet: u32,
    precision: u32,
}

impl Index<'_> {
    /// The symbol whose interval holds `slot < M`, with `cum` and `f`: the
    /// last `s` with `cum[s] ≤ slot` (a symbol of count 0 has the same
    /// `cum` as the next one, so the search never stops on it).
    #[inline(always)]
    fn find(&self, slot: u32) -> (u32, u32, u32) {
        let at = |s: u32| u32::from(self.cum.get(s as usize).copied().unwrap_or(u16::MAX));
        let (mut lo, mut hi) = (0u32, self.alphabet);
        while hi.wrapping_sub(lo) > 1 {
            let mid = lo.wrapping_add(hi) >> 1;
            if at(mid) <= slot {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let cum = at(lo);
        (lo, cum, at(hi).wrapping_sub(cum))
    }
}

/// A rANS decoder over one stream (one block, SPEC.md §10.3–§10.5): the
/// table, the state and the unread bytes; bytes past the stream's end read
/// as zero.
#[derive(Clone, Debug)]
pub struct Decoder<'a, 't> {
    table: Table<'t>,
    x: u32,
    rest: &'a [u8],
}

impl<'a, 't> Decoder<'a, 't> {
    /// Starts decoding `stream` (a block's bytes, from its first byte):
    /// reads the state, `EntropyState` unless `2^23 ≤ x < 2^31`.
    pub fn new(table: Table<'t>, stream: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(stream);
        let x = r.u32_le().ok_or(Error::EntropyState)?;
        if !(STATE_LOW..1u32 << 31).contains(&x) {
            return Err(Error::EntropyState);
        }
        Ok(Decoder {
            table,
            x,
            rest: r.rest(),
        })
    }

    /// Goes on decoding where another decoder of the same stream stopped:
    /// its state `x` ([`Decoder::state`]) and its unread bytes
    /// ([`Decoder::rest`]). Unchecked: a state that no decoder left gives
    /// garbage symbols, never a panic (a codec keeps these two in its
    /// player state between frames).
    pub fn resume(table: Table<'t>, x: u32, rest: &'a [u8]) -> Self {
        Decoder { table, x, rest }
    }

    #[inline(always)]
    fn byte(&mut self) -> u32 {
        match *self.rest {
            [b, ref rest @ ..] => {
                self.rest = rest;
                u32::from(b)
            }
            [] => 0,
        }
    }

    /// Brings `x` back to `≥ 2^23`: a valid state after a step is at least
    /// `2^8` (`n ≤ 15`, raw `k ≤ 16`: `2^7`), so two bytes always suffice.
    #[inline(always)]
    fn renormalise(&mut self) {
        if self.x < STATE_LOW {
            self.x = (self.x << 8) | self.byte();
            if self.x < STATE_LOW {
                self.x = (self.x << 8) | self.byte();
            }
        }
    }

    /// The next symbol (`0 … A − 1`).
    #[inline]
    pub fn symbol(&mut self) -> u32 {
        self.step(|table, slot| table.find(slot))
    }

    /// One decode step: the slot, its symbol's `(s, cum, f)` by `find`, the
    /// state's update and renormalisation.
    #[inline(always)]
    fn step(&mut self, find: impl FnOnce(&Table<'t>, u32) -> (u32, u32, u32)) -> u32 {
        let table = self.table;
        self.step_of(&table, find)
    }

    /// [`Decoder::step`] with the counts of `table`.
    #[inline(always)]
    fn step_of(
        &mut self,
        table: &Table<'t>,
        find: impl FnOnce(&Table<'t>, u32) -> (u32, u32, u32),
    ) -> u32 {
        let n = table.precision;
        let slot = self.x & ((1u32 << n).wrapping_sub(1));
        let (s, cum, f) = find(table, slot);
        self.x = f
            .wrapping_mul(self.x >> n)
            .wrapping_add(slot.wrapping_sub(cum));
        self.renormalise();
        s
    }

    /// [`Decoder::symbol`] through the table's [`Index`]: the same symbol
    /// and state, found by binary search. An index of another table (other
    /// alphabet or precision) falls back to the scan; one of another table
    /// of the same shape gives other symbols, never a panic.
    #[inline]
    pub fn symbol_in(&mut self, index: &Index) -> u32 {
        if index.alphabet != self.table.alphabet || index.precision != self.table.precision {
            return self.symbol();
        }
        self.step(|_, slot| index.find(slot))
    }

    /// [`Decoder::value`] through the table's [`Index`] (see
    /// [`Decoder::symbol_in`]).
    #[inline]
    pub fn value_in(&mut self, index: &Index) -> u32 {
        let s = self.symbol_in(index);
        self.escape(s)
    }

    /// `k ≤ 16` raw bits (uniform, `M = 2^k`, SPEC.md §10.4); larger `k`
    /// are reduced modulo 32 and clamped to 16.
    #[inline]
    pub fn raw(&mut self, k: u32) -> u32 {
        let k = (k & 31).min(MAX_RAW_BITS);
        let v = self.x & ((1u32 << k).wrapping_sub(1));
        self.x >>= k;
        self.renormalise();
        v
    }

    /// A value coded with the escape of SPEC.md §10.4: a symbol below
    /// `E = A − 1` is the value; symbol `E` is followed by 5 raw bits `k`
    /// and a `k`-bit `r`, the value is `E + 2^k + r − 1` (wrapping).
    #[inline]
    pub fn value(&mut self) -> u32 {
        let s = self.symbol();
        self.escape(s)
    }

    /// [`Decoder::value`] with the counts of another table, in the same
    /// stream (SPEC.md §10.3: a stream may mix the steps of several
    /// tables, each step decoded with the table it was coded with).
    #[inline]
    pub fn value_of(&mut self, table: &Table<'t>) -> u32 {
        let s = self.step_of(table, |t, slot| t.find(slot));
        self.escape_of(table.alphabet, s)
    }

    /// The value of symbol `s`: `s` below `E`, else the escaped value read
    /// after it.
    #[inline(always)]
    fn escape(&mut self, s: u32) -> u32 {
        self.escape_of(self.table.alphabet, s)
    }

    /// [`Decoder::escape`] for a table of `alphabet` symbols.
    #[inline(always)]
    fn escape_of(&mut self, alphabet: u32, s: u32) -> u32 {
        let e = alphabet.wrapping_sub(1);
        if s < e {
            return s;
        }
        let k = self.raw(5);
        let r = if k > MAX_RAW_BITS {
            let lo = self.raw(MAX_RAW_BITS);
            let hi = self.raw(k.wrapping_sub(MAX_RAW_BITS));
            (hi << MAX_RAW_BITS) | lo
        } else {
            self.raw(k)
        };
        e.wrapping_add((1u32 << k) | r).wrapping_sub(1)
    }

    /// The state `x`.
    pub fn state(&self) -> u32 {
        self.x
    }

    /// Stream bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.rest.len()
    }

    /// The stream's unread bytes.
    pub fn rest(&self) -> &'a [u8] {
        self.rest
    }

    /// Whether the stream ended exactly where the encoder started: every
    /// byte read and the state back at `2^23` (SPEC.md §10.5). A sanity
    /// check, not an integrity check (the container's CRC is that): a
    /// stream cut after trailing zero bytes still ends there.
    pub fn is_finished(&self) -> bool {
        self.rest.is_empty() && self.x == STATE_LOW
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// n = 2 (M = 4), W = 2, A = 3: counts 2 (2 bits), 1 (2 bits: 2 left), 1 (what is left).
    const TABLE: [u8; 3] = [0x22, 0x03, 0b0110];

    #[test]
    fn parses_a_small_table() {
        let (t, used) = Table::parse(&TABLE).unwrap();
        assert_eq!(used, 3);
        assert_eq!((t.precision(), t.alphabet()), (2, 3));
        assert_eq!(
            (t.count(0), t.count(1), t.count(2), t.count(3)),
            (2, 1, 1, 0)
        );
        assert_eq!(t.find(0), (0, 0, 2));
        assert_eq!(t.find(1), (0, 0, 2));
        assert_eq!(t.find(2), (1, 2, 1));
        assert_eq!(t.find(3), (2, 3, 1));
    }

    /// [`Table::reread`] of a validated table's bytes is the table
    /// [`Table::parse`] gave: every slot finds the same symbol.
    #[test]
    fn rereading_a_table_gives_the_parsed_table() {
        // §10.6's table (A = 4, M = 8), this module's, one symbol, and
        // one with zero counts after the first.
        let tables: [&[u8]; 4] = [
            &[0x33, 0x04, 0x2d],
            &TABLE,
            &[0x10, 0x01],
            &[0x11, 0x06, 0x11],
        ];
        for bytes in tables {
            let (t, used) = Table::parse(bytes).unwrap();
            assert_eq!(used, bytes.len());
            let r = Table::reread(bytes);
            assert_eq!((r.precision(), r.alphabet()), (t.precision(), t.alphabet()));
            for slot in 0..1u32 << t.precision() {
                assert_eq!(r.find(slot), t.find(slot), "{bytes:02x?} slot {slot}");
            }
        }
    }

    #[test]
    fn rejects_bad_tables() {
        let err = |b: &[u8]| Table::parse(b).unwrap_err();
        assert!(matches!(err(&[]), Error::EntropyTable { .. }));
        assert!(matches!(err(&[0x22]), Error::EntropyTable { .. }));
        assert!(matches!(err(&[0x22, 0x03]), Error::EntropyTable { .. }));
        // W = 3: symbol 0's count 5 > M = 4.
        assert!(matches!(
            err(&[0x32, 0x03, 0b101]),
            Error::EntropyTable { .. }
        ));
        // Padding bits set.
        assert!(matches!(
            err(&[0x22, 0x03, 0b1_0110]),
            Error::EntropyTable { .. }
        ));
        // Alphabet 65 537 (65 536 is fine), alphabet 0.
        assert!(matches!(
            err(&[0x00, 0x81, 0x80, 0x04]),
            Error::EntropyTable { .. }
        ));
        assert_eq!(
            Table::parse(&[0x00, 0x80, 0x80, 0x04])
                .unwrap()
                .0
                .alphabet(),
            65_536
        );
        assert!(matches!(err(&[0x00, 0x00]), Error::EntropyTable { .. }));
        // Unterminated varint.
        assert!(matches!(err(&[0x00, 0x80]), Error::EntropyTable { .. }));
    }

    #[test]
    fn one_symbol_table_decodes_without_bytes() {
        let (t, used) = Table::parse(&[0x00, 0x01]).unwrap();
        assert_eq!(used, 2);
        let stream = STATE_LOW.to_le_bytes();
        let mut d = Decoder::new(t, &stream).unwrap();
        for _ in 0..1000 {
            assert_eq!(d.symbol(), 0);
        }
        assert!(d.is_finished());
    }

    #[test]
    fn rejects_bad_states() {
        let (t, _) = Table::parse(&TABLE).unwrap();
        assert_eq!(
            Decoder::new(t, &[1, 2, 3]).unwrap_err(),
            Error::EntropyState
        );
        assert_eq!(
            Decoder::new(t, &(STATE_LOW - 1).to_le_bytes()).unwrap_err(),
            Error::EntropyState
        );
        assert_eq!(
            Decoder::new(t, &(1u32 << 31).to_le_bytes()).unwrap_err(),
            Error::EntropyState
        );
    }

    /// Any table bytes and any stream: errors or symbols, never a panic,
    /// and symbols always inside the alphabet.
    #[test]
    fn garbage_is_safe() {
        let mut seed = 0x1234_5678u32;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        for _ in 0..20_000 {
            let len = (rnd() % 24) as usize;
            let bytes: Vec<u8> = (0..len).map(|_| rnd() as u8).collect();
            let Ok((t, used)) = Table::parse(&bytes) else {
                continue;
            };
            let Ok(mut d) = Decoder::new(t, &bytes[used..]) else {
                continue;
            };
            for _ in 0..64 {
                assert!(d.symbol() < t.alphabet());
                let _ = d.value();
                let _ = d.raw(rnd());
                assert!(d.state() < 1 << 31);
            }
        }
    }
}
