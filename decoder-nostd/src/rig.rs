//! The rig section (SPEC.md §3.5): in a servo clip, channel `i` is the
//! angle of servo `i` in millidegrees of servo travel, and this table maps
//! it to a pulse width with the servo's limits. [`RigServo::pulse_qus`] is
//! the one mapping the host (`mocap play`) and the firmware both use.

use crate::consts::rig_flag as flag;
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
    /// The compact form (§3.5.1): servos read relative to the previous one.
    compact: bool,
}

/// Millidegrees per degree in the compact form's whole-degree fields.
const MDEG: i64 = 1000;

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
    /// The pulse at `angle_mdeg` on the line through this servo's two
    /// ends, not clamped, division truncating toward zero — how the compact
    /// rig table's `SAME_MAP` gives the next servo its pulses (SPEC.md
    /// §3.5.1); `None` if it does not fit a `u16`.
    pub fn line_qus(&self, angle_mdeg: i64) -> Option<u16> {
        let (a0, a1) = (i64::from(self.angle_lo_mdeg), i64::from(self.angle_hi_mdeg));
        let (q0, q1) = (i64::from(self.pulse_lo_qus), i64::from(self.pulse_hi_qus));
        let num = angle_mdeg
            .checked_sub(a0)?
            .checked_mul(q1.wrapping_sub(q0))?;
        let q = q0.wrapping_add(num.checked_div(a1.wrapping_sub(a0).max(1))?);
        u16::try_from(q).ok()
    }

    /// The pulse for a decoded angle: clamped to the travel, then linear
    /// between the two ends, rounded half away from zero (integer
    /// arithmetic, SPEC.md §3.5).
    pub fn pulse_qus(&self, angle_mdeg: i32) -> u16 {
        let (lo, hi) = (i64::from(self.angle_lo_mdeg), i64::from(self.angle_hi_mdeg));
        // max then min, not clamp: no panic for a hand-built servo with lo > hi.
        let a = i64::from(angle_mdeg).max(lo).min(hi);
        let span = hi.wrapping_sub(lo).max(1);
        let (p0, p1) = (i64::from(self.pulse_lo_qus), i64::from(self.pulse_hi_qus));
        let num = a.wrapping_sub(lo).wrapping_mul(p1.wrapping_sub(p0));
        // Round half away from zero, symmetric for reversed servos.
        let den = span.wrapping_mul(2);
        let q = if num >= 0 {
            div(num.wrapping_mul(2).wrapping_add(span), den)
        } else {
            div(num.wrapping_mul(-2).wrapping_add(span), den).wrapping_neg()
        };
        p0.wrapping_add(q).clamp(0, i64::from(u16::MAX)) as u16
    }

    /// The most the pulse may change per tick at `rate_mhz` for the speed
    /// limit, ¼ µs, rounded up (at least 1); 0 = no limit.
    pub fn max_step_qus(&self, rate_mhz: u32) -> u16 {
        if self.max_speed_mdeg_s == 0 {
            return 0;
        }
        let span_mdeg = i64::from(self.angle_hi_mdeg)
            .wrapping_sub(i64::from(self.angle_lo_mdeg))
            .max(1) as u64;
        let pulses = u64::from(self.pulse_lo_qus.abs_diff(self.pulse_hi_qus));
        // speed [mdeg/s] · pulses/span [qus/mdeg] / (rate_mhz / 1000) [1/s]
        let num = u64::from(self.max_speed_mdeg_s)
            .wrapping_mul(pulses)
            .wrapping_mul(1000);
        let den = span_mdeg.wrapping_mul(u64::from(rate_mhz.max(1)));
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
        let mut rate_mhz = r.varint_u32().ok_or(bad("truncated"))?;
        // A leading 0 (no valid rate) marks the compact form (§3.5.1).
        let compact = rate_mhz == 0;
        if compact {
            rate_mhz = r.varint_u32().ok_or(bad("truncated"))?;
        }
        let count = r.varint_u32().ok_or(bad("truncated"))?;
        if rate_mhz == 0 {
            return Err(bad("servo rate must be positive"));
        }
        if count as usize != channels {
            return Err(bad("one servo per channel"));
        }
        let at = r.pos();
        let mut prev = None;
        for _ in 0..count {
            let s = if compact {
                read_compact_servo(&mut r, prev.as_ref())
                    .ok_or(bad("compact servo malformed or truncated"))?
            } else {
                read_servo(&mut r).ok_or(bad("truncated"))?
            };
            prev = Some(s);
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
            compact,
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
        let compact = self.compact;
        let mut prev: Option<RigServo> = None;
        core::iter::from_fn(move || {
            if left == 0 {
                return None;
            }
            left = left.wrapping_sub(1);
            let s = if compact {
                read_compact_servo(&mut r, prev.as_ref())
            } else {
                read_servo(&mut r)
            };
            prev = s;
            s
        })
    }

    /// True for the compact form of the table (SPEC.md §3.5.1).
    pub fn is_compact(&self) -> bool {
        self.compact
    }
}

/// Servo ticks over `duration_us` at `rate_mhz`: one at t = 0, then one
/// per period up to the duration (SPEC.md §3.5).
pub fn tick_count(duration_us: u64, rate_mhz: u32) -> u64 {
    (duration_us.saturating_mul(u64::from(rate_mhz)) / 1_000_000_000).wrapping_add(1)
}

/// Time of tick `i` at `rate_mhz`, µs: `i · 10^9 / rate_mhz` rounded down.
pub fn tick_us(i: u64, rate_mhz: u32) -> u64 {
    i.saturating_mul(1_000_000_000)
        .checked_div(u64::from(rate_mhz.max(1)))
        .unwrap_or(0)
}

/// `n / d` (0 for `d = 0`), in 32 bits when both fit: the same quotient
/// without a 64-bit division (a library call on a Cortex-M) for every rig
/// whose angle span times pulse span is below 2³¹ (all real ones).
fn div(n: i64, d: i64) -> i64 {
    match (u32::try_from(n), u32::try_from(d)) {
        (Ok(n), Ok(d)) => i64::from(n.checked_div(d).unwrap_or(0)),
        _ => n.checked_div(d).unwrap_or(0),
    }
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

/// One servo of the compact form (SPEC.md §3.5.1); `None` if malformed.
/// The bounds of the values are checked by the caller as for the full form.
fn read_compact_servo(r: &mut Reader<'_>, prev: Option<&RigServo>) -> Option<RigServo> {
    let flags = r.u8()?;
    if flags & !flag::ALL != 0 {
        return None;
    }
    let has = |f: u8| flags & f != 0;
    let output = if has(flag::OUTPUT_NEXT) {
        match prev {
            Some(p) => p.output.checked_add(1)?,
            None => 0,
        }
    } else {
        u16::try_from(r.varint_u32()?).ok()?
    };
    let (angle_lo_mdeg, angle_hi_mdeg, pulse_lo_qus, pulse_hi_qus) = if has(flag::SAME_RANGE) {
        if has(flag::ANGLE_DEG) || has(flag::SAME_MAP) {
            return None;
        }
        let p = prev?;
        (
            p.angle_lo_mdeg,
            p.angle_hi_mdeg,
            p.pulse_lo_qus,
            p.pulse_hi_qus,
        )
    } else {
        let unit = if has(flag::ANGLE_DEG) { MDEG } else { 1 };
        let lo = i64::from(r.zigzag_i32()?).checked_mul(unit)?;
        let span = i64::from(r.varint_u32()?).checked_mul(unit)?;
        let lo32 = i32::try_from(lo).ok()?;
        let hi32 = i32::try_from(lo.checked_add(span)?).ok()?;
        let (pulse_lo, pulse_hi) = if has(flag::SAME_MAP) {
            let p = prev?;
            (p.line_qus(lo)?, p.line_qus(lo.wrapping_add(span))?)
        } else {
            let p0 = r.varint_u32()?;
            let p1 = i64::from(p0).checked_add(i64::from(r.zigzag_i32()?))?;
            (u16::try_from(p0).ok()?, u16::try_from(p1).ok()?)
        };
        (lo32, hi32, pulse_lo, pulse_hi)
    };
    let neutral_qus = if has(flag::MID_NEUTRAL) {
        // Both pulses fit u16, so the sum fits u32.
        (u32::from(pulse_lo_qus).wrapping_add(u32::from(pulse_hi_qus)) / 2) as u16
    } else {
        u16::try_from(r.varint_u32()?).ok()?
    };
    let max_speed_mdeg_s = if has(flag::SAME_SPEED) {
        if has(flag::SPEED_DEG) {
            return None;
        }
        prev?.max_speed_mdeg_s
    } else {
        let v = r.varint_u32()?;
        if has(flag::SPEED_DEG) {
            v.checked_mul(MDEG as u32)?
        } else {
            v
        }
    };
    Some(RigServo {
        output,
        angle_lo_mdeg,
        angle_hi_mdeg,
        pulse_lo_qus,
        pulse_hi_qus,
        neutral_qus,
        max_speed_mdeg_s,
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

    /// The mapping as SPEC.md §3.5 writes it, all in 64 bits: `pulse_qus`'s
    /// 32-bit division gives the same pulse for any servo and angle.
    fn pulse_reference(s: &RigServo, angle: i32) -> u16 {
        let (lo, hi) = (i64::from(s.angle_lo_mdeg), i64::from(s.angle_hi_mdeg));
        let a = i64::from(angle).max(lo).min(hi);
        let span = hi.wrapping_sub(lo).max(1);
        let (p0, p1) = (i64::from(s.pulse_lo_qus), i64::from(s.pulse_hi_qus));
        let num = a.wrapping_sub(lo).wrapping_mul(p1.wrapping_sub(p0));
        let q = if num >= 0 {
            num.wrapping_mul(2)
                .wrapping_add(span)
                .checked_div(span.wrapping_mul(2))
                .unwrap_or(0)
        } else {
            num.wrapping_mul(-2)
                .wrapping_add(span)
                .checked_div(span.wrapping_mul(2))
                .unwrap_or(0)
                .wrapping_neg()
        };
        p0.wrapping_add(q).clamp(0, i64::from(u16::MAX)) as u16
    }

    #[test]
    fn pulse_mapping_is_the_64_bit_formula() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let edges = [
            i32::MIN,
            -1_000_000,
            -90_000,
            -1,
            0,
            1,
            90_000,
            360_000,
            i32::MAX,
        ];
        for round in 0..200_000u32 {
            let r = next();
            let pick = |v: u64, wide: bool| -> i32 {
                if wide {
                    v as i32
                } else {
                    (v % 400_001) as i32 - 200_000
                }
            };
            let wide = round % 4 == 0;
            let (a, b) = (pick(r, wide), pick(r >> 32, wide));
            let r2 = next();
            let s = RigServo {
                output: 0,
                // Hand-built servos too: lo = hi, lo > hi.
                angle_lo_mdeg: if round % 11 == 0 { a.max(b) } else { a.min(b) },
                angle_hi_mdeg: if round % 7 == 0 { a.min(b) } else { a.max(b) },
                pulse_lo_qus: r2 as u16,
                pulse_hi_qus: (r2 >> 16) as u16,
                neutral_qus: 6000,
                max_speed_mdeg_s: 0,
            };
            let angle = if round % 3 == 0 {
                edges[(r2 >> 40) as usize % edges.len()]
            } else {
                pick(next(), wide)
            };
            assert_eq!(
                s.pulse_qus(angle),
                pulse_reference(&s, angle),
                "{s:?} {angle}"
            );
        }
    }

    /// SPEC.md §3.5.1's example: two servos, the second all "as before".
    const COMPACT: [u8; 15] = [
        0x00, 0xD0, 0x86, 0x03, 0x02, //
        0x2D, 0x59, 0x5A, 0xA0, 0x1F, 0xC0, 0x3E, 0xAC, 0x02, //
        0x1B,
    ];

    #[test]
    fn compact_table_reads_the_spec_example() -> Result<(), Error> {
        let rig = Rig::parse(&COMPACT, 2)?;
        assert!(rig.is_compact());
        assert_eq!(rig.rate_mhz(), 50_000);
        let want = RigServo {
            output: 0,
            angle_lo_mdeg: -45_000,
            angle_hi_mdeg: 45_000,
            pulse_lo_qus: 4000,
            pulse_hi_qus: 8000,
            neutral_qus: 6000,
            max_speed_mdeg_s: 300_000,
        };
        let mut servos = rig.servos();
        assert_eq!(servos.next(), Some(want));
        assert_eq!(servos.next(), Some(RigServo { output: 1, ..want }));
        assert_eq!(servos.next(), None);
        Ok(())
    }

    #[test]
    fn compact_table_rejects_bad_flags_and_truncation() {
        assert!(Rig::parse(&COMPACT, 3).is_err());
        for cut in 1..COMPACT.len() {
            let short = COMPACT.get(..cut).unwrap_or(&[]);
            assert!(Rig::parse(short, 2).is_err(), "cut at {cut}");
        }
        let with = |at: usize, v: u8| {
            let mut b = COMPACT;
            if let Some(x) = b.get_mut(at) {
                *x = v;
            }
            b
        };
        // An undefined bit; SAME_MAP, SAME_RANGE, SAME_SPEED on the first
        // servo; ANGLE_DEG with SAME_RANGE; SPEED_DEG with SAME_SPEED.
        assert!(Rig::parse(&with(5, 0xAD), 2).is_err());
        assert!(Rig::parse(&with(5, 0x6D), 2).is_err());
        assert!(Rig::parse(&with(5, 0x2B), 2).is_err());
        assert!(Rig::parse(&with(5, 0x1D), 2).is_err());
        assert!(Rig::parse(&with(14, 0x1F), 2).is_err());
        assert!(Rig::parse(&with(14, 0x3B), 2).is_err());
        // Trailing bytes.
        let mut long = [0x1B; 16];
        for (l, &c) in long.iter_mut().zip(&COMPACT) {
            *l = c;
        }
        assert!(Rig::parse(&long, 2).is_err());
    }

    #[test]
    fn same_map_follows_the_previous_servos_line() {
        let s = RigServo {
            output: 0,
            angle_lo_mdeg: -45_000,
            angle_hi_mdeg: 45_000,
            pulse_lo_qus: 4000,
            pulse_hi_qus: 8000,
            neutral_qus: 6000,
            max_speed_mdeg_s: 0,
        };
        // Extrapolated past the travel, truncating toward zero.
        assert_eq!(s.line_qus(-90_000), Some(2000));
        assert_eq!(s.line_qus(-36_000), Some(4400));
        assert_eq!(s.line_qus(1), Some(6000));
        assert_eq!(s.line_qus(-1), Some(5999));
        assert_eq!(s.line_qus(i64::from(i32::MAX)), None);
    }
}

/// One servo of a rig as its digest covers it (SPEC.md §3.6): the rig
/// table's servo and the figure's speed and acceleration limits of its
/// output (`mocap_servo::HardLimit`; 0 = none).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DigestServo {
    /// The servo as the rig table holds it.
    pub servo: RigServo,
    /// Most the pulse may change per second, ¼ µs/s.
    pub max_speed_qus_s: u32,
    /// Most the pulse's speed may change per second, ¼ µs/s².
    pub max_accel_qus_s2: u32,
}

/// Bytes of one servo's record in the digest (SPEC.md §3.6).
pub const DIGEST_SERVO_LEN: usize = 28;

/// The rig digest of SPEC.md §3.6: the CRC-32 (§2.3) of `rate_mhz` and the
/// servo count as two `u32`s, then per servo, little-endian, `output` (u16),
/// `angle_lo`, `angle_hi` (i32), `pulse_lo`, `pulse_hi`, `neutral` (u16),
/// `max_speed` (u32, mdeg/s), `max_speed_qus_s`, `max_accel_qus_s2` (u32).
/// What a figure and a clip must agree on for the clip to be the figure's:
/// the rig table and the mechanism's speed and acceleration.
pub fn rig_digest<I>(rate_mhz: u32, servos: I) -> u32
where
    I: IntoIterator<Item = DigestServo>,
    I::IntoIter: ExactSizeIterator,
{
    let servos = servos.into_iter();
    let mut digest = crate::wire::Crc32Digest::new();
    digest.update(&rate_mhz.to_le_bytes());
    let count = u32::try_from(servos.len()).unwrap_or(u32::MAX);
    digest.update(&count.to_le_bytes());
    for d in servos {
        let s = &d.servo;
        digest.update(&s.output.to_le_bytes());
        digest.update(&s.angle_lo_mdeg.to_le_bytes());
        digest.update(&s.angle_hi_mdeg.to_le_bytes());
        digest.update(&s.pulse_lo_qus.to_le_bytes());
        digest.update(&s.pulse_hi_qus.to_le_bytes());
        digest.update(&s.neutral_qus.to_le_bytes());
        digest.update(&s.max_speed_mdeg_s.to_le_bytes());
        digest.update(&d.max_speed_qus_s.to_le_bytes());
        digest.update(&d.max_accel_qus_s2.to_le_bytes());
    }
    digest.finalize()
}
