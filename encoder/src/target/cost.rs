//! What a clip costs the chip that plays it, predicted from the clip's
//! structure: instructions per pose (a linear model per core and codec,
//! fitted to QEMU instruction counts by `scripts/cost.sh`), the player's
//! state, the caller's pose, the playback path's stack, and flash.

use std::fmt;

use mocap_decoder::pca_spline_cache::{CACHE_HEAD, GROUP_HEAD, INTERVAL};
use mocap_decoder::{consts, Clip};

use super::calibration;
use super::chips::{Chip, Core};
use crate::codec::{index, pca_spline, predictive, rma};

/// The codec a clip is coded with, as the cost model sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CodecKind {
    Index,
    PcaSpline,
    Predictive,
    /// `index` in its fast layout (SPEC.md §4.6, section `0x13`).
    IndexFast,
    /// `rma` (SPEC.md §12): a `pca-spline` body evaluated at `t`, and again
    /// at `Ref(t)` in a repeated clip.
    Rma,
}

/// The `pca-spline` features (the first ten of `rma`'s: its body's).
const PCA_FEATURES: usize = 10;

impl CodecKind {
    pub const ALL: [CodecKind; 5] = [
        CodecKind::Index,
        CodecKind::PcaSpline,
        CodecKind::Predictive,
        CodecKind::IndexFast,
        CodecKind::Rma,
    ];

    pub fn name(self) -> &'static str {
        match self {
            CodecKind::Index => "index",
            CodecKind::PcaSpline => "pca-spline",
            CodecKind::Predictive => "predictive",
            CodecKind::IndexFast => "index-fast",
            CodecKind::Rma => "rma",
        }
    }

    /// `rma`'s features: its body's evaluations at `t` and at `Ref(t)` as
    /// `pca-spline`'s (weighted by the poses that make each), then what a
    /// repeated pose adds.
    const RMA_FEATURES: [&'static str; PCA_FEATURES + 3] = [
        "1",
        "channels",
        "cached: sum of k",
        "cached: groups",
        "uncached: sum of channels x k",
        "uncached: groups",
        "uncached: sum of k",
        "constants not cached (zigzag varints read per pose)",
        "key intervals entered x k per pose",
        "cached, k > 8: sum of channels x k",
        "repeated poses",
        "repeated poses x added channels",
        "repeated poses whose scratch is laid over t's cache",
    ];

    /// What each entry of [`Features::x`] is, for the fit's report.
    pub fn feature_names(self) -> &'static [&'static str] {
        match self {
            CodecKind::Index => &[
                "1",
                "channels",
                "delta-coded channels",
                "delta groups",
                "key channel levels / key interval",
                "key groups / key interval",
                "payload bits per pose / 32",
            ],
            CodecKind::PcaSpline => &Self::RMA_FEATURES[..PCA_FEATURES],
            CodecKind::Rma => &Self::RMA_FEATURES,
            CodecKind::IndexFast => &[
                "1",
                "channels",
                "groups per pose",
                "width-0 channels per pose",
                "width 1/2/4 channels per pose",
                "width 8/16 channels per pose",
                "key frames x channels per pose (the clear)",
            ],
            CodecKind::Predictive => &[
                "1",
                "channels",
                "coded channels",
                "payload bits per pose / 32",
                "block starts x coded channels per pose",
            ],
        }
    }
}

impl fmt::Display for CodecKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A clip's structure, the inputs of the cost model.
#[derive(Clone, Debug, PartialEq)]
pub struct Features {
    pub codec: CodecKind,
    pub channels: usize,
    pub frames: u32,
    pub frame_rate_hz: f64,
    pub clip_bytes: usize,
    /// Words of the player's state (`Player<N>`): what the clip needs, or
    /// the capacity the features were taken for.
    pub state_words: usize,
    /// The capacities worth a player for this clip, smallest first: one for
    /// `index` and `predictive` (what they need); for `pca-spline` every `N`
    /// at which one more group's slot fits (from the channel count up to
    /// caching every group; at most 16 of them), a trade of RAM for
    /// instructions.
    pub capacities: Vec<usize>,
    /// The model's inputs, per pose ([`CodecKind::feature_names`]).
    pub x: Vec<f64>,
}

/// Why a clip has no cost figures.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FeatureError {
    #[error("not a clip: {0}")]
    Parse(String),
    #[error("the clip has no codec section the cost model knows (a show or a newer codec)")]
    NoCodec,
}

impl Features {
    /// The structure of the clip `bytes`, played by a player whose state
    /// holds everything the clip can use (`pca-spline`: every group cached).
    pub fn of(bytes: &[u8]) -> Result<Features, FeatureError> {
        Features::with_capacity(bytes, None)
    }

    /// The structure of the clip `bytes` played by a `Player<N>` of
    /// `capacity = Some(N)` words (`pca-spline` caches the groups that fit).
    pub fn with_capacity(bytes: &[u8], capacity: Option<usize>) -> Result<Features, FeatureError> {
        let clip = Clip::parse(bytes).map_err(|e| FeatureError::Parse(e.to_string()))?;
        let h = clip.header();
        let channels = h.channel_count();
        let frames = h.frame_count();
        let f = f64::from(frames.max(1));
        let c = channels as f64;
        let frame_rate_hz = 1e9 / f64::from(h.frame_time_ns().max(1));
        let mut out = Features {
            codec: CodecKind::Index,
            channels,
            frames,
            frame_rate_hz,
            clip_bytes: bytes.len(),
            state_words: channels,
            capacities: Vec::new(),
            x: Vec::new(),
        };
        for sec in clip.sections() {
            match sec.id {
                consts::SECTION_CODEC_INDEX => {
                    let s = index::inspect(sec.bytes).ok_or(FeatureError::NoCodec)?;
                    let per = s.per_channel(channels);
                    let k = f64::from(s.key_interval);
                    let (delta_channels, delta_groups, key_levels, key_groups) =
                        if s.key_interval == 0 {
                            // Every frame from the key set.
                            let levels: usize = per.iter().map(|d| usize::from(d.key_levels)).sum();
                            (levels as f64, s.key.len() as f64, 0.0, 0.0)
                        } else {
                            let levels: usize = per.iter().map(|d| usize::from(d.key_levels)).sum();
                            (
                                per.iter().filter(|d| d.delta_bits.is_some()).count() as f64,
                                s.delta.len() as f64,
                                levels as f64 / k,
                                s.key.len() as f64 / k,
                            )
                        };
                    out.codec = CodecKind::Index;
                    out.capacities = vec![channels];
                    out.x = vec![
                        1.0,
                        c,
                        delta_channels,
                        delta_groups,
                        key_levels,
                        key_groups,
                        s.payload_bytes as f64 * 8.0 / f / 32.0,
                    ];
                    return Ok(out);
                }
                consts::SECTION_CODEC_INDEX_FAST => {
                    let s = index::inspect_fast(sec.bytes).ok_or(FeatureError::NoCodec)?;
                    out.codec = CodecKind::IndexFast;
                    out.capacities = vec![channels];
                    out.x = fast_index_features(&s, channels, frames);
                    return Ok(out);
                }
                consts::SECTION_CODEC_PCA_SPLINE => {
                    let s = pca_spline::inspect(sec.bytes).ok_or(FeatureError::NoCodec)?;
                    let need = pca_cache_words(&s).max(channels);
                    let words = capacity.unwrap_or(need);
                    out.state_words = words;
                    out.capacities = pca_capacities(&s, channels, need);
                    out.codec = CodecKind::PcaSpline;
                    out.x = pca_features(&s, channels, f, words);
                    return Ok(out);
                }
                consts::SECTION_CODEC_RMA => {
                    let s = rma::section::inspect(sec.bytes).ok_or(FeatureError::NoCodec)?;
                    let body = pca_cache_words(&s.body);
                    let least = RMA_CURSOR_WORDS + channels;
                    // Every group cached at `t` (and at `Ref(t)` beside the
                    // scratch pose if the clip repeats).
                    let need = if s.clips.is_empty() {
                        RMA_CURSOR_WORDS + body.max(channels)
                    } else {
                        least + 2 * body
                    };
                    let words = capacity.unwrap_or(need);
                    out.state_words = words;
                    out.capacities = pca_capacities(&s.body, 0, need - least)
                        .into_iter()
                        .map(|w| w + least)
                        .collect();
                    out.codec = CodecKind::Rma;
                    out.x = rma_features(&s, channels, f, words);
                    return Ok(out);
                }
                consts::SECTION_CODEC_PREDICTIVE => {
                    let s = predictive::inspect(sec.bytes).ok_or(FeatureError::NoCodec)?;
                    out.codec = CodecKind::Predictive;
                    out.state_words = s.state_words.max(channels);
                    out.capacities = vec![out.state_words];
                    out.x = vec![
                        1.0,
                        c,
                        s.coded as f64,
                        s.payload_bytes as f64 * 8.0 / f / 32.0,
                        f64::from(s.blocks) * s.coded as f64 / f,
                    ];
                    return Ok(out);
                }
                _ => {}
            }
        }
        Err(FeatureError::NoCodec)
    }
}

/// The fast layout's features (SPEC.md §4.6): a pose runs the key set on
/// a key frame (after clearing the state) and the delta set on the others,
/// each group a loop by its width; the key sets weigh `keys / frames`.
fn fast_index_features(s: &index::SectionInfo, channels: usize, frames: u32) -> Vec<f64> {
    let f = f64::from(frames.max(1));
    let key_weight = if s.key_interval == 0 {
        1.0
    } else {
        f64::from(frames.div_ceil(u32::from(s.key_interval))) / f
    };
    // A key frame also clears the state: a store per channel.
    let clear = key_weight * channels as f64;
    let mut x = vec![1.0, channels as f64, 0.0, 0.0, 0.0, 0.0, clear];
    for (groups, w) in [(&s.key, key_weight), (&s.delta, 1.0 - key_weight)] {
        for g in groups {
            let n = g.channels.len() as f64;
            x[2] += w;
            let col = match g.bits {
                0 => 3,
                1 | 2 | 4 => 4,
                _ => 5,
            };
            x[col] += w * n;
        }
    }
    x
}

/// Cache words a segment's groups take (SPEC.md §6, `pca_spline_cache`).
fn slot_words(n: usize, k: usize) -> usize {
    if k == 0 {
        GROUP_HEAD + n
    } else {
        GROUP_HEAD + INTERVAL + 4 * k
    }
}

/// Player state words that cache every group and the constants of every
/// segment of a `pca-spline` clip.
fn pca_cache_words(s: &pca_spline::SectionInfo) -> usize {
    s.segments
        .iter()
        .map(|(_, _, per)| {
            let slots: usize = s
                .group_channels
                .iter()
                .zip(per)
                .map(|(&n, &(k, _))| slot_words(n, k))
                .sum();
            CACHE_HEAD + slots + s.consts
        })
        .max()
        .unwrap_or(CACHE_HEAD)
}

/// The capacities at which a `pca-spline` player caches one more group of
/// some segment (its slots are taken in order), from `channels` (the least
/// a player holds) to `need` (every group and the constants): at most 16,
/// evenly picked, always both ends.
fn pca_capacities(s: &pca_spline::SectionInfo, channels: usize, need: usize) -> Vec<usize> {
    let mut all = vec![channels, need];
    for (_, _, per) in &s.segments {
        let mut words = CACHE_HEAD;
        for (&n, &(k, _)) in s.group_channels.iter().zip(per) {
            words += slot_words(n, k);
            all.push(words.clamp(channels, need));
        }
    }
    all.sort_unstable();
    all.dedup();
    if all.len() <= 16 {
        return all;
    }
    let last = all.len() - 1;
    let mut picked: Vec<usize> = (0..16).map(|i| all[i * last / 15]).collect();
    picked.dedup();
    picked
}

/// The `pca-spline` features with a cache of `words` words: the groups of
/// each segment are cached in order while their slots fit (as the
/// player's `prepare`), the rest decoded from their records on every pose
/// (some 2 300 instructions a group on the M0 and 1 000 more a component),
/// and the constants cached after the slots if they fit, else decoded on
/// every pose. Chosen by their fit on the calibration clips (BENCHMARKS.md
/// §2).
fn pca_features(
    s: &pca_spline::SectionInfo,
    channels: usize,
    frames: f64,
    words: usize,
) -> Vec<f64> {
    pca_features_weighted(s, channels, words, |start, end| {
        f64::from(end.saturating_sub(start) + 1) / frames
    })
}

/// [`pca_features`] of evaluations made on each segment `(start, end)`
/// `weight(start, end)` times per pose (`pca-spline`: its share of the
/// frames; `rma`'s evaluations at `Ref(t)`: the share of the poses whose
/// reference falls there).
fn pca_features_weighted(
    s: &pca_spline::SectionInfo,
    channels: usize,
    words: usize,
    weight: impl Fn(u32, u32) -> f64,
) -> Vec<f64> {
    let mut evaluations = 0.0;
    let (mut cached_k, mut uncached_nk, mut uncached_groups, mut entered) = (0.0, 0.0, 0.0, 0.0);
    let (mut cached_groups, mut uncached_k) = (0.0, 0.0);
    // The constants are cached after the slots if they fit there, else
    // decoded from the clip on every pose.
    let mut uncached_consts = 0.0;
    // Groups of more components than the player's specialised loops (k ≤ 8)
    // take its generic one, slower per channel and component.
    let mut generic_nk = 0.0;
    for (start, end, per) in &s.segments {
        let w = weight(*start, *end);
        evaluations += w;
        let length = f64::from(end.saturating_sub(*start) + 1);
        let mut free = words.saturating_sub(CACHE_HEAD);
        let mut fits = true;
        for (&n, &(k, m)) in s.group_channels.iter().zip(per) {
            let size = slot_words(n, k);
            fits = fits && size <= free;
            if fits {
                free -= size;
                cached_k += w * k as f64;
                cached_groups += w;
                if k > 8 {
                    generic_nk += w * (n * k) as f64;
                }
            } else {
                // An uncached group parses its record (n means, k component
                // descriptors), finds its key interval and reads four key rows
                // of k components, then n x k basis products.
                uncached_nk += w * (n * k) as f64;
                uncached_groups += w;
                uncached_k += w * k as f64;
            }
            entered += w * (m * k) as f64 / length;
        }
        if s.consts > free {
            uncached_consts += w * s.consts as f64;
        }
    }
    vec![
        evaluations,
        evaluations * channels as f64,
        cached_k,
        cached_groups,
        uncached_nk,
        uncached_groups,
        uncached_k,
        uncached_consts,
        entered,
        generic_nk,
    ]
}

/// Words of the player's state `rma` keeps before its scratch pose.
const RMA_CURSOR_WORDS: usize = mocap_decoder::rma::CURSOR_WORDS;

/// The `rma` features with `words` words of state, the words split as the
/// decoder splits them (`RmaCodec::decode_at`): the cursor, then with room
/// for the scratch pose and `t`'s whole cache both, those and the rest for
/// `Ref(t)`; without, in a clip at most a quarter repeated, `t`'s cache
/// first with the scratch laid over it (refilled after a repeated pose);
/// without repeated clips, every word for `t`.
fn rma_features(
    s: &rma::section::SectionInfo,
    channels: usize,
    frames: f64,
    words: usize,
) -> Vec<f64> {
    let body = &s.body;
    let len = words.saturating_sub(RMA_CURSOR_WORDS);
    if s.clips.is_empty() {
        let mut x = pca_features(body, channels, frames, len);
        x.extend([0.0; 3]);
        return x;
    }
    let t_cache = pca_cache_words(body);
    let overlay = s.repeated_frames as f64 * 4.0 <= frames && len < channels + t_cache;
    let (t_words, ref_words) = if overlay {
        let t = t_cache.min(len);
        (t, len.saturating_sub(t.max(channels)))
    } else {
        let t = t_cache.min(len.saturating_sub(channels));
        (t, len.saturating_sub(channels + t))
    };
    let mut x = pca_features(body, channels, frames, t_words);
    // Where the references fall: poses per segment (its primary frames).
    let starts: Vec<u32> = body.segments.iter().map(|(a, _, _)| *a).collect();
    let mut at_ref = vec![0.0; starts.len()];
    for c in &s.clips {
        for t in 0..=c.last.saturating_sub(c.start) {
            let r = c.reference_at(t).max(0.0) as u32;
            let seg = starts.partition_point(|&a| a <= r).saturating_sub(1);
            if let Some(n) = at_ref.get_mut(seg) {
                *n += 1.0 / frames;
            }
        }
    }
    let by_start = |start: u32| {
        starts
            .binary_search(&start)
            .ok()
            .and_then(|i| at_ref.get(i).copied())
            .unwrap_or(0.0)
    };
    let at_ref_x = pca_features_weighted(body, channels, ref_words, |start, _| by_start(start));
    for (x, r) in x.iter_mut().zip(&at_ref_x) {
        *x += r;
    }
    let repeated = s.repeated_frames as f64 / frames;
    x.extend([
        repeated,
        repeated * s.added as f64,
        if overlay { repeated } else { 0.0 },
    ]);
    x
}

/// A core's figures for one codec (generated into [`calibration`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    pub core: Core,
    pub codec: CodecKind,
    /// Instructions per pose = `coefficients · x`.
    pub coefficients: &'static [f64],
}

/// Peak stack of the playback path of `codec` on `core` (`next_frame` and
/// what it calls), the most measured by `scripts/cost.sh`.
pub fn playback_stack_bytes(core: Core, codec: CodecKind) -> Option<usize> {
    calibration::PLAYBACK_STACK_BYTES
        .iter()
        .find(|(c, k, _)| *c == core && *k == codec)
        .map(|&(_, _, b)| b as usize)
}

/// The model of `codec` on `core`, and the core it was fitted on (a core
/// without measurements borrows the nearest one's: the M4F the M3's).
pub fn model(core: Core, codec: CodecKind) -> Option<(&'static Model, Core)> {
    let fitted = |codec: CodecKind| {
        let find = |c: Core| {
            calibration::MODELS
                .iter()
                .find(|m| m.core == c && m.codec == codec)
        };
        find(core).map(|m| (m, core)).or_else(|| match core {
            Core::M4F => find(Core::M3).map(|m| (m, Core::M3)),
            _ => None,
        })
    };
    // Before `rma` rows are measured, its body's evaluations alone, read by
    // `pca-spline`'s model (its first features are `pca-spline`'s).
    fitted(codec).or_else(|| match codec {
        CodecKind::Rma => fitted(CodecKind::PcaSpline),
        _ => None,
    })
}

/// The player's state in bytes for `state_words` words on a 32-bit core:
/// `size_of::<Player<N>>()` with `N = state_words`.
pub fn state_bytes(state_words: usize) -> usize {
    // The player holds 64-bit fields (8-byte aligned on these cores): an
    // odd number of words is padded.
    (calibration::PLAYER_FIXED_BYTES + 4 * state_words).next_multiple_of(8)
}

/// Predicted cost of a clip on a chip.
#[derive(Clone, Debug, PartialEq)]
pub struct Cost {
    pub chip: &'static Chip,
    /// The core whose measurements the prediction comes from.
    pub model_core: Core,
    /// Instructions per decoded pose (`next_frame`).
    pub instructions_per_pose: f64,
    /// Poses per second: the clip's frame rate (the player decodes every
    /// frame it passes, also under `sample_at` at a lower servo rate).
    pub poses_per_second: f64,
    /// Share of the core at its clock, one instruction per cycle.
    pub cpu_share: f64,
    /// `N` of the `Player<N>` the prediction is for.
    pub state_words: usize,
    pub state_bytes: usize,
    /// The caller's pose (4 bytes per channel).
    pub pose_bytes: usize,
    pub playback_stack_bytes: usize,
    /// Clip plus the decoder's code.
    pub flash_bytes: usize,
}

impl Cost {
    /// State + pose + playback stack: the RAM playing the clip takes.
    pub fn ram_bytes(&self) -> usize {
        self.state_bytes + self.pose_bytes + self.playback_stack_bytes
    }
}

/// Why a cost cannot be predicted.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CostError {
    #[error(transparent)]
    Features(#[from] FeatureError),
    #[error("no cost model of {codec} on the {core} (run scripts/cost.sh --write)")]
    NoModel { core: Core, codec: CodecKind },
}

/// The cost of the clip `bytes` on `chip`.
pub fn predict(bytes: &[u8], chip: &'static Chip) -> Result<Cost, CostError> {
    predict_features(&Features::of(bytes)?, chip)
}

/// The cost of the clip `bytes` on `chip` for each capacity worth a player
/// ([`Features::capacities`]), smallest state first.
pub fn predict_capacities(bytes: &[u8], chip: &'static Chip) -> Result<Vec<Cost>, CostError> {
    let full = Features::of(bytes)?;
    full.capacities
        .iter()
        .map(|&n| predict_features(&Features::with_capacity(bytes, Some(n))?, chip))
        .collect()
}

/// The cost of a clip of features `f` on `chip`.
pub fn predict_features(f: &Features, chip: &'static Chip) -> Result<Cost, CostError> {
    let (m, model_core) = model(chip.core, f.codec).ok_or(CostError::NoModel {
        core: chip.core,
        codec: f.codec,
    })?;
    let per_pose = instructions(m.coefficients, &f.x);
    let cpu_share = per_pose * f.frame_rate_hz / f64::from(chip.clock_hz.max(1));
    Ok(Cost {
        chip,
        model_core,
        instructions_per_pose: per_pose,
        poses_per_second: f.frame_rate_hz,
        cpu_share,
        state_words: f.state_words,
        state_bytes: state_bytes(f.state_words),
        pose_bytes: 4 * f.channels,
        playback_stack_bytes: playback_stack_bytes(chip.core, f.codec)
            .or_else(|| playback_stack_bytes(model_core, f.codec))
            .unwrap_or(0),
        flash_bytes: f.clip_bytes
            + decoder_code_bytes(chip.core).unwrap_or(decoder_code_bytes(model_core).unwrap_or(0)),
    })
}

/// `coefficients · x`, never below one instruction per channel's copy.
pub fn instructions(coefficients: &[f64], x: &[f64]) -> f64 {
    let dot: f64 = coefficients.iter().zip(x).map(|(a, b)| a * b).sum();
    // x[1] is the channel count for every codec: at least the copy.
    dot.max(x.get(1).copied().unwrap_or(1.0))
}

/// The decoder's code on `core` (every codec linked), as measured.
pub fn decoder_code_bytes(core: Core) -> Option<usize> {
    calibration::DECODER_CODE_BYTES
        .iter()
        .find(|(c, _)| *c == core)
        .map(|&(_, b)| b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn golden(name: &str) -> Vec<u8> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/golden")
            .join(name);
        std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// The section of `id` in the clip `bytes`.
    fn section(bytes: &[u8], id: u8) -> Vec<u8> {
        let clip = Clip::parse(bytes).unwrap();
        let s = clip.sections().find(|s| s.id == id).unwrap();
        s.bytes.to_vec()
    }

    /// An `rma` clip without repeated clips is its body: `pca-spline`'s
    /// features of the body with the player's words less the cursor, and
    /// nothing for repeated poses.
    #[test]
    fn rma_without_repeats_is_its_body() {
        let bytes = golden("rma_demo_20mm.mcb");
        let s = rma::section::inspect(&section(&bytes, consts::SECTION_CODEC_RMA)).unwrap();
        assert!(s.clips.is_empty());
        let f = Features::of(&bytes).unwrap();
        assert_eq!(f.codec, CodecKind::Rma);
        assert_eq!(f.x.len(), CodecKind::Rma.feature_names().len());
        let frames = f64::from(f.frames);
        for words in f.capacities.iter().copied().chain([f.channels + 2, 700]) {
            let x = Features::with_capacity(&bytes, Some(words)).unwrap().x;
            let body = pca_features(&s.body, f.channels, frames, words - RMA_CURSOR_WORDS);
            assert_eq!(x[..PCA_FEATURES], body[..], "{words} words");
            assert_eq!(x[PCA_FEATURES..], [0.0; 3], "{words} words");
        }
    }

    /// A repeated clip adds a body evaluation at `Ref(t)` per repeated
    /// pose and the terms of repeated poses; more words never add work.
    #[test]
    fn rma_repeated_poses_evaluate_the_body_twice() {
        let bytes = golden("rma_demo_twice_20mm.mcb");
        let s = rma::section::inspect(&section(&bytes, consts::SECTION_CODEC_RMA)).unwrap();
        let f = Features::of(&bytes).unwrap();
        let share = s.repeated_frames as f64 / f64::from(f.frames);
        assert_eq!(share, 0.5);
        // Every group cached: one evaluation per pose, and one more per
        // repeated pose; no scratch over `t`'s cache.
        let near = |a: f64, b: f64| (a - b).abs() < 1e-9 * b.abs().max(1.0);
        assert!(near(f.x[0], 1.0 + share), "{:?}", f.x);
        assert!(near(f.x[1], (1.0 + share) * f.channels as f64), "{:?}", f.x);
        assert_eq!(f.x[PCA_FEATURES..], [share, share * s.added as f64, 0.0]);
        assert_eq!(f.state_words, *f.capacities.last().unwrap());
        assert_eq!(f.capacities[0], f.channels + RMA_CURSOR_WORDS);
        let chip = super::super::chip("lm3s6965").unwrap();
        let costs = super::super::predict_capacities(&bytes, chip).unwrap();
        for w in costs.windows(2) {
            assert!(w[0].state_words < w[1].state_words);
            assert!(w[0].instructions_per_pose >= w[1].instructions_per_pose);
        }
        // Half the poses repeated: more than the body alone at the same player.
        let body = instructions(
            model(Core::M3, CodecKind::PcaSpline)
                .unwrap()
                .0
                .coefficients,
            &pca_features(
                &s.body,
                f.channels,
                f64::from(f.frames),
                f.state_words - RMA_CURSOR_WORDS,
            ),
        );
        assert!(costs.last().unwrap().instructions_per_pose > 1.4 * body);
    }
}
