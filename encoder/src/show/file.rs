//! The show file: TOML read into a [`ShowSpec`], every rule checked, every
//! error placed at its line and column (schema: `assets/shows/README.md`).

use serde::Deserialize;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

use crate::codec::CodecChoice;
use crate::encode::{Bound, BoundSpec};
use crate::located::{LocatedError, Position};
use crate::units::LengthUnit;

/// A time or frame in a show file: an integer is a frame of the source
/// file, a string a time (`"1.5s"`, `"400ms"`), a float seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mark {
    /// A frame of the source.
    Frame(usize),
    /// Seconds from the source's (or the list's) start.
    Seconds(f64),
}

impl Mark {
    /// The mark in seconds at `frame_time` seconds per frame.
    pub fn seconds(self, frame_time: f64) -> f64 {
        match self {
            Mark::Frame(f) => f as f64 * frame_time,
            Mark::Seconds(s) => s,
        }
    }
}

/// How a clip loops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopSpec {
    /// Where a new pass starts (clip-relative; `None`: the clip's start).
    pub start: Option<Mark>,
    /// The last frame of a pass (clip-relative; `None`: the clip's end).
    pub end: Option<Mark>,
    /// Seam blend length, seconds (`None`: the encoder picks it).
    pub seam_s: Option<f64>,
}

/// One clip of a show file.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipSpec {
    /// The clip's name in the show.
    pub name: String,
    /// Source BVH file (resolved against the show file's folder).
    pub file: PathBuf,
    /// First source frame or time (inclusive).
    pub from: Option<Mark>,
    /// Last source frame or time (inclusive).
    pub to: Option<Mark>,
    /// Its loop, if it loops.
    pub looping: Option<LoopSpec>,
    /// Codec (the show's default if not given).
    pub codec: CodecChoice,
    /// Bound (the show's default if not given).
    pub bound: Bound,
    /// Source length unit (`None`: detected).
    pub units: Option<LengthUnit>,
    /// Where the clip's table starts in the show file.
    pub at: Position,
}

/// What a cue does, clips and lists by name.
#[derive(Clone, Debug, PartialEq)]
pub enum ActionSpec {
    /// Play a clip after the default transition.
    Play(String),
    /// Crossfade to a clip over `ms`.
    Fade(String, u32),
    /// Queue a clip.
    Queue(String),
    /// Stop.
    Stop,
    /// Hold the pose.
    Hold,
    /// Resume after a hold.
    Resume,
    /// Loop on or off.
    Loop(bool),
    /// Set a GPIO pin.
    Gpio(u8, bool),
    /// Send serial bytes.
    Serial(Vec<u8>),
}

/// One cue of a list.
#[derive(Clone, Debug, PartialEq)]
pub struct CueSpec {
    /// Time from the list's start, ms.
    pub at_ms: u32,
    /// What it does.
    pub action: ActionSpec,
    /// Where it is in the file.
    pub pos: Position,
}

/// A cue list.
#[derive(Clone, Debug, PartialEq)]
pub struct CueListSpec {
    /// Its name.
    pub name: String,
    /// Its cues, in time order.
    pub cues: Vec<CueSpec>,
}

/// A trigger.
#[derive(Clone, Debug, PartialEq)]
pub struct TriggerSpec {
    /// Input number 0..32.
    pub input: u8,
    /// Targets: cue lists (`true`) or clips.
    pub lists: bool,
    /// Target names.
    pub targets: Vec<String>,
    /// Cooldown, ms.
    pub cooldown_ms: u32,
    /// Where it is.
    pub pos: Position,
}

/// A show file, read and checked.
#[derive(Clone, Debug, PartialEq)]
pub struct ShowSpec {
    /// The show file as given.
    pub file: String,
    /// The show's name.
    pub name: String,
    /// The rig of a servo show.
    pub rig: Option<PathBuf>,
    /// Default transition, ms.
    pub fade_ms: u32,
    /// Seed of the random choices.
    pub seed: u32,
    /// The clips, in show order.
    pub clips: Vec<ClipSpec>,
    /// Cue lists.
    pub cues: Vec<CueListSpec>,
    /// Idle clips by name.
    pub idle: Vec<String>,
    /// Triggers.
    pub triggers: Vec<TriggerSpec>,
    /// The `pattern` codec's settings: body-part nodes, each a list of
    /// joint names (`pattern_nodes`; empty: the skeleton's limbs), and
    /// layout (`pattern_layout`: `packed`, the default, or `columns`).
    pub pattern: crate::codec::pattern::PatternOptions,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    show: Option<Spanned<RawShow>>,
    #[serde(default)]
    clip: Vec<Spanned<RawClip>>,
    #[serde(default)]
    cues: Vec<Spanned<RawList>>,
    #[serde(default)]
    trigger: Vec<Spanned<RawTrigger>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawShow {
    name: Option<Spanned<String>>,
    rig: Option<Spanned<String>>,
    codec: Option<Spanned<String>>,
    max_error: Option<Spanned<String>>,
    units: Option<Spanned<String>>,
    fade_ms: Option<Spanned<u32>>,
    seed: Option<Spanned<u32>>,
    #[serde(default)]
    idle: Vec<Spanned<String>>,
    pattern_nodes: Option<Spanned<Vec<Vec<String>>>>,
    pattern_layout: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawMark {
    Frame(i64),
    Seconds(f64),
    Text(String),
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawLoop {
    On(bool),
    Points {
        #[serde(rename = "in")]
        start: Option<RawMark>,
        out: Option<RawMark>,
        seam: Option<RawMark>,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawClip {
    name: Option<Spanned<String>>,
    file: Option<Spanned<String>>,
    from: Option<Spanned<RawMark>>,
    to: Option<Spanned<RawMark>>,
    #[serde(rename = "loop")]
    looping: Option<Spanned<RawLoop>>,
    codec: Option<Spanned<String>>,
    max_error: Option<Spanned<String>>,
    units: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawList {
    name: Option<Spanned<String>>,
    #[serde(default)]
    cue: Vec<Spanned<RawCue>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCue {
    at: Option<Spanned<RawMark>>,
    play: Option<String>,
    fade: Option<String>,
    ms: Option<u32>,
    queue: Option<String>,
    stop: Option<bool>,
    hold: Option<bool>,
    resume: Option<bool>,
    #[serde(rename = "loop")]
    looping: Option<bool>,
    gpio: Option<u8>,
    level: Option<bool>,
    serial: Option<Vec<u8>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTrigger {
    input: Option<Spanned<u8>>,
    lists: Option<Vec<String>>,
    clips: Option<Vec<String>>,
    cooldown_ms: Option<u32>,
}

/// Reads `${VAR}` references in a path from the environment. A variable's value that begins
/// the path and is itself relative (`MOCAP_CORPUS=../shared/data`) was typed relative to the
/// user's working directory, as a shell would read it, so it is made absolute against it; a
/// `:-` default stays relative to the show file like any path written in it.
fn expand(s: &str) -> Result<String, String> {
    expand_with(s, |name| std::env::var(name).ok())
}

fn expand_with(s: &str, var: impl Fn(&str) -> Option<String>) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find("${") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let Some(j) = after.find('}') else {
            return Err(format!("unterminated `${{` in `{s}`"));
        };
        let reference = &after[..j];
        let (name, default) = match reference.split_once(":-") {
            Some((n, d)) => (n, Some(d)),
            None => (reference, None),
        };
        match (var(name), default) {
            (Some(v), _) if out.is_empty() && Path::new(&v).is_relative() && !v.is_empty() => {
                let abs = std::path::absolute(&v)
                    .map_err(|e| format!("`{name}`={v}: cannot resolve: {e}"))?;
                out.push_str(&abs.to_string_lossy());
            }
            (Some(v), _) => out.push_str(&v),
            (None, Some(d)) => out.push_str(d),
            (None, None) => return Err(format!("environment variable `{name}` is not set")),
        }
        rest = &after[j + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Parses `"1.5s"`, `"400ms"`, `"120f"` (frames) or a bare number of
/// seconds.
fn parse_mark_text(t: &str) -> Option<Mark> {
    let t = t.trim();
    let num = |s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v >= 0.0)
    };
    if let Some(ms) = t.strip_suffix("ms") {
        return num(ms).map(|v| Mark::Seconds(v / 1000.0));
    }
    if let Some(s) = t.strip_suffix('s') {
        return num(s).map(Mark::Seconds);
    }
    if let Some(f) = t.strip_suffix('f') {
        return f.trim().parse::<usize>().ok().map(Mark::Frame);
    }
    num(t).map(Mark::Seconds)
}

impl ShowSpec {
    /// Reads and checks a show file. I/O errors have line and column 0.
    pub fn read_file(path: &Path) -> Result<ShowSpec, LocatedError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            LocatedError::at(
                &file,
                Position::default(),
                format!("cannot read show file: {e}"),
            )
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        ShowSpec::parse(&text, &file, dir)
    }

    /// Parses and checks show text; relative paths are taken from `dir`.
    pub fn parse(text: &str, file: &str, dir: &Path) -> Result<ShowSpec, LocatedError> {
        let pos = |span: Range<usize>| Position::of_byte(text, span.start);
        let at = |span: Range<usize>, msg: String| LocatedError::at(file, pos(span), msg);
        let raw: RawFile = toml::from_str(text).map_err(|e| {
            let p = e.span().map_or(Position { line: 1, column: 1 }, pos);
            LocatedError::at(file, p, e.message().trim_end().to_string())
        })?;
        let Some(raw_show) = raw.show else {
            return Err(LocatedError::at(
                file,
                Position { line: 1, column: 1 },
                "missing [show] table (with at least `name`)",
            ));
        };
        let show_span = raw_show.span();
        let show = raw_show.into_inner();
        let name = match &show.name {
            Some(n) if !n.get_ref().trim().is_empty() => n.get_ref().trim().to_string(),
            Some(n) => return Err(at(n.span(), "the show name is empty".into())),
            None => return Err(at(show_span, "missing key `name` in [show]".into())),
        };
        let path_of = |s: &Spanned<String>| -> Result<PathBuf, LocatedError> {
            let p = expand(s.get_ref()).map_err(|m| at(s.span(), m))?;
            Ok(dir.join(p))
        };
        let rig = show.rig.as_ref().map(path_of).transpose()?;
        let codec_of = |c: &Option<Spanned<String>>, default: CodecChoice| match c {
            Some(c) => c
                .get_ref()
                .parse::<CodecChoice>()
                .map_err(|e| at(c.span(), e.to_string())),
            None => Ok(default),
        };
        let bound_of = |b: &Option<Spanned<String>>, default: Bound| match b {
            Some(b) => b
                .get_ref()
                .split('+')
                .map(str::parse::<BoundSpec>)
                .collect::<Result<Vec<_>, _>>()
                .map(|specs| Bound::from_specs(&specs))
                .map_err(|e| at(b.span(), e.to_string())),
            None => Ok(default),
        };
        let units_of = |u: &Option<Spanned<String>>, default: Option<LengthUnit>| match u {
            Some(u) if u.get_ref() == "auto" => Ok(None),
            Some(u) => u
                .get_ref()
                .parse::<LengthUnit>()
                .map(Some)
                .map_err(|e| at(u.span(), e.to_string())),
            None => Ok(default),
        };
        let default_codec = codec_of(
            &show.codec,
            if rig.is_some() {
                CodecChoice::Predictive
            } else {
                CodecChoice::Index
            },
        )?;
        let default_bound = bound_of(
            &show.max_error,
            Bound::from_specs(&["1deg"
                .parse()
                .map_err(|e: crate::encode::BoundError| at(show_span.clone(), e.to_string()))?]),
        )?;
        // A servo show's clips are servo angles: no joints to measure in
        // millimetres, no feet to keep from sliding.
        let servo_bound = |bound: &Bound,
                           given: &Option<Spanned<String>>,
                           fallback: &Range<usize>| {
            if rig.is_some() && (bound.positional() || bound.foot_slide_mm_s.is_some()) {
                let span = given.as_ref().map_or(fallback.clone(), |b| b.span());
                return Err(at(
                    span,
                    "a servo show's bound is in degrees of servo travel (e.g. max_error = \"0.5deg\")"
                        .into(),
                ));
            }
            Ok(())
        };
        servo_bound(&default_bound, &show.max_error, &show_span)?;
        let default_units = units_of(&show.units, None)?;
        let mark_at = |m: &RawMark, span: Range<usize>| -> Result<Mark, LocatedError> {
            match m {
                RawMark::Frame(f) if *f >= 0 => Ok(Mark::Frame(*f as usize)),
                RawMark::Seconds(s) if s.is_finite() && *s >= 0.0 => Ok(Mark::Seconds(*s)),
                RawMark::Text(t) => parse_mark_text(t).ok_or_else(|| {
                    at(
                        span,
                        format!("`{t}` is not a time (\"1.5s\", \"400ms\") or a frame (\"120f\")"),
                    )
                }),
                _ => Err(at(span, "a time or frame must not be negative".into())),
            }
        };
        let mark = |m: &Spanned<RawMark>| mark_at(m.get_ref(), m.span());

        if raw.clip.is_empty() {
            return Err(at(
                show_span,
                "the show has no clips (add [[clip]] tables)".into(),
            ));
        }
        let mut clips: Vec<ClipSpec> = Vec::new();
        for c in &raw.clip {
            let span = c.span();
            let c = c.get_ref();
            let name = match &c.name {
                Some(n) => n.get_ref().trim().to_string(),
                None => return Err(at(span, "missing key `name` in [[clip]]".into())),
            };
            let name_span = c.name.as_ref().map_or(span.clone(), |n| n.span());
            if name.is_empty() || name.len() > mocap_decoder::consts::MAX_CLIP_NAME {
                return Err(at(
                    name_span,
                    format!(
                        "a clip name has 1 to {} bytes, not {}",
                        mocap_decoder::consts::MAX_CLIP_NAME,
                        name.len()
                    ),
                ));
            }
            if clips.iter().any(|o| o.name == name) {
                return Err(at(name_span, format!("a second clip named `{name}`")));
            }
            let Some(f) = &c.file else {
                return Err(at(span, format!("clip `{name}`: missing key `file`")));
            };
            let looping = match c.looping.as_ref().map(|l| l.get_ref()) {
                None | Some(RawLoop::On(false)) => None,
                Some(RawLoop::On(true)) => Some(LoopSpec {
                    start: None,
                    end: None,
                    seam_s: None,
                }),
                Some(RawLoop::Points { start, out, seam }) => {
                    let lspan = c.looping.as_ref().map_or(span.clone(), |l| l.span());
                    let m = |v: &Option<RawMark>| -> Result<Option<Mark>, LocatedError> {
                        v.as_ref().map(|v| mark_at(v, lspan.clone())).transpose()
                    };
                    let seam_s = match m(seam)? {
                        Some(Mark::Frame(_)) => {
                            return Err(at(lspan, "a loop's `seam` is a time (\"300ms\")".into()))
                        }
                        other => other.map(|m| m.seconds(0.0)),
                    };
                    Some(LoopSpec {
                        start: m(start)?,
                        end: m(out)?,
                        seam_s,
                    })
                }
            };
            clips.push(ClipSpec {
                name,
                file: path_of(f)?,
                from: c.from.as_ref().map(mark).transpose()?,
                to: c.to.as_ref().map(mark).transpose()?,
                looping,
                codec: codec_of(&c.codec, default_codec)?,
                bound: {
                    let bound = bound_of(&c.max_error, default_bound)?;
                    servo_bound(&bound, &c.max_error, &span)?;
                    bound
                },
                units: units_of(&c.units, default_units)?,
                at: pos(span),
            });
        }
        if clips.len() > mocap_decoder::consts::MAX_SHOW_CLIPS {
            return Err(at(
                show_span,
                format!(
                    "{} clips; a show holds at most {}",
                    clips.len(),
                    mocap_decoder::consts::MAX_SHOW_CLIPS
                ),
            ));
        }
        let clip_named = |n: &str, span: Range<usize>| -> Result<String, LocatedError> {
            if clips.iter().any(|c| c.name == n) {
                Ok(n.to_string())
            } else {
                Err(at(span, format!("no clip named `{n}` in the show")))
            }
        };

        let mut cues: Vec<CueListSpec> = Vec::new();
        for l in &raw.cues {
            let span = l.span();
            let l = l.get_ref();
            let Some(name) = &l.name else {
                return Err(at(span, "missing key `name` in [[cues]]".into()));
            };
            let list_name = name.get_ref().trim().to_string();
            if list_name.is_empty() || list_name.len() > mocap_decoder::consts::MAX_CLIP_NAME {
                return Err(at(name.span(), "a cue list name has 1 to 31 bytes".into()));
            }
            if cues.iter().any(|o| o.name == list_name) {
                return Err(at(
                    name.span(),
                    format!("a second cue list named `{list_name}`"),
                ));
            }
            let mut list = Vec::new();
            for cue in &l.cue {
                let cspan = cue.span();
                let c = cue.get_ref();
                let Some(t) = &c.at else {
                    return Err(at(
                        cspan,
                        "a cue needs `at` (its time, e.g. \"12.5s\")".into(),
                    ));
                };
                let at_s = match mark(t)? {
                    Mark::Seconds(s) => s,
                    Mark::Frame(_) => {
                        return Err(at(
                            t.span(),
                            "a cue's `at` is a time (\"12.5s\"), not a frame".into(),
                        ))
                    }
                };
                let at_ms = (at_s * 1000.0).round();
                if at_ms > f64::from(u32::MAX) {
                    return Err(at(t.span(), "a cue's time must be below 49 days".into()));
                }
                let mut actions = Vec::new();
                let s = cspan.clone();
                if let Some(p) = &c.play {
                    actions.push(ActionSpec::Play(clip_named(p, s.clone())?));
                }
                if let Some(p) = &c.fade {
                    actions.push(ActionSpec::Fade(
                        clip_named(p, s.clone())?,
                        c.ms.unwrap_or(500),
                    ));
                } else if c.ms.is_some() {
                    return Err(at(s, "`ms` goes with `fade`".into()));
                }
                if let Some(p) = &c.queue {
                    actions.push(ActionSpec::Queue(clip_named(p, s.clone())?));
                }
                if c.stop == Some(true) {
                    actions.push(ActionSpec::Stop);
                }
                if c.hold == Some(true) {
                    actions.push(ActionSpec::Hold);
                }
                if c.resume == Some(true) {
                    actions.push(ActionSpec::Resume);
                }
                if let Some(on) = c.looping {
                    actions.push(ActionSpec::Loop(on));
                }
                if let Some(pin) = c.gpio {
                    actions.push(ActionSpec::Gpio(pin, c.level.unwrap_or(true)));
                } else if c.level.is_some() {
                    return Err(at(s, "`level` goes with `gpio`".into()));
                }
                if let Some(bytes) = &c.serial {
                    if bytes.is_empty() || bytes.len() > mocap_decoder::show::cues::MAX_SERIAL {
                        return Err(at(s, "`serial` sends 1 to 32 bytes".into()));
                    }
                    actions.push(ActionSpec::Serial(bytes.clone()));
                }
                let action = match actions.len() {
                    1 => actions.remove(0),
                    0 => return Err(at(s, "a cue needs one action: play, fade, queue, stop, hold, resume, loop, gpio or serial".into())),
                    _ => return Err(at(s, "a cue has one action; give each its own cue".into())),
                };
                list.push(CueSpec {
                    at_ms: at_ms as u32,
                    action,
                    pos: pos(cspan),
                });
            }
            // Cues in time order, stable for equal times.
            list.sort_by_key(|c| c.at_ms);
            cues.push(CueListSpec {
                name: list_name,
                cues: list,
            });
        }
        let mut idle = Vec::new();
        for n in &show.idle {
            idle.push(clip_named(n.get_ref(), n.span())?);
        }
        let mut triggers: Vec<TriggerSpec> = Vec::new();
        for t in &raw.trigger {
            let span = t.span();
            let r = t.get_ref();
            let Some(input) = &r.input else {
                return Err(at(span, "missing key `input` in [[trigger]]".into()));
            };
            if usize::from(*input.get_ref()) >= mocap_decoder::show::cues::MAX_TRIGGERS {
                return Err(at(input.span(), "a trigger's input is 0 to 31".into()));
            }
            if triggers.iter().any(|o| o.input == *input.get_ref()) {
                return Err(at(
                    input.span(),
                    format!("a second trigger of input {}", input.get_ref()),
                ));
            }
            let (lists, names) = match (&r.lists, &r.clips) {
                (Some(l), None) => (true, l),
                (None, Some(c)) => (false, c),
                _ => {
                    return Err(at(
                        span,
                        "a trigger has `lists` or `clips` (one of them)".into(),
                    ))
                }
            };
            if names.is_empty() || names.len() > mocap_decoder::show::cues::MAX_TARGETS {
                return Err(at(span, "a trigger has 1 to 16 targets".into()));
            }
            for n in names {
                if lists {
                    if !cues.iter().any(|l| &l.name == n) {
                        return Err(at(span.clone(), format!("no cue list named `{n}`")));
                    }
                } else {
                    clip_named(n, span.clone())?;
                }
            }
            triggers.push(TriggerSpec {
                input: *input.get_ref(),
                lists,
                targets: names.clone(),
                cooldown_ms: r.cooldown_ms.unwrap_or(0),
                pos: pos(span),
            });
        }
        let pattern_nodes = match &show.pattern_nodes {
            None => Vec::new(),
            Some(n) => {
                let nodes = n.get_ref().clone();
                if nodes.iter().any(|node| node.is_empty()) || nodes.len() > 255 {
                    return Err(at(
                        n.span(),
                        "`pattern_nodes` lists 1 to 255 nodes, each a list of one or more joint names"
                            .into(),
                    ));
                }
                nodes
            }
        };
        let layout = match &show.pattern_layout {
            None => Default::default(),
            Some(l) => l.get_ref().parse().map_err(|e: String| at(l.span(), e))?,
        };
        Ok(ShowSpec {
            file: file.to_string(),
            name,
            pattern: crate::codec::pattern::PatternOptions {
                nodes: pattern_nodes,
                layout,
                ..Default::default()
            },
            rig,
            fade_ms: show
                .fade_ms
                .map_or(mocap_decoder::show::player::DEFAULT_FADE_MS, |f| {
                    *f.get_ref()
                }),
            seed: show.seed.map_or(1, |s| (*s.get_ref()).max(1)),
            clips,
            cues,
            idle,
            triggers,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{expand_with, ShowSpec};

    /// A servo show's bound is in degrees of servo travel, in `[show]` and
    /// in every clip: millimetres and a foot-slide bound are refused where
    /// they are written.
    #[test]
    fn a_servo_show_refuses_joint_and_slide_bounds_at_their_line() {
        let dir = std::path::Path::new(".");
        let show = |show_bound: &str, clip_bound: &str| {
            format!(
                "[show]\nname = \"s\"\nrig = \"r.toml\"\nmax_error = \"{show_bound}\"\n\n\
                 [[clip]]\nname = \"a\"\nfile = \"a.bvh\"\nmax_error = \"{clip_bound}\"\n"
            )
        };
        assert!(ShowSpec::parse(&show("0.5deg", "1deg"), "s.toml", dir).is_ok());
        for (show_bound, clip_bound, line) in [
            ("20mm", "1deg", 4),
            ("0.5deg", "0.5deg+slide:100mm/s", 9),
            ("0.5deg", "arms:10mm", 9),
        ] {
            let err = ShowSpec::parse(&show(show_bound, clip_bound), "s.toml", dir)
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("degrees of servo travel") && err.contains(&format!("s.toml:{line}:")),
                "{show_bound} / {clip_bound}: {err}"
            );
        }
    }

    #[test]
    fn a_relative_variable_is_read_from_the_working_directory() {
        let cwd = std::env::current_dir().unwrap();
        let env = |v: &'static str| move |n: &str| (n == "CORPUS").then(|| v.to_string());
        let rel = expand_with("${CORPUS}/cmu/05_04.bvh", env("../data")).unwrap();
        assert_eq!(
            rel,
            format!("{}/cmu/05_04.bvh", cwd.join("../data").display())
        );
        let abs = expand_with("${CORPUS}/x.bvh", env("/srv/data")).unwrap();
        assert_eq!(abs, "/srv/data/x.bvh");
        // a default stays as written (relative to the show file); so does a variable mid-path
        assert_eq!(expand_with("${NONE:-../d}/x", env("")).unwrap(), "../d/x");
        assert_eq!(expand_with("a/${CORPUS}/x", env("d")).unwrap(), "a/d/x");
        assert!(expand_with("${NONE}/x", env("")).is_err());
        assert!(expand_with("${CORPUS/x", env("d")).is_err());
    }
}
