//! Every example of SPEC.md §7 is read out of SPEC.md itself and checked:
//! the decoder decodes it to the stated values, `sample_at` gives the stated
//! interpolation, the encoder's container writer reproduces the exact bytes,
//! and any single flipped bit is rejected.

use mocap_decoder::{Clip, Error, Player};

struct Example {
    name: String,
    bytes: Vec<u8>,
    frames: Vec<i32>,
    sample: Option<(u64, i32)>,
}

fn examples() -> Vec<Example> {
    let spec = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../SPEC.md"))
        .expect("SPEC.md is readable");
    let mut out = Vec::new();
    let mut lines = spec.lines();
    while let Some(line) = lines.next() {
        let Some(attrs) = line.strip_prefix("```text spec-example=") else {
            continue;
        };
        let mut parts = attrs.split_whitespace();
        let name = parts.next().unwrap().to_string();
        let mut frames = Vec::new();
        let mut sample = None;
        for p in parts {
            if let Some(v) = p.strip_prefix("frames=") {
                frames = v.split(';').map(|x| x.parse().unwrap()).collect();
            } else if let Some(v) = p.strip_prefix("sample_at_") {
                let (t, val) = v.split_once("us=").unwrap();
                sample = Some((t.parse().unwrap(), val.parse().unwrap()));
            }
        }
        let mut bytes = Vec::new();
        for l in lines.by_ref() {
            if l.starts_with("```") {
                break;
            }
            // Hex pairs, then (after two or more spaces) a comment.
            let hex = l.split("  ").next().unwrap_or("");
            for tok in hex.split_whitespace() {
                assert_eq!(tok.len(), 2, "{name}: bad hex token {tok:?} in {l:?}");
                bytes.push(u8::from_str_radix(tok, 16).expect("hex byte"));
            }
        }
        out.push(Example {
            name,
            bytes,
            frames,
            sample,
        });
    }
    out
}

#[test]
fn spec_has_examples() {
    assert!(examples().len() >= 2, "SPEC.md §7 examples not found");
}

#[test]
fn examples_decode_to_the_stated_values() {
    for ex in examples() {
        let clip = Clip::parse(&ex.bytes).unwrap_or_else(|e| panic!("{}: {e}", ex.name));
        let mut player = Player::<4>::new(&clip).unwrap();
        let mut out = [0i32; 1];
        let mut got = Vec::new();
        while player.next_frame(&mut out).unwrap().is_some() {
            got.push(out[0]);
        }
        assert_eq!(got, ex.frames, "{}", ex.name);
        // Random access in reverse order gives the same values.
        for i in (0..ex.frames.len()).rev() {
            player.frame(i as u32, &mut out).unwrap();
            assert_eq!(out[0], ex.frames[i], "{} frame {i}", ex.name);
        }
        if let Some((t, v)) = ex.sample {
            player.sample_at(t, &mut out).unwrap();
            assert_eq!(out[0], v, "{} sample_at({t})", ex.name);
        }
    }
}

#[test]
fn encoder_writes_the_examples_byte_for_byte() {
    for ex in examples() {
        let clip = Clip::parse(&ex.bytes).unwrap();
        let sections: Vec<(u8, Vec<u8>)> =
            clip.sections().map(|s| (s.id, s.bytes.to_vec())).collect();
        assert_eq!(
            mocap_encoder::container::assemble(&sections),
            ex.bytes,
            "{}",
            ex.name
        );
    }
}

#[test]
fn header_of_the_examples_is_postcard() {
    use mocap_encoder::container::{ChannelWire, HeaderWire, JointWire};
    let ex = &examples()[0];
    let clip = Clip::parse(&ex.bytes).unwrap();
    let header = clip.sections().find(|s| s.id == 0x01).unwrap();
    let wire = HeaderWire {
        frame_time_ns: 10_000_000,
        frame_count: 2,
        source_unit_nm: 10_000_000,
        joints: vec![JointWire {
            name: "J".into(),
            parent: None,
            offset_um: [0, 0, 0],
            end_site: false,
            kinds: vec![5],
        }],
        channels: vec![ChannelWire {
            unit: 0,
            min: 0,
            max: 1500,
        }],
    };
    assert_eq!(wire.to_bytes(), header.bytes);
}

#[test]
fn every_flipped_bit_is_rejected() {
    for ex in examples() {
        for bit in 0..ex.bytes.len() * 8 {
            let mut b = ex.bytes.clone();
            b[bit / 8] ^= 1 << (bit % 8);
            assert!(
                Clip::parse(&b).is_err(),
                "{}: flip of bit {bit} accepted",
                ex.name
            );
        }
    }
}

#[test]
fn errors_are_typed() {
    let ex = &examples()[0];
    assert_eq!(Clip::parse(b"XXXX").unwrap_err(), Error::ContainerBadMagic);
    assert!(matches!(
        Clip::parse(&ex.bytes[..10]).unwrap_err(),
        Error::ContainerTruncated { .. }
    ));
    let mut b = ex.bytes.clone();
    b[4] = 9;
    assert_eq!(
        Clip::parse(&b).unwrap_err(),
        Error::ContainerUnsupportedVersion { version: 9 }
    );
    let clip = Clip::parse(&ex.bytes).unwrap();
    let mut small = [0i32; 0];
    let mut player = Player::<4>::new(&clip).unwrap();
    assert_eq!(
        player.next_frame(&mut small).unwrap_err(),
        Error::PlayerOutputTooSmall {
            expected: 1,
            actual: 0
        }
    );
    assert!(matches!(
        Player::<0>::new(&clip),
        Err(Error::PlayerCapacity { .. })
    ));
    let mut out = [0i32; 1];
    assert_eq!(
        player.frame(2, &mut out).unwrap_err(),
        Error::PlayerFrameOutOfRange {
            frame: 2,
            frames: 2
        }
    );
}
