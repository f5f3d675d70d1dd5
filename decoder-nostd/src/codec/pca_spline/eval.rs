//! Evaluating a pose from the records themselves (SPEC.md §5.4): key
//! interval search, control points, the channel sums `(mean << ms) +
//! ((64 + Σ b·a) >> 7)` and where they go, constant channels and the
//! blend windows between segments.

use super::*;

/// Where a group's values go: a run of consecutive channels (written as a
/// sub-slice of `out`, without per-channel index reads or bounds checks),
/// or the channels its 1- or 2-byte indices name.
pub(super) enum Dst<'i, 'o> {
    Run(&'o mut [i32]),
    Narrow(&'i [u8], &'o mut [i32]),
    Wide(&'i [u8], &'o mut [i32]),
}

impl<'i, 'o> Dst<'i, 'o> {
    /// The destination of the channels listed in `idx`.
    pub(super) fn of(idx: &'i [u8], wide: bool, out: &'o mut [i32]) -> Option<Self> {
        let width = if wide { 2 } else { 1 };
        // width is 1 or 2.
        #[allow(clippy::arithmetic_side_effects)]
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
    pub(super) fn fill(self, mut value: impl FnMut() -> i32) {
        self.each(|o, _| *o = value());
    }

    /// Writes `values` (one per channel).
    pub(super) fn copy(self, values: &[i32]) {
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
    pub(super) fn each(self, mut f: impl FnMut(&mut i32, usize)) {
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
    pub(super) fn write(
        self,
        k: usize,
        w: [i32; 4],
        controls: &[i32],
        means: &[u8],
        basis: &[u8],
        ms: u32,
    ) {
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
    pub(super) fn write_k<const K: usize>(self, a: [i32; K], means: &[u8], basis: &[u8], ms: u32) {
        let rows = means.chunks_exact(2).zip(basis.chunks_exact(K));
        let value = |m: &[u8], row: &[u8]| row_value(&a, ms, m, row);
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

/// One channel of a `K`-component group from its mean bytes `m` and basis
/// row `row` (0 if the row is short). Always inlined: LLVM left it out of
/// line for `K ≥ 4`, a call per channel.
#[inline(always)]
fn row_value<const K: usize>(a: &[i32; K], ms: u32, m: &[u8], row: &[u8]) -> i32 {
    match <&[u8; K]>::try_from(row) {
        Ok(row) => channel(mean_of(m), ms, row.iter().zip(a.iter())),
        Err(_) => 0,
    }
}

/// The `K` component values at spline weights `w` from their control
/// points (four per component, in order).
#[inline(always)]
pub(super) fn coefficients<const K: usize>(w: [i32; 4], controls: &[i32]) -> [i32; K] {
    let mut a = [0i32; K];
    if let Some(controls) = controls.get(..K.wrapping_mul(4)) {
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
pub(super) fn channel<'x>(
    mean: i32,
    ms: u32,
    terms: impl Iterator<Item = (&'x u8, &'x i32)>,
) -> i32 {
    let mut acc: i32 = 1 << (BASIS_SHIFT - 1);
    for (&b, &a) in terms {
        acc = acc.wrapping_add(i32::from(b as i8).wrapping_mul(a));
    }
    mean.wrapping_shl(ms).wrapping_add(acc >> BASIS_SHIFT)
}

/// One channel's value from a group (row `row` of the basis).
#[inline(always)]
pub(super) fn channel_value(head: &GroupHead<'_>, mean: i32, row: &[u8], coef: &[i32]) -> i32 {
    channel(mean, head.mean_shift, row.iter().zip(coef))
}

/// The values of a group's channels in order (`k = 0`: the zigzag means).
pub(super) struct GroupValues<'h, 'a> {
    pub(super) head: &'h GroupHead<'a>,
    pub(super) coef: &'h [i32],
    pub(super) means: Reader<'a>,
    pub(super) row: usize,
}

impl<'h, 'a> GroupValues<'h, 'a> {
    pub(super) fn new(head: &'h GroupHead<'a>, coef: &'h [i32]) -> Self {
        GroupValues {
            head,
            coef,
            means: Reader::new(head.mean),
            row: 0,
        }
    }

    pub(super) fn next(&mut self) -> Option<i32> {
        let h = self.head;
        if h.k == 0 {
            return Some(self.means.zigzag_i32()?.wrapping_shl(h.mean_shift));
        }
        let mean = mean_of(self.means.take(2)?);
        let at = self.row.wrapping_mul(h.k);
        let row = h.basis.get(at..at.wrapping_add(h.k))?;
        self.row = self.row.wrapping_add(1);
        Some(channel_value(h, mean, row, self.coef))
    }
}

/// Reads up to 30 bits (two reads of at most 15).
pub(super) fn read_wide(bits: &mut BitReader<'_>, n: u32) -> u32 {
    let lo_n = n.min(15);
    let lo = bits.read(lo_n);
    let hi = bits.read(n.wrapping_sub(lo_n));
    lo | (hi << lo_n)
}

impl<'a> PcaSplineCodec<'a> {
    /// Writes the constant channels, from `cached` (their values in order)
    /// when the cache holds them, else from the section.
    pub(super) fn write_consts(&self, cached: Option<&[i32]>, out: &mut [i32]) {
        let mut r = Reader::new(self.consts);
        let n = self.const_count as usize;
        let indices = Indices::new(
            r.take(n.wrapping_mul(self.width())).unwrap_or(&[]),
            self.wide,
        );
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
    pub(super) fn const_values(&self) -> impl Iterator<Item = i32> + 'a {
        let mut r = Reader::new(self.consts);
        r.take((self.const_count as usize).wrapping_mul(self.width()));
        (0..self.const_count).map(move |_| r.zigzag_i32().unwrap_or(0))
    }

    /// Blends the other segment of a window into `out`, which holds the
    /// values of `cur` (§5.4 step 4): `a + (b − a)·w` with `a` the earlier
    /// segment's value. `cur_first` says whether `cur` is `earlier`.
    pub(super) fn blend(
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
        #[allow(clippy::arithmetic_side_effects)] // steps ≥ 1
        let w = (pos.saturating_sub(from) / steps).min(1 << FRAC_BITS) as i64;
        let other = if cur_first { later } else { earlier };
        let rel = u64::from(relative(other, pos));
        let mut g = Reader::new(self.groups);
        let mut body = Reader::new(other.body);
        let mut coef = [0i32; K_MAX];
        for _ in 0..self.group_count {
            let n = g.varint_u32().unwrap_or(0) as usize;
            let idx = g.take(n.wrapping_mul(self.width())).unwrap_or(&[]);
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
                *o = a.wrapping_add((d.wrapping_mul(w) >> FRAC_BITS) as i32);
            }
        }
    }
}

impl GroupHead<'_> {
    /// The key interval holding `rel` (16.16 frames from the segment
    /// start): the largest `i <= m - 2` with `t[i] <= rel`, and the four key
    /// times around it with the ends repeated (§5.4).
    pub(super) fn interval(&self, rel: u64) -> (u32, [u32; 4]) {
        let time = |i: u32| self.time(i);
        let last = self.keys.saturating_sub(1);
        let (mut lo, mut hi) = (0u32, last);
        while hi.wrapping_sub(lo) > 1 {
            let mid = lo.wrapping_add(hi.wrapping_sub(lo) / 2);
            if u64::from(time(mid)) << FRAC_BITS <= rel {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let rows = [
            lo.saturating_sub(1),
            lo,
            lo.wrapping_add(1),
            lo.wrapping_add(2).min(last),
        ];
        (lo, rows.map(time))
    }

    /// Calls `each` with the four control values of every component at the
    /// keys `i − 1 … i + 2` (ends repeated). The four key rows are read in
    /// lockstep, one component at a time.
    pub(super) fn controls(&self, i: u32, mut each: impl FnMut([i32; 4])) {
        let last = self.keys.saturating_sub(1);
        let rows = [
            i.saturating_sub(1),
            i,
            i.wrapping_add(1),
            i.wrapping_add(2).min(last),
        ];
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
    pub(super) fn time(&self, i: u32) -> u32 {
        bits_at64(
            self.bits,
            u64::from(i).wrapping_mul(u64::from(self.time_bits)),
            self.time_bits,
        )
    }

    /// The bit position of key row `row`.
    pub(super) fn key_row(&self, row: u32) -> u64 {
        u64::from(self.keys)
            .wrapping_mul(u64::from(self.time_bits))
            .wrapping_add(u64::from(row).wrapping_mul(u64::from(self.row_bits)))
    }

    /// Calls `each` with the control value of every component in the key
    /// row at bit `at`.
    pub(super) fn row_values(&self, at: u64, mut each: impl FnMut(i32)) {
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
    pub(super) fn coefficients(&self, rel: u64, coef: &mut [i32; K_MAX]) {
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
}
