use super::*;
use crate::motion::{ChannelKind, Joint, Skeleton};

/// A root and a chain of `n` joints with three rotations each, at 120 Hz:
/// `value(frame, channel)` gives every channel but the root's.
fn motion(frames: usize, n: usize, value: impl Fn(usize, usize) -> f64) -> Motion {
    let rot = vec![
        ChannelKind::Zrotation,
        ChannelKind::Xrotation,
        ChannelKind::Yrotation,
    ];
    let mut joints = vec![Joint {
        name: "root".into(),
        parent: None,
        offset: [0.0; 3],
        channels: vec![
            ChannelKind::Xposition,
            ChannelKind::Yposition,
            ChannelKind::Zposition,
            ChannelKind::Zrotation,
            ChannelKind::Xrotation,
            ChannelKind::Yrotation,
        ],
        end_site: false,
    }];
    for j in 0..n {
        joints.push(Joint {
            name: format!("j{j}"),
            parent: Some(j),
            offset: [0.0, 10.0, 0.0],
            channels: rot.clone(),
            end_site: false,
        });
    }
    let channels = 6 + 3 * n;
    let mut values = Vec::with_capacity(frames * channels);
    for f in 0..frames {
        // The root walks on and turns: the analysis must ignore it.
        values.extend([f as f64 * 0.5, 90.0, 0.0, 0.0, 0.0, f as f64 * 0.3]);
        values.extend((0..3 * n).map(|c| value(f, c)));
    }
    Motion {
        skeleton: Skeleton { joints },
        frame_time: 1.0 / 120.0,
        values,
    }
}

/// A deterministic noise in [-1, 1).
fn noise(seed: u64) -> f64 {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51afd7ed558ccd);
    x ^= x >> 33;
    (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

fn periodic(f: usize, c: usize) -> f64 {
    let t = f as f64 / 120.0;
    40.0 * (std::f64::consts::TAU * t + c as f64 * 0.7).sin()
        + 15.0 * (2.0 * std::f64::consts::TAU * t + c as f64 * 1.3).sin()
}

/// A smooth wander: every channel a sum of incommensurate slow sines.
fn wander(f: usize, c: usize) -> f64 {
    let t = f as f64 / 120.0;
    (0..4)
        .map(|k| {
            let w = 0.37 + 0.61 * (noise((c * 7 + k) as u64) + 1.0);
            30.0 * (w * t * std::f64::consts::TAU + 6.0 * noise((c * 13 + k + 99) as u64)).sin()
        })
        .sum()
}

fn check_cover(clips: &[Clip], frames: usize) {
    let mut at = 0;
    for (n, c) in clips.iter().enumerate() {
        assert_eq!(c.start, at, "clip {n} starts where the last ended");
        assert!(c.end > c.start);
        at = c.end;
        if let ClipKind::Repeated { primary, reference } = &c.kind {
            let p = &clips[*primary];
            assert_eq!(p.kind, ClipKind::Primary);
            assert_eq!(reference.len(), c.end - c.start);
            for &r in reference {
                assert!(
                    (p.start..p.end).contains(&r),
                    "reference {r} outside its primary {}..{}",
                    p.start,
                    p.end
                );
            }
        }
    }
    assert_eq!(at, frames);
}

#[test]
fn a_periodic_take_is_mostly_repeated() {
    // Six cycles of a 1 s movement.
    let frames = 720;
    let m = motion(frames, 5, periodic);
    let a = analyse(&m, &Params::default());
    check_cover(&a.clips, frames);
    let [pri, rep, uni] = a.frames_by_kind();
    eprintln!(
        "k {}, {} paths, clips {}, primary {pri}, repeated {rep}, unique {uni}",
        a.features.k,
        a.paths.len(),
        a.clips.len()
    );
    assert!(!a.paths.is_empty());
    assert!(rep >= frames / 2, "repeated {rep} of {frames}");
    // A repeated frame refers to a frame of the same phase of the cycle.
    for c in &a.clips {
        if let ClipKind::Repeated { reference, .. } = &c.kind {
            for (t, &r) in (c.start..c.end).zip(reference) {
                let phase = (t as i64 - r as i64).rem_euclid(120);
                let off = phase.min(120 - phase);
                assert!(
                    off <= 8,
                    "frame {t} refers to {r}: {off} frames off the cycle"
                );
            }
        }
    }
}

#[test]
fn a_take_that_never_repeats_has_little_repetition() {
    let frames = 720;
    let m = motion(frames, 5, wander);
    let a = analyse(&m, &Params::default());
    check_cover(&a.clips, frames);
    let [pri, rep, uni] = a.frames_by_kind();
    eprintln!(
        "k {}, {} paths, primary {pri}, repeated {rep}, unique {uni}",
        a.features.k,
        a.paths.len()
    );
    assert!(rep < frames / 3, "repeated {rep} of {frames}");
}

#[test]
fn tiny_and_still_takes() {
    for frames in [1, 2, 30] {
        let m = motion(frames, 2, periodic);
        let a = analyse(&m, &Params::default());
        check_cover(&a.clips, frames);
    }
    let m = motion(300, 2, |_, _| 5.0);
    let a = analyse(&m, &Params::default());
    check_cover(&a.clips, 300);
}

#[test]
fn kept_gains_find_what_the_plain_greedy_search_finds() {
    // Two movements of different periods, a stretch of wander between
    // them, and back: many rounds, candidates overlapping, stale gains.
    let frames = 4800;
    let m = motion(frames, 5, |f, c| match f {
        0..1200 => periodic(f, c),
        1200..2400 => periodic(f * 3 / 2, c + 2),
        2400..3000 => wander(f, c),
        _ => periodic(f, c),
    });
    let p = Params::default();
    let features = features(&m, &p);
    let paths = paths::find(&features, &p);
    assert!(paths.len() > 10, "{} paths", paths.len());
    let kept = clips::extract_with(&features, &paths, &p, frames, false);
    let plain = clips::extract_with(&features, &paths, &p, frames, true);
    assert!(kept.len() > 5, "{} clips", kept.len());
    assert_eq!(kept, plain);
}

#[test]
fn long_matches_refer_every_playing_again_to_the_first() {
    // A wander of 8 s played three times: the paper's greedy may cut the
    // later playings into pieces; the long matches make each one repeated
    // clip referring, frame for frame, to the first playing (the third
    // through the second's references, which are never repeated frames).
    let once = 960;
    let m = motion(3 * once, 5, |f, c| wander(f % once, c));
    let a = analyse(&m, &Params::default());
    check_cover(&a.matches, 3 * once);
    let repeated: Vec<&Clip> = a
        .matches
        .iter()
        .filter(|c| matches!(c.kind, ClipKind::Repeated { .. }))
        .collect();
    assert_eq!(repeated.len(), 2, "{:?}", a.matches);
    for c in repeated {
        assert!(c.end - c.start >= once * 9 / 10, "{}..{}", c.start, c.end);
        let ClipKind::Repeated { reference, .. } = &c.kind else {
            unreachable!()
        };
        for (t, &r) in (c.start..c.end).zip(reference) {
            assert!(
                r < once,
                "frame {t} refers to {r}, not to the first playing"
            );
            assert!((t % once).abs_diff(r) <= 4, "frame {t} refers to {r}");
        }
    }
    // A take that never repeats has few long matches.
    let m = motion(720, 5, wander);
    let a = analyse(&m, &Params::default());
    check_cover(&a.matches, 720);
    let rep: usize = a
        .matches
        .iter()
        .filter(|c| matches!(c.kind, ClipKind::Repeated { .. }))
        .map(|c| c.end - c.start)
        .sum();
    assert!(rep < 720 / 3, "repeated {rep} of 720");
}
