//! The one servo playback loop, shared by `mocap play` and the firmware: a
//! rig's servos ([`RigServo`], the rig table's own type) at its tick rate,
//! their [`ServoLimits`], the [`Limiter`] that holds every pulse to them, and
//! the return to neutral, driving any [`ServoOutput`].
//!
//! ```text
//! decoded angles ─► Playback::targets ─► Playback::tick ─► ServoOutput::write
//! (sample_at at      (RigServo::pulse_qus)  (Limiter::apply)
//!  Playback::tick_us)                       … then Playback::park (Limiter::stop_step)
//! ```
//!
//! The host builds the same bytes as the MCU because both run this code:
//! the integer tick clock ([`tick_count`], [`tick_us`]), the integer pulse
//! mapping, the limiter and the outputs.

use mocap_decoder::{tick_count, tick_us, Rig, RigServo};

use crate::hard::{Fit, HardLimits, HardStage, HardStep, Policy};
use crate::{Error, Limiter, OutputError, ServoLimits, ServoOutput};

/// Upper bound on the ticks of a return to neutral ([`Playback::park`]):
/// with a speed limit of at least one ¼ µs per tick, any servo is back at
/// neutral within `u16::MAX` ticks.
pub const MAX_STOP_TICKS: u32 = 100_000;

/// The pulse of the slots past a rig's servos: 1500 µs, never written.
const IDLE_QUS: u16 = 6000;

/// A slot past the rig's servos.
const IDLE_SERVO: RigServo = RigServo {
    output: 0,
    angle_lo_mdeg: 0,
    angle_hi_mdeg: 1,
    pulse_lo_qus: IDLE_QUS,
    pulse_hi_qus: IDLE_QUS,
    neutral_qus: IDLE_QUS,
    max_speed_mdeg_s: 0,
};

const IDLE_LIMITS: ServoLimits = ServoLimits {
    min_qus: IDLE_QUS,
    max_qus: IDLE_QUS,
    neutral_qus: IDLE_QUS,
    max_step_qus: 0,
};

impl ServoLimits {
    /// The limits of a rig servo at a tick rate (millihertz): its pulse
    /// range, its neutral, and its speed limit as the most its pulse may
    /// change per tick. The one conversion from the rig's servo to the
    /// limiter's.
    pub fn for_servo(servo: &RigServo, rate_mhz: u32) -> Result<Self, Error> {
        let (min_qus, max_qus) = servo.pulse_range_qus();
        ServoLimits::new(
            min_qus,
            max_qus,
            servo.neutral_qus,
            servo.max_step_qus(rate_mhz),
        )
    }
}

/// A rig of at most `N` servos playing at its tick rate: every pulse it
/// writes went through its [`Limiter`]. Starts with every servo at neutral
/// (the servos' real position at power-on is unknown): the first ticks move
/// towards the first targets at the speed limits.
#[derive(Debug, Clone)]
pub struct Playback<const N: usize> {
    servos: [RigServo; N],
    count: usize,
    rate_mhz: u32,
    limiter: Limiter<N>,
    /// The figure's hard limits after the clip's own (`None`: the clip's
    /// limits are the only ones).
    hard: Option<HardStage<N>>,
    held: [u16; N],
}

impl<const N: usize> Playback<N> {
    /// The servos (rig order) at `rate_mhz`, with their limits
    /// ([`ServoLimits::for_servo`]). [`Error::TooManyServos`] past `N`;
    /// `servo` says which servo's limits were refused.
    pub fn new(
        servos: impl IntoIterator<Item = RigServo>,
        rate_mhz: u32,
    ) -> Result<Self, PlaybackError> {
        let mut all = [IDLE_SERVO; N];
        let mut limits = [IDLE_LIMITS; N];
        let mut count = 0usize;
        let mut servos = servos.into_iter();
        while let Some(servo) = servos.next() {
            let (Some(slot), Some(limit)) = (all.get_mut(count), limits.get_mut(count)) else {
                return Err(PlaybackError::TooManyServos {
                    count: servos.count().saturating_add(N).saturating_add(1),
                    max: N,
                });
            };
            *slot = servo;
            *limit = ServoLimits::for_servo(&servo, rate_mhz).map_err(|error| {
                PlaybackError::Limits {
                    output: servo.output,
                    error,
                }
            })?;
            // count < N here (the slot exists).
            count = count.wrapping_add(1);
        }
        let limiter =
            Limiter::new(limits).map_err(|error| PlaybackError::Limits { output: 0, error })?;
        let held = *limiter.last();
        Ok(Playback {
            servos: all,
            count,
            rate_mhz,
            limiter,
            hard: None,
            held,
        })
    }

    /// This playback with the figure's hard limits applied after the clip's
    /// own to every pulse, and the return to rest going to the figure's
    /// neutrals at its speed and acceleration. `matches_figure` says whether
    /// the clip was made for this figure (today: its rig table is the
    /// figure's, as `mocap play --rig` compares them);
    /// when it is not, `policy` decides: [`Policy::Refuse`] refuses it,
    /// [`Policy::ClampIfInside`] refuses it unless every servo lies inside
    /// the hard limits ([`HardLimits::fit`]), [`Policy::ClampAlways`] plays
    /// it. A servo on an output the figure does not have is always refused.
    /// Returns the fit too (for a status message).
    pub fn with_hard_limits(
        mut self,
        hard: &HardLimits<'_>,
        matches_figure: bool,
        policy: Policy,
    ) -> Result<(Self, Fit), PlaybackError> {
        let fit = hard.fit(self.servos());
        if let Fit::UnknownOutput { output } = fit {
            return Err(PlaybackError::UnknownOutput { output });
        }
        let allowed = matches_figure
            || match policy {
                Policy::Refuse => false,
                Policy::ClampIfInside => fit == Fit::Inside,
                Policy::ClampAlways => true,
            };
        if !allowed {
            return Err(PlaybackError::NotThisFigure { fit });
        }
        let mut steps = [HardStep::OPEN; N];
        for (step, servo) in steps.iter_mut().zip(self.servos()) {
            if let Some(limit) = hard.get(servo.output) {
                *step = HardStep::at_rate(limit, self.rate_mhz);
            }
        }
        // The clip's stage starts at its own neutrals (the pulses it was
        // going to start from), the hard stage and the servos at the
        // figure's.
        let stage = HardStage::new(steps, self.count);
        self.held = *stage.positions();
        self.hard = Some(stage);
        Ok((self, fit))
    }

    /// Per servo (rig order), the ticks whose pulse the figure's hard limits
    /// changed; empty without hard limits.
    pub fn hard_clamps(&self) -> &[u32] {
        match &self.hard {
            Some(h) => h.clamped().get(..self.count).unwrap_or_default(),
            None => &[],
        }
    }

    /// Per servo (rig order), the most the figure's hard limits moved a
    /// pulse, ¼ µs; empty without hard limits.
    pub fn hard_worst(&self) -> &[u16] {
        match &self.hard {
            Some(h) => h.worst().get(..self.count).unwrap_or_default(),
            None => &[],
        }
    }

    /// The rig table of a servo clip (SPEC.md §3.5): its servos and rate.
    pub fn from_rig(rig: &Rig<'_>) -> Result<Self, PlaybackError> {
        if rig.servo_count() > N {
            return Err(PlaybackError::TooManyServos {
                count: rig.servo_count(),
                max: N,
            });
        }
        Self::new(rig.servos(), rig.rate_mhz())
    }

    /// Number of servos.
    pub const fn count(&self) -> usize {
        self.count
    }

    /// Tick rate, millihertz.
    pub const fn rate_mhz(&self) -> u32 {
        self.rate_mhz
    }

    /// The servos, rig order.
    pub fn servos(&self) -> &[RigServo] {
        self.servos.get(..self.count).unwrap_or_default()
    }

    /// Each servo's limits, rig order.
    pub fn limits(&self) -> &[ServoLimits] {
        self.limiter.limits().get(..self.count).unwrap_or_default()
    }

    /// Each servo's controller channel, rig order (the first [`count`](Self::count)
    /// are the servos').
    pub fn outputs(&self) -> [u16; N] {
        let mut outputs = [0u16; N];
        for (o, s) in outputs.iter_mut().zip(&self.servos) {
            *o = s.output;
        }
        outputs
    }

    /// Ticks of a clip of `duration_us`: one at t = 0, then one per period.
    pub fn tick_count(&self, duration_us: u64) -> u64 {
        tick_count(duration_us, self.rate_mhz)
    }

    /// Time of tick `i`, µs (where to `sample_at` the clip).
    pub fn tick_us(&self, i: u64) -> u64 {
        tick_us(i, self.rate_mhz)
    }

    /// Targets (¼ µs) for decoded angles (millidegrees, one per servo) by each
    /// servo's integer mapping, [`RigServo::pulse_qus`]; neutral past the
    /// servos.
    pub fn targets(&self, angles_mdeg: &[i32]) -> [u16; N] {
        let mut targets = [IDLE_QUS; N];
        for ((t, s), &a) in targets
            .iter_mut()
            .zip(&self.servos)
            .zip(angles_mdeg)
            .take(self.count)
        {
            *t = s.pulse_qus(a);
        }
        targets
    }

    /// The pulses last commanded (¼ µs, rig order).
    pub fn held(&self) -> &[u16] {
        self.held.get(..self.count).unwrap_or_default()
    }

    /// Moves the held pulses one tick towards `targets` (¼ µs, one per slot):
    /// clamped to the limits, at most the speed limit. Nothing is written;
    /// [`write`](Self::write) sends them. [`tick`](Self::tick) does both.
    pub fn limit(&mut self, targets: &[u16; N]) -> Result<&[u16], Error> {
        self.limiter.apply(targets, &mut self.held)?;
        if let Some(hard) = &mut self.hard {
            hard.apply(&mut self.held);
        }
        Ok(self.held())
    }

    /// Writes the held pulses to `output`.
    pub fn write<O: ServoOutput>(&self, output: &mut O) -> Result<(), OutputError<O::Error>> {
        output.write(self.held())
    }

    /// One tick towards `targets`: [`limit`](Self::limit), then [`write`](Self::write).
    pub fn tick<O: ServoOutput>(
        &mut self,
        targets: &[u16; N],
        output: &mut O,
    ) -> Result<(), OutputError<O::Error>> {
        self.limit(targets)?;
        self.write(output)
    }

    /// One tick towards neutral at the speed limits, written to `output`;
    /// `true` once every servo is there.
    pub fn stop_tick<O: ServoOutput>(
        &mut self,
        output: &mut O,
    ) -> Result<bool, OutputError<O::Error>> {
        let mut parked = self.limiter.stop_step(&mut self.held)?;
        if let Some(hard) = &mut self.hard {
            // The figure's neutrals, at the figure's speed and acceleration.
            parked = hard.stop_step(&mut self.held);
        }
        self.write(output)?;
        Ok(parked)
    }

    /// The most ticks a return to rest ([`park`](Self::park)) takes from
    /// any state: with the figure's hard limits theirs
    /// ([`HardStage::park_ticks_max`]), else ⌈span / step⌉ + 1 of the
    /// slowest servo of the clip's limits.
    pub fn park_ticks_max(&self) -> u32 {
        if let Some(hard) = &self.hard {
            return hard.park_ticks_max();
        }
        self.limits()
            .iter()
            .map(|l| {
                let span = u32::from(l.max_qus.saturating_sub(l.min_qus)).max(1);
                let step = match l.max_step_qus {
                    0 => span,
                    s => u32::from(s),
                };
                span.div_ceil(step).saturating_add(1)
            })
            .max()
            .unwrap_or(0)
    }

    /// Whether every servo was last commanded its neutral (true before the
    /// first tick).
    pub fn parked(&self) -> bool {
        if let Some(hard) = &self.hard {
            return hard.parked();
        }
        self.limiter
            .limits()
            .iter()
            .zip(self.limiter.last())
            .all(|(l, &p)| p == l.neutral_qus)
    }

    /// Returns every servo to neutral at its speed limit, one
    /// [`stop_tick`](Self::stop_tick) after the other, calling `each_tick`
    /// with the pulses after each; nothing when already parked.
    /// [`Error::NotParked`] after [`MAX_STOP_TICKS`] ticks.
    pub fn park<O: ServoOutput, E>(
        &mut self,
        output: &mut O,
        mut each_tick: impl FnMut(&[u16]) -> Result<(), E>,
    ) -> Result<(), E>
    where
        E: From<OutputError<O::Error>>,
    {
        if self.parked() {
            return Ok(());
        }
        for _ in 0..MAX_STOP_TICKS {
            let parked = self.stop_tick(output)?;
            each_tick(self.held())?;
            if parked {
                return Ok(());
            }
        }
        Err(OutputError::Invalid(Error::NotParked {
            ticks: MAX_STOP_TICKS,
        })
        .into())
    }
}

/// Why a rig cannot play.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PlaybackError {
    /// More servos than the playback holds.
    TooManyServos {
        /// Servos given.
        count: usize,
        /// The most it holds.
        max: usize,
    },
    /// A servo drives an output the figure's hard limits do not have.
    UnknownOutput {
        /// The servo's controller channel.
        output: u16,
    },
    /// The clip was made for another figure, and the policy refuses it.
    NotThisFigure {
        /// How its servos lie against the figure's hard limits.
        fit: Fit,
    },
    /// A servo's limits are invalid.
    Limits {
        /// The servo's controller channel.
        output: u16,
        /// What is wrong with them.
        error: Error,
    },
}

impl core::fmt::Display for PlaybackError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlaybackError::TooManyServos { count, max } => {
                write!(f, "{count} servos, at most {max}")
            }
            PlaybackError::Limits { output, error } => write!(f, "servo output {output}: {error}"),
            PlaybackError::UnknownOutput { output } => {
                write!(f, "servo output {output}: the figure has no such output")
            }
            PlaybackError::NotThisFigure { fit } => match fit {
                Fit::Outside { output } => write!(
                    f,
                    "clip made for another rig, and servo output {output} leaves the figure's hard limits"
                ),
                _ => write!(f, "clip made for another rig (refused by the figure's policy)"),
            },
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for PlaybackError {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::MaestroOutput;

    fn servo(output: u16, max_speed_mdeg_s: u32) -> RigServo {
        RigServo {
            output,
            angle_lo_mdeg: -90_000,
            angle_hi_mdeg: 90_000,
            pulse_lo_qus: 4000,
            pulse_hi_qus: 8000,
            neutral_qus: 6000,
            max_speed_mdeg_s,
        }
    }

    #[test]
    fn ticks_are_limited_then_parked_at_neutral() {
        // 90 °/s at 50 Hz over 180° = 4000 qus: 40 qus per tick.
        let mut p = Playback::<4>::new([servo(0, 90_000), servo(1, 0)], 50_000).unwrap();
        assert_eq!(p.count(), 2);
        assert_eq!(p.limits()[0].max_step_qus, 40);
        assert!(p.parked());
        let mut bytes = std::vec::Vec::new();
        let outputs = p.outputs();
        let mut out = MaestroOutput::new(&mut bytes, &outputs[..2]).unwrap();
        let targets = p.targets(&[90_000, -90_000]);
        assert_eq!(targets, [8000, 4000, IDLE_QUS, IDLE_QUS]);
        p.tick(&targets, &mut out).unwrap();
        assert_eq!(p.held(), &[6040, 4000]);
        let mut ticks = 0;
        p.park(&mut out, |pulses| {
            ticks += 1;
            assert!(pulses[0] >= 6000);
            Ok::<_, OutputError<_>>(())
        })
        .unwrap();
        assert_eq!((ticks, p.held()), (1, &[6000u16, 6000][..]));
        // 2 ticks of 2 Set Target commands.
        drop(out);
        assert_eq!(bytes.len(), 2 * 2 * 4);
    }

    /// A rig already at neutral parks in no tick (as the firmware always did;
    /// `mocap play` used to send one more neutral tick).
    #[test]
    fn park_at_neutral_sends_nothing() {
        let mut p = Playback::<2>::new([servo(4, 90_000)], 50_000).unwrap();
        let outputs = p.outputs();
        let mut bytes = std::vec::Vec::new();
        let mut out = MaestroOutput::new(&mut bytes, &outputs[..1]).unwrap();
        p.tick(&[6000, 6000], &mut out).unwrap();
        let mut ticks = 0;
        p.park(&mut out, |_| {
            ticks += 1;
            Ok::<_, OutputError<_>>(())
        })
        .unwrap();
        assert_eq!(ticks, 0);
        drop(out);
        assert_eq!(bytes, [0x84, 4, 0x70, 0x2e]);
    }

    #[test]
    fn too_many_servos_and_bad_limits_are_refused() {
        assert_eq!(
            Playback::<1>::new([servo(0, 0), servo(1, 0)], 50_000).unwrap_err(),
            PlaybackError::TooManyServos { count: 2, max: 1 }
        );
        let bad = RigServo {
            neutral_qus: 9000,
            ..servo(3, 0)
        };
        assert!(matches!(
            Playback::<2>::new([bad], 50_000),
            Err(PlaybackError::Limits { output: 3, .. })
        ));
    }

    /// The figure: outputs 0 and 1 at 1100–1900 µs, neutral 1400 µs, 100 µs
    /// per tick at 50 Hz (20 000 ¼µs/s), 20 ¼µs per tick² (50 000 ¼µs/s²).
    const FIGURE: [crate::HardLimit; 2] = [
        crate::HardLimit {
            output: 0,
            min_qus: 4400,
            max_qus: 7600,
            neutral_qus: 5600,
            max_speed_qus_s: 20_000,
            max_accel_qus_s2: 50_000,
        },
        crate::HardLimit {
            output: 1,
            min_qus: 4400,
            max_qus: 7600,
            neutral_qus: 5600,
            max_speed_qus_s: 20_000,
            max_accel_qus_s2: 50_000,
        },
    ];

    #[test]
    fn a_wider_rig_is_held_to_the_figure_and_parks_at_its_neutral() {
        let hard = HardLimits::new(&FIGURE);
        // The clip's rig: 1000–2000 µs, no speed limit — wider than the figure.
        let wide = || Playback::<4>::new([servo(0, 0), servo(1, 0)], 50_000).unwrap();
        assert_eq!(
            wide().with_hard_limits(&hard, false, Policy::Refuse).err(),
            Some(PlaybackError::NotThisFigure {
                fit: Fit::Outside { output: 0 }
            })
        );
        assert!(wide()
            .with_hard_limits(&hard, false, Policy::ClampIfInside)
            .is_err());
        let (mut p, fit) = wide()
            .with_hard_limits(&hard, false, Policy::ClampAlways)
            .unwrap();
        assert_eq!(fit, Fit::Outside { output: 0 });
        assert_eq!(p.held(), &[5600, 5600]);
        let mut bytes = std::vec::Vec::new();
        let outputs = p.outputs();
        let mut out = MaestroOutput::new(&mut bytes, &outputs[..2]).unwrap();
        let mut last = [5600i32, 5600];
        let mut vel = [0i32; 2];
        let mut check = |pulses: &[u16]| {
            for ((&q, l), v) in pulses.iter().zip(&mut last).zip(&mut vel) {
                assert!((4400..=7600).contains(&q), "{q}");
                let nv = i32::from(q) - *l;
                assert!(nv.abs() <= 400 && (nv - *v).abs() <= 20, "{nv} {v}");
                (*l, *v) = (i32::from(q), nv);
            }
        };
        for i in 0..400 {
            let a = if (i / 37) % 2 == 0 { 90_000 } else { -90_000 };
            let targets = p.targets(&[a, -a]);
            p.tick(&targets, &mut out).unwrap();
            check(p.held());
        }
        assert!(p.hard_clamps().iter().all(|&c| c > 0));
        p.park(&mut out, |pulses| {
            check(pulses);
            Ok::<_, OutputError<_>>(())
        })
        .unwrap();
        assert_eq!(p.held(), &[5600, 5600]);
        assert!(p.parked());
        // An output the figure does not have is refused whatever the policy.
        let other = Playback::<4>::new([servo(0, 0), servo(7, 0)], 50_000).unwrap();
        assert_eq!(
            other
                .with_hard_limits(&hard, true, Policy::ClampAlways)
                .err(),
            Some(PlaybackError::UnknownOutput { output: 7 })
        );
    }

    #[test]
    fn a_rig_inside_the_figure_plays_unchanged_under_clamp_if_inside() {
        let hard = HardLimits::new(&FIGURE);
        let narrow = RigServo {
            pulse_lo_qus: 5000,
            pulse_hi_qus: 7000,
            ..servo(0, 0)
        };
        let (p, fit) = Playback::<2>::new([narrow], 50_000)
            .unwrap()
            .with_hard_limits(&hard, false, Policy::ClampIfInside)
            .unwrap();
        assert_eq!((fit, p.count()), (Fit::Inside, 1));
    }
}
