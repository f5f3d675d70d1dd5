//! Servo clips (`mocap encode --rig`): the rig's servo signals coded in
//! servo space. The clip's skeleton is the rig — one root joint per servo,
//! named after it, with one `Zrotation` channel holding the servo angle in
//! degrees of travel — and the rig table (SPEC.md §3.5) maps each decoded
//! angle to its pulse with the servo's limits, so the MCU writes decoded
//! values straight to its outputs.

use mocap_decoder::consts::rig_flag as flag;
use mocap_decoder::{consts, tick_count, tick_us, Clip, RigServo};

use crate::clipfile;
use crate::container::{assemble, frame_time_ns, varint, zigzag};
use crate::encode::{self, Bound, CodecChoice, EncodeError, EncodeOptions};
use crate::motion::{ChannelKind, Joint, Motion, Skeleton};
use crate::rig::{Rig, Servo, ServoTracks};

/// Why a servo clip could not be made or measured.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ServoClipError {
    /// A servo's angle range is empty or reversed.
    #[error("servo {servo}: angle range must be increasing")]
    AngleRangeNotIncreasing {
        /// The servo's name.
        servo: String,
    },
    /// More servos than the header's 32-bit count.
    #[error("too many servos")]
    TooManyServos(usize),
    /// The clip has no rig table.
    #[error("not a servo clip (no rig table)")]
    NotAServoClip,
    /// The clip and the reference ticks have different servo counts.
    #[error("servo count differs from the reference")]
    ServoCountDiffers {
        /// Servos in the clip.
        clip: usize,
        /// Servos in the reference.
        reference: usize,
    },
    /// The bound has no angle part.
    #[error("a servo clip needs a bound in degrees of servo travel (e.g. 0.5deg)")]
    NoAngleBound,
    /// A rig-rate clip misses the bound at the ticks after every tightening
    /// round.
    #[error("could not meet {bound_deg}° at the rig's ticks after tightening")]
    BoundNotMetAtTicks {
        /// The bound, degrees of servo travel.
        bound_deg: f64,
    },
    /// The servo motion could not be encoded.
    #[error(transparent)]
    Encode(#[from] EncodeError),
    /// The coded servo motion does not parse (a bug).
    #[error("internal error: {0}")]
    CodedClipRejected(#[source] mocap_decoder::Error),
    /// The clip with the rig table does not parse (a bug).
    #[error("internal error: servo clip rejected: {0}")]
    ServoClipRejected(#[source] mocap_decoder::Error),
    /// The clip does not parse, decode or sample.
    #[error(transparent)]
    Clip(#[from] mocap_decoder::Error),
}

/// The servo signals as a motion: servo `i` is root joint `i` with one
/// `Zrotation` channel, in degrees of servo travel, at the capture's rate.
pub fn servo_motion(rig: &Rig, tracks: &ServoTracks) -> Motion {
    let angles: Vec<&[f64]> = tracks.servos.iter().map(|t| &t.angles[..]).collect();
    signals_motion(rig, &angles, tracks.frame_time)
}

/// Servo angles `[servo][frame]` (degrees of travel) as a motion of one
/// root joint per servo, named after it, with one `Zrotation` channel.
fn signals_motion(rig: &Rig, angles: &[&[f64]], frame_time: f64) -> Motion {
    let joints = rig
        .servos
        .iter()
        .map(|s| Joint {
            name: s.name.clone(),
            parent: None,
            offset: [0.0; 3],
            channels: vec![ChannelKind::Zrotation],
            end_site: false,
        })
        .collect();
    let n = angles.len();
    let frames = angles.first().map_or(0, |a| a.len());
    let mut values = vec![0.0; frames * n];
    for (i, a) in angles.iter().enumerate() {
        for (f, v) in a.iter().enumerate() {
            values[f * n + i] = *v;
        }
    }
    Motion {
        skeleton: Skeleton { joints },
        frame_time,
        values,
    }
}

/// A rig servo as the rig table stores it (SPEC.md §3.5): integer
/// millidegrees and quarter-microseconds, the form the decoder and the
/// firmware map and limit with: [`Servo::rig_servo`], the one conversion
/// from the file's form.
pub fn table_entry(s: &Servo) -> RigServo {
    s.rig_servo()
}

/// The rig's servo rate in millihertz.
pub fn rate_mhz(rig: &Rig) -> u32 {
    (rig.rate_hz * 1000.0)
        .round()
        .clamp(1.0, f64::from(u32::MAX)) as u32
}

/// The rig section in its compact form (SPEC.md §3.5.1): a leading `0`,
/// then each servo as flags and only what differs from the previous one.
pub fn rig_section(rig: &Rig) -> Result<Vec<u8>, ServoClipError> {
    let mut out = vec![0];
    varint(&mut out, rate_mhz(rig));
    varint(&mut out, rig.servos.len() as u32);
    let mut prev: Option<RigServo> = None;
    for (servo, s) in rig.servos.iter().zip(rig.servos.iter().map(table_entry)) {
        let at = out.len();
        out.push(0);
        let mut flags = 0;
        let next_output = prev.map_or(Some(0), |p| p.output.checked_add(1));
        if next_output == Some(s.output) {
            flags |= flag::OUTPUT_NEXT;
        } else {
            varint(&mut out, u32::from(s.output));
        }
        let range = |r: &RigServo| {
            (
                r.angle_lo_mdeg,
                r.angle_hi_mdeg,
                r.pulse_lo_qus,
                r.pulse_hi_qus,
            )
        };
        if prev.is_some_and(|p| range(&p) == range(&s)) {
            flags |= flag::SAME_RANGE;
        } else {
            let span = u32::try_from(i64::from(s.angle_hi_mdeg) - i64::from(s.angle_lo_mdeg))
                .ok()
                .filter(|&v| v > 0)
                .ok_or_else(|| ServoClipError::AngleRangeNotIncreasing {
                    servo: servo.name.clone(),
                })?;
            if s.angle_lo_mdeg % 1000 == 0 && span % 1000 == 0 {
                flags |= flag::ANGLE_DEG;
                zigzag(&mut out, s.angle_lo_mdeg / 1000);
                varint(&mut out, span / 1000);
            } else {
                zigzag(&mut out, s.angle_lo_mdeg);
                varint(&mut out, span);
            }
            // SAME_MAP where the previous servo's line (the decoder's rule)
            // gives exactly this servo's pulses.
            if prev.is_some_and(|p| {
                p.line_qus(i64::from(s.angle_lo_mdeg)) == Some(s.pulse_lo_qus)
                    && p.line_qus(i64::from(s.angle_hi_mdeg)) == Some(s.pulse_hi_qus)
            }) {
                flags |= flag::SAME_MAP;
            } else {
                varint(&mut out, u32::from(s.pulse_lo_qus));
                zigzag(
                    &mut out,
                    i32::from(s.pulse_hi_qus) - i32::from(s.pulse_lo_qus),
                );
            }
        }
        if u32::from(s.neutral_qus) == (u32::from(s.pulse_lo_qus) + u32::from(s.pulse_hi_qus)) / 2 {
            flags |= flag::MID_NEUTRAL;
        } else {
            varint(&mut out, u32::from(s.neutral_qus));
        }
        if prev.is_some_and(|p| p.max_speed_mdeg_s == s.max_speed_mdeg_s) {
            flags |= flag::SAME_SPEED;
        } else if s.max_speed_mdeg_s % 1000 == 0 {
            flags |= flag::SPEED_DEG;
            varint(&mut out, s.max_speed_mdeg_s / 1000);
        } else {
            varint(&mut out, s.max_speed_mdeg_s);
        }
        out[at] = flags;
        prev = Some(s);
    }
    Ok(out)
}

/// The servo form of the compact header (SPEC.md §3.4.1): `varint 0`,
/// frame time, frame count, servo count — all a player needs of a servo
/// clip's skeleton when the names are left out.
pub fn servo_header_section(frame_time_ns: u32, frame_count: u32, servos: u32) -> Vec<u8> {
    let mut out = Vec::new();
    for v in [0, frame_time_ns, frame_count, servos] {
        varint(&mut out, v);
    }
    out
}

/// `clip` (a coded servo motion) as a servo clip: the rig section added
/// after the header, the rig digest (SPEC.md §3.6) at the end, and with `names` [`ServoNames::Strip`] the header
/// replaced by its servo form.
pub fn attach_rig(clip: &[u8], rig: &Rig, names: ServoNames) -> Result<Vec<u8>, ServoClipError> {
    let parsed = Clip::parse(clip).map_err(ServoClipError::CodedClipRejected)?;
    let h = parsed.header();
    let mut sections: Vec<(u8, Vec<u8>)> = Vec::new();
    for s in parsed.sections() {
        if s.id == consts::SECTION_HEADER || s.id == consts::SECTION_HEADER_COMPACT {
            if names == ServoNames::Strip {
                let servos = u32::try_from(h.channel_count())
                    .map_err(|_| ServoClipError::TooManyServos(h.channel_count()))?;
                sections.push((
                    consts::SECTION_HEADER_COMPACT,
                    servo_header_section(h.frame_time_ns(), h.frame_count(), servos),
                ));
            } else {
                sections.push((s.id, s.bytes.to_vec()));
            }
            sections.push((consts::SECTION_RIG, rig_section(rig)?));
        } else {
            sections.push((s.id, s.bytes.to_vec()));
        }
    }
    // Ancillary, last: old decoders skip it.
    sections.push((
        consts::SECTION_RIG_DIGEST,
        rig.digest().to_le_bytes().to_vec(),
    ));
    let bytes = assemble(&sections);
    Clip::parse(&bytes).map_err(ServoClipError::ServoClipRejected)?;
    Ok(bytes)
}

/// Pulses (¼ µs) a servo clip decodes to, `[servo][frame]`, through the
/// decoder's own mapping (`RigServo::pulse_qus`).
pub fn decoded_pulses(clip: &Clip<'_>) -> Result<Vec<Vec<u16>>, ServoClipError> {
    let rig = clip.rig().ok_or(ServoClipError::NotAServoClip)?;
    let frames = clipfile::decode_all(clip)?;
    let n = clip.header().channel_count().max(1);
    Ok(rig
        .servos()
        .enumerate()
        .map(|(i, s)| {
            frames
                .iter()
                .skip(i)
                .step_by(n)
                .map(|&v| s.pulse_qus(v))
                .collect()
        })
        .collect())
}

/// The servo signals at the rig's ticks (SPEC.md §3.5 timing: `tick_count`
/// ticks over the capture's duration, tick `i` at `tick_us(i)`): the
/// capture-rate track interpolated linearly at each tick time, held after
/// its last frame — exactly what a lossless capture-rate servo clip plays
/// there with `sample_at`, up to the fixed-point rounding.
#[derive(Clone, Debug, PartialEq)]
pub struct TickTracks {
    /// Servo rate, millihertz.
    pub rate_mhz: u32,
    /// Tick times, µs.
    pub times_us: Vec<u64>,
    /// Commanded angle per servo per tick, degrees: `[servo][tick]`.
    pub angles: Vec<Vec<f64>>,
    /// The rig's pulse for each of those angles, ¼ µs: `[servo][tick]`.
    pub pulses: Vec<Vec<u16>>,
}

impl TickTracks {
    /// Number of ticks.
    pub fn ticks(&self) -> usize {
        self.times_us.len()
    }
}

/// The capture-rate tracks resampled at the rig's ticks (see
/// [`TickTracks`]).
pub fn tick_tracks(rig: &Rig, tracks: &ServoTracks) -> TickTracks {
    let rate_mhz = rate_mhz(rig);
    let ft_ns = u64::from(frame_time_ns(tracks.frame_time));
    let frames = tracks.frames();
    let duration_us = frames as u64 * ft_ns / 1000;
    let count = tick_count(duration_us, rate_mhz);
    let times_us: Vec<u64> = (0..count).map(|i| tick_us(i, rate_mhz)).collect();
    let at = |angles: &[f64], us: u64| {
        let ns = us.saturating_mul(1000);
        let i = (ns / ft_ns) as usize;
        match (angles.get(i), angles.get(i + 1)) {
            (Some(&a), Some(&b)) => a + (b - a) * ((ns % ft_ns) as f64 / ft_ns as f64),
            // Held after the last frame.
            _ => angles.last().copied().unwrap_or(0.0),
        }
    };
    let angles: Vec<Vec<f64>> = tracks
        .servos
        .iter()
        .map(|t| times_us.iter().map(|&us| at(&t.angles, us)).collect())
        .collect();
    let pulses = rig
        .servos
        .iter()
        .zip(&angles)
        .map(|(s, a)| a.iter().map(|&x| s.angle_to_quarter_us(x)).collect())
        .collect();
    TickTracks {
        rate_mhz,
        times_us,
        angles,
        pulses,
    }
}

/// The tick signals as a servo motion (as [`servo_motion`]) whose frames
/// are the rig's ticks: frame time `1 / rate`, one frame per tick.
pub fn tick_motion(rig: &Rig, ticks: &TickTracks) -> Motion {
    let angles: Vec<&[f64]> = ticks.angles.iter().map(|a| &a[..]).collect();
    signals_motion(rig, &angles, 1000.0 / f64::from(ticks.rate_mhz))
}

/// Error of a servo clip where the firmware plays it: `sample_at` at every
/// tick of `ticks`, against [`TickTracks`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TickError {
    /// Ticks compared.
    pub ticks: usize,
    /// Largest servo-angle error, degrees of travel.
    pub max_deg: f64,
    /// Largest pulse error (decoder's mapping against the rig's), µs.
    pub max_us: f64,
    /// RMS pulse error over all servos and ticks, µs.
    pub rms_us: f64,
}

/// Samples `clip` at every tick of `ticks` and measures it (see
/// [`TickError`]).
pub fn tick_error(clip: &Clip<'_>, ticks: &TickTracks) -> Result<TickError, ServoClipError> {
    let table = clip.rig().ok_or(ServoClipError::NotAServoClip)?;
    let servos: Vec<RigServo> = table.servos().collect();
    let n = clip.header().channel_count();
    if n != ticks.angles.len() {
        return Err(ServoClipError::ServoCountDiffers {
            clip: n,
            reference: ticks.angles.len(),
        });
    }
    let samples = clipfile::sample_all(clip, ticks.times_us.iter().copied())?;
    let mut e = TickError {
        ticks: ticks.ticks(),
        ..TickError::default()
    };
    let mut sum2 = 0.0;
    for (t, row) in samples.chunks(n.max(1)).enumerate() {
        for (i, &v) in row.iter().enumerate() {
            let deg = (f64::from(v) / 1000.0 - ticks.angles[i][t]).abs();
            e.max_deg = e.max_deg.max(deg);
            let us =
                (f64::from(servos[i].pulse_qus(v)) - f64::from(ticks.pulses[i][t])).abs() / 4.0;
            e.max_us = e.max_us.max(us);
            sum2 += us * us;
        }
    }
    let count = (n * ticks.ticks()).max(1);
    e.rms_us = (sum2 / count as f64).sqrt();
    Ok(e)
}

/// At which rate a servo clip codes its signals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ServoRate {
    /// One frame per servo tick of the rig (`rate_hz`), the only times the
    /// firmware and `mocap play` sample a servo clip.
    Rig,
    /// One frame per frame of the captured motion.
    Capture,
}

/// What a servo clip keeps of the servo names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ServoNames {
    /// No names: servos are channels `0..S` (players never read names).
    Strip,
    /// Servo names as the header's joint names.
    Keep,
}

/// Options of [`encode_servo_clip`].
#[derive(Clone, Debug)]
pub struct ServoEncodeOptions {
    /// Codec (`Auto`: the smallest).
    pub codec: CodecChoice,
    /// Bound in degrees of servo travel.
    pub bound: Bound,
    /// Key interval of the index codec, block length of the predictive one.
    pub key_interval: Option<u16>,
    /// Coding rate.
    pub rate: ServoRate,
    /// Servo names.
    pub names: ServoNames,
}

/// A servo clip and where its bytes and errors are.
#[derive(Clone, Debug)]
pub struct ServoClip {
    /// The clip.
    pub bytes: Vec<u8>,
    /// Codec used.
    pub codec: CodecChoice,
    /// Coded frames and their rate (Hz).
    pub frames: usize,
    /// Coded frame rate, Hz.
    pub frame_rate_hz: f64,
    /// Largest servo-angle error at the coded frames (the encoder's proof).
    pub frame_max_deg: f64,
    /// Pulse error at the coded frames of a capture-rate clip against the
    /// capture-rate pulses (max, RMS µs); `None` for a rig-rate clip.
    pub frame_pulse_us: Option<(f64, f64)>,
    /// Error at the rig's ticks, where it is played (bounded for a rig-rate
    /// clip, measured against linear interpolation for a capture-rate one).
    pub ticks: TickError,
    /// Section ids and lengths, in table order.
    pub sections: Vec<(u8, usize)>,
}

/// Encodes a rig's servo tracks as a servo clip (SPEC.md §3.5) whose
/// angle error is within `opts.bound` at its coded frames and, coded at the
/// rig's rate, at the rig's ticks (against [`tick_tracks`]).
pub fn encode_servo_clip(
    rig: &Rig,
    tracks: &ServoTracks,
    opts: &ServoEncodeOptions,
) -> Result<ServoClip, ServoClipError> {
    let bound_deg = opts.bound.angle_deg.ok_or(ServoClipError::NoAngleBound)?;
    let ticks = tick_tracks(rig, tracks);
    let motion = match opts.rate {
        ServoRate::Rig => tick_motion(rig, &ticks),
        ServoRate::Capture => servo_motion(rig, tracks),
    };
    // The encoder proves the bound at the coded frames. A rig-rate clip's
    // frames are the ticks (up to the µs rounding of the tick times), so it
    // is tightened until the bound also holds at the ticks. A capture-rate
    // clip is bounded at its frames only: between them the reference is a
    // convention (linear here, a spline in pca-spline), and its tick error
    // is reported, not enforced.
    let mut bound = opts.bound;
    for _ in 0..8 {
        let enc = encode::encode(
            &motion,
            &EncodeOptions {
                key_bits: None,
                codec: opts.codec,
                bound,
                metres_per_unit: 1e-3,
                key_interval: opts.key_interval,
                index_layout: Default::default(),
                pattern: Default::default(),
            },
        )?;
        let bytes = attach_rig(&enc.bytes, rig, opts.names)?;
        let clip = Clip::parse(&bytes)?;
        let tick = tick_error(&clip, &ticks)?;
        if opts.rate == ServoRate::Rig && tick.max_deg > bound_deg {
            bound.angle_deg = Some(bound.angle_deg.unwrap_or(bound_deg) * 0.9);
            continue;
        }
        let frame_pulse_us = match opts.rate {
            ServoRate::Rig => None,
            ServoRate::Capture => {
                let pulses = decoded_pulses(&clip)?;
                let errors: Vec<_> = tracks
                    .servos
                    .iter()
                    .zip(&pulses)
                    .map(|(t, p)| crate::rig::servo_error(&t.pulses, p))
                    .collect();
                let max = errors.iter().map(|e| e.max_us).fold(0.0, f64::max);
                let rms = (errors.iter().map(|e| e.rms_us * e.rms_us).sum::<f64>()
                    / errors.len().max(1) as f64)
                    .sqrt();
                Some((max, rms))
            }
        };
        let sections = clip.sections().map(|s| (s.id, s.bytes.len())).collect();
        return Ok(ServoClip {
            bytes,
            codec: enc.codec,
            frames: motion.frames(),
            frame_rate_hz: 1.0 / motion.frame_time,
            frame_max_deg: enc.metrics.angle_max_deg,
            frame_pulse_us,
            ticks: tick,
            sections,
        });
    }
    Err(ServoClipError::BoundNotMetAtTicks { bound_deg })
}

/// The summary `mocap encode --rig` prints. "Raw" is 16-bit frames (one
/// `u16` pulse per servo per frame, what Arduino exporters store) at the
/// capture's frame rate and at the rig's tick rate.
pub fn report(output: &std::path::Path, rig: &Rig, tracks: &ServoTracks, sc: &ServoClip) -> String {
    let seconds = tracks.frames() as f64 * tracks.frame_time;
    let raw_capture = 2 * rig.servos.len() * tracks.frames();
    let raw_rig = 2 * rig.servos.len() * sc.ticks.ticks;
    let n = sc.bytes.len() as f64;
    let sections: Vec<String> = sc
        .sections
        .iter()
        .map(|(id, len)| format!("0x{id:02x} {len}"))
        .collect();
    let mut s = format!(
        "{}: servo clip, {} servos, {} bytes = {:.0} B/s of a {:.2} s show; {:.1}x less than raw 16-bit frames at the capture's {:.0} Hz ({} B), {:.1}x at the rig's {:.0} Hz ({} B); coded at {:.0} Hz ({} frames, {})\n",
        output.display(),
        rig.servos.len(),
        sc.bytes.len(),
        n / seconds,
        seconds,
        raw_capture as f64 / n,
        1.0 / tracks.frame_time,
        raw_capture,
        raw_rig as f64 / n,
        f64::from(rate_mhz(rig)) / 1000.0,
        raw_rig,
        sc.frame_rate_hz,
        sc.frames,
        sc.codec.name(),
    );
    s.push_str(&format!(
        "  servo angle max {:.3}° at the coded frames, {:.3}° at the {} rig ticks (pulse error max {:.2} µs, RMS {:.2} µs)",
        sc.frame_max_deg, sc.ticks.max_deg, sc.ticks.ticks, sc.ticks.max_us, sc.ticks.rms_us
    ));
    if let Some((max, rms)) = sc.frame_pulse_us {
        s.push_str(&format!(
            "; at the capture frames pulse error max {max:.2} µs, RMS {rms:.2} µs"
        ));
    }
    s.push_str(&format!("\n  sections: {}\n", sections.join(", ")));
    s
}
