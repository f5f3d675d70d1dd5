//! Servos on a PCA9685 16-channel, 12-bit PWM controller over I²C (feature
//! `pca9685`, driver crate `pwm-pca9685`).
//!
//! The chip divides its 25 MHz internal oscillator by `prescale + 1` and counts
//! 4096 steps per period. For servos the prescale is
//! `round(25 MHz / (4096 · 50 Hz)) − 1 = 121`, so one step is
//! `122 / 25 MHz = 4.88 µs` and the period 19.99 ms (50.03 Hz). A pulse is
//! therefore set to the nearest 4.88 µs (about 0.5° on a 1000 µs / 90°
//! servo): each channel turns on at count 0 and off at
//! [`off_count`]`(pulse)`. The internal oscillator is only accurate to a few
//! per cent; calibrate the rig's pulse limits on the real board.

use embedded_hal::i2c::I2c;
pub use pwm_pca9685::Address;
use pwm_pca9685::{Channel, Pca9685};

use crate::{Error, OutputError};

/// The PCA9685's internal oscillator, Hz.
pub const OSCILLATOR_HZ: u32 = 25_000_000;
/// Counts per PWM period.
pub const STEPS: u32 = 4096;
/// Highest channel.
pub const MAX_CHANNEL: u8 = 15;
/// Prescale for 50 Hz servo PWM.
pub const PRESCALE_50HZ: u8 = prescale_for_hz(50);

/// `round(OSCILLATOR_HZ / (4096 · hz)) − 1`, the datasheet's formula,
/// saturated to the register's range `3..=255`. `hz` must be non-zero
/// (0 is treated as 1); any `hz` is accepted (above ~6.1 kHz the prescale
/// is its minimum, 3).
pub const fn prescale_for_hz(hz: u32) -> u8 {
    // `STEPS * hz` saturates: wrapping (hz >= 2^20 gives 0) would divide by
    // zero, and any divisor above 2 · OSCILLATOR_HZ rounds to 0 alike.
    let divisor = STEPS.saturating_mul(if hz == 0 { 1 } else { hz });
    let rounded = match OSCILLATOR_HZ
        .saturating_add(divisor / 2)
        .checked_div(divisor)
    {
        Some(rounded) => rounded,
        None => 0,
    };
    if rounded <= 4 {
        3
    } else if rounded > 256 {
        255
    } else {
        rounded.wrapping_sub(1) as u8
    }
}

/// The 12-bit off count of a pulse of `pulse_qus` quarter-µs at `prescale`:
/// `round(pulse · 25 MHz / (prescale + 1))`, saturating at 4095.
pub const fn off_count(pulse_qus: u16, prescale: u8) -> u16 {
    // One step is (prescale + 1) / 25 µs = 4 · (prescale + 1) / 25 quarter-µs.
    // Small enough for u32 (<= 1024, <= 65535 · 25 + 512); step_scaled >= 4.
    let step_scaled = (prescale as u32).wrapping_add(1).wrapping_mul(4);
    let num = (pulse_qus as u32)
        .wrapping_mul(25)
        .wrapping_add(step_scaled / 2);
    let count = match num.checked_div(step_scaled) {
        Some(count) => count,
        None => STEPS - 1,
    };
    if count > STEPS - 1 {
        (STEPS - 1) as u16
    } else {
        count as u16
    }
}

/// A PCA9685 running at 50 Hz with its channels driving servos.
#[derive(Debug)]
pub struct Pca9685Servos<I2C> {
    device: Pca9685<I2C>,
}

/// The error of [`Pca9685Servos`]: rejected pulses, or the driver's error.
pub type Pca9685Error<E> = OutputError<pwm_pca9685::Error<E>>;

impl<I2C: I2c> Pca9685Servos<I2C> {
    /// Sets the prescale for 50 Hz and wakes the chip (two I²C writes).
    pub fn new(i2c: I2C, address: Address) -> Result<Self, Pca9685Error<I2C::Error>> {
        let mut device = Pca9685::new(i2c, address).map_err(OutputError::Device)?;
        device
            .set_prescale(PRESCALE_50HZ)
            .map_err(OutputError::Device)?;
        device.enable().map_err(OutputError::Device)?;
        Ok(Pca9685Servos { device })
    }

    /// Sets channels `first_channel..` (one per pulse, quarter-µs), one I²C
    /// write per channel. Nothing is written if the channels do not exist.
    pub fn write(
        &mut self,
        first_channel: u8,
        pulses_qus: &[u16],
    ) -> Result<(), Pca9685Error<I2C::Error>> {
        let last = usize::from(first_channel).saturating_add(pulses_qus.len().saturating_sub(1));
        let out_of_range = Error::ChannelOutOfRange {
            channel: last,
            max: MAX_CHANNEL,
        };
        if last > usize::from(MAX_CHANNEL) {
            return Err(out_of_range.into());
        }
        for (number, &pulse) in (first_channel..).zip(pulses_qus) {
            let channel = Channel::try_from(number).map_err(|()| out_of_range)?;
            self.device
                .set_channel_on_off(channel, 0, off_count(pulse, PRESCALE_50HZ))
                .map_err(OutputError::Device)?;
        }
        Ok(())
    }

    /// The I²C bus back.
    pub fn release(self) -> I2C {
        self.device.destroy()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use embedded_hal_mock::eh1::i2c::{Mock, Transaction};
    use std::vec;

    #[test]
    fn prescale_for_50hz_is_121() {
        assert_eq!(PRESCALE_50HZ, 121);
        assert_eq!(prescale_for_hz(60), 101);
        assert_eq!(prescale_for_hz(1526), 3);
        assert_eq!(prescale_for_hz(24), 253);
        assert_eq!(prescale_for_hz(0), 255);
    }

    /// error_case_1: `STEPS * hz` used to wrap to 0 at `hz = 2^20` (and to
    /// small divisors above it), then divide by zero or give a wrong prescale.
    #[test]
    fn error_case_1_prescale_of_huge_rates_is_the_minimum() {
        for hz in [6104, 1 << 20, (1 << 20) + 1, 3 << 20, 1 << 31, u32::MAX] {
            assert_eq!(prescale_for_hz(hz), 3, "{hz} Hz");
        }
        // Every rate: in the register's range, never rising with the rate.
        let mut last = prescale_for_hz(1);
        for hz in (1..=u32::MAX).step_by(65_537) {
            let prescale = prescale_for_hz(hz);
            assert!((3..=255).contains(&prescale) && prescale <= last, "{hz} Hz");
            last = prescale;
        }
    }

    #[test]
    fn off_count_is_the_nearest_step() {
        // 1500 µs / 4.88 µs = 307.4; 1000 µs -> 204.9; 2000 µs -> 409.8.
        assert_eq!(off_count(6000, PRESCALE_50HZ), 307);
        assert_eq!(off_count(4000, PRESCALE_50HZ), 205);
        assert_eq!(off_count(8000, PRESCALE_50HZ), 410);
        assert_eq!(off_count(0, PRESCALE_50HZ), 0);
        assert_eq!(off_count(u16::MAX, PRESCALE_50HZ), 3357);
        assert_eq!(off_count(u16::MAX, 3), 4095);
        // Rounding never misses by more than half a step.
        for pulse in (0..=u16::MAX).step_by(7) {
            let count = u32::from(off_count(pulse, PRESCALE_50HZ));
            let exact_x488 = u32::from(pulse) * 25 * 2; // count · 488 when exact
            assert!(exact_x488.abs_diff(count * 976) <= 488, "{pulse}");
        }
    }

    #[test]
    fn driver_writes_prescale_wake_and_channels() {
        const ADDR: u8 = 0x40;
        let expectations = [
            Transaction::write(ADDR, vec![0xFE, 121]), // PRE_SCALE while asleep
            Transaction::write(ADDR, vec![0x00, 0x01]), // MODE1: wake, all-call
            Transaction::write(ADDR, vec![0x00, 0x21]), // MODE1: + auto-increment
            // LED3_ON_L..LED3_OFF_H: on 0, off 307 (0x133)
            Transaction::write(ADDR, vec![0x12, 0x00, 0x00, 0x33, 0x01]),
            // LED4: on 0, off 410 (0x19A)
            Transaction::write(ADDR, vec![0x16, 0x00, 0x00, 0x9A, 0x01]),
        ];
        let i2c = Mock::new(&expectations);
        let mut servos = Pca9685Servos::new(i2c, Address::default()).unwrap();
        servos.write(3, &[6000, 8000]).unwrap();
        assert!(matches!(
            servos.write(15, &[6000, 6000]),
            Err(OutputError::Invalid(Error::ChannelOutOfRange {
                channel: 16,
                max: 15
            }))
        ));
        servos.release().done();
    }
}
