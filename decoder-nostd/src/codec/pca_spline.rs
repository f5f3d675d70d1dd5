//! The `pca-spline` codec (SPEC.md §5), after Liu & McMillan (2006): the
//! clip is cut into segments; in each segment every channel group is a
//! mean plus a few principal components whose coefficients follow a
//! key-frame spline. A pose at any time costs one spline evaluation per
//! group (four control points) and `k` multiply-adds per channel; nothing
//! depends on earlier frames.

use crate::bits::BitReader;
use crate::codec::spline;
use crate::consts::pca::{
    BASIS_SHIFT, FRAC_BITS, MAX_COMPONENTS, MAX_MEAN_SHIFT, MAX_SEGMENT_FRAMES, MAX_TIME_BITS,
    MAX_VALUE_BITS, MAX_VALUE_SHIFT,
};
use crate::error::Error;
use crate::reader::Reader;
use crate::wire;

const K_MAX: usize = MAX_COMPONENTS as usize;

/// A validated view of a `pca-spline` section.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PcaSplineCodec<'a> {
    channels: usize,
    /// Bytes per channel index: 1 or 2.
    wide: bool,
    group_count: u32,
    /// The group table (§5.1), after the group count.
    groups: &'a [u8],
    const_count: u32,
    /// Constant channels: indices then zigzag values (§5.1).
    consts: &'a [u8],
    /// The segment blocks (§5.2), after the segment count.
    segments: &'a [u8],
}

/// Where the player is in the segment list: the byte offsets of the
/// current and previous segment headers, the current segment itself and
/// its neighbours' bounds, so a pose inside the current segment reads no
/// segment header; and where the patch scan stopped.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Cursor<'a> {
    current: usize,
    previous: Option<usize>,
    /// The segment at `current`, once located.
    segment: Option<Segment<'a>>,
    /// Start of the next segment and end of the previous one.
    next_start: Option<u32>,
    prev_end: Option<u32>,
    /// The patch scan of `segment`: byte offset of the first patch not yet
    /// passed, and 1 + the frame of the last patch passed (0: none).
    patch: PatchScan,
}

/// Where a segment's patch scan stands: the byte offset `at` of the first
/// patch not yet passed, 1 + the frame of the last patch passed (`seen`,
/// 0: none) and the frame of the patch at `at` (`next`: `u16::MAX` when
/// there is none, 0 when not known), so that a frame between two patches
/// reads nothing. Patch frames are below 2^15 (§5.2, §5.5), so both fit in
/// 16 bits and the scan takes the two words it always took.
#[derive(Clone, Copy, Debug, Default)]
struct PatchScan {
    at: usize,
    seen: u16,
    next: u16,
}

/// What every group of a pose needs: the segment's body, the position
/// relative to its start (§5.4), the output.
struct Pose<'a, 'o> {
    body: &'a [u8],
    rel: u32,
    out: &'o mut [i32],
}

/// One segment's header and its group data.
#[derive(Clone, Copy, Debug)]
struct Segment<'a> {
    start: u32,
    end: u32,
    body: &'a [u8],
    /// Sparse corrections (§5.5).
    patches: &'a [u8],
    /// Offset of the next segment header.
    next: usize,
}

/// The per-group parameters read before the key bits (§5.3). Small on
/// purpose: it is rebuilt for every group of every pose.
struct GroupHead<'a> {
    k: usize,
    mean_shift: u32,
    mean: &'a [u8],
    basis: &'a [u8],
    keys: u32,
    time_bits: u32,
    /// The `k` (width, shift, offset) records, still encoded.
    comps: &'a [u8],
    /// Σ width: bits per key row.
    row_bits: u32,
    bits: &'a [u8],
}

fn malformed(rule: &'static str) -> Error {
    Error::PcaMalformed { rule }
}

impl<'a> PcaSplineCodec<'a> {
    /// Validates the section against the header's channel and frame counts.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize, frames: u32) -> Result<Self, Error> {
        let truncated = malformed("section truncated");
        let mut r = Reader::new(bytes);
        let wide = match r.u8().ok_or(truncated)? {
            1 => false,
            2 => true,
            _ => return Err(malformed("index width must be 1 or 2")),
        };
        if !wide && channels > 256 {
            return Err(malformed("1-byte indices for more than 256 channels"));
        }
        let group_count = r.varint_u32().ok_or(truncated)?;
        let groups_at = r.pos();
        let mut covered: u64 = 0;
        for _ in 0..group_count {
            let n = r.varint_u32().ok_or(truncated)?;
            if n == 0 {
                return Err(malformed("empty group"));
            }
            covered += u64::from(n);
            check_indices(&mut r, n, wide, channels)?;
        }
        let groups = bytes.get(groups_at..r.pos()).ok_or(truncated)?;
        let const_count = r.varint_u32().ok_or(truncated)?;
        let consts_at = r.pos();
        check_indices(&mut r, const_count, wide, channels)?;
        for _ in 0..const_count {
            r.zigzag_i32().ok_or(truncated)?;
        }
        let consts = bytes.get(consts_at..r.pos()).ok_or(truncated)?;
        covered += u64::from(const_count);
        if covered != channels as u64 {
            return Err(malformed(
                "groups and constants do not cover every channel once",
            ));
        }
        let segment_count = r.varint_u32().ok_or(truncated)?;
        let segments = bytes.get(r.pos()..).unwrap_or(&[]);
        let codec = PcaSplineCodec {
            channels,
            wide,
            group_count,
            groups,
            const_count,
            consts,
            segments,
        };
        codec.check_disjoint()?;
        codec.check_segments(segment_count, frames)?;
        Ok(codec)
    }

    /// Every channel in at most one list (sorted lists, pairwise merge).
    fn check_disjoint(&self) -> Result<(), Error> {
        let lists = self.group_count as usize + 1;
        for a in 0..lists {
            for b in a + 1..lists {
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

    /// Channel list `i` (groups first, then the constants) as an index
    /// iterator.
    fn list(&self, i: usize) -> Indices<'a> {
        let mut r = Reader::new(self.groups);
        for g in 0..self.group_count as usize {
            let n = r.varint_u32().unwrap_or(0) as usize;
            let bytes = r.take(n * self.width()).unwrap_or(&[]);
            if g == i {
                return Indices::new(bytes, self.wide);
            }
        }
        let mut c = Reader::new(self.consts);
        let bytes = c
            .take(self.const_count as usize * self.width())
            .unwrap_or(&[]);
        Indices::new(bytes, self.wide)
    }

    fn width(&self) -> usize {
        if self.wide {
            2
        } else {
            1
        }
    }

    fn check_segments(&self, count: u32, frames: u32) -> Result<(), Error> {
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
            if seg.end < seg.start || seg.end - seg.start >= MAX_SEGMENT_FRAMES {
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
            let next_start = self.segment_at(seg.next).map_or(seg.end + 1, |n| n.start);
            self.check_patches(&seg, next_start.saturating_sub(seg.start))?;
            before_prev_end = prev.map(|(_, e)| e);
            prev = Some((seg.start, seg.end));
            at = seg.next;
        }
        if prev.map(|(_, e)| e) != Some(frames - 1) {
            return Err(malformed("last segment must end at the last frame"));
        }
        if at != self.segments.len() {
            return Err(malformed("bytes after the last segment"));
        }
        Ok(())
    }

    fn check_body(&self, seg: &Segment<'a>) -> Result<(), Error> {
        let len = seg.end - seg.start + 1;
        let mut g = Reader::new(self.groups);
        let mut body = Reader::new(seg.body);
        for _ in 0..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            g.take(n * self.width());
            let head = read_group(&mut body, n).ok_or(malformed("group data truncated"))?;
            if head.k == 0 {
                continue;
            }
            if head.keys < 2 || head.keys > len || (len - 1) >> head.time_bits != 0 {
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
            if last != Some(len - 1) {
                return Err(malformed("last key must be the segment's last frame"));
            }
        }
        if !body.is_empty() {
            return Err(malformed("bytes after a segment's last group"));
        }
        Ok(())
    }

    fn check_patches(&self, seg: &Segment<'a>, primary: u32) -> Result<(), Error> {
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

    fn read_patch(&self, r: &mut Reader<'a>) -> Option<(u32, usize, i32)> {
        let delta = r.varint_u32()?;
        let c = Indices::new(r.take(self.width())?, self.wide).next()?;
        let v = r.zigzag_i32()?;
        Some((delta, c, v))
    }

    /// The segment whose header starts at byte `at`.
    fn segment_at(&self, at: usize) -> Option<Segment<'a>> {
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
            next: at + r.pos(),
        })
    }

    /// Decodes the pose at `pos` (frames, 16.16; at most the last frame)
    /// into `out`. `cursor` remembers the segment and the patch scan for the
    /// next call; `cache` (any length, its content is the decoder's own)
    /// keeps each group's record offset and current key interval (control
    /// points, tangent ratios) so that a pose inside an interval reads no
    /// bits and parses no varint (§6: the output never depends on it).
    pub(crate) fn decode_at(
        &self,
        pos: u64,
        cursor: &mut Cursor<'a>,
        out: &mut [i32],
        cache: &mut [i32],
    ) {
        let frame = u32::try_from(pos >> FRAC_BITS).unwrap_or(u32::MAX);
        let Some(cur) = self.locate(frame, cursor) else {
            return;
        };
        self.eval(&cur, pos, out, cache);
        // A blend window (§5.2) around the start of `cur` or of the next
        // segment: blend the other segment's values into `out`.
        if cursor
            .prev_end
            .is_some_and(|e| pos < (u64::from(e) + 1) << FRAC_BITS)
        {
            if let Some(prev) = cursor.previous.and_then(|p| self.segment_at(p)) {
                self.blend(&prev, &cur, pos, false, out);
            }
        } else if cursor
            .next_start
            .is_some_and(|s| pos > u64::from(s.saturating_sub(1)) << FRAC_BITS)
        {
            if let Some(next) = self.segment_at(cur.next) {
                self.blend(&cur, &next, pos, true, out);
            }
        }
        // Patches at the two frames around pos, each weighted by its hat
        // function (§5.5).
        let one = 1i64 << FRAC_BITS;
        let frac = (pos & ((1 << FRAC_BITS) - 1)) as i64;
        let rel = frame.wrapping_sub(cur.start);
        cursor.patch = self.patches_at(&cur, cursor.patch, rel, one - frac, out);
        if frac > 0 {
            let after = frame.saturating_add(1);
            if cursor.next_start == Some(after) {
                if let Some(next) = self.segment_at(cur.next) {
                    self.patches_at(&next, PatchScan::default(), 0, frac, out);
                }
            } else {
                cursor.patch = self.patches_at(&cur, cursor.patch, rel.wrapping_add(1), frac, out);
            }
        }
    }

    /// The segment holding `frame` (the last one starting at or before it).
    /// Inside the cursor's segment this reads nothing; otherwise it walks
    /// the list from the cursor (or from the start when going back) and
    /// moves the cursor.
    fn locate(&self, frame: u32, cursor: &mut Cursor<'a>) -> Option<Segment<'a>> {
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

    /// Writes the constant channels, from `cached` (their values in order)
    /// when the cache holds them, else from the section.
    fn write_consts(&self, cached: Option<&[i32]>, out: &mut [i32]) {
        let mut r = Reader::new(self.consts);
        let n = self.const_count as usize;
        let indices = Indices::new(r.take(n * self.width()).unwrap_or(&[]), self.wide);
        match cached {
            Some(values) if !self.wide => {
                let idx = self.consts.get(..n).unwrap_or(&[]);
                for (&c, &v) in idx.iter().zip(values) {
                    if let Some(o) = out.get_mut(usize::from(c)) {
                        *o = v;
                    }
                }
            }
            Some(values) => {
                for (c, &v) in indices.zip(values) {
                    if let Some(o) = out.get_mut(c) {
                        *o = v;
                    }
                }
            }
            None => {
                for c in indices {
                    let v = r.zigzag_i32().unwrap_or(0);
                    if let Some(o) = out.get_mut(c) {
                        *o = v;
                    }
                }
            }
        }
    }

    /// The constant channels' values in order.
    fn const_values(&self) -> impl Iterator<Item = i32> + 'a {
        let mut r = Reader::new(self.consts);
        r.take(self.const_count as usize * self.width());
        (0..self.const_count).map(move |_| r.zigzag_i32().unwrap_or(0))
    }

    /// Adds the patches of `seg` at relative frame `frame` times `weight`
    /// (16.16) to `out` (§5.5), scanning from `from` unless that is past
    /// `frame` (then from the first patch); nothing is read when `frame`
    /// lies before `from`'s next patch. Returns where the scan can resume
    /// for a later frame.
    fn patches_at(
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
                    *o = o.wrapping_add(((i64::from(v) * weight) >> FRAC_BITS) as i32);
                }
            } else {
                (at, seen) = (base + r.pos(), f.saturating_add(1));
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

    /// Evaluates every group of `seg` at `pos` (clamped into the segment)
    /// into `out`, through the cache (§5.4 step 3).
    ///
    /// Cache layout: `[owner, groups cached, offset of the first uncached
    /// record, offset of the constants]`, then one slot per group, in
    /// order, while they fit, then the constant channels' values if they
    /// fit. A slot
    /// starts with [`GROUP_HEAD`] words — the record's offset in the body,
    /// where the values go (the first channel of a run of consecutive
    /// channels, or `−1 −` the offset of the group's index list), the
    /// offset of its means, and `n | k << 18 | c << 23 | ms << 24` ([`pack`]) — then for `k = 0`
    /// the `n` channel values, for `k > 0` the key interval it holds
    /// ([`INTERVAL`] words: `[from, to)` of `rel` in 16.16, `to` being
    /// `u32::MAX` for the last interval, the span in frames, the tangent
    /// ratios) and its `4k` control points. Groups without a slot are
    /// decoded from the record on every pose.
    fn eval(&self, seg: &Segment<'a>, pos: u64, out: &mut [i32], cache: &mut [i32]) {
        let rel = relative(seg, pos);
        let (head, mut slots) = cache
            .split_at_mut_checked(CACHE_HEAD)
            .unwrap_or((&mut [], &mut []));
        let owner = seg.start.wrapping_add(1) as i32;
        if head.first() != Some(&owner) {
            self.prepare(seg, owner, rel, head, slots);
        }
        let (cached, rest, consts) = match *head {
            [_, g, at, c] => ((g as u32).min(self.group_count), at as usize, c as usize),
            _ => (0, 0, usize::MAX),
        };
        let z = self.const_count as usize;
        self.write_consts(slots.get(consts..consts.wrapping_add(z)), out);
        let mut pose = Pose {
            body: seg.body,
            rel,
            out,
        };
        for _ in 0..cached {
            let Some(&[_, dst, nkm]) = slots.first_chunk::<GROUP_HEAD>() else {
                return;
            };
            let (n, k, _) = unpack(nkm);
            if k == 0 {
                let Some(target) = self.target(dst, n, pose.out) else {
                    return;
                };
                let Some((values, tail)) = core::mem::take(&mut slots)
                    .get_mut(GROUP_HEAD..)
                    .and_then(|t| t.split_at_mut_checked(n))
                else {
                    return;
                };
                slots = tail;
                target.copy(values);
                continue;
            }
            let size = GROUP_HEAD + INTERVAL + 4 * k;
            let Some((slot, tail)) = core::mem::take(&mut slots).split_at_mut_checked(size) else {
                return;
            };
            self.slot_group(nkm, slot, &mut pose);
            slots = tail;
        }
        if cached == self.group_count {
            return;
        }
        // Groups without a cache slot: parse the record on every pose.
        let mut g = Reader::new(self.groups);
        for _ in 0..cached {
            let n = g.varint_u32().unwrap_or(0) as usize;
            g.take(n * self.width());
        }
        let mut body = Reader::new(seg.body.get(rest..).unwrap_or(&[]));
        // A slot on the stack, evaluated like a cached one (refilled every
        // pose).
        let mut slot = [0i32; GROUP_HEAD + INTERVAL + 4 * K_MAX];
        for _ in cached..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            let idx_at = g.pos();
            let idx = g.take(n * self.width()).unwrap_or(&[]);
            let rec = body.pos();
            let Some(group) = read_group(&mut body, n) else {
                return;
            };
            if group.k == 0 {
                let Some(target) = Dst::of(idx, self.wide, pose.out) else {
                    return;
                };
                let mut values = GroupValues::new(&group, &[]);
                target.fill(|| values.next().unwrap_or(0));
                continue;
            }
            let dst = self.dst_word(idx, idx_at, n);
            let hd = [
                (rest + rec) as i32,
                dst,
                pack(n, group.k, group.mean_shift, dst),
            ];
            if let Some((h, iv)) = slot.split_first_chunk_mut::<GROUP_HEAD>() {
                *h = hd;
                if let Some((iv, _)) = iv.split_first_chunk_mut::<INTERVAL>() {
                    *iv = Cached::EMPTY;
                }
            }
            self.slot_group(hd[2], &mut slot, &mut pose);
        }
    }

    /// Where a group's values go, as a slot stores it: the first channel of
    /// a run of consecutive channels, or `−1 −` the offset `idx_at` of its
    /// index list `idx` in the group table.
    fn dst_word(&self, idx: &[u8], idx_at: usize, n: usize) -> i32 {
        let width = self.width();
        let first = idx.get(..width).map_or(usize::MAX, index_of);
        let last = idx.get(idx.len().wrapping_sub(width)..).map_or(0, index_of);
        // Indices strictly increase (checked by `parse`): n of them
        // spanning n values are consecutive.
        if last.wrapping_sub(first) == n.wrapping_sub(1) {
            first as i32
        } else {
            -1 - idx_at as i32
        }
    }

    /// Evaluates a `k > 0` group from its slot (head, key interval, control
    /// points), through the function specialised for its `k` (or for a
    /// single curve), as its head word `nkm` says. The caller hands it
    /// exactly the slot (its size follows from `k`).
    #[inline(always)]
    fn slot_group(&self, nkm: i32, slot: &mut [i32], pose: &mut Pose<'a, '_>) {
        // k, and 32 more for a single curve (see [`pack`]).
        match nkm as u32 >> 18 & 0x3F {
            33 => Self::curve(slot, pose),
            1 => self.cached_group::<1>(slot, pose),
            2 => self.cached_group::<2>(slot, pose),
            3 => self.cached_group::<3>(slot, pose),
            4 => self.cached_group::<4>(slot, pose),
            5 => self.cached_group::<5>(slot, pose),
            6 => self.cached_group::<6>(slot, pose),
            7 => self.cached_group::<7>(slot, pose),
            8 => self.cached_group::<8>(slot, pose),
            _ => self.cached_group_any(slot, pose),
        }
    }

    /// Evaluates a cached group of `K` components whose slot, after its head
    /// `hd`, is `slot` (key interval, control points); refills the slot when
    /// `rel` left its interval.
    #[inline(never)]
    fn cached_group<const K: usize>(&self, slot: &mut [i32], pose: &mut Pose<'a, '_>) {
        // Nothing to report: on a validated clip every step succeeds (and
        // returning nothing keeps a register free in the channel loops).
        let _ = self.group_k::<K>(slot, pose);
    }

    #[inline(always)]
    fn group_k<const K: usize>(&self, slot: &mut [i32], pose: &mut Pose<'a, '_>) -> Option<()> {
        let (&mut [rec, dst, nkm], slot) = slot.split_first_chunk_mut::<GROUP_HEAD>()?;
        let (body, rel) = (pose.body, pose.rel);
        let (n, _, ms) = unpack(nkm);
        let (iv, rest) = slot.split_first_chunk_mut::<INTERVAL>()?;
        let controls = rest.get_mut(..4 * K)?;
        let rec = rec as usize;
        let w = match cached_weights(iv, rel) {
            Some(w) => w,
            None => refill_slot(body, rec, n, K, rel, iv, controls)?,
        };
        let a = coefficients::<K>(w, controls);
        let (means, basis) = body.get(rec + 2..)?.split_at_checked(2 * n)?;
        self.target(dst, n, pose.out)?
            .write_k::<K>(a, means, basis, ms);
        Some(())
    }

    /// [`Self::cached_group`] for any `k`.
    fn cached_group_any(&self, slot: &mut [i32], pose: &mut Pose<'a, '_>) {
        let _ = self.group_any(slot, pose);
    }

    fn group_any(&self, slot: &mut [i32], pose: &mut Pose<'a, '_>) -> Option<()> {
        let (&mut [rec, dst, nkm], slot) = slot.split_first_chunk_mut::<GROUP_HEAD>()?;
        let (body, rel) = (pose.body, pose.rel);
        let (n, k, ms) = unpack(nkm);
        let (iv, rest) = slot.split_first_chunk_mut::<INTERVAL>()?;
        let controls = rest.get_mut(..4 * k)?;
        let rec = rec as usize;
        let w = match cached_weights(iv, rel) {
            Some(w) => w,
            None => refill_slot(body, rec, n, k, rel, iv, controls)?,
        };
        let (means, basis) = body.get(rec + 2..)?.split_at_checked(2 * n)?;
        let basis = basis.get(..n * k)?;
        self.target(dst, n, pose.out)?
            .write(k, w, controls, means, basis, ms);
        Some(())
    }

    /// A cached group of one channel (a run at `hd[1]`) and one component — a
    /// single curve (root translations, heading): [`Self::cached_group`]
    /// without a channel loop and with the record's five leading bytes (k, ms,
    /// mean, basis entry) read at once.
    #[inline(never)]
    fn curve(slot: &mut [i32], pose: &mut Pose<'a, '_>) {
        let _ = Self::curve_at(slot, pose);
    }

    #[inline(always)]
    fn curve_at(slot: &mut [i32], pose: &mut Pose<'a, '_>) -> Option<()> {
        let (&mut [rec, dst, nkm], slot) = slot.split_first_chunk_mut::<GROUP_HEAD>()?;
        let (body, rel) = (pose.body, pose.rel);
        let rec = rec as usize;
        let (iv, rest) = slot.split_first_chunk_mut::<INTERVAL>()?;
        let controls = rest.first_chunk_mut::<4>()?;
        let w = match cached_weights(iv, rel) {
            Some(w) => w,
            None => refill_slot(body, rec, 1, 1, rel, iv, controls)?,
        };
        let a = spline::apply(w, *controls);
        let &[_, _, m0, m1, b] = body.get(rec..rec.wrapping_add(5))? else {
            return None;
        };
        let ms = (nkm as u32) >> 24 & 0x1F;
        let mean = i32::from(i16::from_le_bytes([m0, m1]));
        let acc = (1i32 << (BASIS_SHIFT - 1)).wrapping_add(i32::from(b as i8).wrapping_mul(a));
        *pose.out.get_mut(dst as usize)? = mean.wrapping_shl(ms).wrapping_add(acc >> BASIS_SHIFT);
        Some(())
    }

    /// Where the values of a cached group go (its slot's `dst` word).
    fn target<'o>(&self, dst: i32, n: usize, out: &'o mut [i32]) -> Option<Dst<'a, 'o>> {
        if let Ok(first) = usize::try_from(dst) {
            return out.get_mut(first..first.checked_add(n)?).map(Dst::Run);
        }
        let at = usize::try_from(-1 - i64::from(dst)).ok()?;
        let idx = self.groups.get(at..at.checked_add(n * self.width())?)?;
        Some(if self.wide {
            Dst::Wide(idx, out)
        } else {
            Dst::Narrow(idx, out)
        })
    }

    /// Fills the cache head and as many group slots as fit for `seg`, each
    /// group's key interval the one holding `rel`.
    fn prepare(
        &self,
        seg: &Segment<'a>,
        owner: i32,
        rel: u32,
        head: &mut [i32],
        slots: &mut [i32],
    ) {
        let mut g = Reader::new(self.groups);
        let mut body = Reader::new(seg.body);
        let total = slots.len();
        let mut free = slots;
        let mut count = 0i32;
        for _ in 0..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            let idx_at = g.pos();
            let idx = g.take(n * self.width()).unwrap_or(&[]);
            let rec = body.pos();
            let mut next = body.clone();
            let Some(group) = read_group(&mut next, n) else {
                break;
            };
            let size = GROUP_HEAD
                + if group.k == 0 {
                    n
                } else {
                    INTERVAL + 4 * group.k
                };
            let Some((slot, tail)) = core::mem::take(&mut free).split_at_mut_checked(size) else {
                break;
            };
            free = tail;
            body = next;
            count += 1;
            let Some((hd, rest)) = slot.split_first_chunk_mut::<GROUP_HEAD>() else {
                break;
            };
            let dst = self.dst_word(idx, idx_at, n);
            *hd = [rec as i32, dst, pack(n, group.k, group.mean_shift, dst)];
            if group.k == 0 {
                let mut values = GroupValues::new(&group, &[]);
                for v in rest.iter_mut() {
                    *v = values.next().unwrap_or(0);
                }
            } else if let Some((iv, controls)) = rest.split_first_chunk_mut::<INTERVAL>() {
                // The interval holding `rel`, as the pose's refill of an
                // empty slot would find it, from the record at hand.
                *iv = Cached::EMPTY;
                group.refill(Cached::of(iv), rel, iv, controls);
            }
        }
        // The constants' values too, if they fit after the slots.
        let mut consts = -1;
        if let Some(dst) = free.get_mut(..self.const_count as usize) {
            for (d, v) in dst.iter_mut().zip(self.const_values()) {
                *d = v;
            }
            consts = (total - free.len()) as i32;
        }
        if let [o, g, at, c] = head {
            (*o, *g, *at, *c) = (owner, count, body.pos() as i32, consts);
        }
    }

    /// Blends the other segment of a window into `out`, which holds the
    /// values of `cur` (§5.4 step 4): `a + (b − a)·w` with `a` the earlier
    /// segment's value. `cur_first` says whether `cur` is `earlier`.
    fn blend(
        &self,
        earlier: &Segment<'a>,
        later: &Segment<'a>,
        pos: u64,
        cur_first: bool,
        out: &mut [i32],
    ) {
        // w = (pos - (S - 1)) / (E - S + 2), 16.16, S = later.start,
        // E = earlier.end.
        let from = u64::from(later.start.saturating_sub(1)) << FRAC_BITS;
        let steps = u64::from(earlier.end.saturating_add(2).saturating_sub(later.start)).max(1);
        let w = (pos.saturating_sub(from) / steps).min(1 << FRAC_BITS) as i64;
        let other = if cur_first { later } else { earlier };
        let rel = u64::from(relative(other, pos));
        let mut g = Reader::new(self.groups);
        let mut body = Reader::new(other.body);
        let mut coef = [0i32; K_MAX];
        for _ in 0..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            let idx = g.take(n * self.width()).unwrap_or(&[]);
            let Some(head) = read_group(&mut body, n) else {
                return;
            };
            head.coefficients(rel, &mut coef);
            let mut values = GroupValues::new(&head, coef.get(..head.k).unwrap_or(&[]));
            for c in Indices::new(idx, self.wide) {
                let (Some(o), Some(v)) = (out.get_mut(c), values.next()) else {
                    return;
                };
                let (a, b) = if cur_first { (*o, v) } else { (v, *o) };
                let d = i64::from(b.wrapping_sub(a));
                *o = a.wrapping_add(((d * w) >> FRAC_BITS) as i32);
            }
        }
    }
}

/// Words of the cache head: owner (segment start + 1), groups with a slot,
/// offset of the first record without one, where the constants' values
/// are (−1: not cached).
const CACHE_HEAD: usize = 4;
/// Words at the start of every group slot (see `eval`).
const GROUP_HEAD: usize = 3;
/// Words of a `k > 0` slot's key interval (see [`Cached`]).
const INTERVAL: usize = 4;

/// The key interval a cache slot holds, packed in [`INTERVAL`] words:
/// `t1 << 16 | span` (`span = t2 − t1`), the bound `lim` of `rel − (t1 <<
/// 16)` (`span << 16`, or `span << 16 | 0xFFFF` for the last interval,
/// which also holds its end key), `(ra − 1) | (rb − 1) << 16` and `i | tb
/// << 16` — key times below 2^15 and tangent ratios in `2..=2^16` (§5.4)
/// fit. A pose reads the first three; a refill all four.
#[derive(Clone, Copy)]
struct Cached {
    /// The interval `i` and its four key times `[ta, t1, t2, tb]`; `ta` is
    /// not kept (it only enters `ra`).
    i: u32,
    t1: u32,
    t2: u32,
    tb: u32,
    ra: i32,
    rb: i32,
}

impl Cached {
    /// Holds no position.
    const EMPTY: [i32; INTERVAL] = [0, 0, 0, 0xFFFF];

    fn of(iv: &[i32; INTERVAL]) -> Self {
        let [a, _, c, d] = iv.map(|w| w as u32);
        let t1 = a >> 16;
        Cached {
            i: d & 0xFFFF,
            t1,
            t2: t1 + (a & 0xFFFF),
            tb: d >> 16,
            ra: (c & 0xFFFF) as i32 + 1,
            rb: (c >> 16) as i32 + 1,
        }
    }

    fn store(&self, iv: &mut [i32; INTERVAL]) {
        let span = self.t2.wrapping_sub(self.t1) & 0xFFFF;
        let last = if self.tb == self.t2 { 0xFFFF } else { 0 };
        *iv = [
            self.t1 << FRAC_BITS | span,
            span << FRAC_BITS | last,
            (self.ra - 1) as u32 | ((self.rb - 1) as u32) << 16,
            self.i | self.tb << 16,
        ]
        .map(|w| w as i32);
    }
}

/// The spline weights at `rel` (§5.4) if the interval held in `iv` holds
/// it (else a refill is due): `t1 << 16 <= rel < t2 << 16`, or up to the
/// end key for the last interval.
#[inline(always)]
fn cached_weights(iv: &[i32; INTERVAL], rel: u32) -> Option<[i32; 4]> {
    let [a, lim, r, _] = iv.map(|w| w as u32);
    let d = rel.wrapping_sub(a & 0xFFFF_0000);
    if d >= lim {
        return None;
    }
    let u = d.checked_div(a & 0xFFFF).unwrap_or(0);
    Some(spline::weights_at(
        u,
        (r & 0xFFFF) as i32 + 1,
        (r >> 16) as i32 + 1,
    ))
}

/// `n | k << 18 | c << 23 | ms << 24` (n ≤ 2^17 channels, k ≤ 16, ms ≤ 16)
/// with `c` set for a single curve (one channel, a run at `dst`, one
/// component), so `nkm >> 18 & 0x3F` dispatches a slot.
fn pack(n: usize, k: usize, ms: u32, dst: i32) -> i32 {
    let curve = u32::from(n == 1 && k == 1 && dst >= 0);
    (n as u32 | (k as u32) << 18 | curve << 23 | ms << 24) as i32
}

fn unpack(nkm: i32) -> (usize, usize, u32) {
    let v = nkm as u32;
    (
        (v & 0x3_FFFF) as usize,
        (v >> 18 & 0x1F) as usize,
        v >> 24 & 0x1F,
    )
}

/// `pos` relative to the segment's start, clamped into it (at most
/// `(2^15 − 1)·2^16`, so it fits in 32 bits).
fn relative(seg: &Segment<'_>, pos: u64) -> u32 {
    pos.saturating_sub(u64::from(seg.start) << FRAC_BITS)
        .min(u64::from(seg.end - seg.start) << FRAC_BITS) as u32
}

impl GroupHead<'_> {
    /// The key interval holding `rel` (16.16 frames from the segment
    /// start): the largest `i <= m - 2` with `t[i] <= rel`, and the four key
    /// times around it with the ends repeated (§5.4).
    fn interval(&self, rel: u64) -> (u32, [u32; 4]) {
        let time = |i: u32| self.time(i);
        let last = self.keys.saturating_sub(1);
        let (mut lo, mut hi) = (0u32, last);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if u64::from(time(mid)) << FRAC_BITS <= rel {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let rows = [lo.saturating_sub(1), lo, lo + 1, (lo + 2).min(last)];
        (lo, rows.map(time))
    }

    /// Calls `each` with the four control values of every component at the
    /// keys `i − 1 … i + 2` (ends repeated). The four key rows are read in
    /// lockstep, one component at a time.
    fn controls(&self, i: u32, mut each: impl FnMut([i32; 4])) {
        let last = self.keys.saturating_sub(1);
        let rows = [i.saturating_sub(1), i, i + 1, (i + 2).min(last)];
        let mut at = rows.map(|row| self.key_row(row));
        let mut comps = Reader::new(self.comps);
        for _ in 0..self.k {
            let (Some(wd), Some(sh), Some(off)) = (comps.u8(), comps.u8(), comps.zigzag_i32())
            else {
                return;
            };
            let (wd, sh) = (u32::from(wd), u32::from(sh));
            each(at.each_mut().map(|bit| {
                let v = bits_at64(self.bits, *bit, wd) as i32;
                *bit = bit.wrapping_add(u64::from(wd));
                off.wrapping_add(v.wrapping_shl(sh))
            }));
        }
    }

    /// Key time `i`.
    fn time(&self, i: u32) -> u32 {
        bits_at64(
            self.bits,
            u64::from(i) * u64::from(self.time_bits),
            self.time_bits,
        )
    }

    /// The bit position of key row `row`.
    fn key_row(&self, row: u32) -> u64 {
        u64::from(self.keys) * u64::from(self.time_bits) + u64::from(row) * u64::from(self.row_bits)
    }

    /// Calls `each` with the control value of every component in the key
    /// row at bit `at`.
    fn row_values(&self, at: u64, mut each: impl FnMut(i32)) {
        let mut bits = BitReader::at(self.bits, at);
        let mut comps = Reader::new(self.comps);
        for _ in 0..self.k {
            let (Some(wd), Some(sh), Some(off)) = (comps.u8(), comps.u8(), comps.zigzag_i32())
            else {
                return;
            };
            let v = read_wide(&mut bits, u32::from(wd)) as i32;
            each(off.wrapping_add(v.wrapping_shl(u32::from(sh))));
        }
    }

    /// The spline's value of every component at `rel` (§5.4).
    fn coefficients(&self, rel: u64, coef: &mut [i32; K_MAX]) {
        if self.k == 0 {
            return;
        }
        let (i, t) = self.interval(rel);
        let w = spline::weights(t, rel);
        let mut dst = coef.iter_mut();
        self.controls(i, |p| {
            if let Some(c) = dst.next() {
                *c = spline::apply(w, p);
            }
        });
    }

    /// Refills a cache slot for `rel`: when `rel` lies in the interval
    /// after the cached one (sequential playback), the control points shift
    /// by one key and one key row is read; otherwise the interval is
    /// searched and its four rows read.
    fn refill(
        &self,
        at: Cached,
        rel: u32,
        iv: &mut [i32; INTERVAL],
        controls: &mut [i32],
    ) -> Cached {
        let last = self.keys.saturating_sub(1);
        let next = at.i + 1;
        let sequential = at.tb != at.t2
            && at.t2 << FRAC_BITS <= rel
            && (rel < at.tb << FRAC_BITS || next + 1 == last)
            && next < last;
        let (i, t) = if sequential {
            let tc = self.time((next + 2).min(last));
            let row = self.key_row((next + 2).min(last));
            let mut dst = controls.chunks_exact_mut(4);
            self.row_values(row, |p| {
                if let Some([a, b, c, d]) =
                    dst.next().and_then(|d| <&mut [i32; 4]>::try_from(d).ok())
                {
                    [*a, *b, *c, *d] = [*b, *c, *d, p];
                }
            });
            (next, [at.t1, at.t2, at.tb, tc])
        } else {
            let (i, t) = self.interval(u64::from(rel));
            let mut dst = controls.chunks_exact_mut(4);
            self.controls(i, |p| {
                if let Some(d) = dst.next() {
                    d.copy_from_slice(&p);
                }
            });
            (i, t)
        };
        let [_, t1, t2, tb] = t;
        let (ra, rb) = spline::ratios(t);
        let cached = Cached {
            i,
            t1,
            t2,
            tb,
            ra,
            rb,
        };
        cached.store(iv);
        cached
    }
}

/// Where a group's values go: a run of consecutive channels (written as a
/// sub-slice of `out`, without per-channel index reads or bounds checks),
/// or the channels its 1- or 2-byte indices name.
enum Dst<'i, 'o> {
    Run(&'o mut [i32]),
    Narrow(&'i [u8], &'o mut [i32]),
    Wide(&'i [u8], &'o mut [i32]),
}

impl<'i, 'o> Dst<'i, 'o> {
    /// The destination of the channels listed in `idx`.
    fn of(idx: &'i [u8], wide: bool, out: &'o mut [i32]) -> Option<Self> {
        let width = if wide { 2 } else { 1 };
        let n = idx.len() / width;
        let first = idx.get(..width).map_or(usize::MAX, index_of);
        let last = idx.get(idx.len().wrapping_sub(width)..).map_or(0, index_of);
        // Indices strictly increase (checked by `parse`): n of them
        // spanning n values are consecutive.
        Some(if last.wrapping_sub(first) == n.wrapping_sub(1) {
            Dst::Run(out.get_mut(first..=last)?)
        } else if wide {
            Dst::Wide(idx, out)
        } else {
            Dst::Narrow(idx, out)
        })
    }

    /// Writes `value()` to each channel in order.
    #[inline(always)]
    fn fill(self, mut value: impl FnMut() -> i32) {
        self.each(|o, _| *o = value());
    }

    /// Writes `values` (one per channel).
    fn copy(self, values: &[i32]) {
        if let Dst::Run(dst) = self {
            // Pairs of words (short groups: a call to memcpy costs more).
            let mut pairs = dst.chunks_exact_mut(2);
            let mut from = values.chunks_exact(2);
            for (d, s) in (&mut pairs).zip(&mut from) {
                if let ([d0, d1], &[s0, s1]) = (d, s) {
                    (*d0, *d1) = (s0, s1);
                }
            }
            if let ([d], [s, ..]) = (pairs.into_remainder(), from.remainder()) {
                *d = *s;
            }
            return;
        }
        let mut v = values.iter();
        self.fill(|| v.next().copied().unwrap_or(0));
    }

    /// Calls `f` with each channel's output and its position in the group.
    #[inline(always)]
    fn each(self, mut f: impl FnMut(&mut i32, usize)) {
        match self {
            Dst::Run(dst) => {
                for (i, o) in dst.iter_mut().enumerate() {
                    f(o, i);
                }
            }
            Dst::Narrow(idx, out) => {
                for (i, &c) in idx.iter().enumerate() {
                    if let Some(o) = out.get_mut(usize::from(c)) {
                        f(o, i);
                    }
                }
            }
            Dst::Wide(idx, out) => {
                for (i, c) in idx.chunks_exact(2).enumerate() {
                    if let Some(o) = out.get_mut(index_of(c)) {
                        f(o, i);
                    }
                }
            }
        }
    }

    /// Writes a group of any `k > 0` at spline weights `w`: component `j`
    /// is `a[j] = apply(w, controls[4j..4j + 4])`, then `value = (mean <<
    /// ms) + ((64 + Σ basis·a) >> 7)` (§5.4) from the `n` means and the
    /// `n × k` basis. [`Dst::write_k`] is the same for a fixed `k`.
    fn write(self, k: usize, w: [i32; 4], controls: &[i32], means: &[u8], basis: &[u8], ms: u32) {
        let k = k.clamp(1, K_MAX);
        let mut coef = [0i32; K_MAX];
        for (c, p) in coef.iter_mut().zip(controls.chunks_exact(4)) {
            if let Ok(p) = <[i32; 4]>::try_from(p) {
                *c = spline::apply(w, p);
            }
        }
        let coef = coef.get(..k).unwrap_or(&[]);
        let mut rows = means.chunks_exact(2).zip(basis.chunks_exact(k));
        self.fill(|| match rows.next() {
            Some((m, row)) => channel(mean_of(m), ms, row.iter().zip(coef)),
            None => 0,
        });
    }

    /// [`Dst::write`] for `K` components with coefficients `a`.
    #[inline(always)]
    fn write_k<const K: usize>(self, a: [i32; K], means: &[u8], basis: &[u8], ms: u32) {
        let rows = means.chunks_exact(2).zip(basis.chunks_exact(K));
        let value = |m: &[u8], row: &[u8]| match <&[u8; K]>::try_from(row) {
            Ok(row) => channel(mean_of(m), ms, row.iter().zip(a.iter())),
            Err(_) => 0,
        };
        match self {
            // A single curve (root translations, heading): one channel —
            // no loop to set up.
            Dst::Run([o]) => {
                if let (Some(m), Some(row)) = (means.get(..2), basis.get(..K)) {
                    *o = value(m, row);
                }
            }
            Dst::Run(dst) => {
                for (o, (m, row)) in dst.iter_mut().zip(rows) {
                    *o = value(m, row);
                }
            }
            Dst::Narrow(idx, out) => {
                for (&c, (m, row)) in idx.iter().zip(rows) {
                    if let Some(o) = out.get_mut(usize::from(c)) {
                        *o = value(m, row);
                    }
                }
            }
            Dst::Wide(idx, out) => {
                for (c, (m, row)) in idx.chunks_exact(2).zip(rows) {
                    if let Some(o) = out.get_mut(index_of(c)) {
                        *o = value(m, row);
                    }
                }
            }
        }
    }
}

/// Moves a cache slot (key interval `iv`, control points `controls`) of the
/// group whose record is at `rec` in `body` to the key interval holding
/// `rel`; returns the weights at `rel`.
#[inline(never)]
fn refill_slot(
    body: &[u8],
    rec: usize,
    n: usize,
    k: usize,
    rel: u32,
    iv: &mut [i32; INTERVAL],
    controls: &mut [i32],
) -> Option<[i32; 4]> {
    if next_interval(body, rec, n, k, rel, iv, controls).is_none() {
        refill_search(body, rec, n, rel, iv, controls)?;
    }
    cached_weights(iv, rel)
}

/// [`refill_slot`] when the step is not sequential: the record parsed, the
/// interval searched (out of line: rare, and its frame is large).
#[inline(never)]
fn refill_search(
    body: &[u8],
    rec: usize,
    n: usize,
    rel: u32,
    iv: &mut [i32; INTERVAL],
    controls: &mut [i32],
) -> Option<()> {
    let mut body = Reader::new(body.get(rec..)?);
    let group = read_group(&mut body, n)?;
    group.refill(Cached::of(iv), rel, iv, controls);
    Some(())
}

/// The sequential step of [`GroupHead::refill`] without parsing the whole
/// record: when `rel` lies in the interval after the one in `iv`, shifts
/// the `k` components' control points by one key, reads the new key's
/// time and row (located from `n` and `k`: the record at `rec` was
/// validated when the clip was parsed) and stores the next interval.
/// `None` (nothing changed) when the step is not sequential.
#[inline(always)]
fn next_interval(
    body: &[u8],
    rec: usize,
    n: usize,
    k: usize,
    rel: u32,
    iv: &mut [i32; INTERVAL],
    controls: &mut [i32],
) -> Option<()> {
    let at = Cached::of(iv);
    // The record: k, ms, n means (2 bytes), n × k basis, then m and tb.
    let keys_at = rec.wrapping_add(2).wrapping_add(n.wrapping_mul(k + 2));
    let mut r = Reader::new(body.get(keys_at..)?);
    let keys = r.varint_u32()?;
    let tb = u32::from(r.u8()?);
    let last = keys.saturating_sub(1);
    let next = at.i.wrapping_add(1);
    let sequential = at.tb != at.t2
        && at.t2 << FRAC_BITS <= rel
        && (rel < at.tb << FRAC_BITS || next.wrapping_add(1) == last)
        && next < last;
    if !sequential {
        return None;
    }
    let comps = r.rest();
    let mut row_bits = 0usize;
    let mut p = 0;
    for _ in 0..k {
        let (wd, _, _, next) = comp_at(comps, p)?;
        row_bits = row_bits.wrapping_add(wd as usize);
        p = next;
    }
    let bits = comps.get(p..)?;
    let key = next.wrapping_add(2).min(last) as usize;
    let tb = tb as usize;
    let tc = bits_at(bits, key.wrapping_mul(tb), tb as u32);
    let mut bit = (keys as usize)
        .wrapping_mul(tb)
        .wrapping_add(key.wrapping_mul(row_bits));
    let mut p = 0;
    for d in controls.chunks_exact_mut(4).take(k) {
        let Some((wd, sh, off, next)) = comp_at(comps, p) else {
            break;
        };
        p = next;
        let v = bits_at(bits, bit, wd) as i32;
        bit = bit.wrapping_add(wd as usize);
        let p = off.wrapping_add(v.wrapping_shl(sh));
        if let [a, b, c, e] = d {
            [*a, *b, *c, *e] = [*b, *c, *e, p];
        }
    }
    let t = [at.t1, at.t2, at.tb, tc];
    let (ra, rb) = spline::ratios(t);
    Cached {
        i: next,
        t1: at.t2,
        t2: at.tb,
        tb: tc,
        ra,
        rb,
    }
    .store(iv);
    Some(())
}

/// The component record (§5.3: u8 width, u8 shift, zigzag offset) at byte
/// `p` of `comps`: width, shift, offset and the byte after it.
#[inline(always)]
fn comp_at(comps: &[u8], p: usize) -> Option<(u32, u32, i32, usize)> {
    let &[wd, sh] = comps.get(p..p.wrapping_add(2))? else {
        return None;
    };
    let (u, next) = wire::varint_u32(comps, p.wrapping_add(2))?;
    Some((wd.into(), sh.into(), wire::zigzag_decode(u), next))
}

/// `n ≤ 30` bits of `bytes` from bit `bit`, LSB-first (§4.4); bits past
/// the end read as zero, like [`BitReader`].
#[inline(always)]
fn bits_at(bytes: &[u8], bit: usize, n: u32) -> u32 {
    let at = bit >> 3;
    if n <= 25 {
        // 25 bits past a shift of at most 7 fit in one 32-bit window.
        if let Some(&[a, b, c, d]) = bytes.get(at..at.wrapping_add(4)) {
            let word = u32::from_le_bytes([a, b, c, d]);
            return (word >> (bit & 7)) & 1u32.wrapping_shl(n).wrapping_sub(1);
        }
    }
    let word = match bytes.get(at..at.wrapping_add(8)) {
        Some(&[a, b, c, d, e, f, g, h]) => u64::from_le_bytes([a, b, c, d, e, f, g, h]),
        _ => tail_word(bytes, at),
    };
    ((word >> (bit & 7)) as u32) & 1u32.wrapping_shl(n).wrapping_sub(1)
}

/// [`bits_at`] at a 64-bit bit position.
#[inline(always)]
fn bits_at64(bytes: &[u8], bit: u64, n: u32) -> u32 {
    match usize::try_from(bit) {
        Ok(bit) if bit < usize::MAX - 64 => bits_at(bytes, bit, n),
        _ => 0,
    }
}

/// The eight bytes of `bytes` from `at` as a little-endian word, zeros past
/// the end.
#[inline(never)]
fn tail_word(bytes: &[u8], at: usize) -> u64 {
    let mut word = 0u64;
    for i in 0..8 {
        let b = at
            .checked_add(i)
            .and_then(|j| bytes.get(j))
            .copied()
            .unwrap_or(0);
        word |= u64::from(b) << (8 * i);
    }
    word
}

/// The `K` component values at spline weights `w` from their control
/// points (four per component, in order).
#[inline(always)]
fn coefficients<const K: usize>(w: [i32; 4], controls: &[i32]) -> [i32; K] {
    let mut a = [0i32; K];
    if let Some(controls) = controls.get(..4 * K) {
        for (c, p) in a.iter_mut().zip(controls.chunks_exact(4)) {
            if let &[p0, p1, p2, p3] = p {
                *c = spline::apply(w, [p0, p1, p2, p3]);
            }
        }
    }
    a
}

/// One channel: `(mean << ms) + ((64 + Σ b·a) >> 7)`.
#[inline(always)]
fn channel<'x>(mean: i32, ms: u32, terms: impl Iterator<Item = (&'x u8, &'x i32)>) -> i32 {
    let mut acc: i32 = 1 << (BASIS_SHIFT - 1);
    for (&b, &a) in terms {
        acc = acc.wrapping_add(i32::from(b as i8).wrapping_mul(a));
    }
    mean.wrapping_shl(ms).wrapping_add(acc >> BASIS_SHIFT)
}

/// A 1- or 2-byte little-endian channel index.
#[inline(always)]
fn index_of(ix: &[u8]) -> usize {
    match ix {
        [lo] => usize::from(*lo),
        [lo, hi] => usize::from(*lo) | usize::from(*hi) << 8,
        _ => usize::MAX,
    }
}

/// One channel's value from a group (row `row` of the basis).
#[inline(always)]
fn channel_value(head: &GroupHead<'_>, mean: i32, row: &[u8], coef: &[i32]) -> i32 {
    channel(mean, head.mean_shift, row.iter().zip(coef))
}

/// The values of a group's channels in order (`k = 0`: the zigzag means).
struct GroupValues<'h, 'a> {
    head: &'h GroupHead<'a>,
    coef: &'h [i32],
    means: Reader<'a>,
    row: usize,
}

impl<'h, 'a> GroupValues<'h, 'a> {
    fn new(head: &'h GroupHead<'a>, coef: &'h [i32]) -> Self {
        GroupValues {
            head,
            coef,
            means: Reader::new(head.mean),
            row: 0,
        }
    }

    fn next(&mut self) -> Option<i32> {
        let h = self.head;
        if h.k == 0 {
            return Some(self.means.zigzag_i32()?.wrapping_shl(h.mean_shift));
        }
        let mean = mean_of(self.means.take(2)?);
        let at = self.row * h.k;
        let row = h.basis.get(at..at + h.k)?;
        self.row += 1;
        Some(channel_value(h, mean, row, self.coef))
    }
}

/// A mean: `i16` little-endian.
#[inline(always)]
fn mean_of(m: &[u8]) -> i32 {
    match m {
        [a, b] => i32::from(i16::from_le_bytes([*a, *b])),
        _ => 0,
    }
}

/// Reads up to 30 bits (two reads of at most 15).
fn read_wide(bits: &mut BitReader<'_>, n: u32) -> u32 {
    let lo_n = n.min(15);
    let lo = bits.read(lo_n);
    let hi = bits.read(n - lo_n);
    lo | (hi << lo_n)
}

/// Reads one group's fields (§5.3) from a segment body.
fn read_group<'a>(r: &mut Reader<'a>, n: usize) -> Option<GroupHead<'a>> {
    let k = r.u8()?;
    let mean_shift = r.u8()?;
    if k > MAX_COMPONENTS || mean_shift > MAX_MEAN_SHIFT {
        return None;
    }
    let k = usize::from(k);
    // k = 0: n zigzag varints (a constant pose is often mostly zeros);
    // k > 0: n × i16, read on every pose.
    let mean = if k == 0 {
        let at = r.clone();
        for _ in 0..n {
            r.zigzag_i32()?;
        }
        let len = r.pos() - at.pos();
        at.clone().take(len)?
    } else {
        r.take(n.checked_mul(2)?)?
    };
    let mut head = GroupHead {
        k,
        mean_shift: u32::from(mean_shift),
        mean,
        basis: &[],
        keys: 0,
        time_bits: 0,
        comps: &[],
        row_bits: 0,
        bits: &[],
    };
    if k == 0 {
        return Some(head);
    }
    head.basis = r.take(n.checked_mul(k)?)?;
    head.keys = r.varint_u32()?;
    let time_bits = r.u8()?;
    if time_bits == 0 || time_bits > MAX_TIME_BITS {
        return None;
    }
    head.time_bits = u32::from(time_bits);
    let comps_at = r.clone();
    let mut row_bits = 0u32;
    for _ in 0..k {
        let (w, s, _, len) = comp_at(r.clone().rest(), 0)?;
        r.take(len)?;
        if w > u32::from(MAX_VALUE_BITS) || s > u32::from(MAX_VALUE_SHIFT) {
            return None;
        }
        row_bits += w;
    }
    head.comps = comps_at.clone().take(r.pos() - comps_at.pos())?;
    head.row_bits = row_bits;
    let total = u64::from(head.keys) * u64::from(head.time_bits + row_bits);
    head.bits = r.take(usize::try_from(total.div_ceil(8)).ok()?)?;
    Some(head)
}

/// Checks `n` channel indices: below `channels` and strictly increasing.
fn check_indices(r: &mut Reader<'_>, n: u32, wide: bool, channels: usize) -> Result<(), Error> {
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

/// Channel indices stored as 1- or 2-byte little-endian integers.
#[derive(Clone, Debug)]
struct Indices<'a> {
    bytes: core::slice::Iter<'a, u8>,
    wide: bool,
}

impl<'a> Indices<'a> {
    fn new(bytes: &'a [u8], wide: bool) -> Self {
        Indices {
            bytes: bytes.iter(),
            wide,
        }
    }
}

impl Iterator for Indices<'_> {
    type Item = usize;

    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        let lo = usize::from(*self.bytes.next()?);
        if self.wide {
            Some(lo | usize::from(*self.bytes.next()?) << 8)
        } else {
            Some(lo)
        }
    }
}
