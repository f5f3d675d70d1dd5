//! The crate's errors: one flat enum for everything decided in this crate, and
//! [`OutputError`] for outputs that also talk to hardware.

use core::fmt;

/// Everything this crate can reject. Names are prefixed by the phase that
/// raises them (`Limits…`, `Frame…`), as in postcard.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// A servo's limits break `min_qus <= neutral_qus <= max_qus`.
    LimitsInvalid {
        /// Lowest pulse, quarter-µs.
        min_qus: u16,
        /// Rest pulse, quarter-µs.
        neutral_qus: u16,
        /// Highest pulse, quarter-µs.
        max_qus: u16,
    },
    /// A per-servo slice does not have one value per servo.
    LengthMismatch {
        /// Number of servos.
        expected: usize,
        /// Length of the slice given.
        actual: usize,
    },
    /// The caller's output buffer cannot hold the encoded bytes.
    BufferTooSmall {
        /// Bytes the encoding needs (at most this many).
        needed: usize,
        /// Length of the buffer given.
        available: usize,
    },
    /// A channel number the protocol cannot address.
    ChannelOutOfRange {
        /// The highest channel the command would address.
        channel: usize,
        /// The highest channel the protocol can address.
        max: u8,
    },
    /// A Maestro target above the 14 bits the compact protocol carries.
    TargetOutOfRange {
        /// The target, quarter-µs.
        target_qus: u16,
        /// The largest target the protocol carries (`0x3FFF`).
        max_qus: u16,
    },
    /// A `ClipChunk` carries more bytes than [`crate::stream::MAX_CHUNK_LEN`].
    ChunkTooLong {
        /// Bytes in the chunk.
        len: usize,
        /// The most a chunk may carry.
        max: usize,
    },
    /// A frame did not fit into the receiver's buffer; it was dropped.
    FrameOverflow {
        /// The receiver's capacity in encoded bytes.
        capacity: usize,
    },
    /// A frame is not valid COBS.
    FrameCobs,
    /// A decoded frame is too short to hold a message and its CRC.
    FrameTooShort {
        /// Decoded bytes.
        len: usize,
    },
    /// The CRC-32 stored in a frame does not match its message bytes.
    FrameCrcMismatch {
        /// CRC read from the frame.
        stored: u32,
        /// CRC computed over the message bytes.
        computed: u32,
    },
    /// The CRC matched but the bytes are not exactly one valid message (or,
    /// never for a message within the limits, postcard could not encode one).
    FrameMessage,
    /// More servos than an output drives or a `Pose` carries.
    TooManyServos {
        /// Servos given.
        count: usize,
        /// The most the output drives.
        max: usize,
    },
    /// An SSC-32 group move needs consecutive channels; these are not.
    OutputChannelsNotConsecutive,
    /// A serial port accepted none of the bytes written to it.
    OutputWriteZero,
    /// The return to neutral did not end (a servo without a speed limit is
    /// parked in one tick; one limited to 1/4 µs per tick in 65 535).
    NotParked {
        /// Ticks it took.
        ticks: u32,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::LimitsInvalid {
                min_qus,
                neutral_qus,
                max_qus,
            } => write!(
                f,
                "servo limits need min <= neutral <= max, got {min_qus} / {neutral_qus} / {max_qus} quarter-µs"
            ),
            Error::LengthMismatch { expected, actual } => {
                write!(f, "expected {expected} values (one per servo), got {actual}")
            }
            Error::BufferTooSmall { needed, available } => {
                write!(f, "output buffer too small: need {needed} bytes, have {available}")
            }
            Error::ChannelOutOfRange { channel, max } => {
                write!(f, "channel {channel} out of range (protocol maximum {max})")
            }
            Error::TargetOutOfRange { target_qus, max_qus } => {
                write!(f, "target {target_qus} quarter-µs above the protocol maximum {max_qus}")
            }
            Error::ChunkTooLong { len, max } => {
                write!(f, "clip chunk of {len} bytes, at most {max} allowed")
            }
            Error::FrameOverflow { capacity } => {
                write!(f, "frame longer than the receive buffer ({capacity} bytes), dropped")
            }
            Error::FrameCobs => f.write_str("frame is not valid COBS, dropped"),
            Error::FrameTooShort { len } => {
                write!(f, "frame of {len} bytes is too short for a message and its CRC, dropped")
            }
            Error::FrameCrcMismatch { stored, computed } => write!(
                f,
                "frame CRC mismatch (stored {stored:#010x}, computed {computed:#010x}), dropped"
            ),
            Error::FrameMessage => f.write_str("frame does not hold exactly one valid message, dropped"),
            Error::TooManyServos { count, max } => {
                write!(f, "{count} servos, at most {max} allowed")
            }
            Error::OutputChannelsNotConsecutive => {
                f.write_str("an SSC-32 group move needs consecutive channels")
            }
            Error::OutputWriteZero => f.write_str("the serial port accepted no bytes"),
            Error::NotParked { ticks } => {
                write!(f, "the return to neutral did not finish in {ticks} ticks")
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for Error {}

/// Error of an output that drives hardware: the pulses were rejected before
/// anything was written, or the device (PWM channel, I²C bus) failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum OutputError<E> {
    /// Rejected by this crate; nothing was written.
    Invalid(Error),
    /// Reported by the device; channels before the failing one were written.
    Device(E),
}

impl<E> From<Error> for OutputError<E> {
    fn from(error: Error) -> Self {
        OutputError::Invalid(error)
    }
}

impl<E: fmt::Debug> fmt::Display for OutputError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OutputError::Invalid(error) => error.fmt(f),
            OutputError::Device(error) => write!(f, "servo output device error: {error:?}"),
        }
    }
}

#[cfg(feature = "std")]
impl<E: fmt::Debug> std::error::Error for OutputError<E> {}
