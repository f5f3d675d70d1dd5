//! SPEC.md §9's show examples, read out of SPEC.md itself: the decoder's
//! [`Show`] and the reference decoder written from the prose
//! (`spec_reference::parse_show`) decode every clip to the stated frames,
//! the encoder's container and show-table writers reproduce the bytes, a
//! flipped bit is rejected, and every rule of the show table has its typed
//! error. Version-1 clips and shows are told apart both ways.

// Shared with spec_examples.rs; each test crate uses part of it.
#[allow(dead_code)]
mod spec_reference;

use mocap_decoder::{consts, Clip, Error, Player, Show};
use mocap_encoder::container::assemble_version;
use mocap_encoder::show::wire::{show_table, TableRow};

struct ShowExample {
    name: String,
    bytes: Vec<u8>,
    /// Clip names and their frames.
    clips: Vec<(String, Vec<Vec<i32>>)>,
}

fn spec() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../SPEC.md")).expect("SPEC.md")
}

fn hex_block<'a>(lines: impl Iterator<Item = &'a str>) -> Vec<u8> {
    let mut bytes = Vec::new();
    for l in lines.take_while(|l| !l.starts_with("```")) {
        for tok in l.split("  ").next().unwrap_or("").split_whitespace() {
            bytes.push(u8::from_str_radix(tok, 16).expect("hex byte"));
        }
    }
    bytes
}

fn examples() -> Vec<ShowExample> {
    let spec = spec();
    let mut out = Vec::new();
    let mut lines = spec.lines();
    while let Some(line) = lines.next() {
        let Some(attrs) = line.strip_prefix("```text spec-show=") else {
            continue;
        };
        let mut parts = attrs.split_whitespace();
        let name = parts.next().unwrap().to_string();
        let mut names = Vec::new();
        let mut frames = std::collections::HashMap::new();
        for p in parts {
            if let Some(v) = p.strip_prefix("clips=") {
                names = v.split(',').map(String::from).collect();
            } else if let Some(v) = p.strip_prefix("frames_") {
                let (clip, rows) = v.split_once('=').unwrap();
                let rows: Vec<Vec<i32>> = rows
                    .split(';')
                    .map(|r| r.split(',').map(|x| x.parse().unwrap()).collect())
                    .collect();
                frames.insert(clip.to_string(), rows);
            } else {
                panic!("{name}: unknown attribute {p}");
            }
        }
        let bytes = hex_block(lines.by_ref());
        let clips = names
            .into_iter()
            .map(|n| {
                let f = frames
                    .remove(&n)
                    .unwrap_or_else(|| panic!("{name}: no frames_{n}"));
                (n, f)
            })
            .collect();
        out.push(ShowExample { name, bytes, clips });
    }
    out
}

fn decode(clip: &Clip<'_>) -> Vec<Vec<i32>> {
    let mut p = Player::<64>::new(clip).unwrap();
    let mut out = vec![0; clip.header().channel_count()];
    let mut frames = Vec::new();
    while p.next_frame(&mut out).unwrap().is_some() {
        frames.push(out.clone());
    }
    frames
}

#[test]
fn spec_has_show_examples() {
    assert!(!examples().is_empty(), "SPEC.md §9.3 examples not found");
}

#[test]
fn shows_decode_to_the_stated_frames() {
    for ex in examples() {
        let show = Show::parse(&ex.bytes).unwrap_or_else(|e| panic!("{}: {e}", ex.name));
        assert_eq!(
            usize::from(show.clip_count()),
            ex.clips.len(),
            "{}",
            ex.name
        );
        for (i, (name, frames)) in ex.clips.iter().enumerate() {
            let entry = show.entry(i as u16).unwrap();
            assert_eq!(entry.name, name, "{}", ex.name);
            assert_eq!(show.find(name), Some(i as u16));
            assert_eq!(
                &decode(&show.clip(i as u16).unwrap()),
                frames,
                "{} {name}",
                ex.name
            );
        }
        // The reference decoder, from the prose alone.
        let reference = spec_reference::parse_show(&ex.bytes);
        for ((rname, rclip), (name, frames)) in reference.iter().zip(&ex.clips) {
            assert_eq!(rname, name);
            assert_eq!(&rclip.frames(), frames, "{} {name} (reference)", ex.name);
        }
    }
}

#[test]
fn the_encoder_writes_the_show_examples_byte_for_byte() {
    for ex in examples() {
        let show = Show::parse(&ex.bytes).unwrap();
        let sections: Vec<(u8, Vec<u8>)> = (0..show.section_count())
            .map(|i| {
                let (id, len) = show.sections().nth(usize::from(i)).unwrap();
                let entry = 8 + 12 * usize::from(i);
                let off = u32::from_le_bytes(ex.bytes[entry + 4..entry + 8].try_into().unwrap());
                (id, ex.bytes[off as usize..off as usize + len].to_vec())
            })
            .collect();
        assert_eq!(
            assemble_version(consts::VERSION_SHOW, &sections),
            ex.bytes,
            "{}",
            ex.name
        );
        let rows: Vec<TableRow> = (0..show.clip_count())
            .map(|i| {
                let e = show.entry(i).unwrap();
                TableRow {
                    name: e.name.to_string(),
                    codec_section: u32::from(e.codec_section),
                    frames: e.frames,
                    looping: e.looping,
                    models: e.models[..usize::from(e.model_count)]
                        .iter()
                        .map(|&m| u32::from(m))
                        .collect(),
                }
            })
            .collect();
        let table = sections
            .iter()
            .find(|(id, _)| *id == consts::SECTION_SHOW)
            .unwrap();
        assert_eq!(show_table(&rows), table.1, "{}", ex.name);
    }
}

#[test]
fn every_flipped_bit_of_a_show_is_rejected() {
    for ex in examples() {
        for bit in 0..ex.bytes.len() * 8 {
            let mut b = ex.bytes.clone();
            b[bit / 8] ^= 1 << (bit % 8);
            assert!(
                Show::parse(&b).is_err(),
                "{}: bit {bit} flipped still parses",
                ex.name
            );
        }
    }
}

#[test]
fn clips_and_shows_are_told_apart() {
    let ex = &examples()[0];
    assert_eq!(Clip::parse(&ex.bytes).err(), Some(Error::ContainerIsShow));
    // A version-1 clip: the show's first clip on its own.
    let show = Show::parse(&ex.bytes).unwrap();
    let clip = show.clip(0).unwrap();
    let header = show.sections().next().unwrap();
    assert_eq!(header.0, consts::SECTION_HEADER);
    let one = mocap_encoder::container::assemble(&[
        (
            consts::SECTION_HEADER,
            reheader(&ex.bytes, clip.header().frame_count()),
        ),
        (clip.codec_id(), codec_bytes(&ex.bytes, 2)),
    ]);
    assert_eq!(decode(&Clip::parse(&one).unwrap()), ex.clips[0].1);
    assert_eq!(
        Show::parse(&one).err(),
        Some(Error::ContainerUnsupportedVersion { version: 1 })
    );
}

/// The bytes of section `i` of a container.
fn codec_bytes(file: &[u8], i: usize) -> Vec<u8> {
    let e = 8 + 12 * i;
    let off = u32::from_le_bytes(file[e + 4..e + 8].try_into().unwrap()) as usize;
    let len = u32::from_le_bytes(file[e + 8..e + 12].try_into().unwrap()) as usize;
    file[off..off + len].to_vec()
}

/// The example's header (section 0, postcard §3.1) with another frame count.
fn reheader(file: &[u8], frames: u32) -> Vec<u8> {
    let mut h = codec_bytes(file, 0);
    // frame_time_ns is 4 varint bytes (10 ms), then the one-byte frame count.
    assert!(frames < 128);
    h[4] = frames as u8;
    h
}

/// `ex` with its show table replaced by `table` (offsets and CRC redone).
fn with_table(ex: &[u8], table: &[u8]) -> Vec<u8> {
    let show = Show::parse(ex).unwrap();
    let sections: Vec<(u8, Vec<u8>)> = (0..usize::from(show.section_count()))
        .map(|i| {
            let id = ex[8 + 12 * i];
            if id == consts::SECTION_SHOW {
                (id, table.to_vec())
            } else {
                (id, codec_bytes(ex, i))
            }
        })
        .collect();
    assemble_version(consts::VERSION_SHOW, &sections)
}

#[test]
fn show_table_rules_have_typed_errors() {
    let ex = &examples()[0].bytes;
    let ok = codec_bytes(ex, 1);
    assert!(Show::parse(&with_table(ex, &ok)).is_ok());
    let malformed = |t: &[u8]| match Show::parse(&with_table(ex, t)) {
        Err(Error::ShowMalformed { .. }) => {}
        other => panic!("{t:02x?}: {other:?}"),
    };
    // No clips; a repeated name; an empty name; reserved flags; a position
    // past the table; trailing bytes; a frame count that does not sum to the

    malformed(&[0]);
    malformed(&[2, 2, b'u', b'p', 2, 2, 0, 0, 2, b'u', b'p', 3, 1, 0, 0]);
    malformed(&[2, 0, 2, 2, 0, 0, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0]);
    malformed(&[
        2, 2, b'u', b'p', 2, 2, 2, 0, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0,
    ]);
    malformed(&[
        2, 2, b'u', b'p', 9, 2, 0, 0, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0,
    ]);
    malformed(&[
        2, 2, b'u', b'p', 2, 2, 0, 0, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0, 0,
    ]);
    malformed(
        &[
            2, 2, b'u', b'p', 2, 2, 0, 0, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0,
        ][..1],
    );
    malformed(&[
        2, 2, b'u', b'p', 2, 2, 1, 1, 0, 0, 0, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0,
    ]);
    malformed(&[
        2, 2, b'u', b'p', 2, 2, 0, 1, 3, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0,
    ]);
    // A clip naming a section that is no codec, two clips one codec, a codec
    // section no clip names: ShowClipCodec.
    let codec_err = |t: &[u8], clip: u16| {
        assert_eq!(
            Show::parse(&with_table(ex, t)).err(),
            Some(Error::ShowClipCodec { clip }),
            "{t:02x?}"
        )
    };
    codec_err(
        &[
            2, 2, b'u', b'p', 0, 2, 0, 0, 4, b'd', b'o', b'w', b'n', 3, 1, 0, 0,
        ],
        0,
    );
    codec_err(
        &[
            2, 2, b'u', b'p', 2, 2, 0, 0, 4, b'd', b'o', b'w', b'n', 2, 1, 0, 0,
        ],
        1,
    );
    // One clip of 3 frames over `up`'s codec: the index section was made for
    // 2 frames, so its own check fails first; with `down` left unnamed.
    assert!(Show::parse(&with_table(ex, &[1, 2, b'u', b'p', 2, 3, 0, 0])).is_err());
    assert_eq!(
        Show::parse(&with_table(ex, &ok)).unwrap().clip(2).err(),
        Some(Error::ShowClipOutOfRange { clip: 2, clips: 2 })
    );
}
