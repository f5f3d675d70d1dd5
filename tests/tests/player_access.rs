//! The three ways of playing agree: random access in any order equals
//! sequential decoding, and `sample_at` follows SPEC.md §6 exactly (frame
//! times give frames, other times the fixed-point interpolation, past the
//! end the last frame).

use mocap_decoder::{Clip, Player};
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{clipfile, generate, units};

fn demo_clip(codec: CodecChoice, key_interval: Option<u16>) -> Vec<u8> {
    clip_of(&generate::animatronic_demo(), codec, "0.5deg", key_interval)
}

fn clip_of(
    m: &mocap_encoder::motion::Motion,
    codec: CodecChoice,
    bound: &str,
    key_interval: Option<u16>,
) -> Vec<u8> {
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound::from_specs(&[bound.parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(m).metres(),
        key_interval,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    encode::encode(m, &opts).unwrap().bytes
}

/// Frame codecs and their key intervals (index) or block lengths
/// (predictive) under test.
const FRAME_CODECS: [(CodecChoice, u16); 7] = [
    (CodecChoice::Index, 0),
    (CodecChoice::Index, 5),
    (CodecChoice::Index, 16),
    (CodecChoice::Predictive, 1),
    (CodecChoice::Predictive, 7),
    (CodecChoice::Predictive, 1000),
    (CodecChoice::Pattern, 0),
];

#[test]
fn random_access_equals_sequential() {
    for (codec, k) in FRAME_CODECS {
        let bytes = demo_clip(codec, Some(k));
        let clip = Clip::parse(&bytes).unwrap();
        let all = clipfile::decode_all(&clip).unwrap();
        let n = clip.header().channel_count();
        let frames = clip.header().frame_count();
        let mut player = Player::<160>::new(&clip).unwrap();
        let mut out = [0i32; 64];
        // A fixed pseudo-random order that jumps back and forth.
        let mut f = 7u32;
        for _ in 0..600 {
            f = (f * 1103 + 12345) % frames;
            player.frame(f, &mut out).unwrap();
            let i = f as usize * n;
            assert_eq!(&out[..n], &all[i..i + n], "{codec:?} K={k} frame {f}");
        }
    }
}

/// `rma` (SPEC.md §12) on the demo played twice, its second playing a
/// repeated clip: any frame in any order is the sequential decode's, and
/// `sample_at` at a frame's time is that frame (between frames it fades
/// the clip in and out, §12.4: the spec examples check that).
#[test]
fn rma_random_access_equals_sequential() {
    let twice = mocap_tests::demo_played_twice();
    let bytes = clip_of(&twice, CodecChoice::Rma, "20mm", None);
    let clip = Clip::parse(&bytes).unwrap();
    let info = mocap_encoder::codec::rma::section::inspect_clip(&bytes).expect("an rma section");
    assert_eq!(info.repeated, 1, "the second playing is a repeated clip");
    // Read back as written: it lies in the second playing and refers to
    // the first.
    let kept = &info.clips[0];
    let half = twice.frames() as u32 / 2;
    assert_eq!(info.repeated_frames, (kept.last - kept.start + 1) as usize);
    assert!(
        kept.primary.1 < kept.start && kept.primary.1 < half && kept.last >= half,
        "{kept:?}"
    );
    let all = clipfile::decode_all(&clip).unwrap();
    let h = clip.header();
    let (n, frames, period) = (
        h.channel_count(),
        h.frame_count(),
        u64::from(h.frame_time_ns()),
    );
    let mut player = Player::<512>::new(&clip).unwrap();
    let mut out = [0i32; 64];
    let mut f = 7u32;
    for _ in 0..900 {
        f = (f * 1103 + 12345) % frames;
        player.frame(f, &mut out).unwrap();
        let i = f as usize * n;
        assert_eq!(&out[..n], &all[i..i + n], "rma frame {f}");
    }
    // A player too small to cache the body whole (its cursor, the scratch
    // pose, then a few words for the body at t and none for Ref(t)) plays
    // the same frames.
    let mut small = Player::<{ 2 + 42 + 60 }>::new(&clip).unwrap();
    for _ in 0..900 {
        f = (f * 1103 + 12345) % frames;
        small.frame(f, &mut out).unwrap();
        let i = f as usize * n;
        assert_eq!(&out[..n], &all[i..i + n], "rma frame {f}, small player");
    }
    for f in (0..frames).rev().step_by(7).chain(0..frames) {
        // Frame times rounded up to whole microseconds fall under 1 µs
        // after the frame: within two counts of it (the body's step and the
        // clip's fade each round down once), or of the step to the next
        // frame scaled by that microsecond.
        player
            .sample_at((u64::from(f) * period).div_ceil(1000), &mut out)
            .unwrap();
        let i = f as usize * n;
        let j = (f as usize + 1).min(frames as usize - 1) * n;
        for c in 0..n {
            let (o, a, b) = (out[c], all[i + c], all[j + c]);
            let slack = 2 + a.abs_diff(b) / 4096;
            assert!(
                o.abs_diff(a) <= slack,
                "rma sample at frame {f} channel {c}: {o} vs {a}"
            );
        }
    }
}

#[test]
fn sample_at_follows_the_spec() {
    for (codec, k) in [
        (CodecChoice::Index, 8),
        (CodecChoice::Predictive, 7),
        (CodecChoice::Predictive, 1000),
        (CodecChoice::Pattern, 0),
    ] {
        sample_at_follows_the_spec_for(codec, k);
    }
}

fn sample_at_follows_the_spec_for(codec: CodecChoice, k: u16) {
    let bytes = demo_clip(codec, Some(k));
    let clip = Clip::parse(&bytes).unwrap();
    let all = clipfile::decode_all(&clip).unwrap();
    let h = clip.header();
    let (n, frames, period) = (
        h.channel_count(),
        h.frame_count() as usize,
        u64::from(h.frame_time_ns()),
    );
    let mut player = Player::<160>::new(&clip).unwrap();
    let mut out = [0i32; 64];
    let want_at = |t_us: u64, c: usize| {
        let ns = t_us * 1000;
        let i = (ns / period) as usize;
        let frac = (((ns % period) << 16) / period) as i64;
        if i >= frames - 1 {
            all[(frames - 1) * n + c]
        } else {
            let (a, b) = (all[i * n + c], all[(i + 1) * n + c]);
            a.wrapping_add(((i64::from(b.wrapping_sub(a)) * frac) >> 16) as i32)
        }
    };
    // 50 Hz servo ticks over a 60 Hz clip, plus times past the end; then
    // 100 Hz (two samples per frame interval) and times in a scrambled order.
    let ticks: Vec<u64> = (0..(frames as u64 * 60 / 50 + 20))
        .map(|tick| tick * 20_000)
        .chain((0..frames as u64 * 2).map(|tick| tick * 10_000 + 3))
        .chain((0..300u64).map(|i| (i * 7919 % 997) * 8_123))
        .collect();
    for t_us in ticks {
        player.sample_at(t_us, &mut out).unwrap();
        for (c, &o) in out[..n].iter().enumerate() {
            assert_eq!(o, want_at(t_us, c), "{codec:?} t={t_us} µs channel {c}");
        }
    }
    // Time 0 is frame 0; a time within the last nanoseconds before frame f
    // is frame f - 1 plus almost the whole step; far past the end holds.
    player.sample_at(0, &mut out).unwrap();
    assert_eq!(&out[..n], &all[..n]);
    player.sample_at(u64::MAX, &mut out).unwrap();
    assert_eq!(&out[..n], &all[(frames - 1) * n..]);
}

#[test]
fn predictive_player_needs_its_state() {
    let bytes = demo_clip(CodecChoice::Predictive, None);
    let clip = Clip::parse(&bytes).unwrap();
    let n = clip.header().channel_count();
    assert_eq!(
        Player::<64>::new(&clip).unwrap_err(),
        mocap_decoder::Error::PlayerStateTooSmall {
            needed: 3 * n + 19,
            capacity: 64
        }
    );
    assert!(Player::<{ 3 * 42 + 19 }>::new(&clip).is_ok());
    assert_eq!(n, 42);
}

fn pca_clip() -> Vec<u8> {
    let m = generate::animatronic_demo();
    let opts = EncodeOptions {
        key_bits: None,
        codec: CodecChoice::PcaSpline,
        bound: Bound::from_specs(&["0.5deg".parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(&m).metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    encode::encode(&m, &opts).unwrap().bytes
}

#[test]
fn pca_spline_access_orders_agree() {
    let bytes = pca_clip();
    let clip = Clip::parse(&bytes).unwrap();
    let all = clipfile::decode_all(&clip).unwrap();
    let h = clip.header();
    let (n, frames, period) = (
        h.channel_count(),
        h.frame_count(),
        u64::from(h.frame_time_ns()),
    );
    let mut player = Player::<64>::new(&clip).unwrap();
    let mut out = [0i32; 64];
    let mut f = 3u32;
    for _ in 0..600 {
        f = (f * 1103 + 12345) % frames;
        player.frame(f, &mut out).unwrap();
        let i = f as usize * n;
        assert_eq!(&out[..n], &all[i..i + n], "frame {f}");
        // A frame's own time is that frame (exactly when the time is a
        // whole microsecond, within a unit when it was rounded).
        let ns = u64::from(f) * period;
        player.sample_at(ns / 1000, &mut out).unwrap();
        for c in 0..n {
            let d = (out[c] - all[i + c]).abs();
            assert!(
                d <= i32::from(ns % 1000 != 0),
                "sample_at frame {f} channel {c}: {d}"
            );
        }
    }
    // sample_at does not depend on what was played before: 50 Hz ticks in
    // order and in a scrambled order give the same poses.
    let ticks: Vec<u64> = (0..(u64::from(frames) * 50 / 60 + 5))
        .map(|t| t * 20_000)
        .collect();
    let mut in_order = Vec::new();
    for &t in &ticks {
        player.sample_at(t, &mut out).unwrap();
        in_order.push(out[..n].to_vec());
    }
    let mut fresh = Player::<64>::new(&clip).unwrap();
    let mut k = 11usize;
    for _ in 0..ticks.len() {
        k = (k * 7919 + 13) % ticks.len();
        fresh.sample_at(ticks[k], &mut out).unwrap();
        assert_eq!(&out[..n], &in_order[k][..], "t={} µs", ticks[k]);
    }
    player.sample_at(u64::MAX, &mut out).unwrap();
    assert_eq!(&out[..n], &all[(frames as usize - 1) * n..]);
}

/// Poses from a `Player<N>` at frames and at 50 Hz ticks, visited in a
/// scrambled order.
fn scrambled_poses<const N: usize>(clip: &Clip<'_>, visits: &[(bool, u64)]) -> Vec<Vec<i32>> {
    let mut player = Player::<N>::new(clip).unwrap();
    let n = player.channel_count();
    let mut out = vec![0i32; n];
    visits
        .iter()
        .map(|&(frame, at)| {
            if frame {
                player.frame(at as u32, &mut out).unwrap();
            } else {
                player.sample_at(at, &mut out).unwrap();
            }
            out.clone()
        })
        .collect()
}

/// The pca-spline cache (the player's state) only saves work: a player too
/// small to cache anything, one that caches some groups, and one that
/// caches everything give the same poses (SPEC.md §6), including blend
/// windows and patches of a real multi-segment clip.
#[test]
fn pca_spline_cache_size_does_not_change_output() {
    let mut clips = vec![("demo".to_string(), pca_clip())];
    if let Some(files) = mocap_tests::corpus_files("cmu") {
        let path = files.iter().find(|p| p.ends_with("05_04.bvh")).unwrap();
        let m = mocap_encoder::bvh::read_file(path).unwrap();
        let opts = EncodeOptions {
            key_bits: None,
            codec: CodecChoice::PcaSpline,
            bound: Bound::from_specs(&[
                "50mm".parse::<BoundSpec>().unwrap(),
                "arms:10mm".parse::<BoundSpec>().unwrap(),
            ]),
            metres_per_unit: units::detect(&m).metres(),
            key_interval: None,
            index_layout: Default::default(),
            pattern: Default::default(),
        };
        clips.push(("05_04".into(), encode::encode(&m, &opts).unwrap().bytes));
    }
    for (name, bytes) in &clips {
        let clip = Clip::parse(bytes).unwrap();
        let h = clip.header();
        let frames = u64::from(h.frame_count());
        let duration_us = frames * u64::from(h.frame_time_ns()) / 1000;
        // Sequential frames, then scrambled frames and ticks.
        let mut visits: Vec<(bool, u64)> = (0..frames).map(|f| (true, f)).collect();
        let mut x = 7u64;
        for i in 0..3 * frames {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let tick = (x >> 33) % (duration_us / 20_000 + 2);
            visits.push(if i % 2 == 0 {
                (true, (x >> 20) % frames)
            } else {
                (false, tick * 20_000 + (x >> 40) % 7)
            });
        }
        let full = scrambled_poses::<4096>(&clip, &visits);
        // The smallest player (N = channels) caches a few groups at most;
        // the middle one most groups but not the constants.
        let (small, middle) = if h.channel_count() <= 42 {
            (
                scrambled_poses::<42>(&clip, &visits),
                scrambled_poses::<64>(&clip, &visits),
            )
        } else {
            (
                scrambled_poses::<96>(&clip, &visits),
                scrambled_poses::<140>(&clip, &visits),
            )
        };
        for (i, want) in full.iter().enumerate() {
            assert_eq!(&small[i], want, "{name}: visit {i} {:?}, small", visits[i]);
            assert_eq!(
                &middle[i], want,
                "{name}: visit {i} {:?}, middle",
                visits[i]
            );
        }
        let all = clipfile::decode_all(&clip).unwrap();
        let n = h.channel_count();
        for f in 0..frames as usize {
            assert_eq!(&full[f][..], &all[f * n..(f + 1) * n], "{name}: frame {f}");
        }
    }
}

/// `rma` with few repeated frames (the demo, then its first 120 frames
/// again: 20 % repeated): a player without room for the scratch pose beside
/// the body's whole cache lays the scratch over that cache (SPEC §12.3);
/// whatever the player's size, frames in order, in any order and samples
/// between frames are the large player's, which keeps them apart.
#[test]
fn rma_scratch_over_the_cache_plays_the_same() {
    let mut m = generate::animatronic_demo();
    let c = m.channels();
    let head = m.values[..120 * c].to_vec();
    m.values.extend_from_slice(&head);
    let bytes = clip_of(&m, CodecChoice::Rma, "20mm", None);
    let clip = Clip::parse(&bytes).unwrap();
    let info = mocap_encoder::codec::rma::section::inspect_clip(&bytes).expect("an rma section");
    let frames = clip.header().frame_count();
    assert!(info.repeated >= 1, "the replay is a repeated clip");
    assert!(info.repeated_frames * 4 <= frames as usize, "{info:?}");
    let all = clipfile::decode_all(&clip).unwrap();
    let period = u64::from(clip.header().frame_time_ns());
    // Times: every frame, then between frames, then random.
    let times: Vec<u64> = (0..u64::from(frames))
        .map(|f| f * period / 1000)
        .chain((0..u64::from(frames)).map(|f| (f * period + period / 3) / 1000))
        .chain(
            (0..2000u64).map(|i| (i * 7919 * period / 1000) % (u64::from(frames) * period / 1000)),
        )
        .collect();
    let mut big = Player::<4096>::new(&clip).unwrap();
    let mut want = vec![[0i32; 64]; times.len()];
    for (w, &t) in want.iter_mut().zip(&times) {
        big.sample_at(t, w).unwrap();
    }
    fn check<const N: usize>(clip: &Clip, all: &[i32], times: &[u64], want: &[[i32; 64]]) {
        let n = clip.header().channel_count();
        let mut p = Player::<N>::new(clip).unwrap();
        let mut out = [0i32; 64];
        for f in 0..clip.header().frame_count() {
            p.frame(f, &mut out).unwrap();
            assert_eq!(
                &out[..n],
                &all[f as usize * n..][..n],
                "frame {f}, Player<{N}>"
            );
        }
        for (w, &t) in want.iter().zip(times) {
            p.sample_at(t, &mut out).unwrap();
            assert_eq!(&out[..n], &w[..n], "sample at {t} µs, Player<{N}>");
        }
    }
    check::<{ 2 + 42 }>(&clip, &all, &times, &want);
    check::<{ 2 + 42 + 40 }>(&clip, &all, &times, &want);
    check::<{ 2 + 42 + 150 }>(&clip, &all, &times, &want);
    check::<300>(&clip, &all, &times, &want);
    check::<400>(&clip, &all, &times, &want);
}

/// `pattern` with entropy-coded segment lists (SPEC.md §11.1b) in blocks
/// of 4, 8 and 64 segments (the demo played on to 2 000 frames): a player with room for every node's cursor
/// (sequential steps through the streams), one without (a binary search
/// over the blocks and a walk through one for every frame), frames in a
/// jumping order and `sample_at` at 50 Hz in a scrambled order all give
/// the sequential decode's poses.
#[test]
fn pattern_coded_lists_play_alike_in_any_order() {
    let demo = generate::animatronic_demo();
    let m = generate::long_take(&demo, &generate::LongOptions::new(2000)).unwrap();
    for bits in [Some(2u8), Some(3), None] {
        let opts = EncodeOptions {
            key_bits: None,
            codec: CodecChoice::Pattern,
            bound: Bound::from_specs(&["0.5deg".parse::<BoundSpec>().unwrap()]),
            metres_per_unit: units::detect(&m).metres(),
            key_interval: None,
            index_layout: Default::default(),
            pattern: mocap_encoder::codec::pattern::PatternOptions {
                block_bits: bits,
                ..Default::default()
            },
        };
        let bytes = encode::encode(&m, &opts).unwrap().bytes;
        let clip = Clip::parse(&bytes).unwrap();
        let section = clip
            .sections()
            .find(|s| s.id == mocap_encoder::codec::pattern::SECTION_ID)
            .unwrap();
        let info = mocap_encoder::codec::pattern::inspect(section.bytes).unwrap();
        assert!(info.coded_lists, "bits {bits:?}: the lists are coded");
        let segments: usize = info.nodes.iter().map(|n| n[1]).sum();
        eprintln!(
            "bits {bits:?}: {segments} segments, {} nodes",
            info.nodes.len()
        );
        assert!(
            segments > 8 * info.nodes.len(),
            "bits {bits:?}: {segments} segments"
        );
        let all = clipfile::decode_all(&clip).unwrap();
        let h = clip.header();
        let (n, frames) = (h.channel_count(), h.frame_count());
        // Room for the cursors (channels + 12 words a node) and none (the
        // demo has 42 channels and 5 nodes).
        let mut visits = Vec::new();
        let mut f = 5u32;
        for i in 0..400u64 {
            f = (f * 1103 + 12345) % frames;
            visits.push((
                i % 3 != 0,
                if i % 3 != 0 { u64::from(f) } else { i * 20_000 },
            ));
        }
        let big = scrambled_poses::<512>(&clip, &visits);
        assert!(n + 12 * info.nodes.len() > 48);
        let small = scrambled_poses::<48>(&clip, &visits);
        assert_eq!(big, small, "bits {bits:?}");
        for (&(frame, at), pose) in visits.iter().zip(&big) {
            if frame {
                let i = at as usize * n;
                assert_eq!(&pose[..], &all[i..i + n], "bits {bits:?} frame {at}");
            }
        }
        // In order, every frame.
        let mut player = Player::<512>::new(&clip).unwrap();
        let mut out = vec![0i32; n];
        for f in 0..frames {
            player.next_frame(&mut out).unwrap();
            let i = f as usize * n;
            assert_eq!(
                &out[..],
                &all[i..i + n],
                "bits {bits:?} in order, frame {f}"
            );
        }
    }
}
