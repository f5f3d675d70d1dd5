//! Frames as vectors of joint quaternions (Hu et al. 2010, §3): every joint
//! with rotation channels gives its local rotation as a unit quaternion
//! `(w, x, y, z)` with `w ≥ 0` (q and −q are the same rotation). The root's
//! translation is dropped and its heading (the twist about the vertical Y
//! axis, BVH's up axis) is removed, so only its tilt remains.

use mocap_encoder::motion::Motion;

/// A quaternion `(w, x, y, z)`.
pub type Quat = [f64; 4];

/// Hamilton product `a · b`.
pub fn qmul(a: Quat, b: Quat) -> Quat {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// Rotation of `deg` degrees about axis 0 = X, 1 = Y, 2 = Z.
pub fn axis_quat(axis: usize, deg: f64) -> Quat {
    let (s, c) = (deg.to_radians() * 0.5).sin_cos();
    let mut q = [c, 0.0, 0.0, 0.0];
    q[1 + axis] = s;
    q
}

/// `q` with its heading (twist about world Y) removed: with `q = T · tilt`
/// and `T` the twist about Y, returns `tilt = conj(T) · q`.
pub fn remove_heading(q: Quat) -> Quat {
    let n = (q[0] * q[0] + q[2] * q[2]).sqrt();
    if n < 1e-12 {
        return q; // a pure 180° swing: no defined heading
    }
    let t_conj = [q[0] / n, 0.0, -q[2] / n, 0.0];
    qmul(t_conj, q)
}

fn canonical(mut q: Quat) -> Quat {
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
    let s = if q[0] < 0.0 { -1.0 / n } else { 1.0 / n };
    for v in &mut q {
        *v *= s;
    }
    q
}

/// The rotating joints of a motion, by name, in skeleton order.
pub fn rotating_joints(m: &Motion) -> Vec<String> {
    m.skeleton
        .joints
        .iter()
        .filter(|j| j.channels.iter().any(|k| k.is_rotation()))
        .map(|j| j.name.clone())
        .collect()
}

/// Quaternion frames of one clip.
#[derive(Clone, Debug)]
pub struct QuatFrames {
    /// Values per frame (4 per joint).
    pub dim: usize,
    /// Row-major `frames × dim`.
    pub data: Vec<f32>,
    /// Mean joint angular speed per frame, degrees per second.
    pub speed: Vec<f64>,
}

impl QuatFrames {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.data.len().checked_div(self.dim).unwrap_or(0)
    }
}

/// Quaternion frames of `m` over the joints named in `joints` (in that
/// order; see [`rotating_joints`]). A joint missing from `m` is an error.
pub fn quat_frames(m: &Motion, joints: &[String]) -> Result<QuatFrames, super::TrackError> {
    // (first channel index, kinds) per selected joint.
    let mut first = Vec::with_capacity(m.skeleton.joints.len());
    let mut k = 0;
    for j in &m.skeleton.joints {
        first.push(k);
        k += j.channels.len();
    }
    let mut sel = Vec::with_capacity(joints.len());
    for name in joints {
        let (idx, joint) = m
            .skeleton
            .joints
            .iter()
            .enumerate()
            .find(|(_, j)| &j.name == name)
            .ok_or_else(|| super::TrackError::MissingJoint(name.clone()))?;
        sel.push((first[idx], &joint.channels, joint.parent.is_none()));
    }
    let dim = 4 * sel.len();
    let frames = m.frames();
    let mut data = Vec::with_capacity(frames * dim);
    let mut quats: Vec<Quat> = Vec::with_capacity(frames * sel.len());
    for f in 0..frames {
        let row = m.frame(f);
        for &(c0, kinds, is_root) in &sel {
            let mut q = [1.0, 0.0, 0.0, 0.0];
            for (i, kind) in kinds.iter().enumerate() {
                if kind.is_rotation() {
                    q = qmul(q, axis_quat(kind.axis(), row[c0 + i]));
                }
            }
            if is_root {
                q = remove_heading(q);
            }
            let q = canonical(q);
            quats.push(q);
            data.extend(q.iter().map(|&v| v as f32));
        }
    }
    let n = sel.len().max(1);
    let mut speed = vec![0.0; frames];
    for f in 1..frames {
        let mut sum = 0.0;
        for j in 0..sel.len() {
            let (a, b) = (quats[(f - 1) * sel.len() + j], quats[f * sel.len() + j]);
            let dot: f64 = (0..4).map(|i| a[i] * b[i]).sum::<f64>().abs().min(1.0);
            sum += 2.0 * dot.acos().to_degrees();
        }
        speed[f] = sum / n as f64 / m.frame_time.max(1e-9);
    }
    if frames > 1 {
        speed[0] = speed[1];
    }
    Ok(QuatFrames { dim, data, speed })
}
