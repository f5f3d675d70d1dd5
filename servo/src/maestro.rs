//! Pololu Maestro servo controllers, compact protocol (UART).
//!
//! Targets are in quarter-µs, the Maestro's own unit, sent as two 7-bit data
//! bytes (low 7 bits first), so the protocol carries `0..=0x3FFF`. A target of
//! 0 tells the Maestro to stop sending pulses on that channel.
//!
//! | command              | bytes                                                              |
//! |----------------------|--------------------------------------------------------------------|
//! | Set Target           | `0x84, channel, target & 0x7F, (target >> 7) & 0x7F`                |
//! | Set Multiple Targets | `0x9F, count, first channel, then low, high for each target`        |
//!
//! Set Multiple Targets exists on the Mini Maestro 12/18/24 only.
//! Each function writes into the caller's buffer and returns the byte count,
//! ready for `uart.write_all(&buf[..n])`.

use crate::Error;

/// Command byte of Set Target.
pub const SET_TARGET: u8 = 0x84;
/// Command byte of Set Multiple Targets.
pub const SET_MULTIPLE_TARGETS: u8 = 0x9F;
/// Largest target the compact protocol carries (14 bits, 4095.75 µs).
pub const MAX_TARGET_QUS: u16 = 0x3FFF;
/// Highest channel number a data byte can hold.
pub const MAX_CHANNEL: u8 = 0x7F;

/// Bytes of one Set Target command.
pub const SET_TARGET_LEN: usize = 4;

/// Bytes of a Set Multiple Targets command for `count` targets.
pub const fn set_multiple_targets_len(count: usize) -> usize {
    count.saturating_mul(2).saturating_add(3)
}

/// Encodes Set Target for `channel` into `buf`; returns 4.
pub fn set_target(channel: u8, target_qus: u16, buf: &mut [u8]) -> Result<usize, Error> {
    check_channel(usize::from(channel))?;
    let [low, high] = target_bytes(target_qus)?;
    match buf {
        [b0, b1, b2, b3, ..] => {
            (*b0, *b1, *b2, *b3) = (SET_TARGET, channel, low, high);
            Ok(SET_TARGET_LEN)
        }
        _ => Err(Error::BufferTooSmall {
            needed: SET_TARGET_LEN,
            available: buf.len(),
        }),
    }
}

/// Encodes Set Multiple Targets for the channels `first_channel..` (one per
/// target) into `buf`; returns the byte count. An empty `targets_qus` writes
/// nothing and returns 0. Nothing is written on error.
pub fn set_multiple_targets(
    first_channel: u8,
    targets_qus: &[u16],
    buf: &mut [u8],
) -> Result<usize, Error> {
    let Some(last) = targets_qus.len().checked_sub(1) else {
        return Ok(0);
    };
    check_channel(usize::from(first_channel).saturating_add(last))?;
    // check_channel bounds the count by 128, so it fits a data byte.
    let count = targets_qus.len() as u8;
    let needed = set_multiple_targets_len(targets_qus.len());
    let available = buf.len();
    let Some((header, body)) = buf
        .get_mut(..needed)
        .and_then(|b| b.split_first_chunk_mut::<3>())
    else {
        return Err(Error::BufferTooSmall { needed, available });
    };
    for &target in targets_qus {
        target_bytes(target)?;
    }
    for (pair, &target) in body.chunks_exact_mut(2).zip(targets_qus) {
        pair.copy_from_slice(&target_bytes(target)?);
    }
    *header = [SET_MULTIPLE_TARGETS, count, first_channel];
    Ok(needed)
}

const fn check_channel(channel: usize) -> Result<(), Error> {
    if channel <= MAX_CHANNEL as usize {
        Ok(())
    } else {
        Err(Error::ChannelOutOfRange {
            channel,
            max: MAX_CHANNEL,
        })
    }
}

const fn target_bytes(target_qus: u16) -> Result<[u8; 2], Error> {
    if target_qus > MAX_TARGET_QUS {
        return Err(Error::TargetOutOfRange {
            target_qus,
            max_qus: MAX_TARGET_QUS,
        });
    }
    Ok([(target_qus & 0x7F) as u8, (target_qus >> 7) as u8])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_target_matches_pololu_example() {
        // Pololu's user guide: channel 2 to 1500 µs (6000 quarter-µs) is 0x84, 0x02, 0x70, 0x2E.
        let mut buf = [0u8; 8];
        assert_eq!(set_target(2, 6000, &mut buf), Ok(4));
        assert_eq!(buf[..4], [0x84, 0x02, 0x70, 0x2E]);
    }

    #[test]
    fn set_target_rejects_what_the_protocol_cannot_carry() {
        let mut buf = [0u8; 4];
        assert_eq!(
            set_target(0, 0x4000, &mut buf),
            Err(Error::TargetOutOfRange {
                target_qus: 0x4000,
                max_qus: 0x3FFF
            })
        );
        assert_eq!(
            set_target(128, 6000, &mut buf),
            Err(Error::ChannelOutOfRange {
                channel: 128,
                max: 127
            })
        );
        assert_eq!(
            set_target(0, 6000, &mut buf[..3]),
            Err(Error::BufferTooSmall {
                needed: 4,
                available: 3
            })
        );
        assert_eq!(set_target(127, 0x3FFF, &mut buf), Ok(4));
        assert_eq!(buf, [0x84, 0x7F, 0x7F, 0x7F]);
    }

    #[test]
    fn set_multiple_targets_matches_pololu_example() {
        // Pololu's user guide: channels 3 and 4 to 1500 µs and 1750 µs is
        // 0x9F, 0x02, 0x03, 0x70, 0x2E, 0x58, 0x36.
        let mut buf = [0xAAu8; 16];
        assert_eq!(set_multiple_targets(3, &[6000, 7000], &mut buf), Ok(7));
        assert_eq!(buf[..7], [0x9F, 0x02, 0x03, 0x70, 0x2E, 0x58, 0x36]);
        assert_eq!(buf[7], 0xAA);
    }

    #[test]
    fn set_multiple_targets_errors_write_nothing() {
        let mut buf = [0xAAu8; 16];
        assert_eq!(set_multiple_targets(0, &[], &mut buf), Ok(0));
        assert_eq!(
            set_multiple_targets(0, &[6000, 6000], &mut buf[..6]),
            Err(Error::BufferTooSmall {
                needed: 7,
                available: 6
            })
        );
        assert_eq!(
            set_multiple_targets(126, &[6000, 6000, 6000], &mut buf),
            Err(Error::ChannelOutOfRange {
                channel: 128,
                max: 127
            })
        );
        assert_eq!(
            set_multiple_targets(0, &[6000, 0xFFFF], &mut buf),
            Err(Error::TargetOutOfRange {
                target_qus: 0xFFFF,
                max_qus: 0x3FFF
            })
        );
        assert_eq!(buf, [0xAA; 16]);
    }
}
