//! Power levels (SPEC.md §6.1, `mocap_decoder::power::LevelSampler`): level 0 is `sample_at`,
//! a level samples every `2^L`-th tick of a stretch exactly and interpolates between, a change
//! of level never jumps (the output up to the change is the old level's), and `mocap play
//! --power`'s schedules parse as documented. QEMU parity of the firmware's levels:
//! `qemu_parity.rs`.

use mocap_decoder::power::{level_at, LevelSampler, MAX_LEVEL};
use mocap_decoder::{tick_us, Clip, Error, Player};
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::play::parse_power;
use mocap_encoder::{generate, units};

/// The demo motion at 0.5° in `codec`, its servo rate 50 Hz (0.02 s a tick).
fn demo_clip(codec: CodecChoice, key_interval: Option<u16>) -> Vec<u8> {
    let m = generate::animatronic_demo();
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound::from_specs(&["0.5deg".parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(&m).metres(),
        key_interval,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    encode::encode(&m, &opts).unwrap().bytes
}

const CODECS: [(CodecChoice, Option<u16>); 4] = [
    (CodecChoice::Index, None),
    (CodecChoice::Index, Some(16)),
    (CodecChoice::PcaSpline, None),
    (CodecChoice::Predictive, None),
];

/// 50 Hz in millihertz.
const RATE: u32 = 50_000;

/// The ticks `0..n` through a sampler following `schedule` (`(tick, level)` pairs).
fn run(bytes: &[u8], schedule: &[(u64, u8)], n: u64) -> Vec<Vec<i32>> {
    let clip = Clip::parse(bytes).unwrap();
    let mut player = Player::<200>::new(&clip).unwrap();
    let mut s = LevelSampler::<200>::new(RATE);
    let mut out = vec![0i32; clip.header().channel_count()];
    let schedule: Vec<(u64, u8)> = schedule
        .iter()
        .map(|&(tick, l)| (tick_us(tick, RATE), l))
        .collect();
    (0..n)
        .map(|i| {
            s.set_level(level_at(&schedule, tick_us(i, RATE)));
            s.sample(&mut player, i, &mut out).unwrap();
            out.clone()
        })
        .collect()
}

/// `sample_at` at every tick `0..n`.
fn samples(bytes: &[u8], n: u64) -> Vec<Vec<i32>> {
    let clip = Clip::parse(bytes).unwrap();
    let mut player = Player::<200>::new(&clip).unwrap();
    let mut out = vec![0i32; clip.header().channel_count()];
    (0..n)
        .map(|i| {
            player.sample_at(tick_us(i, RATE), &mut out).unwrap();
            out.clone()
        })
        .collect()
}

/// Ticks of the demo clip at 50 Hz, and a few past its end.
fn ticks(bytes: &[u8]) -> u64 {
    let clip = Clip::parse(bytes).unwrap();
    mocap_decoder::tick_count(clip.header().duration_us(), RATE) + 20
}

#[test]
fn level_zero_is_sample_at() {
    for (codec, k) in CODECS {
        let bytes = demo_clip(codec, k);
        let n = ticks(&bytes);
        assert_eq!(run(&bytes, &[], n), samples(&bytes, n), "{codec:?}");
        assert_eq!(run(&bytes, &[(0, 0)], n), samples(&bytes, n), "{codec:?}");
    }
}

/// At a constant level every `2^L`-th tick is the clip's own pose and the ticks between are
/// §6's interpolation of their neighbours: recomputed here from `sample_at` alone.
#[test]
fn a_level_samples_every_2_pow_l_ticks_and_interpolates_between() {
    for (codec, k) in CODECS {
        let bytes = demo_clip(codec, k);
        let n = ticks(&bytes);
        let exact = samples(&bytes, n + 16);
        for level in 1..=MAX_LEVEL {
            let got = run(&bytes, &[(0, level)], n);
            let step = 1u64 << level;
            for (i, pose) in got.iter().enumerate() {
                let i = i as u64;
                let (s, kk) = (i - i % step, i % step);
                let (a, b) = (&exact[s as usize], &exact[(s + step) as usize]);
                let frac = (kk << (16 - level)) as i64;
                let want: Vec<i32> = a
                    .iter()
                    .zip(b)
                    .map(|(&a, &b)| {
                        a.wrapping_add(((i64::from(b.wrapping_sub(a)) * frac) >> 16) as i32)
                    })
                    .collect();
                assert_eq!(pose, &want, "{codec:?} level {level} tick {i}");
            }
            // The interpolation is close: within the motion of a stretch.
            let worst = got
                .iter()
                .zip(&exact)
                .flat_map(|(g, e)| g.iter().zip(e).map(|(a, b)| (a - b).abs()))
                .max()
                .unwrap();
            assert!(
                worst > 0,
                "{codec:?} level {level}: no interpolation at all"
            );
        }
    }
}

/// A change of level never jumps: up to and including the tick of the change the output is the
/// old level's; from there a new stretch starts from that very pose.
#[test]
fn a_level_change_continues_from_the_pose_output() {
    for (codec, k) in CODECS {
        let bytes = demo_clip(codec, k);
        let n = ticks(&bytes);
        for (from, to, at) in [(3u8, 0u8, 37u64), (0, 4, 50), (4, 1, 83), (2, 3, 130)] {
            let before = run(&bytes, &[(0, from)], n);
            let changed = run(&bytes, &[(0, from), (at, to)], n);
            let at = at as usize;
            // Ticks before the change: the old level's; the change tick too, unless the old
            // level was 0 (then the tick is the clip's own pose either way).
            assert_eq!(
                changed[..=at],
                before[..=at],
                "{codec:?} {from}→{to} at {at}"
            );
            // After the change: the new level's stretches, starting at `at`.
            let step = 1usize << to;
            let exact = samples(&bytes, n + 16);
            for j in (at + step..n as usize).step_by(step) {
                assert_eq!(changed[j], exact[j], "{codec:?} {from}→{to}: tick {j}");
            }
        }
    }
}

#[test]
fn a_sampler_too_small_for_the_clip_is_refused() {
    let bytes = demo_clip(CodecChoice::Index, None);
    let clip = Clip::parse(&bytes).unwrap();
    let channels = clip.header().channel_count();
    let mut player = Player::<200>::new(&clip).unwrap();
    let mut small = LevelSampler::<4>::new(RATE);
    let mut out = vec![0i32; channels];
    assert_eq!(
        small.sample(&mut player, 0, &mut out),
        Err(Error::PlayerCapacity {
            channels,
            capacity: 4
        })
    );
    let mut s = LevelSampler::<200>::new(RATE);
    let mut short = vec![0i32; channels - 1];
    assert_eq!(
        s.sample(&mut player, 0, &mut short),
        Err(Error::PlayerOutputTooSmall {
            expected: channels,
            actual: channels - 1
        })
    );
    // Levels past the cheapest are the cheapest.
    s.set_level(200);
    s.sample(&mut player, 0, &mut out).unwrap();
    assert_eq!(s.level(), MAX_LEVEL);
}

#[test]
fn power_schedules_parse_as_documented() {
    assert_eq!(parse_power("2").unwrap(), vec![(0, 2)]);
    assert_eq!(
        parse_power("0, 3@2s,1@2.5,4@300000ms").unwrap(),
        vec![(0, 0), (2_000_000, 3), (2_500_000, 1), (300_000_000, 4)]
    );
    assert_eq!(parse_power("1@0.0005s").unwrap(), vec![(500, 1)]);
    for (bad, says) in [
        ("5", "not 0 to 4"),
        ("x", "not 0 to 4"),
        ("1@", "is not a time"),
        ("1@-2s", "is not a time"),
        ("1@2h", "is not a time"),
        ("1@2s,0@1s", "goes back in time"),
        ("", "not 0 to 4"),
    ] {
        let e = parse_power(bad).unwrap_err();
        assert!(e.contains(says), "{bad:?}: {e}");
    }
    assert_eq!(level_at(&[(100, 2), (200, 3)], 99), 0);
    assert_eq!(level_at(&[(100, 2), (200, 3)], 100), 2);
    assert_eq!(level_at(&[(100, 2), (200, 3)], 10_000), 3);
}
