//! Long inputs from one take (issue 15): the take repeated with its root
//! motion continued, so the figure walks on instead of jumping back.
//!
//! Repetition `k` is the take moved in the ground plane (X, Z: BVH is Y-up)
//! and turned about the vertical axis by `ψ_k`, chosen so it starts where
//! repetition `k − 1` ended: `ψ_k` adds the take's own heading change (last
//! frame against first) and one frame's turn, the start point is the
//! previous end plus one frame's step. The root's rotation channels are
//! the Euler angles of `Ry(ψ_k)·R` in the root's own channel order, the
//! solution nearest the previous frame with whole turns kept, so the
//! angles continue past ±180° instead of wrapping; every other rotation
//! channel moves by whole turns to continue from the previous frame. What
//! still differs at the seam (the body's pose, the root's height and tilt)
//! is blended out over the first [`LongOptions::blend_seconds`] of the
//! repetition: the step across the seam is the mean of the steps on either
//! side, and the correction fades with a smoothstep.
//!
//! [`resample`] changes the frame rate (linear interpolation, rotation
//! channels unwrapped first), e.g. for a 30 Hz version of a 120 Hz take.

use crate::fixed::unwrap_degrees;
use crate::motion::{ChannelKind, Motion};

/// How a long input is made.
#[derive(Clone, Debug, PartialEq)]
pub struct LongOptions {
    /// Frames of the result.
    pub frames: usize,
    /// Frames dropped from the take's start before repeating it (CMU's
    /// first frame is a reference pose, not motion: 1 drops it).
    pub skip: usize,
    /// Frame rate of the result; `None` keeps the take's.
    pub fps: Option<f64>,
    /// Seconds over which the pose difference at a seam is blended out.
    pub blend_seconds: f64,
}

impl LongOptions {
    /// The default seam blend, seconds.
    pub const DEFAULT_BLEND_SECONDS: f64 = 0.5;

    /// `frames` frames of the whole take at its own rate.
    pub fn new(frames: usize) -> LongOptions {
        LongOptions {
            frames,
            skip: 0,
            fps: None,
            blend_seconds: Self::DEFAULT_BLEND_SECONDS,
        }
    }
}

/// Why a long input cannot be made from a take.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LongError {
    /// Fewer than two frames left to repeat.
    #[error("the take has {frames} frames after skipping {skip}: at least 2 are needed")]
    TooShort {
        /// Frames of the take.
        frames: usize,
        /// Frames skipped.
        skip: usize,
    },
    /// The skeleton has no channels or no root.
    #[error("the take has no channels")]
    NoChannels,
    /// The root has one of the ground-plane position channels only.
    #[error("the root has an Xposition or a Zposition channel but not both: the ground path cannot turn")]
    OneGroundChannel,
    /// The root's rotation channels cannot express a turn about Y.
    #[error("the root's rotation channels ({0}) cannot express a turn about Y: three axes or Yrotation alone are needed")]
    RootRotation(String),
    /// A frame rate that is not positive.
    #[error("frame rate {0} is not a positive number")]
    BadFps(f64),
}

use crate::rotation::{mul, rot, M3};

/// The angle about world Y of a rotation (its twist about Y), degrees.
fn yaw(r: &M3) -> f64 {
    (r[0][2] - r[2][0]).atan2(r[0][0] + r[2][2]).to_degrees()
}

/// `v` plus whole turns, nearest `near`.
fn near_turn(v: f64, near: f64) -> f64 {
    v + 360.0 * ((near - v) / 360.0).round()
}

/// The angles `(a, b, c)` about `axes` (three different axes) with
/// `R = R_a·R_b·R_c`, of the two solutions (each with whole turns added)
/// the one nearest `prev`.
fn euler(r: &M3, axes: [usize; 3], prev: [f64; 3]) -> [f64; 3] {
    let [i, j, k] = axes;
    // +1 for the cyclic orders XYZ, YZX, ZXY.
    let e = if (j + 3 - i) % 3 == 1 { 1.0 } else { -1.0 };
    let s = (e * r[i][k]).clamp(-1.0, 1.0);
    let (a, c) = if s.abs() > 1.0 - 1e-12 {
        // Gimbal lock: only a ± c is defined; keep c.
        let c = prev[2];
        let rc = mul(r, &rot(k, -c));
        // R·R_c⁻¹ = R_a·R_b with b = ±90°: its column j is R_a's column j.
        let a = (e * rc[k][j]).atan2(rc[j][j]).to_degrees();
        (a, c)
    } else {
        (
            (-e * r[j][k]).atan2(r[k][k]).to_degrees(),
            (-e * r[i][j]).atan2(r[i][i]).to_degrees(),
        )
    };
    let b = s.asin().to_degrees();
    let one = [a, b, c];
    let two = [a + 180.0, 180.0 - b, c + 180.0];
    let fit = |x: [f64; 3]| -> ([f64; 3], f64) {
        let y = [0, 1, 2].map(|n| near_turn(x[n], prev[n]));
        let d = (0..3).map(|n| (y[n] - prev[n]).abs()).sum();
        (y, d)
    };
    let (x, dx) = fit(one);
    let (y, dy) = fit(two);
    if dy < dx {
        y
    } else {
        x
    }
}

/// The root's channels that carry its path and heading.
struct Root {
    /// Xposition and Zposition channels.
    ground: Option<(usize, usize)>,
    /// Rotation channels in listed order: (channel, axis).
    rot: Vec<(usize, usize)>,
}

impl Root {
    fn of(m: &Motion) -> Result<Root, LongError> {
        let joint = m.skeleton.joints.first().ok_or(LongError::NoChannels)?;
        let (mut x, mut z, mut rot) = (None, None, Vec::new());
        for (c, &kind) in joint.channels.iter().enumerate() {
            match kind {
                ChannelKind::Xposition => x = Some(c),
                ChannelKind::Zposition => z = Some(c),
                k if k.is_rotation() => rot.push((c, k.axis())),
                _ => {}
            }
        }
        let ground = match (x, z) {
            (Some(x), Some(z)) => Some((x, z)),
            (None, None) => None,
            _ => return Err(LongError::OneGroundChannel),
        };
        let mut axes: Vec<usize> = rot.iter().map(|&(_, a)| a).collect();
        axes.sort_unstable();
        axes.dedup();
        let turnable = rot.is_empty()
            || (rot.len() == 3 && axes.len() == 3)
            || (rot.len() == 1 && rot[0].1 == 1);
        if !turnable {
            let names: Vec<String> = joint
                .channels
                .iter()
                .filter(|k| k.is_rotation())
                .map(|k| k.to_string())
                .collect();
            return Err(LongError::RootRotation(names.join(" ")));
        }
        Ok(Root { ground, rot })
    }

    fn matrix(&self, row: &[f64]) -> M3 {
        self.rot.iter().fold(
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            |m, &(c, axis)| mul(&m, &rot(axis, row[c])),
        )
    }

    /// Turns `row` (a frame of the take) by `psi` degrees about Y, its
    /// ground position relative to `from` placed at `at`; the rotation
    /// angles continue from `prev` (the frame before).
    fn turn(&self, row: &mut [f64], psi: f64, from: [f64; 2], at: [f64; 2], prev: &[f64]) {
        if let Some((x, z)) = self.ground {
            let (dx, dz) = (row[x] - from[0], row[z] - from[1]);
            let [rx, rz] = turn_xz(psi, [dx, dz]);
            row[x] = at[0] + rx;
            row[z] = at[1] + rz;
        }
        match self.rot.as_slice() {
            [] => {}
            &[(c, _)] => row[c] = near_turn(row[c] + psi, prev[c]),
            &[(c0, a0), (c1, a1), (c2, a2)] => {
                let r = mul(&rot(1, psi), &self.matrix(row));
                let e = euler(&r, [a0, a1, a2], [prev[c0], prev[c1], prev[c2]]);
                row[c0] = e[0];
                row[c1] = e[1];
                row[c2] = e[2];
            }
            _ => unreachable!("Root::of accepts one or three rotation channels"),
        }
    }
}

/// `Ry(psi)` applied to a ground-plane vector `(x, z)`.
fn turn_xz(psi: f64, [x, z]: [f64; 2]) -> [f64; 2] {
    let (s, c) = psi.to_radians().sin_cos();
    [c * x + s * z, -s * x + c * z]
}

fn smoothstep(x: f64) -> f64 {
    let s = x.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// `take` at `fps` frames per second: every channel linearly
/// interpolated (rotation channels unwrapped first), as many frames as fit
/// in the take's duration.
pub fn resample(take: &Motion, fps: f64) -> Result<Motion, LongError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(LongError::BadFps(fps));
    }
    let n = take.channels();
    let frames = take.frames();
    if n == 0 {
        return Err(LongError::NoChannels);
    }
    let kinds = take.skeleton.channel_kinds();
    let series: Vec<Vec<f64>> = (0..n)
        .map(|c| {
            let mut v = take.channel(c);
            if kinds[c].is_rotation() {
                unwrap_degrees(&mut v);
            }
            v
        })
        .collect();
    let duration = frames.saturating_sub(1) as f64 * take.frame_time;
    let step = 1.0 / fps;
    let out_frames = if frames == 0 {
        0
    } else {
        (duration / step + 1e-9).floor() as usize + 1
    };
    let mut values = Vec::with_capacity(out_frames * n);
    for f in 0..out_frames {
        let t = f as f64 * step / take.frame_time;
        let i = (t.floor() as usize).min(frames - 1);
        let u = t - i as f64;
        let j = (i + 1).min(frames - 1);
        values.extend(series.iter().map(|s| s[i] + (s[j] - s[i]) * u));
    }
    Ok(Motion {
        skeleton: take.skeleton.clone(),
        frame_time: step,
        values,
    })
}

/// The take repeated to `opts.frames` frames with its root motion
/// continued (module documentation). The first repetition is the take
/// itself (after `skip` and resampling), value for value.
pub fn long_take(take: &Motion, opts: &LongOptions) -> Result<Motion, LongError> {
    let n = take.channels();
    if n == 0 {
        return Err(LongError::NoChannels);
    }
    let root = Root::of(take)?;
    let skipped = Motion {
        skeleton: take.skeleton.clone(),
        frame_time: take.frame_time,
        values: take.values[(opts.skip * n).min(take.values.len())..].to_vec(),
    };
    let src = match opts.fps {
        Some(fps) => resample(&skipped, fps)?,
        None => skipped,
    };
    let len = src.frames();
    if len < 2 {
        return Err(LongError::TooShort {
            frames: take.frames(),
            skip: opts.skip,
        });
    }
    let kinds = take.skeleton.channel_kinds();
    let last = len - 1;
    let yaws: Vec<f64> = (0..len).map(|f| yaw(&root.matrix(src.frame(f)))).collect();
    let wrap = crate::fixed::wrap_degrees;
    // One repetition's turn: the take's own, plus one frame's.
    let step_turn = 0.5 * (wrap(yaws[last] - yaws[last - 1]) + wrap(yaws[1] - yaws[0]));
    let turn = wrap(yaws[last] - yaws[0]) + step_turn;
    let ground = |f: usize| match root.ground {
        Some((x, z)) => [src.frame(f)[x], src.frame(f)[z]],
        None => [0.0; 2],
    };
    let blend = ((opts.blend_seconds / src.frame_time).round() as usize).min(last);
    let mut out: Vec<f64> = Vec::with_capacity(opts.frames * n);
    out.extend_from_slice(&src.values[..opts.frames.min(len) * n]);
    let mut psi = 0.0;
    let mut rep = vec![0.0; len * n];
    while out.len() < opts.frames * n {
        let have = out.len() / n;
        let prev_last = out[(have - 1) * n..].to_vec();
        let prev_before = out[(have - 2) * n..(have - 1) * n].to_vec();
        // Where this repetition starts: one frame's step past the last.
        let end_step = turn_xz(psi, sub(ground(last), ground(last - 1)));
        psi += turn;
        let start_step = turn_xz(psi, sub(ground(1), ground(0)));
        let at = match root.ground {
            Some((x, z)) => [
                prev_last[x] + 0.5 * (end_step[0] + start_step[0]),
                prev_last[z] + 0.5 * (end_step[1] + start_step[1]),
            ],
            None => [0.0; 2],
        };
        rep.copy_from_slice(&src.values);
        let from = ground(0);
        for f in 0..len {
            let (done, row) = rep.split_at_mut(f * n);
            let prev = match f {
                0 => &prev_last[..],
                _ => &done[(f - 1) * n..],
            };
            root.turn(&mut row[..n], psi, from, at, prev);
        }
        // Whole turns so every rotation channel continues, then the seam's
        // remaining difference blended out.
        for c in 0..n {
            let step = 0.5 * ((prev_last[c] - prev_before[c]) + (rep[n + c] - rep[c]));
            let target = prev_last[c] + step;
            if kinds[c].is_rotation() {
                let shift = near_turn(rep[c], target) - rep[c];
                if shift != 0.0 {
                    for f in 0..len {
                        rep[f * n + c] += shift;
                    }
                }
            }
            let d = target - rep[c];
            for f in 0..blend {
                rep[f * n + c] += d * (1.0 - smoothstep(f as f64 / blend as f64));
            }
        }
        let take_frames = (opts.frames - have).min(len);
        out.extend_from_slice(&rep[..take_frames * n]);
    }
    Ok(Motion {
        skeleton: take.skeleton.clone(),
        frame_time: src.frame_time,
        values: out,
    })
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{Joint, Skeleton};
    use ChannelKind::*;

    /// A root walking a quarter circle (90° of heading over the take) with
    /// a swinging leg, root order Z Y X as CMU's.
    fn arc_walk(order: [ChannelKind; 3]) -> Motion {
        let mut root_ch = vec![Xposition, Yposition, Zposition];
        root_ch.extend(order);
        let skeleton = Skeleton {
            joints: vec![
                Joint {
                    name: "Hips".into(),
                    parent: None,
                    offset: [0.0; 3],
                    channels: root_ch,
                    end_site: false,
                },
                Joint {
                    name: "Leg".into(),
                    parent: Some(0),
                    offset: [0.0, -1.0, 0.0],
                    channels: vec![Zrotation, Yrotation, Xrotation],
                    end_site: false,
                },
                Joint {
                    name: "Leg_End".into(),
                    parent: Some(1),
                    offset: [0.0, -1.0, 0.0],
                    channels: vec![],
                    end_site: true,
                },
            ],
        };
        let frames = 240;
        let mut values = Vec::new();
        for f in 0..frames {
            let t = f as f64 / (frames - 1) as f64;
            let heading = 90.0 * t;
            // Forward is +Z turned by the heading; radius 10.
            let (s, c) = heading.to_radians().sin_cos();
            let (x, z) = (10.0 * (1.0 - c), 10.0 * s);
            let tilt = 3.0 * (t * 20.0).sin();
            let r = mul(&rot(1, heading), &rot(0, tilt));
            let axes = order.map(|k| k.axis());
            let e = euler(&r, axes, [0.0; 3]);
            values.extend([x, 17.0 + 0.3 * (t * 40.0).sin(), z]);
            values.extend(e);
            values.extend([5.0 * (t * 9.0).sin(), 0.0, 30.0 * (t * 40.0).sin()]);
        }
        Motion {
            skeleton,
            frame_time: 1.0 / 120.0,
            values,
        }
    }

    fn root_path(m: &Motion) -> Vec<[f64; 2]> {
        (0..m.frames())
            .map(|f| [m.frame(f)[0], m.frame(f)[2]])
            .collect()
    }

    fn largest_step(p: &[[f64; 2]]) -> f64 {
        p.windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .fold(0.0, f64::max)
    }

    #[test]
    fn euler_reconstructs_every_order() {
        let orders = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        for axes in orders {
            for (a, b, c) in [(10.0, 20.0, 30.0), (-170.0, 80.0, 45.0), (5.0, -89.0, 3.0)] {
                let r = [axes[0], axes[1], axes[2]]
                    .iter()
                    .zip([a, b, c])
                    .fold(rot(0, 0.0), |m, (&ax, v)| mul(&m, &rot(ax, v)));
                let e = euler(&r, axes, [a + 1.0, b - 1.0, c + 0.5]);
                assert!(
                    (e[0] - a).abs() < 1e-6 && (e[1] - b).abs() < 1e-6 && (e[2] - c).abs() < 1e-6,
                    "{axes:?}: {e:?} vs {a} {b} {c}"
                );
            }
        }
    }

    #[test]
    fn frame_count_and_first_repetition() {
        let take = arc_walk([Zrotation, Yrotation, Xrotation]);
        for frames in [1, 100, 240, 241, 1000, 2400] {
            let m = long_take(&take, &LongOptions::new(frames)).unwrap();
            assert_eq!(m.frames(), frames);
            let k = frames.min(240) * take.channels();
            assert_eq!(m.values[..k], take.values[..k]);
        }
        let opts = LongOptions {
            skip: 40,
            ..LongOptions::new(500)
        };
        let m = long_take(&take, &opts).unwrap();
        assert_eq!(m.frames(), 500);
        assert_eq!(m.frame(0), take.frame(40));
        let short = LongOptions {
            skip: 239,
            ..LongOptions::new(500)
        };
        assert!(matches!(
            long_take(&take, &short),
            Err(LongError::TooShort { .. })
        ));
    }

    #[test]
    fn root_path_continues_at_seams_and_heading_winds_on() {
        for order in [
            [Zrotation, Yrotation, Xrotation],
            [Yrotation, Xrotation, Zrotation],
            [Xrotation, Zrotation, Yrotation],
        ] {
            let take = arc_walk(order);
            let reps = 12;
            let m = long_take(&take, &LongOptions::new(240 * reps)).unwrap();
            let inside = largest_step(&root_path(&take));
            let path = root_path(&m);
            // No jump anywhere, seams included.
            let all = largest_step(&path);
            assert!(all <= inside * 1.05, "{order:?}: step {all} vs {inside}");
            // The path keeps turning: a quarter circle per repetition, so 12
            // repetitions close three full circles back near the start.
            let back = path[path.len() - 1];
            assert!(back[0].hypot(back[1]) < 1.5, "{order:?}: ends at {back:?}");
            // Heading (from the written rotation channels) winds past ±180°
            // again and again: unwrapped, it grows by ≈ 90° per repetition.
            let root = Root::of(&m).unwrap();
            let mut yaws: Vec<f64> = (0..m.frames())
                .map(|f| yaw(&root.matrix(m.frame(f))))
                .collect();
            unwrap_degrees(&mut yaws);
            let total = yaws[yaws.len() - 1] - yaws[0];
            assert!(
                (total - 90.0 * reps as f64).abs() < 10.0,
                "{order:?}: {total}"
            );
            // The figure moves on without a jump: no joint steps further at
            // a seam than anywhere in the take, give or take the blend.
            let joint_step = |v: &Motion| {
                let p = crate::kinematics::all_positions(v);
                let j = v.skeleton.joints.len();
                (1..v.frames())
                    .flat_map(|f| (0..j).map(move |i| (f, i)))
                    .map(|(f, i)| {
                        let (a, b) = (p[f * j + i], p[(f - 1) * j + i]);
                        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2))
                            .sqrt()
                    })
                    .fold(0.0, f64::max)
            };
            let (s, t) = (joint_step(&m), joint_step(&take));
            assert!(s <= t * 1.2, "{order:?}: joint step {s} vs {t}");
            // And they are not wrapped: some root angle is past ±180°.
            let beyond = (0..m.frames()).any(|f| m.frame(f)[3..6].iter().any(|a| a.abs() > 540.0));
            assert!(beyond, "{order:?}: angles wrapped");
        }
    }

    #[test]
    fn resampling_keeps_duration_and_values() {
        let take = arc_walk([Zrotation, Yrotation, Xrotation]);
        let m = resample(&take, 30.0).unwrap();
        assert_eq!(m.frames(), 60); // 239/120 s at 30 Hz: 0 … 59/30
        assert!((m.frame_time - 1.0 / 30.0).abs() < 1e-12);
        for f in 0..m.frames() {
            let g = f * 4;
            for (a, b) in m.frame(f).iter().zip(take.frame(g)) {
                assert!((a - b).abs() < 1e-9);
            }
        }
        let opts = LongOptions {
            fps: Some(30.0),
            ..LongOptions::new(1000)
        };
        let long = long_take(&take, &opts).unwrap();
        assert_eq!(long.frames(), 1000);
        assert!((long.frame_time - 1.0 / 30.0).abs() < 1e-12);
        assert!(matches!(resample(&take, 0.0), Err(LongError::BadFps(_))));
    }
}
