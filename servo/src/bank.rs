//! Servos on the MCU's own PWM channels, through embedded-hal 1.0
//! [`SetDutyCycle`].
//!
//! The HAL sets the timer's frequency (50 Hz for hobby servos); the bank only
//! needs the matching period to turn pulses into duty cycles:
//! `duty = round(pulse / period · max_duty_cycle())`, in integers.

use core::num::NonZeroU32;

use embedded_hal::pwm::SetDutyCycle;

use crate::{Error, OutputError};

/// The servo PWM period at 50 Hz, µs.
pub const PERIOD_50HZ_US: NonZeroU32 = match NonZeroU32::new(20_000) {
    Some(period) => period,
    None => NonZeroU32::MIN,
};

/// The duty cycle, out of `max_duty`, of a pulse of `pulse_qus` quarter-µs in
/// a period of `period_us` µs: rounded to nearest, saturating at `max_duty`.
pub const fn duty_cycle(pulse_qus: u16, period_us: NonZeroU32, max_duty: u16) -> u16 {
    // u32 · 4 and u16 · u16 cannot overflow their types.
    let period_qus = (period_us.get() as u64).wrapping_mul(4);
    // 32-bit arithmetic when it cannot overflow (any servo period): a 64-bit
    // division is a library call on Cortex-M, 16 of them a tick cost ~10k
    // instructions on an M3.
    let product = (pulse_qus as u32).wrapping_mul(max_duty as u32);
    if period_qus <= u32::MAX as u64 {
        let period = period_qus as u32;
        if let Some(num) = product.checked_add(period / 2) {
            // period >= 4 (a non-zero period in quarter-µs).
            let duty = match num.checked_div(period) {
                Some(duty) => duty,
                None => max_duty as u32,
            };
            return if duty > max_duty as u32 {
                max_duty
            } else {
                duty as u16
            };
        }
    }
    // u16 · u16 + u34 cannot overflow u64; period_qus >= 4.
    let num = (pulse_qus as u64)
        .wrapping_mul(max_duty as u64)
        .wrapping_add(period_qus / 2);
    let duty = match num.checked_div(period_qus) {
        Some(duty) => duty,
        None => max_duty as u64,
    };
    if duty > max_duty as u64 {
        max_duty
    } else {
        duty as u16
    }
}

/// `N` servos, one per PWM channel, written together.
#[derive(Debug)]
pub struct ServoBank<P, const N: usize> {
    channels: [P; N],
    period_us: NonZeroU32,
}

impl<P: SetDutyCycle, const N: usize> ServoBank<P, N> {
    /// A bank of channels whose timer runs at 50 Hz.
    pub const fn new(channels: [P; N]) -> Self {
        Self::with_period_us(channels, PERIOD_50HZ_US)
    }

    /// A bank of channels whose timer period is `period_us`.
    pub const fn with_period_us(channels: [P; N], period_us: NonZeroU32) -> Self {
        ServoBank {
            channels,
            period_us,
        }
    }

    /// The PWM period, µs.
    pub const fn period_us(&self) -> NonZeroU32 {
        self.period_us
    }

    /// Sets each channel to its pulse (quarter-µs); `pulses_qus` holds exactly
    /// `N` values, otherwise nothing is written.
    pub fn write(&mut self, pulses_qus: &[u16]) -> Result<(), OutputError<P::Error>> {
        if pulses_qus.len() != N {
            return Err(Error::LengthMismatch {
                expected: N,
                actual: pulses_qus.len(),
            }
            .into());
        }
        for (channel, &pulse) in self.channels.iter_mut().zip(pulses_qus) {
            let duty = duty_cycle(pulse, self.period_us, channel.max_duty_cycle());
            channel.set_duty_cycle(duty).map_err(OutputError::Device)?;
        }
        Ok(())
    }

    /// The channels back.
    pub fn release(self) -> [P; N] {
        self.channels
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal_mock::eh1::pwm::{Mock, Transaction};

    #[test]
    fn duty_cycle_rounds_and_saturates() {
        let period = PERIOD_50HZ_US;
        assert_eq!(duty_cycle(6000, period, 20_000), 1500);
        assert_eq!(duty_cycle(6000, period, 1000), 75);
        // 1 ms of 20 ms on a 16-bit timer: 3276.75 -> 3277.
        assert_eq!(duty_cycle(4000, period, u16::MAX), 3277);
        assert_eq!(duty_cycle(0, period, u16::MAX), 0);
        let tiny = NonZeroU32::new(1).unwrap();
        assert_eq!(duty_cycle(u16::MAX, tiny, u16::MAX), u16::MAX);
        assert_eq!(duty_cycle(u16::MAX, NonZeroU32::MAX, u16::MAX), 0);
    }

    #[test]
    fn duty_cycle_matches_the_64_bit_formula() {
        let reference = |pulse: u16, period: u32, max: u16| {
            let period_qus = 4 * u64::from(period);
            let duty = (u64::from(pulse) * u64::from(max) + period_qus / 2) / period_qus;
            duty.min(u64::from(max)) as u16
        };
        for period in [1, 2_500, 20_000, 1 << 30, u32::MAX] {
            let p = NonZeroU32::new(period).unwrap();
            for pulse in (0..=u16::MAX).step_by(97).chain([u16::MAX]) {
                for max in [1, 255, 4095, 20_000, u16::MAX] {
                    assert_eq!(duty_cycle(pulse, p, max), reference(pulse, period, max));
                }
            }
        }
    }

    #[test]
    fn write_sets_every_channel() {
        let a = Mock::new(&[
            Transaction::max_duty_cycle(4095),
            Transaction::set_duty_cycle(307),
        ]);
        let b = Mock::new(&[
            Transaction::max_duty_cycle(4095),
            Transaction::set_duty_cycle(410),
        ]);
        let mut bank = ServoBank::new([a, b]);
        // 1500 µs -> 307.125, 2000 µs -> 409.5 -> 410.
        bank.write(&[6000, 8000]).unwrap();
        assert!(matches!(
            bank.write(&[6000]),
            Err(OutputError::Invalid(Error::LengthMismatch {
                expected: 2,
                actual: 1
            }))
        ));
        for mut channel in bank.release() {
            channel.done();
        }
    }
}
