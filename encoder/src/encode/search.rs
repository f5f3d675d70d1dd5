//! The searches: for each codec the coarsest setting whose proven clip
//! still meets the bound — tightening or bisecting per-channel tolerances
//! (`index`, `predictive`, `pattern`), bisecting the weighted tolerance `τ`
//! (`pca-spline`).

use mocap_decoder::consts;
use rayon::prelude::*;

use super::proof::{prove, Attempt};
use super::reference::Reference;
use super::{Bound, CodecChoice, EncodeError, EncodeOptions, Encoded, Progress};
use crate::codec::{index, pattern, pca_spline, predictive};
use crate::fixed::FixedChannels;
use crate::metrics::Metrics;
use crate::motion::Motion;

/// One try of a search: what it made and how its decoded motion measured.
pub trait Trial {
    /// Its size in bytes (the search keeps the smallest that holds).
    fn size(&self) -> usize;
    /// Its metrics, measured on its decoded motion ([`Reference::measure`]).
    fn metrics(&self) -> &Metrics;
}

fn attempt(
    m: &Motion,
    input: &Reference,
    tol: &[i64],
    opts: &EncodeOptions,
    progress: &dyn Progress,
) -> Result<Attempt, EncodeError> {
    let fixed = &input.fixed;
    if opts.codec == CodecChoice::Pattern {
        let nodes = pattern::nodes_with(m, &opts.pattern.nodes)?;
        let accept = pattern::accept_for(&opts.bound);
        let fps = 1.0 / m.frame_time;
        let enc = pattern::encode(&fixed.values, tol, accept, &nodes, fps, &opts.pattern)?;
        let expected = FixedChannels {
            kinds: fixed.kinds.clone(),
            values: enc.decoded,
        };
        return prove(
            m,
            input,
            (pattern::SECTION_ID, enc.section),
            Some(&expected),
            opts,
        );
    }
    if opts.codec == CodecChoice::Predictive {
        let block = match opts.key_interval {
            Some(k) => u32::from(k.max(1)),
            None => ((predictive::DEFAULT_BLOCK_SECONDS / m.frame_time).round() as u32).max(1),
        };
        let enc = predictive::encode_with(&fixed.values, tol, block, &|d, t| progress.work(d, t))?;
        let expected = FixedChannels {
            kinds: fixed.kinds.clone(),
            values: enc.decoded,
        };
        let mut a = prove(
            m,
            input,
            (consts::SECTION_CODEC_PREDICTIVE, enc.section),
            Some(&expected),
            opts,
        )?;
        a.key_interval = block.min(u32::from(u16::MAX)) as u16;
        return Ok(a);
    }
    let intervals: Vec<u16> = match opts.key_interval {
        Some(k) => vec![k],
        None => index::KEY_INTERVALS.to_vec(),
    };
    let enc = index::encode(&fixed.values, tol, &intervals, opts.index_layout).map_err(|e| {
        EncodeError::ToleranceTooTight {
            channel: e.channel,
            name: m.skeleton.channel_names()[e.channel].clone(),
        }
    })?;
    let expected = FixedChannels {
        kinds: fixed.kinds.clone(),
        values: enc.decoded(),
    };
    let mut a = prove(
        m,
        input,
        (opts.index_layout.section_id(), enc.to_section()?),
        Some(&expected),
        opts,
    )?;
    a.key_interval = enc.key_interval;
    Ok(a)
}

/// A log-bisection for the largest parameter in `[lo, hi]` whose attempt
/// meets the bound (size falls as the parameter grows): at most `steps`
/// rounds, stopping once `hi / lo < ratio`. Returns the smallest holding
/// attempt seen (if any), the largest holding parameter found (`lo`) and
/// the attempts made.
fn bisect<T: Trial, E>(
    bound: &Bound,
    (mut lo, mut hi): (f64, f64),
    steps: usize,
    ratio: f64,
    mut run: impl FnMut(f64) -> Result<T, E>,
    mut round: impl FnMut(usize),
) -> Result<(Option<T>, f64, usize), E> {
    let mut best: Option<T> = None;
    let mut attempts = 0;
    for _ in 0..steps {
        attempts += 1;
        round(attempts);
        let x = (lo * hi).sqrt();
        let a = run(x)?;
        if bound.holds(a.metrics()) {
            lo = x;
            if best.as_ref().is_none_or(|b| a.size() <= b.size()) {
                best = Some(a);
            }
        } else {
            hi = x;
        }
        if hi / lo < ratio {
            break;
        }
    }
    Ok((best, lo, attempts))
}

/// How many rounds [`bisect`] makes: the ratio `hi / lo` is square-rooted
/// each round, whatever the outcome.
fn bisect_rounds((lo, hi): (f64, f64), steps: usize, ratio: f64) -> usize {
    let mut r = (hi / lo).ln();
    let mut n = 0;
    while n < steps {
        n += 1;
        r /= 2.0;
        if r < ratio.ln() {
            break;
        }
    }
    n
}

/// Encodes with `pca-spline`, searching the tolerance `τ` (log-bisection)
/// for the smallest clip whose decoded output meets the bound.
pub(super) fn encode_pca(
    m: &Motion,
    reference: &Reference,
    opts: &EncodeOptions,
    progress: &dyn Progress,
) -> Result<Encoded, EncodeError> {
    let Reference {
        fixed,
        levers_um,
        joint_of,
        ..
    } = reference;
    let mm = opts.bound.positional();
    let weights = pca_spline::pca_weights(
        m,
        levers_um,
        joint_of,
        &fixed.kinds,
        mm,
        opts.bound.arms_mm.is_some(),
    );
    let groups = pca_spline::pca_groups(m, 9);
    let input = pca_spline::Input {
        values: &fixed.values,
        weights: &weights,
        groups: &groups,
    };
    let fps = 1.0 / m.frame_time;
    let cache = pca_spline::Cache::default();
    let run = |tau: f64, feet: f64| -> Result<Attempt, EncodeError> {
        let held = (feet < 1.0).then(|| with_feet(&weights, &reference.moves_feet, feet));
        let input = pca_spline::Input {
            weights: held.as_deref().unwrap_or(&weights),
            ..input
        };
        let params = pca_spline::Params {
            key_bits: opts.key_bits.map(|b| b.0),
            ..pca_spline::Params::new(tau, fps)
        };
        let mut model =
            pca_spline::model_with(&input, &params, &cache, &|d, t| progress.work(d, t))?;
        let try_model = |model: &pca_spline::Model| {
            let section = model.to_section(fixed.kinds.len());
            prove(
                m,
                reference,
                (consts::SECTION_CODEC_PCA_SPLINE, section),
                None,
                opts,
            )
        };
        let first = try_model(&model)?;
        // What the smooth model misses by more than τ (glitches, spikes)
        // becomes sparse patches.
        if model.add_patches(&input, &first.decoded, params.patch_share * tau) == 0 {
            return Ok(first);
        }
        try_model(&model)
    };
    search_tau(opts, CodecChoice::PcaSpline, progress, run)
}

/// `weights` with the channels that move a foot weighing `1 / feet` times
/// more (their share of the tolerance `feet` times smaller).
pub(super) fn with_feet(weights: &[f64], moves_feet: &[bool], feet: f64) -> Vec<f64> {
    weights
        .iter()
        .zip(moves_feet)
        .map(|(&w, &m)| if m { w / feet } else { w })
        .collect()
}

/// The search of the codecs driven by one weighted tolerance `τ`
/// (`pca-spline`, `rma`): a log-bisection of `τ` from 1/256 to twice the
/// bound's scale for the largest `τ` whose clip (made and proven by
/// `run(τ, 1)`) meets the bound, then a few probes just above it (size and
/// error are not quite monotonic in `τ`); the smallest clip that holds.
/// Under a slide bound: that search under the other bounds first; if the
/// feet slide too much there, the weight of the channels that move a foot
/// raised alone at that `τ` (`run(τ, f)` divides their tolerance's share by
/// `1 / f`, `f` log-bisected); only if that fails, `τ` under every bound.
pub(super) fn search_tau(
    opts: &EncodeOptions,
    codec: CodecChoice,
    progress: &dyn Progress,
    run: impl Fn(f64, f64) -> Result<Attempt, EncodeError> + Sync,
) -> Result<Encoded, EncodeError> {
    let (best, attempts) = search_with_slide(
        &opts.bound,
        |b| search_tau_under(b, opts, codec, progress, |t| run(t, 1.0)),
        &run,
        |n, rounds| progress.round(codec, n, rounds),
    )?;
    Ok(Encoded {
        bytes: best.bytes,
        metrics: best.metrics,
        codec,
        key_interval: 0,
        attempts,
    })
}

/// A search under `bound`, in two steps when it limits the foot slide:
/// `search(b)` (the best try under `b`, the tries made, and the parameter
/// it was made with) under the other bounds first; if the feet slide too
/// much there, `feet(p, f)` at that parameter with the channels that move
/// a foot held `f` times tighter, `f` log-bisected in `[1/256, 1]`; only
/// if no `f` holds, `search` under every bound. `round(n, rounds)` reports
/// the feet's tries, counted on from the first step's.
fn search_with_slide<T: Trial, P: Copy, E>(
    bound: &Bound,
    search: impl Fn(&Bound) -> Result<(T, usize, P), E>,
    feet: impl Fn(P, f64) -> Result<T, E>,
    round: impl Fn(usize, usize),
) -> Result<(T, usize), E> {
    if bound.foot_slide_mm_s.is_none() {
        let (best, attempts, _) = search(bound)?;
        return Ok((best, attempts));
    }
    let others = Bound {
        foot_slide_mm_s: None,
        ..*bound
    };
    let (first, mut attempts, at) = search(&others)?;
    if bound.holds(first.metrics()) {
        return Ok((first, attempts));
    }
    let range = (1.0 / 256.0, 1.0);
    let rounds = attempts + bisect_rounds(range, 10, 1.05);
    let (held, _, n) = bisect(
        bound,
        range,
        10,
        1.05,
        |f| feet(at, f),
        |n| round(attempts + n, rounds),
    )?;
    attempts += n;
    if let Some(best) = held {
        return Ok((best, attempts));
    }
    let (best, n, _) = search(bound)?;
    Ok((best, attempts + n))
}

/// [`search_tau`]'s search of `τ` under `bound` (errors name the bound
/// asked, `opts.bound`): the smallest clip that holds, the attempts made,
/// and the largest `τ` the bisection found holding.
fn search_tau_under(
    bound: &Bound,
    opts: &EncodeOptions,
    codec: CodecChoice,
    progress: &dyn Progress,
    run: impl Fn(f64) -> Result<Attempt, EncodeError> + Sync,
) -> Result<(Attempt, usize, f64), EncodeError> {
    let scale = match (bound.position_mm.or(bound.arms_mm), bound.angle_deg) {
        (Some(p), _) => p,
        (None, Some(d)) => d,
        (None, None) => Bound::DEFAULT_TRANSLATION_MM,
    };
    let range = (scale / 256.0, scale * 2.0);
    let rounds = bisect_rounds(range, 20, 1.02) + 6;
    let (mut best, lo, mut attempts) = bisect(bound, range, 20, 1.02, &run, |n| {
        progress.round(codec, n, rounds)
    })?;
    // Size and error are not quite monotonic in τ: probe a little above
    // the boundary too and keep the smallest clip that holds. The probes
    // are independent: run in parallel, kept in order (the same clip for
    // any number of threads), each without its decoded values (only its
    // bytes and metrics are kept).
    let first = attempts;
    let probes: Vec<Result<Attempt, EncodeError>> = (1..=6)
        .into_par_iter()
        .map(|i| {
            progress.round(codec, first + i, rounds.max(first + i));
            let mut a = run(lo * (1.0 + 0.03 * i as f64))?;
            a.decoded = Vec::new();
            Ok(a)
        })
        .collect();
    for a in probes {
        attempts += 1;
        let a = a?;
        if bound.holds(&a.metrics) && best.as_ref().is_none_or(|b| a.bytes.len() < b.bytes.len()) {
            best = Some(a);
        }
    }
    let best = match best {
        Some(b) => b,
        None => {
            attempts += 1;
            progress.round(codec, attempts, attempts);
            let a = run(lo)?;
            if !bound.holds(&a.metrics) {
                return Err(EncodeError::PcaBoundNotMet {
                    codec,
                    bound: opts.bound,
                    max_joint_err_mm: a.metrics.max_joint_err_mm,
                    angle_max_deg: a.metrics.angle_max_deg,
                });
            }
            a
        }
    };
    Ok((best, attempts, lo))
}

/// Encodes with a codec driven by per-channel tolerances (`index`,
/// `predictive`): [`search_tolerances`] with an attempt of that codec.
pub(super) fn encode_by_tolerance(
    m: &Motion,
    input: &Reference,
    opts: &EncodeOptions,
    progress: &dyn Progress,
) -> Result<Encoded, EncodeError> {
    let (best, attempts) = search_tolerances_with(
        input,
        &opts.bound,
        |tol| attempt(m, input, tol, opts, progress),
        |n, rounds| progress.round(opts.codec, n, rounds),
    )?;
    Ok(Encoded {
        bytes: best.bytes,
        metrics: best.metrics,
        codec: opts.codec,
        key_interval: best.key_interval,
        attempts,
    })
}

/// Under a bound on ARMS alone, the position budget's bisection starts at
/// this many times the ARMS.
const ARMS_BUDGET_SCALE: f64 = 8.0;

/// The search of every coder driven by per-channel tolerances: `run` codes
/// the motion at the tolerances it is given (from
/// [`Reference::tolerances`]) and measures its decoded motion. Under an
/// angle bound (no millimetre bound) the tolerances are tightened by 0.8
/// until the bound holds (at most 8 tries); under a millimetre bound (a
/// joint's largest error, or ARMS alone) the position budget per channel is
/// log-bisected (errors of every joint up
/// the chain add up, so the budget per channel is a fraction of the bound)
/// and the smallest try that holds is kept. Returns it and the tries made;
/// [`EncodeError::BoundNotMetAfter`] or [`EncodeError::BoundNotMet`] when
/// none holds.
pub fn search_tolerances<T: Trial, E: From<EncodeError>>(
    input: &Reference,
    bound: &Bound,
    run: impl Fn(&[i64]) -> Result<T, E>,
) -> Result<(T, usize), E> {
    search_tolerances_with(input, bound, run, |_, _| {})
}

/// [`search_tolerances`], calling `round(n, rounds)` as try `n` (from 1) of
/// about `rounds` starts.
pub(super) fn search_tolerances_with<T: Trial, E: From<EncodeError>>(
    input: &Reference,
    bound: &Bound,
    run: impl Fn(&[i64]) -> Result<T, E>,
    round: impl Fn(usize, usize),
) -> Result<(T, usize), E> {
    let run = |s_um: Option<f64>, tighten: f64, feet: f64| {
        run(&input.tolerances_with_feet(bound, s_um, tighten, feet))
    };
    search_with_slide(
        bound,
        |b| search_budget(b, bound, |s, t| run(s, t, 1.0), &round),
        |(s_um, tighten), f| run(s_um, tighten, f),
        &round,
    )
}

/// What [`search_budget`] found: the attempt, the attempts made, and the
/// position budget (µm) and tightening it was made with.
type Budgeted<T> = (T, usize, (Option<f64>, f64));

/// The largest position budget (or, without a position bound, the least
/// tightening of the angle tolerances) whose attempt meets `bound`; errors
/// name `named`, the bound as asked.
fn search_budget<T: Trial, E: From<EncodeError>>(
    bound: &Bound,
    named: &Bound,
    run: impl Fn(Option<f64>, f64) -> Result<T, E>,
    round: impl Fn(usize, usize),
) -> Result<Budgeted<T>, E> {
    let mut attempts = 0;
    let mut tighten = 1.0;
    // Under an ARMS bound alone the position budget is bisected too, up to
    // eight times the ARMS (the largest error of a joint is a few times the
    // mean).
    let position = bound
        .position_mm
        .or(bound.arms_mm.map(|a| a * ARMS_BUDGET_SCALE));
    match position {
        None => loop {
            attempts += 1;
            round(attempts, attempts);
            let a = run(None, tighten)?;
            if bound.holds(a.metrics()) {
                return Ok((a, attempts, (None, tighten)));
            }
            if attempts >= 8 {
                return Err(EncodeError::BoundNotMetAfter {
                    bound: *named,
                    attempts,
                }
                .into());
            }
            tighten *= 0.8;
        },
        Some(p) => {
            let bound_um = p * 1000.0;
            let range = (bound_um * 1e-3, bound_um);
            let rounds = bisect_rounds(range, 14, 1.03);
            let (best, lo, n) = bisect(
                bound,
                range,
                14,
                1.03,
                |s| run(Some(s), 1.0),
                |n| round(n, rounds),
            )?;
            attempts += n;
            let best = match best {
                Some(b) => b,
                None => {
                    attempts += 1;
                    round(attempts, attempts);
                    let a = run(Some(lo), 1.0)?;
                    if !bound.holds(a.metrics()) {
                        return Err(EncodeError::BoundNotMet { bound: *named }.into());
                    }
                    a
                }
            };
            Ok((best, attempts, (Some(lo), 1.0)))
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::encode::{encode, Bound, BoundSpec, CodecChoice, EncodeOptions};
    use crate::generate::animatronic_demo;

    /// A bound on ARMS alone is met by every codec driven by tolerances
    /// (it used to fail after eight tightening rounds: no budget bounded
    /// the rotations).
    #[test]
    fn an_arms_bound_alone_is_met() {
        let m = animatronic_demo();
        let bound = Bound::from_specs(&["arms:5mm".parse::<BoundSpec>().unwrap()]);
        for codec in [
            CodecChoice::Index,
            CodecChoice::Predictive,
            CodecChoice::Pattern,
            CodecChoice::Rma,
        ] {
            let opts = EncodeOptions {
                key_bits: None,
                codec,
                bound,
                metres_per_unit: crate::units::detect(&m).metres(),
                key_interval: None,
                index_layout: Default::default(),
                pattern: Default::default(),
            };
            let e = encode(&m, &opts).unwrap_or_else(|e| panic!("{codec:?}: {e}"));
            assert!(e.metrics.arms_mm <= 5.0, "{codec:?}");
            assert!(e.metrics.arms_mm > 1.0, "{codec:?}: the budget is used");
        }
    }
}
