//! Reports: what the shaping clamped or limited per servo, the servo tracks
//! with their text forms, and the difference between two pulse tracks.

use std::fmt::{self, Write as _};

use super::*;

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
    pub(super) fn note(&mut self, amount: f64, frame: usize) {
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
