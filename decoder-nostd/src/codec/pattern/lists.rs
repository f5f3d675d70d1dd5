//! Entropy-coded segment lists (SPEC.md §11.1b): per node the segment
//! count, the block size, an index of blocks (each block's first segment's
//! start frame and pattern, and where its stream ends) and the blocks'
//! rANS streams (§10), which code each segment's length and, after a
//! block's first, its pattern as the change from "the pattern after the
//! last one". Sequential playback steps one segment at a time from the
//! state the player keeps (the rANS state and the stream position); a seek
//! binary-searches the blocks by their start and decodes at most one
//! block's segments.

use crate::entropy::{Decoder, Table};
use crate::error::Error;

/// Bytes of a block's index entry: start frame (u32), first pattern
/// (u16), end of its stream (u32).
pub(super) const BLOCK: usize = 10;
/// The largest block size exponent: blocks of at most `2^15` segments.
pub const MAX_BLOCK_BITS: u8 = 15;

/// A node's coded segment list, read where it lies.
#[derive(Clone, Copy)]
pub(super) struct CodedList<'a> {
    /// Its segments.
    pub count: usize,
    /// Blocks of `2^bits` segments.
    bits: u32,
    index: &'a [u8],
    streams: &'a [u8],
}

/// One decoded segment and the stream's state after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Seg {
    pub start: u32,
    pub end: u32,
    pub pattern: u32,
    /// Its number in the node.
    pub i: usize,
    /// The rANS state after its steps.
    pub x: u32,
    /// Offset of the stream's next unread byte in the node's streams.
    pub pos: usize,
}

/// The two tables of a coded section: lengths, then patterns.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tables<'a> {
    pub lengths: Table<'a>,
    pub patterns: Table<'a>,
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let &[x, y, z, w] = b.get(at..)?.first_chunk::<4>()?;
    Some(u32::from_le_bytes([x, y, z, w]))
}

/// The signed value of a zigzag code (§3.1).
#[inline(always)]
fn unzigzag(v: u32) -> u32 {
    (v >> 1) ^ (v & 1).wrapping_neg()
}

impl<'a> CodedList<'a> {
    /// The coded list at `at` in `lists` and its length in bytes.
    pub fn read(lists: &'a [u8], at: usize) -> Option<(CodedList<'a>, usize)> {
        let b = lists.get(at..)?;
        let &[c0, c1, bits] = b.first_chunk::<3>()?;
        let count = usize::from(u16::from_le_bytes([c0, c1]));
        let bits = u32::from(bits);
        if bits > u32::from(MAX_BLOCK_BITS) {
            return None;
        }
        let blocks = count.wrapping_add((1usize << bits).wrapping_sub(1)) >> bits;
        let index_len = blocks.checked_mul(BLOCK)?;
        let index = b.get(3..index_len.checked_add(3)?)?;
        // The last block's end (its index entry's last field).
        let streams_len = match blocks.checked_sub(1) {
            Some(last) => u32_at(index, last.wrapping_mul(BLOCK).wrapping_add(6))? as usize,
            None => 0,
        };
        let streams_at = index_len.wrapping_add(3);
        let streams = b.get(streams_at..streams_at.checked_add(streams_len)?)?;
        let list = CodedList {
            count,
            bits,
            index,
            streams,
        };
        Some((list, streams_at.wrapping_add(streams_len)))
    }

    fn blocks(&self) -> usize {
        self.index.len() / BLOCK
    }

    /// Where block `k`'s stream ends in the streams.
    fn block_end(&self, k: usize) -> Option<usize> {
        Some(u32_at(self.index, k.wrapping_mul(BLOCK).wrapping_add(6))? as usize)
    }

    /// Block `k`'s start frame, first pattern and stream bytes `from..to`.
    fn block(&self, k: usize) -> Option<(u32, u32, usize, usize)> {
        let at = k.wrapping_mul(BLOCK);
        let start = u32_at(self.index, at)?;
        let &[p0, p1] = self.index.get(at.wrapping_add(4)..)?.first_chunk::<2>()?;
        let from = match k.checked_sub(1) {
            Some(j) => self.block_end(j)?,
            None => 0,
        };
        let to = self.block_end(k)?;
        Some((start, u32::from(u16::from_le_bytes([p0, p1])), from, to))
    }

    /// The first segment of block `k`: `Err` only if the block's stream
    /// cannot start (caught when the section is parsed).
    pub fn first(&self, k: usize, t: &Tables<'_>) -> Result<Seg, Error> {
        let bad = Error::PatternMalformed {
            rule: "a block index entry past the list",
        };
        let (start, pattern, from, to) = self.block(k).ok_or(bad)?;
        let stream = self.streams.get(from..to).ok_or(bad)?;
        let mut dec = Decoder::new(t.lengths, stream).map_err(|_| Error::PatternMalformed {
            rule: "a block's stream state out of range",
        })?;
        let n = dec.value().wrapping_add(1);
        Ok(Seg {
            start,
            end: start.wrapping_add(n),
            pattern,
            i: k << self.bits,
            x: dec.state(),
            pos: to.wrapping_sub(dec.remaining()),
        })
    }

    /// The segment after `s`, in the same block (`None` past the block's
    /// last segment or if `s` is not one of this list's).
    pub fn after(&self, s: &Seg, t: &Tables<'_>) -> Option<Seg> {
        let i = s.i.wrapping_add(1);
        let mask = (1usize << self.bits).wrapping_sub(1);
        if i & mask == 0 || i >= self.count {
            return None;
        }
        let to = self.block_end(s.i >> self.bits)?;
        let rest = self.streams.get(s.pos..to)?;
        let mut dec = Decoder::resume(t.lengths, s.x, rest);
        let d = unzigzag(dec.value_of(&t.patterns));
        let n = dec.value().wrapping_add(1);
        Some(Seg {
            start: s.end,
            end: s.end.wrapping_add(n),
            pattern: s.pattern.wrapping_add(1).wrapping_add(d),
            i,
            x: dec.state(),
            pos: to.wrapping_sub(dec.remaining()),
        })
    }

    /// The next segment after `s`: in its block, or the next block's first.
    pub fn next(&self, s: &Seg, t: &Tables<'_>) -> Option<Seg> {
        match self.after(s, t) {
            Some(n) => Some(n),
            None if s.i.wrapping_add(1) < self.count => {
                self.first(s.i.wrapping_add(1) >> self.bits, t).ok()
            }
            None => None,
        }
    }

    /// The segment of frame `f` (the last block starting at or before `f`
    /// by a binary search, then its segments in order).
    pub fn find(&self, f: u32, t: &Tables<'_>) -> Option<Seg> {
        let (mut lo, mut hi) = (0usize, self.blocks());
        while hi.wrapping_sub(lo) > 1 {
            let mid = lo.wrapping_add(hi.wrapping_sub(lo) / 2);
            if u32_at(self.index, mid.wrapping_mul(BLOCK))? <= f {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let mut s = self.first(lo, t).ok()?;
        // At most a block's segments (2^15).
        for _ in 0..1u32 << MAX_BLOCK_BITS {
            if f < s.end {
                break;
            }
            s = self.after(&s, t)?;
        }
        Some(s)
    }

    /// The rules of §11.5 for this list (`patterns` patterns in its node,
    /// `frames` frames): every block starts where the one before ended,
    /// every segment is 1 … 65 535 frames and plays a pattern of the node,
    /// the segments end at the last frame and every block's stream ends
    /// where its encoder started.
    pub fn check(&self, t: &Tables<'_>, patterns: usize, frames: u32) -> Result<(), Error> {
        let malformed = |rule| Error::PatternMalformed { rule };
        if self.count == 0 {
            return Err(malformed("a node without segments"));
        }
        let mut end = 0u32;
        for k in 0..self.blocks() {
            let (_, _, from, to) = self.block(k).ok_or(malformed("segment list truncated"))?;
            if from > to {
                return Err(malformed("block streams not in order"));
            }
            let mut s = self.first(k, t)?;
            if s.start != end {
                return Err(malformed(
                    "a block does not start where the segments before it end",
                ));
            }
            loop {
                let n = s.end.wrapping_sub(s.start);
                // `n` wraps above 65 535 if `end < start`.
                if n == 0 || n > super::MAX_SEGMENT || s.end > frames {
                    return Err(malformed(
                        "a segment of 0 or over 65535 frames, or past the last frame",
                    ));
                }
                if s.pattern as usize >= patterns {
                    return Err(malformed("a segment's pattern is not in its node"));
                }
                end = s.end;
                match self.after(&s, t) {
                    Some(next) => s = next,
                    None => break,
                }
            }
            let rest = self.streams.get(s.pos..to).unwrap_or(&[]);
            if !Decoder::resume(t.lengths, s.x, rest).is_finished() {
                return Err(malformed(
                    "a block's stream does not end where its encoder started",
                ));
            }
        }
        if end != frames {
            return Err(malformed("the segments do not end at the last frame"));
        }
        Ok(())
    }
}

/// The coded segment list at `at` in `lists` (§11.1b, the bytes after the
/// two tables): its segment count and its length in bytes; `None` if it
/// does not fit. For tools that walk a section (`mocap info`).
pub fn coded_extent(lists: &[u8], at: usize) -> Option<(usize, usize)> {
    CodedList::read(lists, at).map(|(l, len)| (l.count, len))
}

/// Calls `f(start, end, pattern)` for every segment of the coded list at
/// `at` in `lists` (§11.1b, the bytes after the two tables `lengths` and
/// `patterns`), in order; `None` if the list does not decode. For tools
/// and tests (`mocap info`): the player steps through a list with
/// [`CodedList::next`] instead.
pub fn for_each_coded_segment(
    lists: &[u8],
    at: usize,
    lengths: Table<'_>,
    patterns: Table<'_>,
    mut f: impl FnMut(u32, u32, u32),
) -> Option<()> {
    let t = Tables { lengths, patterns };
    let (list, _) = CodedList::read(lists, at)?;
    let mut s = list.first(0, &t).ok()?;
    for _ in 0..list.count {
        f(s.start, s.end, s.pattern);
        match list.next(&s, &t) {
            Some(n) => s = n,
            None => break,
        }
    }
    Some(())
}
