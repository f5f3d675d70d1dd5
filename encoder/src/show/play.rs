//! `mocap play` of a show: the show's [`ShowRunner`] (cue lists, triggers,
//! idle clips) driven by a command script at the rig's tick rate, each
//! tick's pose through the one servo playback loop ([`crate::play`]) — the
//! firmware's show mode runs the same code on the same commands.
//!
//! A script (`--cues cues.txt`) has one command per line, `#` comments:
//!
//! ```text
//! 0      list main        # start a cue list
//! 3.2    trigger 1        # input 1 fires
//! 5      play talk        # play / fade <clip> <ms> / queue <clip>
//! 6      fade wave 400
//! 8      loop on          # loop on|off, hold, resume, stop
//! 9      status           # the firmware answers with a ShowStatus frame
//! 20     end              # stop the show here (default: when it is done)
//! ```

use mocap_decoder::show::player::Now;
use mocap_decoder::show::runner::{Command, Output};
use mocap_decoder::{tick_us, Show, ShowRunner};
pub use mocap_servo::stream::ShowRequest;

use super::{MAX_CHANNELS, PLAYER_WORDS};
use crate::located::{LocatedError, Position};
use crate::play::{self, Figure, PlayError, Protocol, ServoStream};
use crate::rig::{Rig, Servo};
use crate::{clipfile, fixed, servo_clip};

/// The host's show runner.
pub type HostShowRunner<'a> = ShowRunner<'a, PLAYER_WORDS, MAX_CHANNELS>;

/// A command script: commands at show times, and where to end.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Script {
    /// Commands (`ShowRequest::Run`, `ShowRequest::Status`) and their show
    /// times, µs, in time order.
    pub commands: Vec<(u64, ShowRequest)>,
    /// `end` at this time, µs.
    pub end_us: Option<u64>,
}

impl Script {
    /// Parses a script for `show` (clip and list names resolved); `file`
    /// only names the script in errors.
    pub fn parse(text: &str, file: &str, show: &Show<'_>) -> Result<Script, LocatedError> {
        let cues = show.cues();
        let mut script = Script::default();
        for (n, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let at = |msg: String| {
                LocatedError::at(
                    file,
                    Position {
                        line: n + 1,
                        column: 1,
                    },
                    msg,
                )
            };
            let words: Vec<&str> = line.split_whitespace().collect();
            let t: f64 = words[0]
                .trim_end_matches('s')
                .parse()
                .ok()
                .filter(|t: &f64| t.is_finite() && *t >= 0.0)
                .ok_or_else(|| at(format!("`{}` is not a time in seconds", words[0])))?;
            let t_us = (t * 1e6).round() as u64;
            if script.commands.last().is_some_and(|(last, _)| *last > t_us) {
                return Err(at("commands must be in time order".into()));
            }
            let clip = |k: usize| -> Result<u16, LocatedError> {
                let name = words.get(k).ok_or_else(|| at("which clip?".into()))?;
                show.find(name)
                    .ok_or_else(|| at(format!("the show has no clip `{name}`")))
            };
            let arity = |k: usize| {
                if words.len() == k {
                    Ok(())
                } else {
                    Err(at(format!("`{}` takes {} argument(s)", words[1], k - 2)))
                }
            };
            let cmd = match words.get(1).copied() {
                Some("end") => {
                    arity(2)?;
                    script.end_us = Some(t_us);
                    continue;
                }
                Some("list") => {
                    arity(3)?;
                    let name = words[2];
                    Command::List(
                        cues.and_then(|c| c.find_list(name))
                            .ok_or_else(|| at(format!("the show has no cue list `{name}`")))?,
                    )
                }
                Some("trigger") => {
                    arity(3)?;
                    Command::Trigger(
                        words[2]
                            .parse()
                            .map_err(|_| at(format!("`{}` is not an input number", words[2])))?,
                    )
                }
                Some("play") => {
                    arity(3)?;
                    Command::Play(clip(2)?)
                }
                Some("fade") => {
                    arity(4)?;
                    Command::Fade {
                        clip: clip(2)?,
                        ms: words[3]
                            .trim_end_matches("ms")
                            .parse()
                            .map_err(|_| at(format!("`{}` is not milliseconds", words[3])))?,
                    }
                }
                Some("queue") => {
                    arity(3)?;
                    Command::Queue(clip(2)?)
                }
                Some("loop") => {
                    arity(3)?;
                    Command::Loop(match words[2] {
                        "on" => true,
                        "off" => false,
                        w => return Err(at(format!("loop on or off, not `{w}`"))),
                    })
                }
                Some("hold") => {
                    arity(2)?;
                    Command::Hold
                }
                Some("resume") => {
                    arity(2)?;
                    Command::Resume
                }
                Some("stop") => {
                    arity(2)?;
                    Command::Stop
                }
                Some("status") => {
                    arity(2)?;
                    script.commands.push((t_us, ShowRequest::Status));
                    continue;
                }
                Some(w) => return Err(at(format!(
                    "unknown command `{w}` (list, trigger, play, fade, queue, loop, hold, resume, stop, status, end)"
                ))),
                None => return Err(at("a time and a command".into())),
            };
            script.commands.push((t_us, ShowRequest::Run(cmd)));
        }
        Ok(script)
    }
}

impl Script {
    /// The script of a show run without one: its first cue list from time
    /// 0, or its first clip when it has no cue list.
    pub fn first_list_or_clip(show: &Show<'_>) -> Script {
        let first = match show.cues().filter(|c| c.list_count() > 0) {
            Some(_) => Command::List(0),
            None => Command::Play(0),
        };
        Script {
            commands: vec![(0, ShowRequest::Run(first))],
            end_us: None,
        }
    }
}

/// A played show: the servo stream and the cues' output events.
#[derive(Clone, Debug)]
pub struct ShowPlay {
    /// The ticks' bytes and pulses (the show, then the return to rest).
    pub stream: ServoStream,
    /// Output events (`gpio`, `serial` cues) and their show times, µs, as
    /// the firmware prints them (`# event …`).
    pub events: Vec<(u64, String)>,
    /// What the show player played at each tick of the show (its clip, its
    /// state: playing, blending, …), before the return to rest.
    pub timeline: Vec<Now>,
}

/// The line an output event prints on the host and on the firmware's UART.
pub fn event_text(t_us: u64, o: &Output<'_>) -> String {
    match o {
        Output::Gpio { pin, level } => {
            format!("# event t_us={t_us} gpio {pin} {}", u8::from(*level))
        }
        Output::Serial(bytes) => {
            let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02x}")).collect();
            format!("# event t_us={t_us} serial {}", hex.join(" "))
        }
    }
}

/// Most ticks a show plays without an `end` (one hour at 1 kHz).
pub const MAX_TICKS: u64 = 3_600_000;

/// Plays `show` with `script` at the rig's rate: a servo show on its own rig
/// table (on `figure`'s hard limits when given), a motion show through
/// `rig`. It ends at the script's `end`, or after `max_s` seconds, or once
/// nothing moves any more on its own (no cue list, no queue, the last clip
/// ended); then every servo returns to rest.
pub fn show_stream(
    show: &Show<'_>,
    script: &Script,
    protocol: Protocol,
    rig: Option<&Rig>,
    figure: Option<&Figure>,
    max_s: f64,
) -> Result<ShowPlay, PlayError> {
    let mut runner = Box::new(HostShowRunner::new(*show)?);
    let (servos, rate_mhz) = match (show.rig(), rig) {
        (Some(r), _) => (r.servos().collect::<Vec<_>>(), r.rate_mhz()),
        (None, Some(rig)) => (
            rig.servos.iter().map(Servo::rig_servo).collect(),
            servo_clip::rate_mhz(rig),
        ),
        (None, None) => return Err(PlayError::NotAServoClip),
    };
    let n = show.header().channel_count();
    let max_ticks = ((max_s.max(0.0) * f64::from(rate_mhz) / 1000.0) as u64).min(MAX_TICKS);
    let mut poses: Vec<i32> = Vec::new();
    let mut events = Vec::new();
    let mut timeline = Vec::new();
    let mut next = 0;
    let mut pose = vec![0i32; n];
    let mut ticks = 0u64;
    while ticks < max_ticks {
        let t = tick_us(ticks, rate_mhz);
        if script.end_us.is_some_and(|e| t > e) {
            break;
        }
        let mut emit = |at: u64, o: Output<'_>| events.push((at, event_text(at, &o)));
        while let Some((at, request)) = script.commands.get(next).filter(|(at, _)| *at <= t) {
            // A status request moves nothing (the firmware answers it).
            if let ShowRequest::Run(cmd) = request {
                runner.command(*cmd, *at, &mut emit)?;
            }
            next += 1;
        }
        timeline.push(runner.tick(t, &mut pose, &mut emit)?);
        poses.extend_from_slice(&pose);
        ticks += 1;
        if script.end_us.is_none() && next >= script.commands.len() && runner.is_done() {
            break;
        }
    }
    let targets: Vec<Vec<u16>> = match show.rig() {
        Some(_) => poses
            .chunks(n.max(1))
            .map(|p| servos.iter().zip(p).map(|(s, &v)| s.pulse_qus(v)).collect())
            .collect(),
        None => {
            let rig = rig.ok_or(PlayError::NotAServoClip)?;
            let clip = show.clip(0)?;
            let skeleton = clipfile::skeleton(&clip);
            let channels = rig.resolve(&skeleton)?;
            let metres = f64::from(show.header().source_unit_nm()) * 1e-9;
            let motion = fixed::from_fixed(&skeleton, 1000.0 / f64::from(rate_mhz), &poses, metres);
            let tracks = rig.servo_tracks(&motion, &channels, metres);
            (0..ticks as usize)
                .map(|i| tracks.servos.iter().map(|t| t.pulses[i]).collect())
                .collect()
        }
    };
    let identity = match figure {
        Some(f) => Some((f, f.id().compare(&show.clip(0)?))),
        None => None,
    };
    let stream = play::drive(targets, &servos, rate_mhz, protocol, None, identity)?;
    Ok(ShowPlay {
        stream,
        events,
        timeline,
    })
}

/// Show time between two `Sync` frames of `mocap send --cues`, µs.
pub const SYNC_EVERY_US: u64 = 1_000_000;

/// How long before its time `mocap send` sends a command, µs: the firmware
/// queues it ([`Command`]s act at their show time) and a late one acts late.
pub const SEND_AHEAD_US: u64 = 1_000_000;

/// The frames `mocap send show.mcb --cues` writes for the firmware's show
/// mode (SPEC.md §8.2), each with the time it is due: `00` and `Hello` and
/// the first `Show` frame at once (its arrival starts the show clock), every
/// other command [`SEND_AHEAD_US`] before its time, a `Sync` every
/// [`SYNC_EVERY_US`] of show time (the firmware then runs in lockstep: its
/// show clock never passes the last time vouched for, so every command acts
/// at its own time however the line delivers), then `End` at the script's
/// `end` (without one, a final `Sync` of `u32::MAX` ms lets the show run free).
pub fn command_frames(script: &Script) -> Result<Vec<(u64, Vec<u8>)>, PlayError> {
    use mocap_servo::stream::{self, Message, ShowOp};
    let ms = |us: u64| u32::try_from(us / 1000).unwrap_or(u32::MAX);
    let frame = |m: &Message<'_>| -> Result<Vec<u8>, PlayError> {
        let mut buf = [0u8; stream::MAX_FRAME_LEN];
        let len = stream::encode_frame(m, &mut buf).map_err(PlayError::Frame)?;
        Ok(buf[..len].to_vec())
    };
    let mut hello = vec![stream::DELIMITER];
    hello.extend(frame(&Message::Hello {
        version: stream::PROTOCOL_VERSION,
    })?);
    let mut out = vec![(0, hello)];
    let op_frame = |at: u64, op: ShowOp| {
        frame(&Message::Show {
            at_ms: ms(at),
            op: op as u8,
            arg: 0,
            ms: 0,
        })
    };
    let due = |at: u64| at.saturating_sub(SEND_AHEAD_US);
    // A `Sync` each second of show time (ties: the commands first), so the firmware's show
    // clock never passes a time whose commands are still on the line.
    let last = script
        .end_us
        .or(script.commands.last().map(|(at, _)| *at))
        .unwrap_or(0);
    let mut next_sync = 0u64;
    for (i, (at, request)) in script.commands.iter().enumerate() {
        while next_sync < *at {
            out.push((due(next_sync), op_frame(next_sync, ShowOp::Sync)?));
            next_sync += SYNC_EVERY_US;
        }
        let m = match request {
            ShowRequest::Run(cmd) => frame(&stream::show_message(ms(*at), *cmd))?,
            ShowRequest::Status => op_frame(*at, ShowOp::Status)?,
            ShowRequest::End => op_frame(*at, ShowOp::End)?,
            ShowRequest::Sync => op_frame(*at, ShowOp::Sync)?,
        };
        out.push((if i == 0 { 0 } else { due(*at) }, m));
    }
    while next_sync <= last {
        out.push((due(next_sync), op_frame(next_sync, ShowOp::Sync)?));
        next_sync += SYNC_EVERY_US;
    }
    match script.end_us {
        Some(end) => out.push((due(end), op_frame(end, ShowOp::End)?)),
        // No end: every command is sent; the show runs free from here.
        None => out.push((
            due(last),
            op_frame(u64::from(u32::MAX) * 1000, ShowOp::Sync)?,
        )),
    }
    // Due times never go back (a sender writes in order).
    let mut latest = 0;
    for (due, _) in &mut out {
        latest = latest.max(*due);
        *due = latest;
    }
    Ok(out)
}
