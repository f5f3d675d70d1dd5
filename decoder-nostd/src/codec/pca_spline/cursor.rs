//! Where a player is in the segment list (SPEC.md §5.2) and in the current
//! segment's patches (§5.5): locating the segment of a frame and scanning
//! its patches without re-reading what a previous pose passed.

use super::*;

/// Where the player is in the segment list: the byte offsets of the
/// current and previous segment headers, the current segment itself and
/// its neighbours' bounds, so a pose inside the current segment reads no
/// segment header; and where the patch scan stopped.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Cursor<'a> {
    pub(super) current: usize,
    pub(super) previous: Option<usize>,
    /// The segment at `current`, once located.
    pub(super) segment: Option<Segment<'a>>,
    /// Start of the next segment and end of the previous one.
    pub(super) next_start: Option<u32>,
    pub(super) prev_end: Option<u32>,
    /// The patch scan of `segment`: byte offset of the first patch not yet
    /// passed, and 1 + the frame of the last patch passed (0: none).
    pub(super) patch: PatchScan,
}

/// Where a segment's patch scan stands: the byte offset `at` of the first
/// patch not yet passed, 1 + the frame of the last patch passed (`seen`,
/// 0: none) and the frame of the patch at `at` (`next`: `u16::MAX` when
/// there is none, 0 when not known), so that a frame between two patches
/// reads nothing. Patch frames are below 2^15 (§5.2, §5.5), so both fit in
/// 16 bits and the scan takes the two words it always took.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PatchScan {
    pub(super) at: usize,
    pub(super) seen: u16,
    pub(super) next: u16,
}

/// `pos` relative to the segment's start, clamped into it (at most
/// `(2^15 − 1)·2^16`, so it fits in 32 bits).
pub(super) fn relative(seg: &Segment<'_>, pos: u64) -> u32 {
    pos.saturating_sub(u64::from(seg.start) << FRAC_BITS)
        .min(u64::from(seg.end.wrapping_sub(seg.start)) << FRAC_BITS) as u32
}

impl<'a> PcaSplineCodec<'a> {
    pub(super) fn read_patch(&self, r: &mut Reader<'a>) -> Option<(u32, usize, i32)> {
        let delta = r.varint_u32_inline()?;
        let c = Indices::new(r.take(self.width())?, self.wide).next()?;
        let v = wire::zigzag_decode(r.varint_u32_inline()?);
        Some((delta, c, v))
    }

    /// The segment whose header starts at byte `at`.
    pub(super) fn segment_at(&self, at: usize) -> Option<Segment<'a>> {
        let mut r = Reader::new(self.segments.get(at..)?);
        let start = r.varint_u32()?;
        let end = r.varint_u32()?;
        let body = r.byte_seq()?;
        let patches = r.byte_seq()?;
        Some(Segment {
            start,
            end,
            body,
            patches,
            next: at.wrapping_add(r.pos()),
        })
    }

    /// The segment holding `frame` (the last one starting at or before it).
    /// Inside the cursor's segment this reads nothing; otherwise it walks
    /// the list from the cursor (or from the start when going back) and
    /// moves the cursor.
    pub(super) fn locate(&self, frame: u32, cursor: &mut Cursor<'a>) -> Option<Segment<'a>> {
        if let Some(seg) = cursor.segment {
            if seg.start <= frame && cursor.next_start.is_none_or(|s| frame < s) {
                return Some(seg);
            }
        }
        let (mut at, mut prev) = (cursor.current, cursor.previous);
        let mut cur = self.segment_at(at)?;
        if frame < cur.start {
            (at, prev) = (0, None);
            cur = self.segment_at(0)?;
        }
        loop {
            match self.segment_at(cur.next) {
                Some(n) if n.start <= frame => {
                    prev = Some(at);
                    at = cur.next;
                    cur = n;
                }
                next => {
                    *cursor = Cursor {
                        current: at,
                        previous: prev,
                        segment: Some(cur),
                        next_start: next.map(|n| n.start),
                        prev_end: prev.and_then(|p| self.segment_at(p)).map(|p| p.end),
                        patch: PatchScan::default(),
                    };
                    return Some(cur);
                }
            }
        }
    }

    /// Adds the patches of `seg` at relative frame `frame` times `weight`
    /// (16.16) to `out` (§5.5), scanning from `from` unless that is past
    /// `frame` (then from the first patch); nothing is read when `frame`
    /// lies before `from`'s next patch. Returns where the scan can resume
    /// for a later frame.
    pub(super) fn patches_at(
        &self,
        seg: &Segment<'a>,
        from: PatchScan,
        frame: u32,
        weight: i64,
        out: &mut [i32],
    ) -> PatchScan {
        if u32::from(from.seen) <= frame && frame < u32::from(from.next) {
            return from;
        }
        let (mut at, mut seen) = if u32::from(from.seen) > frame {
            (0, 0)
        } else {
            (from.at, u32::from(from.seen))
        };
        let mut r = Reader::new(seg.patches.get(at..).unwrap_or(&[]));
        let base = at;
        let mut last = seen.saturating_sub(1);
        // The frame of the first patch read since `at` last moved.
        let mut next = None;
        while let Some((delta, c, v)) = self.read_patch(&mut r) {
            let f = last.wrapping_add(delta);
            next = next.or(Some(f));
            if f > frame {
                break;
            }
            if f == frame {
                if let Some(o) = out.get_mut(c) {
                    *o = o.wrapping_add((i64::from(v).wrapping_mul(weight) >> FRAC_BITS) as i32);
                }
            } else {
                (at, seen) = (base.wrapping_add(r.pos()), f.saturating_add(1));
                next = None;
            }
            last = f;
        }
        PatchScan {
            at,
            seen: seen as u16,
            next: next.map_or(u16::MAX, |f| f as u16),
        }
    }
}
