//! `encode --target CHIP --budget …`: of the clips each codec made, the
//! smallest whose predicted cost fits the budget and the chip.

use super::budget::Budget;
use super::chips::Chip;
use super::cost::{predict, Cost};
use crate::codec::CodecChoice;
use crate::encode::{EncodeError, Encoded};

/// One codec's clip, judged.
#[derive(Debug)]
pub struct Candidate {
    pub codec: CodecChoice,
    /// The clip, or why the codec could not make one within the bound.
    pub encoded: Result<Encoded, EncodeError>,
    /// Predicted cost on the chip (or why there is none).
    pub cost: Result<Cost, String>,
    /// What goes over the budget or the chip; empty when it fits.
    pub overruns: Vec<String>,
}

impl Candidate {
    pub fn fits(&self) -> bool {
        self.encoded.is_ok() && self.cost.is_ok() && self.overruns.is_empty()
    }
}

/// Judges every codec's result on `chip` under `budget`; returns them with
/// the index of the smallest clip that fits (the first of equal sizes).
pub fn choose(
    results: impl IntoIterator<Item = (CodecChoice, Result<Encoded, EncodeError>)>,
    chip: &'static Chip,
    budget: &Budget,
) -> (Vec<Candidate>, Option<usize>) {
    let candidates: Vec<Candidate> = results
        .into_iter()
        .map(|(codec, encoded)| {
            let cost = match &encoded {
                Ok(e) => predict(&e.bytes, chip).map_err(|e| e.to_string()),
                Err(e) => Err(e.to_string()),
            };
            let overruns = cost.as_ref().map_or(Vec::new(), |c| budget.overruns(c));
            Candidate {
                codec,
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
    use crate::encode::{encode, Bound, BoundSpec, EncodeOptions, AUTO_CODECS};
    use crate::generate::animatronic_demo;
    use crate::target::{chip, cost::CodecKind, Features};

    fn results() -> Vec<(CodecChoice, Result<Encoded, EncodeError>)> {
        let m = animatronic_demo();
        AUTO_CODECS
            .iter()
            .map(|&codec| {
                let opts = EncodeOptions {
                    codec,
                    bound: Bound::from_specs(&[BoundSpec::Degrees(1.0)]),
                    metres_per_unit: crate::units::detect(&m).metres(),
                    key_interval: None,
                };
                (codec, encode(&m, &opts))
            })
            .collect()
    }

    #[test]
    fn features_name_the_codec_and_every_input() {
        for (codec, r) in results() {
            let bytes = r.unwrap().bytes;
            let f = Features::of(&bytes).unwrap();
            let kind = match codec {
                CodecChoice::Index => CodecKind::Index,
                CodecChoice::PcaSpline => CodecKind::PcaSpline,
                _ => CodecKind::Predictive,
            };
            assert_eq!(f.codec, kind);
            assert_eq!(f.x.len(), kind.feature_names().len());
            assert_eq!((f.x[0], f.x[1]), (1.0, f.channels as f64));
            assert!(f.state_words >= f.channels);
            assert!(f.x.iter().all(|v| v.is_finite() && *v >= 0.0));
        }
        assert!(Features::of(b"not a clip").is_err());
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
