//! The `rma` codec's encode (SPEC.md §12): the repeated-motion analysis
//! once, then for each tolerance `τ` of the search: the stretches outside
//! the repeated clips modelled as `pca-spline` segments, decoded; each
//! repeated clip's residual against its primary's *source* read at
//! `Ref(t)`, modelled the same way; the whole clip decoded, patched where
//! the primary's error and the residual's add up past the tolerance, and
//! proven like every codec. (A residual against the *decoded* primary
//! would not add errors, but it carries the primary's coding noise: an
//! exact repetition of a 480-frame take then costs 395 bytes of residual
//! instead of nothing — 1 530 bytes against 1 235 at 20 mm.)

use mocap_decoder::consts;
use rayon::prelude::*;

use super::proof::{prove, Attempt};
use super::reference::Reference;
use super::search::search_tau;
use super::{CodecChoice, EncodeError, EncodeOptions, Encoded, Progress};
use crate::codec::pca_spline::{self, GroupModel, Model, SegmentModel};
use crate::codec::rma::{self, Plan};
use crate::motion::Motion;

/// Knots of `Ref(t)` every this many frames at 120 Hz (scaled with the
/// rate): a line between the analysis's references (BENCHMARKS.md §9).
pub const KNOT_FRAMES_120HZ: f64 = 16.0;

/// How far the knots' line may stray from each frame's best reference,
/// frames.
pub const REF_TOLERANCE_FRAMES: f64 = 0.5;

/// Encodes with `rma`, searching `τ` like `pca-spline`.
pub(super) fn encode_rma(
    m: &Motion,
    reference: &Reference,
    opts: &EncodeOptions,
    progress: &dyn Progress,
) -> Result<Encoded, EncodeError> {
    let fixed = &reference.fixed;
    let weights = pca_spline::pca_weights(
        m,
        &reference.levers_um,
        &reference.joint_of,
        &fixed.kinds,
        opts.bound.positional(),
        opts.bound.arms_mm.is_some(),
    );
    let fps = 1.0 / m.frame_time;
    let frames = m.frames();
    let constant: Vec<bool> = fixed
        .values
        .iter()
        .map(|v| v.iter().all(|&x| x == v[0]))
        .collect();
    let added: Vec<usize> = rma::body_channels(m)
        .into_iter()
        .filter(|&c| !constant[c])
        .collect();
    let analysis = rma::analyse(m, &rma::Params::default());
    let knot_every = ((KNOT_FRAMES_120HZ * fps / 120.0).round() as usize).max(2);
    // Two readings of the analysis: the paper's clips and the longest
    // matches; each is searched, the smaller clip kept.
    let mut plans: Vec<Plan> = Vec::new();
    for clips in [&analysis.clips, &analysis.matches] {
        let mut plan = Plan::new(clips, added.clone(), knot_every);
        plan.refine(
            &fixed.values,
            &weights,
            &added,
            2 * analysis.features.step,
            REF_TOLERANCE_FRAMES,
        );
        if !plans.contains(&plan) {
            plans.push(plan);
        }
    }
    let groups: Vec<Vec<usize>> = pca_spline::pca_groups(m, 9)
        .into_iter()
        .map(|g| g.into_iter().filter(|&c| !constant[c]).collect::<Vec<_>>())
        .filter(|g| !g.is_empty())
        .collect();
    let consts: Vec<(usize, i32)> = (0..fixed.values.len())
        .filter(|&c| !groups.iter().any(|g| g.contains(&c)))
        .map(|c| (c, fixed.values[c][0]))
        .collect();
    // Each plan with and without the PPCA cuts (measured at 50 mm + ARMS
    // 10 mm: 01_14 5.9 % smaller without, 05_04 6.5 % larger; at 1° 01_14
    // 3.6 % larger without): the smaller clip is kept.
    let mut best: Option<Encoded> = None;
    for (plan, ppca) in plans.iter().flat_map(|p| [(p, true), (p, false)]) {
        let job = Job {
            m,
            reference,
            opts,
            progress,
            weights: weights.clone(),
            groups: groups.clone(),
            consts: consts.clone(),
            fps,
            own_frames: own_caches(plan, frames),
            joined: joined_caches(plan, frames),
            ppca,
        };
        let encoded = search_tau(opts, CodecChoice::Rma, progress, |tau, feet| {
            if feet < 1.0 {
                job.with_feet(plan, feet).run(plan, tau)
            } else {
                job.run(plan, tau)
            }
        })?;
        if best
            .as_ref()
            .is_none_or(|b| encoded.bytes.len() < b.bytes.len())
        {
            best = Some(encoded);
        }
    }
    best.ok_or(EncodeError::Empty)
}

/// PPCA caches for the own stretches of `plan`, by (first, last) frame.
fn own_caches(plan: &Plan, frames: usize) -> Vec<((usize, usize), pca_spline::Cache)> {
    plan.own_stretches(frames)
        .into_iter()
        .map(|span| (span, Default::default()))
        .collect()
}

/// PPCA caches for each repeated clip of `plan` joined to the own
/// stretches next to it, by (first, last) frame.
fn joined_caches(plan: &Plan, frames: usize) -> Vec<((usize, usize), pca_spline::Cache)> {
    let own = plan.own_stretches(frames);
    plan.repeated
        .iter()
        .map(|r| {
            let first = own
                .iter()
                .find(|s| s.1 + 1 == r.start as usize)
                .map_or(r.start as usize, |s| s.0);
            let last = own
                .iter()
                .find(|s| s.0 == r.last as usize + 1)
                .map_or(r.last as usize, |s| s.1);
            ((first, last), Default::default())
        })
        .collect()
}

/// Rounds of dropping the repeated clips that do not pay.
const KEEP_ROUNDS: usize = 3;

/// What every try of the search shares.
struct Job<'a> {
    m: &'a Motion,
    reference: &'a Reference,
    opts: &'a EncodeOptions,
    progress: &'a dyn Progress,
    weights: Vec<f64>,
    groups: Vec<Vec<usize>>,
    consts: Vec<(usize, i32)>,
    fps: f64,
    /// PPCA caches of the input's own values: the stretches outside the
    /// analysis's repeated clips, and each repeated clip's frames.
    own_frames: Vec<((usize, usize), pca_spline::Cache)>,
    /// … and each repeated clip joined to the own stretches around it.
    joined: Vec<((usize, usize), pca_spline::Cache)>,
    /// Whether the stretches are cut where their PPCA model changes
    /// (`pca-spline`'s segmentation), or only at jumps and at
    /// `pca_spline::MAX_FIT_SECONDS`.
    ppca: bool,
}

/// One try's model: the section's model, its proven clip.
struct Made {
    model: Model,
    attempt: Attempt,
}

impl<'a> Job<'a> {
    /// The job with the channels that move a foot weighing `1 / feet` times
    /// more (a slide bound's second step), with PPCA caches of its own.
    fn with_feet(&self, plan: &Plan, feet: f64) -> Job<'a> {
        let frames = self.m.frames();
        Job {
            weights: super::search::with_feet(&self.weights, &self.reference.moves_feet, feet),
            groups: self.groups.clone(),
            consts: self.consts.clone(),
            own_frames: own_caches(plan, frames),
            joined: joined_caches(plan, frames),
            ..*self
        }
    }

    /// The body's parameters at `τ` for the own stretches.
    fn params(&self, tau: f64) -> pca_spline::Params {
        let params = pca_spline::Params::new(tau, self.fps);
        pca_spline::Params {
            fixed_groups: true,
            key_bits: self.opts.key_bits.map(|b| b.0),
            ppca: if self.ppca { params.ppca } else { None },
            ..params
        }
    }

    /// … and for the repeated clips' residuals.
    fn residual_params(&self, tau: f64) -> pca_spline::Params {
        pca_spline::Params {
            key_bits: self.opts.key_bits.map(|b| b.1),
            ..self.params(tau)
        }
    }

    fn section(&self, plan: &Plan, model: &Model) -> (u8, Vec<u8>) {
        let n = self.reference.fixed.kinds.len();
        (
            consts::SECTION_CODEC_RMA,
            plan.to_section(&model.to_section(n)),
        )
    }

    fn prove(&self, plan: &Plan, model: &Model) -> Result<Attempt, EncodeError> {
        prove(
            self.m,
            self.reference,
            self.section(plan, model),
            None,
            self.opts,
        )
    }

    /// The segments of frames `a..=b` of `values` modelled on their own.
    fn stretch(
        &self,
        values: &[Vec<i32>],
        (a, b): (usize, usize),
        params: &pca_spline::Params,
        cache: &pca_spline::Cache,
    ) -> Result<Vec<SegmentModel>, EncodeError> {
        let part: Vec<Vec<i32>> = values.iter().map(|v| v[a..=b].to_vec()).collect();
        let input = input_of(&part, &self.weights, &self.groups);
        let progress = self.progress;
        let sub = pca_spline::model_with(&input, params, cache, &|d, t| progress.work(d, t))?;
        Ok(shifted(sub.segments, a))
    }

    /// The bytes `segments` take in a body.
    fn bytes_of(&self, segments: Vec<SegmentModel>) -> usize {
        let model = Model {
            groups: self.groups.clone(),
            consts: self.consts.clone(),
            segments,
        };
        model.to_section(self.reference.fixed.kinds.len()).len()
    }

    /// One try at `τ`: the plan's clip; then, if some repeated clips cost
    /// more as residuals than their frames on their own, the clip without
    /// them (their frames joined to the stretches around them).
    fn run(&self, plan: &Plan, tau: f64) -> Result<Attempt, EncodeError> {
        let mut plan = plan.clone();
        let mut made = self.make(&plan, tau)?;
        for _ in 0..KEEP_ROUNDS {
            if plan.repeated.is_empty() {
                return Ok(made.attempt);
            }
            let keep = self.keep(&plan, &made, tau)?;
            if keep.iter().all(|&k| k) {
                break;
            }
            plan.repeated = plan
                .repeated
                .into_iter()
                .zip(keep)
                .filter_map(|(r, k)| k.then_some(r))
                .collect();
            made = self.make(&plan, tau)?;
        }
        if plan.repeated.is_empty() {
            return Ok(made.attempt);
        }
        // The estimates above are each clip's alone: the clip without any
        // repetition decides.
        let none = Plan {
            added: plan.added.clone(),
            repeated: Vec::new(),
        };
        let none = self.make(&none, tau)?.attempt;
        let holds = |a: &Attempt| self.opts.bound.holds(&a.metrics);
        Ok(match (holds(&made.attempt), holds(&none)) {
            (true, false) => made.attempt,
            (false, true) => none,
            _ if none.bytes.len() <= made.attempt.bytes.len() => none,
            _ => made.attempt,
        })
    }

    /// Which of `plan`'s repeated clips pay in `made` (its clip at `τ`): a
    /// clip stays if its residual and its record cost less than its frames
    /// would add to the own stretches around it.
    fn keep(&self, plan: &Plan, made: &Made, tau: f64) -> Result<Vec<bool>, EncodeError> {
        let params = self.params(tau);
        let values = &self.reference.fixed.values;
        let empty = self.bytes_of(Vec::new());
        let seg_bytes = |lo: u32, hi: u32| {
            let segs: Vec<SegmentModel> = made
                .model
                .segments
                .iter()
                .filter(|s| (lo..=hi).contains(&s.start))
                .cloned()
                .collect();
            self.bytes_of(segs) - empty
        };
        let own = plan.own_stretches(self.m.frames());
        plan.repeated
            .par_iter()
            .map(|r| {
                let before = own.iter().find(|s| s.1 + 1 == r.start as usize).copied();
                let after = own.iter().find(|s| s.0 == r.last as usize + 1).copied();
                let span = (
                    before.map_or(r.start as usize, |b| b.0),
                    after.map_or(r.last as usize, |a| a.1),
                );
                let fresh = pca_spline::Cache::default();
                let cache = self
                    .joined
                    .iter()
                    .find(|(s, _)| *s == span)
                    .map_or(&fresh, |(_, c)| c);
                let joined = self.stretch(values, span, &params, cache)?;
                let around = before.map_or(0, |b| seg_bytes(b.0 as u32, b.1 as u32))
                    + after.map_or(0, |a| seg_bytes(a.0 as u32, a.1 as u32));
                let own_cost = (self.bytes_of(joined) - empty).saturating_sub(around);
                let record = Plan {
                    added: Vec::new(),
                    repeated: vec![r.clone()],
                }
                .to_section(&[])
                .len();
                Ok(seg_bytes(r.start, r.last) + record < own_cost)
            })
            .collect()
    }

    /// The clip of `plan` at `τ`, proven.
    fn make(&self, plan: &Plan, tau: f64) -> Result<Made, EncodeError> {
        let params = self.params(tau);
        let tol = params.patch_share * tau;
        let values = &self.reference.fixed.values;
        let frames = self.m.frames();
        let (weights, groups) = (&self.weights, &self.groups);
        // 1. Outside the repeated clips, with zero-valued stand-ins for
        // them: decoded, that clip reads the primaries at Ref(t) there.
        let own = plan.own_stretches(frames);
        let own_segments: Vec<Vec<SegmentModel>> = own
            .par_iter()
            .map(|&span| {
                let fresh = pca_spline::Cache::default();
                let cache = self
                    .own_frames
                    .iter()
                    .find(|(s, _)| *s == span)
                    .map_or(&fresh, |(_, c)| c);
                self.stretch(values, span, &params, cache)
            })
            .collect::<Result<_, _>>()?;
        let stand_ins: Vec<SegmentModel> = plan
            .repeated
            .iter()
            .map(|r| SegmentModel {
                start: r.start,
                end: r.last,
                groups: groups.iter().map(|g| zero_group(g.len())).collect(),
                patches: Vec::new(),
            })
            .collect();
        let mut model = Model {
            groups: groups.clone(),
            consts: self.consts.clone(),
            segments: merged(own_segments.into_iter().flatten(), stand_ins),
        };
        let mut base = self.prove(plan, &model)?;
        // What the smooth model misses outside the repeated clips by more
        // than the patch tolerance becomes patches, before any residual
        // is taken against it.
        let outside = with_repeated_from(values, &base.decoded, plan, true);
        if model.add_patches(&input_of(&outside, weights, groups), &base.decoded, tol) > 0 {
            base = self.prove(plan, &model)?;
        }
        if plan.repeated.is_empty() {
            return Ok(Made {
                model,
                attempt: base,
            });
        }
        // 2. The residuals of the repeated clips against their primaries'
        // source values at Ref(t), on the added channels (elsewhere the
        // body is the value itself).
        let residual_params = self.residual_params(tau);
        let mut residual = values.clone();
        for &c in &plan.added {
            for r in &plan.repeated {
                let span = r.start as usize..=r.last as usize;
                for t in span {
                    let at = r.reference_at(t as u32 - r.start);
                    residual[c][t] = values[c][t].wrapping_sub(read_at(&values[c], at));
                }
            }
        }
        let repeated: Vec<Vec<SegmentModel>> = plan
            .repeated
            .par_iter()
            .map(|r| {
                let span = (r.start as usize, r.last as usize);
                self.stretch(
                    &residual,
                    span,
                    &residual_params,
                    &pca_spline::Cache::default(),
                )
            })
            .collect::<Result<_, _>>()?;
        let own_now: Vec<SegmentModel> = model
            .segments
            .into_iter()
            .filter(|s| !plan.repeated_at(s.start as usize))
            .collect();
        model.segments = merged(own_now, repeated.into_iter().flatten().collect());
        let first = self.prove(plan, &model)?;
        // 3. Patches inside the repeated clips (outside them the clip is
        // what step 1 proved).
        let inside = with_repeated_from(values, &first.decoded, plan, false);
        if model.add_patches(&input_of(&inside, weights, groups), &first.decoded, tol) == 0 {
            return Ok(Made {
                model,
                attempt: first,
            });
        }
        let attempt = self.prove(plan, &model)?;
        Ok(Made { model, attempt })
    }
}

fn input_of<'a>(
    values: &'a [Vec<i32>],
    weights: &'a [f64],
    groups: &'a [Vec<usize>],
) -> pca_spline::Input<'a> {
    pca_spline::Input {
        values,
        weights,
        groups,
    }
}

/// `values` with the frames inside (`inside = true`) or outside the
/// repeated clips taken from `decoded`: what patches compare with, so that
/// only the other frames get patches.
fn with_repeated_from(
    values: &[Vec<i32>],
    decoded: &[Vec<i32>],
    plan: &Plan,
    inside: bool,
) -> Vec<Vec<i32>> {
    values
        .iter()
        .zip(decoded)
        .map(|(v, d)| {
            v.iter()
                .zip(d)
                .enumerate()
                .map(|(f, (&x, &y))| if plan.repeated_at(f) == inside { y } else { x })
                .collect()
        })
        .collect()
}

/// A group of `n` channels that decodes to 0.
fn zero_group(n: usize) -> GroupModel {
    GroupModel {
        mean: vec![0; n],
        ..GroupModel::default()
    }
}

/// Segments of a stretch modelled on its own, moved to start at frame `a`.
fn shifted(segments: Vec<SegmentModel>, a: usize) -> Vec<SegmentModel> {
    segments
        .into_iter()
        .map(|mut s| {
            s.start += a as u32;
            s.end += a as u32;
            s
        })
        .collect()
}

/// Two lists of segments in time order.
fn merged(a: impl IntoIterator<Item = SegmentModel>, b: Vec<SegmentModel>) -> Vec<SegmentModel> {
    let mut all: Vec<SegmentModel> = a.into_iter().chain(b).collect();
    all.sort_by_key(|s| s.start);
    all
}

/// `values` read at frame `x` (a line between the frames around it),
/// rounded.
fn read_at(values: &[i32], x: f64) -> i32 {
    let last = values.len().saturating_sub(1);
    let i = (x.max(0.0).floor() as usize).min(last);
    let w = (x - i as f64).clamp(0.0, 1.0);
    let (a, b) = (f64::from(values[i]), f64::from(values[(i + 1).min(last)]));
    (a + w * (b - a)).round() as i32
}
