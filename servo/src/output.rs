//! The outputs a playback loop drives, behind one trait: every tick the loop
//! hands [`ServoOutput::write`] the pulses a [`crate::Limiter`] let through,
//! one per servo in rig order, and the output puts them on its device.
//!
//! | output | device | one tick |
//! |---|---|---|
//! | [`MaestroOutput`] | UART (`embedded_io::Write`) | a Set Target per servo ([`crate::maestro`]) |
//! | [`Ssc32Output`] | UART (`embedded_io::Write`) | one group move ([`crate::ssc32`]) |
//! | [`PwmOutput`] | PWM channels (embedded-hal `SetDutyCycle`) through a [`ServoBank`] | every channel's duty |
//! | `Pca9685Output` (feature `pca9685`) | PCA9685 over I²C through `Pca9685Servos` | one register write per servo |
//!
//! Each output is built with the servos' controller channels (rig order;
//! at most [`MAX_SERVOS`]) and checks them once. A write rejected by this
//! crate ([`OutputError::Invalid`]) sends nothing.
//!
//! ```
//! use mocap_servo::output::{MaestroOutput, ServoOutput};
//!
//! let mut wire = [0u8; 8];
//! let mut maestro = MaestroOutput::new(&mut wire[..], &[0, 5]).unwrap();
//! maestro.write(&[6000, 4000]).unwrap();
//! assert_eq!(wire, [0x84, 0, 0x70, 0x2E, 0x84, 5, 0x20, 0x1F]);
//! ```

use embedded_hal::pwm::SetDutyCycle;
use embedded_io::Write;

use crate::{maestro, ssc32, Error, OutputError, ServoBank};

/// Most servos one output drives (a figure of 8–40 servos spans several
/// controllers' channels; a `Pose` carries at most 32).
pub const MAX_SERVOS: usize = 64;

/// Where a playback loop sends each tick's pulses.
pub trait ServoOutput {
    /// The device's error, inside [`OutputError::Device`].
    type Error;

    /// Commands one tick: `pulses_qus[i]` (quarter-µs) goes to servo `i`,
    /// in the order of the channels the output was built with; exactly one
    /// pulse per servo.
    fn write(&mut self, pulses_qus: &[u16]) -> Result<(), OutputError<Self::Error>>;
}

type Channels = heapless::Vec<u8, MAX_SERVOS>;

/// Checks and narrows the servos' channels: at most [`MAX_SERVOS`], each at
/// most `max`.
fn channels(outputs: &[u16], max: u8) -> Result<Channels, Error> {
    let mut channels = Channels::new();
    for &output in outputs {
        let channel =
            u8::try_from(output)
                .ok()
                .filter(|&c| c <= max)
                .ok_or(Error::ChannelOutOfRange {
                    channel: usize::from(output),
                    max,
                })?;
        channels.push(channel).map_err(|_| Error::TooManyServos {
            count: outputs.len(),
            max: MAX_SERVOS,
        })?;
    }
    Ok(channels)
}

fn check_count(servos: usize, pulses: usize) -> Result<(), Error> {
    if servos == pulses {
        Ok(())
    } else {
        Err(Error::LengthMismatch {
            expected: servos,
            actual: pulses,
        })
    }
}

/// `write_all` without a panic path: a port that takes no bytes is an error.
fn write_all<W: Write>(port: &mut W, mut bytes: &[u8]) -> Result<(), OutputError<W::Error>> {
    while !bytes.is_empty() {
        let n = port.write(bytes).map_err(OutputError::Device)?;
        if n == 0 {
            return Err(Error::OutputWriteZero.into());
        }
        bytes = bytes.get(n..).unwrap_or_default();
    }
    Ok(())
}

/// A Pololu Maestro on a UART: one Set Target (`84 ch low7 high7`, target in
/// quarter-µs) per servo per tick, in rig order, written at once.
#[derive(Debug)]
pub struct MaestroOutput<W> {
    port: W,
    channels: Channels,
}

impl<W: Write> MaestroOutput<W> {
    /// The servos on Maestro channels `outputs` (at most 127).
    pub fn new(port: W, outputs: &[u16]) -> Result<Self, Error> {
        Ok(MaestroOutput {
            port,
            channels: channels(outputs, maestro::MAX_CHANNEL)?,
        })
    }

    /// The port back.
    pub fn release(self) -> W {
        self.port
    }
}

impl<W: Write> ServoOutput for MaestroOutput<W> {
    type Error = W::Error;

    fn write(&mut self, pulses_qus: &[u16]) -> Result<(), OutputError<W::Error>> {
        check_count(self.channels.len(), pulses_qus.len())?;
        let mut bytes = [0u8; maestro::SET_TARGET_LEN * MAX_SERVOS];
        let mut len = 0;
        for (&channel, &pulse) in self.channels.iter().zip(pulses_qus) {
            let slot = bytes.get_mut(len..).unwrap_or_default();
            // At most 4 · MAX_SERVOS: wrapping is plain addition here, and keeps
            // the loop as cheap as it was (saturating cost ~20 instructions a servo).
            len = len.wrapping_add(maestro::set_target(channel, pulse, slot)?);
        }
        write_all(&mut self.port, bytes.get(..len).unwrap_or_default())
    }
}

/// A Lynxmotion SSC-32 on a UART: one group move per tick,
/// `#<ch>P<µs>…T<ms>\r`, channels in ascending order. The servos' channels
/// must be consecutive (in any rig order).
#[derive(Debug)]
pub struct Ssc32Output<W> {
    port: W,
    first: u8,
    /// `order[k]` is the servo on channel `first + k`.
    order: Channels,
    time_ms: u16,
}

impl<W: Write> Ssc32Output<W> {
    /// The servos on SSC-32 channels `outputs` (consecutive, at most 31),
    /// each move taking `time_ms` (the tick period).
    pub fn new(port: W, outputs: &[u16], time_ms: u16) -> Result<Self, Error> {
        let channels = channels(outputs, ssc32::MAX_CHANNEL)?;
        let first = channels.iter().copied().min().unwrap_or(0);
        let mut order = Channels::new();
        for k in 0..channels.len() {
            // Servo on channel first + k: exactly one, else not consecutive.
            let want = usize::from(first).saturating_add(k);
            let mut on = channels
                .iter()
                .enumerate()
                .filter(|&(_, &c)| usize::from(c) == want);
            let (servo, _) = on.next().ok_or(Error::OutputChannelsNotConsecutive)?;
            if on.next().is_some() {
                return Err(Error::OutputChannelsNotConsecutive);
            }
            // servo < MAX_SERVOS = 64: fits a u8; order has room for every servo.
            order
                .push(servo as u8)
                .map_err(|_| Error::OutputChannelsNotConsecutive)?;
        }
        Ok(Ssc32Output {
            port,
            first,
            order,
            time_ms,
        })
    }

    /// The port back.
    pub fn release(self) -> W {
        self.port
    }
}

impl<W: Write> ServoOutput for Ssc32Output<W> {
    type Error = W::Error;

    fn write(&mut self, pulses_qus: &[u16]) -> Result<(), OutputError<W::Error>> {
        check_count(self.order.len(), pulses_qus.len())?;
        let mut by_channel = [0u16; MAX_SERVOS];
        for (slot, &servo) in by_channel.iter_mut().zip(&self.order) {
            *slot = pulses_qus.get(usize::from(servo)).copied().unwrap_or(0);
        }
        let pulses = by_channel.get(..self.order.len()).unwrap_or_default();
        let mut bytes = [0u8; ssc32::group_move_max_len(MAX_SERVOS)];
        let len = ssc32::group_move(self.first, pulses, self.time_ms, &mut bytes)?;
        write_all(&mut self.port, bytes.get(..len).unwrap_or_default())
    }
}

/// Servos on `N` PWM channels of the MCU through a [`ServoBank`]: every tick
/// sets every channel, the servos' channels to their pulses and the others
/// to duty 0 (no pulse: an unused channel stays quiet).
#[derive(Debug)]
pub struct PwmOutput<P, const N: usize> {
    bank: ServoBank<P, N>,
    channels: Channels,
}

impl<P: SetDutyCycle, const N: usize> PwmOutput<P, N> {
    /// The servos on channels `outputs` of `bank` (each below `N`).
    pub fn new(bank: ServoBank<P, N>, outputs: &[u16]) -> Result<Self, Error> {
        let max = u8::try_from(N.saturating_sub(1)).unwrap_or(u8::MAX);
        if N == 0 && !outputs.is_empty() {
            return Err(Error::TooManyServos {
                count: outputs.len(),
                max: 0,
            });
        }
        Ok(PwmOutput {
            bank,
            channels: channels(outputs, max)?,
        })
    }

    /// The bank back.
    pub fn release(self) -> ServoBank<P, N> {
        self.bank
    }
}

impl<P: SetDutyCycle, const N: usize> ServoOutput for PwmOutput<P, N> {
    type Error = P::Error;

    fn write(&mut self, pulses_qus: &[u16]) -> Result<(), OutputError<P::Error>> {
        check_count(self.channels.len(), pulses_qus.len())?;
        let mut by_channel = [0u16; N];
        for (&channel, &pulse) in self.channels.iter().zip(pulses_qus) {
            if let Some(slot) = by_channel.get_mut(usize::from(channel)) {
                *slot = pulse;
            }
        }
        self.bank.write(&by_channel)
    }
}

#[cfg(feature = "pca9685")]
pub use pca::Pca9685Output;

#[cfg(feature = "pca9685")]
mod pca {
    use embedded_hal::i2c::I2c;

    use super::{channels, check_count, Channels, ServoOutput};
    use crate::pca9685::{Pca9685Servos, MAX_CHANNEL};
    use crate::{Error, OutputError};

    /// Servos on a PCA9685 over I²C (50 Hz; pulses to the nearest 4.88 µs
    /// step, see [`crate::pca9685`]): one 5-byte register write per servo per
    /// tick, in rig order.
    #[derive(Debug)]
    pub struct Pca9685Output<I2C> {
        device: Pca9685Servos<I2C>,
        channels: Channels,
    }

    impl<I2C: I2c> Pca9685Output<I2C> {
        /// The servos on PCA9685 channels `outputs` (at most 15) of `device`.
        pub fn new(device: Pca9685Servos<I2C>, outputs: &[u16]) -> Result<Self, Error> {
            Ok(Pca9685Output {
                device,
                channels: channels(outputs, MAX_CHANNEL)?,
            })
        }

        /// The device back.
        pub fn release(self) -> Pca9685Servos<I2C> {
            self.device
        }
    }

    impl<I2C: I2c> ServoOutput for Pca9685Output<I2C> {
        type Error = pwm_pca9685::Error<I2C::Error>;

        fn write(&mut self, pulses_qus: &[u16]) -> Result<(), OutputError<Self::Error>> {
            check_count(self.channels.len(), pulses_qus.len())?;
            for (&channel, &pulse) in self.channels.iter().zip(pulses_qus) {
                self.device.write(channel, core::slice::from_ref(&pulse))?;
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use std::vec;
    use std::vec::Vec;

    use super::*;
    use crate::record::{DutyRecorder, I2cRecorder, SerialRecorder};

    #[test]
    fn maestro_writes_one_set_target_per_servo_in_rig_order() {
        let rec = SerialRecorder::<64>::new();
        let mut out = MaestroOutput::new(&rec, &[3, 1]).unwrap();
        out.write(&[6000, 8000]).unwrap();
        let bytes = rec.with_bytes(<[u8]>::to_vec).unwrap();
        assert_eq!(bytes, [0x84, 3, 0x70, 0x2E, 0x84, 1, 0x40, 0x3E]);
        // Rejected pulses send nothing.
        rec.clear();
        assert!(matches!(
            out.write(&[6000, 0x4000]),
            Err(OutputError::Invalid(Error::TargetOutOfRange { .. }))
        ));
        assert!(matches!(
            out.write(&[6000]),
            Err(OutputError::Invalid(Error::LengthMismatch {
                expected: 2,
                actual: 1
            }))
        ));
        assert_eq!(rec.with_bytes(<[u8]>::len), Ok(0));
        assert!(matches!(
            MaestroOutput::new(&rec, &[128]),
            Err(Error::ChannelOutOfRange {
                channel: 128,
                max: 127
            })
        ));
        let many = [0u16; MAX_SERVOS + 1];
        assert!(matches!(
            MaestroOutput::new(&rec, &many),
            Err(Error::TooManyServos { count: 65, max: 64 })
        ));
    }

    #[test]
    fn a_port_that_takes_nothing_is_an_error() {
        let rec = SerialRecorder::<0>::new();
        let mut out = MaestroOutput::new(&rec, &[0]).unwrap();
        assert!(matches!(
            out.write(&[6000]),
            Err(OutputError::Device(crate::record::RecordError::Full))
        ));
        let mut empty: [u8; 0] = [];
        let mut out = MaestroOutput::new(&mut empty[..], &[0]).unwrap();
        assert!(out.write(&[6000]).is_err());
    }

    #[test]
    fn ssc32_sorts_channels_and_needs_them_consecutive() {
        let rec = SerialRecorder::<64>::new();
        let mut out = Ssc32Output::new(&rec, &[5, 3, 4], 20).unwrap();
        out.write(&[8000, 6000, 7000]).unwrap();
        let text = rec.with_bytes(<[u8]>::to_vec).unwrap();
        assert_eq!(text, b"#3P1500#4P1750#5P2000T20\r");
        assert!(matches!(
            Ssc32Output::new(&rec, &[0, 2], 20),
            Err(Error::OutputChannelsNotConsecutive)
        ));
        assert!(matches!(
            Ssc32Output::new(&rec, &[1, 1, 2], 20),
            Err(Error::OutputChannelsNotConsecutive)
        ));
        assert!(Ssc32Output::new(&rec, &[32], 20).is_err());
    }

    #[test]
    fn pwm_sets_every_channel_and_quiets_the_unused_ones() {
        let recorders: [DutyRecorder; 4] = core::array::from_fn(|_| DutyRecorder::new(20_000));
        for r in &recorders {
            let mut ch = r;
            ch.set_duty_cycle(99).unwrap();
        }
        let mut out = PwmOutput::new(ServoBank::new(recorders.each_ref()), &[2, 0]).unwrap();
        out.write(&[6000, 8001]).unwrap();
        let duties: Vec<u16> = recorders.iter().map(DutyRecorder::duty).collect();
        // 2000.25 µs -> 2000; 1500 µs; channels 1 and 3 unused -> 0.
        assert_eq!(duties, [2000, 0, 1500, 0]);
        assert!(matches!(
            PwmOutput::new(ServoBank::new(recorders.each_ref()), &[4]),
            Err(Error::ChannelOutOfRange { channel: 4, max: 3 })
        ));
    }

    #[test]
    fn pca9685_writes_one_register_block_per_servo() {
        use crate::pca9685::{Address, Pca9685Servos};
        let rec = I2cRecorder::<64>::new();
        let device = Pca9685Servos::new(&rec, Address::default()).unwrap();
        rec.clear();
        let mut out = Pca9685Output::new(device, &[4, 3]).unwrap();
        out.write(&[8000, 6000]).unwrap();
        let mut writes = Vec::new();
        rec.for_each_write(|a, b| writes.push((a, b.to_vec())))
            .unwrap();
        assert_eq!(
            writes,
            [
                (0x40, vec![0x00, 0x21]), // MODE1 auto-increment, before the first block
                (0x40, vec![0x16, 0x00, 0x00, 0x9A, 0x01]), // LED4 off 410
                (0x40, vec![0x12, 0x00, 0x00, 0x33, 0x01]), // LED3 off 307
            ]
        );
        assert!(Pca9685Output::new(out.release(), &[16]).is_err());
    }
}
