//! `mocap play` and `mocap send`: a clip played through a servo rig into
//! serial servo-controller commands (Pololu Maestro compact protocol,
//! SSC-32 text), and a clip framed for the firmware's streaming mode. The
//! byte streams are built here; the CLI writes them to a port or a file,
//! paced in real time unless `--fast`.

use mocap_decoder::{Clip, Player};
use mocap_servo::{maestro, ssc32, stream, Limiter, Message, ServoLimits};

use crate::clipfile;
use crate::fixed;
use crate::rig::{Rig, ServoTracks};

/// Serial servo-controller protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Protocol {
    /// Pololu Maestro compact protocol: Set Target `0x84 ch low7 high7`
    /// in quarter-microseconds.
    Maestro,
    /// Lynxmotion SSC-32 group move: `#<ch>P<µs>…T<ms>\r`.
    Ssc32,
}

/// Most servos a rig may drive here.
pub const MAX_SERVOS: usize = 64;
/// Most channels a clip may have for `play` (the host player's capacity).
const MAX_CHANNELS: usize = 4096;
/// Upper bound on the ticks of the return to neutral.
const MAX_STOP_TICKS: usize = 100_000;

/// A played clip: the bytes to send at each servo tick and what was sent.
#[derive(Clone, Debug)]
pub struct ServoStream {
    /// Servo ticks per second.
    pub rate_hz: f64,
    /// The bytes of each tick (the clip, then the return to neutral).
    pub ticks: Vec<Vec<u8>>,
    /// The pulse sent to each servo (rig order) at each tick, ¼ µs.
    pub pulses: Vec<Vec<u16>>,
    /// Ticks of the clip itself; the rest return the servos to neutral.
    pub clip_ticks: usize,
    /// The rig's own signals at the tick rate, with their clamp reports
    /// (motion clips; `None` for servo clips, already in servo space).
    pub tracks: Option<ServoTracks>,
    /// The limits every pulse was held to, rig order.
    pub limits: Vec<ServoLimits>,
}

impl ServoStream {
    /// All bytes in order.
    pub fn bytes(&self) -> Vec<u8> {
        self.ticks.concat()
    }
}

/// Plays a servo clip (one with a rig table, SPEC.md §3.5) at its rig's
/// rate or `rate_hz`: each channel's decoded angle becomes its servo's
/// pulse through `RigServo::pulse_qus` — the firmware's own integer
/// mapping — then the same [`Limiter`] and return to neutral as
/// [`servo_stream`].
pub fn servo_clip_stream(
    clip: &Clip<'_>,
    protocol: Protocol,
    rate_hz: Option<f64>,
) -> Result<ServoStream, String> {
    let rig = clip.rig().ok_or("not a servo clip: give --rig")?;
    let servos: Vec<_> = rig.servos().collect();
    if servos.len() > MAX_SERVOS {
        return Err(format!("{} servos, at most {MAX_SERVOS}", servos.len()));
    }
    // Integer timing and limits, exactly as the firmware computes them
    // (`tick_count`, `tick_us`, `RigServo::max_step_qus`).
    let rate_mhz = match rate_hz {
        Some(r) if r.is_finite() && r > 0.0 => {
            (r * 1000.0).round().clamp(1.0, f64::from(u32::MAX)) as u32
        }
        Some(r) => return Err(format!("servo rate {r} Hz must be positive")),
        None => rig.rate_mhz(),
    };
    let rate_hz = f64::from(rate_mhz) / 1000.0;
    let limits: Vec<ServoLimits> = servos
        .iter()
        .map(|s| {
            let (lo, hi) = s.pulse_range_qus();
            ServoLimits::new(lo, hi, s.neutral_qus, s.max_step_qus(rate_mhz))
                .map_err(|e| format!("servo output {}: {e}", s.output))
        })
        .collect::<Result<_, _>>()?;
    let duration_us = clip.header().duration_us();
    let count = mocap_decoder::tick_count(duration_us, rate_mhz) as usize;
    let mut player = Box::new(Player::<MAX_SERVOS>::new(clip).map_err(|e| e.to_string())?);
    let mut out = [0i32; MAX_SERVOS];
    let targets = (0..count).map(move |i| {
        let t_us = mocap_decoder::tick_us(i as u64, rate_mhz);
        player
            .sample_at(t_us, &mut out)
            .map_err(|e| e.to_string())
            .map(|()| {
                servos
                    .iter()
                    .zip(&out)
                    .map(|(s, &v)| s.pulse_qus(v))
                    .collect::<Vec<u16>>()
            })
    });
    let outputs: Vec<u16> = clip
        .rig()
        .map(|r| r.servos().map(|s| s.output).collect())
        .unwrap_or_default();
    drive(targets, &limits, &outputs, protocol, rate_hz, count, None)
}

/// Samples `clip` at `rate_hz` with `sample_at`, maps it through `rig`
/// (expression, angle range, speed and acceleration limits), holds every
/// pulse to the rig's pulse range and speed with [`Limiter`], then brings
/// every servo back to neutral at its speed limit.
pub fn servo_stream(
    clip: &Clip<'_>,
    rig: &Rig,
    protocol: Protocol,
    rate_hz: f64,
) -> Result<ServoStream, String> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(format!("servo rate {rate_hz} Hz must be positive"));
    }
    let n_servos = rig.servos.len();
    if n_servos > MAX_SERVOS {
        return Err(format!(
            "{}: {n_servos} servos, at most {MAX_SERVOS}",
            rig.file
        ));
    }
    let skeleton = clipfile::skeleton(clip);
    let channels = rig.resolve(&skeleton).map_err(|e| e.to_string())?;
    let h = clip.header();
    let n = h.channel_count();
    if n > MAX_CHANNELS {
        return Err(format!(
            "{n} channels, `play` handles at most {MAX_CHANNELS}"
        ));
    }
    // The clip at the servo rate, sampled exactly as the MCU would.
    let period_us = 1e6 / rate_hz;
    let count = (h.duration_us() as f64 / period_us).floor() as usize + 1;
    let mut player = Box::new(Player::<MAX_CHANNELS>::new(clip).map_err(|e| e.to_string())?);
    let mut out = vec![0i32; n];
    let mut frames = Vec::with_capacity(count * n);
    for i in 0..count {
        let t_us = (i as f64 * period_us).round() as u64;
        player
            .sample_at(t_us, &mut out)
            .map_err(|e| e.to_string())?;
        frames.extend_from_slice(&out);
    }
    let metres_per_unit = f64::from(h.source_unit_nm()) * 1e-9;
    let motion = fixed::from_fixed(&skeleton, 1.0 / rate_hz, &frames, metres_per_unit);
    let tracks = rig.servo_tracks(&motion, &channels, metres_per_unit);

    // The last line of defence: whatever the tracks say, no pulse leaves
    // the rig's range or moves faster than its speed limit.
    let limits: Vec<ServoLimits> = rig
        .servos
        .iter()
        .map(|s| {
            let (lo, hi) = s.quarter_us_range();
            let step = s.max_speed.map_or(0.0, |v| {
                (v / rate_hz / s.degrees_per_us() * 4.0).ceil().max(1.0)
            });
            ServoLimits::new(
                lo,
                hi,
                s.neutral_quarter_us().clamp(lo, hi),
                step.min(f64::from(u16::MAX)) as u16,
            )
            .map_err(|e| format!("{}: servo {}: {e}", rig.file, s.name))
        })
        .collect::<Result<_, _>>()?;
    let outputs: Vec<u16> = rig.servos.iter().map(|s| s.output).collect();
    let targets: Vec<Result<Vec<u16>, String>> = (0..count)
        .map(|i| Ok(tracks.servos.iter().map(|t| t.pulses[i]).collect()))
        .collect();
    drive(
        targets,
        &limits,
        &outputs,
        protocol,
        rate_hz,
        count,
        Some(tracks),
    )
}

/// Holds every tick's targets to `limits` with [`Limiter`] — whatever they
/// are, no pulse leaves its range or moves faster than its speed limit —
/// encodes them, and returns every servo to neutral at its speed limit.
/// The limiter starts at neutral (the servos' real position at power-on is
/// unknown): the first ticks move towards the clip's first pose at the
/// speed limit.
fn drive(
    targets: impl IntoIterator<Item = Result<Vec<u16>, String>>,
    limits: &[ServoLimits],
    outputs: &[u16],
    protocol: Protocol,
    rate_hz: f64,
    count: usize,
    tracks: Option<ServoTracks>,
) -> Result<ServoStream, String> {
    let n_servos = limits.len();
    let idle = ServoLimits::new(6000, 6000, 6000, 0).map_err(|e| e.to_string())?;
    let mut all = [idle; MAX_SERVOS];
    all[..n_servos].copy_from_slice(limits);
    let mut limiter = Limiter::new(all).map_err(|e| e.to_string())?;
    let time_ms = (1000.0 / rate_hz).round().clamp(1.0, f64::from(u16::MAX)) as u16;
    let encode = |pulses: &[u16]| command(protocol, outputs, pulses, time_ms);
    let mut ticks = Vec::with_capacity(count + 16);
    let mut sent = Vec::with_capacity(count + 16);
    let mut want = [6000u16; MAX_SERVOS];
    let mut held = [6000u16; MAX_SERVOS];
    for t in targets {
        let t = t?;
        want[..n_servos].copy_from_slice(&t[..n_servos]);
        limiter.apply(&want, &mut held).map_err(|e| e.to_string())?;
        ticks.push(encode(&held[..n_servos])?);
        sent.push(held[..n_servos].to_vec());
    }
    let clip_ticks = ticks.len();
    for _ in 0..MAX_STOP_TICKS {
        let done = limiter.stop_step(&mut held).map_err(|e| e.to_string())?;
        ticks.push(encode(&held[..n_servos])?);
        sent.push(held[..n_servos].to_vec());
        if done {
            break;
        }
    }
    Ok(ServoStream {
        rate_hz,
        ticks,
        pulses: sent,
        clip_ticks,
        tracks,
        limits: limits.to_vec(),
    })
}

/// One tick's command bytes for `pulses` (¼ µs) on `outputs`.
fn command(
    protocol: Protocol,
    outputs: &[u16],
    pulses: &[u16],
    time_ms: u16,
) -> Result<Vec<u8>, String> {
    match protocol {
        Protocol::Maestro => {
            let mut out = vec![0u8; outputs.len() * maestro::SET_TARGET_LEN];
            for (i, (&o, &p)) in outputs.iter().zip(pulses).enumerate() {
                let ch =
                    u8::try_from(o).map_err(|_| format!("output {o} is not a Maestro channel"))?;
                let at = i * maestro::SET_TARGET_LEN;
                maestro::set_target(ch, p, &mut out[at..])
                    .map_err(|e| format!("output {o}: {e}"))?;
            }
            Ok(out)
        }
        Protocol::Ssc32 => {
            // One group move over consecutive outputs.
            let mut order: Vec<(u16, u16)> = outputs
                .iter()
                .copied()
                .zip(pulses.iter().copied())
                .collect();
            order.sort_unstable();
            let first = order.first().map_or(0, |&(o, _)| o);
            if order
                .iter()
                .enumerate()
                .any(|(i, &(o, _))| usize::from(o) != usize::from(first) + i)
            {
                return Err("ssc32: the rig's outputs must be consecutive channels".into());
            }
            let first = u8::try_from(first)
                .map_err(|_| format!("output {first} is not an SSC-32 channel"))?;
            let ordered: Vec<u16> = order.iter().map(|&(_, p)| p).collect();
            let mut out = vec![0u8; ssc32::group_move_max_len(ordered.len())];
            let len =
                ssc32::group_move(first, &ordered, time_ms, &mut out).map_err(|e| e.to_string())?;
            out.truncate(len);
            Ok(out)
        }
    }
}

/// The frames `mocap send` writes: `Hello`, the clip in chunks of at most
/// [`stream::MAX_CHUNK_LEN`] bytes, then `Play` (SPEC.md §8).
pub fn clip_frames(clip: &[u8], looped: bool) -> Result<Vec<Vec<u8>>, String> {
    let total = u32::try_from(clip.len()).map_err(|_| "clip larger than 4 GB".to_string())?;
    let mut frames = Vec::new();
    let mut push = |m: &Message<'_>| -> Result<(), String> {
        let mut buf = [0u8; stream::MAX_FRAME_LEN];
        let len = stream::encode_frame(m, &mut buf).map_err(|e| e.to_string())?;
        frames.push(buf[..len].to_vec());
        Ok(())
    };
    push(&Message::Hello {
        version: stream::PROTOCOL_VERSION,
    })?;
    for (i, chunk) in clip.chunks(stream::MAX_CHUNK_LEN).enumerate() {
        push(&Message::ClipChunk {
            offset: (i * stream::MAX_CHUNK_LEN) as u32,
            total,
            bytes: chunk,
        })?;
    }
    push(&Message::Play { loop_: looped })?;
    Ok(frames)
}
