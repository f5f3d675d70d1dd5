//! Validation of a `pca-spline` section (SPEC.md §5.1–§5.5), once, by
//! [`PcaSplineCodec::parse`]: channel lists, segments, group records, key
//! times and patches. Everything the other modules read was checked here.

use super::*;

/// Checks `n` channel indices: below `channels` and strictly increasing.
pub(super) fn check_indices(
    r: &mut Reader<'_>,
    n: u32,
    wide: bool,
    channels: usize,
) -> Result<(), Error> {
    let width = if wide { 2 } else { 1 };
    let bytes = r
        .take((n as usize).saturating_mul(width))
        .ok_or(malformed("channel list truncated"))?;
    let mut last: Option<usize> = None;
    for c in Indices::new(bytes, wide) {
        if c >= channels || last.is_some_and(|l| c <= l) {
            return Err(malformed("channel indices must increase and exist"));
        }
        last = Some(c);
    }
    Ok(())
}

impl<'a> PcaSplineCodec<'a> {
    /// Every channel in at most one list (sorted lists, pairwise merge).
    pub(super) fn check_disjoint(&self) -> Result<(), Error> {
        let lists = (self.group_count as usize).wrapping_add(1);
        for a in 0..lists {
            for b in a.wrapping_add(1)..lists {
                let (mut ia, mut ib) = (self.list(a), self.list(b));
                let (mut x, mut y) = (ia.next(), ib.next());
                while let (Some(p), Some(q)) = (x, y) {
                    match p.cmp(&q) {
                        core::cmp::Ordering::Less => x = ia.next(),
                        core::cmp::Ordering::Greater => y = ib.next(),
                        core::cmp::Ordering::Equal => {
                            return Err(malformed("a channel appears in two lists"))
                        }
                    }
                }
            }
        }
        Ok(())
    }

    pub(super) fn check_segments(&self, count: u32, frames: u32) -> Result<(), Error> {
        if count == 0 {
            return Err(malformed("no segments"));
        }
        let mut at = 0usize;
        let mut prev: Option<(u32, u32)> = None;
        let mut before_prev_end: Option<u32> = None;
        for _ in 0..count {
            let seg = self
                .segment_at(at)
                .ok_or(malformed("segment header truncated"))?;
            if seg.end < seg.start || seg.end.wrapping_sub(seg.start) >= MAX_SEGMENT_FRAMES {
                return Err(malformed("segment length out of range"));
            }
            if seg.end >= frames {
                return Err(malformed("segment ends after the last frame"));
            }
            match prev {
                None if seg.start != 0 => return Err(malformed("first segment must start at 0")),
                None => {}
                Some((ps, pe)) => {
                    // Starts increase, no gap, and blend windows do not
                    // touch each other (§5.2).
                    if seg.start <= ps || pe.saturating_add(1) < seg.start {
                        return Err(malformed("segments out of order or with a gap"));
                    }
                    if before_prev_end.is_some_and(|e| e.saturating_add(2) > seg.start) {
                        return Err(malformed("blend windows overlap"));
                    }
                }
            }
            self.check_body(&seg)?;
            // Patches of a segment lie before the next one starts.
            let next_start = self
                .segment_at(seg.next)
                .map_or(seg.end.wrapping_add(1), |n| n.start);
            self.check_patches(&seg, next_start.saturating_sub(seg.start))?;
            before_prev_end = prev.map(|(_, e)| e);
            prev = Some((seg.start, seg.end));
            at = seg.next;
        }
        if prev.map(|(_, e)| e) != Some(frames.wrapping_sub(1)) {
            return Err(malformed("last segment must end at the last frame"));
        }
        if at != self.segments.len() {
            return Err(malformed("bytes after the last segment"));
        }
        Ok(())
    }

    pub(super) fn check_body(&self, seg: &Segment<'a>) -> Result<(), Error> {
        let len = seg.end.wrapping_sub(seg.start).wrapping_add(1);
        let mut g = Reader::new(self.groups);
        let mut body = Reader::new(seg.body);
        for _ in 0..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            g.take(n.wrapping_mul(self.width()));
            let head = read_group(&mut body, n).ok_or(malformed("group data truncated"))?;
            if head.k == 0 {
                continue;
            }
            if head.keys < 2 || head.keys > len || len.wrapping_sub(1) >> head.time_bits != 0 {
                return Err(malformed("key count or time width out of range"));
            }
            let mut bits = BitReader::at(head.bits, 0);
            let mut last: Option<u32> = None;
            for _ in 0..head.keys {
                let t = bits.read(head.time_bits);
                if last.map_or(t != 0, |l| t <= l) {
                    return Err(malformed("key times must start at 0 and increase"));
                }
                last = Some(t);
            }
            if last != Some(len.wrapping_sub(1)) {
                return Err(malformed("last key must be the segment's last frame"));
            }
        }
        if !body.is_empty() {
            return Err(malformed("bytes after a segment's last group"));
        }
        Ok(())
    }

    pub(super) fn check_patches(&self, seg: &Segment<'a>, primary: u32) -> Result<(), Error> {
        let bad = malformed("patches out of order or out of range");
        let mut r = Reader::new(seg.patches);
        let mut last: Option<(u32, usize)> = None;
        let mut frame = 0u32;
        while !r.is_empty() {
            let (delta, c, _) = self.read_patch(&mut r).ok_or(bad)?;
            frame = frame.checked_add(delta).ok_or(bad)?;
            if frame >= primary || c >= self.channels {
                return Err(bad);
            }
            if last.is_some_and(|(f, lc)| f == frame && c <= lc) {
                return Err(bad);
            }
            last = Some((frame, c));
        }
        Ok(())
    }
}
