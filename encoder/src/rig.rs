//! Servo rigs: a TOML file that maps motion channels to the servos of an
//! animatronic figure, and the servo-space signals (pulse widths) a motion
//! produces on it.
//!
//! # The rig file
//!
//! ```toml
//! [rig]
//! name = "cmu-upper-body"
//! rate_hz = 50                 # servo update rate (default 50)
//!
//! [[servo]]
//! name = "neck_pan"
//! output = 0                   # controller channel / PWM index (unique)
//! channel = "Neck.Yrotation"   # "<Joint>.<Kind>" as in Skeleton::channel_names
//! scale = 1.0                  # optional, default 1
//! offset = 0.0                 # optional, default 0: degrees (mm for position channels)
//! invert = false               # optional: negate after scale and offset
//! angle = [-60.0, 60.0]        # servo travel in degrees; targets outside are clamped
//! pulse = [1000, 2000]         # µs at angle[0] and angle[1] (descending = reversed servo)
//! neutral = 1500               # µs, optional (default: middle of the pulse range)
//! max_speed = 250.0            # deg/s, optional
//! max_accel = 2000.0           # deg/s², optional
//! ```
//!
//! `assets/rigs/cmu_upper_body.toml` documents every key; `assets/rigs/README.md`
//! explains the units. Unknown keys are errors. Every error names the rig file,
//! the 1-based line and the 1-based column (in characters) of the offending
//! key or value, in the style of [`crate::bvh::BvhError`]:
//! `rig.toml:12:11: unknown channel "Nek.Yrotation" (did you mean "Neck.Yrotation"?)`.
//!
//! # From motion to pulses
//!
//! [`Rig::parse`] checks the file on its own; [`Rig::resolve`] binds each
//! servo's channel name to a channel index of a skeleton; [`Rig::servo_tracks`]
//! turns a motion into one pulse per servo per motion frame, in quarter
//! microseconds (`u16`; 1500 µs = 6000). Per servo and frame:
//!
//! 1. take the channel value: degrees for rotations, millimetres for
//!    positions (source units × `metres_per_unit` × 1000);
//! 2. rotations are unwrapped across ±180° jumps (each value within 180° of
//!    the previous one, as [`crate::fixed::unwrap_degrees`]), on the 360°
//!    branch nearest the servo's reachable range, switching branch with
//!    hysteresis when the channel has wound a turn ([`REWRAP_HYSTERESIS_DEG`]);
//! 3. apply the expression `angle = scale × value + offset`, negated if
//!    `invert`; a value that is not finite (NaN, ±∞, an overflow, or a
//!    rotation beyond ±[`MAX_ROTATION_DEG`]) is replaced by the angle of the
//!    `neutral` pulse and reported;
//! 4. clamp to `angle` (reported);
//! 5. limit speed and acceleration at the motion's frame rate, in one forward
//!    pass (reported): the servo *lags* behind its target rather than
//!    jumping, and catches up as soon as the limits allow;
//! 6. map linearly from `angle` to `pulse`, round to a quarter microsecond
//!    and clamp to the pulse range, so no output ever leaves it.

use crate::motion::{ChannelKind, Motion, Skeleton};
use serde::Deserialize;
use std::fmt::{self, Write as _};
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// Servo update rate when `[rig] rate_hz` is not given.
pub const DEFAULT_RATE_HZ: f64 = 50.0;
/// Shortest pulse a rig may ask for, in µs.
pub const MIN_PULSE_US: f64 = 400.0;
/// Longest pulse a rig may ask for, in µs.
pub const MAX_PULSE_US: f64 = 2600.0;
/// Output resolution: quarter microseconds per microsecond.
pub const QUARTER_US_PER_US: f64 = 4.0;

/// Hysteresis of the branch choice for rotation channels, in degrees of
/// the channel.
///
/// An unwrapped Euler angle can drift by whole turns (a shoulder that
/// circles twice ends 720° from where it started), and a servo with ±90°
/// of travel would then sit at its end stop although the pose is back in
/// reach. So the unwrapped value keeps its 360° branch (continuity) until
/// another branch (value ± k·360°) is closer to the servo's reachable
/// range by more than this margin; then it switches. A switch happens
/// only while the pose is out of reach on both branches, and the speed
/// and acceleration limits turn it into a move, not a jump. Each switch
/// is counted in [`ClampReport::rewraps`].
pub const REWRAP_HYSTERESIS_DEG: f64 = 30.0;

/// Rotation values beyond ± this many degrees (about 2.8 million turns)
/// cannot be unwrapped in `f64` and are treated like non-finite values.
pub const MAX_ROTATION_DEG: f64 = 1e9;

/// Tolerance (degrees) under which a servo is considered on target.
const LAG_EPS_DEG: f64 = 1e-9;

// ---------------------------------------------------------------------------
// Errors and positions
// ---------------------------------------------------------------------------

/// A 1-based line and column (in characters) in a rig file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Position {
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// 1-based column in characters (0 when unknown).
    pub column: usize,
}

impl Position {
    /// The position of byte offset `byte` in `text` (clamped to the text,
    /// and moved back to a character boundary).
    pub fn of_byte(text: &str, byte: usize) -> Position {
        let mut b = byte.min(text.len());
        while !text.is_char_boundary(b) {
            b -= 1;
        }
        let before = &text[..b];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        Position {
            line: before.matches('\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

/// A rig error: `file:line:column: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RigError {
    /// The rig file name as given to the reader.
    pub file: String,
    /// 1-based line (0 for I/O errors).
    pub line: usize,
    /// 1-based column in characters (0 for I/O errors).
    pub column: usize,
    /// What went wrong.
    pub message: String,
}

impl RigError {
    fn at(file: &str, pos: Position, message: impl Into<String>) -> RigError {
        RigError {
            file: file.to_string(),
            line: pos.line,
            column: pos.column,
            message: message.into(),
        }
    }
}

impl fmt::Display for RigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: {}",
            self.file, self.line, self.column, self.message
        )
    }
}

impl std::error::Error for RigError {}

// ---------------------------------------------------------------------------
// The rig
// ---------------------------------------------------------------------------

/// A parsed and checked rig file.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// The file name given to [`Rig::parse`] (used in error messages).
    pub file: String,
    /// `[rig] name`.
    pub name: String,
    /// `[rig] rate_hz`: the controller's servo update rate, in Hz.
    pub rate_hz: f64,
    /// The `[[servo]]` entries, in file order.
    pub servos: Vec<Servo>,
}

/// One `[[servo]]` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Servo {
    /// Servo name (unique in the rig).
    pub name: String,
    /// Controller channel / PWM index (unique in the rig).
    pub output: u16,
    /// The channel as written, `<Joint>.<Kind>` (kind spelled canonically).
    pub channel: String,
    /// Joint part of [`Servo::channel`].
    pub joint: String,
    /// Kind part of [`Servo::channel`].
    pub kind: ChannelKind,
    /// Expression: `angle = ±(scale × value + offset)`.
    pub scale: f64,
    /// Expression offset, in degrees (mm for position channels).
    pub offset: f64,
    /// Negate after scale and offset.
    pub invert: bool,
    /// Servo travel in degrees: `angle[0] < angle[1]`.
    pub angle: [f64; 2],
    /// Pulse width in µs at `angle[0]` and `angle[1]` (descending for a
    /// reversed servo).
    pub pulse: [f64; 2],
    /// Neutral pulse in µs, inside the pulse range.
    pub neutral: f64,
    /// Maximum speed in degrees per second.
    pub max_speed: Option<f64>,
    /// Maximum acceleration in degrees per second².
    pub max_accel: Option<f64>,
    /// Where the `channel` value is written in the rig file.
    pub channel_at: Position,
}

// Required keys are `Option`s here so that a missing key is reported at its
// table (the `toml` crate gives no position for a missing field).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    rig: Option<Spanned<RawRig>>,
    #[serde(default)]
    servo: Vec<Spanned<RawServo>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRig {
    name: Option<Spanned<String>>,
    rate_hz: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawServo {
    name: Option<Spanned<String>>,
    output: Option<Spanned<u16>>,
    channel: Option<Spanned<String>>,
    scale: Option<Spanned<f64>>,
    offset: Option<Spanned<f64>>,
    invert: Option<bool>,
    angle: Option<Spanned<Vec<f64>>>,
    pulse: Option<Spanned<Vec<f64>>>,
    neutral: Option<Spanned<f64>>,
    max_speed: Option<Spanned<f64>>,
    max_accel: Option<Spanned<f64>>,
}

fn parse_kind(s: &str) -> Option<ChannelKind> {
    ChannelKind::ALL
        .into_iter()
        .find(|k| k.name().eq_ignore_ascii_case(s))
}

impl Rig {
    /// Reads and parses a rig file. I/O errors have line and column 0.
    pub fn read_file(path: &Path) -> Result<Rig, RigError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            RigError::at(
                &file,
                Position::default(),
                format!("cannot read rig file: {e}"),
            )
        })?;
        Rig::parse(&text, &file)
    }

    /// Parses and checks rig text. `file` is only used in error messages.
    ///
    /// Checks: no unknown keys; at least one servo; servo names and outputs
    /// unique; `channel` of the form `<Joint>.<Kind>`; `scale` finite and
    /// non-zero, `offset` finite; `angle[0] < angle[1]`, both finite; both
    /// pulses within 400..=2600 µs and different; `neutral` inside the
    /// pulse range; `rate_hz`, `max_speed`, `max_accel` finite and positive.
    pub fn parse(text: &str, file: &str) -> Result<Rig, RigError> {
        let pos = |span: Range<usize>| Position::of_byte(text, span.start);
        let err = |span: Range<usize>, msg: String| Err(RigError::at(file, pos(span), msg));
        let raw: RawFile = toml::from_str(text).map_err(|e| {
            let p = e.span().map_or(Position { line: 1, column: 1 }, pos);
            RigError::at(file, p, e.message().trim_end().to_string())
        })?;

        let Some(raw_rig) = raw.rig else {
            return Err(RigError::at(
                file,
                Position { line: 1, column: 1 },
                "missing [rig] table (with at least `name`)",
            ));
        };
        let rig_span = raw_rig.span();
        let raw_rig = raw_rig.into_inner();
        let Some(raw_name) = raw_rig.name else {
            return err(rig_span, "missing key `name` in [rig]".into());
        };
        let name = raw_name.get_ref().trim().to_string();
        if name.is_empty() {
            return err(raw_name.span(), "the rig name is empty".into());
        }
        let rate_hz = match &raw_rig.rate_hz {
            Some(r) if !(r.get_ref().is_finite() && *r.get_ref() > 0.0) => {
                return err(
                    r.span(),
                    format!(
                        "rate_hz must be a positive number of Hz, not {}",
                        r.get_ref()
                    ),
                );
            }
            Some(r) => *r.get_ref(),
            None => DEFAULT_RATE_HZ,
        };
        if raw.servo.is_empty() {
            return err(
                rig_span,
                "the rig has no servos (add [[servo]] tables)".into(),
            );
        }

        let mut servos: Vec<Servo> = Vec::with_capacity(raw.servo.len());
        let mut seen_outputs: Vec<(u16, Position)> = Vec::new();
        let mut seen_names: Vec<(String, Position)> = Vec::new();
        for s in raw.servo {
            let table_span = s.span();
            let s = s.into_inner();
            let missing = |key: &str| {
                Err(RigError::at(
                    file,
                    pos(table_span.clone()),
                    format!("missing key `{key}` in [[servo]]"),
                ))
            };
            let Some(name_v) = s.name else {
                return missing("name");
            };
            let Some(output_v) = s.output else {
                return missing("output");
            };
            let Some(channel_v) = s.channel else {
                return missing("channel");
            };
            let Some(angle_v) = s.angle else {
                return missing("angle");
            };
            let Some(pulse_v) = s.pulse else {
                return missing("pulse");
            };

            let sname = name_v.get_ref().trim().to_string();
            if sname.is_empty() {
                return err(name_v.span(), "the servo name is empty".into());
            }
            if let Some((_, first)) = seen_names.iter().find(|(n, _)| *n == sname) {
                return err(
                    name_v.span(),
                    format!(
                        "duplicate servo name \"{sname}\" (first used at line {})",
                        first.line
                    ),
                );
            }
            seen_names.push((sname.clone(), pos(name_v.span())));

            let output = *output_v.get_ref();
            if let Some((_, first)) = seen_outputs.iter().find(|(o, _)| *o == output) {
                return err(
                    output_v.span(),
                    format!(
                        "output {output} is already used (line {}): outputs must be unique",
                        first.line
                    ),
                );
            }
            seen_outputs.push((output, pos(output_v.span())));

            let chan = channel_v.get_ref().trim();
            let Some((joint, kind_str)) = chan.rsplit_once('.') else {
                return err(
                    channel_v.span(),
                    format!(
                        "channel \"{chan}\" is not of the form \"<Joint>.<Kind>\" (e.g. \"Neck.Yrotation\")"
                    ),
                );
            };
            let Some(kind) = parse_kind(kind_str) else {
                return err(
                    channel_v.span(),
                    format!(
                        "unknown channel kind \"{kind_str}\" in \"{chan}\" (expected one of Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation)"
                    ),
                );
            };
            if joint.is_empty() {
                return err(
                    channel_v.span(),
                    format!("channel \"{chan}\" has no joint name before the '.'"),
                );
            }

            let scale = match &s.scale {
                Some(v) if !v.get_ref().is_finite() || *v.get_ref() == 0.0 => {
                    return err(
                        v.span(),
                        format!("scale must be finite and non-zero, not {}", v.get_ref()),
                    );
                }
                Some(v) => *v.get_ref(),
                None => 1.0,
            };
            let offset = match &s.offset {
                Some(v) if !v.get_ref().is_finite() => {
                    return err(
                        v.span(),
                        format!("offset must be finite, not {}", v.get_ref()),
                    );
                }
                Some(v) => *v.get_ref(),
                None => 0.0,
            };

            let angle = match angle_v.get_ref()[..] {
                [a, b] if a.is_finite() && b.is_finite() && a < b => [a, b],
                ref v => {
                    return err(
                        angle_v.span(),
                        format!("bad angle range {v:?}: need [lo, hi], finite, lo < hi (degrees)"),
                    );
                }
            };
            let pulse = match pulse_v.get_ref()[..] {
                [a, b] => [a, b],
                ref v => {
                    return err(
                        pulse_v.span(),
                        format!("bad pulse range {v:?}: need [at_lo, at_hi] in µs"),
                    );
                }
            };
            if let Some(bad) = pulse
                .iter()
                .find(|p| !(p.is_finite() && (MIN_PULSE_US..=MAX_PULSE_US).contains(*p)))
            {
                return err(
                    pulse_v.span(),
                    format!("pulse {bad} µs is outside {MIN_PULSE_US}..={MAX_PULSE_US} µs"),
                );
            }
            if pulse[0] == pulse[1] {
                return err(
                    pulse_v.span(),
                    format!(
                        "bad pulse range [{}, {}]: the two pulses must differ",
                        pulse[0], pulse[1]
                    ),
                );
            }
            let (pmin, pmax) = (pulse[0].min(pulse[1]), pulse[0].max(pulse[1]));
            let neutral = match &s.neutral {
                Some(n) if !(n.get_ref().is_finite() && (pmin..=pmax).contains(n.get_ref())) => {
                    return err(
                        n.span(),
                        format!(
                            "neutral {} µs is outside the pulse range {pmin}..={pmax} µs",
                            n.get_ref()
                        ),
                    );
                }
                Some(n) => *n.get_ref(),
                None => 0.5 * (pulse[0] + pulse[1]),
            };

            let positive =
                |v: &Option<Spanned<f64>>, what: &str| -> Result<Option<f64>, RigError> {
                    match v {
                        Some(x) if !(x.get_ref().is_finite() && *x.get_ref() > 0.0) => {
                            Err(RigError::at(
                                file,
                                pos(x.span()),
                                format!("{what} must be positive and finite, not {}", x.get_ref()),
                            ))
                        }
                        Some(x) => Ok(Some(*x.get_ref())),
                        None => Ok(None),
                    }
                };
            let max_speed = positive(&s.max_speed, "max_speed (deg/s)")?;
            let max_accel = positive(&s.max_accel, "max_accel (deg/s²)")?;

            servos.push(Servo {
                name: sname,
                output,
                channel: format!("{joint}.{}", kind.name()),
                joint: joint.to_string(),
                kind,
                scale,
                offset,
                invert: s.invert.unwrap_or(false),
                angle,
                pulse,
                neutral,
                max_speed,
                max_accel,
                channel_at: pos(channel_v.span()),
            });
        }
        Ok(Rig {
            file: file.to_string(),
            name,
            rate_hz,
            servos,
        })
    }

    /// Binds every servo's channel to a channel index of `skeleton` (its
    /// frame-row order, as [`Skeleton::channel_names`]). The error points at
    /// the servo's `channel` value and suggests the closest channel name.
    pub fn resolve(&self, skeleton: &Skeleton) -> Result<Vec<usize>, RigError> {
        let list = skeleton.channel_list();
        self.servos
            .iter()
            .map(|s| {
                if let Some(i) = list
                    .iter()
                    .position(|&(j, k)| k == s.kind && skeleton.joints[j].name == s.joint)
                {
                    return Ok(i);
                }
                let fail = |msg: String| RigError::at(&self.file, s.channel_at, msg);
                if let Some(joint) = skeleton.joints.iter().find(|j| j.name == s.joint) {
                    let have: Vec<&str> = joint.channels.iter().map(|k| k.name()).collect();
                    return Err(fail(if have.is_empty() {
                        format!(
                            "unknown channel \"{}\": joint \"{}\" has no channels",
                            s.channel, s.joint
                        )
                    } else {
                        format!(
                            "unknown channel \"{}\": joint \"{}\" has only {}",
                            s.channel,
                            s.joint,
                            have.join(", ")
                        )
                    }));
                }
                let joints: Vec<&str> = list
                    .iter()
                    .filter(|&&(_, k)| k == s.kind)
                    .map(|&(j, _)| skeleton.joints[j].name.as_str())
                    .collect();
                let hint = closest(&s.joint, &joints)
                    .map(|j| format!(" (did you mean \"{j}.{}\"?)", s.kind))
                    .unwrap_or_default();
                Err(fail(format!("unknown channel \"{}\"{hint}", s.channel)))
            })
            .collect()
    }

    /// Servo-space signals of `motion`: per servo, one pulse per motion frame
    /// in quarter microseconds, and what was clamped or limited.
    ///
    /// `channels` is [`Rig::resolve`]'s answer for `motion.skeleton`;
    /// `metres_per_unit` is the motion's length unit (see
    /// [`crate::units::LengthUnit::metres`]), used only by position channels
    /// (whose expression works in millimetres).
    ///
    /// Speed and acceleration limits act at the motion's frame rate
    /// (`1 / motion.frame_time`; without a positive finite frame time they
    /// are not applied). The servo starts at rest on the first frame's
    /// target.
    ///
    /// # Panics
    ///
    /// If `channels` does not hold one valid channel index of `motion` per
    /// servo.
    pub fn servo_tracks(
        &self,
        motion: &Motion,
        channels: &[usize],
        metres_per_unit: f64,
    ) -> ServoTracks {
        assert_eq!(
            channels.len(),
            self.servos.len(),
            "servo_tracks: one channel index per servo (use Rig::resolve)"
        );
        let n = motion.channels();
        let names = motion.skeleton.channel_names();
        let servos = self
            .servos
            .iter()
            .zip(channels)
            .map(|(servo, &c)| {
                assert!(
                    c < n,
                    "servo_tracks: channel {c} out of range ({n} channels)"
                );
                let values = motion.channel(c);
                let (pulses, angles, report) =
                    servo.track(&values, motion.frame_time, metres_per_unit);
                ServoTrack {
                    name: servo.name.clone(),
                    output: servo.output,
                    channel: c,
                    channel_name: names[c].clone(),
                    pulses,
                    angles,
                    report,
                }
            })
            .collect();
        ServoTracks {
            rig: self.name.clone(),
            frame_time: motion.frame_time,
            servos,
        }
    }
}

// ---------------------------------------------------------------------------
// One servo: expression, mapping, limits
// ---------------------------------------------------------------------------

impl Servo {
    /// The expression: `±(scale × value + offset)`.
    pub fn expression(&self, value: f64) -> f64 {
        let a = self.scale * value + self.offset;
        if self.invert {
            -a
        } else {
            a
        }
    }

    /// The channel values (degrees, or mm) whose expression lies in the
    /// servo's angle range, as `[low, high]`.
    pub fn reachable_values(&self) -> [f64; 2] {
        let (lo, hi) = if self.invert {
            (-self.angle[1], -self.angle[0])
        } else {
            (self.angle[0], self.angle[1])
        };
        let a = (lo - self.offset) / self.scale;
        let b = (hi - self.offset) / self.scale;
        [a.min(b), a.max(b)]
    }

    /// Lowest and highest output in quarter µs (the pulse range, rounded
    /// inwards).
    pub fn quarter_us_range(&self) -> (u16, u16) {
        let lo = self.pulse[0].min(self.pulse[1]) * QUARTER_US_PER_US;
        let hi = self.pulse[0].max(self.pulse[1]) * QUARTER_US_PER_US;
        (lo.ceil() as u16, hi.floor() as u16)
    }

    /// The pulse for a servo angle in degrees, in quarter µs: linear from
    /// `angle` to `pulse`, rounded, and clamped to the pulse range (a NaN
    /// angle gives the neutral pulse).
    pub fn angle_to_quarter_us(&self, angle: f64) -> u16 {
        if angle.is_nan() {
            return self.neutral_quarter_us();
        }
        let t = (angle - self.angle[0]) / (self.angle[1] - self.angle[0]);
        let us = self.pulse[0] + t.clamp(0.0, 1.0) * (self.pulse[1] - self.pulse[0]);
        self.clamp_quarter_us(us * QUARTER_US_PER_US)
    }

    /// The servo angle in degrees of a pulse in quarter µs (the inverse of
    /// [`Servo::angle_to_quarter_us`] up to rounding; pulses outside the
    /// range extrapolate linearly).
    pub fn quarter_us_to_angle(&self, quarter_us: u16) -> f64 {
        let us = f64::from(quarter_us) / QUARTER_US_PER_US;
        let t = (us - self.pulse[0]) / (self.pulse[1] - self.pulse[0]);
        self.angle[0] + t * (self.angle[1] - self.angle[0])
    }

    /// Degrees of servo travel per µs of pulse: converts a pulse error
    /// ([`servo_error`]) to degrees.
    pub fn degrees_per_us(&self) -> f64 {
        (self.angle[1] - self.angle[0]) / (self.pulse[1] - self.pulse[0]).abs()
    }

    /// The neutral pulse in quarter µs.
    pub fn neutral_quarter_us(&self) -> u16 {
        self.clamp_quarter_us(self.neutral * QUARTER_US_PER_US)
    }

    /// The servo angle of the neutral pulse, in degrees.
    pub fn neutral_angle(&self) -> f64 {
        let t = (self.neutral - self.pulse[0]) / (self.pulse[1] - self.pulse[0]);
        self.angle[0] + t * (self.angle[1] - self.angle[0])
    }

    fn clamp_quarter_us(&self, q: f64) -> u16 {
        let (lo, hi) = self.quarter_us_range();
        if q.is_nan() {
            return lo;
        }
        (q.round().clamp(f64::from(lo), f64::from(hi))) as u16
    }

    /// Targets (expression, neutral for non-finite, rewrapped), clamped,
    /// limited and quantised: (pulses, commanded angles, report).
    fn track(
        &self,
        raw: &[f64],
        frame_time: f64,
        metres_per_unit: f64,
    ) -> (Vec<u16>, Vec<f64>, ClampReport) {
        let frames = raw.len();
        let mut report = ClampReport {
            frames,
            ..ClampReport::default()
        };
        let mut ev = EventLog::default();

        // 1-2. Channel values: mm for positions; rotations unwrapped and
        // placed on the branch nearest the reachable range.
        let values: Vec<f64> = if self.kind.is_rotation() {
            let mut v = raw.to_vec();
            report.rewraps = rewrap(&mut v, self.reachable_values());
            v
        } else {
            raw.iter().map(|v| v * metres_per_unit * 1000.0).collect()
        };

        // 3-4. Expression, neutral for non-finite, clamp to the angle range.
        let [lo, hi] = self.angle;
        let neutral = self.neutral_angle();
        let targets: Vec<f64> = values
            .iter()
            .enumerate()
            .map(|(f, &v)| {
                let a = self.expression(v);
                if !a.is_finite() {
                    report.non_finite += 1;
                    report.first_non_finite.get_or_insert(f);
                    ev.note(LimitKind::NonFinite, f, 0.0);
                    return neutral;
                }
                if a < lo {
                    report.range.note(lo - a, f);
                    ev.note(LimitKind::BelowRange, f, lo - a);
                    lo
                } else if a > hi {
                    report.range.note(a - hi, f);
                    ev.note(LimitKind::AboveRange, f, a - hi);
                    hi
                } else {
                    a
                }
            })
            .collect();

        // 5. Speed and acceleration: a forward pass limiting each step.
        let dt = frame_time;
        let timed = dt.is_finite() && dt > 0.0;
        let max_step = match self.max_speed {
            Some(v) if timed => v * dt,
            _ => f64::INFINITY,
        };
        let max_dstep = match self.max_accel {
            Some(a) if timed => a * dt * dt,
            _ => f64::INFINITY,
        };
        let mut angles = Vec::with_capacity(frames);
        let mut pos = targets.first().copied().unwrap_or(neutral);
        let mut step = 0.0f64;
        for (f, &target) in targets.iter().enumerate() {
            if f > 0 {
                let (d, binding) = limited_step(target - pos, step, max_step, max_dstep);
                let before = pos;
                // An unlimited step lands exactly on the target.
                pos = if binding == Binding::None {
                    target
                } else {
                    (pos + d).clamp(lo, hi)
                };
                step = pos - before;
                let lag = (target - pos).abs();
                if lag > LAG_EPS_DEG {
                    match binding {
                        Binding::Speed => {
                            report.speed.note(lag, f);
                            ev.note(LimitKind::Speed, f, lag);
                        }
                        _ => {
                            report.accel.note(lag, f);
                            ev.note(LimitKind::Accel, f, lag);
                        }
                    }
                }
            }
            angles.push(pos);
        }

        // 6. Pulses.
        let pulses = angles
            .iter()
            .map(|&a| self.angle_to_quarter_us(a))
            .collect();
        report.events = ev.events;
        report.events.sort_by_key(|e| e.first_frame);
        (pulses, angles, report)
    }
}

/// Which limit shaped a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Binding {
    None,
    Speed,
    Accel,
}

/// One step of the limiter. `want` is the distance to the target, `prev`
/// the previous step, `max_step` the speed limit per frame and
/// `max_dstep` the acceleration limit per frame².
///
/// The step heads for the target, no longer than the speed limit, no longer
/// than the servo can still brake from without overshooting a target that
/// stays put ([`brake_step`]), and within `max_dstep` of the previous step
/// (this last rule wins: a servo that cannot brake hard enough overshoots,
/// and that is reported as acceleration-limited).
fn limited_step(want: f64, prev: f64, max_step: f64, max_dstep: f64) -> (f64, Binding) {
    let mut d = want;
    let mut binding = Binding::None;
    if d.abs() > max_step {
        d = max_step.copysign(want);
        binding = Binding::Speed;
    }
    if max_dstep.is_finite() {
        let brake = brake_step(want.abs(), max_dstep);
        if d.abs() > brake {
            d = brake.copysign(want);
            binding = Binding::Accel;
        }
        let (lo, hi) = (prev - max_dstep, prev + max_dstep);
        if d < lo {
            d = lo;
            binding = Binding::Accel;
        } else if d > hi {
            d = hi;
            binding = Binding::Accel;
        }
    }
    (d, binding)
}

/// The longest step `d` after which steps shrinking by `u` per frame
/// (`d`, `d - u`, `d - 2u`, … while positive) cover at most `dist`:
/// with `k = ⌊d/u⌋` they cover `S(d) = (k+1)·d − u·k(k+1)/2`, which is
/// continuous and increasing, so `S(d) = dist` is solved on the right piece.
fn brake_step(dist: f64, u: f64) -> f64 {
    if !(dist > 0.0 && u > 0.0) {
        return 0.0;
    }
    // Continuous estimate d(d + u) / 2u = dist, then the exact piece.
    let est = 0.5 * ((u * u + 8.0 * u * dist).sqrt() - u);
    let k0 = (est / u).floor().max(0.0);
    for k in [k0, k0 - 1.0, k0 + 1.0, k0 - 2.0, k0 + 2.0] {
        if k < 0.0 {
            continue;
        }
        let d = (dist + u * k * (k + 1.0) / 2.0) / (k + 1.0);
        if d >= k * u * (1.0 - 1e-12) && d <= (k + 1.0) * u * (1.0 + 1e-12) {
            return d;
        }
    }
    est
}

/// Unwraps a rotation channel in place and moves it by whole turns towards
/// the reachable range `[a, b]`; returns the number of branch switches.
///
/// Each finite value `x` becomes `x + 360k`: the `k` that keeps it within
/// 180° of the previous finite value (the rule of
/// [`crate::fixed::unwrap_degrees`]), unless the `k` nearest the range is
/// closer to the range by more than [`REWRAP_HYSTERESIS_DEG`]. The first
/// finite value takes the branch nearest the range. Non-finite values and
/// values beyond ±[`MAX_ROTATION_DEG`] become NaN (for the caller to replace)
/// and do not disturb the continuity of the others.
fn rewrap(series: &mut [f64], [a, b]: [f64; 2]) -> usize {
    let mid = 0.5 * (a + b);
    let dist = |v: f64| (a - v).max(v - b).max(0.0);
    let near = |x: f64, to: f64| x + 360.0 * ((to - x) / 360.0).round();
    let mut prev: Option<f64> = None;
    let mut switches = 0;
    for v in series.iter_mut() {
        let x = *v;
        if x.is_nan() || x.abs() > MAX_ROTATION_DEG {
            // NaN, ±∞, or too large to place on a branch in f64.
            *v = f64::NAN;
            continue;
        }
        let best = near(x, mid);
        let chosen = match prev.map(|p| near(x, p)) {
            Some(cont) if cont.is_finite() => {
                if dist(best) + REWRAP_HYSTERESIS_DEG < dist(cont) {
                    switches += 1;
                    best
                } else {
                    cont
                }
            }
            _ => best,
        };
        *v = chosen;
        if chosen.is_finite() {
            prev = Some(chosen);
        }
    }
    switches
}

// ---------------------------------------------------------------------------
// Reports
// ---------------------------------------------------------------------------

/// Count and worst case of one kind of limiting.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LimitStats {
    /// Frames affected.
    pub frames: usize,
    /// Worst amount in degrees: excess beyond the range (range clamps) or
    /// lag behind the target (speed / acceleration limits).
    pub worst: f64,
    /// Frame of the worst amount.
    pub worst_frame: Option<usize>,
}

impl LimitStats {
    fn note(&mut self, amount: f64, frame: usize) {
        self.frames += 1;
        if self.worst_frame.is_none() || amount > self.worst {
            self.worst = amount;
            self.worst_frame = Some(frame);
        }
    }
}

impl fmt::Display for LimitStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.worst_frame {
            None => write!(f, "-"),
            Some(w) => write!(f, "{} ({:.1}° @{w})", self.frames, self.worst),
        }
    }
}

/// What happened to a servo's target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitKind {
    /// Target below `angle[0]`: clamped.
    BelowRange,
    /// Target above `angle[1]`: clamped.
    AboveRange,
    /// The servo lagged its target because of `max_speed`.
    Speed,
    /// The servo lagged (or overshot) its target because of `max_accel`.
    Accel,
    /// The channel value or the expression was not finite: neutral used.
    NonFinite,
}

impl fmt::Display for LimitKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LimitKind::BelowRange => "below range",
            LimitKind::AboveRange => "above range",
            LimitKind::Speed => "speed-limited",
            LimitKind::Accel => "accel-limited",
            LimitKind::NonFinite => "non-finite",
        })
    }
}

/// A run of consecutive frames with the same [`LimitKind`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClampEvent {
    /// What happened.
    pub kind: LimitKind,
    /// First frame of the run.
    pub first_frame: usize,
    /// Last frame of the run (inclusive).
    pub last_frame: usize,
    /// Worst excess (range) or lag (speed, accel) in degrees; 0 for
    /// non-finite values.
    pub worst: f64,
    /// Frame of the worst amount.
    pub worst_frame: usize,
}

impl fmt::Display for ClampEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let frames = if self.first_frame == self.last_frame {
            format!("frame {}", self.first_frame)
        } else {
            format!("frames {}-{}", self.first_frame, self.last_frame)
        };
        match self.kind {
            LimitKind::NonFinite => write!(f, "{frames}: non-finite value, neutral used"),
            LimitKind::BelowRange | LimitKind::AboveRange => write!(
                f,
                "{frames}: {}, worst {:.2}° beyond at frame {}",
                self.kind, self.worst, self.worst_frame
            ),
            LimitKind::Speed | LimitKind::Accel => write!(
                f,
                "{frames}: {}, worst lag {:.2}° at frame {}",
                self.kind, self.worst, self.worst_frame
            ),
        }
    }
}

#[derive(Default)]
struct EventLog {
    events: Vec<ClampEvent>,
    open: [Option<usize>; 5],
}

impl EventLog {
    fn note(&mut self, kind: LimitKind, frame: usize, amount: f64) {
        let slot = kind as usize;
        if let Some(i) = self.open[slot] {
            let e = &mut self.events[i];
            if e.last_frame + 1 == frame {
                e.last_frame = frame;
                if amount > e.worst {
                    e.worst = amount;
                    e.worst_frame = frame;
                }
                return;
            }
        }
        self.open[slot] = Some(self.events.len());
        self.events.push(ClampEvent {
            kind,
            first_frame: frame,
            last_frame: frame,
            worst: amount,
            worst_frame: frame,
        });
    }
}

/// Everything that kept one servo from following its channel exactly.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClampReport {
    /// Frames in the track.
    pub frames: usize,
    /// Targets clamped to the angle range (worst: degrees beyond it).
    pub range: LimitStats,
    /// Frames where `max_speed` kept the servo off target (worst: lag).
    pub speed: LimitStats,
    /// Frames where `max_accel` kept the servo off target (worst: lag).
    pub accel: LimitStats,
    /// Frames whose value was not finite (neutral used instead).
    pub non_finite: usize,
    /// The first such frame.
    pub first_non_finite: Option<usize>,
    /// Branch switches of a rotation channel (see [`REWRAP_HYSTERESIS_DEG`]).
    pub rewraps: usize,
    /// Every run of clamped or limited frames, in order of first frame.
    pub events: Vec<ClampEvent>,
}

impl ClampReport {
    /// True when the servo followed its channel exactly.
    pub fn is_clean(&self) -> bool {
        self.events.is_empty() && self.rewraps == 0
    }
}

/// One servo's signal.
#[derive(Clone, Debug, PartialEq)]
pub struct ServoTrack {
    /// Servo name.
    pub name: String,
    /// Controller output.
    pub output: u16,
    /// Channel index in the motion.
    pub channel: usize,
    /// Channel name, `Joint.Kind`.
    pub channel_name: String,
    /// One pulse per frame, in quarter microseconds.
    pub pulses: Vec<u16>,
    /// The commanded servo angle per frame in degrees (after clamping and
    /// limiting, before quantisation).
    pub angles: Vec<f64>,
    /// What was clamped or limited.
    pub report: ClampReport,
}

/// All servos' signals for one motion.
#[derive(Clone, Debug, PartialEq)]
pub struct ServoTracks {
    /// Rig name.
    pub rig: String,
    /// Seconds per frame (the motion's).
    pub frame_time: f64,
    /// One track per servo, in rig order.
    pub servos: Vec<ServoTrack>,
}

impl ServoTracks {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.servos.first().map_or(0, |s| s.pulses.len())
    }

    /// Pulse error of `other` (e.g. the decoded clip's tracks) against
    /// these, servo by servo (paired by position).
    pub fn error_against(&self, other: &ServoTracks) -> Vec<ServoError> {
        self.servos
            .iter()
            .zip(&other.servos)
            .map(|(a, b)| servo_error(&a.pulses, &b.pulses))
            .collect()
    }

    /// Every clamp event of every servo, one line each (`servo: event`).
    ///
    /// Range clamps and non-finite values are always listed. Speed and
    /// acceleration runs whose worst lag is below `min_lag_deg` are only
    /// counted (captured motion at 120 Hz has enough jitter to brush an
    /// acceleration limit every few frames by hundredths of a degree);
    /// pass 0 to list them all.
    pub fn events_text(&self, min_lag_deg: f64) -> String {
        let mut out = String::new();
        for s in &self.servos {
            let mut hidden = 0usize;
            for e in &s.report.events {
                let lag = matches!(e.kind, LimitKind::Speed | LimitKind::Accel);
                if lag && e.worst < min_lag_deg {
                    hidden += 1;
                } else {
                    let _ = writeln!(out, "{}: {e}", s.name);
                }
            }
            if hidden > 0 {
                let _ = writeln!(
                    out,
                    "{}: {hidden} more speed/accel-limited run(s) with lag under {min_lag_deg}°",
                    s.name
                );
            }
            if s.report.rewraps > 0 {
                let _ = writeln!(
                    out,
                    "{}: {} branch switch(es) of ±360°",
                    s.name, s.report.rewraps
                );
            }
        }
        out
    }
}

/// A summary table: per servo the range clamps (frames, worst excess,
/// its frame), speed- and accel-limited frames (frames, worst lag, frame),
/// non-finite values and branch switches.
impl fmt::Display for ServoTracks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rate = if self.frame_time > 0.0 {
            1.0 / self.frame_time
        } else {
            0.0
        };
        writeln!(
            f,
            "rig {}: {} servos, {} frames at {rate:.0} Hz (counts: frames; worst in degrees @frame)",
            self.rig,
            self.servos.len(),
            self.frames()
        )?;
        writeln!(
            f,
            "{:<18} {:>3}  {:<24} {:<22} {:<22} {:<22} {:>6} {:>7}",
            "servo", "out", "channel", "range", "speed", "accel", "nonfin", "rewraps"
        )?;
        for s in &self.servos {
            let r = &s.report;
            writeln!(
                f,
                "{:<18} {:>3}  {:<24} {:<22} {:<22} {:<22} {:>6} {:>7}",
                s.name,
                s.output,
                s.channel_name,
                r.range.to_string(),
                r.speed.to_string(),
                r.accel.to_string(),
                r.non_finite,
                r.rewraps
            )?;
        }
        Ok(())
    }
}

/// Difference between two pulse tracks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ServoError {
    /// Frames compared (the shorter track's length).
    pub frames: usize,
    /// Largest absolute difference, µs.
    pub max_us: f64,
    /// Root mean square difference, µs.
    pub rms_us: f64,
    /// Frame of the largest difference.
    pub worst_frame: Option<usize>,
}

/// Max and RMS difference in µs of two pulse tracks in quarter µs, over
/// their common length. Use [`Servo::degrees_per_us`] for degrees.
pub fn servo_error(a: &[u16], b: &[u16]) -> ServoError {
    let mut e = ServoError::default();
    let mut sum2 = 0.0;
    for (f, (&x, &y)) in a.iter().zip(b).enumerate() {
        let d = (f64::from(x) - f64::from(y)).abs() / QUARTER_US_PER_US;
        sum2 += d * d;
        if e.worst_frame.is_none() || d > e.max_us {
            e.max_us = d;
            e.worst_frame = Some(f);
        }
        e.frames += 1;
    }
    if e.frames > 0 {
        e.rms_us = (sum2 / e.frames as f64).sqrt();
    }
    e
}

// ---------------------------------------------------------------------------
// Suggestions
// ---------------------------------------------------------------------------

/// The name in `names` closest to `wanted` (case-insensitive edit
/// distance), if it is close enough to be a plausible typo: at most a third
/// of `wanted`'s length, and at least 1.
fn closest<'a>(wanted: &str, names: &[&'a str]) -> Option<&'a str> {
    let w = wanted.to_lowercase();
    let (best, d) = names
        .iter()
        .map(|n| (*n, levenshtein(&w, &n.to_lowercase())))
        .min_by_key(|&(_, d)| d)?;
    let limit = (w.chars().count() / 3).max(1);
    (d <= limit).then_some(best)
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let up = row[j + 1];
            row[j + 1] = (diag + usize::from(ca != cb)).min(up + 1).min(row[j] + 1);
            diag = up;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: &str = r#"
[rig]
name = "t"

[[servo]]
name = "s"
output = 3
channel = "Neck.yrotation"
angle = [-45, 45]
pulse = [1000, 2000]
"#;

    #[test]
    fn defaults_and_kind_case() {
        let rig = Rig::parse(ONE, "t.toml").unwrap();
        assert_eq!(rig.rate_hz, DEFAULT_RATE_HZ);
        let s = &rig.servos[0];
        assert_eq!(s.channel, "Neck.Yrotation");
        assert_eq!(s.kind, ChannelKind::Yrotation);
        assert_eq!((s.scale, s.offset, s.invert), (1.0, 0.0, false));
        assert_eq!(s.neutral, 1500.0);
        assert_eq!((s.max_speed, s.max_accel), (None, None));
        assert_eq!(
            s.channel_at,
            Position {
                line: 8,
                column: 11
            }
        );
    }

    #[test]
    fn position_of_byte_counts_characters() {
        let t = "ab\nµµx\n";
        assert_eq!(Position::of_byte(t, 0), Position { line: 1, column: 1 });
        assert_eq!(Position::of_byte(t, 3), Position { line: 2, column: 1 });
        // 'x' is byte 7 (µ is two bytes) but character column 3.
        assert_eq!(Position::of_byte(t, 7), Position { line: 2, column: 3 });
        // Inside a multi-byte character: moved back to its start.
        assert_eq!(Position::of_byte(t, 4), Position { line: 2, column: 1 });
        assert_eq!(Position::of_byte(t, 99).line, 3);
    }

    #[test]
    fn mapping_and_inverse() {
        let rig = Rig::parse(ONE, "t.toml").unwrap();
        let s = &rig.servos[0];
        assert_eq!(s.angle_to_quarter_us(0.0), 6000);
        assert_eq!(s.angle_to_quarter_us(-45.0), 4000);
        assert_eq!(s.angle_to_quarter_us(45.0), 8000);
        assert_eq!(s.angle_to_quarter_us(1e9), 8000);
        assert_eq!(s.angle_to_quarter_us(f64::NEG_INFINITY), 4000);
        assert_eq!(s.angle_to_quarter_us(f64::NAN), 6000);
        assert_eq!(s.quarter_us_to_angle(7000), 22.5);
        assert!((s.degrees_per_us() - 0.09).abs() < 1e-12);
        for q in (4000..=8000).step_by(7) {
            assert_eq!(s.angle_to_quarter_us(s.quarter_us_to_angle(q)), q);
        }
    }

    #[test]
    fn limiter_without_accel_is_a_speed_clamp() {
        assert_eq!(
            limited_step(5.0, 0.0, 2.0, f64::INFINITY),
            (2.0, Binding::Speed)
        );
        assert_eq!(
            limited_step(-5.0, 0.0, 2.0, f64::INFINITY),
            (-2.0, Binding::Speed)
        );
        assert_eq!(
            limited_step(1.5, 0.0, 2.0, f64::INFINITY),
            (1.5, Binding::None)
        );
    }

    #[test]
    fn brake_step_is_the_exact_discrete_stopping_step() {
        let stop = |d: f64, u: f64| {
            let (mut d, mut s) = (d, 0.0);
            while d > 0.0 {
                s += d;
                d -= u;
            }
            s
        };
        for &u in &[0.1, 0.4, 1.0, 3.0] {
            for i in 0..500 {
                let dist = f64::from(i) * 0.173;
                let d = brake_step(dist, u);
                assert!(stop(d, u) <= dist + 1e-9, "u {u} dist {dist}: d {d}");
                assert!(stop(d + 1e-6, u) > dist - 1e-9 || dist == 0.0);
            }
        }
        assert_eq!(brake_step(0.0, 1.0), 0.0);
        assert_eq!(brake_step(f64::NAN, 1.0), 0.0);
    }

    #[test]
    fn limiter_brakes_without_overshoot_on_a_step() {
        // A 100° step with 1°/frame² acceleration: position rises
        // monotonically, never overshoots, and arrives.
        let (mut p, mut d) = (0.0f64, 0.0f64);
        let mut prev = 0.0;
        for _ in 0..200 {
            let (s, _) = limited_step(100.0 - p, d, f64::INFINITY, 1.0);
            assert!((s - d).abs() <= 1.0 + 1e-12);
            d = s;
            p += s;
            assert!(p <= 100.0 + 1e-9, "overshoot to {p}");
            assert!(p >= prev - 1e-12);
            prev = p;
        }
        assert!((p - 100.0).abs() < 1e-6, "did not arrive: {p}");
    }

    #[test]
    fn rewrap_moves_drifted_turns_back_in_reach() {
        // A channel that has drifted a full turn below the range [-90, 90]
        // (-300 is +60) comes back to +60; one switch.
        let mut v = vec![-300.0, -301.0, -299.0];
        assert_eq!(rewrap(&mut v, [-90.0, 90.0]), 0);
        assert_eq!(v, vec![60.0, 59.0, 61.0]);
        // Passing slowly through the unreachable side switches once, not on
        // every frame.
        let mut w: Vec<f64> = (0..=72).map(|i| 80.0 + 5.0 * f64::from(i)).collect();
        let n = rewrap(&mut w, [-90.0, 90.0]);
        assert_eq!(n, 1);
        assert!(w.iter().all(|v| (-200.0..=280.0).contains(v)));
    }

    #[test]
    fn rewrap_agrees_with_fixed_unwrap_in_reach() {
        // A wrapped random walk around 0 that stays within reach: the same
        // as fixed::unwrap_degrees, no switches.
        let mut x = 0.0f64;
        let mut seed = 1u64;
        let walk: Vec<f64> = (0..2000)
            .map(|_| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                x = (x + ((seed >> 33) as f64 / 2f64.powi(31) - 0.5) * 20.0).clamp(-170.0, 170.0);
                crate::fixed::wrap_degrees(x + 180.0)
            })
            .collect();
        let mut expected = walk.clone();
        crate::fixed::unwrap_degrees(&mut expected);
        let mut got = walk.clone();
        // Range centred on 180: the first value's own branch is nearest.
        assert_eq!(rewrap(&mut got, [0.0, 360.0]), 0);
        for (g, e) in got.iter().zip(&expected) {
            assert!((g - e - (got[0] - expected[0])).abs() < 1e-9);
        }
        // Non-finite values are skipped without breaking continuity.
        let mut v = vec![170.0, f64::NAN, -175.0, f64::INFINITY, f64::MAX, -160.0];
        rewrap(&mut v, [90.0, 270.0]);
        assert_eq!(v[0], 170.0);
        assert!(v[1].is_nan() && v[3].is_nan() && v[4].is_nan());
        assert_eq!((v[2], v[5]), (185.0, 200.0));
    }

    #[test]
    fn suggestions() {
        let names = ["Hips", "Neck", "Neck1", "LeftForeArm", "Head"];
        assert_eq!(closest("Nek", &names), Some("Neck"));
        assert_eq!(closest("neck", &names), Some("Neck"));
        assert_eq!(closest("LeftForearm", &names), Some("LeftForeArm"));
        assert_eq!(closest("LeftFroeArm", &names), Some("LeftForeArm"));
        assert_eq!(closest("Pelvis", &names), None);
        assert_eq!(closest("Hand", &names), None);
        assert_eq!(levenshtein("kitten", "sitting"), 3);
    }

    #[test]
    fn servo_error_in_us() {
        let e = servo_error(&[6000, 6004, 6000], &[6000, 6000, 6008]);
        assert_eq!(e.frames, 3);
        assert_eq!(e.max_us, 2.0);
        assert_eq!(e.worst_frame, Some(2));
        assert!((e.rms_us - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
    }
}
