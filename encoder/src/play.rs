//! `mocap play` and `mocap send`: a clip played through a servo rig into
//! serial servo-controller commands (Pololu Maestro compact protocol,
//! SSC-32 text), and a clip framed for the firmware's streaming mode. The
//! byte streams are built here; the CLI writes them to a port or a file,
//! paced in real time unless `--fast`.

use mocap_decoder::power::{level_at, LevelSampler, MAX_LEVEL};
use mocap_decoder::{tick_count, tick_us, Clip, Player, RigServo};
use mocap_servo::output::{MaestroOutput, ServoOutput, Ssc32Output};
use mocap_servo::record::{RecordError, SerialRecorder};
use mocap_servo::{
    ssc32, stream, HardLimit, HardLimits, Message, OutputError, Playback, PlaybackError,
    ServoLimits,
};

pub use mocap_servo::{FigureId, Fit, Identity, Policy};

use crate::clipfile::HOST_MAX_CHANNELS;
use crate::rig::{Rig, RigError, Servo, ServoTracks};
use crate::{clipfile, fixed, servo_clip};

/// Serial servo-controller protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Protocol {
    /// Pololu Maestro compact protocol: Set Target `0x84 ch low7 high7`
    /// in quarter-microseconds.
    Maestro,
    /// Lynxmotion SSC-32 group move: `#<ch>P<µs>…T<ms>\r`.
    Ssc32,
}

/// Why a clip could not be played or framed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlayError {
    /// `--rate` is zero, negative or not a number.
    #[error("servo rate {rate_hz} Hz must be positive")]
    BadRate {
        /// The rate given, Hz.
        rate_hz: f64,
    },
    /// A clip without a rig table played without a rig.
    #[error("not a servo clip: give --rig")]
    NotAServoClip,
    /// `--poses` of a clip whose servo targets cannot be taken.
    #[error("--poses needs a servo clip (mocap encode --rig)")]
    PosesNeedServoClip(#[source] Box<PlayError>),
    /// The clip's length does not fit the stream's 32-bit `total`.
    #[error("clip larger than 4 GB")]
    ClipTooLarge {
        /// The clip's length, bytes.
        len: usize,
    },
    /// `--passes 0`.
    #[error("--passes must be at least 1")]
    NoPasses,
    /// The clip does not parse, decode or sample.
    #[error(transparent)]
    Clip(#[from] mocap_decoder::Error),
    /// The rig does not fit the clip's skeleton.
    #[error(transparent)]
    Rig(#[from] RigError),
    /// The rig's servos cannot be played (count, limits).
    #[error(transparent)]
    Playback(#[from] PlaybackError),
    /// The servo controller's output refuses the rig's channels.
    #[error("{}: {source}", protocol.name())]
    Output {
        /// The controller's protocol.
        protocol: Protocol,
        /// Why.
        source: mocap_servo::Error,
    },
    /// A tick could not be written.
    #[error(transparent)]
    Tick(#[from] OutputError<RecordError>),
    /// A tick's pulses do not make a `Pose` message.
    #[error(transparent)]
    Pose(mocap_servo::Error),
    /// A message does not fit a stream frame.
    #[error(transparent)]
    Frame(mocap_servo::Error),
}

impl Protocol {
    /// The protocol's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Maestro => "maestro",
            Protocol::Ssc32 => "ssc32",
        }
    }
}

/// Most servos a rig may drive here.
pub const MAX_SERVOS: usize = mocap_servo::output::MAX_SERVOS;
/// Serial bytes of one tick (SSC-32 text is the longer).
const TICK_BYTES: usize = ssc32::group_move_max_len(MAX_SERVOS);

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
    /// Played on a figure's hard limits ([`servo_clip_stream_on`]): how.
    pub figure: Option<FigureReport>,
    /// What played, to replay it up to a stop ([`ServoStream::rest_after`]).
    replay: Replay,
}

/// The inputs of [`drive`], kept so that a stop can be replayed.
#[derive(Clone, Debug)]
struct Replay {
    targets: Vec<Vec<u16>>,
    servos: Vec<RigServo>,
    rate_mhz: u32,
    protocol: Protocol,
    figure: Option<(Figure, Identity)>,
}

/// A figure's hard limits as `mocap play --rig` applies them to a servo
/// clip: the figure's rig, and what to do with a clip made for another.
#[derive(Clone, Debug)]
pub struct Figure {
    /// The figure's servos as a rig table holds them: a clip whose rig
    /// table is exactly this was made for this figure.
    pub servos: Vec<RigServo>,
    /// The figure's rate, millihertz (part of its identity).
    pub rate_mhz: u32,
    /// Its hard limits, one per output.
    pub limits: Vec<HardLimit>,
    /// What to do with a clip made for another rig.
    pub policy: Policy,
    /// The figure's rig digest (SPEC.md §3.6, [`Rig::digest`]).
    pub digest: u32,
}

impl Figure {
    /// The figure of a rig file.
    pub fn from_rig(rig: &Rig, policy: Policy) -> Self {
        Figure {
            servos: rig.servos.iter().map(Servo::rig_servo).collect(),
            rate_mhz: servo_clip::rate_mhz(rig),
            limits: rig.hard_limits(),
            policy,
            digest: rig.digest(),
        }
    }

    /// The figure's identity, to compare clips with.
    pub fn id(&self) -> FigureId<'_> {
        FigureId {
            rate_mhz: self.rate_mhz,
            servos: &self.servos,
            digest: self.digest,
        }
    }
}

/// How a servo clip played on a figure's hard limits.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FigureReport {
    /// How the clip's rig compares with the figure's (rig table and digest).
    pub identity: Identity,
    /// How the clip's servos lie against the hard limits.
    pub fit: Fit,
    /// Per servo, rig order.
    pub clamps: Vec<HardClamps>,
}

/// What a figure's hard limits did to one servo's pulses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HardClamps {
    /// The servo's output.
    pub output: u16,
    /// Ticks whose pulse the hard limits changed.
    pub ticks: u32,
    /// The most they moved a pulse, ¼ µs.
    pub worst_qus: u16,
}

impl ServoStream {
    /// The pulse targets the playback loop was given, one per servo (rig
    /// order) per tick of the clip, ¼ µs: what [`ServoStream::pulses`] sent
    /// before range, speed and hard limits acted on it.
    pub fn targets(&self) -> &[Vec<u16>] {
        &self.replay.targets
    }

    /// The ticks that bring every servo to rest when the playback stops
    /// after its first `ticks` ticks (`mocap play` stopped by Ctrl-C or
    /// SIGTERM): the same return to rest as after the clip's last tick —
    /// the playback loop replayed up to the stop, then `Playback::park` at
    /// the speed (and the figure's acceleration) limits. Past the clip's
    /// own ticks, the rest of the return already under way.
    pub fn rest_after(&self, ticks: usize) -> Result<Vec<Vec<u8>>, PlayError> {
        if ticks >= self.clip_ticks {
            return Ok(self.ticks.get(ticks..).unwrap_or_default().to_vec());
        }
        let r = &self.replay;
        let cut = drive(
            r.targets[..ticks].to_vec(),
            &r.servos,
            r.rate_mhz,
            r.protocol,
            None,
            r.figure.as_ref().map(|(f, id)| (f, *id)),
        )?;
        Ok(cut.ticks[cut.clip_ticks..].to_vec())
    }

    /// All bytes in order.
    pub fn bytes(&self) -> Vec<u8> {
        self.ticks.concat()
    }
}

/// Servo rate in millihertz from an optional `--rate` (Hz).
fn rate_mhz(rate_hz: Option<f64>, default_mhz: u32) -> Result<u32, PlayError> {
    match rate_hz {
        Some(r) if r.is_finite() && r > 0.0 => {
            Ok((r * 1000.0).round().clamp(1.0, f64::from(u32::MAX)) as u32)
        }
        Some(rate_hz) => Err(PlayError::BadRate { rate_hz }),
        None => Ok(default_mhz),
    }
}

/// The clip sampled with `sample_at` at every servo tick (the integer
/// timing the firmware uses: `tick_count`, `tick_us`), `ticks × channels`.
/// With a power schedule (`power`, [`parse_power`]), each tick's level
/// from it and the poses through `mocap_decoder::power::LevelSampler`,
/// the firmware's (SPEC.md §6.1).
fn sample_ticks(
    clip: &Clip<'_>,
    rate_mhz: u32,
    power: &[(u64, u8)],
) -> Result<(usize, Vec<i32>), PlayError> {
    let count = tick_count(clip.header().duration_us(), rate_mhz);
    if power.is_empty() {
        let samples = clipfile::sample_all(clip, (0..count).map(|i| tick_us(i, rate_mhz)))?;
        return Ok((count as usize, samples));
    }
    let mut player = Box::new(Player::<HOST_MAX_CHANNELS>::new(clip)?);
    let mut sampler = Box::new(LevelSampler::<HOST_MAX_CHANNELS>::new(rate_mhz));
    let mut out = vec![0i32; player.channel_count()];
    let mut samples = Vec::with_capacity(out.len() * count as usize);
    for i in 0..count {
        sampler.set_level(level_at(power, tick_us(i, rate_mhz)));
        sampler.sample(&mut player, i, &mut out)?;
        samples.extend_from_slice(&out);
    }
    Ok((count as usize, samples))
}

/// What one power level (SPEC.md §6.1) does to a servo clip, against
/// level 0 (every tick sampled): `mocap target levels`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelError {
    /// The level: one tick in `2^level` sampled.
    pub level: u8,
    /// Poses sampled per second at the clip's rate.
    pub samples_per_s: f64,
    /// The largest difference from level 0 of any servo at any tick, degrees of travel.
    pub max_deg: f64,
    /// The RMS difference over every servo and tick, degrees.
    pub rms_deg: f64,
    /// The largest difference of any pulse target, µs.
    pub max_pulse_us: f64,
}

/// Every power level of a servo clip at its rig's rate (or `rate_hz`):
/// its angles at each level against level 0's.
pub fn level_errors(clip: &Clip<'_>, rate_hz: Option<f64>) -> Result<Vec<LevelError>, PlayError> {
    let rig = clip.rig().ok_or(PlayError::NotAServoClip)?;
    let servos: Vec<RigServo> = rig.servos().collect();
    let rate_mhz = rate_mhz(rate_hz, rig.rate_mhz())?;
    let (_, exact) = sample_ticks(clip, rate_mhz, &[])?;
    let n = servos.len().max(1);
    (0..=MAX_LEVEL)
        .map(|level| {
            let (_, got) = sample_ticks(clip, rate_mhz, &[(0, level)])?;
            let (mut max, mut sum, mut max_pulse) = (0f64, 0f64, 0f64);
            for (i, (&g, &e)) in got.iter().zip(&exact).enumerate() {
                let d = (f64::from(g) - f64::from(e)).abs() / 1000.0;
                max = max.max(d);
                sum += d * d;
                let s = &servos[i % n];
                let dp = (f64::from(s.pulse_qus(g)) - f64::from(s.pulse_qus(e))).abs() / 4.0;
                max_pulse = max_pulse.max(dp);
            }
            Ok(LevelError {
                level,
                samples_per_s: f64::from(rate_mhz) / 1000.0 / f64::from(1u32 << level),
                max_deg: max,
                rms_deg: (sum / exact.len().max(1) as f64).sqrt(),
                max_pulse_us: max_pulse,
            })
        })
        .collect()
}

/// A power schedule (`mocap play --power`, the firmware's `MOCAP_POWER`):
/// comma-separated `LEVEL[@TIME]`, TIME in seconds (`2.5`, `2.5s`) or
/// milliseconds (`300ms`), in increasing time order; a level without a
/// time starts at 0. Levels 0 (every tick sampled) to
/// `mocap_decoder::power::MAX_LEVEL` (one tick in 16), SPEC.md §6.1.
/// Returns `(from_us, level)` pairs.
pub fn parse_power(text: &str) -> Result<Vec<(u64, u8)>, String> {
    let mut steps: Vec<(u64, u8)> = Vec::new();
    for item in text.split(',').map(str::trim) {
        let (level, time) = match item.split_once('@') {
            Some((l, t)) => (l.trim(), Some(t.trim())),
            None => (item, None),
        };
        let level: u8 = level
            .parse()
            .ok()
            .filter(|&l| l <= MAX_LEVEL)
            .ok_or_else(|| format!("power level `{level}` is not 0 to {MAX_LEVEL}"))?;
        let from_us = match time {
            None => 0,
            Some(t) => {
                let (number, scale) = if let Some(ms) = t.strip_suffix("ms") {
                    (ms, 1e3)
                } else {
                    (t.strip_suffix('s').unwrap_or(t), 1e6)
                };
                let seconds: f64 = number
                    .trim()
                    .parse()
                    .ok()
                    .filter(|v: &f64| v.is_finite() && *v >= 0.0)
                    .ok_or_else(|| format!("power time `{t}` is not a time (2.5, 2.5s, 300ms)"))?;
                (seconds * scale).round() as u64
            }
        };
        if steps.last().is_some_and(|&(last, _)| from_us < last) {
            return Err(format!("power step `{item}` goes back in time"));
        }
        steps.push((from_us, level));
    }
    Ok(steps)
}

/// A servo clip's pulse targets at every servo tick, before any limiter:
/// each channel's decoded angle (`sample_at` at the integer tick times)
/// through its servo's `RigServo::pulse_qus`, the firmware's own mapping.
#[derive(Clone, Debug)]
pub struct ClipTargets {
    /// The rig table's servos.
    pub servos: Vec<RigServo>,
    /// Servo rate, millihertz.
    pub rate_mhz: u32,
    /// One pulse per servo (rig order) per tick, ¼ µs.
    pub targets: Vec<Vec<u16>>,
}

/// The targets of a servo clip (one with a rig table, SPEC.md §3.5) at its
/// rig's rate or `rate_hz`.
pub fn servo_clip_targets(clip: &Clip<'_>, rate_hz: Option<f64>) -> Result<ClipTargets, PlayError> {
    servo_clip_targets_at(clip, rate_hz, &[])
}

/// [`servo_clip_targets`] at the power levels of a schedule ([`parse_power`]).
pub fn servo_clip_targets_at(
    clip: &Clip<'_>,
    rate_hz: Option<f64>,
    power: &[(u64, u8)],
) -> Result<ClipTargets, PlayError> {
    let rig = clip.rig().ok_or(PlayError::NotAServoClip)?;
    let servos: Vec<RigServo> = rig.servos().collect();
    let rate_mhz = rate_mhz(rate_hz, rig.rate_mhz())?;
    let (count, samples) = sample_ticks(clip, rate_mhz, power)?;
    let n = clip.header().channel_count().max(1);
    let targets = (0..count)
        .map(|i| {
            let pose = &samples[i * n..(i + 1) * n];
            servos
                .iter()
                .zip(pose)
                .map(|(s, &v)| s.pulse_qus(v))
                .collect()
        })
        .collect();
    Ok(ClipTargets {
        servos,
        rate_mhz,
        targets,
    })
}

/// Plays a servo clip at its rig's rate or `rate_hz`: [`servo_clip_targets`]
/// played on [`Playback`], the firmware's own loop — every pulse held to its
/// servo's range and speed, from neutral and back to it.
pub fn servo_clip_stream(
    clip: &Clip<'_>,
    protocol: Protocol,
    rate_hz: Option<f64>,
) -> Result<ServoStream, PlayError> {
    servo_clip_stream_at(clip, None, protocol, rate_hz, &[])
}

/// [`servo_clip_stream`] (`figure` `None`) or [`servo_clip_stream_on`], at
/// the power levels of a schedule ([`parse_power`]).
pub fn servo_clip_stream_at(
    clip: &Clip<'_>,
    figure: Option<&Figure>,
    protocol: Protocol,
    rate_hz: Option<f64>,
    power: &[(u64, u8)],
) -> Result<ServoStream, PlayError> {
    let t = servo_clip_targets_at(clip, rate_hz, power)?;
    let on = figure.map(|f| (f, f.id().compare(clip)));
    drive(t.targets, &t.servos, t.rate_mhz, protocol, None, on)
}

/// [`servo_clip_stream`] on a figure's hard limits: every pulse through the
/// clip's own limits, then the figure's (`Playback::with_hard_limits`), the
/// return to rest at the figure's neutrals and speeds. A clip made for
/// another rig plays or is refused ([`PlayError::Playback`]) by the
/// figure's policy.
pub fn servo_clip_stream_on(
    clip: &Clip<'_>,
    figure: &Figure,
    protocol: Protocol,
    rate_hz: Option<f64>,
) -> Result<ServoStream, PlayError> {
    servo_clip_stream_at(clip, Some(figure), protocol, rate_hz, &[])
}

/// Samples a motion clip at the rig's rate (or `rate_hz`), maps it through
/// `rig` (expression, angle range, speed and acceleration limits, with the
/// clamp report), then plays the targets on [`Playback`] as
/// [`servo_clip_stream`] does.
pub fn servo_stream(
    clip: &Clip<'_>,
    rig: &Rig,
    protocol: Protocol,
    rate_hz: Option<f64>,
) -> Result<ServoStream, PlayError> {
    servo_stream_at(clip, rig, protocol, rate_hz, &[])
}

/// [`servo_stream`] at the power levels of a schedule ([`parse_power`]).
pub fn servo_stream_at(
    clip: &Clip<'_>,
    rig: &Rig,
    protocol: Protocol,
    rate_hz: Option<f64>,
    power: &[(u64, u8)],
) -> Result<ServoStream, PlayError> {
    let rate_mhz = rate_mhz(rate_hz, servo_clip::rate_mhz(rig))?;
    let skeleton = clipfile::skeleton(clip);
    let channels = rig.resolve(&skeleton)?;
    let (count, samples) = sample_ticks(clip, rate_mhz, power)?;
    let metres_per_unit = f64::from(clip.header().source_unit_nm()) * 1e-9;
    let frame_time = 1000.0 / f64::from(rate_mhz);
    let motion = fixed::from_fixed(&skeleton, frame_time, &samples, metres_per_unit);
    let tracks = rig.servo_tracks(&motion, &channels, metres_per_unit);
    let servos: Vec<RigServo> = rig.servos.iter().map(Servo::rig_servo).collect();
    let targets: Vec<Vec<u16>> = (0..count)
        .map(|i| tracks.servos.iter().map(|t| t.pulses[i]).collect())
        .collect();
    drive(targets, &servos, rate_mhz, protocol, Some(tracks), None)
}

/// Plays every tick's targets on `mocap_servo::Playback`, the firmware's
/// own playback loop: held to the servos' pulse range and speed — whatever
/// they are, no pulse leaves its range or moves faster than its speed limit
/// — encoded by the `mocap_servo::output` the firmware drives, then every
/// servo returned to neutral at its speed limit. The playback starts at
/// neutral (the servos' real position at power-on is unknown): the first
/// ticks move towards the clip's first pose at the speed limit.
pub(crate) fn drive(
    targets: impl IntoIterator<Item = Vec<u16>>,
    servos: &[RigServo],
    rate_mhz: u32,
    protocol: Protocol,
    tracks: Option<ServoTracks>,
    figure: Option<(&Figure, Identity)>,
) -> Result<ServoStream, PlayError> {
    let targets: Vec<Vec<u16>> = targets.into_iter().collect();
    let mut playback = Playback::<MAX_SERVOS>::new(servos.iter().copied(), rate_mhz)?;
    let mut report = None;
    if let Some((f, identity)) = figure {
        let hard = HardLimits::new(&f.limits);
        let (p, fit) = playback.with_hard_limits(&hard, identity.is_same(), f.policy)?;
        playback = p;
        report = Some(FigureReport {
            identity,
            fit,
            clamps: Vec::new(),
        });
    }
    let limits = playback.limits().to_vec();
    let rate_hz = f64::from(rate_mhz) / 1000.0;
    let time_ms = (1000.0 / rate_hz).round().clamp(1.0, f64::from(u16::MAX)) as u16;
    let outputs: Vec<u16> = servos.iter().map(|s| s.output).collect();
    let port = SerialRecorder::<TICK_BYTES>::new();
    let refused = |source| PlayError::Output { protocol, source };
    let (ticks, pulses, clip_ticks) = match protocol {
        Protocol::Maestro => {
            let output = MaestroOutput::new(&port, &outputs).map_err(refused)?;
            play(&mut playback, output, &port, &targets)?
        }
        Protocol::Ssc32 => {
            let output = Ssc32Output::new(&port, &outputs, time_ms).map_err(refused)?;
            play(&mut playback, output, &port, &targets)?
        }
    };
    if let Some(r) = &mut report {
        r.clamps = servos
            .iter()
            .zip(playback.hard_clamps().iter().zip(playback.hard_worst()))
            .map(|(s, (&ticks, &worst_qus))| HardClamps {
                output: s.output,
                ticks,
                worst_qus,
            })
            .collect();
    }
    Ok(ServoStream {
        rate_hz,
        ticks,
        pulses,
        clip_ticks,
        tracks,
        limits,
        figure: report,
        replay: Replay {
            targets,
            servos: servos.to_vec(),
            rate_mhz,
            protocol,
            figure: figure.map(|(f, id)| (f.clone(), id)),
        },
    })
}

/// Every tick's bytes and pulses, and the number of the clip's own ticks.
type Played = (Vec<Vec<u8>>, Vec<Vec<u16>>, usize);

/// [`drive`]'s loop on one output writing into `port`: a tick per target,
/// then `Playback::park`; each tick's bytes are taken from `port`.
fn play<O: ServoOutput<Error = RecordError>>(
    playback: &mut Playback<MAX_SERVOS>,
    mut output: O,
    port: &SerialRecorder<TICK_BYTES>,
    targets: &[Vec<u16>],
) -> Result<Played, OutputError<RecordError>> {
    let (mut ticks, mut sent) = (Vec::new(), Vec::new());
    let mut take = |pulses: &[u16]| -> Result<(), OutputError<RecordError>> {
        ticks.push(
            port.with_bytes(<[u8]>::to_vec)
                .map_err(OutputError::Device)?,
        );
        port.clear();
        sent.push(pulses.to_vec());
        Ok(())
    };
    let n = playback.count();
    let mut want = [0u16; MAX_SERVOS];
    let mut clip_ticks = 0;
    for t in targets {
        want[..n].copy_from_slice(&t[..n]);
        playback.tick(&want, &mut output)?;
        take(playback.held())?;
        clip_ticks += 1;
    }
    playback.park(&mut output, &mut take)?;
    Ok((ticks, sent, clip_ticks))
}

/// One frame (delimiter included) of `message`.
fn frame(message: &Message<'_>) -> Result<Vec<u8>, PlayError> {
    let mut buf = [0u8; stream::MAX_FRAME_LEN];
    let len = stream::encode_frame(message, &mut buf).map_err(PlayError::Frame)?;
    Ok(buf[..len].to_vec())
}

/// The first frame of a session: a lone `00`, which ends whatever the
/// receiver holds (line noise, a frame cut short), then `Hello`.
fn hello() -> Result<Vec<u8>, PlayError> {
    let mut bytes = vec![stream::DELIMITER];
    bytes.extend(frame(&Message::Hello {
        version: stream::PROTOCOL_VERSION,
    })?);
    Ok(bytes)
}

/// The frames `mocap send` writes: `00` and `Hello`, then `passes` times
/// the clip in chunks of at most [`stream::MAX_CHUNK_LEN`] bytes in order
/// followed by `Play` (SPEC.md §8). One pass is the plain upload; more
/// passes are a carousel for a one-way lossy link: the firmware takes each
/// chunk from whichever pass brings it intact, ignores the copies, and
/// starts the clip once every chunk has arrived and one `Play` has (a
/// `Play` before the last missing chunk is remembered), so a `Play` after
/// every pass both starts the clip as early as possible and survives the
/// loss of most `Play`s.
pub fn clip_frames(clip: &[u8], looped: bool, passes: u32) -> Result<Vec<Vec<u8>>, PlayError> {
    let total =
        u32::try_from(clip.len()).map_err(|_| PlayError::ClipTooLarge { len: clip.len() })?;
    if passes == 0 {
        return Err(PlayError::NoPasses);
    }
    let mut pass = Vec::new();
    for (i, chunk) in clip.chunks(stream::MAX_CHUNK_LEN).enumerate() {
        pass.push(frame(&Message::ClipChunk {
            offset: (i * stream::MAX_CHUNK_LEN) as u32,
            total,
            bytes: chunk,
        })?);
    }
    pass.push(frame(&Message::Play { loop_: looped })?);
    let mut frames = vec![hello()?];
    for _ in 0..passes {
        frames.extend(pass.iter().cloned());
    }
    Ok(frames)
}

/// What `mocap send --poses` writes: `00` and `Hello`, one `Pose` per servo
/// tick of a servo clip at its rig's rate — `seq` = the tick's number
/// (wrapping), `pulses` = [`servo_clip_targets`], which the firmware's
/// limiter holds to the rig's limits — then `Stop` (SPEC.md §8).
#[derive(Clone, Debug)]
pub struct PoseStream {
    /// Servo rate, millihertz: `Pose` `i` is due at `tick_us(i, rate_mhz)`.
    pub rate_mhz: u32,
    /// `00 Hello`, the poses, `Stop`.
    pub frames: Vec<Vec<u8>>,
}

impl PoseStream {
    /// When frame `i` is due, µs after the start: `Hello` at 0, `Pose`
    /// `k` at tick `k`, `Stop` one tick after the last pose.
    pub fn due_us(&self, i: usize) -> u64 {
        let ticks = self.frames.len().saturating_sub(2) as u64;
        tick_us((i as u64).saturating_sub(1).min(ticks), self.rate_mhz)
    }
}

/// What `mocap send` writes when it is stopped: a lone `00`, which ends the
/// frame the stop may have cut short, then `Stop` (the firmware parks every
/// servo at its speed limits).
pub fn stop_frame() -> Result<Vec<u8>, PlayError> {
    let mut bytes = vec![stream::DELIMITER];
    bytes.extend(frame(&Message::Stop)?);
    Ok(bytes)
}

/// The frames of `mocap send --poses` for a servo clip.
pub fn pose_frames(clip: &Clip<'_>) -> Result<PoseStream, PlayError> {
    let t =
        servo_clip_targets(clip, None).map_err(|e| PlayError::PosesNeedServoClip(Box::new(e)))?;
    let mut frames = vec![hello()?];
    for (i, pulses) in t.targets.iter().enumerate() {
        let pose = Message::pose(i as u16, pulses).map_err(PlayError::Pose)?;
        frames.push(frame(&pose)?);
    }
    frames.push(frame(&Message::Stop)?);
    Ok(PoseStream {
        rate_mhz: t.rate_mhz,
        frames,
    })
}
