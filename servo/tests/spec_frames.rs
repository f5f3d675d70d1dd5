//! Every stream frame example of SPEC.md §8 (```` ```text spec-frame=NAME
//! message=… field=… ```` blocks) is read out of SPEC.md and checked:
//! `encode_frame` writes exactly its bytes, `decode_frame` and a
//! `FrameReceiver` fed byte by byte give the message back, and — with a COBS
//! decoder and the CRC written here from §8's prose — the frame is
//! `COBS(message crc) 00` with the CRC of the message.

// A test: the crate's panic-free lints (Cargo.toml) do not apply here.
#![allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::arithmetic_side_effects
)]

use mocap_servo::stream::{decode_frame, encode_frame, FrameReceiver, Message, MAX_FRAME_LEN};

const SPEC: &str = include_str!("../../SPEC.md");

struct Example {
    name: String,
    /// `message=` and the fields, in the order written.
    fields: Vec<(String, String)>,
    bytes: Vec<u8>,
}

fn examples() -> Vec<Example> {
    let mut out = Vec::new();
    let mut lines = SPEC.lines();
    while let Some(line) = lines.next() {
        let Some(attrs) = line.strip_prefix("```text spec-frame=") else {
            continue;
        };
        let mut parts = attrs.split_whitespace();
        let name = parts
            .next()
            .expect("a frame example has a name")
            .to_string();
        let fields = parts
            .map(|p| {
                let (k, v) = p.split_once('=').expect("attributes are key=value");
                (k.to_string(), v.to_string())
            })
            .collect();
        let mut bytes = Vec::new();
        for l in lines.by_ref().take_while(|l| !l.starts_with("```")) {
            // Hex pairs, then (after two or more spaces) a comment.
            for tok in l.split("  ").next().unwrap_or("").split_whitespace() {
                assert_eq!(tok.len(), 2, "{name}: bad hex token {tok:?} in {l:?}");
                bytes.push(u8::from_str_radix(tok, 16).expect("hex byte"));
            }
        }
        out.push(Example {
            name,
            fields,
            bytes,
        });
    }
    out
}

impl Example {
    fn field(&self, key: &str) -> &str {
        self.fields
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
            .unwrap_or_else(|| panic!("{}: no attribute {key}=", self.name))
    }

    fn num<T: std::str::FromStr>(&self, key: &str) -> T
    where
        T::Err: std::fmt::Debug,
    {
        self.field(key).parse().expect("a number")
    }

    /// The message the attributes name. `bytes` is where a `ClipChunk`'s
    /// bytes live.
    fn message<'a>(&self, bytes: &'a mut Vec<u8>) -> Message<'a> {
        match self.field("message") {
            "Hello" => Message::Hello {
                version: self.num("version"),
            },
            "ClipChunk" => {
                *bytes = self
                    .field("bytes")
                    .split(',')
                    .map(|b| u8::from_str_radix(b, 16).expect("hex byte"))
                    .collect();
                Message::ClipChunk {
                    offset: self.num("offset"),
                    total: self.num("total"),
                    bytes,
                }
            }
            "Play" => Message::Play {
                loop_: self.num("loop"),
            },
            "Pose" => {
                let pulses: Vec<u16> = self
                    .field("pulses")
                    .split(',')
                    .map(|p| p.parse().expect("a pulse"))
                    .collect();
                Message::pose(self.num("seq"), &pulses).expect("a pose that fits")
            }
            "Stop" => Message::Stop,
            "Show" => Message::Show {
                at_ms: self.num("at_ms"),
                op: self.num("op"),
                arg: self.num("arg"),
                ms: self.num("ms"),
            },
            "Timecode" => Message::Timecode {
                show_ms: self.num("show_ms"),
            },
            "ShowStatus" => Message::ShowStatus {
                show_ms: self.num("show_ms"),
                clip: self.num("clip"),
                state: self.num("state"),
                list: self.num("list"),
            },
            "Status" => Message::Status {
                received: self.num("received"),
                dropped: self.num("dropped"),
                last_seq: self.num("last_seq"),
                state: self.num("state"),
                chunks: self.num("chunks"),
            },
            other => panic!("{}: unknown message {other}", self.name),
        }
    }
}

/// COBS decoding as §8 describes it: a code byte `n` is followed by `n − 1`
/// data bytes and a `00`, except after the last group (and after `FF`).
fn cobs_decode(frame: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < frame.len() {
        let n = usize::from(frame[i]);
        assert!(n > 0, "00 inside a frame");
        out.extend_from_slice(&frame[i + 1..i + n]);
        i += n;
        if i < frame.len() && n < 0xFF {
            out.push(0);
        }
    }
    out
}

/// CRC-32/ISO-HDLC bit by bit (§2.3's parameters).
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = u32::MAX;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Every message, in the order of its tag (SPEC.md §8).
const MESSAGES: [&str; 9] = [
    "Hello",
    "ClipChunk",
    "Play",
    "Pose",
    "Stop",
    "Status",
    "Show",
    "Timecode",
    "ShowStatus",
];

#[test]
fn spec_has_every_message() {
    let found: Vec<String> = examples()
        .iter()
        .map(|e| e.field("message").to_string())
        .collect();
    for m in MESSAGES {
        assert!(
            found.iter().any(|f| f == m),
            "SPEC.md §8 has no {m} frame example"
        );
    }
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
}

#[test]
fn frames_are_encoded_byte_for_byte() {
    for ex in examples() {
        let mut chunk = Vec::new();
        let message = ex.message(&mut chunk);
        let mut wire = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&message, &mut wire).expect("the example fits a frame");
        assert_eq!(&wire[..n], ex.bytes.as_slice(), "{}", ex.name);
    }
}

#[test]
fn frames_decode_to_their_message() {
    for ex in examples() {
        let mut chunk = Vec::new();
        let message = ex.message(&mut chunk);
        let mut copy = ex.bytes.clone();
        assert_eq!(decode_frame(&mut copy), Ok(message.clone()), "{}", ex.name);
        let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
        let (last, body) = ex.bytes.split_last().expect("a frame");
        for &b in body {
            assert!(rx.push(b).is_none(), "{}: frame ended early", ex.name);
        }
        assert_eq!(rx.push(*last), Some(Ok(message)), "{}", ex.name);
        assert_eq!((rx.received(), rx.dropped()), (1, 0));
    }
}

#[test]
fn frames_have_the_layout_of_the_prose() {
    for ex in examples() {
        let (&delimiter, body) = ex.bytes.split_last().expect("a frame");
        assert_eq!(delimiter, 0, "{}: a frame ends with 00", ex.name);
        assert!(!body.contains(&0), "{}: 00 inside the frame", ex.name);
        let payload = cobs_decode(body);
        let (message, crc) = payload.split_at(payload.len() - 4);
        assert_eq!(
            crc,
            crc32(message).to_le_bytes(),
            "{}: CRC of the message",
            ex.name
        );
        // postcard: the tag is the variant's varint, one byte for nine variants.
        let tag = MESSAGES
            .iter()
            .position(|m| *m == ex.field("message"))
            .expect("a known message");
        assert_eq!(usize::from(message[0]), tag, "{}: tag", ex.name);
    }
}
