//! Servo limits and the limiter every output goes through.
//!
//! Whatever a clip, a stream or a bug asks for, [`Limiter`] only ever emits
//! pulses inside each servo's `[min_qus, max_qus]`, moving at most
//! `max_step_qus` per output tick.

use crate::Error;

/// The safe envelope of one servo, in quarter-µs (see the crate doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ServoLimits {
    /// Lowest pulse ever commanded.
    pub min_qus: u16,
    /// Highest pulse ever commanded.
    pub max_qus: u16,
    /// Rest position: the start position and where [`Limiter::stop_step`] goes.
    pub neutral_qus: u16,
    /// Largest change per output tick; 0 means unlimited.
    pub max_step_qus: u16,
}

impl ServoLimits {
    /// Limits checked for `min_qus <= neutral_qus <= max_qus`.
    pub const fn new(
        min_qus: u16,
        max_qus: u16,
        neutral_qus: u16,
        max_step_qus: u16,
    ) -> Result<Self, Error> {
        let limits = ServoLimits {
            min_qus,
            max_qus,
            neutral_qus,
            max_step_qus,
        };
        match limits.validate() {
            Ok(()) => Ok(limits),
            Err(error) => Err(error),
        }
    }

    /// Checks `min_qus <= neutral_qus <= max_qus`.
    pub const fn validate(&self) -> Result<(), Error> {
        if self.min_qus <= self.neutral_qus && self.neutral_qus <= self.max_qus {
            Ok(())
        } else {
            Err(Error::LimitsInvalid {
                min_qus: self.min_qus,
                neutral_qus: self.neutral_qus,
                max_qus: self.max_qus,
            })
        }
    }

    /// `target` moved into `[min_qus, max_qus]`.
    pub const fn clamp(&self, target_qus: u16) -> u16 {
        if target_qus < self.min_qus {
            self.min_qus
        } else if target_qus > self.max_qus {
            self.max_qus
        } else {
            target_qus
        }
    }

    /// The pulse one tick after `from`, heading for `target` (clamped) at this
    /// servo's speed limit. Stays in `[min_qus, max_qus]` when `from` is in it.
    pub const fn step(&self, from_qus: u16, target_qus: u16) -> u16 {
        let target = self.clamp(target_qus);
        if self.max_step_qus == 0 {
            target
        } else if target > from_qus {
            // target > from, so the difference cannot wrap, and from + step
            // stays below target <= u16::MAX.
            if target.wrapping_sub(from_qus) > self.max_step_qus {
                from_qus.wrapping_add(self.max_step_qus)
            } else {
                target
            }
        } else if from_qus.wrapping_sub(target) > self.max_step_qus {
            // from - step stays above target >= 0.
            from_qus.wrapping_sub(self.max_step_qus)
        } else {
            target
        }
    }
}

/// Clamps and rate-limits the pulses of `N` servos, remembering the last
/// pulse commanded to each. Starts with every servo at its neutral.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Limiter<const N: usize> {
    limits: [ServoLimits; N],
    last_qus: [u16; N],
}

impl<const N: usize> Limiter<N> {
    /// A limiter for `limits` (each validated), all servos at neutral.
    pub fn new(limits: [ServoLimits; N]) -> Result<Self, Error> {
        let mut last_qus = [0; N];
        for (last, servo) in last_qus.iter_mut().zip(&limits) {
            servo.validate()?;
            *last = servo.neutral_qus;
        }
        Ok(Limiter { limits, last_qus })
    }

    /// The limits, one per servo.
    pub const fn limits(&self) -> &[ServoLimits; N] {
        &self.limits
    }

    /// The last pulse commanded to each servo (quarter-µs).
    pub const fn last(&self) -> &[u16; N] {
        &self.last_qus
    }

    /// Writes into `out` the next pulse of each servo: its target clamped to
    /// its limits, then moved from the last pulse by at most `max_step_qus`.
    /// Both slices must hold exactly `N` values; otherwise nothing is written.
    pub fn apply(&mut self, targets_qus: &[u16], out_qus: &mut [u16]) -> Result<(), Error> {
        check_len::<N>(targets_qus.len())?;
        check_len::<N>(out_qus.len())?;
        for (((out, last), servo), &target) in out_qus
            .iter_mut()
            .zip(&mut self.last_qus)
            .zip(&self.limits)
            .zip(targets_qus)
        {
            *last = servo.step(*last, target);
            *out = *last;
        }
        Ok(())
    }

    /// Moves every servo one tick toward its neutral at its speed limit,
    /// writes the pulses into `out` (exactly `N` values) and tells whether all
    /// servos are now at neutral. Call it every tick to park a rig.
    pub fn stop_step(&mut self, out_qus: &mut [u16]) -> Result<bool, Error> {
        check_len::<N>(out_qus.len())?;
        let mut all_parked = true;
        for ((out, last), servo) in out_qus.iter_mut().zip(&mut self.last_qus).zip(&self.limits) {
            *last = servo.step(*last, servo.neutral_qus);
            *out = *last;
            all_parked &= *last == servo.neutral_qus;
        }
        Ok(all_parked)
    }
}

const fn check_len<const N: usize>(actual: usize) -> Result<(), Error> {
    if actual == N {
        Ok(())
    } else {
        Err(Error::LengthMismatch {
            expected: N,
            actual,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::TestRng;

    const N: usize = 6;

    fn random_limits(rng: &mut TestRng) -> ServoLimits {
        let a = rng.next_u16();
        let b = rng.next_u16();
        let (min_qus, max_qus) = if a <= b { (a, b) } else { (b, a) };
        let neutral_qus = min_qus + (rng.next_u32() % (u32::from(max_qus - min_qus) + 1)) as u16;
        // Unlimited a quarter of the time, otherwise anything up to the full range.
        let max_step_qus = match rng.next_u32() % 4 {
            0 => 0,
            _ => rng.next_u16() % 2000,
        };
        ServoLimits::new(min_qus, max_qus, neutral_qus, max_step_qus).unwrap()
    }

    #[test]
    fn validate_rejects_neutral_outside_range() {
        assert_eq!(
            ServoLimits::new(4000, 8000, 9000, 0),
            Err(Error::LimitsInvalid {
                min_qus: 4000,
                neutral_qus: 9000,
                max_qus: 8000
            })
        );
        assert!(ServoLimits::new(8000, 4000, 6000, 0).is_err());
        assert!(ServoLimits::new(6000, 6000, 6000, 0).is_ok());
        let bad = ServoLimits {
            min_qus: 5000,
            max_qus: 7000,
            neutral_qus: 4000,
            max_step_qus: 10,
        };
        let good = ServoLimits::new(4000, 8000, 6000, 40).unwrap();
        assert!(matches!(
            Limiter::new([good, bad]),
            Err(Error::LimitsInvalid {
                neutral_qus: 4000,
                ..
            })
        ));
    }

    #[test]
    fn wrong_lengths_are_typed_errors_and_write_nothing() {
        let limits = ServoLimits::new(4000, 8000, 6000, 40).unwrap();
        let mut limiter = Limiter::new([limits; 3]).unwrap();
        let mut out = [0u16; 3];
        assert_eq!(
            limiter.apply(&[1, 2], &mut out),
            Err(Error::LengthMismatch {
                expected: 3,
                actual: 2
            })
        );
        assert_eq!(
            limiter.apply(&[1, 2, 3], &mut [0u16; 4]),
            Err(Error::LengthMismatch {
                expected: 3,
                actual: 4
            })
        );
        assert_eq!(
            limiter.stop_step(&mut []),
            Err(Error::LengthMismatch {
                expected: 3,
                actual: 0
            })
        );
        assert_eq!(out, [0; 3]);
        assert_eq!(limiter.last(), &[6000; 3]);
    }

    #[test]
    fn ramps_at_the_speed_limit_then_holds_the_clamped_target() {
        let limits = ServoLimits::new(4000, 8000, 6000, 500).unwrap();
        let mut limiter = Limiter::new([limits]).unwrap();
        let mut out = [0u16; 1];
        let mut seen = [0u16; 6];
        for slot in &mut seen {
            limiter.apply(&[u16::MAX], &mut out).unwrap();
            *slot = out[0];
        }
        assert_eq!(seen, [6500, 7000, 7500, 8000, 8000, 8000]);
    }

    #[test]
    fn stop_step_parks_every_servo_at_neutral() {
        let a = ServoLimits::new(4000, 8000, 6000, 300).unwrap();
        let b = ServoLimits::new(3000, 9000, 5000, 0).unwrap();
        let mut limiter = Limiter::new([a, b]).unwrap();
        let mut out = [0u16; 2];
        limiter.apply(&[8000, 9000], &mut out).unwrap();
        assert_eq!(out, [6300, 9000]);
        let mut ticks = 0;
        while !limiter.stop_step(&mut out).unwrap() {
            ticks += 1;
            assert!(ticks < 10);
        }
        assert_eq!(out, [6000, 5000]);
        assert_eq!(ticks, 0, "6300 -> 6000 is one step of 300");
        assert!(limiter.stop_step(&mut out).unwrap());
    }

    /// Property: for random limits and random (including garbage) targets,
    /// every output is within `[min, max]` and moves at most `max_step` per tick.
    #[test]
    fn outputs_always_in_limits_and_steps_bounded() {
        let mut rng = TestRng::new(0x5e7_0001);
        for _rig in 0..500 {
            let limits: [ServoLimits; N] = core::array::from_fn(|_| random_limits(&mut rng));
            let mut limiter = Limiter::new(limits).unwrap();
            let mut previous = limits.map(|l| l.neutral_qus);
            let mut out = [0u16; N];
            for tick in 0..200 {
                let targets: [u16; N] = core::array::from_fn(|_| rng.next_u16());
                let parked = if tick % 50 >= 45 {
                    limiter.stop_step(&mut out).unwrap()
                } else {
                    limiter.apply(&targets, &mut out).unwrap();
                    false
                };
                for ((&pulse, &before), servo) in out.iter().zip(&previous).zip(&limits) {
                    assert!(
                        servo.min_qus <= pulse && pulse <= servo.max_qus,
                        "{servo:?} {pulse}"
                    );
                    if servo.max_step_qus != 0 {
                        assert!(
                            pulse.abs_diff(before) <= servo.max_step_qus,
                            "{servo:?} {before} -> {pulse}"
                        );
                    }
                }
                if parked {
                    assert_eq!(out, limits.map(|l| l.neutral_qus));
                }
                assert_eq!(limiter.last(), &out);
                previous = out;
            }
        }
    }

    /// Property: a constant reachable target is reached within
    /// `ceil(distance / max_step)` ticks and then held exactly.
    #[test]
    fn constant_target_is_reached_in_minimal_ticks() {
        let mut rng = TestRng::new(0x5e7_0002);
        for _ in 0..2000 {
            let servo = random_limits(&mut rng);
            let mut limiter = Limiter::new([servo]).unwrap();
            let target = rng.next_u16();
            let goal = servo.clamp(target);
            let distance = u32::from(goal.abs_diff(servo.neutral_qus));
            let ticks = match servo.max_step_qus {
                0 => u32::from(distance > 0),
                step => distance.div_ceil(u32::from(step)),
            };
            let mut out = [0u16];
            for _ in 0..ticks {
                limiter.apply(&[target], &mut out).unwrap();
            }
            assert_eq!(out[0], if ticks == 0 { 0 } else { goal });
            limiter.apply(&[target], &mut out).unwrap();
            assert_eq!(out[0], goal);
        }
    }
}
