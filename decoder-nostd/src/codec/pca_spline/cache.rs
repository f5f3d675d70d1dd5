//! The player's cache of key intervals (SPEC.md §6: the output never
//! depends on it): its layout, filling it for a segment, and the hot path
//! that evaluates every cached group of a pose — control points and
//! tangent ratios kept so a pose inside an interval reads no bits.

use super::*;

/// Words of the cache head: owner (segment start + 1), groups with a slot,
/// offset of the first record without one, where the constants' values
/// are (−1: not cached).
pub const CACHE_HEAD: usize = 4;

/// Words at the start of every group slot (see `eval`).
pub const GROUP_HEAD: usize = 3;

/// Words of a `k > 0` slot's key interval (see [`Cached`]).
pub const INTERVAL: usize = 4;

/// The key interval a cache slot holds, packed in [`INTERVAL`] words:
/// `t1 << 16 | span` (`span = t2 − t1`), the bound `lim` of `rel − (t1 <<
/// 16)` (`span << 16`, or `span << 16 | 0xFFFF` for the last interval,
/// which also holds its end key), `(ra − 1) | (rb − 1) << 16` and `i | tb
/// << 16` — key times below 2^15 and tangent ratios in `2..=2^16` (§5.4)
/// fit. A pose reads the first three; a refill all four.
#[derive(Clone, Copy)]
pub(super) struct Cached {
    /// The interval `i` and its four key times `[ta, t1, t2, tb]`; `ta` is
    /// not kept (it only enters `ra`).
    pub(super) i: u32,
    t1: u32,
    t2: u32,
    pub(super) tb: u32,
    pub(super) ra: i32,
    pub(super) rb: i32,
}

impl Cached {
    /// Holds no position.
    const EMPTY: [i32; INTERVAL] = [0, 0, 0, 0xFFFF];

    pub(super) fn of(iv: &[i32; INTERVAL]) -> Self {
        let [a, _, c, d] = iv.map(|w| w as u32);
        let t1 = a >> 16;
        Cached {
            i: d & 0xFFFF,
            t1,
            t2: t1.wrapping_add(a & 0xFFFF),
            tb: d >> 16,
            ra: ((c & 0xFFFF) as i32).wrapping_add(1),
            rb: ((c >> 16) as i32).wrapping_add(1),
        }
    }

    pub(super) fn store(&self, iv: &mut [i32; INTERVAL]) {
        let span = self.t2.wrapping_sub(self.t1) & 0xFFFF;
        let last = if self.tb == self.t2 { 0xFFFF } else { 0 };
        *iv = [
            self.t1 << FRAC_BITS | span,
            span << FRAC_BITS | last,
            self.ra.wrapping_sub(1) as u32 | (self.rb.wrapping_sub(1) as u32) << 16,
            self.i | self.tb << 16,
        ]
        .map(|w| w as i32);
    }
}

/// The spline weights at `rel` (§5.4) if the interval held in `iv` holds
/// it (else a refill is due): `t1 << 16 <= rel < t2 << 16`, or up to the
/// end key for the last interval.
#[inline(always)]
pub(super) fn cached_weights(iv: &[i32; INTERVAL], rel: u32) -> Option<[i32; 4]> {
    let [a, lim, r, _] = iv.map(|w| w as u32);
    let d = rel.wrapping_sub(a & 0xFFFF_0000);
    if d >= lim {
        return None;
    }
    let u = d.checked_div(a & 0xFFFF).unwrap_or(0);
    Some(spline::weights_at(
        u,
        ((r & 0xFFFF) as i32).wrapping_add(1),
        ((r >> 16) as i32).wrapping_add(1),
    ))
}

/// `n | k << 18 | c << 23 | ms << 24` (n ≤ 2^17 channels, k ≤ 16, ms ≤ 16)
/// with `c` set for a single curve (one channel, a run at `dst`, one
/// component), so `nkm >> 18 & 0x3F` dispatches a slot.
pub(super) fn pack(n: usize, k: usize, ms: u32, dst: i32) -> i32 {
    let curve = u32::from(n == 1 && k == 1 && dst >= 0);
    (n as u32 | (k as u32) << 18 | curve << 23 | ms << 24) as i32
}

pub(super) fn unpack(nkm: i32) -> (usize, usize, u32) {
    let v = nkm as u32;
    (
        (v & 0x3_FFFF) as usize,
        (v >> 18 & 0x1F) as usize,
        v >> 24 & 0x1F,
    )
}

/// Moves a cache slot (key interval `iv`, control points `controls`) of the
/// group whose record is at `rec` in `body` to the key interval holding
/// `rel`; returns the weights at `rel`.
#[inline(never)]
pub(super) fn refill_slot(
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
pub(super) fn refill_search(
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
pub(super) fn next_interval(
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
    let keys_at = rec
        .wrapping_add(2)
        .wrapping_add(n.wrapping_mul(k.wrapping_add(2)));
    // The key count through the varint loop inlined on the slice, not a
    // `Reader`: an out-of-line slow path (the reader's) would keep values
    // in memory or in extra registers on the fast path too.
    let keys_on = body.get(keys_at..)?;
    let (keys, p) = wire::varint_u32_any(keys_on, 0)?;
    let (&tb, comps) = keys_on.get(p..)?.split_first()?;
    let tb = u32::from(tb);
    let last = keys.saturating_sub(1);
    let next = at.i.wrapping_add(1);
    let sequential = at.tb != at.t2
        && at.t2 << FRAC_BITS <= rel
        && (rel < at.tb << FRAC_BITS || next.wrapping_add(1) == last)
        && next < last;
    if !sequential {
        return None;
    }
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

impl<'a> PcaSplineCodec<'a> {
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
    /// decoded from the record on every pose. `None` (with `out` partly
    /// written) only if an invariant of the validated section is broken.
    pub(super) fn eval(
        &self,
        seg: &Segment<'a>,
        pos: u64,
        out: &mut [i32],
        cache: &mut [i32],
    ) -> Option<()> {
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
            let &[_, dst, nkm] = slots.first_chunk::<GROUP_HEAD>()?;
            let (n, k, _) = unpack(nkm);
            if k == 0 {
                let (values, tail) = core::mem::take(&mut slots)
                    .get_mut(GROUP_HEAD..)
                    .and_then(|t| t.split_at_mut_checked(n))?;
                slots = tail;
                self.copy_group(dst, values, pose.out)?;
                continue;
            }
            let size = (GROUP_HEAD + INTERVAL).wrapping_add(k.wrapping_mul(4));
            let (slot, tail) = core::mem::take(&mut slots).split_at_mut_checked(size)?;
            self.slot_group(nkm, slot, &mut pose);
            slots = tail;
        }
        if cached == self.group_count {
            return Some(());
        }
        self.uncached_groups(seg, cached, rest, &mut pose)
    }

    /// The groups without a cache slot (from group `cached` on; their
    /// records from offset `rest` of the segment's body), decoded from the
    /// record on every pose through a slot on the stack. Out of line: that
    /// slot (`GROUP_HEAD + INTERVAL + 4·K_MAX` words) is on the stack only
    /// while a player too small to cache every group needs it, not under
    /// every `next_frame`.
    #[inline(never)]
    fn uncached_groups(
        &self,
        seg: &Segment<'a>,
        cached: u32,
        rest: usize,
        pose: &mut Pose<'a, '_>,
    ) -> Option<()> {
        // Groups without a cache slot: parse the record on every pose.
        let mut g = Reader::new(self.groups);
        for _ in 0..cached {
            let n = g.varint_u32().unwrap_or(0) as usize;
            g.take(n.wrapping_mul(self.width()));
        }
        let mut body = Reader::new(seg.body.get(rest..).unwrap_or(&[]));
        // A slot on the stack, evaluated like a cached one (refilled every
        // pose).
        let mut slot = [0i32; GROUP_HEAD + INTERVAL + 4 * K_MAX];
        for _ in cached..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            let idx_at = g.pos();
            let idx = g.take(n.wrapping_mul(self.width())).unwrap_or(&[]);
            let rec = body.pos();
            let group = read_group(&mut body, n)?;
            if group.k == 0 {
                let target = Dst::of(idx, self.wide, pose.out)?;
                let mut values = GroupValues::new(&group, &[]);
                target.fill(|| values.next().unwrap_or(0));
                continue;
            }
            let dst = self.dst_word(idx, idx_at, n);
            let hd = [
                rest.wrapping_add(rec) as i32,
                dst,
                pack(n, group.k, group.mean_shift, dst),
            ];
            if let Some((h, iv)) = slot.split_first_chunk_mut::<GROUP_HEAD>() {
                *h = hd;
                if let Some((iv, _)) = iv.split_first_chunk_mut::<INTERVAL>() {
                    *iv = Cached::EMPTY;
                }
            }
            self.slot_group(hd[2], &mut slot, pose);
        }
        Some(())
    }

    /// Writes the values of a cached `k = 0` group (one per channel) where
    /// its slot's `dst` word says. Out of line: one such group per pose at
    /// most in practice, and inlined it costs the slot loop two registers
    /// (a copy on every group).
    #[inline(never)]
    pub(super) fn copy_group(&self, dst: i32, values: &[i32], out: &mut [i32]) -> Option<()> {
        self.target(dst, values.len(), out)?.copy(values);
        Some(())
    }

    /// Where a group's values go, as a slot stores it: the first channel of
    /// a run of consecutive channels, or `−1 −` the offset `idx_at` of its
    /// index list `idx` in the group table.
    pub(super) fn dst_word(&self, idx: &[u8], idx_at: usize, n: usize) -> i32 {
        let width = self.width();
        let first = idx.get(..width).map_or(usize::MAX, index_of);
        let last = idx.get(idx.len().wrapping_sub(width)..).map_or(0, index_of);
        // Indices strictly increase (checked by `parse`): n of them
        // spanning n values are consecutive.
        if last.wrapping_sub(first) == n.wrapping_sub(1) {
            first as i32
        } else {
            (-1i32).wrapping_sub(idx_at as i32)
        }
    }

    /// Evaluates a `k > 0` group from its slot (head, key interval, control
    /// points), through the function specialised for its `k` (or for a
    /// single curve), as its head word `nkm` says. The caller hands it
    /// exactly the slot (its size follows from `k`).
    #[inline(always)]
    pub(super) fn slot_group(&self, nkm: i32, slot: &mut [i32], pose: &mut Pose<'a, '_>) {
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
    pub(super) fn cached_group<const K: usize>(&self, slot: &mut [i32], pose: &mut Pose<'a, '_>) {
        // Nothing to report: on a validated clip every step succeeds (and
        // returning nothing keeps a register free in the channel loops).
        let _ = self.group_k::<K>(slot, pose);
    }

    #[inline(always)]
    pub(super) fn group_k<const K: usize>(
        &self,
        slot: &mut [i32],
        pose: &mut Pose<'a, '_>,
    ) -> Option<()> {
        let (&mut [rec, dst, nkm], slot) = slot.split_first_chunk_mut::<GROUP_HEAD>()?;
        let (body, rel) = (pose.body, pose.rel);
        let (n, _, ms) = unpack(nkm);
        let (iv, rest) = slot.split_first_chunk_mut::<INTERVAL>()?;
        let controls = rest.get_mut(..K.wrapping_mul(4))?;
        let rec = rec as usize;
        let w = match cached_weights(iv, rel) {
            Some(w) => w,
            None => refill_slot(body, rec, n, K, rel, iv, controls)?,
        };
        let a = coefficients::<K>(w, controls);
        let (means, basis) = body
            .get(rec.wrapping_add(2)..)?
            .split_at_checked(n.wrapping_mul(2))?;
        self.target(dst, n, pose.out)?
            .write_k::<K>(a, means, basis, ms);
        Some(())
    }

    /// [`Self::cached_group`] for any `k`.
    pub(super) fn cached_group_any(&self, slot: &mut [i32], pose: &mut Pose<'a, '_>) {
        let _ = self.group_any(slot, pose);
    }

    pub(super) fn group_any(&self, slot: &mut [i32], pose: &mut Pose<'a, '_>) -> Option<()> {
        let (&mut [rec, dst, nkm], slot) = slot.split_first_chunk_mut::<GROUP_HEAD>()?;
        let (body, rel) = (pose.body, pose.rel);
        let (n, k, ms) = unpack(nkm);
        let (iv, rest) = slot.split_first_chunk_mut::<INTERVAL>()?;
        let controls = rest.get_mut(..k.wrapping_mul(4))?;
        let rec = rec as usize;
        let w = match cached_weights(iv, rel) {
            Some(w) => w,
            None => refill_slot(body, rec, n, k, rel, iv, controls)?,
        };
        let (means, basis) = body
            .get(rec.wrapping_add(2)..)?
            .split_at_checked(n.wrapping_mul(2))?;
        let basis = basis.get(..n.wrapping_mul(k))?;
        self.target(dst, n, pose.out)?
            .write(k, w, controls, means, basis, ms);
        Some(())
    }

    /// A cached group of one channel (a run at `hd[1]`) and one component — a
    /// single curve (root translations, heading): [`Self::cached_group`]
    /// without a channel loop and with the record's five leading bytes (k, ms,
    /// mean, basis entry) read at once.
    #[inline(never)]
    pub(super) fn curve(slot: &mut [i32], pose: &mut Pose<'a, '_>) {
        let _ = Self::curve_at(slot, pose);
    }

    #[inline(always)]
    pub(super) fn curve_at(slot: &mut [i32], pose: &mut Pose<'a, '_>) -> Option<()> {
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
    pub(super) fn target<'o>(&self, dst: i32, n: usize, out: &'o mut [i32]) -> Option<Dst<'a, 'o>> {
        if let Ok(first) = usize::try_from(dst) {
            return out.get_mut(first..first.checked_add(n)?).map(Dst::Run);
        }
        let at = usize::try_from((-1i64).wrapping_sub(i64::from(dst))).ok()?;
        let idx = self
            .groups
            .get(at..at.checked_add(n.wrapping_mul(self.width()))?)?;
        Some(if self.wide {
            Dst::Wide(idx, out)
        } else {
            Dst::Narrow(idx, out)
        })
    }

    /// Words of a cache that holds every group of every segment and the
    /// constants (what [`Self::prepare`] fills at most); read once, when a
    /// codec built on this body decides how to share a player's words.
    pub(crate) fn full_cache_words(&self) -> usize {
        let mut most = 0usize;
        let mut at = 0usize;
        while let Some(seg) = self.segment_at(at) {
            let mut g = Reader::new(self.groups);
            let mut body = Reader::new(seg.body);
            let mut words = CACHE_HEAD.wrapping_add(self.const_count as usize);
            for _ in 0..self.group_count {
                let n = g.varint_u32().unwrap_or(0) as usize;
                if g.take(n.wrapping_mul(self.width())).is_none() {
                    break;
                }
                let Some(group) = read_group(&mut body, n) else {
                    break;
                };
                words = words.wrapping_add(GROUP_HEAD.wrapping_add(if group.k == 0 {
                    n
                } else {
                    INTERVAL.wrapping_add(group.k.wrapping_mul(4))
                }));
            }
            most = most.max(words);
            if seg.next <= at {
                break;
            }
            at = seg.next;
        }
        most
    }

    /// Marks a cache as holding nothing (its words were used for something
    /// else): the next pose through it fills it again.
    pub(crate) fn forget(cache: &mut [i32]) {
        if let Some(owner) = cache.first_mut() {
            *owner = 0;
        }
    }

    /// Fills the cache head and as many group slots as fit for `seg`, each
    /// group's key interval the one holding `rel`.
    pub(super) fn prepare(
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
            let idx = g.take(n.wrapping_mul(self.width())).unwrap_or(&[]);
            let rec = body.pos();
            let mut next = body.clone();
            let Some(group) = read_group(&mut next, n) else {
                break;
            };
            let size = GROUP_HEAD.wrapping_add(if group.k == 0 {
                n
            } else {
                INTERVAL.wrapping_add(group.k.wrapping_mul(4))
            });
            let Some((slot, tail)) = core::mem::take(&mut free).split_at_mut_checked(size) else {
                break;
            };
            free = tail;
            body = next;
            count = count.wrapping_add(1);
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
            consts = total.wrapping_sub(free.len()) as i32;
        }
        if let [o, g, at, c] = head {
            (*o, *g, *at, *c) = (owner, count, body.pos() as i32, consts);
        }
    }
}

impl GroupHead<'_> {
    /// Refills a cache slot for `rel`: when `rel` lies in the interval
    /// after the cached one (sequential playback), the control points shift
    /// by one key and one key row is read; otherwise the interval is
    /// searched and its four rows read.
    pub(super) fn refill(
        &self,
        at: Cached,
        rel: u32,
        iv: &mut [i32; INTERVAL],
        controls: &mut [i32],
    ) -> Cached {
        let last = self.keys.saturating_sub(1);
        let next = at.i.wrapping_add(1);
        let sequential = at.tb != at.t2
            && at.t2 << FRAC_BITS <= rel
            && (rel < at.tb << FRAC_BITS || next.wrapping_add(1) == last)
            && next < last;
        let (i, t) = if sequential {
            let tc = self.time(next.wrapping_add(2).min(last));
            let row = self.key_row(next.wrapping_add(2).min(last));
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
