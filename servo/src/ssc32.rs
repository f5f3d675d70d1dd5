//! Lynxmotion SSC-32 / SSC-32U servo controllers, text commands (UART).
//!
//! One output tick is one group move: every servo's pulse, then the move time,
//! so all servos arrive together:
//!
//! ```text
//! #0P1500#1P1625T20\r      channels 0 and 1 to 1500 µs and 1625 µs over 20 ms
//! ```
//!
//! The SSC-32 takes whole µs in `500..=2500`: quarter-µs are rounded to the
//! nearest µs (halves up) and clamped to that range.

use crate::Error;

/// Highest SSC-32 channel.
pub const MAX_CHANNEL: u8 = 31;
/// Shortest pulse the SSC-32 accepts, µs.
pub const MIN_PULSE_US: u16 = 500;
/// Longest pulse the SSC-32 accepts, µs.
pub const MAX_PULSE_US: u16 = 2500;

/// Longest group move for `count` servos: `#31P2500` per servo, `T65535\r`.
pub const fn group_move_max_len(count: usize) -> usize {
    count.saturating_mul(8).saturating_add(7)
}

/// The SSC-32 pulse (µs) for a pulse in quarter-µs: rounded, then clamped to
/// `500..=2500`.
pub const fn pulse_us(pulse_qus: u16) -> u16 {
    let us = (pulse_qus as u32).wrapping_add(2) / 4; // <= 16384: fits u16
    if us < MIN_PULSE_US as u32 {
        MIN_PULSE_US
    } else if us > MAX_PULSE_US as u32 {
        MAX_PULSE_US
    } else {
        us as u16
    }
}

/// Encodes one group move of channels `first_channel..` (one per pulse) over
/// `time_ms` into `buf`; returns the byte count. Nothing is written on error.
pub fn group_move(
    first_channel: u8,
    pulses_qus: &[u16],
    time_ms: u16,
    buf: &mut [u8],
) -> Result<usize, Error> {
    let last_channel =
        usize::from(first_channel).saturating_add(pulses_qus.len().saturating_sub(1));
    if last_channel > usize::from(MAX_CHANNEL) {
        return Err(Error::ChannelOutOfRange {
            channel: last_channel,
            max: MAX_CHANNEL,
        });
    }
    // A dry run sizes the command so that a short buffer stays untouched.
    let needed = write_group_move(
        first_channel,
        pulses_qus,
        time_ms,
        &mut Cursor::new(&mut []),
    );
    if needed > buf.len() {
        return Err(Error::BufferTooSmall {
            needed,
            available: buf.len(),
        });
    }
    Ok(write_group_move(
        first_channel,
        pulses_qus,
        time_ms,
        &mut Cursor::new(buf),
    ))
}

fn write_group_move(
    first_channel: u8,
    pulses_qus: &[u16],
    time_ms: u16,
    out: &mut Cursor<'_>,
) -> usize {
    for (channel, &pulse) in (u32::from(first_channel)..).zip(pulses_qus) {
        out.byte(b'#');
        out.decimal(channel);
        out.byte(b'P');
        out.decimal(u32::from(pulse_us(pulse)));
    }
    out.byte(b'T');
    out.decimal(u32::from(time_ms));
    out.byte(b'\r');
    out.len
}

/// Writes into a byte buffer while room remains, and counts every byte.
struct Cursor<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> Cursor<'a> {
    fn new(buf: &'a mut [u8]) -> Self {
        Cursor { buf, len: 0 }
    }

    fn byte(&mut self, byte: u8) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = byte;
        }
        // Counts on past the buffer (the length a caller needed); at most a
        // group move's length, far from wrapping.
        self.len = self.len.wrapping_add(1);
    }

    fn decimal(&mut self, mut value: u32) {
        let mut digits = [0u8; 10];
        let mut count = 0usize;
        for digit in digits.iter_mut().rev() {
            *digit = b'0'.wrapping_add((value % 10) as u8);
            value /= 10;
            count = count.wrapping_add(1); // <= 10 digits
            if value == 0 {
                break;
            }
        }
        for &digit in digits.iter().skip(digits.len().saturating_sub(count)) {
            self.byte(digit);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(buf: &[u8], len: usize) -> &str {
        core::str::from_utf8(&buf[..len]).unwrap()
    }

    #[test]
    fn group_move_matches_the_manual_form() {
        let mut buf = [0u8; 64];
        let n = group_move(0, &[6000, 6500], 20, &mut buf).unwrap();
        assert_eq!(text(&buf, n), "#0P1500#1P1625T20\r");
    }

    #[test]
    fn pulses_round_to_nearest_us_and_clamp() {
        assert_eq!(pulse_us(6001), 1500);
        assert_eq!(pulse_us(6002), 1501);
        assert_eq!(pulse_us(6003), 1501);
        assert_eq!(pulse_us(0), 500);
        assert_eq!(pulse_us(1999), 500);
        assert_eq!(pulse_us(10_002), 2500);
        assert_eq!(pulse_us(u16::MAX), 2500);
        let mut buf = [0u8; 64];
        let n = group_move(30, &[0, u16::MAX], 65535, &mut buf).unwrap();
        assert_eq!(text(&buf, n), "#30P500#31P2500T65535\r");
        assert_eq!(n, group_move_max_len(2) - 1);
    }

    #[test]
    fn errors_write_nothing() {
        let mut buf = [b'x'; 17];
        assert_eq!(
            group_move(0, &[6000, 6500], 20, &mut buf),
            Err(Error::BufferTooSmall {
                needed: 18,
                available: 17
            })
        );
        assert_eq!(
            group_move(31, &[6000, 6500], 20, &mut buf),
            Err(Error::ChannelOutOfRange {
                channel: 32,
                max: 31
            })
        );
        assert_eq!(buf, [b'x'; 17]);
        assert_eq!(group_move(0, &[], 0, &mut buf), Ok(3));
        assert_eq!(text(&buf, 3), "T0\r");
    }

    #[test]
    fn max_len_holds_for_all_channels() {
        let mut buf = [0u8; group_move_max_len(32)];
        let n = group_move(0, &[u16::MAX; 32], u16::MAX, &mut buf).unwrap();
        // Channels 0..=9 take one digit less than the bound assumes.
        assert_eq!(n, group_move_max_len(32) - 10);
    }
}
