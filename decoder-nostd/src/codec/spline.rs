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
    let [t0, t1, t2, t3] = t;
    let span = t2 - t1;
    let from = t1 << FRAC_BITS;
    let pos = (pos.min(u64::from(t2) << FRAC_BITS) as u32).max(from);
    let u = (pos - from) / span;
    let u2 = ((u64::from(u) * u64::from(u)) >> FRAC_BITS) as i64;
    let u3 = (u2 * i64::from(u)) >> FRAC_BITS;
    let u = i64::from(u);
    let h00 = 2 * u3 - 3 * u2 + ONE;
    let h10 = u3 - 2 * u2 + u;
    let h01 = 3 * u2 - 2 * u3;
    let h11 = u3 - u2;
    let ra = i64::from((span << FRAC_BITS) / (t2 - t0));
    let rb = i64::from((span << FRAC_BITS) / (t3 - t1));
    let x = (h10 * ra) >> FRAC_BITS;
    let y = (h11 * rb) >> FRAC_BITS;
    [-x, h00 - y, h01 + x, y].map(|w| w as i32)
}

fn weights_long(t: [u32; 4], pos: u64) -> [i32; 4] {
    let [t0, t1, t2, t3] = t.map(i64::from);
    if !(t0 <= t1 && t1 < t2 && t2 <= t3) {
        return [0, 1 << FRAC_BITS, 0, 0];
    }
    let span = t2 - t1;
    let from = t1 << FRAC_BITS;
    let pos = (pos.min(i64::MAX as u64) as i64).clamp(from, t2 << FRAC_BITS);
    // u in [0, 1] as 16.16.
    let u = (pos - from) / span;
    let u2 = (u * u) >> FRAC_BITS;
    let u3 = (u2 * u) >> FRAC_BITS;
    let h00 = 2 * u3 - 3 * u2 + ONE;
    let h10 = u3 - 2 * u2 + u;
    let h01 = 3 * u2 - 2 * u3;
    let h11 = u3 - u2;
    // Tangents scaled to the interval: (P[i+1] - P[i-1]) · span / (t2 - t0).
    let ra = (span << FRAC_BITS) / (t2 - t0);
    let rb = (span << FRAC_BITS) / (t3 - t1);
    let x = (h10 * ra) >> FRAC_BITS;
    let y = (h11 * rb) >> FRAC_BITS;
    [-x, h00 - y, h01 + x, y].map(|w| w as i32)
}

/// `Σ w·p` rounded back from 16.16, with 64-bit intermediates.
#[inline]
pub fn apply(w: [i32; 4], p: [i32; 4]) -> i32 {
    let mut acc: i64 = 1 << (FRAC_BITS - 1);
    for (w, p) in w.iter().zip(p) {
        acc += i64::from(*w) * i64::from(p);
    }
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
    fn degenerate_times_do_not_panic() {
        assert_eq!(weights([5, 5, 5, 5], 5 << 16), [0, 1 << 16, 0, 0]);
        assert_eq!(weights([9, 3, 7, 1], u64::MAX), [0, 1 << 16, 0, 0]);
        let w = weights([0, 0, u32::MAX, u32::MAX], u64::MAX);
        assert_eq!(w.iter().map(|&w| i64::from(w)).sum::<i64>(), 1 << 16);
    }
}
