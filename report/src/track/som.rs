//! Self-organising map (Kohonen), batch form: deterministic for a seed,
//! and its best-matching-unit search runs in parallel (rayon). Nodes start
//! at seeded random data samples; the Gaussian neighbourhood shrinks
//! geometrically from half the grid to `sigma_end` over the epochs.

use rayon::prelude::*;

/// SOM settings.
#[derive(Clone, Debug)]
pub struct SomConfig {
    /// Grid columns.
    pub width: usize,
    /// Grid rows.
    pub height: usize,
    /// Batch epochs.
    pub epochs: usize,
    /// Seed of the initialisation.
    pub seed: u64,
    /// Final neighbourhood radius, in grid cells.
    pub sigma_end: f64,
}

impl Default for SomConfig {
    fn default() -> Self {
        SomConfig {
            width: 16,
            height: 16,
            epochs: 30,
            seed: 1,
            sigma_end: 0.7,
        }
    }
}

/// A trained map: node `r * width + c` holds `nodes[(r*width+c)*dim..][..dim]`.
#[derive(Clone, Debug)]
pub struct Som {
    /// Grid columns.
    pub width: usize,
    /// Grid rows.
    pub height: usize,
    /// Vector length.
    pub dim: usize,
    /// Node vectors, row-major.
    pub nodes: Vec<f32>,
}

/// SplitMix64: a tiny seeded generator, so results never depend on a
/// crate's algorithm changing.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_f64() * n as f64) as usize % n.max(1)
    }
}

/// Squared Euclidean distance.
#[inline]
pub fn dist2(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Index of the row of `rows` (row length `dim`) nearest to `x`.
pub fn nearest(rows: &[f32], dim: usize, x: &[f32]) -> (usize, f32) {
    let mut best = (0, f32::INFINITY);
    for (i, r) in rows.chunks_exact(dim).enumerate() {
        let d = dist2(r, x);
        if d < best.1 {
            best = (i, d);
        }
    }
    best
}

impl Som {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// True for an empty map.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Node `i`'s vector.
    pub fn node(&self, i: usize) -> &[f32] {
        &self.nodes[i * self.dim..(i + 1) * self.dim]
    }

    /// Best-matching unit of every row of `data`.
    pub fn bmus(&self, data: &[f32]) -> Vec<usize> {
        data.par_chunks_exact(self.dim)
            .map(|x| nearest(&self.nodes, self.dim, x).0)
            .collect()
    }

    /// Mean distance from each row of `data` to its best-matching unit.
    pub fn quantisation_error(&self, data: &[f32]) -> f64 {
        let n = data.len() / self.dim.max(1);
        let sum: f64 = data
            .par_chunks_exact(self.dim)
            .map(|x| f64::from(nearest(&self.nodes, self.dim, x).1.sqrt()))
            .sum();
        sum / n.max(1) as f64
    }

    /// For every node, the index of the nearest row of `data` (the paper's
    /// adjustment of §3.3: key frames become real frames).
    pub fn snap(&self, data: &[f32]) -> Vec<usize> {
        (0..self.len())
            .into_par_iter()
            .map(|i| nearest(data, self.dim, self.node(i)).0)
            .collect()
    }
}

/// Trains a map on the rows of `data` (row length `dim`).
pub fn train(data: &[f32], dim: usize, cfg: &SomConfig) -> Som {
    let n = data.len() / dim.max(1);
    let nodes_n = cfg.width * cfg.height;
    assert!(n > 0 && dim > 0 && nodes_n > 0, "SOM needs data and nodes");
    let mut rng = SplitMix64(cfg.seed);
    let mut nodes = Vec::with_capacity(nodes_n * dim);
    for _ in 0..nodes_n {
        let r = rng.below(n);
        nodes.extend_from_slice(&data[r * dim..(r + 1) * dim]);
    }
    let mut som = Som {
        width: cfg.width,
        height: cfg.height,
        dim,
        nodes,
    };
    let sigma0 = (cfg.width.max(cfg.height) as f64 / 2.0).max(cfg.sigma_end);
    let epochs = cfg.epochs.max(1);
    // Grid coordinates of every node.
    let grid: Vec<(f64, f64)> = (0..nodes_n)
        .map(|i| ((i % cfg.width) as f64, (i / cfg.width) as f64))
        .collect();
    for e in 0..epochs {
        let t = if epochs > 1 {
            e as f64 / (epochs - 1) as f64
        } else {
            1.0
        };
        let sigma = sigma0 * (cfg.sigma_end / sigma0).powf(t);
        let bmus = som.bmus(data);
        // Per-node sums and counts of the samples it wins.
        let mut sums = vec![0.0f64; nodes_n * dim];
        let mut counts = vec![0.0f64; nodes_n];
        for (x, &b) in data.chunks_exact(dim).zip(&bmus) {
            counts[b] += 1.0;
            for (s, &v) in sums[b * dim..(b + 1) * dim].iter_mut().zip(x) {
                *s += f64::from(v);
            }
        }
        let inv = 1.0 / (2.0 * sigma * sigma);
        let updated: Vec<Vec<f32>> = (0..nodes_n)
            .into_par_iter()
            .map(|m| {
                let mut acc = vec![0.0f64; dim];
                let mut den = 0.0;
                for w in 0..nodes_n {
                    if counts[w] == 0.0 {
                        continue;
                    }
                    let (dx, dy) = (grid[m].0 - grid[w].0, grid[m].1 - grid[w].1);
                    let h = (-(dx * dx + dy * dy) * inv).exp();
                    if h < 1e-9 {
                        continue;
                    }
                    den += h * counts[w];
                    for (a, s) in acc.iter_mut().zip(&sums[w * dim..(w + 1) * dim]) {
                        *a += h * s;
                    }
                }
                if den > 0.0 {
                    acc.iter().map(|a| (a / den) as f32).collect()
                } else {
                    som.node(m).to_vec()
                }
            })
            .collect();
        for (m, v) in updated.into_iter().enumerate() {
            som.nodes[m * dim..(m + 1) * dim].copy_from_slice(&v);
        }
    }
    som
}
