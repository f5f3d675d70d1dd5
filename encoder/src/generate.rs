//! A procedural demo clip: an animatronic upper-body puppet on a pedestal
//! greeting its audience.
//!
//! The clip is deterministic (sums of sines and smoothstep envelopes, no
//! random numbers) and exercises the format on purpose: a 6-channel root,
//! joints with ZXY and XYZ rotation orders, a 1-channel jaw, a 2-channel
//! eyelid joint, several End Sites, and constant channels. Lengths are in
//! centimetres (Y up, the figure faces +Z; about 1.35 m tall and 1.5 m
//! across the outstretched arms of the rest pose), 60 Hz, 8 seconds.
//!
//! [`long_take`] makes long inputs of any length from a real take (issue
//! 15): the take repeated with its root path and heading continued.

use crate::motion::ChannelKind::{self, *};
use crate::motion::{Joint, Motion, Skeleton};
use std::f64::consts::{PI, TAU};

mod long;
pub use long::{long_take, resample, LongError, LongOptions};

/// Frames per second of the demo clip.
pub const DEMO_RATE_HZ: usize = 60;
/// Length of the demo clip in seconds.
pub const DEMO_SECONDS: usize = 8;

const ZXY: &[ChannelKind] = &[Zrotation, Xrotation, Yrotation];
const XYZ: &[ChannelKind] = &[Xrotation, Yrotation, Zrotation];

/// The demo clip: 480 frames at 60 Hz of a puppet that sways, looks
/// around, raises its right arm and waves, talks and blinks.
///
/// Joints: `Base` (pedestal, 6 channels: X/Y/Z position then Z X Y
/// rotation), `Torso`, `Neck`, `Head` (with `Jaw`: 1 channel, `Eyelids`:
/// 2 channels, and an End Site), and per side `…Shoulder`, `…UpperArm`,
/// `…ForeArm`, `…Hand` (with an End Site). 42 channels in all.
pub fn animatronic_demo() -> Motion {
    let skeleton = skeleton();
    let channels = skeleton.channel_list();
    let index = |joint: &str, kind: ChannelKind| {
        channels
            .iter()
            .position(|&(j, k)| k == kind && skeleton.joints[j].name == joint)
            .unwrap_or_else(|| panic!("demo skeleton has no channel {joint}.{kind}"))
    };
    // Resolve every animated channel once.
    let track = |joint: &'static str, kind: ChannelKind, f: fn(f64) -> f64| (index(joint, kind), f);
    let tracks = [
        // Pedestal: a slow turntable swivel and a little wobble; the
        // Yposition and X/Z rotation channels stay constant.
        track("Base", Xposition, |t| 0.8 * (TAU * 0.11 * t).sin()),
        track("Base", Zposition, |t| {
            0.5 * (TAU * 0.07 * t + 1.0).sin() - 0.5 * 1f64.sin()
        }),
        track("Base", Yrotation, |t| 12.0 * (TAU * t / 8.0).sin()),
        // Body sway, leaning in while greeting.
        track("Torso", Zrotation, |t| 4.0 * (TAU * 0.25 * t).sin()),
        track("Torso", Xrotation, |t| {
            2.0 * (TAU * 0.18 * t).sin() + 6.0 * wave(t)
        }),
        track("Torso", Yrotation, |t| 0.25 * look(t)),
        track("Neck", Xrotation, |t| 0.4 * nod(t)),
        track("Neck", Yrotation, |t| 0.35 * look(t)),
        track("Neck", Zrotation, |t| 2.0 * (TAU * 0.15 * t + 0.5).sin()),
        track("Head", Zrotation, |t| {
            6.0 * (TAU * 0.15 * t + 0.5).sin() * (1.0 - 0.5 * talk(t))
        }),
        track("Head", Xrotation, nod),
        track("Head", Yrotation, |t| 0.6 * look(t)),
        // Talking: the jaw opens 0–18° at a syllable rate.
        track("Jaw", Xrotation, |t| {
            let syllables = 0.5 - 0.5 * (TAU * 4.3 * t).cos();
            talk(t) * 14.0 * syllables * (1.0 + 0.3 * (TAU * 1.1 * t).sin())
        }),
        track("Eyelids", Xrotation, |t| {
            [0.9, 3.3, 5.0, 7.2]
                .iter()
                .map(|&c| 45.0 * bump(t, c, 0.12))
                .sum()
        }),
        track("Eyelids", Yrotation, |t| 0.2 * look(t)),
        // Left arm rests lowered (rest pose: arms along ±X), breathing and
        // gesturing a little while talking.
        track("LeftShoulder", Zrotation, |t| {
            2.0 * (TAU * 0.25 * t + 1.0).sin()
        }),
        track("LeftUpperArm", Zrotation, |t| {
            -60.0 + 3.0 * (TAU * 0.25 * t + 1.0).sin()
        }),
        track("LeftUpperArm", Yrotation, |t| -10.0 - 5.0 * talk(t)),
        track("LeftForeArm", Yrotation, |t| {
            -20.0 - 12.0 * talk(t) * (0.5 - 0.5 * (TAU * 0.7 * (t - 2.5)).cos())
        }),
        track("LeftForeArm", Zrotation, |t| {
            10.0 + 2.0 * (TAU * 0.2 * t).sin()
        }),
        track("LeftHand", Xrotation, |t| 5.0 * (TAU * 0.3 * t).sin()),
        // Right arm: raise, bend the elbow up and wave.
        track("RightShoulder", Zrotation, |t| -8.0 * wave(t)),
        track("RightShoulder", Yrotation, |t| 4.0 * wave(t)),
        track("RightUpperArm", Zrotation, |t| 60.0 - 85.0 * wave(t)),
        track("RightUpperArm", Yrotation, |t| 10.0 + 15.0 * wave(t)),
        track("RightUpperArm", Xrotation, |t| 2.0 * (TAU * 0.2 * t).sin()),
        track("RightForeArm", Zrotation, |t| {
            -10.0 - 55.0 * wave(t) + 20.0 * wave(t) * waving(t)
        }),
        track("RightForeArm", Yrotation, |t| 15.0 * wave(t)),
        track("RightHand", Zrotation, |t| {
            15.0 * wave(t) * (TAU * 1.6 * (t - 1.5) - 0.6).sin()
        }),
        track("RightHand", Xrotation, |t| -10.0 * wave(t)),
    ];

    let n = skeleton.channel_count();
    let frames = DEMO_RATE_HZ * DEMO_SECONDS;
    let mut values = vec![0.0; frames * n];
    for (f, row) in values.chunks_exact_mut(n).enumerate() {
        let t = f as f64 / DEMO_RATE_HZ as f64;
        for &(c, curve) in &tracks {
            // Round to the precision BVH text keeps, so the clip survives a
            // write/read cycle bit for bit.
            row[c] = (curve(t) * 1e6).round() / 1e6 + 0.0;
        }
    }
    Motion {
        skeleton,
        frame_time: 1.0 / DEMO_RATE_HZ as f64,
        values,
    }
}

/// The puppet's joint hierarchy (centimetres, Y up, facing +Z).
fn skeleton() -> Skeleton {
    let mut joints = Vec::new();
    let mut add =
        |name: &str, parent: Option<usize>, offset: [f64; 3], channels: &[ChannelKind]| {
            joints.push(Joint {
                name: name.to_owned(),
                parent,
                offset,
                channels: channels.to_vec(),
                end_site: false,
            });
            joints.len() - 1
        };
    let base = add(
        "Base",
        None,
        [0.0; 3],
        &[
            Xposition, Yposition, Zposition, Zrotation, Xrotation, Yrotation,
        ],
    );
    let torso = add("Torso", Some(base), [0.0, 72.0, 0.0], ZXY);
    let neck = add("Neck", Some(torso), [0.0, 34.0, 0.0], XYZ);
    let head = add("Head", Some(neck), [0.0, 9.0, 0.0], ZXY);
    let jaw = add("Jaw", Some(head), [0.0, 3.0, 5.0], &[Xrotation]);
    add_end(&mut add, "Jaw", jaw, [0.0, -5.0, 6.0]);
    let lids = add(
        "Eyelids",
        Some(head),
        [0.0, 10.0, 8.0],
        &[Xrotation, Yrotation],
    );
    add_end(&mut add, "Eyelids", lids, [0.0, 0.0, 2.0]);
    add_end(&mut add, "Head", head, [0.0, 20.0, 0.0]);
    for (side, s) in [("Left", 1.0), ("Right", -1.0)] {
        let shoulder = add(
            &format!("{side}Shoulder"),
            Some(torso),
            [6.0 * s, 30.0, 0.0],
            XYZ,
        );
        let upper = add(
            &format!("{side}UpperArm"),
            Some(shoulder),
            [12.0 * s, 0.0, 0.0],
            ZXY,
        );
        let fore = add(
            &format!("{side}ForeArm"),
            Some(upper),
            [26.0 * s, 0.0, 0.0],
            XYZ,
        );
        let hand = add(
            &format!("{side}Hand"),
            Some(fore),
            [22.0 * s, 0.0, 0.0],
            ZXY,
        );
        add_end(&mut add, &format!("{side}Hand"), hand, [9.0 * s, 0.0, 0.0]);
    }
    for j in &mut joints {
        j.end_site = j.name.ends_with("_End");
    }
    Skeleton { joints }
}

/// Adds an End Site (named `<parent>_End`, as the BVH reader names it).
fn add_end(
    add: &mut impl FnMut(&str, Option<usize>, [f64; 3], &[ChannelKind]) -> usize,
    parent_name: &str,
    parent: usize,
    offset: [f64; 3],
) {
    add(&format!("{parent_name}_End"), Some(parent), offset, &[]);
}

/// 0 below `e0`, 1 above `e1`, a smooth cubic in between.
fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let s = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// 1 inside [a, b], fading in and out over `ramp` seconds.
fn window(t: f64, a: f64, b: f64, ramp: f64) -> f64 {
    smoothstep(a, a + ramp, t) * (1.0 - smoothstep(b - ramp, b, t))
}

/// A raised-cosine pulse of half-width `w` centred on `c`.
fn bump(t: f64, c: f64, w: f64) -> f64 {
    let x = (t - c) / w;
    if x.abs() < 1.0 {
        0.5 + 0.5 * (PI * x).cos()
    } else {
        0.0
    }
}

/// Envelope of the right arm's greeting (raised from 1.5 s to 6.2 s).
fn wave(t: f64) -> f64 {
    window(t, 1.5, 6.2, 0.8)
}

/// The side-to-side waving motion itself (−1..1), starting at 0.
fn waving(t: f64) -> f64 {
    (TAU * 1.6 * (t - 1.5)).sin()
}

/// Envelope of talking (2.5 s to 6.5 s).
fn talk(t: f64) -> f64 {
    window(t, 2.5, 6.5, 0.3)
}

/// Where the head looks (yaw, degrees): scanning left and right, settling
/// on the audience while greeting.
fn look(t: f64) -> f64 {
    30.0 * (TAU * 0.2 * t).sin() * (1.0 - 0.7 * wave(t)) - 8.0 * wave(t)
}

/// Head pitch (degrees): a bow while greeting and nods while talking.
fn nod(t: f64) -> f64 {
    -6.0 * wave(t) + 4.0 * talk(t) * (TAU * 0.5 * (t - 2.5)).sin()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{bvh, units};

    #[test]
    fn demo_clip_shape() {
        let m = animatronic_demo();
        assert_eq!(m.frames(), 480);
        assert_eq!(m.channels(), 42);
        assert!((m.frame_time - 1.0 / 60.0).abs() < 1e-15);
        let j = &m.skeleton.joints;
        let find = |n: &str| j.iter().find(|x| x.name == n).map(|x| x.channels.clone());
        assert_eq!(find("Base").map(|c| c.len()), Some(6));
        assert_eq!(find("Jaw"), Some(vec![Xrotation]));
        assert_eq!(find("Eyelids"), Some(vec![Xrotation, Yrotation]));
        assert_eq!(find("Torso").as_deref(), Some(ZXY));
        assert_eq!(find("Neck").as_deref(), Some(XYZ));
        assert_eq!(j.iter().filter(|x| x.end_site).count(), 5);
        assert!(j
            .iter()
            .filter(|x| x.end_site)
            .all(|x| x.channels.is_empty()));
    }

    #[test]
    fn demo_clip_round_trips_and_is_centimetres() {
        let m = animatronic_demo();
        let text = bvh::write_string(&m);
        let back = bvh::parse_str(&text, "demo.bvh").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back.frames(), 480);
        assert_eq!(back.skeleton, m.skeleton);
        assert!((back.frame_time - m.frame_time).abs() < 1e-6);
        assert!(back
            .values
            .iter()
            .zip(&m.values)
            .all(|(a, b)| (a - b).abs() < 1e-9));
        assert_eq!(units::detect(&m), units::LengthUnit::Cm);
        assert_eq!(units::detect(&back), units::LengthUnit::Cm);
        let h = units::skeleton_height(&m);
        assert!((100.0..=170.0).contains(&h), "height {h} cm");
    }

    #[test]
    fn demo_clip_is_smooth_deterministic_and_in_range() {
        let m = animatronic_demo();
        assert_eq!(m, animatronic_demo());
        let n = m.channels();
        let list = m.skeleton.channel_list();
        for (c, &(j, kind)) in list.iter().enumerate() {
            let v = m.channel(c);
            let limit = if kind.is_rotation() { 90.0 } else { 2.0 };
            assert!(
                v.iter().all(|x| x.abs() <= limit),
                "{}.{kind} exceeds ±{limit}",
                m.skeleton.joints[j].name
            );
            let max_step = v
                .windows(2)
                .map(|w| (w[1] - w[0]).abs())
                .fold(0.0, f64::max);
            assert!(
                max_step < 12.0,
                "{}.{kind} jumps {max_step}",
                m.skeleton.joints[j].name
            );
        }
        // The greeting really happens: the right hand rises above the head
        // top's rest height at some point, and the jaw and eyelids move.
        let pos = crate::kinematics::all_positions(&m);
        let joints = m.skeleton.joints.len();
        let idx = |name: &str| m.skeleton.joints.iter().position(|j| j.name == name);
        let (Some(hand), Some(neck)) = (idx("RightHand_End"), idx("Neck")) else {
            panic!("joints missing");
        };
        let highest = (0..m.frames())
            .map(|f| pos[f * joints + hand][1])
            .fold(f64::MIN, f64::max);
        assert!(
            highest > pos[neck][1],
            "hand never rises above the neck: {highest}"
        );
        let moving = |name: &str, kind| {
            let c = list
                .iter()
                .position(|&(j, k)| m.skeleton.joints[j].name == name && k == kind);
            c.is_some_and(|c| (0..m.frames()).any(|f| m.values[f * n + c] > 10.0))
        };
        assert!(moving("Jaw", Xrotation));
        assert!(moving("Eyelids", Xrotation));
    }
}
