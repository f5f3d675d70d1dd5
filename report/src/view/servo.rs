//! The servo page of `mocap view`: a servo clip's pulse curves, one row per
//! servo, against the limits every pulse is held to.
//!
//! Per servo and servo tick (¼ µs, as JSON integer arrays — a servo clip is
//! small): `decoded`, the clip's target (`sample_at` at the tick through the
//! rig table, [`play::servo_clip_targets`]); `commanded`, what the
//! firmware's playback loop sends ([`play::servo_clip_stream`]: range,
//! speed, from neutral); `shaped`, the ticks where the two differ (the
//! playback loop changed the command); with the source BVH and its rig file,
//! `source`, the rig's signal at the same ticks ([`servo_clip::tick_tracks`];
//! a clip at the rig's rate lasts whole ticks and may hold one tick more
//! than the source's duration gives: the page shows the ticks both have).

use std::path::Path;

use mocap_decoder::show::player::State;
use mocap_encoder::play::{self, PlayError, Protocol, ServoStream};
use mocap_encoder::rig::{Rig, RigError};
use mocap_encoder::servo_clip;
use mocap_encoder::show::play::{show_stream, Script};
use mocap_encoder::units::{self, LengthUnit};
use serde::Serialize;

use super::{file_name, fill, ViewError, SERVO_JS, SERVO_PAGE};

/// The source of a servo clip: the BVH it was encoded from and its rig file.
#[derive(Clone, Copy, Debug)]
pub struct ServoSource<'a> {
    /// The BVH.
    pub bvh: &'a Path,
    /// The rig file the clip was encoded with.
    pub rig: &'a Path,
    /// The BVH's length unit (`None`: detected).
    pub unit: Option<LengthUnit>,
}

/// A servo page and what it shows.
#[derive(Clone, Debug)]
pub struct ServoPage {
    /// The whole HTML file.
    pub html: String,
    /// Servo ticks of the clip.
    pub ticks: usize,
    /// Servos.
    pub servos: usize,
    /// Ticks at which the playback loop changed at least one servo's command.
    pub shaped_ticks: usize,
    /// With a source: the largest pulse difference, decoded against source, µs.
    pub max_error_us: Option<f64>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ServoInfo {
    name: String,
    min_qus: u16,
    max_qus: u16,
    neutral_qus: u16,
    max_step_qus: u16,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ServoData<'a> {
    format: u32,
    kind: &'a str,
    clip: &'a str,
    source: Option<&'a str>,
    rig: Option<&'a str>,
    rate_hz: f64,
    ticks: usize,
    servos: Vec<ServoInfo>,
    decoded: Vec<Vec<u16>>,
    commanded: Vec<Vec<u16>>,
    source_pulses: Option<Vec<Vec<u16>>>,
    shaped: Vec<Vec<usize>>,
    shaped_ticks: usize,
    show: Option<ShowData>,
}

/// A show's part of the page: its clips, what played when, its cues.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ShowData {
    clips: Vec<ShowClipInfo>,
    /// Runs of ticks with one clip in one state, in order.
    segments: Vec<Segment>,
    /// The script's commands and the cues' output events: (tick, text).
    cues: Vec<(usize, String)>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct ShowClipInfo {
    name: String,
    seconds: f64,
    loops: bool,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Segment {
    from: usize,
    to: usize,
    clip: Option<u16>,
    state: &'static str,
}

/// Reads the servo clip at `clip` (with its source when given) and builds
/// its page.
pub fn load_servo(clip: &Path, source: Option<ServoSource<'_>>) -> Result<ServoPage, ViewError> {
    let bytes = std::fs::read(clip).map_err(|e| ViewError::Read {
        path: clip.to_path_buf(),
        source: e,
    })?;
    let c = mocap_decoder::Clip::parse(&bytes).map_err(|e| ViewError::Clip {
        path: clip.to_path_buf(),
        source: e,
    })?;
    let play_error = |e: PlayError| ViewError::Servo {
        path: clip.to_path_buf(),
        source: e,
    };
    if c.rig().is_none() {
        return Err(ViewError::NotServo {
            path: clip.to_path_buf(),
        });
    }
    let targets = play::servo_clip_targets(&c, None).map_err(play_error)?;
    let stream = play::servo_clip_stream(&c, Protocol::Maestro, None).map_err(play_error)?;
    let n = targets.servos.len();
    let mut ticks = targets.targets.len().min(stream.clip_ticks);

    let mut names: Vec<String> = (0..n).map(|i| format!("servo {i}")).collect();
    let mut source_pulses: Option<Vec<Vec<u16>>> = None;
    let (mut source_name, mut rig_name) = (None, None);
    if let Some(src) = source {
        let rig = Rig::read_file(src.rig)?;
        let mismatch = |what: String| ViewError::ServoMismatch {
            clip: clip.to_path_buf(),
            rig: src.rig.to_path_buf(),
            what,
        };
        if rig.servos.len() != n {
            return Err(mismatch(format!(
                "the clip drives {n} servos, the rig {}",
                rig.servos.len()
            )));
        }
        if c.rig_digest().is_some_and(|d| d != rig.digest()) {
            return Err(mismatch("the clip was encoded for another rig".into()));
        }
        let m = mocap_encoder::bvh::read_file(src.bvh)?;
        let unit = src.unit.unwrap_or_else(|| units::detect(&m));
        let channels = rig.resolve(&m.skeleton)?;
        let tracks = rig.servo_tracks(&m, &channels, unit.metres());
        let tt = servo_clip::tick_tracks(&rig, &tracks);
        // A clip at the rig's rate lasts whole ticks: it may hold one tick
        // more than the source's duration gives. Shown: the ticks both have.
        if tt.ticks().abs_diff(ticks) > 1 {
            return Err(mismatch(format!(
                "the clip has {ticks} servo ticks, {} at the rig's rate has {}",
                src.bvh.display(),
                tt.ticks()
            )));
        }
        ticks = ticks.min(tt.ticks());
        names = rig.servos.iter().map(|s| s.name.clone()).collect();
        source_pulses = Some(tt.pulses.iter().map(|p| p[..ticks].to_vec()).collect());
        source_name = Some(file_name(src.bvh));
        rig_name = Some(file_name(src.rig));
    }

    let parts = Parts {
        title: file_name(clip),
        clip: file_name(clip),
        source: source_name,
        rig: rig_name,
        names,
        source_pulses,
        show: None,
    };
    Ok(build(parts, &targets.targets, &stream, ticks))
}

/// What a servo page shows besides the pulses.
struct Parts {
    title: String,
    clip: String,
    source: Option<String>,
    rig: Option<String>,
    names: Vec<String>,
    source_pulses: Option<Vec<Vec<u16>>>,
    show: Option<ShowData>,
}

/// The page of `ticks` ticks of `targets` (`[tick][servo]`) as `stream`
/// played them.
fn build(p: Parts, targets: &[Vec<u16>], stream: &ServoStream, ticks: usize) -> ServoPage {
    let n = p.names.len();
    let by_servo = |rows: &[Vec<u16>]| -> Vec<Vec<u16>> {
        (0..n)
            .map(|s| rows[..ticks].iter().map(|r| r[s]).collect())
            .collect()
    };
    let decoded = by_servo(targets);
    let commanded = by_servo(&stream.pulses);
    let shaped: Vec<Vec<usize>> = decoded
        .iter()
        .zip(&commanded)
        .map(|(d, c)| (0..ticks).filter(|&t| d[t] != c[t]).collect())
        .collect();
    let shaped_ticks = (0..ticks)
        .filter(|&t| (0..n).any(|s| decoded[s][t] != commanded[s][t]))
        .count();
    let max_error_us = p.source_pulses.as_ref().map(|src| {
        src.iter()
            .zip(&decoded)
            .flat_map(|(a, b)| a.iter().zip(b).map(|(&x, &y)| x.abs_diff(y)))
            .max()
            .map_or(0.0, |d| f64::from(d) / 4.0)
    });
    let data = ServoData {
        format: 1,
        kind: if p.show.is_some() { "show" } else { "servo" },
        clip: &p.clip,
        source: p.source.as_deref(),
        rig: p.rig.as_deref(),
        rate_hz: stream.rate_hz,
        ticks,
        servos: p
            .names
            .into_iter()
            .zip(&stream.limits)
            .map(|(name, l)| ServoInfo {
                name,
                min_qus: l.min_qus,
                max_qus: l.max_qus,
                neutral_qus: l.neutral_qus,
                max_step_qus: l.max_step_qus,
            })
            .collect(),
        decoded,
        commanded,
        source_pulses: p.source_pulses,
        shaped,
        shaped_ticks,
        show: p.show,
    };
    let json = serde_json::to_string(&data).expect("page data serialises");
    ServoPage {
        html: fill(SERVO_PAGE, SERVO_JS, &p.title, &json),
        ticks,
        servos: n,
        shaped_ticks,
        max_error_us,
    }
}

/// Runs the show at `path` with the command script at `cues` (or its first
/// cue list, as `mocap play` does) for at most `max_s` seconds, and builds
/// its page: the servo curves as for a clip, over the clips that played
/// (transitions marked) and the script's commands and the cues' events.
/// A servo show plays on its own rig table (`rig`, when given, names its
/// servos); a motion show plays through `rig`.
pub fn load_show(
    path: &Path,
    cues: Option<&Path>,
    rig_path: Option<&Path>,
    max_s: f64,
) -> Result<ServoPage, ViewError> {
    let read = |p: &Path| {
        std::fs::read(p).map_err(|e| ViewError::Read {
            path: p.to_path_buf(),
            source: e,
        })
    };
    let bytes = read(path)?;
    let show = mocap_decoder::Show::parse(&bytes).map_err(|e| ViewError::Clip {
        path: path.to_path_buf(),
        source: e,
    })?;
    let script = match cues {
        Some(p) => {
            let text = String::from_utf8_lossy(&read(p)?).into_owned();
            Script::parse(&text, &p.display().to_string(), &show).map_err(ViewError::Script)?
        }
        None => Script::first_list_or_clip(&show),
    };
    let rig = rig_path.map(Rig::read_file).transpose()?;
    let played = show_stream(&show, &script, Protocol::Maestro, rig.as_ref(), None, max_s)
        .map_err(|e| ViewError::Servo {
            path: path.to_path_buf(),
            source: e,
        })?;
    let stream = &played.stream;
    let ticks = played.timeline.len().min(stream.clip_ticks);
    let n = stream.limits.len();
    let names = match (&rig, rig_path) {
        (Some(r), Some(rp)) if r.servos.len() != n => {
            return Err(ViewError::ServoMismatch {
                clip: path.to_path_buf(),
                rig: rp.to_path_buf(),
                what: format!("the show drives {n} servos, the rig {}", r.servos.len()),
            })
        }
        (Some(r), _) => r.servos.iter().map(|s| s.name.clone()).collect(),
        (None, _) => (0..n).map(|i| format!("servo {i}")).collect(),
    };
    let clips = (0..show.clip_count())
        .map(|i| {
            let e = show.entry(i).map_err(|e| ViewError::Clip {
                path: path.to_path_buf(),
                source: e,
            })?;
            Ok(ShowClipInfo {
                name: e.name.to_string(),
                seconds: f64::from(e.frames) * f64::from(show.header().frame_time_ns()) * 1e-9,
                loops: e.looping.is_some(),
            })
        })
        .collect::<Result<Vec<_>, ViewError>>()?;
    let mut segments: Vec<Segment> = Vec::new();
    for (t, now) in played.timeline[..ticks].iter().enumerate() {
        let state = match now.state {
            State::Idle => "idle",
            State::Playing => "playing",
            State::Blending => "blending",
            State::Held => "held",
            State::Stopped => "stopped",
            State::Ended => "ended",
        };
        match segments.last_mut() {
            Some(s) if s.clip == now.clip && s.state == state => s.to = t + 1,
            _ => segments.push(Segment {
                from: t,
                to: t + 1,
                clip: now.clip,
                state,
            }),
        }
    }
    let tick_of = |us: u64| (us as f64 * stream.rate_hz / 1e6).round() as usize;
    let mut cue_marks: Vec<(usize, String)> = script
        .commands
        .iter()
        .map(|(at, r)| (tick_of(*at), format!("{r:?}")))
        .chain(played.events.iter().map(|(at, text)| {
            let text = text.split_once(' ').map_or(text.as_str(), |x| x.1);
            (tick_of(*at), text.trim_start_matches("event ").to_string())
        }))
        .collect();
    cue_marks.sort_by_key(|c| c.0);
    let show_name = file_name(path);
    let parts = Parts {
        title: show_name.clone(),
        clip: show_name,
        source: None,
        rig: rig.as_ref().map(|r| r.name.clone()),
        names,
        source_pulses: None,
        show: Some(ShowData {
            clips,
            segments,
            cues: cue_marks,
        }),
    };
    Ok(build(parts, stream.targets(), stream, ticks))
}

impl From<RigError> for ViewError {
    fn from(e: RigError) -> Self {
        ViewError::Rig(Box::new(e))
    }
}
