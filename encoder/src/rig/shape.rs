//! Signal shaping: a motion channel turned into a servo's pulses (unwrapping,
//! expression, range clamp, speed and acceleration limits, quantisation;
//! steps 1–6 of the module doc).

use crate::motion::Motion;

use super::*;

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

impl Rig {
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

impl Servo {
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
pub(super) enum Binding {
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
pub(super) fn limited_step(want: f64, prev: f64, max_step: f64, max_dstep: f64) -> (f64, Binding) {
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
pub(super) fn brake_step(dist: f64, u: f64) -> f64 {
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
pub(super) fn rewrap(series: &mut [f64], [a, b]: [f64; 2]) -> usize {
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
