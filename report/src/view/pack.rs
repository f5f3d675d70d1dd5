//! How `mocap view` packs joint positions and errors into its page.
//!
//! Positions (millimetres, by forward kinematics) are quantised to one
//! quantum `q`, the smallest of [`QUANTA_MM`] (0.1, 1, 10, 100 mm) for
//! which every number below fits an `i16`:
//! - `first`: frame 0, `joints × 3` integers (`round(p / q)`), in JSON;
//! - `deltas`: frames 1.., each integer minus the same integer one frame
//!   before, `(frames − 1) × joints × 3` little-endian `i16`, base64;
//! - `residuals` (with a decoded clip): the decoded integer minus the
//!   original integer, `frames × joints × 3` little-endian `i16`, base64.
//!
//! Differences are taken between already rounded integers, so the page
//! rebuilds every position exactly to the quantum (no drift). Per-joint
//! errors are `u16` little-endian of the smallest error quantum of
//! [`ERROR_QUANTA_MM`] that holds the largest one, base64. The 10 s, 120 Hz
//! CMU clip 05_04 (38 joints with End Sites) with its decoded version makes
//! a page of 874 643 bytes (`tests/tests/view_browser.rs` checks < 2 MB).

use base64::Engine as _;

/// Position quanta tried in order, millimetres.
pub const QUANTA_MM: [f64; 4] = [0.1, 1.0, 10.0, 100.0];
/// Error quanta tried in order, millimetres.
pub const ERROR_QUANTA_MM: [f64; 4] = [0.01, 0.1, 1.0, 10.0];

/// Positions of one motion (and optionally its decoded version), packed.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedPositions {
    /// Millimetres per integer step.
    pub quantum_mm: f64,
    /// Frame 0, `joints × 3` integers.
    pub first: Vec<i64>,
    /// base64 of the frame-to-frame `i16` differences.
    pub deltas: String,
    /// base64 of the decoded-minus-original `i16` differences.
    pub residuals: Option<String>,
}

fn quantise(p: &[[f64; 3]], q: f64) -> Vec<i64> {
    p.iter()
        .flat_map(|v| v.map(|x| (x / q).round() as i64))
        .collect()
}

fn i16_base64(values: impl Iterator<Item = i64>) -> Option<String> {
    let mut bytes = Vec::new();
    for v in values {
        bytes.extend_from_slice(&i16::try_from(v).ok()?.to_le_bytes());
    }
    Some(base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// Packs `original` (`frames × joints` positions, mm) and `decoded` (the
/// same shape) with the smallest quantum that fits; `None` when even
/// 100 mm does not (a joint moving more than 3.2 km in one frame).
pub fn pack_positions(
    original: &[[f64; 3]],
    decoded: Option<&[[f64; 3]]>,
    joints: usize,
) -> Option<PackedPositions> {
    let stride = joints * 3;
    QUANTA_MM.iter().find_map(|&q| {
        let a = quantise(original, q);
        let deltas = i16_base64(
            a.iter()
                .skip(stride)
                .zip(&a)
                .map(|(now, before)| now - before),
        )?;
        let residuals = match decoded {
            Some(d) => Some(i16_base64(
                quantise(d, q).iter().zip(&a).map(|(b, a)| b - a),
            )?),
            None => None,
        };
        Some(PackedPositions {
            quantum_mm: q,
            first: a[..stride.min(a.len())].to_vec(),
            deltas,
            residuals,
        })
    })
}

/// Packs non-negative errors (mm) as `u16` of the smallest quantum of
/// [`ERROR_QUANTA_MM`] that holds the largest (the last one saturates):
/// `(quantum, base64)`.
pub fn pack_errors(errors: &[f64]) -> (f64, String) {
    let max = errors.iter().copied().fold(0.0, f64::max);
    let q = ERROR_QUANTA_MM
        .iter()
        .copied()
        .find(|q| (max / q).round() <= f64::from(u16::MAX))
        .unwrap_or(ERROR_QUANTA_MM[ERROR_QUANTA_MM.len() - 1]);
    let mut bytes = Vec::with_capacity(errors.len() * 2);
    for e in errors {
        let v = (e / q).round().clamp(0.0, f64::from(u16::MAX)) as u16;
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    (q, base64::engine::general_purpose::STANDARD.encode(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unpack_i16(s: &str) -> Vec<i64> {
        let b = base64::engine::general_purpose::STANDARD.decode(s).unwrap();
        b.chunks_exact(2)
            .map(|c| i64::from(i16::from_le_bytes([c[0], c[1]])))
            .collect()
    }

    #[test]
    fn positions_rebuild_to_the_quantum() {
        // Two joints, three frames; the second joint far from the origin.
        let a = [
            [0.0, 900.04, 0.0],
            [2500.0, -10.0, 4000.0],
            [1.26, 903.0, -0.05],
            [2510.0, -9.0, 4001.0],
            [3.0, 905.0, 0.0],
            [2520.0, -8.0, 4002.0],
        ];
        let d: Vec<[f64; 3]> = a.iter().map(|p| [p[0] + 0.5, p[1], p[2] - 2.0]).collect();
        let p = pack_positions(&a, Some(&d), 2).unwrap();
        assert_eq!(p.quantum_mm, 0.1);
        assert_eq!(p.first, vec![0, 9000, 0, 25000, -100, 40000]);
        let deltas = unpack_i16(&p.deltas);
        let resid = unpack_i16(p.residuals.as_ref().unwrap());
        assert_eq!(deltas.len(), 12);
        assert_eq!(resid.len(), 18);
        let mut acc = p.first.clone();
        for f in 0..3 {
            if f > 0 {
                for (k, v) in acc.iter_mut().enumerate() {
                    *v += deltas[(f - 1) * 6 + k];
                }
            }
            for k in 0..6 {
                let orig = acc[k] as f64 * 0.1;
                assert!((orig - a[f * 2 + k / 3][k % 3]).abs() <= 0.05 + 1e-9);
                let dec = (acc[k] + resid[f * 6 + k]) as f64 * 0.1;
                assert!((dec - d[f * 2 + k / 3][k % 3]).abs() <= 0.05 + 1e-9);
            }
        }
    }

    #[test]
    fn a_big_step_takes_a_coarser_quantum() {
        // 5 m in one frame is 50 000 steps of 0.1 mm (more than an i16
        // holds) and 5 000 of 1 mm.
        let a = [[0.0; 3], [5000.0, 0.0, 0.0]];
        assert_eq!(pack_positions(&a, None, 1).unwrap().quantum_mm, 1.0);
        let far = [[0.0; 3], [5e6, 0.0, 0.0]];
        assert!(pack_positions(&far, None, 1).is_none());
    }

    #[test]
    fn errors_take_the_finest_quantum_that_holds_them() {
        let (q, s) = pack_errors(&[0.0, 1.234, 600.0]);
        assert_eq!(q, 0.01);
        assert_eq!(
            base64::engine::general_purpose::STANDARD.decode(s).unwrap(),
            [0u16, 123, 60000]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect::<Vec<_>>()
        );
        assert_eq!(pack_errors(&[700.0]).0, 0.1);
    }
}
