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

/// The hex bytes of the ```` ```text spec-bytes=NAME ```` block of SPEC.md.
fn spec_bytes(name: &str) -> Vec<u8> {
    let spec = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../SPEC.md"))
        .expect("SPEC.md is readable");
    let marker = format!("```text spec-bytes={name}");
    let mut lines = spec.lines().skip_while(|l| l.trim() != marker);
    assert!(lines.next().is_some(), "SPEC.md has no block {marker}");
    let mut bytes = Vec::new();
    for l in lines.take_while(|l| !l.starts_with("```")) {
        for tok in l.split("  ").next().unwrap_or("").split_whitespace() {
            bytes.push(u8::from_str_radix(tok, 16).expect("hex byte"));
        }
    }
    bytes
}

/// §3.4.1 and §3.5.1: the encoder writes exactly the examples' bytes, and
/// a servo clip made of them decodes to the stated servos.
#[test]
fn servo_form_and_compact_rig_examples() {
    use mocap_encoder::container::assemble;
    use mocap_encoder::rig::Rig;
    use mocap_encoder::servo_clip::{rig_section, servo_header_section};

    let header = spec_bytes("servo-header");
    assert_eq!(servo_header_section(20_000_000, 150, 16), header);

    let rig = Rig::parse(
        r#"
[rig]
name = "spec"
rate_hz = 50
[[servo]]
name = "a"
output = 0
channel = "J.Zrotation"
angle = [-45.0, 45.0]
pulse = [1000, 2000]
max_speed = 300.0
[[servo]]
name = "b"
output = 1
channel = "J.Yrotation"
angle = [-45.0, 45.0]
pulse = [1000, 2000]
max_speed = 300.0
"#,
        "spec.toml",
    )
    .unwrap();
    let table = spec_bytes("compact-rig");
    assert_eq!(rig_section(&rig).unwrap(), table);

    // A two-servo, one-frame index clip around them (§7.1's codec section
    // shape is not needed: take a real one from the encoder).
    use mocap_encoder::motion::{ChannelKind, Joint, Motion, Skeleton};
    let joint = |name: &str| Joint {
        name: name.into(),
        parent: None,
        offset: [0.0; 3],
        channels: vec![ChannelKind::Zrotation],
        end_site: false,
    };
    let motion = Motion {
        skeleton: Skeleton {
            joints: vec![joint("a"), joint("b")],
        },
        frame_time: 0.02,
        values: vec![10.0, -20.0, 10.0, -20.0, 10.0, -20.0],
    };
    let enc = mocap_encoder::encode::encode(
        &motion,
        &mocap_encoder::encode::EncodeOptions {
            codec: mocap_encoder::encode::CodecChoice::Index,
            bound: mocap_encoder::encode::Bound {
                angle_deg: Some(0.5),
                position_mm: None,
                arms_mm: None,
            },
            metres_per_unit: 1e-3,
            key_interval: None,
        },
    )
    .unwrap();
    let codec = Clip::parse(&enc.bytes)
        .unwrap()
        .sections()
        .find(|s| s.id >= 0x10)
        .map(|s| (s.id, s.bytes.to_vec()))
        .unwrap();
    let bytes = assemble(&[
        (0x02, servo_header_section(20_000_000, 3, 2)),
        (0x03, table.clone()),
        codec.clone(),
    ]);
    let clip = Clip::parse(&bytes).unwrap();
    assert!(clip.header().is_servo_form());
    assert_eq!(clip.header().channel_count(), 2);
    let servos: Vec<_> = clip.rig().unwrap().servos().collect();
    assert_eq!(servos.len(), 2);
    for (i, s) in servos.iter().enumerate() {
        assert_eq!(s.output, i as u16);
        assert_eq!((s.angle_lo_mdeg, s.angle_hi_mdeg), (-45_000, 45_000));
        assert_eq!(
            (s.pulse_lo_qus, s.pulse_hi_qus, s.neutral_qus),
            (4000, 8000, 6000)
        );
        assert_eq!(s.max_speed_mdeg_s, 300_000);
    }
    let mut player = Player::<8>::new(&clip).unwrap();
    let mut out = [0i32; 2];
    player.next_frame(&mut out).unwrap();
    assert!(
        (out[0] - 10_000).abs() <= 500 && (out[1] + 20_000).abs() <= 500,
        "{out:?}"
    );
    // Without its rig table the servo form means nothing: refused.
    let bare = assemble(&[(0x02, servo_header_section(20_000_000, 3, 2)), codec]);
    assert_eq!(
        Clip::parse(&bare).unwrap_err(),
        Error::ContainerMissingSection { id: 0x03 }
    );
}
