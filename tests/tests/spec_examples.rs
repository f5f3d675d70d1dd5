//! Every example of SPEC.md §7 is read out of SPEC.md itself and checked:
//! the decoder decodes it to the stated values, `sample_at` gives the stated
//! interpolation, the encoder's container writer reproduces the exact bytes,
//! and any single flipped bit is rejected. Every example is also decoded by
//! a reference decoder written from SPEC.md's prose alone
//! (`spec_reference`), and the encoder makes each `pca-spline` and
//! `predictive` example (§7.3–§7.6), byte for byte, from the motion its
//! prose names.

// Shared with spec_examples.rs; each test crate uses part of it.
#[allow(dead_code)]
mod spec_reference;

use mocap_decoder::{Clip, Error, Player};

struct Example {
    name: String,
    bytes: Vec<u8>,
    /// `frames=` rows: frame by frame (`;`), channel by channel (`,`).
    frames: Vec<Vec<i32>>,
    /// `sample_at_<t>us=` values, one per channel.
    samples: Vec<(u64, Vec<i32>)>,
}

impl Example {
    fn channels(&self) -> usize {
        self.frames.first().map_or(0, Vec::len)
    }

    fn codec(&self) -> u8 {
        let clip = Clip::parse(&self.bytes).unwrap();
        let id = clip.sections().map(|s| s.id).find(|&id| id >= 0x10);
        id.unwrap()
    }
}

fn row(v: &str) -> Vec<i32> {
    v.split(',').map(|x| x.parse().unwrap()).collect()
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
        let mut samples = Vec::new();
        for p in parts {
            if let Some(v) = p.strip_prefix("frames=") {
                frames = v.split(';').map(row).collect();
            } else if let Some(v) = p.strip_prefix("sample_at_") {
                let (t, val) = v.split_once("us=").unwrap();
                samples.push((t.parse().unwrap(), row(val)));
            } else {
                panic!("{name}: unknown attribute {p}");
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
            samples,
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
        let c = ex.channels();
        assert_eq!(clip.header().channel_count(), c, "{}", ex.name);
        let mut player = Player::<64>::new(&clip).unwrap();
        let mut out = vec![0i32; c];
        let mut got = Vec::new();
        while player.next_frame(&mut out).unwrap().is_some() {
            got.push(out.clone());
        }
        assert_eq!(got, ex.frames, "{}", ex.name);
        // Random access in reverse order gives the same values.
        for i in (0..ex.frames.len()).rev() {
            player.frame(i as u32, &mut out).unwrap();
            assert_eq!(out, ex.frames[i], "{} frame {i}", ex.name);
        }
        for (t, v) in &ex.samples {
            player.sample_at(*t, &mut out).unwrap();
            assert_eq!(&out, v, "{} sample_at({t})", ex.name);
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

/// §4.5 on §7.2b's clip in levels: each level matters, and the key set
/// still needs an entry per channel.
#[test]
fn key_frames_in_levels() {
    let ex = examples().into_iter().find(|e| e.name == "levels").unwrap();
    let clip = Clip::parse(&ex.bytes).unwrap();
    let sections: Vec<(u8, Vec<u8>)> = clip.sections().map(|s| (s.id, s.bytes.to_vec())).collect();
    let frames_with = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut s = sections.clone();
        f(&mut s[1].1);
        let bytes = mocap_encoder::container::assemble(&s);
        let clip = Clip::parse(&bytes)?;
        let mut player = Player::<1>::new(&clip).unwrap();
        let mut out = [0i32];
        let mut frames = Vec::new();
        while player.next_frame(&mut out).unwrap().is_some() {
            frames.push(out[0]);
        }
        Ok::<_, Error>(frames)
    };
    // Section: 8 bytes; key set 2 + 12 + 12 (flags at 11 and 23); delta
    // set 14; pool 12 (48..60); payload 1.
    assert_eq!(
        frames_with(&|_| {}),
        Ok(vec![70_000_000, 70_000_250, -30_000_000])
    );
    // The fine level assigning instead of adding: it comes second, so the
    // coarse level is lost (its value 0 + the fine entry).
    assert_eq!(frames_with(&|c| c[23] &= !0x80), Ok(vec![-640, -390, -896]));
    // Both assigning: the later entry wins (§4.2), as before §4.5.
    assert_eq!(
        frames_with(&|c| {
            c[11] &= !0x80;
            c[23] &= !0x80;
        }),
        Ok(vec![-640, -390, -896])
    );
    // A key set with fewer entries than channels: one group of none.
    let err = frames_with(&|c| {
        c.splice(8..34, [1, 0, 0, 0, 0, 0]);
        c.truncate(c.len() - 1);
        c.push(0);
    });
    assert_eq!(
        err,
        Err(Error::IndexMalformed {
            rule: "key set has fewer entries than channels"
        })
    );
}

/// §4.6 on §7.2c's clip: each rule gives its typed error, and every
/// mutation of the section (truncations, every byte set to every value at
/// the header and each group's header) parses or fails without a panic —
/// and what parses decodes every frame.
#[test]
fn fast_layout_malformed_sections() {
    let ex = examples()
        .into_iter()
        .find(|e| e.name == "index-fast")
        .unwrap();
    let clip = Clip::parse(&ex.bytes).unwrap();
    let sections: Vec<(u8, Vec<u8>)> = clip.sections().map(|s| (s.id, s.bytes.to_vec())).collect();
    let with = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut s = sections.clone();
        f(&mut s[1].1);
        mocap_encoder::container::assemble(&s)
    };
    let play = |bytes: &[u8]| -> Result<Vec<Vec<i32>>, Error> {
        let clip = Clip::parse(bytes)?;
        let mut player = Player::<3>::new(&clip)?;
        let mut out = [0i32; 3];
        let mut frames = Vec::new();
        while player.next_frame(&mut out)?.is_some() {
            frames.push(out.to_vec());
        }
        player.sample_at(15_000, &mut out)?;
        Ok(frames)
    };
    assert_eq!(play(&with(&|_| {})), Ok(ex.frames.clone()));
    let err = |f: &dyn Fn(&mut Vec<u8>)| play(&with(f)).unwrap_err();
    // Section: K, C (0..4); key set at 4: count, group 1 header at 6 (width 6,
    // flags 7, count 8, stride 10), destination 12, table 14..30; group 2 at
    // 30 (destination 36, table 38..46); group 3 at 46; delta set at 58:
    // groups at 60 and 84; payload 100..106.
    assert_eq!(
        err(&|c| c[2] = 4),
        Error::IndexMalformed {
            rule: "channel count differs from the header"
        }
    );
    for (at, v) in [
        (6, 3),
        (6, 5),
        (7, 0x01),
        (10, 3),
        (10, 0),
        (34, 3),
        (50, 2),
        (85, 0x81),
    ] {
        assert_eq!(
            err(&|c| c[at] = v),
            Error::IndexMalformed {
                rule: "invalid group header"
            },
            "byte {at} = {v}"
        );
    }
    assert_eq!(err(&|c| c[12] = 3), Error::IndexDescriptor { channel: 3 });
    assert!(matches!(
        err(&|c| {
            c.pop();
        }),
        Error::IndexPayloadTruncated { .. }
    ));
    assert!(matches!(
        err(&|c| c.push(0)),
        Error::IndexPayloadTruncated { .. }
    ));
    assert_eq!(
        err(&|c| c[4] = 2),
        Error::IndexMalformed {
            rule: "key set has fewer entries than channels"
        }
    );
    assert_eq!(
        err(&|c| c.truncate(20)),
        Error::IndexMalformed {
            rule: "set truncated"
        }
    );
    // No panic anywhere: every value at every header byte, every truncation.
    for at in [
        0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 30, 31, 32, 33, 34, 36, 46, 47, 48, 50, 52,
        58, 59, 60, 61, 62, 63, 64, 66, 84, 85, 86, 88, 90, 100, 101,
    ] {
        for v in 0..=255u8 {
            let _ = play(&with(&|c| c[at] = v));
        }
    }
    for len in 0..sections[1].1.len() {
        let _ = play(&with(&|c| c.truncate(len)));
    }
    // An index past its table (width 8: stride < 2^8) leaves the channel as
    // it is: the Z channel as a width-8 group of stride 2, frame 0's index 3.
    let wide = with(&|c| {
        c[30] = 8;
        c[100] = 0x00;
        c[101] = 0x03;
    });
    // Key record: X block 1 byte, Z block 1 byte (8 bits) — same lengths.
    let frames = play(&wide).unwrap();
    assert_eq!(frames[0], vec![0, 0, 2000]);
}

/// The fast layout (§4.6) round-trips real motion within its bound (the
/// encoder's own proof decodes it), and the reference decoder written from
/// §4.6 agrees with the decoder on every frame.
#[test]
fn fast_layout_round_trip() {
    use mocap_encoder::codec::index::IndexLayout;
    let motion = mocap_encoder::bvh::read_file(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../assets/animatronic_demo.bvh"
    )))
    .unwrap();
    for key_interval in [None, Some(0)] {
        let clip = |layout| {
            mocap_encoder::encode::encode(
                &motion,
                &mocap_encoder::encode::EncodeOptions {
                    key_bits: None,
                    codec: mocap_encoder::encode::CodecChoice::Index,
                    bound: mocap_encoder::encode::Bound::from_specs(&[
                        mocap_encoder::encode::BoundSpec::Degrees(1.0),
                    ]),
                    metres_per_unit: mocap_encoder::units::detect(&motion).metres(),
                    key_interval,
                    index_layout: layout,
                    pattern: Default::default(),
                },
            )
            .unwrap()
        };
        let (compact, fast) = (clip(IndexLayout::Compact), clip(IndexLayout::Fast));
        assert!(fast.metrics.angle_max_deg <= 1.0 + 1e-9);
        let decode = |bytes: &[u8]| {
            let clip = Clip::parse(bytes).unwrap();
            let mut player = Player::<64>::new(&clip).unwrap();
            let mut out = vec![0i32; clip.header().channel_count()];
            let mut frames = Vec::new();
            while player.next_frame(&mut out).unwrap().is_some() {
                frames.push(out.clone());
            }
            (clip.sections().map(|s| s.id).collect::<Vec<_>>(), frames)
        };
        let (ids_c, _) = decode(&compact.bytes);
        let (ids_f, frames_f) = decode(&fast.bytes);
        assert!(ids_c.contains(&0x10) && ids_f.contains(&0x13));
        let reference = spec_reference::parse(&fast.bytes);
        assert_eq!(reference.frames(), frames_f);
    }
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

/// Two root joints `a` and `b` of one `Zrotation` each, three frames of 10° and −20°, coded
/// by `index` at 0.5°: the codec section of §3.5.1's and §3.6's servo clips.
fn two_channel_clip() -> Vec<u8> {
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
    mocap_encoder::encode::encode(
        &motion,
        &mocap_encoder::encode::EncodeOptions {
            key_bits: None,
            codec: mocap_encoder::encode::CodecChoice::Index,
            bound: mocap_encoder::encode::Bound {
                angle_deg: Some(0.5),
                position_mm: None,
                arms_mm: None,
                foot_slide_mm_s: None,
            },
            metres_per_unit: 1e-3,
            key_interval: None,
            index_layout: Default::default(),
            pattern: Default::default(),
        },
    )
    .unwrap()
    .bytes
}

/// The two-servo rig of §3.5.1's and §3.6's examples.
fn spec_rig() -> mocap_encoder::rig::Rig {
    use mocap_encoder::rig::Rig;
    Rig::parse(
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
    .unwrap()
}

/// §3.6: the digest of §3.5.1's rig is the CRC-32 of the record shown; the encoder writes the
/// section shown as the servo clip's last section, and `Clip::rig_digest` reads it back. A
/// `0x80` section of another length is no digest, and a clip without one still parses.
#[test]
fn rig_digest_example() {
    use mocap_encoder::container::assemble;
    use mocap_encoder::servo_clip::{attach_rig, ServoNames};

    let rig = spec_rig();
    let record = spec_bytes("rig-digest-record");
    let section = spec_bytes("rig-digest");
    assert_eq!(record.len(), 8 + 2 * mocap_decoder::DIGEST_SERVO_LEN);
    assert_eq!(
        mocap_decoder::wire::crc32(&record).to_le_bytes().to_vec(),
        section
    );
    assert_eq!(rig.digest().to_le_bytes().to_vec(), section);

    // A one-channel-per-servo coded clip, made a servo clip by the encoder.
    let coded = two_channel_clip();
    let bytes = attach_rig(&coded, &rig, ServoNames::Strip).unwrap();
    let clip = Clip::parse(&bytes).unwrap();
    let last = clip.sections().last().unwrap();
    assert_eq!((last.id, last.bytes), (0x80, section.as_slice()));
    assert_eq!(clip.rig_digest(), Some(0xc05a_85a0));

    // Without it (as before §3.6) the clip parses and has no digest; a 0x80 section of
    // another length is skipped.
    let others: Vec<(u8, Vec<u8>)> = clip
        .sections()
        .filter(|s| s.id != 0x80)
        .map(|s| (s.id, s.bytes.to_vec()))
        .collect();
    assert_eq!(Clip::parse(&assemble(&others)).unwrap().rig_digest(), None);
    let mut odd = others.clone();
    odd.push((0x80, vec![0xa0, 0x85, 0x5a]));
    assert_eq!(Clip::parse(&assemble(&odd)).unwrap().rig_digest(), None);
}

/// §3.4.1 and §3.5.1: the encoder writes exactly the examples' bytes, and
/// a servo clip made of them decodes to the stated servos.
#[test]
fn servo_form_and_compact_rig_examples() {
    use mocap_encoder::container::assemble;
    use mocap_encoder::servo_clip::{rig_section, servo_header_section};

    let header = spec_bytes("servo-header");
    assert_eq!(servo_header_section(20_000_000, 150, 16), header);

    let rig = spec_rig();
    let table = spec_bytes("compact-rig");
    assert_eq!(rig_section(&rig).unwrap(), table);

    // A two-servo, one-frame index clip around them (§7.1's codec section
    // shape is not needed: take a real one from the encoder).
    let coded = two_channel_clip();
    let codec = Clip::parse(&coded)
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

/// The motion and options each `pca-spline` / `predictive` example of §7
/// says it was made from.
fn example_input(
    name: &str,
) -> (
    mocap_encoder::motion::Motion,
    mocap_encoder::encode::EncodeOptions,
) {
    use mocap_encoder::encode::{Bound, CodecChoice, EncodeOptions};
    use mocap_encoder::motion::{ChannelKind, Joint, Motion, Skeleton};
    use ChannelKind::{Xrotation, Zrotation};
    let joint = |name: &str, channels: Vec<ChannelKind>| Joint {
        name: name.into(),
        parent: None,
        offset: [0.0; 3],
        channels,
        end_site: false,
    };
    let (joints, values, codec, key_interval) = match name {
        "pca-constant" => (
            vec![
                joint("A", vec![Xrotation, Zrotation]),
                joint("B", vec![Zrotation]),
            ],
            vec![
                10.0, -5.0, 5.0, 10.2, -5.1, 5.0, 10.1, -5.0, 5.0, 10.3, -4.9, 5.0,
            ],
            CodecChoice::PcaSpline,
            None,
        ),
        "pca-keys" => (
            vec![joint("J", vec![Zrotation])],
            vec![0.0, 20.0, 40.0, 45.0, 80.0, 50.0, 40.0],
            CodecChoice::PcaSpline,
            None,
        ),
        "pred-restart" => (
            vec![joint("J", vec![Xrotation, Zrotation])],
            vec![
                5.0, 0.0, 5.0, 10.0, 5.0, 20.0, 5.0, 35.0, 5.0, 30.0, 5.0, 25.0,
            ],
            CodecChoice::Predictive,
            Some(3),
        ),
        "pred-weights" => (
            vec![joint("J", vec![Xrotation, Zrotation])],
            vec![
                0.0, 0.0, 3.0, 10.0, 6.0, 21.0, 9.0, 29.0, 12.0, 41.0, 15.0, 50.0, 18.0, 58.0,
                21.0, 71.0,
            ],
            CodecChoice::Predictive,
            Some(4),
        ),
        other => panic!("SPEC.md example {other}: no input motion in this test"),
    };
    let motion = Motion {
        skeleton: Skeleton { joints },
        frame_time: 0.01,
        values,
    };
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound {
            angle_deg: Some(1.0),
            position_mm: None,
            arms_mm: None,
            foot_slide_mm_s: None,
        },
        // Lengths in cm: the header's source unit 10 000 000 nm.
        metres_per_unit: 0.01,
        key_interval,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    (motion, opts)
}

/// The examples of the `pca-spline` (0x11) and `predictive` (0x12) codecs.
fn codec_examples() -> Vec<Example> {
    examples()
        .into_iter()
        .filter(|e| matches!(e.codec(), 0x11 | 0x12))
        .collect()
}

#[test]
fn spec_has_examples_of_every_codec() {
    let ids: Vec<u8> = examples().iter().map(Example::codec).collect();
    for (id, name) in [(0x10, "index"), (0x11, "pca-spline"), (0x12, "predictive")] {
        assert!(
            ids.iter().filter(|&&i| i == id).count() >= 2,
            "SPEC.md §7 needs two examples of {name}"
        );
    }
    // `pattern`: §7.7 here, its shared database in a show in spec_shows.rs.
    assert!(
        ids.contains(&0x14),
        "SPEC.md §7 needs an example of pattern"
    );
    // `rma`: §7.10 (a repeated clip over a residual, fading between frames).
    assert!(ids.contains(&0x15), "SPEC.md §7 needs an example of rma");
}

/// The reference decoder, written from the prose, gives the stated values
/// of every example (all codecs): every frame, and `sample_at`.
#[test]
fn reference_decoder_gives_the_stated_values() {
    for ex in examples() {
        let clip = spec_reference::parse(&ex.bytes);
        assert_eq!(clip.channels, ex.channels(), "{}", ex.name);
        assert_eq!(clip.frames(), ex.frames, "{}: reference decoder", ex.name);
        for (t, v) in &ex.samples {
            assert_eq!(
                &clip.sample_at(*t),
                v,
                "{}: reference sample_at({t})",
                ex.name
            );
        }
        // At the frames themselves sample_at is the frame.
        let frame_us = u64::from(clip.frame_time_ns / 1000);
        for (i, f) in ex.frames.iter().enumerate() {
            assert_eq!(
                &clip.sample_at(i as u64 * frame_us),
                f,
                "{} at frame {i}",
                ex.name
            );
        }
    }
}

/// The reference decoder and the decoder agree between the frames too,
/// every millisecond up to past the end (where the last pose holds).
#[test]
fn reference_and_decoder_agree_at_every_millisecond() {
    for ex in examples() {
        let clip = Clip::parse(&ex.bytes).unwrap();
        let reference = spec_reference::parse(&ex.bytes);
        let mut player = Player::<64>::new(&clip).unwrap();
        let mut out = vec![0i32; ex.channels()];
        for ms in 0..=(ex.frames.len() as u64 + 1) * 10 {
            player.sample_at(ms * 1000, &mut out).unwrap();
            assert_eq!(
                out,
                reference.sample_at(ms * 1000),
                "{} at {ms} ms",
                ex.name
            );
        }
    }
}

/// The encoder makes each example, byte for byte, from the motion its
/// text gives.
#[test]
fn encoder_makes_the_codec_examples_from_their_motion() {
    for ex in codec_examples() {
        let (motion, opts) = example_input(&ex.name);
        let encoded = mocap_encoder::encode::encode(&motion, &opts).unwrap();
        assert_eq!(encoded.bytes, ex.bytes, "{}", ex.name);
    }
}

/// The worked numbers of §7.4 and §7.5's prose.
#[test]
fn worked_numbers_of_the_prose() {
    let pca = examples()
        .into_iter()
        .find(|e| e.name == "pca-keys")
        .unwrap();
    let spec_reference::Codec::PcaSpline(p) = spec_reference::parse(&pca.bytes).codec else {
        panic!("pca-keys is a pca-spline clip");
    };
    let g = &p.segments[0].groups[0];
    assert_eq!(g.times, [0, 2, 3, 5, 6]);
    let control: Vec<i32> = g.control.iter().map(|c| c[0]).collect();
    assert_eq!(control, [-35_328, 5_120, 10_240, 14_848, 5_632]);
    assert_eq!(
        spec_reference::catmull_rom(&g.times, &g.control, 1 << 16),
        [-13_846]
    );
    assert_eq!(p.segments[0].patches, [(4, 0, 31_726)]);

    let pred = examples()
        .into_iter()
        .find(|e| e.name == "pred-restart")
        .unwrap();
    let clip = spec_reference::parse(&pred.bytes);
    let spec_reference::Codec::Predictive(p) = &clip.codec else {
        panic!("pred-restart is a predictive clip");
    };
    let (_, r) = p.decode_traced(clip.channels, clip.frame_count);
    let q: Vec<i64> = r.q.iter().map(|f| f[1]).collect();
    assert_eq!(q, [0, 6, 0, 20, -3, 0]);
    let block0: Vec<u32> = r.traces[0].iter().map(|t| t.3).collect();
    assert_eq!(block0, [0, 1, 0, 1, 1, 1, 1, 1, 0, 0]);
    assert_eq!(r.traces[0][1], (Some(1056), 0x7fff_fc00, 0x6008_0000, 1));
    assert_eq!(r.traces[0][8], (Some(1024), 0xf800_0000, 0x0004_2000, 0));

    let pred = examples()
        .into_iter()
        .find(|e| e.name == "pred-weights")
        .unwrap();
    let clip = spec_reference::parse(&pred.bytes);
    let spec_reference::Codec::Predictive(p) = &clip.codec else {
        panic!("pred-weights is a predictive clip");
    };
    let (_, r) = p.decode_traced(clip.channels, clip.frame_count);
    assert_eq!(
        r.q,
        [
            [0, 0],
            [2, 5],
            [0, 1],
            [0, -2],
            [6, 21],
            [2, 4],
            [0, 0],
            [0, 3]
        ]
    );
}

/// §3.7: the mask of the example is what the encoder writes as a marker clip's last section;
/// `Clip::missing` reads it back; a clip without it parses and has none; each rule of §3.7
/// has its error.
#[test]
fn missing_samples_example() {
    use mocap_encoder::container::assemble;
    use mocap_encoder::markers::{encode_markers, marker_skeleton, MarkerClip, MissingMask};
    use mocap_encoder::motion::Motion;

    let section = spec_bytes("missing-samples");
    let mut mask = MissingMask::none(6, 3);
    for f in [0, 1, 4] {
        mask.missing[f * 3 + 1] = true;
    }
    mask.missing[5 * 3 + 2] = true;
    assert_eq!(mask.to_section(), section);
    // The reference reader, from §3.7's prose, reads the same mask.
    let reference = spec_reference::missing_samples(&section, 3, 6);
    for (k, marker) in reference.iter().enumerate() {
        for (f, &gone) in marker.iter().enumerate() {
            assert_eq!(gone, mask.is_missing(f, k), "marker {k} frame {f}");
        }
    }

    // Three markers, six frames, in mm; 0 at the missing samples (as the C3D reader gives them).
    let mut values = Vec::new();
    for f in 0..6 {
        for k in 0..3 {
            let v = [10.0 * f as f64, 100.0 * k as f64, 1000.0];
            values.extend(if mask.is_missing(f, k) { [0.0; 3] } else { v });
        }
    }
    let clip = MarkerClip {
        motion: Motion {
            skeleton: marker_skeleton(["A", "B", "C"].map(String::from)),
            frame_time: 0.01,
            values,
        },
        missing: mask.clone(),
        unit: mocap_encoder::units::LengthUnit::Mm,
    };
    let opts = mocap_encoder::encode::EncodeOptions {
        key_bits: None,
        codec: mocap_encoder::encode::CodecChoice::Index,
        bound: mocap_encoder::encode::Bound {
            angle_deg: None,
            position_mm: Some(1.0),
            arms_mm: None,
            foot_slide_mm_s: None,
        },
        metres_per_unit: 1e-3,
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    let enc = encode_markers(&clip, &opts).unwrap();
    assert!(enc.error.max_mm <= 1.0);
    assert_eq!((enc.error.present, enc.error.missing), (14, 4));
    let parsed = Clip::parse(&enc.encoded.bytes).unwrap();
    let last = parsed.sections().last().unwrap();
    assert_eq!((last.id, last.bytes), (0x81, section.as_slice()));
    let m = parsed.missing().unwrap();
    assert_eq!(
        (m.markers(), m.frames(), m.count(), m.run_count()),
        (3, 6, 4, 3)
    );
    assert_eq!(m.runs(1).collect::<Vec<_>>(), [(0, 2), (4, 1)]);
    assert_eq!(m.runs(2).collect::<Vec<_>>(), [(5, 1)]);
    for f in 0..6 {
        for k in 0..3 {
            assert_eq!(m.is_missing(f, k), mask.is_missing(f as usize, k as usize));
        }
    }
    assert_eq!(MissingMask::of_clip(&parsed), Some(mask));

    // Without it (as before §3.7) the clip parses and has no mask.
    let others: Vec<(u8, Vec<u8>)> = parsed
        .sections()
        .filter(|s| s.id != 0x81)
        .map(|s| (s.id, s.bytes.to_vec()))
        .collect();
    assert!(Clip::parse(&assemble(&others)).unwrap().missing().is_none());
    // Each rule.
    let with = |bytes: &[u8]| {
        let mut s = others.clone();
        s.push((0x81, bytes.to_vec()));
        // The reference reader refuses what the decoder refuses.
        let reference = std::panic::catch_unwind(|| spec_reference::missing_samples(bytes, 3, 6));
        let decoded = Clip::parse(&assemble(&s)).err();
        assert_eq!(reference.is_err(), decoded.is_some(), "{bytes:02x?}");
        decoded
    };
    assert_eq!(
        with(&[0x02, 0x00, 0x00]),
        Some(Error::MissingMarkerCount {
            markers: 2,
            joints: 3
        })
    );
    let mut empty = section.clone();
    empty[7] = 0; // marker 1's fifth run (present 1) → 0
    assert_eq!(
        with(&empty),
        Some(Error::MissingEmptyRun { marker: 1, run: 4 })
    );
    let mut long = section.clone();
    long[5] = 3; // marker 1's third run (present 2) → 3: its runs add up to 7
    assert_eq!(
        with(&long),
        Some(Error::MissingRunTotal {
            marker: 1,
            frames: 6
        })
    );
    let mut trailing = section.clone();
    trailing.push(0);
    assert_eq!(
        with(&trailing),
        Some(Error::MissingTrailingBytes { offset: 11 })
    );
    assert_eq!(
        with(&section[..5]),
        Some(Error::MissingMalformed { offset: 5 })
    );
}

/// The entropy coder's example of SPEC.md §10.6 (```` ```text
/// spec-entropy=NAME symbols=… ````): table and stream bytes.
fn entropy_examples() -> Vec<(String, Vec<u32>, Vec<u8>)> {
    let spec = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../SPEC.md"))
        .expect("SPEC.md is readable");
    let mut out = Vec::new();
    let mut lines = spec.lines();
    while let Some(line) = lines.next() {
        let Some(attrs) = line.strip_prefix("```text spec-entropy=") else {
            continue;
        };
        let mut parts = attrs.split_whitespace();
        let name = parts.next().unwrap().to_string();
        let mut symbols = Vec::new();
        for p in parts {
            match p.strip_prefix("symbols=") {
                Some(v) => symbols = v.split(',').map(|x| x.parse().unwrap()).collect(),
                None => panic!("{name}: unknown attribute {p}"),
            }
        }
        let mut bytes = Vec::new();
        for l in lines.by_ref() {
            if l.starts_with("```") {
                break;
            }
            let hex = l.split("  ").next().unwrap_or("");
            for tok in hex.split_whitespace() {
                assert_eq!(tok.len(), 2, "{name}: bad hex token {tok:?} in {l:?}");
                bytes.push(u8::from_str_radix(tok, 16).expect("hex byte"));
            }
        }
        out.push((name, symbols, bytes));
    }
    out
}

#[test]
fn entropy_example() {
    use mocap_decoder::entropy::{Decoder, Table};
    let examples = entropy_examples();
    assert!(!examples.is_empty(), "SPEC.md §10.6 example not found");
    for (name, symbols, bytes) in examples {
        // The encoder writes exactly these bytes.
        let encoded = mocap_encoder::entropy::encode_all(&symbols).unwrap();
        let hex: Vec<String> = encoded.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(encoded, bytes, "{name}: encoder gives {}", hex.join(" "));
        // The decoder decodes them to the stated symbols; the trace of the
        // steps is printed for the table of §10.6.
        let (t, used) = Table::parse(&bytes).unwrap();
        let mut d = Decoder::new(t, &bytes[used..]).unwrap();
        let mut got = Vec::new();
        for _ in 0..symbols.len() {
            let x = d.state();
            let slot = x & ((1 << t.precision()) - 1);
            let before = d.remaining();
            let s = d.symbol();
            println!(
                "{name}: x {x:08x} slot {slot} -> symbol {s}, x {:08x}, {} bytes read",
                d.state(),
                before - d.remaining()
            );
            got.push(s);
        }
        assert_eq!(got, symbols, "{name}");
        assert!(d.is_finished(), "{name}: every byte read, x back at 2^23");
        // A corrupted table: `W` 3 → 4 makes symbol 0's count 13 > M = 8.
        let mut bad = bytes.clone();
        bad[0] = 0x43;
        assert!(
            matches!(
                Table::parse(&bad),
                Err(Error::EntropyTable {
                    rule: "a count is above what is left of M"
                })
            ),
            "{name}"
        );
        // Zero alphabet, truncated table, missing state.
        let mut zero = bytes.clone();
        zero[1] = 0;
        assert!(matches!(
            Table::parse(&zero),
            Err(Error::EntropyTable { .. })
        ));
        assert!(matches!(
            Table::parse(&bytes[..used - 1]),
            Err(Error::EntropyTable { .. })
        ));
        assert_eq!(
            Decoder::new(t, &bytes[used..used + 3]).unwrap_err(),
            Error::EntropyState
        );
    }
}
