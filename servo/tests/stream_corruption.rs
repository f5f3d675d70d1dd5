//! A long stream of `Pose` frames through a noisy serial line.
//!
//! `cargo test -p mocap-servo --test stream_corruption -- --nocapture` prints
//! the figures (frames sent, delivered, dropped; resynchronisation distance).

// A test: the crate's panic-free lints (Cargo.toml) do not apply here.
#![allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::arithmetic_side_effects
)]

use mocap_servo::stream::{encode_frame, FrameReceiver, Message, MAX_FRAME_LEN};

const FRAMES: usize = 20_000;
const SERVOS: usize = 16;
/// One byte in `CORRUPT_ONE_IN` is hit by a random non-zero XOR.
const CORRUPT_ONE_IN: u32 = 100;

/// SplitMix64: deterministic, dependency-free.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: u32) -> u32 {
        ((self.next_u64() >> 32) % u64::from(n)) as u32
    }
}

struct Sent {
    message: Message<'static>,
    /// Byte range of the frame in the stream, delimiter included.
    start: usize,
    end: usize,
}

/// Encodes `FRAMES` poses of slowly moving servos into one byte stream.
fn clean_stream(rng: &mut Rng) -> (Vec<u8>, Vec<Sent>) {
    let mut stream = Vec::new();
    let mut sent = Vec::new();
    let mut pulses = [6000u16; SERVOS];
    for seq in 0..FRAMES {
        for pulse in &mut pulses {
            *pulse = (i32::from(*pulse) + rng.below(81) as i32 - 40).clamp(4000, 8000) as u16;
        }
        let message = Message::Pose {
            seq: seq as u16,
            pulses: heapless::Vec::from_slice(&pulses).unwrap(),
        };
        let mut frame = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&message, &mut frame).unwrap();
        let start = stream.len();
        stream.extend_from_slice(&frame[..n]);
        sent.push(Sent {
            message,
            start,
            end: stream.len(),
        });
    }
    (stream, sent)
}

/// A delivered message, and whether it is the sent frame that ends at the same offset.
struct Delivered {
    seq: u16,
    matches_sent: bool,
}

fn receive_by_slices(stream: &[u8], sent: &[Sent], rng: &mut Rng) -> (Vec<Delivered>, u32, u32) {
    let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
    let mut delivered = Vec::new();
    let mut offset = 0;
    while offset < stream.len() {
        // Uneven pieces, as a UART interrupt or DMA half-buffer would hand them over.
        let piece_len = (1 + rng.below(64) as usize).min(stream.len() - offset);
        let mut piece = &stream[offset..offset + piece_len];
        while !piece.is_empty() {
            let (frame, rest) = rx.feed(piece);
            offset += piece.len() - rest.len();
            if let Some(Ok(message)) = frame {
                delivered.push(check(&message, offset, sent));
            }
            piece = rest;
        }
    }
    (delivered, rx.received(), rx.dropped())
}

fn receive_by_bytes(stream: &[u8], sent: &[Sent]) -> (Vec<Delivered>, u32, u32) {
    let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
    let mut delivered = Vec::new();
    for (offset, &byte) in stream.iter().enumerate() {
        if let Some(Ok(message)) = rx.push(byte) {
            delivered.push(check(&message, offset + 1, sent));
        }
    }
    (delivered, rx.received(), rx.dropped())
}

fn check(message: &Message<'_>, end: usize, sent: &[Sent]) -> Delivered {
    let Message::Pose { seq, .. } = message else {
        return Delivered {
            seq: u16::MAX,
            matches_sent: false,
        };
    };
    let original = &sent[usize::from(*seq)];
    Delivered {
        seq: *seq,
        matches_sent: original.message == *message && original.end == end,
    }
}

#[test]
fn one_percent_corruption_drops_only_damaged_frames_and_resyncs() {
    let mut rng = Rng(0x5e70_c0b5);
    let (mut stream, sent) = clean_stream(&mut rng);

    let mut corrupted = Vec::new();
    for (offset, byte) in stream.iter_mut().enumerate() {
        if rng.below(CORRUPT_ONE_IN) == 0 {
            *byte ^= 1 + rng.below(255) as u8;
            corrupted.push(offset);
        }
    }

    let (delivered, received, dropped) = receive_by_slices(&stream, &sent, &mut rng);
    let (by_bytes, received_b, dropped_b) = receive_by_bytes(&stream, &sent);

    // No false accepts: every delivered frame is a sent frame, at its place.
    assert!(delivered.iter().all(|d| d.matches_sent));
    // Exactly the frames whose bytes and leading delimiter were untouched arrive.
    let is_hit = |range: std::ops::Range<usize>| {
        let first = corrupted.partition_point(|&c| c < range.start);
        corrupted.get(first).is_some_and(|&c| c < range.end)
    };
    let intact: Vec<u16> = sent
        .iter()
        .filter(|s| !is_hit(s.start.saturating_sub(1)..s.end))
        .map(|s| match s.message {
            Message::Pose { seq, .. } => seq,
            _ => unreachable!(),
        })
        .collect();
    let delivered_seqs: Vec<u16> = delivered.iter().map(|d| d.seq).collect();
    assert_eq!(delivered_seqs, intact);
    // Feeding byte by byte or in slices makes no difference.
    assert_eq!(
        by_bytes.iter().map(|d| d.seq).collect::<Vec<_>>(),
        delivered_seqs
    );
    assert_eq!((received_b, dropped_b), (received, dropped));
    assert_eq!(received as usize, delivered.len());

    // Resync distance: from each corrupted byte to the first byte of the next
    // frame delivered intact.
    let starts: Vec<usize> = delivered
        .iter()
        .map(|d| sent[usize::from(d.seq)].start)
        .collect();
    let distances: Vec<usize> = corrupted
        .iter()
        .filter_map(|&c| {
            let next = starts.partition_point(|&s| s <= c);
            starts.get(next).map(|&s| s - c)
        })
        .collect();
    let mean = distances.iter().sum::<usize>() as f64 / distances.len() as f64;
    let max = distances.iter().copied().max().unwrap_or(0);
    // Back in step: from each corrupted byte to the next sent delimiter that
    // survived, where the receiver starts a clean frame whatever follows.
    let ends: Vec<usize> = sent
        .iter()
        .map(|s| s.end)
        .filter(|&end| corrupted.binary_search(&(end - 1)).is_err())
        .collect();
    let in_step: Vec<usize> = corrupted
        .iter()
        .filter_map(|&c| ends.get(ends.partition_point(|&e| e <= c)).map(|&e| e - c))
        .collect();
    let in_step_mean = in_step.iter().sum::<usize>() as f64 / in_step.len() as f64;
    let in_step_max = in_step.iter().copied().max().unwrap_or(0);
    let frame_bytes = stream.len() as f64 / FRAMES as f64;

    println!(
        "stream: {FRAMES} Pose frames of {SERVOS} servos, {} bytes ({frame_bytes:.1} per frame), \
         {} bytes corrupted ({:.2} %)",
        stream.len(),
        corrupted.len(),
        100.0 * corrupted.len() as f64 / stream.len() as f64
    );
    println!(
        "frames: sent {FRAMES}, delivered {received} ({:.1} %), dropped {dropped} (corrupt frames \
         counted by the receiver), lost {} sent frames, false accepts 0",
        100.0 * f64::from(received) / FRAMES as f64,
        FRAMES - received as usize
    );
    println!(
        "resync: bytes from a corrupted byte to the next good frame: mean {mean:.1}, max {max}; \
         to the next surviving delimiter (receiver back in step): mean {in_step_mean:.1}, max {in_step_max}"
    );

    // Sanity of the figures themselves.
    assert!(received as usize > FRAMES / 2);
    assert!(dropped > 0);
    assert!(max < 8 * MAX_FRAME_LEN);
}

#[test]
fn random_noise_is_never_accepted() {
    let mut rng = Rng(0x0000_5eed);
    let noise: Vec<u8> = (0..1_000_000).map(|_| rng.next_u64() as u8).collect();
    let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
    for &byte in &noise {
        assert!(!matches!(rx.push(byte), Some(Ok(_))));
    }
    println!(
        "noise: 1 000 000 random bytes -> {} frames dropped, 0 accepted",
        rx.dropped()
    );
    assert_eq!(rx.received(), 0);
    assert!(rx.dropped() > 1000);
}
