//! Shows (SPEC.md §9): a show file ([`file::ShowSpec`]) of clips cut from
//! BVH files, encoded each with its codec and bound (the single-clip
//! pipeline, proven by decoding), then assembled into one version-2 file
//! with the header and rig once, the show table and the cue section
//! ([`wire`]). Every clip of the built show decodes to exactly what its
//! single clip decodes to (checked before anything is written).

pub mod file;
pub mod play;
pub mod wire;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use mocap_decoder::{consts, Clip, Loop, Show, ShowPlayer};

use crate::bvh::BvhError;
use crate::clipfile;
use crate::codec::CodecChoice;
use crate::container::{assemble_version, HeaderWire};
use crate::encode::{self, EncodeError, EncodeOptions};
use crate::located::LocatedError;
use crate::motion::Motion;
use crate::rig::{Rig, RigError};
use crate::servo_clip::{self, ServoClipError, ServoEncodeOptions, ServoNames, ServoRate};
use crate::units::{self, LengthUnit};
use file::{ClipSpec, Mark, ShowSpec};
use wire::TableRow;

/// Most channels a show may have (the host's show player's capacity).
pub const MAX_CHANNELS: usize = 1024;
/// Player state words of the host's show player.
pub const PLAYER_WORDS: usize = 4096;

/// The host's show player: room for every show the encoder builds.
pub type HostShowPlayer<'a> = ShowPlayer<'a, PLAYER_WORDS, MAX_CHANNELS>;

/// Why a show could not be built.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ShowError {
    /// The show file is wrong (file, line, column).
    #[error(transparent)]
    File(#[from] LocatedError),
    /// A clip's BVH file is wrong.
    #[error(transparent)]
    Bvh(#[from] BvhError),
    /// A clip's AMC/ASF source is wrong (or has no skeleton beside it).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    /// A clip's frames or loop points are out of its source.
    #[error("{file}: clip `{clip}`: {message}")]
    Range {
        /// The show file.
        file: String,
        /// The clip.
        clip: String,
        /// What is wrong.
        message: String,
    },
    /// Two clips' sources have different channels.
    #[error("clip `{clip}` ({other}) does not have the channels of clip `{first_clip}` ({first}): {detail}")]
    Channels {
        /// The first clip.
        first_clip: String,
        /// Its source.
        first: String,
        /// The clip that differs.
        clip: String,
        /// Its source.
        other: String,
        /// The first difference.
        detail: String,
    },
    /// A clip could not be encoded.
    #[error("clip `{clip}` ({file}): {source}")]
    Encode {
        /// The clip.
        clip: String,
        /// Its source.
        file: String,
        /// Why (boxed: an encode error carries the bound).
        source: Box<EncodeError>,
    },
    /// A servo clip could not be encoded.
    #[error("clip `{clip}` ({file}): {source}")]
    Servo {
        /// The clip.
        clip: String,
        /// Its source.
        file: String,
        /// Why (boxed: it may carry an encode error and its bound).
        source: Box<ServoClipError>,
    },
    /// The rig of a servo show is wrong.
    #[error(transparent)]
    Rig(RigError),
    /// The rig's channels are not in a clip's source.
    #[error("clip `{clip}`: {source}")]
    RigChannels {
        /// The clip.
        clip: String,
        /// Why.
        source: RigError,
    },
    /// More channels than a show player holds.
    #[error("{channels} channels; a show holds at most {MAX_CHANNELS}")]
    TooManyChannels {
        /// Channels of the clips.
        channels: usize,
    },
    /// The decoder refused the built show, or a clip decodes differently
    /// from its single clip (a bug).
    #[error("internal error: {0}")]
    Internal(String),
}

/// The seam of a looping clip, measured on the show player.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeamCheck {
    /// Largest step per coded frame across the seam: rotations (degrees),
    /// translations (mm).
    pub seam_step: [f64; 2],
    /// The clip's own largest frame-to-frame step, same units.
    pub clip_step: [f64; 2],
}

impl SeamCheck {
    /// True when no step across the seam exceeds the clip's own largest.
    pub fn holds(&self) -> bool {
        self.seam_step[0] <= self.clip_step[0] + 1e-9
            && self.seam_step[1] <= self.clip_step[1] + 1e-9
    }
}

/// One clip of a built show.
#[derive(Clone, Debug)]
pub struct BuiltClip {
    /// Its name.
    pub name: String,
    /// Its source.
    pub source: PathBuf,
    /// Source frames cut (first, last, inclusive).
    pub source_frames: (usize, usize),
    /// Codec used.
    pub codec: CodecChoice,
    /// Coded frames.
    pub frames: u32,
    /// Bytes of the clip as a single `.mcb` file (a clip that shares a
    /// pattern database: with the whole database in its section).
    pub single_bytes: usize,
    /// It reads a pattern database shared with other clips (§11.2).
    pub shares_database: bool,
    /// Bytes of its codec section in the show.
    pub codec_bytes: usize,
    /// The bound's proof, as `mocap encode` prints it.
    pub proof: String,
    /// Its loop.
    pub looping: Option<Loop>,
    /// Its seam, measured.
    pub seam: Option<SeamCheck>,
}

/// A built show.
#[derive(Clone, Debug)]
pub struct BuiltShow {
    /// The show's `.mcb` bytes.
    pub bytes: Vec<u8>,
    /// Its clips.
    pub clips: Vec<BuiltClip>,
    /// Bytes of each shared section: (id, length), in table order.
    pub sections: Vec<(u8, usize)>,
}

impl BuiltShow {
    /// Sum of the clips as single files.
    pub fn singles_bytes(&self) -> usize {
        self.clips.iter().map(|c| c.single_bytes).sum()
    }
}

/// A motion clip of the `pattern` codec waiting to be coded with the
/// others: its number, its cut motion, metres per unit, source range and
/// source frame time.
type PatternClip = (usize, Motion, f64, (usize, usize), f64);

/// A clip encoded alone.
struct Single {
    bytes: Vec<u8>,
    codec: CodecChoice,
    proof: String,
    /// Source frame time, s.
    source_frame_time: f64,
    range: (usize, usize),
}

/// Builds the show `spec` describes.
pub fn build(spec: &ShowSpec) -> Result<BuiltShow, ShowError> {
    build_with(spec, &|_, _, _| Box::new(encode::Silent))
}

/// [`build`], each clip's encode reporting to `progress(clip, clips,
/// name)`.
pub fn build_with<'a>(
    spec: &ShowSpec,
    progress: &dyn Fn(usize, usize, &str) -> Box<dyn encode::Progress + 'a>,
) -> Result<BuiltShow, ShowError> {
    let rig = spec
        .rig
        .as_ref()
        .map(|p| Rig::read_file(p))
        .transpose()
        .map_err(ShowError::Rig)?;
    let mut sources: HashMap<PathBuf, Motion> = HashMap::new();
    // The length unit a source declares (an ASF's), used unless the clip sets one.
    let mut declared: HashMap<PathBuf, LengthUnit> = HashMap::new();
    let mut singles: Vec<Option<Single>> = Vec::new();
    // Motion clips of the `pattern` codec: coded together, one database
    // per bound (§11.2), after the loop.
    let mut patterns: Vec<PatternClip> = Vec::new();
    let mut first: Option<(usize, Vec<String>, f64)> = None;
    for (k, c) in spec.clips.iter().enumerate() {
        if !sources.contains_key(&c.file) {
            let input = crate::input::read_motion(&c.file, None)?;
            if let Some(u) = input.unit {
                declared.insert(c.file.clone(), u);
            }
            sources.insert(c.file.clone(), input.motion);
        }
        let m = &sources[&c.file];
        let range = cut_range(spec, c, m)?;
        let cut = cut(m, range);
        if rig.is_none() {
            let names = m.skeleton.channel_names();
            match &first {
                None => first = Some((k, names, m.frame_time)),
                Some((f, first_names, first_time)) => {
                    let fc = &spec.clips[*f];
                    let differ = |detail: String| ShowError::Channels {
                        first_clip: fc.name.clone(),
                        first: fc.file.display().to_string(),
                        clip: c.name.clone(),
                        other: c.file.display().to_string(),
                        detail,
                    };
                    if let Some(d) = first_difference(first_names, &names) {
                        return Err(differ(d));
                    }
                    if crate::container::frame_time_ns(*first_time)
                        != crate::container::frame_time_ns(m.frame_time)
                    {
                        return Err(differ(format!(
                            "frame time {:.6} s against {:.6} s (a show has one frame rate)",
                            m.frame_time, first_time
                        )));
                    }
                }
            }
        }
        let unit = declared.get(&c.file).copied();
        if rig.is_none() && c.codec == CodecChoice::Pattern {
            let metres = c
                .units
                .or(unit)
                .unwrap_or_else(|| units::detect(&cut))
                .metres();
            patterns.push((k, cut, metres, range, m.frame_time));
            singles.push(None);
            continue;
        }
        let p = progress(k, spec.clips.len(), &c.name);
        let source = Source {
            motion: &cut,
            range,
            frame_time: m.frame_time,
            declared: unit,
        };
        singles.push(Some(encode_one(
            c,
            source,
            rig.as_ref(),
            &spec.pattern,
            p.as_ref(),
        )?));
    }
    let mut databases = Vec::new();
    let mut in_show = vec![None; spec.clips.len()];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, p) in patterns.iter().enumerate() {
        match groups
            .iter_mut()
            .find(|g| spec.clips[patterns[g[0]].0].bound == spec.clips[p.0].bound)
        {
            Some(g) => g.push(i),
            None => groups.push(vec![i]),
        }
    }
    for group in groups {
        let (k0, ..) = patterns[group[0]];
        let c0 = &spec.clips[k0];
        let motions: Vec<&Motion> = group.iter().map(|&i| &patterns[i].1).collect();
        let metres: Vec<f64> = group.iter().map(|&i| patterns[i].2).collect();
        let p = progress(k0, spec.clips.len(), &c0.name);
        let opts = EncodeOptions {
            key_bits: None,
            codec: CodecChoice::Pattern,
            bound: c0.bound,
            metres_per_unit: metres[0],
            key_interval: None,
            index_layout: Default::default(),
            pattern: spec.pattern.clone(),
        };
        let shared = encode::encode_pattern_shared(&motions, &metres, &opts, p.as_ref()).map_err(
            |source| ShowError::Encode {
                clip: c0.name.clone(),
                file: c0.file.display().to_string(),
                source: Box::new(source),
            },
        )?;
        let model = databases.len();
        for ((&i, enc), section) in group.iter().zip(shared.clips).zip(shared.sections) {
            let (k, _, _, range, source_frame_time) = patterns[i];
            let x = &enc.metrics;
            singles[k] = Some(Single {
                proof: format!(
                    "angle max {:.3}°, joint max {:.2} mm (bound {}; pattern database shared by {} clips)",
                    x.angle_max_deg,
                    x.max_joint_err_mm,
                    spec.clips[k].bound,
                    group.len()
                ),
                bytes: enc.bytes,
                codec: CodecChoice::Pattern,
                source_frame_time,
                range,
            });
            in_show[k] = Some((section, model));
        }
        databases.push(shared.database);
    }
    let singles: Vec<Single> = singles.into_iter().flatten().collect();
    assemble_show(spec, &singles, &in_show, &databases)
}

fn first_difference(a: &[String], b: &[String]) -> Option<String> {
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        if x != y {
            return Some(format!("channel {i} is `{y}`, not `{x}`"));
        }
    }
    match a.len().cmp(&b.len()) {
        std::cmp::Ordering::Equal => None,
        std::cmp::Ordering::Less => Some(format!(
            "{} channels, not {} (channel {} is `{}`)",
            b.len(),
            a.len(),
            a.len(),
            b[a.len()]
        )),
        std::cmp::Ordering::Greater => Some(format!(
            "{} channels, not {} (channel {} `{}` is missing)",
            b.len(),
            a.len(),
            b.len(),
            a[b.len()]
        )),
    }
}

/// The source frames of clip `c` (first, last, inclusive).
fn cut_range(spec: &ShowSpec, c: &ClipSpec, m: &Motion) -> Result<(usize, usize), ShowError> {
    let frames = m.frames();
    let bad = |message: String| ShowError::Range {
        file: spec.file.clone(),
        clip: c.name.clone(),
        message,
    };
    if frames == 0 {
        return Err(bad(format!("{} has no frames", c.file.display())));
    }
    let frame_of = |mark: Mark| match mark {
        Mark::Frame(f) => f,
        Mark::Seconds(s) => (s / m.frame_time).round() as usize,
    };
    let from = c.from.map_or(0, frame_of);
    let to = c.to.map_or(frames - 1, frame_of);
    if from > to || to >= frames {
        return Err(bad(format!(
            "frames {from}..={to} are not inside {} ({frames} frames, {:.3} s)",
            c.file.display(),
            frames as f64 * m.frame_time
        )));
    }
    Ok((from, to))
}

fn cut(m: &Motion, (from, to): (usize, usize)) -> Motion {
    let n = m.channels();
    Motion {
        skeleton: m.skeleton.clone(),
        frame_time: m.frame_time,
        values: m.values[from * n..(to + 1) * n].to_vec(),
    }
}

/// A clip's motion as cut from its source: the source's frames `range`
/// at its frame time, and the length unit the source declares.
struct Source<'m> {
    motion: &'m Motion,
    range: (usize, usize),
    frame_time: f64,
    declared: Option<LengthUnit>,
}

fn encode_one(
    c: &ClipSpec,
    source: Source<'_>,
    rig: Option<&Rig>,
    pattern: &crate::codec::pattern::PatternOptions,
    progress: &dyn encode::Progress,
) -> Result<Single, ShowError> {
    let Source {
        motion: m,
        range,
        frame_time: source_frame_time,
        declared,
    } = source;
    let unit = c.units.or(declared).unwrap_or_else(|| units::detect(m));
    let file = c.file.display().to_string();
    if let Some(rig) = rig {
        let channels = rig
            .resolve(&m.skeleton)
            .map_err(|source| ShowError::RigChannels {
                clip: c.name.clone(),
                source,
            })?;
        let tracks = rig.servo_tracks(m, &channels, unit.metres());
        let sc = servo_clip::encode_servo_clip(
            rig,
            &tracks,
            &ServoEncodeOptions {
                codec: c.codec,
                bound: c.bound,
                key_interval: None,
                rate: ServoRate::Rig,
                names: ServoNames::Strip,
            },
        )
        .map_err(|source| ShowError::Servo {
            clip: c.name.clone(),
            file: file.clone(),
            source: Box::new(source),
        })?;
        return Ok(Single {
            proof: format!(
                "servo angle max {:.3}° at {} ticks (bound {})",
                sc.ticks.max_deg, sc.ticks.ticks, c.bound
            ),
            bytes: sc.bytes,
            codec: sc.codec,
            source_frame_time,
            range,
        });
    }
    let enc = encode::encode_with(
        m,
        &EncodeOptions {
            key_bits: None,
            codec: c.codec,
            bound: c.bound,
            metres_per_unit: unit.metres(),
            key_interval: None,
            index_layout: Default::default(),
            pattern: pattern.clone(),
        },
        progress,
    )
    .map_err(|source| ShowError::Encode {
        clip: c.name.clone(),
        file,
        source: Box::new(source),
    })?;
    let x = &enc.metrics;
    Ok(Single {
        proof: format!(
            "angle max {:.3}°, joint max {:.2} mm (bound {})",
            x.angle_max_deg, x.max_joint_err_mm, c.bound
        ),
        bytes: enc.bytes,
        codec: enc.codec,
        source_frame_time,
        range,
    })
}

fn internal(e: impl std::fmt::Display) -> ShowError {
    ShowError::Internal(e.to_string())
}

/// The shared sections of the show: the header (ranges over every clip,
/// frame count their sum), and a servo show's rig table and digest.
struct Shared {
    header: (u8, Vec<u8>),
    rig: Option<Vec<u8>>,
    digest: Option<Vec<u8>>,
}

fn shared_sections(clips: &[Clip<'_>]) -> Result<Shared, ShowError> {
    let first = clips.first().ok_or_else(|| internal("no clips"))?;
    let total: u64 = clips
        .iter()
        .map(|c| u64::from(c.header().frame_count()))
        .sum();
    let total = u32::try_from(total).map_err(|_| internal("more than 2^32 frames"))?;
    let h = first.header();
    let header = if h.is_servo_form() {
        (
            consts::SECTION_HEADER_COMPACT,
            servo_clip::servo_header_section(h.frame_time_ns(), total, h.channel_count() as u32),
        )
    } else {
        let mut wire = HeaderWire::from_decoded(h);
        wire.frame_count = total;
        for c in &clips[1..] {
            for (w, ch) in wire.channels.iter_mut().zip(c.header().channels()) {
                w.min = w.min.min(ch.min);
                w.max = w.max.max(ch.max);
            }
        }
        (consts::SECTION_HEADER_COMPACT, wire.to_compact())
    };
    let section = |id| {
        first
            .sections()
            .find(|s| s.id == id)
            .map(|s| s.bytes.to_vec())
    };
    Ok(Shared {
        header,
        rig: section(consts::SECTION_RIG),
        digest: section(consts::SECTION_RIG_DIGEST),
    })
}

/// The show's sections: header, rig, show table, cues, one codec section
/// per clip, the pattern databases (shared model sections), digest.
fn show_sections(
    shared: &Shared,
    rows: &[TableRow],
    codecs: &[(u8, Vec<u8>)],
    models: &[Vec<u8>],
    cues: &[u8],
) -> Vec<(u8, Vec<u8>)> {
    let mut out = vec![shared.header.clone()];
    if let Some(r) = &shared.rig {
        out.push((consts::SECTION_RIG, r.clone()));
    }
    out.push((consts::SECTION_SHOW, wire::show_table(rows)));
    out.push((consts::SECTION_CUES, cues.to_vec()));
    out.extend(codecs.iter().cloned());
    out.extend(
        models
            .iter()
            .map(|m| (consts::SECTION_MODEL_PATTERN, m.clone())),
    );
    if let Some(d) = &shared.digest {
        out.push((consts::SECTION_RIG_DIGEST, d.clone()));
    }
    out
}

/// Position of the first codec section in [`show_sections`].
fn first_codec_position(shared: &Shared) -> u32 {
    3 + u32::from(shared.rig.is_some())
}

/// Assembles the show of `singles`; clip `k` with `in_show[k] = (section,
/// g)` plays in the show from that codec section and database
/// `databases[g]` (its single clip holds the same database in its section).
fn assemble_show(
    spec: &ShowSpec,
    singles: &[Single],
    in_show: &[Option<(Vec<u8>, usize)>],
    databases: &[Vec<u8>],
) -> Result<BuiltShow, ShowError> {
    let clips: Vec<Clip<'_>> = singles
        .iter()
        .map(|s| Clip::parse(&s.bytes))
        .collect::<Result<_, _>>()
        .map_err(internal)?;
    let channels = clips[0].header().channel_count();
    if channels > MAX_CHANNELS {
        return Err(ShowError::TooManyChannels { channels });
    }
    let shared = shared_sections(&clips)?;
    let codecs: Vec<(u8, Vec<u8>)> = clips
        .iter()
        .map(|c| {
            c.sections()
                .find(|s| s.id == c.codec_id())
                .map(|s| (s.id, s.bytes.to_vec()))
                .ok_or_else(|| internal("a clip without its codec section"))
        })
        .collect::<Result<_, _>>()?;
    let base = first_codec_position(&shared);
    let frame_ns = clips[0].header().frame_time_ns();
    let mut rows = Vec::new();
    for (i, ((c, s), clip)) in spec.clips.iter().zip(singles).zip(&clips).enumerate() {
        let frames = clip.header().frame_count();
        let looping = match &c.looping {
            None => None,
            Some(l) => Some(loop_points(spec, c, l, s, frames, frame_ns)?),
        };
        let models = in_show[i]
            .as_ref()
            .map(|(_, g)| vec![base + singles.len() as u32 + *g as u32])
            .unwrap_or_default();
        rows.push(TableRow {
            name: c.name.clone(),
            codec_section: base + i as u32,
            frames,
            looping,
            models,
        });
    }
    let cues = wire::cue_section(spec);
    // Seams the show file leaves open: the shortest whose steps stay within
    // the clip's own (measured on the show player), from the default fade.
    let mut seams = Vec::new();
    for (i, (c, row)) in spec.clips.iter().zip(rows.clone()).enumerate() {
        let Some(l) = row.looping else {
            seams.push(None);
            continue;
        };
        let own = clip_step(&clips[i])?;
        let chosen_fixed = c.looping.and_then(|l| l.seam_s).is_some();
        let max_seam = l.end - l.start - 1;
        let mut seam = l.seam.min(max_seam);
        loop {
            let mut one = row.clone();
            one.codec_section = base;
            one.looping = Some(Loop { seam, ..l });
            // The single clip's section (its database inside).
            one.models = Vec::new();
            let bytes = assemble_version(
                consts::VERSION_SHOW,
                &show_sections(
                    &one_clip(&clips[i])?,
                    &[one],
                    &codecs[i..=i],
                    &[],
                    &cues_for_one(&cues),
                ),
            );
            let check = seam_check(&bytes, own)?;
            if chosen_fixed || check.holds() || seam >= max_seam {
                rows[i].looping = Some(Loop { seam, ..l });
                seams.push(Some(check));
                break;
            }
            seam = (seam + seam / 2 + 1).min(max_seam);
        }
    }
    // In the show, the clips that share a database read it from its model
    // section.
    let codecs: Vec<(u8, Vec<u8>)> = codecs
        .into_iter()
        .zip(in_show)
        .map(|(c, s)| match s {
            Some((section, _)) => (c.0, section.clone()),
            None => c,
        })
        .collect();
    let sections = show_sections(&shared, &rows, &codecs, databases, &cues);
    let bytes = assemble_version(consts::VERSION_SHOW, &sections);
    verify(&bytes, &clips)?;
    let built = spec
        .clips
        .iter()
        .zip(singles)
        .zip(rows)
        .zip(seams)
        .zip(&codecs)
        .zip(in_show)
        .map(|(((((c, s), row), seam), codec), shared)| BuiltClip {
            name: c.name.clone(),
            source: c.file.clone(),
            source_frames: s.range,
            codec: s.codec,
            frames: row.frames,
            single_bytes: s.bytes.len(),
            shares_database: shared.is_some(),
            codec_bytes: codec.1.len(),
            proof: s.proof.clone(),
            looping: row.looping,
            seam,
        })
        .collect();
    Ok(BuiltShow {
        sections: sections.iter().map(|(id, b)| (*id, b.len())).collect(),
        bytes,
        clips: built,
    })
}

/// The shared sections of a one-clip show of `clip` (its own frame count).
fn one_clip(clip: &Clip<'_>) -> Result<Shared, ShowError> {
    shared_sections(std::slice::from_ref(clip))
}

/// The cue section without lists, idle clips or triggers (which name
/// other clips): the default transition and seed only.
fn cues_for_one(cues: &[u8]) -> Vec<u8> {
    let mut r = crate::container::ByteCursor::new(cues);
    let fade = r
        .varint()
        .unwrap_or(mocap_decoder::show::player::DEFAULT_FADE_MS);
    let seed = r.varint().unwrap_or(1);
    let mut out = Vec::new();
    for v in [fade, seed, 0, 0, 0] {
        crate::container::varint(&mut out, v);
    }
    out
}

/// Loop points of clip `c` in coded frames.
fn loop_points(
    spec: &ShowSpec,
    c: &ClipSpec,
    l: &file::LoopSpec,
    s: &Single,
    frames: u32,
    frame_ns: u32,
) -> Result<Loop, ShowError> {
    let coded = |mark: Mark| -> u32 {
        let seconds = mark.seconds(s.source_frame_time);
        (seconds * 1e9 / f64::from(frame_ns))
            .round()
            .clamp(0.0, f64::from(u32::MAX)) as u32
    };
    let start = l.start.map_or(0, coded);
    let end = l.end.map_or(frames.saturating_sub(1), coded);
    if start >= end || end >= frames {
        return Err(ShowError::Range {
            file: spec.file.clone(),
            clip: c.name.clone(),
            message: format!(
                "loop points {start}..{end} (coded frames) are not inside the clip's {frames} frames with in < out"
            ),
        });
    }
    let seam = match l.seam_s {
        Some(seconds) => (seconds * 1e9 / f64::from(frame_ns)).round() as u32,
        None => (f64::from(spec.fade_ms) * 1e6 / f64::from(frame_ns)).round() as u32,
    };
    Ok(Loop {
        start,
        end,
        seam: seam.min(end - start - 1),
    })
}

/// The largest frame-to-frame step of `clip`: rotations (mdeg, the short
/// way round) and translations (µm).
fn clip_step(clip: &Clip<'_>) -> Result<[i64; 2], ShowError> {
    let frames = clipfile::decode_all(clip).map_err(internal)?;
    let kinds: Vec<bool> = clip
        .header()
        .channels()
        .map(|c| c.kind.is_rotation())
        .collect();
    let servo = clip.rig().is_some();
    let n = kinds.len().max(1);
    let mut best = [0i64; 2];
    for w in frames.chunks(n).collect::<Vec<_>>().windows(2) {
        for (i, (&a, &b)) in w[0].iter().zip(w[1]).enumerate() {
            let rot = kinds[i];
            let d = i64::from(mocap_decoder::show::player::diff(b, a, rot && !servo)).abs();
            let k = usize::from(!rot);
            best[k] = best[k].max(d);
        }
    }
    Ok(best)
}

/// Plays the one looping clip of `bytes` through its first seam at its
/// frame rate and measures the largest step.
fn seam_check(bytes: &[u8], own: [i64; 2]) -> Result<SeamCheck, ShowError> {
    let show = Show::parse(bytes).map_err(internal)?;
    let entry = show.entry(0).map_err(internal)?;
    let l = entry.looping.ok_or_else(|| internal("no loop"))?;
    let mut player = Box::new(HostShowPlayer::new(show).map_err(internal)?);
    let servo = show.rig().is_some();
    let kinds: Vec<bool> = show
        .header()
        .channels()
        .map(|c| c.kind.is_rotation())
        .collect();
    let ns = u64::from(show.header().frame_time_ns());
    let t = |f: u64| f * ns / 1000;
    player.play(0, 0).map_err(internal)?;
    let n = kinds.len();
    let mut prev = vec![0i32; n];
    let mut cur = vec![0i32; n];
    let from = u64::from(l.end - l.seam).saturating_sub(2);
    let to = u64::from(l.end) + 2;
    let mut step = [0i64; 2];
    for f in from..=to {
        player.sample(t(f), &mut cur).map_err(internal)?;
        if f > from {
            for (i, (&a, &b)) in prev.iter().zip(&cur).enumerate() {
                let d =
                    i64::from(mocap_decoder::show::player::diff(b, a, kinds[i] && !servo)).abs();
                let k = usize::from(!kinds[i]);
                step[k] = step[k].max(d);
            }
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let conv = |v: [i64; 2]| [v[0] as f64 / 1000.0, v[1] as f64 / 1000.0];
    Ok(SeamCheck {
        seam_step: conv(step),
        clip_step: conv(own),
    })
}

/// Every clip of the show decodes to exactly its single clip's frames.
fn verify(bytes: &[u8], singles: &[Clip<'_>]) -> Result<(), ShowError> {
    let show = Show::parse(bytes).map_err(internal)?;
    for (i, single) in singles.iter().enumerate() {
        let clip = show.clip(i as u16).map_err(internal)?;
        let a = clipfile::decode_all(&clip).map_err(internal)?;
        let b = clipfile::decode_all(single).map_err(internal)?;
        if a != b {
            return Err(internal(format!(
                "show clip {i} decodes differently from its single clip"
            )));
        }
    }
    Ok(())
}

/// The summary `mocap show build` prints.
pub fn report(output: &Path, spec: &ShowSpec, built: &BuiltShow) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let singles = built.singles_bytes();
    let shared: Vec<String> = built
        .sections
        .iter()
        .filter(|(id, _)| !consts::is_codec_section(*id))
        .map(|(id, len)| format!("{} {len} B", section_name(*id)))
        .collect();
    let _ = writeln!(
        s,
        "{}: show `{}`, {} clips, {} bytes (the clips as single files: {} bytes, {:+.1} %); shared: {}; every clip's bound holds",
        output.display(),
        spec.name,
        built.clips.len(),
        built.bytes.len(),
        singles,
        (built.bytes.len() as f64 / singles.max(1) as f64 - 1.0) * 100.0,
        shared.join(", ")
    );
    if built.clips.iter().any(|c| c.shares_database) {
        let _ = writeln!(
            s,
            "  (the `pattern` clips read one database: as single files each would carry all of it)"
        );
    }
    for c in &built.clips {
        let looping = match (c.looping, c.seam) {
            (Some(l), Some(k)) => format!(
                "; loop {}..{}, seam {} frames: step {:.3}°/{:.2} mm (clip's own {:.3}°/{:.2} mm){}",
                l.start,
                l.end,
                l.seam,
                k.seam_step[0],
                k.seam_step[1],
                k.clip_step[0],
                k.clip_step[1],
                if k.holds() { "" } else { " — LARGER than the clip's own: lengthen the seam or choose other loop points" }
            ),
            _ => String::new(),
        };
        let _ = writeln!(
            s,
            "  {:<12} {:<10} {:>6} frames  {:>7} B (single {:>7} B)  {}{}",
            c.name,
            c.codec.name(),
            c.frames,
            c.codec_bytes,
            c.single_bytes,
            c.proof,
            looping
        );
    }
    s
}

/// The name `mocap info` and the build summary give a section.
pub fn section_name(id: u8) -> &'static str {
    match id {
        consts::SECTION_HEADER => "header",
        consts::SECTION_HEADER_COMPACT => "header (compact)",
        consts::SECTION_RIG => "rig table",
        consts::SECTION_SHOW => "show table",
        consts::SECTION_CUES => "cues",
        consts::SECTION_CODEC_INDEX => "index",
        consts::SECTION_CODEC_PCA_SPLINE => "pca-spline",
        consts::SECTION_CODEC_PREDICTIVE => "predictive",
        consts::SECTION_CODEC_INDEX_FAST => "index (fast)",
        consts::SECTION_CODEC_PATTERN => "pattern",
        consts::SECTION_RIG_DIGEST => "rig digest",
        consts::SECTION_MODEL_FIRST..=consts::SECTION_MODEL_LAST => {
            if id == consts::SECTION_MODEL_PATTERN {
                "pattern database"
            } else {
                "shared model"
            }
        }
        _ => "ancillary",
    }
}
