//! Conversion between the motion model (degrees, source length units) and
//! the bitstream's fixed-point channels (SPEC.md §3.3): rotations in
//! millidegrees, unwrapped so each channel is continuous; positions in
//! micrometres.

use crate::motion::{ChannelKind, Motion};

/// Millidegrees per degree.
pub const MDEG_PER_DEG: f64 = 1000.0;

/// A motion as integer channels: `values[channel][frame]`.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedChannels {
    /// Kind of each channel.
    pub kinds: Vec<ChannelKind>,
    /// Per channel, per frame: the fixed-point value.
    pub values: Vec<Vec<i32>>,
}

impl FixedChannels {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.values.first().map_or(0, Vec::len)
    }
}

/// Integer units per source unit for a channel kind.
pub fn scale(kind: ChannelKind, metres_per_unit: f64) -> f64 {
    if kind.is_rotation() {
        MDEG_PER_DEG
    } else {
        metres_per_unit * 1e6
    }
}

/// Unwraps an angle sequence in degrees so consecutive values differ by at
/// most 180°.
pub fn unwrap_degrees(values: &mut [f64]) {
    let mut offset = 0.0;
    let mut prev: Option<f64> = None;
    for v in values.iter_mut() {
        let raw = *v;
        if let Some(p) = prev {
            let d = raw + offset - p;
            offset -= 360.0 * (d / 360.0).round();
        }
        *v = raw + offset;
        prev = Some(*v);
    }
}

/// Wraps degrees into (-180, 180].
pub fn wrap_degrees(v: f64) -> f64 {
    let w = v - 360.0 * (v / 360.0).round();
    if w <= -180.0 {
        w + 360.0
    } else {
        w
    }
}

/// Converts a motion to integer channels.
pub fn to_fixed(m: &Motion, metres_per_unit: f64) -> FixedChannels {
    let kinds = m.skeleton.channel_kinds();
    let values = kinds
        .iter()
        .enumerate()
        .map(|(c, &kind)| {
            let mut series = m.channel(c);
            if kind.is_rotation() {
                unwrap_degrees(&mut series);
            }
            let s = scale(kind, metres_per_unit);
            series
                .iter()
                .map(|v| (v * s).round().clamp(i32::MIN as f64, i32::MAX as f64) as i32)
                .collect()
        })
        .collect();
    FixedChannels { kinds, values }
}

/// Converts decoded frames (frame-major `frames × channels`) back to a
/// motion on `skeleton`, in source units, angles wrapped to (-180, 180].
pub fn from_fixed(
    skeleton: &crate::motion::Skeleton,
    frame_time: f64,
    frames: &[i32],
    metres_per_unit: f64,
) -> Motion {
    let kinds = skeleton.channel_kinds();
    let mut values = Vec::with_capacity(frames.len());
    for frame in frames.chunks(kinds.len().max(1)) {
        extend_from_fixed(&kinds, frame, metres_per_unit, &mut values);
    }
    Motion {
        skeleton: skeleton.clone(),
        frame_time,
        values,
    }
}

/// One frame of [`from_fixed`]: appends the source-unit values of the
/// fixed-point `frame` (channel kinds `kinds`) to `out`.
pub fn extend_from_fixed(
    kinds: &[ChannelKind],
    frame: &[i32],
    metres_per_unit: f64,
    out: &mut Vec<f64>,
) {
    out.extend(frame.iter().zip(kinds).map(|(&v, &kind)| {
        let x = f64::from(v) / scale(kind, metres_per_unit);
        if kind.is_rotation() {
            wrap_degrees(x)
        } else {
            x
        }
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwrap_and_wrap() {
        let mut v = vec![170.0, -175.0, -160.0, 179.0, -179.0];
        unwrap_degrees(&mut v);
        assert_eq!(v, vec![170.0, 185.0, 200.0, 179.0, 181.0]);
        assert_eq!(wrap_degrees(185.0), -175.0);
        assert_eq!(wrap_degrees(-180.0), 180.0);
        assert_eq!(wrap_degrees(540.0), 180.0);
    }
}
