//! Weighted PCA of one channel group in one segment, and its integer form:
//! an `i8` basis (SPEC.md §5.3) and, per frame, the least-squares
//! coefficients against that quantised basis.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// A group's model in one segment, before key frames.
pub struct GroupFit {
    /// Components kept.
    pub k: usize,
    /// `i8` basis, `n × k` row-major.
    pub basis: Vec<i8>,
    /// Per frame, the `k` coefficients (`len × k`, row-major), in the units
    /// the decoder multiplies by `basis / 128`.
    pub coef: Vec<f64>,
    /// `Bᵀ W² B / 128²`: the weighted error of a coefficient error `δ` is
    /// `sqrt(δᵀ G δ)`.
    pub gram: Vec<f64>,
}

/// Fits `x` (`len × n`, row-major, already minus the quantised mean) with
/// channel weights `w`: the fewest components (at most `max_k`) whose
/// per-frame weighted residual stays within `tol`.
pub fn fit(x: &[f64], n: usize, w: &[f64], tol: f64, max_k: usize) -> GroupFit {
    let len = x.len() / n;
    let y = DMatrix::from_fn(len, n, |f, c| x[f * n + c] * w[c]);
    let k = if n == 1 {
        // A single channel is its own component.
        usize::from(y.iter().any(|v| v.abs() > tol * 1e-3))
    } else {
        0
    };
    let (k, dirs) = if n == 1 {
        (k, DMatrix::from_element(1, 1, 1.0))
    } else {
        let cov = y.transpose() * &y;
        let eig = SymmetricEigen::new(cov);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let dirs = DMatrix::from_fn(n, n, |r, c| eig.eigenvectors[(r, order[c])]);
        // Residual² per frame as components are added.
        let mut resid: Vec<f64> = (0..len).map(|f| y.row(f).norm_squared()).collect();
        let mut k = 0;
        let limit = max_k.min(n);
        while k < limit && resid.iter().any(|&r| r > tol * tol) {
            let u = dirs.column(k);
            for (f, r) in resid.iter_mut().enumerate() {
                let p = y.row(f).dot(&u.transpose());
                *r -= p * p;
            }
            k += 1;
        }
        (k, dirs)
    };
    if k == 0 {
        return GroupFit {
            k: 0,
            basis: Vec::new(),
            coef: Vec::new(),
            gram: Vec::new(),
        };
    }
    // Unweighted directions, each scaled so its largest entry is ±127.
    let mut basis = vec![0i8; n * k];
    for j in 0..k {
        let col: Vec<f64> = (0..n).map(|c| dirs[(c, j)] / w[c]).collect();
        let peak = col.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        for c in 0..n {
            basis[c * k + j] = (col[c] / peak * 127.0).round() as i8;
        }
    }
    // Least squares against the integer basis: minimise ‖W(x − B a/128)‖.
    let bw = DMatrix::from_fn(n, k, |c, j| f64::from(basis[c * k + j]) / 128.0 * w[c]);
    let gram = bw.transpose() * &bw;
    let chol = gram.clone().cholesky();
    let mut coef = vec![0.0; len * k];
    for f in 0..len {
        let yf = DVector::from_fn(n, |c, _| y[(f, c)]);
        let rhs = bw.transpose() * yf;
        let a = match &chol {
            Some(ch) => ch.solve(&rhs),
            None => rhs,
        };
        coef[f * k..(f + 1) * k].copy_from_slice(a.as_slice());
    }
    GroupFit {
        k,
        basis,
        coef,
        gram: gram.as_slice().to_vec(),
    }
}

/// `sqrt(δᵀ G δ)` for a `k × k` Gram matrix (column-major or row-major:
/// it is symmetric).
pub fn weighted_norm(gram: &[f64], delta: &[f64]) -> f64 {
    let k = delta.len();
    let mut s = 0.0;
    for a in 0..k {
        for b in 0..k {
            s += delta[a] * gram[a * k + b] * delta[b];
        }
    }
    s.max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rank_two_data_needs_two_components() {
        let n = 5;
        let len = 50;
        let x: Vec<f64> = (0..len)
            .flat_map(|f| {
                let (s, c) = ((f as f64 * 0.2).sin(), (f as f64 * 0.13).cos());
                (0..n).map(move |ch| s * (ch as f64 + 1.0) * 1000.0 + c * (3.0 - ch as f64) * 800.0)
            })
            .collect();
        let w = vec![0.01; n];
        let g = fit(&x, n, &w, 0.5, 16);
        assert_eq!(g.k, 2);
        // Reconstruction through the integer basis stays close.
        for f in 0..len {
            for c in 0..n {
                let v: f64 = (0..2)
                    .map(|j| f64::from(g.basis[c * 2 + j]) / 128.0 * g.coef[f * 2 + j])
                    .sum();
                assert!((v - x[f * n + c]).abs() * w[c] < 0.5);
            }
        }
    }
}
