//! Baking an ASF skeleton and its AMC frames into the BVH model.
//!
//! # Conventions (those of CMU's amc viewer and Barbič's ASF/AMC code)
//!
//! * `axis a0 a1 a2 ORDER`: `C = R(ORDER[2], a2) · R(ORDER[1], a1) ·
//!   R(ORDER[0], a0)` (column vectors): the rotations are applied in the
//!   order the letters give, value `i` about letter `i` (`axis 0 0 20 XYZ`:
//!   `C = Rz(20)·Ry(0)·Rx(0)`). The root's `orientation` with its `axis`
//!   order likewise.
//! * dof: `M = R(dof_last) · … · R(dof_first)`: the dof rotate in their
//!   listed order (the viewers apply `rz`, then `ry`, then `rx` to the
//!   vector last-to-first, `M = Rz·Ry·Rx`, which is this rule for CMU's
//!   `dof rx ry rz`). The root's rotations in its `order` likewise.
//! * A bone's frame is `F = F_parent · C_parent⁻¹ · C · M`; with the
//!   world-aligned joint frame `G = F · C⁻¹`, `G = G_parent · (C·M·C⁻¹)`,
//!   and the bone's tip is `G · (direction × length)` from its start.
//!   Translation dof move the bone in its axis frame: `C·t` in the
//!   parent's frame. The root translates in world coordinates (before its
//!   `C`), as the viewers do, from `:root position`.
//!
//! # Channels
//!
//! * `C` the identity (`axis 0 0 0`): the bone keeps exactly its own dof
//!   as channels: translations as position channels in their order, then
//!   the rotations in reverse dof order (BVH multiplies channels left to
//!   right, `R = R_first · R_second`, so `dof rx ry rz` becomes `Zrotation
//!   Yrotation Xrotation` with the same values). A 1-dof bone stays one
//!   channel; a bone without dof has none (`lhipjoint`).
//! * Otherwise the rotation `C·M·C⁻¹` (any dof subset) becomes three
//!   channels in the fixed order [`EULER_ORDER`] (`Zrotation Yrotation
//!   Xrotation`, the order of the CMU BVH conversion), and translations
//!   three position channels `C·t`. Of the two Euler solutions of each
//!   frame the one nearest the previous frame's is kept (angles wrapped to
//!   (−180°, 180°]), so the channels stay continuous; at gimbal lock the
//!   first angle keeps its previous value.
//! * The dof `l` (bone stretching) has no BVH equivalent and is refused.

use super::motion::segment_dof;
use super::skeleton::{Asf, Dof};
use super::{Amc, AsfError};
use crate::motion::{ChannelKind, Joint, Motion, Skeleton};

/// The Euler order of baked rotations, as BVH channels (`R = Rz·Ry·Rx`).
pub const EULER_ORDER: [ChannelKind; 3] = [
    ChannelKind::Zrotation,
    ChannelKind::Yrotation,
    ChannelKind::Xrotation,
];

/// What the conversion did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeReport {
    /// Joints whose channels are their own dof (`axis` the identity).
    pub direct_joints: usize,
    /// Joints whose rotation was baked into [`EULER_ORDER`] channels.
    pub baked_joints: usize,
    /// The largest |middle angle| (Yrotation) of a baked rotation over all
    /// frames, in degrees: 90° is gimbal lock.
    pub max_middle_angle_deg: f64,
}

use crate::rotation::{apply, mul, rot, transpose, I3, M3};

/// `C` of angles `a[i]` about `order[i]`, applied in that order.
fn axis_matrix(a: [f64; 3], order: [usize; 3]) -> M3 {
    mul(
        &rot(order[2], a[2]),
        &mul(&rot(order[1], a[1]), &rot(order[0], a[0])),
    )
}

fn is_identity(m: &M3) -> bool {
    (0..3).all(|r| (0..3).all(|c| (m[r][c] - I3[r][c]).abs() < 1e-12))
}

fn wrap(d: f64) -> f64 {
    crate::fixed::wrap_degrees(d)
}

/// `R = Rz(z)·Ry(y)·Rx(x)`: `(z, y, x)` in degrees, of the two solutions
/// the one nearest `prev` (wrapped differences).
fn euler_zyx(r: &M3, prev: [f64; 3]) -> [f64; 3] {
    let s = (-r[2][0]).clamp(-1.0, 1.0);
    if s.abs() > 1.0 - 1e-12 {
        // Gimbal lock: only z − x (y = +90°) or z + x (y = −90°) is defined.
        let x = prev[2];
        let (y, z) = if s > 0.0 {
            (90.0, x - r[0][1].atan2(r[1][1]).to_degrees())
        } else {
            (-90.0, (-r[0][1]).atan2(r[1][1]).to_degrees() - x)
        };
        return [wrap(z), y, wrap(x)];
    }
    let y1 = s.asin().to_degrees();
    let a = [
        wrap(r[1][0].atan2(r[0][0]).to_degrees()),
        y1,
        wrap(r[2][1].atan2(r[2][2]).to_degrees()),
    ];
    let b = [wrap(a[0] + 180.0), wrap(180.0 - y1), wrap(a[2] + 180.0)];
    let dist = |e: &[f64; 3]| -> f64 { (0..3).map(|i| wrap(e[i] - prev[i]).abs()).sum() };
    if dist(&b) < dist(&a) {
        b
    } else {
        a
    }
}

/// How a joint's channel values come from a frame row of the AMC.
enum Recipe {
    /// Each channel is one AMC value (its index in the row).
    Direct(Vec<usize>),
    /// Translations `C·t` then `C·M·C⁻¹` as [`EULER_ORDER`].
    Baked {
        c: M3,
        ct: M3,
        /// The translations are in world axes (the root's), not `C`'s.
        world: bool,
        /// (axis, AMC index) of the translation dof.
        trans: Vec<(usize, usize)>,
        /// (axis, AMC index) of the rotation dof, in listed order.
        rots: Vec<(usize, usize)>,
    },
}

/// Channels and recipe of one segment (0 = root, `1 + b` = bone `b`).
fn plan(
    asf: &Asf,
    amc: &Amc,
    segment: usize,
    file: &str,
) -> Result<(Vec<ChannelKind>, Recipe), AsfError> {
    let dof = segment_dof(asf, segment);
    let base = amc.offsets[segment];
    let (c, root) = match segment {
        0 => (axis_matrix(asf.root.orientation, asf.root.axis_order), true),
        s => {
            let b = &asf.bones[s - 1];
            if dof.contains(&Dof::L) {
                return Err(AsfError::new(
                    file,
                    0,
                    0,
                    format!(
                        "bone '{}' (ASF line {}): dof l (length change) has no BVH equivalent and is not supported",
                        b.name, b.line
                    ),
                ));
            }
            (axis_matrix(b.axis, b.axis_order), false)
        }
    };
    let trans: Vec<(usize, usize)> = dof
        .iter()
        .enumerate()
        .filter(|(_, d)| !d.is_rotation())
        .map(|(k, d)| (d.axis(), base + k))
        .collect();
    let rots: Vec<(usize, usize)> = dof
        .iter()
        .enumerate()
        .filter(|(_, d)| d.is_rotation())
        .map(|(k, d)| (d.axis(), base + k))
        .collect();
    let pos_kind = |a: usize| ChannelKind::ALL[a];
    let rot_kind = |a: usize| ChannelKind::ALL[3 + a];
    // The root translates in world coordinates, before its C.
    if is_identity(&c) || (root && rots.is_empty()) {
        let mut kinds: Vec<ChannelKind> = trans.iter().map(|&(a, _)| pos_kind(a)).collect();
        let mut src: Vec<usize> = trans.iter().map(|&(_, i)| i).collect();
        for &(a, i) in rots.iter().rev() {
            kinds.push(rot_kind(a));
            src.push(i);
        }
        return Ok((kinds, Recipe::Direct(src)));
    }
    let mut kinds = Vec::new();
    if !trans.is_empty() {
        kinds.extend(&ChannelKind::ALL[..3]);
    }
    if !rots.is_empty() {
        kinds.extend(EULER_ORDER);
    }
    Ok((
        kinds,
        Recipe::Baked {
            c,
            ct: transpose(&c),
            world: root,
            trans,
            rots,
        },
    ))
}

/// Bakes `asf` and its frames `amc` into a [`Motion`] at `frame_time`
/// seconds per frame; `file` (the AMC) names errors.
pub fn bake(
    asf: &Asf,
    amc: &Amc,
    frame_time: f64,
    file: &str,
) -> Result<(Motion, BakeReport), AsfError> {
    let mut joints = Vec::with_capacity(asf.bones.len() + 8);
    let mut recipes = Vec::with_capacity(asf.bones.len() + 1);
    let mut report = BakeReport::default();
    let (kinds, recipe) = plan(asf, amc, 0, file)?;
    joints.push(Joint {
        name: "root".into(),
        parent: None,
        offset: asf.root.position,
        channels: kinds,
        end_site: false,
    });
    recipes.push((0usize, recipe));
    // Joint index of each bone.
    let mut joint_of = vec![0usize; asf.bones.len()];
    for b in asf.depth_first() {
        let bone = &asf.bones[b];
        let (parent, offset) = match bone.parent {
            None => (0, [0.0; 3]),
            Some(p) => {
                let pb = &asf.bones[p];
                (joint_of[p], pb.direction.map(|d| d * pb.length))
            }
        };
        let (kinds, recipe) = plan(asf, amc, 1 + b, file)?;
        joint_of[b] = joints.len();
        recipes.push((joints.len(), recipe));
        joints.push(Joint {
            name: bone.name.clone(),
            parent: Some(parent),
            offset,
            channels: kinds,
            end_site: false,
        });
        if bone.children.is_empty() {
            joints.push(Joint {
                name: crate::bvh::end_site_name(&bone.name, 1),
                parent: Some(joint_of[b]),
                offset: bone.direction.map(|d| d * bone.length),
                channels: Vec::new(),
                end_site: true,
            });
        }
    }
    let skeleton = Skeleton { joints };
    let channels = skeleton.channel_count();
    if channels == 0 {
        return Err(AsfError::new(
            file,
            0,
            0,
            "the skeleton has no dof (no root order, no bone dof), so there is no motion to read",
        ));
    }
    // Where each joint's channels start in a motion row.
    let mut start = Vec::with_capacity(skeleton.joints.len());
    let mut acc = 0;
    for j in &skeleton.joints {
        start.push(acc);
        acc += j.channels.len();
    }
    for (_, r) in &recipes {
        match r {
            Recipe::Direct(_) => report.direct_joints += 1,
            Recipe::Baked { .. } => report.baked_joints += 1,
        }
    }
    let frames = amc.frames();
    let mut values = vec![0.0; frames * channels];
    let mut prev: Vec<[f64; 3]> = vec![[0.0; 3]; recipes.len()];
    for f in 0..frames {
        let row = &amc.values[f * amc.width..(f + 1) * amc.width];
        let out = &mut values[f * channels..(f + 1) * channels];
        for (k, (j, r)) in recipes.iter().enumerate() {
            let o = &mut out[start[*j]..];
            match r {
                Recipe::Direct(src) => {
                    for (slot, &i) in o.iter_mut().zip(src) {
                        *slot = row[i];
                    }
                }
                Recipe::Baked {
                    c,
                    ct,
                    world,
                    trans,
                    rots,
                } => {
                    let mut n = 0;
                    if !trans.is_empty() {
                        let mut t = [0.0; 3];
                        for &(a, i) in trans {
                            t[a] = row[i];
                        }
                        let t = if *world { t } else { apply(c, t) };
                        o[..3].copy_from_slice(&t);
                        n = 3;
                    }
                    if !rots.is_empty() {
                        let mut m = I3;
                        for &(a, i) in rots {
                            m = mul(&rot(a, row[i]), &m);
                        }
                        let r = mul(c, &mul(&m, ct));
                        let e = euler_zyx(&r, prev[k]);
                        prev[k] = e;
                        report.max_middle_angle_deg = report.max_middle_angle_deg.max(e[1].abs());
                        o[n..n + 3].copy_from_slice(&e);
                    }
                }
            }
        }
    }
    Ok((
        Motion {
            skeleton,
            frame_time,
            values,
        },
        report,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &M3, b: &M3) -> bool {
        (0..3).all(|r| (0..3).all(|c| (a[r][c] - b[r][c]).abs() < 1e-9))
    }

    #[test]
    fn euler_zyx_reconstructs_and_stays_continuous() {
        let mut prev = [0.0; 3];
        for (z, y, x) in [
            (10.0, 20.0, 30.0),
            (170.0, -80.0, -175.0),
            (-179.0, 89.9, 5.0),
            (45.0, 90.0, 30.0),
            (45.0, -90.0, 30.0),
        ] {
            let r = mul(&rot(2, z), &mul(&rot(1, y), &rot(0, x)));
            let e = euler_zyx(&r, prev);
            let back = mul(&rot(2, e[0]), &mul(&rot(1, e[1]), &rot(0, e[2])));
            assert!(close(&r, &back), "{z} {y} {x} -> {e:?}");
            prev = e;
        }
        // The second solution is taken when it is nearer the previous frame.
        let r = mul(&rot(2, 10.0), &mul(&rot(1, 20.0), &rot(0, 30.0)));
        let e = euler_zyx(&r, [190.0, 160.0, 210.0]);
        assert!((e[1] - 160.0).abs() < 1e-9, "{e:?}");
    }

    #[test]
    fn axis_order_applies_letters_in_order() {
        // XYZ: x first. Rx(90) then Rz(90) takes +Y to +Z, then +Z stays.
        let c = axis_matrix([90.0, 0.0, 90.0], [0, 1, 2]);
        let v = apply(&c, [0.0, 1.0, 0.0]);
        assert!((v[2] - 1.0).abs() < 1e-12, "{v:?}");
        // ZYX with values (z, y, x) = (90, 0, 90): z first takes +Y to −X,
        // then Rx leaves −X alone.
        let c = axis_matrix([90.0, 0.0, 90.0], [2, 1, 0]);
        let v = apply(&c, [0.0, 1.0, 0.0]);
        assert!((v[0] + 1.0).abs() < 1e-12, "{v:?}");
    }
}
