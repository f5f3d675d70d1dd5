//! The rig section (SPEC.md §3.5): in a servo clip, channel `i` is the
//! angle of servo `i` in millidegrees of servo travel, and this table maps
//! it to a pulse width with the servo's limits. [`RigServo::pulse_qus`] is
//! the one mapping the host (`mocap play`) and the firmware both use.

use crate::error::Error;
use crate::reader::Reader;

/// Smallest pulse a rig may name, ¼ µs (400 µs).
pub const MIN_PULSE_QUS: u32 = 1600;
/// Largest pulse a rig may name, ¼ µs (2 600 µs).
pub const MAX_PULSE_QUS: u32 = 10_400;

/// A validated rig table.
#[derive(Clone, Copy, Debug)]
pub struct Rig<'a> {
    rate_mhz: u32,
    count: u32,
    servos: &'a [u8],
}

/// One servo of a rig.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RigServo {
    /// Controller output (PWM index, PCA9685 or serial-controller channel).
    pub output: u16,
    /// Angle at `pulse_lo_qus`, millidegrees.
    pub angle_lo_mdeg: i32,
    /// Angle at `pulse_hi_qus`, millidegrees (`> angle_lo_mdeg`).
    pub angle_hi_mdeg: i32,
    /// Pulse at the low end of the travel, ¼ µs.
    pub pulse_lo_qus: u16,
    /// Pulse at the high end of the travel, ¼ µs (may be below
    /// `pulse_lo_qus`: a reversed servo).
    pub pulse_hi_qus: u16,
    /// Rest pulse, ¼ µs, within the pulse range.
    pub neutral_qus: u16,
    /// Speed limit in millidegrees per second, 0 = none.
    pub max_speed_mdeg_s: u32,
}

impl RigServo {
    /// The pulse for a decoded angle: clamped to the travel, then linear
    /// between the two ends, rounded half up (integer arithmetic).
    pub fn pulse_qus(&self, angle_mdeg: i32) -> u16 {
        let (lo, hi) = (i64::from(self.angle_lo_mdeg), i64::from(self.angle_hi_mdeg));
        let a = i64::from(angle_mdeg).clamp(lo, hi);
        let span = (hi - lo).max(1);
        let (p0, p1) = (i64::from(self.pulse_lo_qus), i64::from(self.pulse_hi_qus));
        let num = (a - lo) * (p1 - p0);
        // Round half away from zero, symmetric for reversed servos.
        let q = if num >= 0 {
            (2 * num + span) / (2 * span)
        } else {
            -((-2 * num + span) / (2 * span))
        };
        (p0 + q).clamp(0, i64::from(u16::MAX)) as u16
    }

    /// The most the pulse may change per tick at `rate_mhz` for the speed
    /// limit, ¼ µs, rounded up (at least 1); 0 = no limit.
    pub fn max_step_qus(&self, rate_mhz: u32) -> u16 {
        if self.max_speed_mdeg_s == 0 {
            return 0;
        }
        let span_mdeg =
            (i64::from(self.angle_hi_mdeg) - i64::from(self.angle_lo_mdeg)).max(1) as u64;
        let pulses = u64::from(self.pulse_lo_qus.abs_diff(self.pulse_hi_qus));
        // speed [mdeg/s] · pulses/span [qus/mdeg] / (rate_mhz / 1000) [1/s]
        let num = u64::from(self.max_speed_mdeg_s) * pulses * 1000;
        let den = span_mdeg * u64::from(rate_mhz.max(1));
        num.div_ceil(den).clamp(1, u64::from(u16::MAX)) as u16
    }

    /// The smallest and largest pulse of the servo.
    pub fn pulse_range_qus(&self) -> (u16, u16) {
        (
            self.pulse_lo_qus.min(self.pulse_hi_qus),
            self.pulse_lo_qus.max(self.pulse_hi_qus),
        )
    }
}

impl<'a> Rig<'a> {
    /// Validates a rig section against the header's channel count.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize) -> Result<Self, Error> {
        let bad = |rule| Error::RigMalformed { rule };
        let mut r = Reader::new(bytes);
        let rate_mhz = r.varint_u32().ok_or(bad("truncated"))?;
        let count = r.varint_u32().ok_or(bad("truncated"))?;
        if rate_mhz == 0 {
            return Err(bad("servo rate must be positive"));
        }
        if count as usize != channels {
            return Err(bad("one servo per channel"));
        }
        let at = r.pos();
        for _ in 0..count {
            let s = read_servo(&mut r).ok_or(bad("truncated"))?;
            let (lo, hi) = s.pulse_range_qus();
            if s.angle_lo_mdeg >= s.angle_hi_mdeg
                || u32::from(lo) < MIN_PULSE_QUS
                || u32::from(hi) > MAX_PULSE_QUS
                || s.neutral_qus < lo
                || s.neutral_qus > hi
            {
                return Err(bad("servo range, pulse or neutral out of bounds"));
            }
        }
        if !r.is_empty() {
            return Err(bad("bytes after the last servo"));
        }
        Ok(Rig {
            rate_mhz,
            count,
            servos: bytes.get(at..).unwrap_or(&[]),
        })
    }

    /// Servo update rate, millihertz.
    pub fn rate_mhz(&self) -> u32 {
        self.rate_mhz
    }

    /// Number of servos (= channels).
    pub fn servo_count(&self) -> usize {
        self.count as usize
    }

    /// The servos, in channel order.
    pub fn servos(&self) -> impl Iterator<Item = RigServo> + 'a {
        let mut r = Reader::new(self.servos);
        let mut left = self.count;
        core::iter::from_fn(move || {
            if left == 0 {
                return None;
            }
            left -= 1;
            read_servo(&mut r)
        })
    }
}

/// Servo ticks over `duration_us` at `rate_mhz`: one at t = 0, then one
/// per period up to the duration (SPEC.md §3.5).
pub fn tick_count(duration_us: u64, rate_mhz: u32) -> u64 {
    duration_us.saturating_mul(u64::from(rate_mhz)) / 1_000_000_000 + 1
}

/// Time of tick `i` at `rate_mhz`, µs: `i · 10^9 / rate_mhz` rounded down.
pub fn tick_us(i: u64, rate_mhz: u32) -> u64 {
    i.saturating_mul(1_000_000_000) / u64::from(rate_mhz.max(1))
}

fn read_servo(r: &mut Reader<'_>) -> Option<RigServo> {
    let pulse = |v: u32| u16::try_from(v).ok();
    Some(RigServo {
        output: r.u16_le()?,
        angle_lo_mdeg: r.zigzag_i32()?,
        angle_hi_mdeg: r.zigzag_i32()?,
        pulse_lo_qus: pulse(r.varint_u32()?)?,
        pulse_hi_qus: pulse(r.varint_u32()?)?,
        neutral_qus: pulse(r.varint_u32()?)?,
        max_speed_mdeg_s: r.varint_u32()?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulse_mapping_rounds_and_clamps() {
        let s = RigServo {
            output: 0,
            angle_lo_mdeg: -90_000,
            angle_hi_mdeg: 90_000,
            pulse_lo_qus: 2000,
            pulse_hi_qus: 10_000,
            neutral_qus: 6000,
            max_speed_mdeg_s: 0,
        };
        assert_eq!(s.pulse_qus(0), 6000);
        assert_eq!(s.pulse_qus(-90_000), 2000);
        assert_eq!(s.pulse_qus(1_000_000), 10_000);
        assert_eq!(s.pulse_qus(i32::MIN), 2000);
        let rev = RigServo {
            pulse_lo_qus: 10_000,
            pulse_hi_qus: 2000,
            ..s
        };
        assert_eq!(rev.pulse_qus(45_000), 4000);
        assert_eq!(rev.pulse_qus(i32::MAX), 2000);
    }
}
