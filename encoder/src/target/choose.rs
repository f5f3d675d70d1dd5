//! `encode --target CHIP --budget …`: of the clips each codec made, the
//! smallest whose predicted cost fits the budget and the chip.

use super::budget::Budget;
use super::chips::Chip;
use super::cost::{predict_capacities, CodecKind, Cost};
use crate::codec::index::IndexLayout;
use crate::codec::CodecChoice;
use crate::encode::Encoded;

/// One codec's clip, judged.
#[derive(Debug)]
pub struct Candidate {
    /// The codec and layout (`index`, `index-fast`, `pca-spline`, …).
    pub label: &'static str,
    /// The clip, or why the codec could not make one within the bound.
    pub encoded: Result<Encoded, String>,
    /// Predicted cost on the chip (or why there is none), for the player
    /// capacity chosen: of those that fit, the fewest instructions; the
    /// largest when none fits.
    pub cost: Result<Cost, String>,
    /// What goes over the budget or the chip; empty when it fits.
    pub overruns: Vec<String>,
}

impl Candidate {
    pub fn fits(&self) -> bool {
        self.encoded.is_ok() && self.cost.is_ok() && self.overruns.is_empty()
    }
}

/// The name a candidate is shown by: the codec's, the cost model's
/// `index-fast` for `index` in its fast layout.
pub fn candidate_label(codec: CodecChoice, layout: IndexLayout) -> &'static str {
    match (codec, layout) {
        (CodecChoice::Index, IndexLayout::Fast) => CodecKind::IndexFast.name(),
        (c, _) => c.name(),
    }
}

/// Of one clip's costs (one per player capacity), the one that fits with
/// the fewest instructions (the smaller state of equals), else the largest
/// capacity's.
pub fn best_capacity(costs: Vec<Cost>, budget: &Budget) -> Result<Cost, String> {
    let fitting = costs
        .iter()
        .filter(|c| budget.overruns(c).is_empty())
        .min_by(|a, b| {
            a.instructions_per_pose
                .total_cmp(&b.instructions_per_pose)
                .then(a.state_words.cmp(&b.state_words))
        })
        .cloned();
    fitting
        .or_else(|| costs.last().cloned())
        .ok_or_else(|| "no cost".to_string())
}

/// Judges every codec's result on `chip` under `budget`; returns them with
/// the index of the smallest clip that fits (the first of equal sizes).
pub fn choose<E: std::fmt::Display>(
    results: impl IntoIterator<Item = (&'static str, Result<Encoded, E>)>,
    chip: &'static Chip,
    budget: &Budget,
) -> (Vec<Candidate>, Option<usize>) {
    let candidates: Vec<Candidate> = results
        .into_iter()
        .map(|(label, encoded)| {
            let encoded = encoded.map_err(|e| e.to_string());
            let cost = match &encoded {
                Ok(e) => predict_capacities(&e.bytes, chip)
                    .map_err(|e| e.to_string())
                    .and_then(|costs| best_capacity(costs, budget)),
                Err(e) => Err(e.to_string()),
            };
            let overruns = cost.as_ref().map_or(Vec::new(), |c| budget.overruns(c));
            Candidate {
                label,
                encoded,
                cost,
                overruns,
            }
        })
        .collect();
    let best = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.fits())
        .min_by_key(|(i, c)| (c.encoded.as_ref().map_or(usize::MAX, |e| e.bytes.len()), *i))
        .map(|(i, _)| i);
    (candidates, best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::{encode, Bound, BoundSpec, EncodeOptions};
    use crate::generate::animatronic_demo;
    use crate::target::CANDIDATE_CODECS;
    use crate::target::{chip, Features};

    /// Every codec's clip of the demo, `index` in both layouts.
    fn results() -> Vec<(&'static str, Result<Encoded, crate::encode::EncodeError>)> {
        let m = animatronic_demo();
        CANDIDATE_CODECS
            .iter()
            .map(|&codec| (codec, IndexLayout::Compact))
            .chain([(CodecChoice::Index, IndexLayout::Fast)])
            .map(|(codec, index_layout)| {
                let opts = EncodeOptions {
                    key_bits: None,
                    codec,
                    bound: Bound::from_specs(&[BoundSpec::Degrees(1.0)]),
                    metres_per_unit: crate::units::detect(&m).metres(),
                    key_interval: None,
                    index_layout,
                    pattern: Default::default(),
                };
                (candidate_label(codec, index_layout), encode(&m, &opts))
            })
            .collect()
    }

    #[test]
    fn features_name_the_codec_and_every_input() {
        let mut kinds = Vec::new();
        for (label, r) in results() {
            let bytes = r.unwrap().bytes;
            let f = Features::of(&bytes).unwrap();
            assert_eq!(f.codec.name(), label);
            kinds.push(f.codec);
            assert_eq!(f.x.len(), f.codec.feature_names().len());
            assert_eq!((f.x[0], f.x[1]), (1.0, f.channels as f64));
            assert!(f.state_words >= f.channels);
            assert!(f.x.iter().all(|v| v.is_finite() && *v >= 0.0));
        }
        kinds.sort();
        assert_eq!(kinds, CodecKind::ALL);
        assert!(Features::of(b"not a clip").is_err());
    }

    #[test]
    fn a_ram_budget_takes_a_smaller_pca_spline_player() {
        let (_, pca) = results().swap_remove(1);
        let bytes = pca.unwrap().bytes;
        let chip = chip("microbit").unwrap();
        let costs = crate::target::predict_capacities(&bytes, chip).unwrap();
        assert!(costs.len() >= 2, "{costs:?}");
        for w in costs.windows(2) {
            // More cache: more state, never more instructions.
            assert!(w[0].state_words < w[1].state_words);
            assert!(w[0].instructions_per_pose >= w[1].instructions_per_pose);
        }
        let (small, full) = (costs[0].clone(), costs[costs.len() - 1].clone());
        assert!(small.instructions_per_pose > full.instructions_per_pose);
        let ram = |bytes| Budget {
            ram: Some(bytes),
            ..Budget::default()
        };
        // Room for every group: the fewest instructions, in the least state that has them.
        let best = best_capacity(costs.clone(), &ram(full.ram_bytes())).unwrap();
        assert_eq!(best.instructions_per_pose, full.instructions_per_pose);
        assert!(best.state_words <= full.state_words);
        let best = best_capacity(costs.clone(), &ram(small.ram_bytes())).unwrap();
        assert_eq!(best.state_words, small.state_words);
        // Nothing fits: the largest, whose overruns the caller reports.
        let best = best_capacity(costs, &ram(small.ram_bytes() - 1)).unwrap();
        assert_eq!(best.state_words, full.state_words);
    }

    #[test]
    fn the_smallest_clip_that_fits_is_chosen() {
        let chip = chip("microbit").unwrap();
        // No budget: the smallest clip (the chip's own flash and RAM are ample).
        let (c, best) = choose(results(), chip, &Budget::default());
        let sizes: Vec<usize> = c
            .iter()
            .map(|c| c.encoded.as_ref().unwrap().bytes.len())
            .collect();
        let smallest = (0..sizes.len()).min_by_key(|&i| (sizes[i], i));
        assert_eq!(best, smallest);
        // A CPU budget between the cheapest and the dearest: only those under it fit.
        let shares: Vec<f64> = c
            .iter()
            .map(|c| c.cost.as_ref().unwrap().cpu_share)
            .collect();
        let lo = shares.iter().copied().fold(f64::MAX, f64::min);
        let budget = Budget {
            cpu: Some(lo * 1.0001),
            ..Budget::default()
        };
        let (c, best) = choose(results(), chip, &budget);
        let best = best.unwrap();
        assert!(c[best].cost.as_ref().unwrap().cpu_share <= lo * 1.0001);
        for (i, cand) in c.iter().enumerate() {
            assert_eq!(
                cand.fits(),
                cand.cost.as_ref().unwrap().cpu_share <= lo * 1.0001,
                "{i}"
            );
        }
        // Nothing fits a budget below the cheapest.
        let budget = Budget {
            cpu: Some(lo * 0.5),
            ..Budget::default()
        };
        let (c, best) = choose(results(), chip, &budget);
        assert_eq!(best, None);
        assert!(c
            .iter()
            .all(|c| c.overruns.iter().any(|o| o.starts_with("cpu "))));
    }
}
