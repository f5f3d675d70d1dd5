//! What the `pca-spline` codec weighs and groups: each channel's weight in
//! the tolerance (millimetres of joint movement per fixed-point unit) and
//! the channel groups (one per limb) that share principal components.

use crate::kinematics;
use crate::motion::{ChannelKind, Motion};

/// Channel weights for the `pca-spline` tolerance: millimetres of joint
/// movement per fixed-point unit under a position bound (rotation: the
/// joint's lever arm, blended with its RMS lever under an ARMS bound; feet
/// and toes count double, as in the paper), else degrees per millidegree
/// and millimetres per micrometre.
pub fn pca_weights(
    m: &Motion,
    levers_um: &[f64],
    joint_of: &[usize],
    kinds: &[ChannelKind],
    mm: bool,
    arms: bool,
) -> Vec<f64> {
    let longest = levers_um.iter().fold(0.0f64, |a, &b| a.max(b));
    // Under an ARMS bound a channel also counts by how many joints it
    // moves: blend in its RMS lever (scaled to the same total).
    let beta = if arms { 0.3 } else { 0.0 };
    let rms = kinematics::rms_levers(&m.skeleton);
    let (sl, sr): (f64, f64) = (levers_um.iter().sum(), rms.iter().sum());
    let kappa = if sr > 0.0 { sl / sr } else { 0.0 };
    kinds
        .iter()
        .enumerate()
        .map(|(c, kind)| {
            if !kind.is_rotation() {
                // Translations move every joint and weigh on ARMS: an
                // eighth of the tolerance (root curves are cheap).
                return 8e-3;
            }
            if !mm {
                return 1e-3;
            }
            let j = joint_of[c];
            let foot = crate::contacts::is_foot_name(&m.skeleton.joints[j].name);
            // Joints that move nothing measured still get a small weight
            // so they do not wander.
            let mixed = (1.0 - beta) * levers_um[j] + beta * kappa * rms[j];
            let lever_mm = (mixed / 1000.0).max(longest / 1000.0 * 0.02);
            let w = lever_mm * std::f64::consts::PI / 180.0 / 1000.0;
            if foot {
                2.0 * w
            } else {
                w
            }
        })
        .collect()
}

/// Channel groups of the `pca-spline` codec: the roots' translations and
/// heading (Y rotation: BVH is Y-up) each alone, then one group per limb —
/// a chain of joints between branchings — with chains of fewer than
/// `min_channels` channels (fingers, thumbs) merged into the chain they
/// branch from.
pub fn pca_groups(m: &Motion, min_channels: usize) -> Vec<Vec<usize>> {
    let joints = &m.skeleton.joints;
    let mut children = vec![0usize; joints.len()];
    for joint in joints.iter().filter(|j| !j.end_site) {
        if let Some(p) = joint.parent {
            children[p] += 1;
        }
    }
    // Chain of each joint: a joint continues its parent's chain when it is
    // the parent's only child.
    let mut chain: Vec<usize> = Vec::with_capacity(joints.len());
    let mut parent_chain: Vec<Option<usize>> = Vec::new();
    for joint in joints {
        match joint.parent {
            Some(p) if children[p] == 1 && joints[p].parent.is_some() => chain.push(chain[p]),
            Some(p) => {
                chain.push(parent_chain.len());
                parent_chain.push(Some(chain[p]));
            }
            None => {
                chain.push(parent_chain.len());
                parent_chain.push(None);
            }
        }
    }
    let mut size = vec![0usize; parent_chain.len()];
    for (joint, &c) in joints.iter().zip(&chain) {
        size[c] += joint.channels.len();
    }
    // Merge small chains upwards (children come after parents, so walk
    // backwards).
    let mut target: Vec<usize> = (0..parent_chain.len()).collect();
    for c in (0..parent_chain.len()).rev() {
        if size[c] < min_channels {
            if let Some(p) = parent_chain[c] {
                size[p] += size[c];
                target[c] = p;
            }
        }
    }
    let resolve = |mut c: usize| {
        while target[c] != c {
            c = target[c];
        }
        c
    };
    let mut groups: Vec<Vec<usize>> = vec![Vec::new(); parent_chain.len()];
    let mut tracks = Vec::new();
    let mut ch = 0;
    for (joint, &c) in joints.iter().zip(&chain) {
        for kind in &joint.channels {
            if joint.parent.is_none() && (!kind.is_rotation() || *kind == ChannelKind::Yrotation) {
                tracks.push(vec![ch]);
            } else {
                groups[resolve(c)].push(ch);
            }
            ch += 1;
        }
    }
    tracks.extend(groups.into_iter().filter(|g| !g.is_empty()));
    tracks
}
