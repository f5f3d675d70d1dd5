//! Arbitrary small motion -> `mocap_encoder::encode::encode` -> `Clip::parse` + `Player`: every
//! clip the encoder accepts to write decodes, frame by frame, within the bound it promises — the
//! angle bound on every rotation channel (wrap-aware) and `Bound::DEFAULT_TRANSLATION_MM` on
//! every translation channel — and the encoder never panics. The corruption target beside it
//! (`parse_and_play`) covers what the encoder never writes.
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use mocap_decoder::{Clip, Player};
use mocap_encoder::encode::{encode, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::fixed::{scale, wrap_degrees};
use mocap_encoder::motion::{ChannelKind, Joint, Motion, Skeleton};

/// Channels of the largest motion: a root with 6 channels and 3 more joints with 3 each.
const MAX_CHANNELS: usize = 6 + 3 * 3;
/// Player state words: the predictive codec needs 3 per channel plus its adaptive model
/// (`3 * channels + STATE_EXTRA_WORDS`); 512 as in `parse_and_play` holds every motion here.
const PLAYER_WORDS: usize = 512;
/// Frames of the largest motion.
const MAX_FRAMES: usize = 48;
/// Source length unit: centimetres.
const METRES_PER_UNIT: f64 = 0.01;

#[derive(Arbitrary, Debug)]
struct Input {
    /// 0 index, 1 pca-spline, 2 predictive, 3 pattern, 4 rma (modulo 5).
    codec: u8,
    /// Angle bound in hundredths of a degree, folded into 0.05°..=10°.
    bound_cdeg: u16,
    /// The root has X/Y/Z position channels too.
    root_position: bool,
    /// Joints below the root (modulo 4).
    children: u8,
    /// Forced key-frame interval / block length (0 = the encoder's choice).
    key_interval: u8,
    /// Per frame and channel: hundredths of a degree or tenths of a centimetre (frame-major;
    /// the last partial frame is dropped).
    values: Vec<i16>,
}

fn motion(input: &Input) -> Option<Motion> {
    let rot = [
        ChannelKind::Zrotation,
        ChannelKind::Xrotation,
        ChannelKind::Yrotation,
    ];
    let mut root = rot.to_vec();
    if input.root_position {
        root.splice(
            0..0,
            [
                ChannelKind::Xposition,
                ChannelKind::Yposition,
                ChannelKind::Zposition,
            ],
        );
    }
    let mut joints = vec![Joint {
        name: "root".into(),
        parent: None,
        offset: [0.0; 3],
        channels: root,
        end_site: false,
    }];
    for j in 0..usize::from(input.children % 4) {
        joints.push(Joint {
            name: format!("j{j}"),
            parent: Some(j),
            offset: [0.0, 10.0, 0.0],
            channels: rot.to_vec(),
            end_site: false,
        });
    }
    let skeleton = Skeleton { joints };
    let channels = skeleton.channel_count();
    let frames = (input.values.len() / channels).min(MAX_FRAMES);
    if frames == 0 {
        return None;
    }
    let kinds = skeleton.channel_kinds();
    let values = input.values[..frames * channels]
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if kinds[i % channels].is_rotation() {
                f64::from(v) / 100.0
            } else {
                f64::from(v) / 10.0
            }
        })
        .collect();
    Some(Motion {
        skeleton,
        frame_time: 1.0 / 30.0,
        values,
    })
}

fuzz_target!(|input: Input| {
    let Some(m) = motion(&input) else { return };
    let codec = [
        CodecChoice::Index,
        CodecChoice::PcaSpline,
        CodecChoice::Predictive,
        CodecChoice::Pattern,
        CodecChoice::Rma,
    ][usize::from(input.codec % 5)];
    let bound_deg = 0.05 + f64::from(input.bound_cdeg % 996) / 100.0;
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound::from_specs(&[BoundSpec::Degrees(bound_deg)]),
        metres_per_unit: METRES_PER_UNIT,
        key_interval: (input.key_interval != 0).then_some(u16::from(input.key_interval)),
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    // An encoder may refuse a motion (it says why); it must not write a clip that breaks the bound.
    let Ok(encoded) = encode(&m, &opts) else {
        return;
    };
    let clip = Clip::parse(&encoded.bytes).expect("the encoder's clip parses");
    let mut player = Player::<PLAYER_WORDS>::new(&clip).expect("the encoder's clip plays");
    assert_eq!(player.frame_count() as usize, m.frames());
    assert_eq!(player.channel_count(), m.channels());
    let kinds = m.skeleton.channel_kinds();
    let mut out = [0i32; MAX_CHANNELS];
    let out = &mut out[..m.channels()];
    let mut f = 0;
    while let Some(i) = player.next_frame(out).expect("every frame decodes") {
        assert_eq!(i as usize, f);
        for ((c, &kind), (&got, &want)) in kinds.iter().enumerate().zip(out.iter().zip(m.frame(f)))
        {
            let decoded = f64::from(got) / scale(kind, METRES_PER_UNIT);
            if kind.is_rotation() {
                let err = wrap_degrees(decoded - want).abs();
                assert!(
                    err <= bound_deg + 1e-9,
                    "{codec:?}: frame {f} channel {c}: {err}° > {bound_deg}° ({want} -> {decoded})"
                );
            } else {
                let err_mm = (decoded - want).abs() * METRES_PER_UNIT * 1000.0;
                assert!(
                    err_mm <= Bound::DEFAULT_TRANSLATION_MM + 1e-9,
                    "{codec:?}: frame {f} channel {c}: {err_mm} mm > {} mm ({want} -> {decoded})",
                    Bound::DEFAULT_TRANSLATION_MM
                );
            }
        }
        f += 1;
    }
    assert_eq!(f, m.frames());
});
