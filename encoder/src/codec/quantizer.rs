//! Scalar codebooks ("models" in Chattopadhyay et al.): 2^b representative
//! values stored as `base + (entry << shift)` with `i16` entries
//! (SPEC.md §4.2), built so every sample lies within a tolerance of its
//! nearest code value.

/// A codebook in the bitstream's representation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Codebook {
    /// Index width in bits; the table has `2^bits` slots.
    pub bits: u8,
    /// Left shift applied to entries.
    pub shift: u8,
    /// Added to every shifted entry.
    pub base: i32,
    /// Used entries, ascending (`len() <= 2^bits`); unused slots are
    /// padding the encoder never indexes.
    pub entries: Vec<i16>,
}

impl Codebook {
    /// The value code `i` decodes to (SPEC.md §4.3), as the decoder
    /// computes it.
    pub fn value(&self, i: usize) -> i64 {
        i64::from(
            self.base
                .wrapping_add(i32::from(self.entries[i]) << self.shift),
        )
    }

    /// The index of the code value nearest to `x`.
    pub fn nearest(&self, x: i64) -> usize {
        let n = self.entries.len();
        // Entries ascend, so binary search on decoded values.
        let (mut lo, mut hi) = (0usize, n);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.value(mid) < x {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        if lo == 0 {
            0
        } else if lo == n {
            n - 1
        } else if x - self.value(lo - 1) <= self.value(lo) - x {
            lo - 1
        } else {
            lo
        }
    }
}

/// Smallest shift so that every value of `[lo, hi]` relative to `base`
/// fits an `i16` entry.
fn shift_for(lo: i64, hi: i64, base: i64) -> u8 {
    let reach = (hi - base).max(base - lo).max(0);
    let mut shift = 0u8;
    while (reach >> shift) > i64::from(i16::MAX) - 1 {
        shift += 1;
    }
    shift
}

/// Bits needed to index `n` codes.
pub fn bits_for(n: usize) -> u8 {
    let mut b = 0u8;
    while (1usize << b) < n {
        b += 1;
    }
    b
}

/// Greedy interval covering: the fewest centres so that every point is
/// within `tol` of one (optimal in 1-D). `points` must be sorted.
fn cover(points: &[i64], tol: i64) -> Vec<i64> {
    let mut centres = Vec::new();
    let mut covered_to = i64::MIN;
    let hi = points.last().copied().unwrap_or(0);
    for &p in points {
        if p > covered_to {
            // Never past the last point: keeps centres inside the data range.
            let c = p.saturating_add(tol).min(hi);
            centres.push(c);
            covered_to = c.saturating_add(tol);
        }
    }
    centres
}

/// One-dimensional k-means (Lloyd) on sorted points from initial centres.
fn lloyd(points: &[i64], mut centres: Vec<i64>, rounds: usize) -> Vec<i64> {
    for _ in 0..rounds {
        let mut sum = vec![0i128; centres.len()];
        let mut count = vec![0u64; centres.len()];
        let mut k = 0;
        for &p in points {
            while k + 1 < centres.len() && (centres[k + 1] - p).abs() <= (centres[k] - p).abs() {
                k += 1;
            }
            sum[k] += i128::from(p);
            count[k] += 1;
        }
        let mut changed = false;
        for (i, c) in centres.iter_mut().enumerate() {
            if count[i] > 0 {
                let n = count[i] as i128;
                let mean = ((sum[i] + n / 2).div_euclid(n)) as i64;
                changed |= mean != *c;
                *c = mean;
            }
        }
        centres.sort_unstable();
        if !changed {
            break;
        }
    }
    centres
}

fn build(centres: &[i64], lo: i64, hi: i64, bits: u8) -> Codebook {
    let base = lo + (hi - lo) / 2;
    let shift = shift_for(
        lo.min(centres[0]),
        hi.max(*centres.last().unwrap_or(&hi)),
        base,
    );
    let mut entries: Vec<i16> = centres
        .iter()
        .map(|&c| {
            let r = c - base;
            let e = (r + ((1i64 << shift) >> 1)) >> shift;
            e.clamp(i64::from(i16::MIN), i64::from(i16::MAX)) as i16
        })
        .collect();
    entries.sort_unstable();
    entries.dedup();
    Codebook {
        bits,
        shift,
        base: base.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32,
        entries,
    }
}

/// Worst distance from a point to its nearest code value.
pub fn max_error(cb: &Codebook, points: &[i64]) -> i64 {
    points
        .iter()
        .map(|&p| (cb.value(cb.nearest(p)) - p).abs())
        .max()
        .unwrap_or(0)
}

/// The smallest codebook whose code values lie within `tol` of every point
/// (`tol >= 0`), with spare codes spent by Lloyd iterations on lowering the
/// mean error. `None` if more than `2^max_bits` codes would be needed.
pub fn fit(points: &[i64], tol: i64, max_bits: u8) -> Option<Codebook> {
    let mut sorted = points.to_vec();
    sorted.sort_unstable();
    let (lo, hi) = (*sorted.first()?, *sorted.last()?);
    // Entry rounding loses up to half a step: cover with what remains.
    let mut shift = shift_for(lo, hi, lo + (hi - lo) / 2);
    loop {
        let slack = (1i64 << shift) / 2;
        let inner = tol - slack;
        if inner < 0 {
            return None;
        }
        let centres = cover(&sorted, inner);
        let bits = bits_for(centres.len());
        if bits > max_bits {
            return None;
        }
        let cb = build(&centres, lo, hi, bits);
        if cb.shift > shift {
            // Centres are inside [lo, hi], so this cannot repeat forever;
            // the shift only grows.
            shift = cb.shift;
            continue;
        }
        if max_error(&cb, &sorted) > tol {
            return None;
        }
        // Spend spare slots: Lloyd from quantile seeds, kept if it still
        // meets the bound.
        let k = 1usize << bits;
        if bits > 0 && k > centres.len() {
            let mut seeds: Vec<i64> = (0..k)
                .map(|i| sorted[(i * 2 + 1) * sorted.len() / (2 * k)])
                .collect();
            seeds.dedup();
            let refined = build(&lloyd(&sorted, seeds, 30), lo, hi, bits);
            if refined.shift <= cb.shift && max_error(&refined, &sorted) <= tol {
                return Some(refined);
            }
        }
        return Some(cb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cover_is_within_tolerance_and_minimal() {
        let pts: Vec<i64> = (0..100).map(|i| i * 10).collect();
        let cb = fit(&pts, 50, 12).unwrap();
        assert!(max_error(&cb, &pts) <= 50);
        // 0..990 with radius 50 needs 10 centres -> 4 bits.
        assert_eq!(cb.bits, 4);
    }

    #[test]
    fn constant_channel_needs_no_bits() {
        let cb = fit(&[7, 7, 7], 0, 12).unwrap();
        assert_eq!(cb.bits, 0);
        assert_eq!(cb.value(0), 7);
    }

    #[test]
    fn wide_ranges_use_a_shift() {
        let pts = vec![-2_000_000_000i64, 0, 2_000_000_000];
        let cb = fit(&pts, 100_000, 12).unwrap();
        assert!(cb.shift > 0);
        assert!(max_error(&cb, &pts) <= 100_000);
        assert!(fit(&pts, 1, 12).is_none());
    }
}
