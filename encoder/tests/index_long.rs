//! The `index` codec on channels no 12-bit table covers (SPEC.md §4.5,
//! key frames in levels):
//! the root of a long walk, a heading that winds many times, a channel of
//! wild jumps. Every clip must encode, and the `no_std` decoder must play
//! it back within the bound, frame by frame and by random access.

use mocap_decoder::{Clip, Player};
use mocap_encoder::encode::{self, Bound, CodecChoice, EncodeOptions};
use mocap_encoder::motion::{ChannelKind, Joint, Motion, Skeleton};

/// A root joint with `Xposition Zposition Yrotation Xrotation` (lengths in
/// metres) and `frames` frames from `value(frame, channel)`.
fn motion(frames: usize, value: impl Fn(usize, usize) -> f64) -> Motion {
    use ChannelKind::{Xposition, Xrotation, Yrotation, Zposition};
    Motion {
        skeleton: Skeleton {
            joints: vec![Joint {
                name: "Hips".into(),
                parent: None,
                offset: [0.0; 3],
                channels: vec![Xposition, Zposition, Yrotation, Xrotation],
                end_site: false,
            }],
        },
        frame_time: 1.0 / 30.0,
        values: (0..frames)
            .flat_map(|f| (0..4).map(move |c| (f, c)))
            .map(|(f, c)| value(f, c))
            .collect(),
    }
}

fn options(key_interval: Option<u16>) -> EncodeOptions {
    EncodeOptions {
        key_bits: None,
        codec: CodecChoice::Index,
        bound: Bound {
            angle_deg: Some(1.0),
            position_mm: None,
            arms_mm: None,
            foot_slide_mm_s: None,
        },
        metres_per_unit: 1.0,
        key_interval,
        index_layout: Default::default(),
        pattern: Default::default(),
    }
}

/// Decodes every frame (in order, then by random access backwards) and
/// checks each value within 1° (rotations, millidegrees) or 1 mm
/// (positions, µm) of the source.
fn check_within_bound(m: &Motion, bytes: &[u8]) {
    let clip = Clip::parse(bytes).expect("the clip parses");
    let frames = m.values.len() / 4;
    assert_eq!(clip.header().frame_count() as usize, frames);
    let mut player = Player::<4>::new(&clip).unwrap();
    let mut out = [0i32; 4];
    let expect = |f: usize, c: usize| {
        let scale = if c < 2 { 1e6 } else { 1e3 };
        m.values[f * 4 + c] * scale
    };
    let check = |f: usize, out: &[i32; 4]| {
        for (c, &v) in out.iter().enumerate() {
            let err = (f64::from(v) - expect(f, c)).abs();
            assert!(
                err <= 1000.5,
                "frame {f} channel {c}: {v} vs {}",
                expect(f, c)
            );
        }
    };
    let mut f = 0;
    while player.next_frame(&mut out).unwrap().is_some() {
        check(f, &out);
        f += 1;
    }
    assert_eq!(f, frames);
    for f in (0..frames).rev().step_by(97) {
        player.frame(f as u32, &mut out).unwrap();
        check(f, &out);
    }
}

/// The bytes of `mocap info` for the clip.
fn info(bytes: &[u8]) -> String {
    let clip = Clip::parse(bytes).unwrap();
    let (id, section) = clip
        .sections()
        .map(|s| (s.id, s.bytes))
        .find(|(id, _)| *id >= 0x10)
        .unwrap();
    mocap_encoder::codec::describe_section(id, section, clip.header(), true).unwrap()
}

/// A 20 000-frame (11 min) walk at 1.5 m/s along a spiral: ±1 km in X
/// and Z, the heading 200 turns (72 000°, a figure that spins), a periodic
/// arm swing. No key table holds X, Z or the heading to 1 mm / 1°.
#[test]
fn a_long_walk_encodes_with_key_frames_in_levels() {
    let m = motion(20_000, |f, c| {
        let t = f as f64 / 30.0;
        match c {
            0 => 1.5 * t * (0.01 * t).cos(),
            1 => 1.5 * t * (0.01 * t).sin() + 0.02 * (7.0 * t).sin(),
            2 => 360.0 * 200.0 * f as f64 / 20_000.0 + 5.0 * (3.0 * t).sin(),
            _ => 30.0 * (2.0 * t).sin(),
        }
    });
    let e = encode::encode(&m, &options(None)).expect("a long walk encodes");
    assert!(
        e.key_interval > 0,
        "delta frames between key frames in levels: {}",
        info(&e.bytes)
    );
    let text = info(&e.bytes);
    assert!(
        text.contains("key frames in levels (SPEC §4.5): 3 channels"),
        "{text}"
    );
    // Far below 32 bits per value: levels cost only the key frames.
    let bits_per_value = e.bytes.len() as f64 * 8.0 / (20_000.0 * 4.0);
    assert!(bits_per_value < 12.0, "{bits_per_value} bits per value");
    check_within_bound(&m, &e.bytes);
}

/// Values that jump anywhere in ±2·10⁹ µm every frame: no table and no
/// delta table covers them; at `K = 0` every frame is coded in levels and
/// decodes within the bound.
#[test]
fn wild_jumps_fall_back_to_levels_at_k0() {
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut jumps = Vec::new();
    for _ in 0..600 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        jumps.push((x % 4_000_000_000) as f64 / 1e6 - 2000.0);
    }
    let m = motion(600, |f, c| match c {
        0 => jumps[f],
        1 => 0.5,
        2 => 10.0 * (f as f64 * 0.1).sin(),
        _ => 0.0,
    });
    let e = encode::encode(&m, &options(None)).expect("any valid clip encodes");
    assert_eq!(e.key_interval, 0);
    assert!(info(&e.bytes).contains("levels"), "{}", info(&e.bytes));
    check_within_bound(&m, &e.bytes);
    // A forced key interval has no fallback at K = 0: a clear error names
    // the channel.
    let err = encode::encode(&m, &options(Some(8))).unwrap_err();
    assert!(err.to_string().contains("Hips.Xposition"), "{err}");
}

/// Clips that fit the tables do not change: no levels appear.
#[test]
fn short_clips_use_no_levels() {
    let m = motion(300, |f, c| {
        let t = f as f64 / 30.0;
        [0.3 * t, 0.1 * t, 20.0 * t.sin(), 10.0 * (2.0 * t).cos()][c]
    });
    let e = encode::encode(&m, &options(None)).unwrap();
    assert!(!info(&e.bytes).contains("levels"));
    check_within_bound(&m, &e.bytes);
}
