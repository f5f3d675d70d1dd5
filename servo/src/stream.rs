//! Serial streaming between the host (`mocap send`) and the MCU.
//!
//! # Frame
//!
//! ```text
//! frame   = COBS(payload) 0x00
//! payload = message crc
//! message = postcard encoding of a `Message`
//! crc     = CRC-32/ISO-HDLC of `message`, 4 bytes little-endian
//! ```
//!
//! COBS leaves no `0x00` inside a frame, so `0x00` only ends frames: a
//! receiver that loses bytes or joins mid-stream drops at most the frame it
//! is in and is back in step at the next `0x00`. Empty frames (`0x00 0x00`)
//! are ignored, so a sender may start with a lone `0x00` to flush a
//! half-received frame. A frame is accepted only if it is valid COBS, its CRC
//! matches and `message` is exactly one valid message (no trailing bytes);
//! otherwise it is dropped and counted.
//!
//! # Message (postcard)
//!
//! The first byte is the variant index (postcard varint); integers `u16` and
//! `u32` are LEB128 varints, `u8` one byte, `bool` one byte `0x00`/`0x01`,
//! byte strings and vectors a varint length then the elements.
//!
//! | tag | message     | direction  | fields, in order                                        |
//! |-----|-------------|------------|---------------------------------------------------------|
//! | 0   | `Hello`     | host → MCU | `version: u8` ([`PROTOCOL_VERSION`])                     |
//! | 1   | `ClipChunk` | host → MCU | `offset: u32`, `total: u32`, `bytes: [u8]` (≤ 64)       |
//! | 2   | `Play`      | host → MCU | `loop_: bool`                                           |
//! | 3   | `Pose`      | host → MCU | `seq: u16`, `pulses: [u16]` (≤ 32, quarter-µs)          |
//! | 4   | `Stop`      | host → MCU | —                                                       |
//! | 5   | `Status`    | MCU → host | `received: u32`, `dropped: u32`, `last_seq: u16`, `state: u8`, `chunks: u32` |
//! | 6   | `Show`      | host → MCU | `at_ms: u32`, `op: u8`, `arg: u16`, `ms: u32`: a show command ([`ShowOp`]) |
//! | 7   | `Timecode`  | host → MCU | `show_ms: u32`: the show clock's time now |
//! | 8   | `ShowStatus`| MCU → host | `show_ms: u32`, `clip: u16`, `state: u8`, `list: u16`: the reply to `Show` op `Status` |
//!
//! A message is at most [`MAX_MESSAGE_LEN`] bytes (a `Pose` of 32 pulses of
//! 3-byte varints) and a frame at most [`MAX_FRAME_LEN`] bytes with its
//! delimiter; `FrameReceiver<{ MAX_FRAME_LEN }>` holds any frame.
//!
//! # Upload
//!
//! A clip's `ClipChunk`s may arrive in any order and any number of times;
//! [`upload::Upload`] is the receiving rule (SPEC.md §8.1), shared by the
//! firmware and the host's tests.

pub mod upload;

use serde::{Deserialize, Serialize};

use crate::Error;

/// Version carried by `Hello`; bumped on any change of this wire format.
///
/// 3: `Show` and `Timecode` (the show mode, SPEC.md §8.2). 2: `Status` carries `chunks`, and chunks of an upload may come in any
/// order and more than once (SPEC.md §8.1). 1: the first version.
pub const PROTOCOL_VERSION: u8 = 3;
/// Frame delimiter.
pub const DELIMITER: u8 = 0x00;
/// Most bytes one `ClipChunk` carries.
pub const MAX_CHUNK_LEN: usize = 64;
/// Most pulses one `Pose` carries.
pub const MAX_POSE_SERVOS: usize = 32;
/// Bytes of the CRC after the message.
pub const CRC_LEN: usize = 4;
/// Longest postcard message: `Pose` with tag, 3-byte `seq`, length and 32
/// pulses of 3 bytes each.
pub const MAX_MESSAGE_LEN: usize = 1 + 3 + 1 + 3 * MAX_POSE_SERVOS;
/// Longest frame: COBS of the longest payload plus the delimiter.
pub const MAX_FRAME_LEN: usize = cobs::max_encoding_length(MAX_MESSAGE_LEN + CRC_LEN) + 1;

/// The clip's CRC parameters (one definition: the decoder's wire module),
/// computed bitwise: the stream's messages are short, and no table in flash.
const CRC32: crc::Crc<u32, crc::NoTable> =
    crc::Crc::<u32, crc::NoTable>::new(mocap_decoder::wire::CRC_ALGORITHM);

/// One message of the serial protocol. The variant order is the wire tag:
/// never reorder, only append (and bump [`PROTOCOL_VERSION`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum Message<'a> {
    /// Opens a session; either side may send it.
    Hello {
        /// [`PROTOCOL_VERSION`] of the sender.
        version: u8,
    },
    /// A piece of a `.mcb` clip for the MCU's RAM buffer.
    ClipChunk {
        /// Byte offset of `bytes` in the clip.
        offset: u32,
        /// Length of the whole clip.
        total: u32,
        /// At most [`MAX_CHUNK_LEN`] bytes of the clip.
        bytes: &'a [u8],
    },
    /// Plays the uploaded clip.
    Play {
        /// Restart at the end instead of stopping.
        loop_: bool,
    },
    /// A live pose: one pulse per servo, applied at once (through the limits).
    Pose {
        /// Sender's sequence number, wrapping; gaps show lost poses.
        seq: u16,
        /// Pulses in quarter-µs, servo 0 first.
        pulses: heapless::Vec<u16, MAX_POSE_SERVOS>,
    },
    /// Stops playback; the MCU parks the servos at neutral.
    Stop,
    /// The MCU's report.
    Status {
        /// Frames accepted.
        received: u32,
        /// Frames dropped as corrupt.
        dropped: u32,
        /// `seq` of the last `Pose` applied.
        last_seq: u16,
        /// Player state, defined by the firmware.
        state: u8,
        /// Distinct chunks of the current upload received (0: no upload);
        /// the clip has `total.div_ceil(64)`.
        chunks: u32,
    },
    /// A command to the show in flash, at a show time (SPEC.md §8.2).
    Show {
        /// Show time it acts at, ms.
        at_ms: u32,
        /// What it does ([`ShowOp`]).
        op: u8,
        /// Its clip, cue list, input or on/off.
        arg: u16,
        /// A fade's length, ms (0 otherwise).
        ms: u32,
    },
    /// The show clock's time now: the MCU's show clock slews towards it.
    Timecode {
        /// Show time, ms.
        show_ms: u32,
    },
    /// The show mode's report, the reply to a `Show` of op [`ShowOp::Status`].
    ShowStatus {
        /// Show time of the report, ms.
        show_ms: u32,
        /// The clip that plays (the incoming one of a transition), `u16::MAX` for none.
        clip: u16,
        /// The show player's state: 0 idle, 1 playing, 2 blending, 3 held, 4 stopped, 5 ended.
        state: u8,
        /// The running cue list, `u16::MAX` for none.
        list: u16,
    },
}

/// `Show.op` (SPEC.md §8.2): the show commands of `mocap_decoder::Command`,
/// and `End`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum ShowOp {
    /// Start cue list `arg`.
    List = 0,
    /// Input `arg` fired.
    Trigger = 1,
    /// Play clip `arg`.
    Play = 2,
    /// Crossfade to clip `arg` over `ms`.
    Fade = 3,
    /// Queue clip `arg`.
    Queue = 4,
    /// Loop on (`arg` 1) or off (0).
    Loop = 5,
    /// Hold.
    Hold = 6,
    /// Resume.
    Resume = 7,
    /// Stop.
    Stop = 8,
    /// The show ends: the servos return to rest.
    End = 9,
    /// Report: the MCU answers with a `ShowStatus`.
    Status = 10,
    /// Lockstep: every command up to `at_ms` has been sent (`at_ms = u32::MAX`: all of them).
    Sync = 11,
}

/// What a `Show` message asks (SPEC.md §8.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShowRequest {
    /// A command of the show runner.
    Run(mocap_decoder::Command),
    /// The show ends.
    End,
    /// A `ShowStatus` in reply.
    Status,
    /// Every command up to this `Show`'s time has been sent (the MCU's show clock may run up
    /// to it; SPEC.md §8.2).
    Sync,
}

/// A show command as a `Show` message's fields (`End` is not a command).
pub fn show_message(at_ms: u32, command: mocap_decoder::Command) -> Message<'static> {
    use mocap_decoder::Command as C;
    let (op, arg, ms) = match command {
        C::List(l) => (ShowOp::List, l, 0),
        C::Trigger(i) => (ShowOp::Trigger, u16::from(i), 0),
        C::Play(c) => (ShowOp::Play, c, 0),
        C::Fade { clip, ms } => (ShowOp::Fade, clip, ms),
        C::Queue(c) => (ShowOp::Queue, c, 0),
        C::Loop(on) => (ShowOp::Loop, u16::from(on), 0),
        C::Hold => (ShowOp::Hold, 0, 0),
        C::Resume => (ShowOp::Resume, 0, 0),
        C::Stop => (ShowOp::Stop, 0, 0),
    };
    Message::Show {
        at_ms,
        op: op as u8,
        arg,
        ms,
    }
}

/// What a `Show` message asks; `None` for an op this version does not
/// know (or an input past `u8`, a loop flag other than 0 and 1).
pub fn show_request(op: u8, arg: u16, ms: u32) -> Option<ShowRequest> {
    use mocap_decoder::Command as C;
    Some(ShowRequest::Run(match op {
        0 => C::List(arg),
        1 => C::Trigger(u8::try_from(arg).ok()?),
        2 => C::Play(arg),
        3 => C::Fade { clip: arg, ms },
        4 => C::Queue(arg),
        5 => C::Loop(match arg {
            0 => false,
            1 => true,
            _ => return None,
        }),
        6 => C::Hold,
        7 => C::Resume,
        8 => C::Stop,
        9 => return Some(ShowRequest::End),
        10 => return Some(ShowRequest::Status),
        11 => return Some(ShowRequest::Sync),
        _ => return None,
    }))
}

impl Message<'_> {
    /// A `Pose` of `pulses` (at most [`MAX_POSE_SERVOS`]).
    pub fn pose(seq: u16, pulses: &[u16]) -> Result<Self, Error> {
        let pulses = heapless::Vec::from_slice(pulses).map_err(|_| Error::TooManyServos {
            count: pulses.len(),
            max: MAX_POSE_SERVOS,
        })?;
        Ok(Message::Pose { seq, pulses })
    }
}

/// Encodes `message` as one complete frame (delimiter included) into `buf`
/// and returns its length, at most [`MAX_FRAME_LEN`].
pub fn encode_frame(message: &Message<'_>, buf: &mut [u8]) -> Result<usize, Error> {
    check_chunk(message)?;
    let mut payload = [0u8; MAX_MESSAGE_LEN + CRC_LEN];
    // Every message that passed check_chunk fits MAX_MESSAGE_LEN.
    let message_len = postcard::to_slice(message, &mut payload)
        .map_err(|_| Error::FrameMessage)?
        .len();
    let (message_bytes, rest) = payload
        .split_at_mut_checked(message_len)
        .ok_or(Error::FrameMessage)?;
    let crc = CRC32.checksum(message_bytes).to_le_bytes();
    rest.get_mut(..CRC_LEN)
        .ok_or(Error::FrameMessage)?
        .copy_from_slice(&crc);
    let payload = payload
        .get(..message_len.saturating_add(CRC_LEN))
        .unwrap_or_default();

    let needed = cobs::max_encoding_length(payload.len()).saturating_add(1);
    let available = buf.len();
    let too_small = Error::BufferTooSmall { needed, available };
    let encoded_len = cobs::try_encode(payload, buf).map_err(|_| too_small)?;
    *buf.get_mut(encoded_len).ok_or(too_small)? = DELIMITER;
    // encoded_len < buf.len(): the delimiter's slot exists.
    Ok(encoded_len.wrapping_add(1))
}

/// Decodes one frame, with or without its final delimiter, in place; the
/// message borrows `frame`.
pub fn decode_frame(frame: &mut [u8]) -> Result<Message<'_>, Error> {
    let frame = match frame {
        [body @ .., DELIMITER] => body,
        body => body,
    };
    if frame.contains(&DELIMITER) {
        return Err(Error::FrameCobs);
    }
    let decoded_len = cobs::decode_in_place(frame).map_err(|_| Error::FrameCobs)?;
    let decoded = frame.get(..decoded_len).ok_or(Error::FrameCobs)?;
    let too_short = Error::FrameTooShort { len: decoded_len };
    let (message_bytes, crc) = decoded.split_last_chunk::<CRC_LEN>().ok_or(too_short)?;
    if message_bytes.is_empty() {
        return Err(too_short);
    }
    let stored = u32::from_le_bytes(*crc);
    let computed = CRC32.checksum(message_bytes);
    if stored != computed {
        return Err(Error::FrameCrcMismatch { stored, computed });
    }
    match postcard::take_from_bytes::<Message<'_>>(message_bytes) {
        Ok((message, [])) => {
            check_chunk(&message)?;
            Ok(message)
        }
        _ => Err(Error::FrameMessage),
    }
}

fn check_chunk(message: &Message<'_>) -> Result<(), Error> {
    match message {
        Message::ClipChunk { bytes, .. } if bytes.len() > MAX_CHUNK_LEN => {
            Err(Error::ChunkTooLong {
                len: bytes.len(),
                max: MAX_CHUNK_LEN,
            })
        }
        _ => Ok(()),
    }
}

/// Receives frames from a byte stream (a UART) into a fixed buffer of `CAP`
/// encoded bytes; `CAP = MAX_FRAME_LEN` holds every valid frame.
///
/// Each completed frame yields its message, borrowing the receiver until the
/// next byte is fed, or the error for which it was dropped. Corrupt frames are
/// counted and reception resumes after the next delimiter.
///
/// ```
/// use mocap_servo::stream::{encode_frame, FrameReceiver, Message, MAX_FRAME_LEN};
///
/// let mut wire = [0u8; MAX_FRAME_LEN];
/// let n = encode_frame(&Message::Play { loop_: true }, &mut wire).unwrap();
///
/// let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
/// let mut input = &wire[..n];
/// while !input.is_empty() {
///     let (frame, rest) = rx.feed(input);
///     if let Some(Ok(message)) = frame {
///         assert_eq!(message, Message::Play { loop_: true });
///     }
///     input = rest;
/// }
/// assert_eq!((rx.received(), rx.dropped()), (1, 0));
/// ```
#[derive(Debug, Clone)]
pub struct FrameReceiver<const CAP: usize> {
    buf: [u8; CAP],
    len: usize,
    overflowed: bool,
    received: u32,
    dropped: u32,
}

impl<const CAP: usize> Default for FrameReceiver<CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize> FrameReceiver<CAP> {
    /// An empty receiver (`const`, so it can live in a `static`).
    pub const fn new() -> Self {
        FrameReceiver {
            buf: [0; CAP],
            len: 0,
            overflowed: false,
            received: 0,
            dropped: 0,
        }
    }

    /// Frames accepted so far (wrapping).
    pub const fn received(&self) -> u32 {
        self.received
    }

    /// Frames dropped so far (wrapping).
    pub const fn dropped(&self) -> u32 {
        self.dropped
    }

    /// Forgets the frame in progress without counting it.
    pub fn reset(&mut self) {
        self.len = 0;
        self.overflowed = false;
    }

    /// Feeds one byte; a delimiter completes a frame.
    pub fn push(&mut self, byte: u8) -> Option<Result<Message<'_>, Error>> {
        if byte == DELIMITER {
            self.end_frame()
        } else {
            self.store(core::slice::from_ref(&byte));
            None
        }
    }

    /// Feeds bytes up to and including the first delimiter; returns what
    /// [`push`](Self::push) returned for the last of them and the bytes not
    /// consumed. Call it again with the rest until the rest is empty.
    pub fn feed<'i>(&mut self, input: &'i [u8]) -> (Option<Result<Message<'_>, Error>>, &'i [u8]) {
        match input.iter().position(|&b| b == DELIMITER) {
            None => {
                self.store(input);
                (None, &[])
            }
            Some(end) => {
                let (body, rest) = input.split_at(end);
                self.store(body);
                (self.end_frame(), rest.get(1..).unwrap_or_default())
            }
        }
    }

    fn store(&mut self, bytes: &[u8]) {
        let end = self.len.saturating_add(bytes.len());
        match self.buf.get_mut(self.len..end) {
            Some(slot) if !self.overflowed => {
                // Equal lengths (the slot is `bytes.len()` long); a zip
                // copy keeps copy_from_slice's length panic out.
                for (s, &b) in slot.iter_mut().zip(bytes) {
                    *s = b;
                }
                self.len = end;
            }
            _ => self.overflowed = true,
        }
    }

    fn end_frame(&mut self) -> Option<Result<Message<'_>, Error>> {
        let len = core::mem::take(&mut self.len);
        if core::mem::take(&mut self.overflowed) {
            self.dropped = self.dropped.wrapping_add(1);
            return Some(Err(Error::FrameOverflow { capacity: CAP }));
        }
        if len == 0 {
            return None;
        }
        let result = decode_frame(self.buf.get_mut(..len).unwrap_or_default());
        match result {
            Ok(_) => self.received = self.received.wrapping_add(1),
            Err(_) => self.dropped = self.dropped.wrapping_add(1),
        }
        Some(result)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(seq: u16, pulses: &[u16]) -> Message<'static> {
        Message::pose(seq, pulses).unwrap()
    }

    #[test]
    fn pose_refuses_more_servos_than_a_frame_carries() {
        assert_eq!(
            Message::pose(0, &[6000; MAX_POSE_SERVOS + 1]),
            Err(Error::TooManyServos {
                count: MAX_POSE_SERVOS + 1,
                max: MAX_POSE_SERVOS
            })
        );
    }

    fn every_message() -> [Message<'static>; 9] {
        static CLIP: [u8; MAX_CHUNK_LEN] = [0xA5; MAX_CHUNK_LEN];
        [
            Message::Hello {
                version: PROTOCOL_VERSION,
            },
            Message::ClipChunk {
                offset: 0,
                total: 1234,
                bytes: &CLIP[..10],
            },
            Message::ClipChunk {
                offset: u32::MAX,
                total: u32::MAX,
                bytes: &CLIP,
            },
            Message::Play { loop_: true },
            pose(7, &[6000, 0, u16::MAX]),
            pose(u16::MAX, &[u16::MAX; MAX_POSE_SERVOS]),
            Message::Stop,
            Message::Status {
                received: 100_000,
                dropped: 3,
                last_seq: 65_535,
                state: 2,
                chunks: 22,
            },
            Message::Status {
                received: u32::MAX,
                dropped: u32::MAX,
                last_seq: u16::MAX,
                state: u8::MAX,
                chunks: u32::MAX,
            },
        ]
    }

    fn round_trip(message: &Message<'_>) -> usize {
        let mut wire = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(message, &mut wire).unwrap();
        assert_eq!(wire[n - 1], DELIMITER);
        assert!(!wire[..n - 1].contains(&DELIMITER));
        let mut copy = wire;
        assert_eq!(&decode_frame(&mut copy[..n]).unwrap(), message);
        let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
        let (last, body) = wire[..n].split_last().unwrap();
        for &byte in body {
            assert!(rx.push(byte).is_none());
        }
        assert_eq!(&rx.push(*last).unwrap().unwrap(), message);
        n
    }

    #[test]
    fn every_message_round_trips() {
        for message in &every_message() {
            round_trip(message);
        }
    }

    #[test]
    fn max_lengths_are_exact() {
        let longest = every_message().iter().map(round_trip).max().unwrap();
        assert_eq!(longest, MAX_FRAME_LEN);
        let mut payload = [0u8; 2 * MAX_MESSAGE_LEN];
        let worst = pose(u16::MAX, &[u16::MAX; MAX_POSE_SERVOS]);
        assert_eq!(
            postcard::to_slice(&worst, &mut payload).unwrap().len(),
            MAX_MESSAGE_LEN
        );
        assert_eq!(MAX_FRAME_LEN, 107);
        // The longest Status (every varint at its widest) is far shorter.
        let status = Message::Status {
            received: u32::MAX,
            dropped: u32::MAX,
            last_seq: u16::MAX,
            state: u8::MAX,
            chunks: u32::MAX,
        };
        assert_eq!(postcard::to_slice(&status, &mut payload).unwrap().len(), 20);
        let mut wire = [0u8; MAX_FRAME_LEN];
        assert_eq!(encode_frame(&status, &mut wire), Ok(26));
    }

    #[test]
    fn encode_errors_are_typed() {
        let big = [1u8; MAX_CHUNK_LEN + 1];
        let chunk = Message::ClipChunk {
            offset: 0,
            total: 65,
            bytes: &big,
        };
        let mut wire = [0u8; 2 * MAX_FRAME_LEN];
        assert_eq!(
            encode_frame(&chunk, &mut wire),
            Err(Error::ChunkTooLong { len: 65, max: 64 })
        );
        assert_eq!(
            encode_frame(&Message::Stop, &mut wire[..6]),
            Err(Error::BufferTooSmall {
                needed: 7,
                available: 6
            })
        );
    }

    #[test]
    fn corrupt_frames_are_dropped_with_their_reason() {
        let mut wire = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&pose(9, &[6000, 6100]), &mut wire).unwrap();

        let mut flipped = wire;
        flipped[3] ^= 0x10;
        assert!(matches!(
            decode_frame(&mut flipped[..n]),
            Err(Error::FrameCrcMismatch { .. })
        ));
        // COBS of [1, 2, 3]: too short for a CRC; of four bytes: no message before the CRC.
        assert_eq!(
            decode_frame(&mut [4, 1, 2, 3]),
            Err(Error::FrameTooShort { len: 3 })
        );
        assert_eq!(
            decode_frame(&mut [5, 1, 2, 3, 4, 0]),
            Err(Error::FrameTooShort { len: 4 })
        );
        let mut bad_cobs = wire;
        bad_cobs[0] = 0xFE;
        assert_eq!(decode_frame(&mut bad_cobs[..n]), Err(Error::FrameCobs));
        assert_eq!(
            decode_frame(&mut [0x01, 0x02, 0x00, 0x00]),
            Err(Error::FrameCobs)
        );

        // A valid CRC over bytes that are not one message.
        let mut trailing = [0u8; 16];
        let body = [0x04, 0x04]; // Stop, then a stray byte
        trailing[..2].copy_from_slice(&body);
        trailing[2..6].copy_from_slice(&CRC32.checksum(&body).to_le_bytes());
        let mut framed = [0u8; 16];
        let m = cobs::try_encode(&trailing[..6], &mut framed).unwrap();
        assert_eq!(decode_frame(&mut framed[..m]), Err(Error::FrameMessage));
    }

    #[test]
    fn receiver_resynchronises_and_counts() {
        let mut wire = [0u8; 3 * MAX_FRAME_LEN];
        let a = encode_frame(&pose(1, &[6000]), &mut wire).unwrap();
        let b = encode_frame(&pose(2, &[6001]), &mut wire[a..]).unwrap();
        let c = encode_frame(&pose(3, &[6002]), &mut wire[a + b..]).unwrap();
        wire[a + 2] ^= 0x40; // damage frame 2
        let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
        let mut seqs = [0u16; 2];
        let mut got = 0;
        let mut input = &wire[1..a + b + c]; // join mid-frame 1
        while !input.is_empty() {
            let (frame, rest) = rx.feed(input);
            if let Some(Ok(Message::Pose { seq, .. })) = frame {
                seqs[got] = seq;
                got += 1;
            }
            input = rest;
        }
        assert_eq!(&seqs[..got], &[3]);
        assert_eq!((rx.received(), rx.dropped()), (1, 2));
    }

    #[test]
    fn overflow_drops_one_frame_and_empty_frames_are_ignored() {
        let mut wire = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&pose(5, &[6000; 20]), &mut wire).unwrap();
        let mut small = FrameReceiver::<16>::new();
        for &byte in &wire[..n - 1] {
            assert!(small.push(byte).is_none());
        }
        assert_eq!(
            small.push(0),
            Some(Err(Error::FrameOverflow { capacity: 16 }))
        );
        assert_eq!(small.push(0), None);
        let (frame, rest) = small.feed(&[0, 0, 0]);
        assert!(frame.is_none());
        assert_eq!(rest.len(), 2);
        assert_eq!((small.received(), small.dropped()), (0, 1));

        let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
        let mut input = &wire[..n];
        let mut delivered = 0;
        while !input.is_empty() {
            // Feed in 5-byte pieces, as a UART interrupt would.
            let (piece, later) = input.split_at(input.len().min(5));
            let mut piece = piece;
            while !piece.is_empty() {
                let (frame, rest) = rx.feed(piece);
                delivered += usize::from(matches!(frame, Some(Ok(_))));
                piece = rest;
            }
            input = later;
        }
        assert_eq!(delivered, 1);
    }
}
