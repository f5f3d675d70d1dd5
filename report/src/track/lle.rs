//! Locally Linear Embedding (Roweis & Saul 2000), as Hu et al. use it to
//! lay the key frames out in 2-D: k nearest neighbours (Euclidean), local
//! reconstruction weights from the regularised Gram system, then the
//! bottom eigenvectors of `M = (I − W)ᵀ(I − W)` (the constant one skipped).

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::TrackError;

/// Regularisation of the local Gram matrix, relative to its trace (needed
/// when k exceeds the data's local dimension).
pub const REGULARISATION: f64 = 1e-3;

/// Embeds the `n` points of `points` (rows of length `dim`) into `out_dim`
/// dimensions using `k` neighbours (clamped to `n − 1`). Returns row-major
/// `n × out_dim` coordinates, scaled so each coordinate has unit variance;
/// each axis's sign is fixed so its largest-magnitude entry is positive.
pub fn embed(points: &[f64], dim: usize, k: usize, out_dim: usize) -> Result<Vec<f64>, TrackError> {
    let n = points.len() / dim.max(1);
    if n < out_dim + 2 {
        return Err(TrackError::TooFewKeyFrames {
            needed: out_dim + 2,
            got: n,
        });
    }
    let k = k.clamp(1, n - 1);
    let row = |i: usize| &points[i * dim..(i + 1) * dim];
    let mut w = DMatrix::<f64>::zeros(n, n);
    for i in 0..n {
        // k nearest neighbours of i (ties by index: deterministic).
        let mut d: Vec<(f64, usize)> = (0..n)
            .filter(|&j| j != i)
            .map(|j| {
                let s: f64 = row(i)
                    .iter()
                    .zip(row(j))
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum();
                (s, j)
            })
            .collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let nb: Vec<usize> = d[..k].iter().map(|&(_, j)| j).collect();
        // Local Gram matrix of the neighbours centred on point i.
        let mut c = DMatrix::<f64>::zeros(k, k);
        for a in 0..k {
            for b in a..k {
                let s: f64 = (0..dim)
                    .map(|t| (row(nb[a])[t] - row(i)[t]) * (row(nb[b])[t] - row(i)[t]))
                    .sum();
                c[(a, b)] = s;
                c[(b, a)] = s;
            }
        }
        let trace = c.trace();
        let reg = if trace > 0.0 {
            REGULARISATION * trace
        } else {
            REGULARISATION
        };
        for a in 0..k {
            c[(a, a)] += reg;
        }
        let ones = DVector::<f64>::from_element(k, 1.0);
        let sol = c
            .clone()
            .cholesky()
            .map(|ch| ch.solve(&ones))
            .or_else(|| c.lu().solve(&ones))
            .ok_or(TrackError::SingularGram)?;
        let sum = sol.sum();
        for (a, &j) in nb.iter().enumerate() {
            w[(i, j)] = sol[a] / sum;
        }
    }
    let iw = DMatrix::<f64>::identity(n, n) - w;
    let m = iw.transpose() * &iw;
    let eig = SymmetricEigen::new(m);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let mut out = vec![0.0; n * out_dim];
    let scale = (n as f64).sqrt();
    for (d, &e) in order[1..=out_dim].iter().enumerate() {
        let v = eig.eigenvectors.column(e);
        let big = v
            .iter()
            .copied()
            .fold(0.0f64, |m, x| if x.abs() > m.abs() { x } else { m });
        let sign = if big < 0.0 { -1.0 } else { 1.0 };
        for i in 0..n {
            out[i * out_dim + d] = sign * v[i] * scale;
        }
    }
    Ok(out)
}
