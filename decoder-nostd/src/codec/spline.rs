//! The key-frame spline of the `pca-spline` codec (SPEC.md §5.4): a
//! non-uniform Catmull-Rom (cubic Hermite) curve evaluated in 16.16 fixed
//! point. It is local — a value depends on four control points — so any
//! time can be sampled without history and without solving anything.

use crate::consts::pca::FRAC_BITS;

const ONE: i64 = 1 << FRAC_BITS;

/// Weights of the four control points `P[i-1], P[i], P[i+1], P[i+2]` at
/// position `pos` (frames, 16.16) inside the interval `[t[1], t[2]]`.
///
/// `t` holds the four key times; at the ends of a curve the missing
/// neighbour repeats the end key (`t[0] == t[1]` or `t[3] == t[2]`), which
/// makes that end's tangent one-sided. The weights sum to exactly `2^16`,
/// so a constant curve is reproduced exactly. `pos` outside the interval is
/// clamped into it. Requires `t[0] <= t[1] < t[2] <= t[3]`; anything else
/// yields the weights of the nearest control point.
pub fn weights(t: [u32; 4], pos: u64) -> [i32; 4] {
    let [t0, t1, t2, t3] = t;
    if t0 <= t1 && t1 < t2 && t2 <= t3 && t3 < 1 << 15 {
        return weights_short(t, pos);
    }
    weights_long(t, pos)
}

/// [`weights`] for key times below 2^15 (every valid segment): the same
/// numbers with 32-bit divisions, which Cortex-M3/M4 do in one instruction.
#[inline]
fn weights_short(t: [u32; 4], pos: u64) -> [i32; 4] {
    let [_, t1, t2, _] = t;
    let from = t1 << FRAC_BITS;
    let pos = (pos.min(u64::from(t2) << FRAC_BITS) as u32).max(from);
    let (ra, rb) = ratios(t);
    // t1 < t2: key times strictly increase (validated, §5.3).
    #[allow(clippy::arithmetic_side_effects)]
    let u = pos.wrapping_sub(from) / t2.wrapping_sub(t1);
    weights_at(u, ra, rb)
}

/// The tangent ratios of an interval, `ra = span·2^16 / (t2 − t0)` and
/// `rb = span·2^16 / (t3 − t1)` (each at most 2^16). They depend on the
/// key times only, so a player computes them once per interval. Requires
/// `t0 <= t1 < t2 <= t3 < 2^15`.
#[inline]
pub(crate) fn ratios(t: [u32; 4]) -> (i32, i32) {
    let [t0, t1, t2, t3] = t;
    let span = t2.wrapping_sub(t1) << FRAC_BITS;
    let ra = span.checked_div(t2.wrapping_sub(t0)).unwrap_or(0);
    let rb = span.checked_div(t3.wrapping_sub(t1)).unwrap_or(0);
    (ra as i32, rb as i32)
}

/// The four weights at `u` (16.16, `0 <= u <= 2^16`) into the interval,
/// given its [`ratios`] (each at most 2^16). Within those ranges every
/// intermediate of §5.4 fits in 32 bits (|h10|, |h11| < 2^14), so this is
/// the `i64` formula computed in `i32`; the squares use 64-bit products.
#[inline(always)]
pub(crate) fn weights_at(u: u32, ra: i32, rb: i32) -> [i32; 4] {
    let u2 = (u64::from(u).wrapping_mul(u64::from(u)) >> FRAC_BITS) as u32;
    let u3 = (u64::from(u2).wrapping_mul(u64::from(u)) >> FRAC_BITS) as i32;
    let (u, u2) = (u as i32, u2 as i32);
    let one = ONE as i32;
    // Wrapping only matters outside the documented ranges (never for a
    // validated clip); it keeps any input panic-free.
    let h00 = u3
        .wrapping_mul(2)
        .wrapping_sub(u2.wrapping_mul(3))
        .wrapping_add(one);
    let h10 = u3.wrapping_sub(u2.wrapping_mul(2)).wrapping_add(u);
    let h01 = u2.wrapping_mul(3).wrapping_sub(u3.wrapping_mul(2));
    let h11 = u3.wrapping_sub(u2);
    let x = h10.wrapping_mul(ra) >> FRAC_BITS;
    let y = h11.wrapping_mul(rb) >> FRAC_BITS;
    [
        x.wrapping_neg(),
        h00.wrapping_sub(y),
        h01.wrapping_add(x),
        y,
    ]
}

fn weights_long(t: [u32; 4], pos: u64) -> [i32; 4] {
    let [t0, t1, t2, t3] = t.map(i64::from);
    if !(t0 <= t1 && t1 < t2 && t2 <= t3) {
        return [0, 1 << FRAC_BITS, 0, 0];
    }
    let span = t2.wrapping_sub(t1);
    let from = t1 << FRAC_BITS;
    let pos = (pos.min(i64::MAX as u64) as i64).clamp(from, t2 << FRAC_BITS);
    // u in [0, 1] as 16.16.
    // span > 0, t2 − t0 > 0, t3 − t1 > 0: checked above.
    #[allow(clippy::arithmetic_side_effects)]
    let u = pos.wrapping_sub(from) / span;
    let u2 = u.wrapping_mul(u) >> FRAC_BITS;
    let u3 = u2.wrapping_mul(u) >> FRAC_BITS;
    let h00 = u3
        .wrapping_mul(2)
        .wrapping_sub(u2.wrapping_mul(3))
        .wrapping_add(ONE);
    let h10 = u3.wrapping_sub(u2.wrapping_mul(2)).wrapping_add(u);
    let h01 = u2.wrapping_mul(3).wrapping_sub(u3.wrapping_mul(2));
    let h11 = u3.wrapping_sub(u2);
    // Tangents scaled to the interval: (P[i+1] - P[i-1]) · span / (t2 - t0).
    #[allow(clippy::arithmetic_side_effects)]
    let ra = (span << FRAC_BITS) / t2.wrapping_sub(t0);
    #[allow(clippy::arithmetic_side_effects)]
    let rb = (span << FRAC_BITS) / t3.wrapping_sub(t1);
    let x = h10.wrapping_mul(ra) >> FRAC_BITS;
    let y = h11.wrapping_mul(rb) >> FRAC_BITS;
    [
        x.wrapping_neg(),
        h00.wrapping_sub(y),
        h01.wrapping_add(x),
        y,
    ]
    .map(|w| w as i32)
}

/// `Σ w·p` rounded back from 16.16, with 64-bit intermediates.
#[inline(always)]
pub fn apply(w: [i32; 4], p: [i32; 4]) -> i32 {
    let [w0, w1, w2, w3] = w.map(i64::from);
    let [p0, p1, p2, p3] = p.map(i64::from);
    let acc = (1i64 << (FRAC_BITS - 1))
        .wrapping_add(w0.wrapping_mul(p0))
        .wrapping_add(w1.wrapping_mul(p1))
        .wrapping_add(w2.wrapping_mul(p2))
        .wrapping_add(w3.wrapping_mul(p3));
    (acc >> FRAC_BITS) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_interpolate_keys() {
        let t = [0, 10, 25, 40];
        for pos in (10u64 << 16..=25 << 16).step_by(7919) {
            let w = weights(t, pos);
            assert_eq!(w.iter().map(|&w| i64::from(w)).sum::<i64>(), 1 << 16);
        }
        assert_eq!(weights(t, 10 << 16), [0, 1 << 16, 0, 0]);
        assert_eq!(weights(t, 25 << 16), [0, 0, 1 << 16, 0]);
        // Clamped outside the interval.
        assert_eq!(weights(t, 0), [0, 1 << 16, 0, 0]);
    }

    #[test]
    fn linear_data_stays_linear() {
        // Control points on a line: the curve is that line (up to rounding).
        let t = [0, 4, 8, 12];
        let p = [0, 4000, 8000, 12000];
        for f in 4..=8u64 {
            for frac in [0u64, 1 << 14, 1 << 15, 3 << 14] {
                let pos = (f << 16) + if f == 8 { 0 } else { frac };
                let v = apply(weights(t, pos), p);
                let want = (pos * 1000 / 65536) as i32;
                assert!((v - want).abs() <= 1, "{pos}: {v} vs {want}");
            }
        }
    }

    #[test]
    fn short_and_long_forms_agree() {
        let mut x = 12345u64;
        let mut next = |n: u64| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 33) % n
        };
        for _ in 0..20_000 {
            let t1 = next(30_000) as u32;
            let t0 = t1 - next(u64::from(t1) + 1) as u32;
            let t2 = t1 + 1 + next(2000) as u32;
            let t3 = t2 + next(2000) as u32;
            let t = [t0, t1, t2, t3];
            let pos = (u64::from(t1) << 16) + next((u64::from(t2 - t1) << 16) + 1);
            assert_eq!(weights_short(t, pos), weights_long(t, pos), "{t:?} {pos}");
        }
    }

    #[test]
    fn weights_at_is_the_i64_formula() {
        // §5.4 in i64, for every u and extreme ratios.
        let reference = |u: i64, ra: i64, rb: i64| {
            let u2 = (u * u) >> 16;
            let u3 = (u2 * u) >> 16;
            let (h00, h10) = (2 * u3 - 3 * u2 + ONE, u3 - 2 * u2 + u);
            let (h01, h11) = (3 * u2 - 2 * u3, u3 - u2);
            let (x, y) = ((h10 * ra) >> 16, (h11 * rb) >> 16);
            [-x, h00 - y, h01 + x, y].map(|w| w as i32)
        };
        for (ra, rb) in [
            (65536, 65536),
            (1, 1),
            (0, 65536),
            (32768, 21845),
            (65535, 3),
        ] {
            for u in 0..=65536u32 {
                let want = reference(i64::from(u), i64::from(ra), i64::from(rb));
                assert_eq!(weights_at(u, ra, rb), want, "u {u} ra {ra} rb {rb}");
            }
        }
    }

    #[test]
    fn degenerate_times_do_not_panic() {
        assert_eq!(weights([5, 5, 5, 5], 5 << 16), [0, 1 << 16, 0, 0]);
        assert_eq!(weights([9, 3, 7, 1], u64::MAX), [0, 1 << 16, 0, 0]);
        let w = weights([0, 0, u32::MAX, u32::MAX], u64::MAX);
        assert_eq!(w.iter().map(|&w| i64::from(w)).sum::<i64>(), 1 << 16);
    }
}
