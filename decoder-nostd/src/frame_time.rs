//! A time as a frame and a 16-bit fraction (SPEC.md §6), exactly:
//! `i = ns div P` and `frac = ((ns mod P) << 16) div P` for the frame time
//! `P` ns — without the two 64-bit divisions (a library call on Cortex-M,
//! `__aeabi_uldivmod`) whenever the time is at most 4.29 s past the frame
//! of the previous call, as a player sampled at a servo tick always is.

use core::num::{NonZeroU32, NonZeroU64};

/// Splits times into frames and fractions; remembers the frame of the last
/// split so that the next, later time divides only what lies past it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameTime {
    period: NonZeroU32,
    /// `⌊2^48 / P⌋`: for `rem < P`, `⌊rem · 2^16 / P⌋` is `(rem · inv) >> 32`
    /// or one more (see [`FrameTime::fraction`]).
    inv: u64,
    /// The frame the last split fell in …
    base: u32,
    /// … and its start, `base · P` ns.
    base_ns: u64,
}

impl FrameTime {
    /// Frame time `period` in ns.
    pub(crate) fn new(period: NonZeroU32) -> Self {
        FrameTime {
            period,
            inv: (1u64 << 48) / NonZeroU64::from(period),
            base: 0,
            base_ns: 0,
        }
    }

    /// `(ns div P, ((ns mod P) << 16) div P)`.
    pub(crate) fn split(&mut self, ns: u64) -> (u64, u32) {
        let p = self.period.get();
        let ahead = ns.wrapping_sub(self.base_ns);
        let (whole, rem) = if ns >= self.base_ns && ahead <= u64::from(u32::MAX) {
            // ns = base · P + ahead, ahead < 2^32: a 32-bit division.
            let ahead = ahead as u32;
            let q = ahead / self.period;
            (
                u64::from(self.base).wrapping_add(u64::from(q)),
                ahead.wrapping_sub(q.wrapping_mul(p)),
            )
        } else {
            let q = ns / NonZeroU64::from(self.period);
            // ns mod P < P fits in 32 bits.
            (q, ns.wrapping_sub(q.wrapping_mul(u64::from(p))) as u32)
        };
        if let Ok(base) = u32::try_from(whole) {
            self.base = base;
            self.base_ns = ns.wrapping_sub(u64::from(rem));
        }
        (whole, self.fraction(rem))
    }

    /// `⌊rem · 2^16 / P⌋` for `rem < P`, by the reciprocal and one correction.
    /// With `inv = 2^48 / P − e`, `0 ≤ e < 1`: `rem · inv / 2^32 =
    /// rem · 2^16 / P − rem · e / 2^32`, and `rem · e < 2^32`, so the estimate
    /// `q = ⌊rem · inv / 2^32⌋` is the quotient or one less; the remainder
    /// `rem · 2^16 − q · P` tells which. `rem · inv < 2^48` and `q · P < 2^48`:
    /// no product overflows.
    fn fraction(&self, rem: u32) -> u32 {
        let p = u64::from(self.period.get());
        let q = (u64::from(rem).wrapping_mul(self.inv) >> 32) as u32;
        let left = (u64::from(rem) << 16).wrapping_sub(u64::from(q).wrapping_mul(p));
        if left >= p {
            q.wrapping_add(1)
        } else {
            q
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SPEC.md §6 as written.
    fn spec(ns: u64, p: u32) -> (u64, u32) {
        let p = u64::from(p);
        (ns / p, (((ns % p) << 16) / p) as u32)
    }

    /// xorshift64*: a fixed, reproducible sequence.
    fn rng(s: &mut u64) -> u64 {
        *s ^= *s >> 12;
        *s ^= *s << 25;
        *s ^= *s >> 27;
        s.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    #[test]
    fn every_split_is_the_specs() {
        let mut s = 0x9e37_79b9_7f4a_7c15;
        let periods = [
            1,
            2,
            3,
            7,
            999,
            65_535,
            65_536,
            65_537,
            8_333_333,
            16_666_667,
            33_333_333,
            u32::MAX / 3,
            u32::MAX - 1,
            u32::MAX,
        ];
        for &p in &periods {
            let mut ft = FrameTime::new(NonZeroU32::new(p).unwrap());
            let mut t_us = 0u64;
            for i in 0..20_000u32 {
                let r = rng(&mut s);
                // Forward steps of a servo tick, jumps back, far jumps, saturation.
                t_us = match i % 97 {
                    0 => r % 1_000_000,
                    1 => r,
                    2 => u64::MAX / 1000 + r % 3,
                    _ => t_us.wrapping_add(r % 40_000),
                };
                let ns = t_us.saturating_mul(1000);
                assert_eq!(ft.split(ns), spec(ns, p), "P {p} ns {ns}");
            }
            // The remainders next to every multiple: the estimate's worst cases.
            for rem in [0, 1, p / 2, p.saturating_sub(2), p - 1] {
                for k in [0u64, 1, 5, 1 << 32, 1 << 40] {
                    let ns = k
                        .saturating_mul(u64::from(p))
                        .saturating_add(u64::from(rem));
                    assert_eq!(ft.split(ns), spec(ns, p), "P {p} ns {ns}");
                }
            }
        }
    }

    #[test]
    fn every_fraction_of_small_periods() {
        for p in 1..=600u32 {
            let ft = FrameTime::new(NonZeroU32::new(p).unwrap());
            for rem in 0..p {
                assert_eq!(
                    ft.fraction(rem),
                    ((u64::from(rem) << 16) / u64::from(p)) as u32
                );
            }
        }
    }
}
