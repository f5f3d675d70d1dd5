//! Forward kinematics: world positions of every joint for one frame.
//!
//! A joint's local transform is `T(OFFSET + position channels) · R`, where
//! `R = R_first · R_second · …` is the product of elementary rotations in the
//! order the CHANNELS line lists them (degrees, right-handed, column
//! vectors), and `world = parent_world · local`. Position channels add to
//! the OFFSET along their axis, whatever their place in the CHANNELS list.
//! End Sites have no channels, so their transform is `T(OFFSET)`.
//!
//! The skeleton must be in the documented depth-first order (a parent
//! before its children), as [`crate::bvh`] builds it.

use crate::motion::{ChannelKind, Skeleton};
use std::cell::RefCell;

/// A 3×3 rotation matrix stored as three columns: `m[c][r]`.
pub type Mat3 = [[f64; 3]; 3];

/// The identity matrix.
pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

thread_local! {
    /// Reused world rotations for [`joint_positions`], so that steady-state
    /// calls do not allocate.
    static SCRATCH: RefCell<Vec<Mat3>> = const { RefCell::new(Vec::new()) };
}

/// Fills `out` with the world position of every joint (End Sites included),
/// in skeleton units, for one frame of channel values.
///
/// `out` is cleared and refilled; reuse it across calls to avoid
/// allocation. Panics if `frame` has fewer values than the skeleton has
/// channels.
pub fn joint_positions(skeleton: &Skeleton, frame: &[f64], out: &mut Vec<[f64; 3]>) {
    SCRATCH.with(|s| match s.try_borrow_mut() {
        Ok(mut rotations) => joint_transforms(skeleton, frame, &mut rotations, out),
        // Only reachable on re-entrance; fall back to a local buffer.
        Err(_) => joint_transforms(skeleton, frame, &mut Vec::new(), out),
    });
}

/// Like [`joint_positions`], but also returns each joint's world rotation
/// (`rotations[j]` maps joint `j`'s local axes to world axes).
pub fn joint_transforms(
    skeleton: &Skeleton,
    frame: &[f64],
    rotations: &mut Vec<Mat3>,
    positions: &mut Vec<[f64; 3]>,
) {
    let joints = &skeleton.joints;
    rotations.clear();
    rotations.resize(joints.len(), IDENTITY);
    positions.clear();
    positions.resize(joints.len(), [0.0; 3]);
    let mut k = 0;
    for (j, joint) in joints.iter().enumerate() {
        let (mut r, origin) = match joint.parent {
            Some(p) => {
                debug_assert!(p < j, "skeleton is not in depth-first order");
                (rotations[p], positions[p])
            }
            None => (IDENTITY, [0.0; 3]),
        };
        let mut t = joint.offset;
        for &kind in &joint.channels {
            let v = frame[k];
            k += 1;
            if kind.is_rotation() {
                rotate(&mut r, kind, v.to_radians());
            } else {
                t[kind.axis()] += v;
            }
        }
        // The joint sits at parent_origin + parent_rotation · t.
        let pr = match joint.parent {
            Some(p) => &rotations[p],
            None => &IDENTITY,
        };
        positions[j] = [
            origin[0] + pr[0][0] * t[0] + pr[1][0] * t[1] + pr[2][0] * t[2],
            origin[1] + pr[0][1] * t[0] + pr[1][1] * t[1] + pr[2][1] * t[2],
            origin[2] + pr[0][2] * t[0] + pr[1][2] * t[1] + pr[2][2] * t[2],
        ];
        rotations[j] = r;
    }
}

/// Post-multiplies `m` by the elementary rotation of `angle` radians about
/// the axis of `kind`: `m ← m · R_axis(angle)`.
fn rotate(m: &mut Mat3, kind: ChannelKind, angle: f64) {
    let (s, c) = angle.sin_cos();
    // Column pair (a, b) of the plane the rotation acts in, such that
    // R maps e_a → c·e_a + s·e_b and e_b → −s·e_a + c·e_b.
    let (a, b) = match kind.axis() {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let (ca, cb) = (m[a], m[b]);
    for i in 0..3 {
        m[a][i] = c * ca[i] + s * cb[i];
        m[b][i] = -s * ca[i] + c * cb[i];
    }
}

/// World positions of every joint for every frame: `frames × joints`,
/// row-major (`result[f * joints + j]`).
pub fn all_positions(m: &crate::motion::Motion) -> Vec<[f64; 3]> {
    let n = m.skeleton.joints.len();
    let mut all = Vec::with_capacity(m.frames() * n);
    let mut one = Vec::with_capacity(n);
    for f in 0..m.frames() {
        joint_positions(&m.skeleton, m.frame(f), &mut one);
        all.extend_from_slice(&one);
    }
    all
}

/// Calls `f(ancestor, distance²)` for every joint and each of its
/// ancestors, with rest-pose (all channels zero) positions.
fn for_each_ancestor(skeleton: &Skeleton, mut f: impl FnMut(usize, f64)) {
    let rest = vec![0.0; skeleton.channel_count()];
    let mut pos = Vec::new();
    joint_positions(skeleton, &rest, &mut pos);
    for (j, p) in pos.iter().enumerate() {
        let mut ancestor = skeleton.joints[j].parent;
        while let Some(a) = ancestor {
            let q = pos[a];
            f(
                a,
                (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2),
            );
            ancestor = skeleton.joints[a].parent;
        }
    }
}

/// For each joint, the largest rest-pose (all channels zero) distance from
/// that joint to any of its descendants, End Sites included, in skeleton
/// units; 0 for leaves. A rotation error of θ radians at a joint moves its
/// subtree by at most `lever_arms[j] · θ`.
pub fn lever_arms(skeleton: &Skeleton) -> Vec<f64> {
    let mut lever = vec![0.0f64; skeleton.joints.len()];
    for_each_ancestor(skeleton, |a, d2| lever[a] = lever[a].max(d2.sqrt()));
    lever
}

/// For each joint, the RMS over *all* joints of the rest-pose distance
/// from that joint to each of its descendants (non-descendants count as
/// 0): a rotation error of θ radians at the joint adds at most
/// `θ · rms_levers[j]` to the frame's RMS joint error (ARMS).
pub fn rms_levers(skeleton: &Skeleton) -> Vec<f64> {
    let mut sum = vec![0.0f64; skeleton.joints.len()];
    for_each_ancestor(skeleton, |a, d2| sum[a] += d2);
    let n = skeleton.joints.len().max(1) as f64;
    sum.into_iter().map(|s| (s / n).sqrt()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::ChannelKind::*;
    use crate::motion::{Joint, Motion};

    fn joint(name: &str, parent: Option<usize>, offset: [f64; 3], ch: &[ChannelKind]) -> Joint {
        Joint {
            name: name.into(),
            parent,
            offset,
            channels: ch.to_vec(),
            end_site: false,
        }
    }

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9)
    }

    fn positions(sk: &Skeleton, frame: &[f64]) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        joint_positions(sk, frame, &mut out);
        out
    }

    #[test]
    fn chain_rotated_about_z() {
        let sk = Skeleton {
            joints: vec![
                joint("A", None, [1.0, 2.0, 3.0], &[Zrotation]),
                joint("B", Some(0), [1.0, 0.0, 0.0], &[]),
            ],
        };
        let p = positions(&sk, &[90.0]);
        assert!(close(p[0], [1.0, 2.0, 3.0]));
        // +90° about Z takes +X to +Y (right-handed).
        assert!(close(p[1], [1.0, 3.0, 3.0]), "{:?}", p[1]);
        let p = positions(&sk, &[-90.0]);
        assert!(close(p[1], [1.0, 1.0, 3.0]), "{:?}", p[1]);
    }

    #[test]
    fn rotation_order_follows_channels_line() {
        // Child at +X; rotate 90° about Z and 90° about Y.
        let make = |order: &[ChannelKind]| Skeleton {
            joints: vec![
                joint("A", None, [0.0; 3], order),
                joint("B", Some(0), [1.0, 0.0, 0.0], &[]),
            ],
        };
        // Z then Y: R = Rz·Ry; Ry(90) takes +X to −Z, Rz leaves −Z alone.
        let p = positions(&make(&[Zrotation, Yrotation]), &[90.0, 90.0]);
        assert!(close(p[1], [0.0, 0.0, -1.0]), "{:?}", p[1]);
        // Y then Z: R = Ry·Rz; Rz(90) takes +X to +Y, Ry leaves +Y alone.
        let p = positions(&make(&[Yrotation, Zrotation]), &[90.0, 90.0]);
        assert!(close(p[1], [0.0, 1.0, 0.0]), "{:?}", p[1]);

        // Full three-axis orders: ZYX vs XYZ with the same angles differ.
        let zyx = make(&[Zrotation, Yrotation, Xrotation]);
        let xyz = make(&[Xrotation, Yrotation, Zrotation]);
        let a = positions(&zyx, &[90.0, 90.0, 90.0]);
        // ZYX: values are (z, y, x) = 90 each; R = Rz·Ry·Rx, Rx keeps +X.
        assert!(close(a[1], [0.0, 0.0, -1.0]), "{:?}", a[1]);
        let b = positions(&xyz, &[90.0, 90.0, 90.0]);
        // XYZ: R = Rx·Ry·Rz: +X → +Y (Rz) → +Y (Ry) → +Z (Rx).
        assert!(close(b[1], [0.0, 0.0, 1.0]), "{:?}", b[1]);
    }

    #[test]
    fn rotations_are_orthonormal() {
        let sk = Skeleton {
            joints: vec![joint(
                "A",
                None,
                [0.0; 3],
                &[Zrotation, Xrotation, Yrotation],
            )],
        };
        let (mut r, mut p) = (Vec::new(), Vec::new());
        joint_transforms(&sk, &[33.0, -71.0, 128.0], &mut r, &mut p);
        let m = r[0];
        for a in 0..3 {
            for b in 0..3 {
                let dot: f64 = (0..3).map(|i| m[a][i] * m[b][i]).sum();
                assert!((dot - f64::from(u8::from(a == b))).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn six_channel_non_root_joint() {
        let sk = Skeleton {
            joints: vec![
                joint(
                    "Root",
                    None,
                    [0.0; 3],
                    &[Xposition, Yposition, Zposition, Yrotation],
                ),
                joint(
                    "Mid",
                    Some(0),
                    [0.0, 1.0, 0.0],
                    &[
                        Zrotation, Xposition, Yposition, Zposition, Xrotation, Yrotation,
                    ],
                ),
                joint("Tip", Some(1), [2.0, 0.0, 0.0], &[]),
            ],
        };
        // Root at (10,0,0) turned 90° about Y; Mid translated by (1,0,0)
        // in the root's frame and rotated 90° about Z.
        let frame = [10.0, 0.0, 0.0, 90.0, 90.0, 1.0, 0.0, 0.0, 0.0, 0.0];
        let p = positions(&sk, &frame);
        assert!(close(p[0], [10.0, 0.0, 0.0]));
        // Ry(90) maps (1,1,0) to (0,1,-1).
        assert!(close(p[1], [10.0, 1.0, -1.0]), "{:?}", p[1]);
        // Tip: Ry·Rz·(2,0,0) = Ry·(0,2,0) = (0,2,0).
        assert!(close(p[2], [10.0, 3.0, -1.0]), "{:?}", p[2]);
    }

    #[test]
    fn root_offset_is_honoured() {
        // The iclone-cmu case: a root OFFSET with position channels relative
        // to it.
        let sk = Skeleton {
            joints: vec![
                joint(
                    "CC_Base_Hip",
                    None,
                    [0.0, 105.2, 0.0],
                    &[
                        Xposition, Yposition, Zposition, Zrotation, Yrotation, Xrotation,
                    ],
                ),
                Joint {
                    end_site: true,
                    ..joint("CC_Base_Hip_End", Some(0), [0.0, -100.0, 0.0], &[])
                },
            ],
        };
        let p = positions(&sk, &[1.0, 5.6, 2.0, 0.0, 0.0, 0.0]);
        assert!(close(p[0], [1.0, 110.8, 2.0]), "{:?}", p[0]);
        assert!(close(p[1], [1.0, 10.8, 2.0]), "{:?}", p[1]);
    }

    #[test]
    fn all_positions_and_lever_arms() {
        let sk = Skeleton {
            joints: vec![
                joint("A", None, [0.0; 3], &[Yposition]),
                joint("B", Some(0), [3.0, 0.0, 0.0], &[Zrotation]),
                joint("C", Some(1), [0.0, 4.0, 0.0], &[]),
                joint("D", Some(0), [0.0, 0.0, -2.0], &[]),
            ],
        };
        let m = Motion {
            skeleton: sk.clone(),
            frame_time: 0.1,
            values: vec![0.0, 0.0, 1.0, 90.0],
        };
        let all = all_positions(&m);
        assert_eq!(all.len(), 8);
        assert!(close(all[2], [3.0, 4.0, 0.0]));
        assert!(close(all[4 + 2], [-1.0, 1.0, 0.0]), "{:?}", all[6]);
        let l = lever_arms(&sk);
        assert_eq!(l.len(), 4);
        assert!((l[0] - 5.0).abs() < 1e-12);
        assert!((l[1] - 4.0).abs() < 1e-12);
        assert_eq!(l[2], 0.0);
        assert_eq!(l[3], 0.0);
    }
}
