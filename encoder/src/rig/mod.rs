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
//!
//! # Modules
//!
//! - `file`: the TOML file, its checks and its errors (`file:line:col`);
//! - `resolve`: servo channels bound to a skeleton's channels, with "did you
//!   mean" suggestions;
//! - `shape`: the signal shaping of steps 1–6 ([`Rig::servo_tracks`]);
//! - `report`: what the shaping clamped or limited, and pulse errors.

mod file;
mod report;
mod resolve;
mod shape;
#[cfg(test)]
mod tests;

pub use file::{Position, RigError};
pub use report::{
    servo_error, ClampEvent, ClampReport, LimitKind, LimitStats, ServoError, ServoTrack,
    ServoTracks,
};
pub use shape::{MAX_ROTATION_DEG, REWRAP_HYSTERESIS_DEG};

use crate::motion::ChannelKind;
use mocap_decoder::RigServo;
use mocap_servo::HardLimit;

/// Servo update rate when `[rig] rate_hz` is not given.
pub const DEFAULT_RATE_HZ: f64 = 50.0;
/// Shortest pulse a rig may ask for, in µs.
pub const MIN_PULSE_US: f64 = 400.0;
/// Longest pulse a rig may ask for, in µs.
pub const MAX_PULSE_US: f64 = 2600.0;
/// Output resolution: quarter microseconds per microsecond.
pub const QUARTER_US_PER_US: f64 = 4.0;

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

    /// This servo as the rig table stores it (SPEC.md §3.5) and as the
    /// firmware and `mocap play` run it (`mocap_servo::Playback`): integer
    /// millidegrees and quarter-microseconds. The one conversion from the
    /// file's form to the runtime one; the limiter's `ServoLimits` come from
    /// the `RigServo` (`ServoLimits::for_servo`).
    pub fn rig_servo(&self) -> RigServo {
        let mdeg = |v: f64| (v * 1000.0).round() as i32;
        let qus = |us: f64| (us * 4.0).round().clamp(0.0, f64::from(u16::MAX)) as u16;
        RigServo {
            output: self.output,
            angle_lo_mdeg: mdeg(self.angle[0]),
            angle_hi_mdeg: mdeg(self.angle[1]),
            pulse_lo_qus: qus(self.pulse[0]),
            pulse_hi_qus: qus(self.pulse[1]),
            neutral_qus: self.neutral_quarter_us(),
            max_speed_mdeg_s: self.max_speed.map_or(0, |v| {
                (v * 1000.0).round().clamp(1.0, f64::from(u32::MAX)) as u32
            }),
        }
    }

    /// This servo as a figure's hard limit (`mocap_servo::HardLimit`): its
    /// pulse range and neutral in quarter-microseconds, its `max_speed` and
    /// `max_accel` (degrees of travel) as quarter-microseconds of pulse per
    /// second and per second² through its pulse-per-degree slope (rounded
    /// down, at least 1 when set). The one conversion the firmware's
    /// build-time table and `mocap play --rig` share.
    pub fn hard_limit(&self) -> HardLimit {
        let s = self.rig_servo();
        let (min_qus, max_qus) = s.pulse_range_qus();
        let qus_per_deg = 1.0 / self.degrees_per_us() * QUARTER_US_PER_US;
        let rate = |v: Option<f64>| {
            v.map_or(0, |v| {
                (v * qus_per_deg).floor().clamp(1.0, f64::from(u32::MAX)) as u32
            })
        };
        HardLimit {
            output: self.output,
            min_qus,
            max_qus,
            neutral_qus: s.neutral_qus,
            max_speed_qus_s: rate(self.max_speed),
            max_accel_qus_s2: rate(self.max_accel),
        }
    }

    fn clamp_quarter_us(&self, q: f64) -> u16 {
        let (lo, hi) = self.quarter_us_range();
        if q.is_nan() {
            return lo;
        }
        (q.round().clamp(f64::from(lo), f64::from(hi))) as u16
    }
}
