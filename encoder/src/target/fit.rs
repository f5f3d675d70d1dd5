//! `mocap target fit`: the cost model's coefficients from QEMU instruction
//! counts (`scripts/cost.sh`), and the report of predicted against measured.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, DVector};

use super::chips::Core;
use super::cost::{instructions, CodecKind, Features};

/// One measured clip on one board (a row of `measured.tsv`).
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    pub board: String,
    pub core: Core,
    /// Calibration row (`fit`) or held out (`check`).
    pub fit: bool,
    pub clip: PathBuf,
    /// `N` of the firmware's `Player<N>`.
    pub player_words: usize,
    pub features: Features,
    pub decode_per_pose: f64,
    pub playback_stack_bytes: u32,
}

/// Why the measurements cannot be read or fitted.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("{file}:{line}: {what}")]
    Row {
        file: PathBuf,
        line: usize,
        what: String,
    },
    #[error("{0}: {1}")]
    Io(PathBuf, std::io::Error),
    #[error("{core} rma: no pca-spline model (measured or shipped) to take its body's coefficients from")]
    NoBody { core: Core },
    #[error(
        "{core} {codec}: {rows} calibration rows for {params} coefficients: measure more clips"
    )]
    TooFew {
        core: Core,
        codec: CodecKind,
        rows: usize,
        params: usize,
    },
}

/// Reads `measured.tsv` (header `board core set clip decode_per_pose
/// playback_stack_bytes [player_words]`), each clip's features from its file
/// (a relative clip path is taken from the current directory, as the script
/// writes it) for the player the firmware had: `player_words`, or the
/// board's default `capacity(board)`.
pub fn read_measurements(
    path: &Path,
    capacity: impl Fn(&str) -> Option<usize>,
) -> Result<Vec<Measurement>, FitError> {
    let text = std::fs::read_to_string(path).map_err(|e| FitError::Io(path.into(), e))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let row = |what: String| FitError::Row {
            file: path.into(),
            line: i + 1,
            what,
        };
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split('\t').collect();
        let (board, core, set, clip, per, stack, words) = match f[..] {
            [b, c, s, p, d, k] => (b, c, s, p, d, k, None),
            [b, c, s, p, d, k, w] => (b, c, s, p, d, k, Some(w)),
            _ => return Err(row(format!("{} fields, expected 6 or 7", f.len()))),
        };
        let core = Core::from_name(core).ok_or_else(|| row(format!("unknown core '{core}'")))?;
        let fit = match set {
            "fit" => true,
            "check" => false,
            _ => return Err(row(format!("set '{set}' is neither fit nor check"))),
        };
        let bytes = std::fs::read(clip).map_err(|e| row(format!("{clip}: {e}")))?;
        let words = match words {
            Some(w) => w
                .parse()
                .map_err(|_| row(format!("player_words '{w}' is not a number")))?,
            None => capacity(board).ok_or_else(|| {
                row(format!(
                    "board '{board}' has no player capacity (boards.tsv)"
                ))
            })?,
        };
        let features = Features::with_capacity(&bytes, Some(words))
            .map_err(|e| row(format!("{clip}: {e}")))?;
        out.push(Measurement {
            board: board.to_string(),
            core,
            fit,
            clip: clip.into(),
            player_words: words,
            features,
            decode_per_pose: per
                .parse()
                .map_err(|_| row(format!("decode_per_pose '{per}' is not a number")))?,
            playback_stack_bytes: stack
                .parse()
                .map_err(|_| row(format!("playback_stack_bytes '{stack}' is not a number")))?,
        });
    }
    Ok(out)
}

/// A fitted model of one core and codec.
#[derive(Clone, Debug, PartialEq)]
pub struct Fitted {
    pub core: Core,
    pub codec: CodecKind,
    pub coefficients: Vec<f64>,
}

/// Least squares of the relative error (each row divided by its measured
/// count, so a 300-instruction clip weighs as much as a 30 000 one), per
/// core and codec, on the calibration rows. `rma` takes the same core's
/// `pca-spline` coefficients for its body's evaluations (its first
/// features) and fits only what its repeated poses add, on what those
/// leave (few calibration clips repeat, and their bodies are `pca-spline`
/// bodies).
pub fn fit(rows: &[Measurement]) -> Result<Vec<Fitted>, FitError> {
    let mut groups: BTreeMap<(Core, CodecKind), Vec<&Measurement>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.fit) {
        groups
            .entry((r.core, r.features.codec))
            .or_default()
            .push(r);
    }
    let mut out: Vec<Fitted> = Vec::new();
    for ((core, codec), g) in groups {
        let params = codec.feature_names().len();
        if codec == CodecKind::Rma {
            let body = out
                .iter()
                .find(|f| f.core == core && f.codec == CodecKind::PcaSpline)
                .map(|f| f.coefficients.clone())
                .or_else(|| {
                    super::calibration::MODELS
                        .iter()
                        .find(|m| m.core == core && m.codec == CodecKind::PcaSpline)
                        .map(|m| m.coefficients.to_vec())
                })
                .ok_or(FitError::NoBody { core })?;
            let own = params - body.len();
            if g.len() < own + 2 {
                return Err(FitError::TooFew {
                    core,
                    codec,
                    rows: g.len(),
                    params: own,
                });
            }
            let a = DMatrix::from_fn(g.len(), own, |i, j| {
                g[i].features.x.get(body.len() + j).copied().unwrap_or(0.0)
                    / g[i].decode_per_pose.max(1.0)
            });
            let b = DVector::from_fn(g.len(), |i, _| {
                1.0 - instructions(&body, &g[i].features.x[..body.len()])
                    / g[i].decode_per_pose.max(1.0)
            });
            let mut coefficients = body;
            coefficients.extend(nonnegative_solve(&a, &b, None));
            out.push(Fitted {
                core,
                codec,
                coefficients,
            });
            continue;
        }
        if g.len() < params + 2 {
            return Err(FitError::TooFew {
                core,
                codec,
                rows: g.len(),
                params,
            });
        }
        let a = DMatrix::from_fn(g.len(), params, |i, j| {
            g[i].features.x.get(j).copied().unwrap_or(0.0) / g[i].decode_per_pose.max(1.0)
        });
        let ones = DVector::from_element(g.len(), 1.0);
        let coefficients = if matches!(codec, CodecKind::PcaSpline | CodecKind::IndexFast) {
            nonnegative_solve(&a, &ones, Some(0))
        } else {
            solve(&a, &ones, &vec![true; params])
        };
        out.push(Fitted {
            core,
            codec,
            coefficients,
        });
    }
    Ok(out)
}

/// The models the encoder ships (`calibration.rs`).
fn shipped() -> Vec<Fitted> {
    super::calibration::MODELS
        .iter()
        .map(|m| Fitted {
            core: m.core,
            codec: m.codec,
            coefficients: m.coefficients.to_vec(),
        })
        .collect()
}

/// `fitted` and, for every core and codec it has no model of, the one the
/// encoder ships: a run that measured some codecs only (`scripts/cost.sh
/// --only rma`) keeps the others' models. Sorted by core and codec.
pub fn with_shipped(fitted: Vec<Fitted>) -> Vec<Fitted> {
    let mut all = fitted;
    for m in shipped() {
        if !all.iter().any(|f| f.core == m.core && f.codec == m.codec) {
            all.push(m);
        }
    }
    all.sort_by_key(|f| (f.core, f.codec));
    all
}

/// [`playback_stacks`] of `rows` and, for every core and codec they have
/// no row of, the stack the encoder ships.
pub fn stacks_with_shipped(rows: &[Measurement]) -> Vec<(Core, CodecKind, u32)> {
    let mut all = playback_stacks(rows);
    for &(c, k, b) in super::calibration::PLAYBACK_STACK_BYTES {
        if !all.iter().any(|&(c2, k2, _)| (c2, k2) == (c, k)) {
            all.push((c, k, b));
        }
    }
    all.sort_by_key(|&(c, k, _)| (c, k));
    all
}

/// Least squares of `a · c = b` over the columns `used` (the others 0).
fn solve(a: &DMatrix<f64>, b: &DVector<f64>, used: &[bool]) -> Vec<f64> {
    let cols: Vec<usize> = (0..a.ncols()).filter(|&j| used[j]).collect();
    let sub = DMatrix::from_fn(a.nrows(), cols.len(), |i, j| a[(i, cols[j])]);
    let mut c = vec![0.0; a.ncols()];
    if let Ok(x) = sub.svd(true, true).solve(b, 1e-9) {
        for (&j, v) in cols.iter().zip(x.iter()) {
            c[j] = *v;
        }
    }
    c
}

/// [`solve`] with every coefficient but the constant's (column `free`, if
/// any) at least 0: each is an instruction count per unit of work, and a negative one is
/// the fit trading features it cannot tell apart on the calibration clips,
/// which extrapolates badly (the M0's full-cache `pca-spline` players, past
/// the microbit's RAM). The most negative is dropped and the rest refitted
/// until none is left (an active-set descent, as Lawson–Hanson's NNLS).
fn nonnegative_solve(a: &DMatrix<f64>, b: &DVector<f64>, free: Option<usize>) -> Vec<f64> {
    let mut used = vec![true; a.ncols()];
    loop {
        let c = solve(a, b, &used);
        let worst = (0..c.len())
            .filter(|&j| Some(j) != free && used[j] && c[j] < 0.0)
            .min_by(|&i, &j| c[i].total_cmp(&c[j]));
        match worst {
            Some(j) => used[j] = false,
            None => return c,
        }
    }
}

/// The most playback stack measured per core and codec, over every row
/// (a stack is not fitted: it is what the decoder's deepest call took).
pub fn playback_stacks(rows: &[Measurement]) -> Vec<(Core, CodecKind, u32)> {
    let mut most: BTreeMap<(Core, CodecKind), u32> = BTreeMap::new();
    for r in rows {
        let m = most.entry((r.core, r.features.codec)).or_default();
        *m = (*m).max(r.playback_stack_bytes);
    }
    most.into_iter().map(|((c, k), b)| (c, k, b)).collect()
}

/// The Rust source of `encoder/src/target/calibration.rs` for `fitted`.
pub fn calibration_source(
    fitted: &[Fitted],
    stacks: &[(Core, CodecKind, u32)],
    player_fixed_bytes: usize,
    decoder_code: &[(Core, usize)],
) -> String {
    let mut s = String::from(
        "//! The cost model's measured figures. Generated by `scripts/cost.sh --write`\n\
         //! (`mocap target fit`) from QEMU instruction counts: do not edit by hand.\n\n\
         use super::chips::Core;\n\
         use super::cost::{CodecKind, Model};\n\n\
         /// `size_of::<Player<0>>()` on a 32-bit core (the firmware's `state_bytes` less 4 per word).\n",
    );
    let _ = writeln!(
        s,
        "pub const PLAYER_FIXED_BYTES: usize = {player_fixed_bytes};\n"
    );
    s += "/// The decoder's code per core, every codec linked (`scripts/firmware.sh size`).\n";
    s += "pub const DECODER_CODE_BYTES: &[(Core, usize)] = &[\n";
    for (c, b) in decoder_code {
        let _ = writeln!(s, "    (Core::{c:?}, {b}),");
    }
    s += "];\n\n/// Instructions per pose, per core and codec.\npub const MODELS: &[Model] = &[\n";
    for f in fitted {
        let _ = writeln!(s, "    Model {{");
        let _ = writeln!(s, "        core: Core::{:?},", f.core);
        let _ = writeln!(s, "        codec: CodecKind::{:?},", f.codec);
        let coeffs: Vec<String> = f.coefficients.iter().map(|c| format!("{c:e}")).collect();
        let _ = writeln!(s, "        coefficients: &[{}],", coeffs.join(", "));
        let _ = writeln!(s, "    }},");
    }
    s += "];\n\n/// Peak stack of the playback path (`next_frame` and what it calls), the most measured.\n";
    s += "pub const PLAYBACK_STACK_BYTES: &[(Core, CodecKind, u32)] = &[\n";
    for (c, k, b) in stacks {
        let _ = writeln!(s, "    (Core::{c:?}, CodecKind::{k:?}, {b}),");
    }
    s += "];\n";
    s
}

/// Predicted against measured: every held-out row as a Markdown table, and
/// the worst error of each core and codec on both sets (the calibration rows
/// stay in the measurements file), with `predict` giving the model's
/// instructions per pose of a row (`None`: no model).
pub fn report(rows: &[Measurement], predict: impl Fn(&Measurement) -> Option<f64>) -> String {
    let mut s = String::from(
        "Held-out clips (never seen by the fit):\n\n| board | core | clip | channels | Player<N> | measured / pose | predicted | error | playback stack B |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    // (core codec) -> [calibration, held out]: rows, worst error.
    let mut worst: BTreeMap<String, [(usize, f64); 2]> = BTreeMap::new();
    for r in rows {
        let Some(p) = predict(r) else { continue };
        let err = (p - r.decode_per_pose) / r.decode_per_pose.max(1.0);
        let w = &mut worst
            .entry(format!("{} {}", r.core, r.features.codec))
            .or_default()[usize::from(!r.fit)];
        *w = (w.0 + 1, w.1.max(err.abs()));
        if r.fit {
            continue;
        }
        let name = r.clip.file_stem().map_or_else(
            || r.clip.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let _ = writeln!(
            s,
            "| {} | {} | {name} | {} | {} | {:.0} | {p:.0} | {:+.1} % | {} |",
            r.board,
            r.core,
            r.features.channels,
            r.player_words,
            r.decode_per_pose,
            err * 100.0,
            r.playback_stack_bytes
        );
    }
    s += "\nWorst error per core and codec (rows measured):\n\n| core codec | calibration | held out |\n|---|---|---|\n";
    for (k, sets) in &worst {
        let cell = |(n, w): (usize, f64)| {
            if n == 0 {
                "-".to_string()
            } else {
                format!("{:.1} % ({n})", w * 100.0)
            }
        };
        let _ = writeln!(s, "| {k} | {} | {} |", cell(sets[0]), cell(sets[1]));
    }
    s
}

/// The predicted instructions per pose of `r` under `fitted`, the M4F from
/// the M3's model when it has none of its own (as [`super::cost::model`]).
pub fn predict_with(fitted: &[Fitted], r: &Measurement) -> Option<f64> {
    let find = |c: Core| {
        fitted
            .iter()
            .find(|f| f.core == c && f.codec == r.features.codec)
    };
    let f = find(r.core).or_else(|| (r.core == Core::M4F).then(|| find(Core::M3)).flatten())?;
    Some(instructions(&f.coefficients, &r.features.x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run that measured one codec replaces that codec's models and keeps
    /// every other shipped one, in (core, codec) order.
    #[test]
    fn a_partial_fit_keeps_the_shipped_models() {
        let all = with_shipped(Vec::new());
        assert_eq!(all, shipped_sorted());
        let mine = Fitted {
            core: Core::M3,
            codec: CodecKind::Rma,
            coefficients: vec![1.0; CodecKind::Rma.feature_names().len()],
        };
        let merged = with_shipped(vec![mine.clone()]);
        assert_eq!(
            merged
                .iter()
                .filter(|f| (f.core, f.codec) == (Core::M3, CodecKind::Rma))
                .collect::<Vec<_>>(),
            [&mine]
        );
        let others = |v: &[Fitted]| {
            v.iter()
                .filter(|f| (f.core, f.codec) != (Core::M3, CodecKind::Rma))
                .cloned()
                .collect::<Vec<_>>()
        };
        assert_eq!(others(&merged), others(&all));
        assert!(merged
            .windows(2)
            .all(|w| (w[0].core, w[0].codec) < (w[1].core, w[1].codec)));
    }

    fn shipped_sorted() -> Vec<Fitted> {
        let mut s = shipped();
        s.sort_by_key(|f| (f.core, f.codec));
        s
    }
}
