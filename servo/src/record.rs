//! Devices that record what an output tells them instead of driving
//! hardware: a PWM channel ([`DutyRecorder`]), a serial port
//! ([`SerialRecorder`]) and an I²C bus ([`I2cRecorder`]).
//!
//! They let the same [`crate::output`] code run where no servo is attached
//! — the firmware in QEMU, whose boards have no observable PWM or PCA9685,
//! and the host computing what that firmware must produce — and compare
//! the two byte for byte.
//!
//! Each recorder is shared: the HAL traits are implemented for `&Recorder`,
//! so an output owns a reference while the caller keeps another to read and
//! clear the record after each tick. Interior mutability is `Cell` and a
//! `RefCell` borrowed only inside one call (a failed borrow is an error,
//! never a panic).

use core::cell::{Cell, RefCell};
use core::convert::Infallible;
use core::fmt;

use embedded_hal::i2c::{self, I2c, Operation};
use embedded_hal::pwm::{self, SetDutyCycle};

/// Why a recorder refused a write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RecordError {
    /// The record is full: clear it after each tick.
    Full,
    /// The record was borrowed during the write (reentrant use).
    Busy,
}

impl fmt::Display for RecordError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RecordError::Full => "recorder full",
            RecordError::Busy => "recorder busy",
        })
    }
}

#[cfg(feature = "std")]
impl std::error::Error for RecordError {}

impl embedded_io::Error for RecordError {
    fn kind(&self) -> embedded_io::ErrorKind {
        match self {
            RecordError::Full => embedded_io::ErrorKind::OutOfMemory,
            RecordError::Busy => embedded_io::ErrorKind::Other,
        }
    }
}

impl i2c::Error for RecordError {
    fn kind(&self) -> i2c::ErrorKind {
        i2c::ErrorKind::Other
    }
}

/// A PWM channel that keeps the last duty cycle set.
#[derive(Debug)]
pub struct DutyRecorder {
    max_duty: u16,
    duty: Cell<u16>,
}

impl DutyRecorder {
    /// A channel whose full period is `max_duty` counts, at duty 0.
    pub const fn new(max_duty: u16) -> Self {
        DutyRecorder {
            max_duty,
            duty: Cell::new(0),
        }
    }

    /// The last duty cycle set.
    pub fn duty(&self) -> u16 {
        self.duty.get()
    }
}

impl pwm::ErrorType for &DutyRecorder {
    type Error = Infallible;
}

impl SetDutyCycle for &DutyRecorder {
    fn max_duty_cycle(&self) -> u16 {
        self.max_duty
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Self::Error> {
        self.duty.set(duty);
        Ok(())
    }
}

/// A transmit-only serial port that keeps up to `CAP` bytes written.
#[derive(Debug, Default)]
pub struct SerialRecorder<const CAP: usize> {
    bytes: RefCell<heapless::Vec<u8, CAP>>,
}

impl<const CAP: usize> SerialRecorder<CAP> {
    /// An empty record.
    pub const fn new() -> Self {
        SerialRecorder {
            bytes: RefCell::new(heapless::Vec::new()),
        }
    }

    /// Calls `f` with the bytes written since the last [`clear`](Self::clear).
    pub fn with_bytes<R>(&self, f: impl FnOnce(&[u8]) -> R) -> Result<R, RecordError> {
        let bytes = self.bytes.try_borrow().map_err(|_| RecordError::Busy)?;
        Ok(f(&bytes))
    }

    /// Forgets the bytes written so far.
    pub fn clear(&self) {
        if let Ok(mut bytes) = self.bytes.try_borrow_mut() {
            bytes.clear();
        }
    }
}

impl<const CAP: usize> embedded_io::ErrorType for &SerialRecorder<CAP> {
    type Error = RecordError;
}

impl<const CAP: usize> embedded_io::Write for &SerialRecorder<CAP> {
    /// Keeps as many bytes as fit; [`RecordError::Full`] when none do.
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        let mut bytes = self.bytes.try_borrow_mut().map_err(|_| RecordError::Busy)?;
        let room = CAP.saturating_sub(bytes.len());
        if room == 0 && !buf.is_empty() {
            return Err(RecordError::Full);
        }
        let n = buf.len().min(room);
        bytes
            .extend_from_slice(buf.get(..n).unwrap_or_default())
            .map_err(|_| RecordError::Full)?;
        Ok(n)
    }

    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// An I²C bus that keeps every write (address and bytes), up to `CAP` bytes
/// of record in all (2 bytes per write plus its data). Reads return zeros.
#[derive(Debug, Default)]
pub struct I2cRecorder<const CAP: usize> {
    /// Writes, each as `address, length, bytes…`.
    log: RefCell<heapless::Vec<u8, CAP>>,
}

impl<const CAP: usize> I2cRecorder<CAP> {
    /// An empty record.
    pub const fn new() -> Self {
        I2cRecorder {
            log: RefCell::new(heapless::Vec::new()),
        }
    }

    /// Calls `f(address, bytes)` for each write since the last
    /// [`clear`](Self::clear), in order.
    pub fn for_each_write(&self, mut f: impl FnMut(u8, &[u8])) -> Result<(), RecordError> {
        let log = self.log.try_borrow().map_err(|_| RecordError::Busy)?;
        let mut rest: &[u8] = &log;
        while let [address, len, tail @ ..] = rest {
            let (bytes, next) = tail.split_at(usize::from(*len).min(tail.len()));
            f(*address, bytes);
            rest = next;
        }
        Ok(())
    }

    /// Forgets the writes so far.
    pub fn clear(&self) {
        if let Ok(mut log) = self.log.try_borrow_mut() {
            log.clear();
        }
    }
}

impl<const CAP: usize> i2c::ErrorType for &I2cRecorder<CAP> {
    type Error = RecordError;
}

impl<const CAP: usize> I2c for &I2cRecorder<CAP> {
    /// Records the writes; nothing is recorded when the record cannot hold
    /// them all.
    fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        let mut log = self.log.try_borrow_mut().map_err(|_| RecordError::Busy)?;
        let mark = log.len();
        for op in operations {
            match op {
                Operation::Write(bytes) => {
                    let len = u8::try_from(bytes.len()).map_err(|_| RecordError::Full);
                    let pushed = len.and_then(|len| {
                        log.extend_from_slice(&[address, len])
                            .and_then(|()| log.extend_from_slice(bytes))
                            .map_err(|_| RecordError::Full)
                    });
                    if let Err(e) = pushed {
                        log.truncate(mark);
                        return Err(e);
                    }
                }
                Operation::Read(buf) => buf.fill(0),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use std::vec;
    use std::vec::Vec;

    use super::*;
    use embedded_io::Write as _;

    #[test]
    fn duty_recorder_keeps_the_last_duty() {
        let rec = DutyRecorder::new(1000);
        let mut ch = &rec;
        assert_eq!(ch.max_duty_cycle(), 1000);
        ch.set_duty_cycle(75).unwrap();
        ch.set_duty_cycle(80).unwrap();
        assert_eq!(rec.duty(), 80);
    }

    #[test]
    fn serial_recorder_fills_then_refuses() {
        let rec = SerialRecorder::<5>::new();
        let mut port = &rec;
        assert_eq!(port.write(&[1, 2, 3]), Ok(3));
        assert_eq!(port.write(&[4, 5, 6]), Ok(2));
        assert_eq!(port.write(&[7]), Err(RecordError::Full));
        assert_eq!(port.write(&[]), Ok(0));
        assert_eq!(rec.with_bytes(<[u8]>::to_vec), Ok(vec![1, 2, 3, 4, 5]));
        rec.clear();
        assert_eq!(rec.with_bytes(<[u8]>::len), Ok(0));
    }

    #[test]
    fn i2c_recorder_keeps_writes_and_refuses_what_does_not_fit() {
        let rec = I2cRecorder::<10>::new();
        let mut bus = &rec;
        bus.write(0x40, &[0xFE, 121]).unwrap();
        let mut read = [9u8; 2];
        bus.write_read(0x41, &[0x00], &mut read).unwrap();
        assert_eq!(read, [0, 0]);
        // 4 + 3 bytes recorded; 5 more do not fit and leave no trace.
        assert_eq!(bus.write(0x40, &[1, 2, 3]), Err(RecordError::Full));
        let mut seen = Vec::new();
        rec.for_each_write(|a, b| seen.push((a, b.to_vec())))
            .unwrap();
        assert_eq!(seen, [(0x40, vec![0xFE, 121]), (0x41, vec![0x00])]);
        rec.clear();
        let mut count = 0;
        rec.for_each_write(|_, _| count += 1).unwrap();
        assert_eq!(count, 0);
    }
}
