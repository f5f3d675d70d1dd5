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
/// current and previous segment headers, so sequential playback never
/// walks the list again.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Cursor {
    current: usize,
    previous: Option<usize>,
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

    /// Adds the patches of `seg` at relative frame `frame` times `weight`
    /// (16.16) to `out` (§5.5).
    fn apply_patches(&self, seg: &Segment<'a>, frame: u32, weight: i64, out: &mut [i32]) {
        let mut r = Reader::new(seg.patches);
        let mut at = 0u32;
        while let Some((delta, c, v)) = self.read_patch(&mut r) {
            at = at.wrapping_add(delta);
            if at > frame {
                return;
            }
            if at == frame {
                if let Some(o) = out.get_mut(c) {
                    *o = o.wrapping_add(((i64::from(v) * weight) >> FRAC_BITS) as i32);
                }
            }
        }
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
    /// into `out`. `cursor` remembers the segment for the next call;
    /// `cache` (any length, its content is the decoder's own) keeps the
    /// current key interval of each group of that segment so that poses
    /// inside one interval skip the bit reading (§6: the output never
    /// depends on it).
    pub(crate) fn decode_at(
        &self,
        pos: u64,
        cursor: &mut Cursor,
        out: &mut [i32],
        cache: &mut [i32],
    ) {
        let frame = u32::try_from(pos >> FRAC_BITS).unwrap_or(u32::MAX);
        let Some((prev, cur, next)) = self.locate(frame, cursor) else {
            return;
        };
        self.write_consts(out);
        // A blend window (§5.2) around the start of `cur` or of `next`:
        // (earlier, later, which of them is `cur`).
        let window = match (prev, next) {
            (Some(p), _) if pos < (u64::from(p.end) + 1) << FRAC_BITS => Some((p, cur, false)),
            (_, Some(n)) if pos > u64::from(n.start.saturating_sub(1)) << FRAC_BITS => {
                Some((cur, n, true))
            }
            _ => None,
        };
        match window {
            None => self.eval(&cur, None, pos, out, cache),
            Some((a, b, cur_first)) => {
                // w = (pos - (S - 1)) / (E - S + 2), 16.16, S = b.start,
                // E = a.end.
                let from = u64::from(b.start.saturating_sub(1)) << FRAC_BITS;
                let steps = u64::from(a.end.saturating_add(2).saturating_sub(b.start)).max(1);
                let w = (pos.saturating_sub(from) / steps).min(1 << FRAC_BITS) as i64;
                let (cached, other) = if cur_first { (a, b) } else { (b, a) };
                self.eval(&cached, Some((&other, w, cur_first)), pos, out, cache);
            }
        }
        // Patches at the two frames around pos, each weighted by its hat
        // function (§5.5).
        let one = 1i64 << FRAC_BITS;
        let frac = (pos & ((1 << FRAC_BITS) - 1)) as i64;
        self.apply_patches(&cur, frame.wrapping_sub(cur.start), one - frac, out);
        if frac > 0 {
            let after = frame.saturating_add(1);
            match next {
                Some(n) if n.start == after => self.apply_patches(&n, 0, frac, out),
                _ => self.apply_patches(&cur, after.wrapping_sub(cur.start), frac, out),
            }
        }
    }

    /// Finds the segment holding `frame` (the last one starting at or
    /// before it) and its neighbours, moving `cursor`.
    #[allow(clippy::type_complexity)]
    fn locate(
        &self,
        frame: u32,
        cursor: &mut Cursor,
    ) -> Option<(Option<Segment<'a>>, Segment<'a>, Option<Segment<'a>>)> {
        let mut cur = self.segment_at(cursor.current)?;
        if frame < cur.start {
            *cursor = Cursor::default();
            cur = self.segment_at(0)?;
        }
        loop {
            let next = self.segment_at(cur.next);
            match next {
                Some(n) if n.start <= frame => {
                    cursor.previous = Some(cursor.current);
                    cursor.current = cur.next;
                    cur = n;
                }
                _ => {
                    let prev = cursor.previous.and_then(|p| self.segment_at(p));
                    return Some((prev, cur, next));
                }
            }
        }
    }

    fn write_consts(&self, out: &mut [i32]) {
        let mut r = Reader::new(self.consts);
        let n = self.const_count as usize;
        let indices = Indices::new(r.take(n * self.width()).unwrap_or(&[]), self.wide);
        for c in indices {
            let v = r.zigzag_i32().unwrap_or(0);
            if let Some(o) = out.get_mut(c) {
                *o = v;
            }
        }
    }

    /// Evaluates every group of `seg` at `pos` (clamped into the segment),
    /// through the cache; with `other = (segment, w, seg_is_earlier)` each
    /// channel is the blend of the two segments' values with weight `w` on
    /// the later one (§5.4 step 4).
    fn eval(
        &self,
        seg: &Segment<'a>,
        other: Option<(&Segment<'a>, i64, bool)>,
        pos: u64,
        out: &mut [i32],
        cache: &mut [i32],
    ) {
        // cache[0] names the segment the slots belong to (start + 1).
        let owner = seg.start.wrapping_add(1) as i32;
        let fresh = cache.first() != Some(&owner);
        if let Some(c) = cache.first_mut() {
            *c = owner;
        }
        let mut slots = cache.get_mut(1..).unwrap_or(&mut []);
        let rel = relative(seg, pos);
        let mut g = Reader::new(self.groups);
        let mut body = Reader::new(seg.body);
        let mut body_b = other.map(|(o, _, _)| (Reader::new(o.body), relative(o, pos)));
        for _ in 0..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            let idx = g.take(n * self.width()).unwrap_or(&[]);
            let k = body.clone().u8().map_or(0, usize::from);
            let want = if k == 0 { 0 } else { SLOT_HEAD + 4 * k };
            let (slot, rest) = if slots.len() >= want {
                let (slot, rest) = core::mem::take(&mut slots).split_at_mut(want);
                (Some(slot), rest)
            } else {
                (None, core::mem::take(&mut slots))
            };
            slots = rest;
            let mut coef = [0i32; K_MAX];
            let Some(head) = group_at(&mut body, n, rel, &mut coef, slot, fresh) else {
                return;
            };
            let coef = coef.get(..head.k).unwrap_or(&[]);
            match &mut body_b {
                None => {
                    if self.wide {
                        reconstruct::<true>(idx, &head, coef, out);
                    } else {
                        reconstruct::<false>(idx, &head, coef, out);
                    }
                }
                Some((rb, rel_b)) => {
                    let mut coef_b = [0i32; K_MAX];
                    let Some(head_b) = group_at(rb, n, *rel_b, &mut coef_b, None, true) else {
                        return;
                    };
                    let coef_b = coef_b.get(..head_b.k).unwrap_or(&[]);
                    let (_, w, seg_first) = other.unwrap_or((seg, 0, true));
                    // (earlier, later) for the blend.
                    let (ea, la) = if seg_first {
                        ((&head, coef), (&head_b, coef_b))
                    } else {
                        ((&head_b, coef_b), (&head, coef))
                    };
                    blend_group(idx, self.wide, ea, la, w, out);
                }
            }
        }
    }
}

/// Header words of a cache slot: interval, record length, four key times.
const SLOT_HEAD: usize = 6;

/// `pos` relative to the segment's start, clamped into it.
fn relative(seg: &Segment<'_>, pos: u64) -> u64 {
    pos.saturating_sub(u64::from(seg.start) << FRAC_BITS)
        .min(u64::from(seg.end - seg.start) << FRAC_BITS)
}

/// Reads the next group record of a segment body and its coefficients at
/// `rel`. A cache `slot` (6 + 4k words) that holds the interval of `rel`
/// spares the bit reading; otherwise it is refilled.
fn group_at<'a>(
    body: &mut Reader<'a>,
    n: usize,
    rel: u64,
    coef: &mut [i32; K_MAX],
    slot: Option<&mut [i32]>,
    fresh: bool,
) -> Option<GroupHead<'a>> {
    if let Some(slot) = slot {
        if !fresh {
            if let Some(head) = cached(body, n, rel, coef, slot) {
                return Some(head);
            }
        }
        let start = body.clone();
        let head = read_group(body, n)?;
        head.coefficients(rel, coef, Some(slot));
        if let Some(len) = slot.get_mut(1) {
            *len = (body.pos() - start.pos()) as i32;
        }
        return Some(head);
    }
    let head = read_group(body, n)?;
    head.coefficients(rel, coef, None);
    Some(head)
}

/// A cache hit: `rel` lies in the slot's interval. Skips the record and
/// evaluates the cached control points.
fn cached<'a>(
    body: &mut Reader<'a>,
    n: usize,
    rel: u64,
    coef: &mut [i32; K_MAX],
    slot: &[i32],
) -> Option<GroupHead<'a>> {
    let [interval, len, ta, t1, t2, tb] = *slot.get(..SLOT_HEAD)? else {
        return None;
    };
    let t = [ta, t1, t2, tb].map(|t| t as u32);
    let inside = interval >= 0
        && u64::from(t[1]) << FRAC_BITS <= rel
        && (rel < u64::from(t[2]) << FRAC_BITS || t[2] == t[3]);
    if !inside {
        return None;
    }
    let mut rec = Reader::new(body.clone().take(usize::try_from(len).ok()?)?);
    let k = usize::from(rec.u8()?);
    let mean_shift = u32::from(rec.u8()?);
    let mean = rec.take(n.checked_mul(2)?)?;
    let basis = rec.take(n.checked_mul(k)?)?;
    body.take(usize::try_from(len).ok()?)?;
    let w = spline::weights(t, rel);
    let controls = slot.get(SLOT_HEAD..)?;
    for (c, p) in coef.iter_mut().zip(controls.chunks_exact(4)).take(k) {
        if let [a, b, c2, d] = *p {
            *c = spline::apply(w, [a, b, c2, d]);
        }
    }
    Some(GroupHead {
        k,
        mean_shift,
        mean,
        basis,
        keys: 0,
        time_bits: 0,
        comps: &[],
        row_bits: 0,
        bits: &[],
    })
}

impl GroupHead<'_> {
    /// The spline's value of every component at `rel` (16.16 frames from
    /// the segment start), §5.4.
    fn coefficients(&self, rel: u64, coef: &mut [i32; K_MAX], mut slot: Option<&mut [i32]>) {
        if self.k == 0 {
            return;
        }
        let m = self.keys;
        let time = |i: u32| {
            BitReader::at(self.bits, u64::from(i) * u64::from(self.time_bits)).read(self.time_bits)
        };
        // Largest i <= m - 2 with t[i] <= rel.
        let last = m.saturating_sub(1);
        let (mut lo, mut hi) = (0u32, last);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if u64::from(time(mid)) << FRAC_BITS <= rel {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let i = lo;
        let rows = [i.saturating_sub(1), i, i + 1, (i + 2).min(last)];
        let t = rows.map(time);
        let w = spline::weights(t, rel);
        if let Some([interval, _, ta, t1, t2, tb]) =
            slot.as_deref_mut().and_then(|s| s.get_mut(..SLOT_HEAD))
        {
            *interval = i as i32;
            [*ta, *t1, *t2, *tb] = t.map(|t| t as i32);
        }
        // The four key rows are read in lockstep, one component at a time.
        let base = u64::from(m) * u64::from(self.time_bits);
        let mut readers = rows
            .map(|row| BitReader::at(self.bits, base + u64::from(row) * u64::from(self.row_bits)));
        let mut comps = Reader::new(self.comps);
        let mut controls = slot
            .and_then(|s| s.get_mut(SLOT_HEAD..))
            .unwrap_or(&mut [])
            .chunks_exact_mut(4);
        for c in coef.iter_mut().take(self.k) {
            let (Some(wd), Some(sh), Some(off)) = (comps.u8(), comps.u8(), comps.zigzag_i32())
            else {
                return;
            };
            let (wd, sh) = (u32::from(wd), u32::from(sh));
            let p = readers
                .each_mut()
                .map(|r| off.wrapping_add((read_wide(r, wd) as i32).wrapping_shl(sh)));
            if let Some(dst) = controls.next() {
                dst.copy_from_slice(&p);
            }
            *c = spline::apply(w, p);
        }
    }
}

/// The inner loop: `value = mean << shift + (Σ basis·coef + 64) >> 7`.
#[inline(always)]
fn reconstruct<const WIDE: bool>(idx: &[u8], head: &GroupHead<'_>, coef: &[i32], out: &mut [i32]) {
    let indices = Indices::new(idx, WIDE);
    let means = head.mean.chunks_exact(2);
    let k = head.k.max(1);
    let rows = head.basis.chunks_exact(k);
    if head.k == 0 {
        let mut r = Reader::new(head.mean);
        for c in indices {
            let m = r.zigzag_i32().unwrap_or(0);
            if let Some(o) = out.get_mut(c) {
                *o = m.wrapping_shl(head.mean_shift);
            }
        }
        return;
    }
    for ((c, m), row) in indices.zip(means).zip(rows) {
        let v = channel_value(head, mean_of(m), row, coef);
        if let Some(o) = out.get_mut(c) {
            *o = v;
        }
    }
}

/// One channel's value from a group (row `row` of the basis).
#[inline(always)]
fn channel_value(head: &GroupHead<'_>, mean: i32, row: &[u8], coef: &[i32]) -> i32 {
    let mut acc: i32 = 1 << (BASIS_SHIFT - 1);
    for (&b, &a) in row.iter().zip(coef) {
        acc = acc.wrapping_add(i32::from(b as i8).wrapping_mul(a));
    }
    mean.wrapping_shl(head.mean_shift)
        .wrapping_add(acc >> BASIS_SHIFT)
}

/// Blends one group of two segments channel by channel: `a + (b − a)·w`.
fn blend_group(
    idx: &[u8],
    wide: bool,
    (ha, ca): (&GroupHead<'_>, &[i32]),
    (hb, cb): (&GroupHead<'_>, &[i32]),
    w: i64,
    out: &mut [i32],
) {
    // Values of a k = 0 group come from varints: decode both sides into
    // `out` one channel at a time.
    let mut va = GroupValues::new(ha, ca);
    let mut vb = GroupValues::new(hb, cb);
    for c in Indices::new(idx, wide) {
        let (Some(a), Some(b)) = (va.next(), vb.next()) else {
            return;
        };
        if let Some(o) = out.get_mut(c) {
            let d = i64::from(b.wrapping_sub(a));
            *o = a.wrapping_add(((d * w) >> FRAC_BITS) as i32);
        }
    }
}

/// The values of a group's channels in order.
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
        let w = r.u8()?;
        let s = r.u8()?;
        if w > MAX_VALUE_BITS || s > MAX_VALUE_SHIFT {
            return None;
        }
        r.zigzag_i32()?;
        row_bits += u32::from(w);
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
