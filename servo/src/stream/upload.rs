//! The receiving rule of a clip upload in `ClipChunk`s (SPEC.md §8.1), in one place: the
//! firmware's streaming mode runs it, and the host's tests and measurements run the same code
//! on the bytes they feed the firmware.
//!
//! A clip of `total` bytes is cut into chunks of [`CHUNK_LEN`] bytes: chunk `i` holds bytes
//! `64 i .. min(64 (i + 1), total)` and is sent as `ClipChunk { offset: 64 i, total, bytes }`.
//! A sender may send them in any order and any number of times — over a one-way lossy link it
//! repeats the whole sequence (a carousel, `mocap send --passes N`) — and the receiver keeps
//! one bit per chunk of what it has:
//!
//! - The first chunk accepted (after [`Upload::new`] or [`Upload::reset`]) fixes `total`.
//! - A chunk is accepted if `total` is not 0, fits the receiver's buffer and bitmap, equals
//!   the upload's `total` (once fixed), `offset` is a multiple of 64 below `total`, and
//!   `bytes` is exactly the chunk's length (64, or `total − offset` for the last chunk).
//! - A chunk already received is a duplicate: accepted, nothing changes (not even the bytes;
//!   the frame's CRC-32 vouches that they are the same).
//! - Anything else is [`Rejected`] and changes nothing.
//! - A `Play` ([`Upload::play`]) starts the clip if every chunk has arrived; if the upload is
//!   still incomplete, the `Play` is remembered ("armed") and the clip starts as soon as the
//!   chunk that completes it arrives ([`Upload::take_armed`]); with no upload it is refused.
//!   Whether the complete clip is valid (`Clip::parse`, its CRC, the rig) is the caller's
//!   check, which should [`reset`](Upload::reset) an upload it refuses.
//!
//! The buffer is the caller's (the firmware's RAM buffer); pass the same one every time. The
//! bitmap has `32 × WORDS` bits: [`bitmap_words`] gives `WORDS` for a buffer. No allocation,
//! no panic on any input.
//!
//! ```
//! use mocap_servo::stream::upload::{bitmap_words, Accepted, Play, Upload};
//!
//! const BUFFER: usize = 1024;
//! let clip: Vec<u8> = (0..150u8).collect(); // three chunks: 64, 64, 22 bytes
//! let mut buffer = [0u8; BUFFER];
//! let mut upload = Upload::<{ bitmap_words(BUFFER) }>::new();
//! let total = clip.len() as u32;
//! // The last chunk first, then a Play (armed), then the first chunk twice.
//! assert_eq!(upload.accept(&mut buffer, 128, total, &clip[128..]), Ok(Accepted::New));
//! assert_eq!(upload.play(false), Play::Armed);
//! assert_eq!(upload.accept(&mut buffer, 0, total, &clip[..64]), Ok(Accepted::New));
//! assert_eq!(upload.accept(&mut buffer, 0, total, &clip[..64]), Ok(Accepted::Duplicate));
//! assert_eq!(upload.take_armed(), None); // chunk 1 is still missing
//! assert_eq!(upload.accept(&mut buffer, 64, total, &clip[64..128]), Ok(Accepted::New));
//! assert_eq!(upload.take_armed(), Some(false)); // complete: start now
//! assert_eq!(upload.complete(&buffer), Some(&clip[..]));
//! ```

use super::MAX_CHUNK_LEN;

/// Bytes of every chunk but the last; chunk `i` starts at `CHUNK_LEN × i`.
pub const CHUNK_LEN: usize = MAX_CHUNK_LEN;

/// Words of the bitmap of an upload into a buffer of `buffer_bytes` (one bit per chunk).
pub const fn bitmap_words(buffer_bytes: usize) -> usize {
    buffer_bytes.div_ceil(CHUNK_LEN * 32)
}

/// How a chunk was taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Accepted {
    /// A chunk not received before, copied into the buffer.
    New,
    /// A chunk already received: nothing changed.
    Duplicate,
}

/// Why a chunk was ignored (nothing changed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Rejected {
    /// `total` is 0.
    EmptyClip,
    /// `total` is larger than the buffer or the bitmap.
    TooLarge {
        /// The chunk's `total`.
        total: u32,
        /// The most this receiver takes.
        capacity: usize,
    },
    /// `total` differs from the upload's.
    OtherClip {
        /// The chunk's `total`.
        total: u32,
        /// The upload's.
        expected: u32,
    },
    /// `offset` is not a multiple of [`CHUNK_LEN`].
    Misaligned {
        /// The chunk's `offset`.
        offset: u32,
    },
    /// `offset` is not below `total`.
    PastEnd {
        /// The chunk's `offset`.
        offset: u32,
        /// The chunk's `total`.
        total: u32,
    },
    /// `bytes` is not the chunk's length.
    WrongLength {
        /// Bytes in the chunk.
        len: usize,
        /// The chunk's length: 64, or `total − offset` for the last.
        expected: usize,
    },
    /// A chunk not received yet, checked with [`Upload::check`] (nothing may be written).
    NotWritable,
}

/// What a `Play` does ([`Upload::play`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Play {
    /// Every chunk has arrived: start the clip now.
    Start,
    /// The upload is incomplete: the `Play` is remembered until it completes.
    Armed,
    /// No upload: nothing to play.
    NoUpload,
}

/// An upload in progress: its `total`, the chunks received (a bitmap of `32 × WORDS` chunks)
/// and an armed `Play`. See the [module](self) for the rule.
#[derive(Debug, Clone)]
pub struct Upload<const WORDS: usize> {
    /// Bytes of the clip (0: no upload).
    total: u32,
    /// Distinct chunks received.
    received: u32,
    /// Bit `i % 32` of word `i / 32`: chunk `i` received.
    bitmap: [u32; WORDS],
    /// A `Play` that came before the last chunk: its `loop_`.
    armed: Option<bool>,
}

impl<const WORDS: usize> Default for Upload<WORDS> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const WORDS: usize> Upload<WORDS> {
    /// No upload.
    pub const fn new() -> Self {
        Upload {
            total: 0,
            received: 0,
            bitmap: [0; WORDS],
            armed: None,
        }
    }

    /// Forgets the upload and an armed `Play` (`Hello`; a refused clip).
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// The largest clip taken into `buffer`.
    pub const fn capacity(buffer_len: usize) -> usize {
        let bits = WORDS.saturating_mul(32).saturating_mul(CHUNK_LEN);
        if buffer_len < bits {
            buffer_len
        } else {
            bits
        }
    }

    /// Bytes of the clip (0: no upload).
    pub const fn total(&self) -> u32 {
        self.total
    }

    /// Distinct chunks received.
    pub const fn received(&self) -> u32 {
        self.received
    }

    /// Chunks of the whole clip (0: no upload).
    pub const fn chunks(&self) -> u32 {
        self.total.div_ceil(CHUNK_LEN as u32)
    }

    /// Every chunk has arrived.
    pub const fn is_complete(&self) -> bool {
        self.total > 0 && self.received == self.chunks()
    }

    /// The armed `Play`'s `loop_`, if any.
    pub const fn armed(&self) -> Option<bool> {
        self.armed
    }

    /// Whether chunk `index` has arrived.
    pub fn has_chunk(&self, index: u32) -> bool {
        let word = self.bitmap.get((index / 32) as usize).copied().unwrap_or(0);
        index < self.chunks() && word & (1 << (index % 32)) != 0
    }

    /// Checks a chunk against the rule without taking it (for a buffer that cannot be written,
    /// e.g. while the clip in it plays): `Duplicate` if it has arrived, else the reason it
    /// would be rejected, or [`Rejected::NotWritable`].
    pub fn check(
        &self,
        buffer_len: usize,
        offset: u32,
        total: u32,
        len: usize,
    ) -> Result<Accepted, Rejected> {
        let index = self.index(buffer_len, offset, total, len)?;
        if self.has_chunk(index) {
            Ok(Accepted::Duplicate)
        } else {
            Err(Rejected::NotWritable)
        }
    }

    /// Takes a chunk: copies it into `buffer` if it is new, or says why it was ignored.
    pub fn accept(
        &mut self,
        buffer: &mut [u8],
        offset: u32,
        total: u32,
        bytes: &[u8],
    ) -> Result<Accepted, Rejected> {
        let index = self.index(buffer.len(), offset, total, bytes.len())?;
        if self.has_chunk(index) {
            return Ok(Accepted::Duplicate);
        }
        let start = offset as usize;
        let too_large = Rejected::TooLarge {
            total,
            capacity: Self::capacity(buffer.len()),
        };
        let end = start.checked_add(bytes.len()).ok_or(too_large)?;
        let slot = buffer.get_mut(start..end).ok_or(too_large)?;
        let word = self
            .bitmap
            .get_mut((index / 32) as usize)
            .ok_or(too_large)?;
        slot.copy_from_slice(bytes);
        *word |= 1 << (index % 32);
        self.total = total;
        self.received = self.received.saturating_add(1);
        Ok(Accepted::New)
    }

    /// A `Play { loop_ }`: [`Play::Start`] if the upload is complete, [`Play::Armed`] (and
    /// remembered, the last `loop_` winning) if it is in progress, else [`Play::NoUpload`].
    pub fn play(&mut self, looped: bool) -> Play {
        if self.is_complete() {
            self.armed = None;
            Play::Start
        } else if self.total > 0 {
            self.armed = Some(looped);
            Play::Armed
        } else {
            Play::NoUpload
        }
    }

    /// After a new chunk: the armed `Play`'s `loop_` if the upload is now complete (the
    /// `Play` is then used up).
    pub fn take_armed(&mut self) -> Option<bool> {
        if self.is_complete() {
            self.armed.take()
        } else {
            None
        }
    }

    /// Forgets an armed `Play` (`Pose`, `Stop`), keeping the upload.
    pub fn disarm(&mut self) {
        self.armed = None;
    }

    /// The clip, once every chunk has arrived.
    pub fn complete<'b>(&self, buffer: &'b [u8]) -> Option<&'b [u8]> {
        if self.is_complete() {
            buffer.get(..self.total as usize)
        } else {
            None
        }
    }

    /// The chunk's index if it obeys the rule.
    fn index(
        &self,
        buffer_len: usize,
        offset: u32,
        total: u32,
        len: usize,
    ) -> Result<u32, Rejected> {
        if total == 0 {
            return Err(Rejected::EmptyClip);
        }
        if self.total != 0 && total != self.total {
            return Err(Rejected::OtherClip {
                total,
                expected: self.total,
            });
        }
        let capacity = Self::capacity(buffer_len);
        if total as usize > capacity {
            return Err(Rejected::TooLarge { total, capacity });
        }
        if !(offset as usize).is_multiple_of(CHUNK_LEN) {
            return Err(Rejected::Misaligned { offset });
        }
        if offset >= total {
            return Err(Rejected::PastEnd { offset, total });
        }
        // offset < total (checked above).
        let expected = (total.wrapping_sub(offset) as usize).min(CHUNK_LEN);
        if len != expected {
            return Err(Rejected::WrongLength { len, expected });
        }
        const CHUNK_LEN_U32: u32 = CHUNK_LEN as u32;
        Ok(offset / CHUNK_LEN_U32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::TestRng;

    const BUFFER: usize = 6 * 1024;
    type Up = Upload<{ bitmap_words(BUFFER) }>;

    fn clip(len: usize) -> [u8; BUFFER] {
        let mut c = [0u8; BUFFER];
        for (i, b) in c.iter_mut().take(len).enumerate() {
            *b = (i * 7 + 3) as u8;
        }
        c
    }

    fn chunk(c: &[u8], total: usize, i: usize) -> (u32, &[u8]) {
        let start = i * CHUNK_LEN;
        ((start) as u32, &c[start..total.min(start + CHUNK_LEN)])
    }

    #[test]
    fn bitmap_covers_every_board_buffer() {
        assert_eq!(bitmap_words(6 * 1024), 3);
        assert_eq!(bitmap_words(32 * 1024), 16);
        assert_eq!(bitmap_words(64 * 1024), 32);
        assert_eq!(bitmap_words(65), 1);
        assert_eq!(Up::capacity(BUFFER), BUFFER);
        assert_eq!(Upload::<1>::capacity(BUFFER), 2048);
    }

    #[test]
    fn chunks_in_any_order_with_duplicates_complete_the_clip() {
        let total = 1383; // the demo servo clip: 22 chunks, the last of 39 bytes
        let c = clip(total);
        let n = total.div_ceil(CHUNK_LEN);
        let mut rng = TestRng::new(7);
        for round in 0..50 {
            let mut buffer = [0u8; BUFFER];
            let mut up = Up::new();
            // A random order, each chunk one to three times, interleaved.
            let mut order: [usize; 66] = core::array::from_fn(|k| k % n);
            let copies = 22 + (round % 45);
            for k in (1..copies).rev() {
                order.swap(k, (rng.next_u32() as usize) % (k + 1));
            }
            let mut new = 0;
            for &i in &order[..copies] {
                let (offset, bytes) = chunk(&c, total, i);
                let before = up.has_chunk(i as u32);
                let got = up.accept(&mut buffer, offset, total as u32, bytes).unwrap();
                assert_eq!(got == Accepted::Duplicate, before);
                new += usize::from(got == Accepted::New);
                assert_eq!(up.received() as usize, new);
            }
            // Whatever was missing, in order.
            for i in 0..n {
                let (offset, bytes) = chunk(&c, total, i);
                up.accept(&mut buffer, offset, total as u32, bytes).unwrap();
            }
            assert!(up.is_complete());
            assert_eq!(up.complete(&buffer), Some(&c[..total]));
            assert_eq!(up.chunks() as usize, n);
        }
    }

    #[test]
    fn inconsistent_chunks_are_rejected_and_change_nothing() {
        let total = 200u32; // chunks of 64, 64, 64, 8
        let c = clip(200);
        let mut buffer = [0u8; BUFFER];
        let mut up = Up::new();
        let r = |up: &mut Up, buffer: &mut [u8], offset: u32, total: u32, len: usize| {
            up.accept(buffer, offset, total, &c[..len])
        };
        assert_eq!(r(&mut up, &mut buffer, 0, 0, 0), Err(Rejected::EmptyClip));
        assert_eq!(
            r(&mut up, &mut buffer, 0, BUFFER as u32 + 1, 64),
            Err(Rejected::TooLarge {
                total: BUFFER as u32 + 1,
                capacity: BUFFER
            })
        );
        assert_eq!(up.total(), 0, "a rejected chunk does not fix total");
        assert_eq!(
            r(&mut up, &mut buffer, 32, total, 64),
            Err(Rejected::Misaligned { offset: 32 })
        );
        assert_eq!(
            r(&mut up, &mut buffer, 256, total, 8),
            Err(Rejected::PastEnd { offset: 256, total })
        );
        assert_eq!(
            r(&mut up, &mut buffer, 64, total, 63),
            Err(Rejected::WrongLength {
                len: 63,
                expected: 64
            })
        );
        assert_eq!(
            r(&mut up, &mut buffer, 192, total, 64),
            Err(Rejected::WrongLength {
                len: 64,
                expected: 8
            })
        );
        assert_eq!(buffer, [0u8; BUFFER]);
        assert_eq!(up.play(true), Play::NoUpload);
        // The last chunk first fixes total; another total is then another clip.
        assert_eq!(r(&mut up, &mut buffer, 192, total, 8), Ok(Accepted::New));
        assert_eq!(up.total(), total);
        assert_eq!(
            r(&mut up, &mut buffer, 0, 300, 64),
            Err(Rejected::OtherClip {
                total: 300,
                expected: total
            })
        );
        assert_eq!(up.received(), 1);
        assert_eq!(&buffer[..192], &[0u8; 192]);
        // Hello: forget it; a new clip may start.
        up.reset();
        assert_eq!(r(&mut up, &mut buffer, 0, 300, 64), Ok(Accepted::New));
        assert_eq!((up.total(), up.received(), up.chunks()), (300, 1, 5));
    }

    #[test]
    fn play_is_armed_until_the_upload_completes() {
        let total = 130usize; // 64, 64, 2
        let c = clip(total);
        let mut buffer = [0u8; BUFFER];
        let mut up = Up::new();
        assert_eq!(up.play(false), Play::NoUpload);
        assert_eq!(up.armed(), None);
        let (o, b) = chunk(&c, total, 1);
        up.accept(&mut buffer, o, total as u32, b).unwrap();
        assert_eq!(up.play(false), Play::Armed);
        assert_eq!(up.play(true), Play::Armed, "the last loop_ wins");
        assert_eq!(up.take_armed(), None);
        let (o, b) = chunk(&c, total, 2);
        up.accept(&mut buffer, o, total as u32, b).unwrap();
        assert_eq!(up.take_armed(), None);
        // A Pose forgets the armed Play; a later Play arms again.
        up.disarm();
        assert_eq!(up.armed(), None);
        assert_eq!(up.play(false), Play::Armed);
        let (o, b) = chunk(&c, total, 0);
        up.accept(&mut buffer, o, total as u32, b).unwrap();
        assert_eq!(up.take_armed(), Some(false));
        assert_eq!(up.take_armed(), None, "used up");
        assert_eq!(up.play(true), Play::Start);
        assert_eq!(up.armed(), None);
        // While the clip plays: chunks are checked, never written.
        assert_eq!(
            up.check(BUFFER, o, total as u32, b.len()),
            Ok(Accepted::Duplicate)
        );
        assert_eq!(
            up.check(BUFFER, 0, 99, 64),
            Err(Rejected::OtherClip {
                total: 99,
                expected: 130
            })
        );
        let fresh = Up::new();
        assert_eq!(fresh.check(BUFFER, 0, 130, 64), Err(Rejected::NotWritable));
    }

    #[test]
    fn the_bitmap_bounds_the_clip_as_the_buffer_does() {
        // One word: 32 chunks, 2 KB, even with a larger buffer.
        let mut buffer = [0u8; BUFFER];
        let mut up = Upload::<1>::new();
        let c = clip(BUFFER);
        assert!(matches!(
            up.accept(&mut buffer, 0, 2049, &c[..64]),
            Err(Rejected::TooLarge { capacity: 2048, .. })
        ));
        for i in 0..32 {
            let (o, b) = chunk(&c, 2048, i);
            assert_eq!(up.accept(&mut buffer, o, 2048, b), Ok(Accepted::New));
        }
        assert!(up.is_complete());
        // A buffer shorter than the bitmap.
        let mut small = [0u8; 100];
        let mut up = Up::new();
        assert!(matches!(
            up.accept(&mut small, 0, 101, &c[..64]),
            Err(Rejected::TooLarge { capacity: 100, .. })
        ));
        assert_eq!(up.accept(&mut small, 64, 100, &c[..36]), Ok(Accepted::New));
    }

    #[test]
    fn random_chunks_never_panic_nor_write_outside_the_rule() {
        let mut rng = TestRng::new(0x5EED);
        let data = [0xA5u8; 80];
        for _ in 0..20_000 {
            let mut buffer = [0u8; 300];
            let mut up = Upload::<1>::new();
            for _ in 0..8 {
                let pick = |rng: &mut TestRng, a: u32| match rng.next_u32() % 4 {
                    0 => rng.next_u32(),
                    1 => a,
                    _ => rng.next_u32() % 400,
                };
                let total = pick(&mut rng, 300);
                let offset = pick(&mut rng, 64) & !(rng.next_u32() % 2 * 63);
                let len = (rng.next_u32() % 81) as usize;
                let before = up.clone();
                match up.accept(&mut buffer, offset, total, &data[..len]) {
                    Ok(Accepted::New) => {
                        assert!((offset as usize).is_multiple_of(64) && offset < total);
                        assert!(total as usize <= 300 && len <= 64);
                        assert_eq!(up.received(), before.received() + 1);
                    }
                    _ => assert_eq!(up.received(), before.received()),
                }
                let _ = up.play(rng.next_u32().is_multiple_of(2));
                let _ = up.take_armed();
                assert!(up.received() <= up.chunks());
            }
        }
    }
}
