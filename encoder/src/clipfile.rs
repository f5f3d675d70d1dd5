//! Reading `.mcb` clips back on the host with the `no_std` decoder: the
//! skeleton from the header, every frame through `Player`.

use mocap_decoder::{Clip, Player};

use crate::fixed;
use crate::motion::{Joint, Motion, Skeleton};

/// Largest channel count the host tools decode.
pub const HOST_MAX_CHANNELS: usize = 4096;

/// Decodes every frame of a clip: `frames × channels`, frame-major.
pub fn decode_all(clip: &Clip<'_>) -> Result<Vec<i32>, mocap_decoder::Error> {
    let mut player = Box::new(Player::<HOST_MAX_CHANNELS>::new(clip)?);
    let n = player.channel_count();
    let mut out = vec![0i32; n * player.frame_count() as usize];
    for frame in out.chunks_mut(n.max(1)) {
        if player.next_frame(frame)?.is_none() {
            break;
        }
    }
    Ok(out)
}

/// The skeleton stored in a clip's header, lengths in the source's units.
pub fn skeleton(clip: &Clip<'_>) -> Skeleton {
    let h = clip.header();
    let unit = f64::from(h.source_unit_nm()) * 1e-3; // µm per source unit
    let mut joints: Vec<Joint> = Vec::with_capacity(h.joint_count());
    let mut end_sites = vec![0usize; h.joint_count()];
    for j in h.joints() {
        let parent = j.parent.map(|p| p as usize);
        // Compact headers leave End Sites unnamed (SPEC.md §3.4): name
        // them as the BVH reader does.
        let name = match parent {
            Some(p) if j.end_site && j.name.is_empty() && p < joints.len() => {
                end_sites[p] += 1;
                crate::bvh::end_site_name(&joints[p].name, end_sites[p])
            }
            _ => j.name.to_string(),
        };
        joints.push(Joint {
            name,
            parent,
            offset: j.offset_um.map(|o| f64::from(o) / unit),
            channels: j.channel_kinds().collect(),
            end_site: j.end_site,
        });
    }
    Skeleton { joints }
}

/// Decodes a clip into a motion in the source's units, angles wrapped.
pub fn to_motion(clip: &Clip<'_>) -> Result<Motion, mocap_decoder::Error> {
    let h = clip.header();
    let frames = decode_all(clip)?;
    let metres_per_unit = f64::from(h.source_unit_nm()) * 1e-9;
    Ok(fixed::from_fixed(
        &skeleton(clip),
        f64::from(h.frame_time_ns()) * 1e-9,
        &frames,
        metres_per_unit,
    ))
}

/// The text the firmware example prints for a clip (firmware-example/
/// README.md): one line per frame, values in decimal separated by single
/// spaces. Lines starting with `#` are not part of it.
pub fn uart_text(frames: &[i32], channels: usize) -> String {
    let mut s = String::with_capacity(frames.len() * 8);
    for frame in frames.chunks(channels.max(1)) {
        for (i, v) in frame.iter().enumerate() {
            if i > 0 {
                s.push(' ');
            }
            s.push_str(&v.to_string());
        }
        s.push('\n');
    }
    s
}

/// The text the firmware example prints in its sample mode (`MOCAP_SAMPLE_US`,
/// firmware-example/README.md): one line per `Player::sample_at(t)` for
/// t = 0, P, 2P, … µs up to and including the first t past the clip's
/// duration, in the format of [`uart_text`].
pub fn uart_text_sampled(clip: &Clip<'_>, period_us: u64) -> Result<String, mocap_decoder::Error> {
    assert!(period_us > 0, "sampling period must be > 0 µs");
    let duration_us = clip.header().duration_us();
    let count = duration_us / period_us + 2;
    let samples = sample_all(clip, (0..count).map(|i| i * period_us))?;
    Ok(uart_text(&samples, clip.header().channel_count()))
}

/// `Player::sample_at` at each of `times_us`: `times × channels`,
/// time-major.
pub fn sample_all(
    clip: &Clip<'_>,
    times_us: impl IntoIterator<Item = u64>,
) -> Result<Vec<i32>, mocap_decoder::Error> {
    let mut player = Box::new(Player::<HOST_MAX_CHANNELS>::new(clip)?);
    let mut out = vec![0i32; player.channel_count()];
    let mut samples = Vec::new();
    for t in times_us {
        player.sample_at(t, &mut out)?;
        samples.extend_from_slice(&out);
    }
    Ok(samples)
}

/// Why a clip cannot be played back against a source motion: it was not
/// encoded from it (another skeleton, another length), or it does not decode.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SourceMismatch {
    /// A servo clip holds servo pulses, not the source's channels.
    #[error("it is a servo clip (servo pulses, not the source's {0} channels)")]
    ServoClip(usize),
    /// The clip has another frame or channel count.
    #[error(
        "it has {clip_frames} frames × {clip_channels} channels but the source has \
         {frames} × {channels}"
    )]
    Shape {
        /// The clip's frames.
        clip_frames: usize,
        /// The clip's channels per frame.
        clip_channels: usize,
        /// The source's frames.
        frames: usize,
        /// The source's channels per frame.
        channels: usize,
    },
    /// The clip's skeleton differs from the source's at a joint (its parent,
    /// channels, name or offset).
    #[error("its skeleton differs from the source's at joint {index} ({name}): {what}")]
    Skeleton {
        /// Joint index in file order.
        index: usize,
        /// The source's name of that joint.
        name: String,
        /// What differs.
        what: &'static str,
    },
    /// The clip has another joint count.
    #[error("its skeleton has {clip} joints but the source's has {joints}")]
    JointCount {
        /// The clip's joints (End Sites included).
        clip: usize,
        /// The source's joints.
        joints: usize,
    },
    /// The clip does not decode.
    #[error(transparent)]
    Decode(#[from] mocap_decoder::Error),
}

/// Decodes `clip` as an encoding of `source` and returns it as a motion on
/// the source's skeleton (values unwrapped as the encoder coded them), in
/// the units of `metres_per_unit`, after checking that it is one: same
/// skeleton (parents, channels, the names the clip keeps, offsets within
/// 2 µm), same frame and channel counts. What `mocap eval` and `mocap view`
/// measure.
pub fn decode_against(
    clip: &Clip<'_>,
    source: &Motion,
    metres_per_unit: f64,
) -> Result<Motion, SourceMismatch> {
    let h = clip.header();
    if h.is_servo_form() {
        return Err(SourceMismatch::ServoClip(source.channels()));
    }
    let theirs = skeleton(clip);
    let ours = &source.skeleton.joints;
    if theirs.joints.len() != ours.len() {
        return Err(SourceMismatch::JointCount {
            clip: theirs.joints.len(),
            joints: ours.len(),
        });
    }
    // Header offsets are whole micrometres of the clip's source unit.
    let unit_m = f64::from(h.source_unit_nm()) * 1e-9;
    let tolerance = 2e-6 / unit_m.max(f64::MIN_POSITIVE);
    for (index, (a, b)) in theirs.joints.iter().zip(ours).enumerate() {
        let what = if a.parent != b.parent || a.end_site != b.end_site {
            "parent"
        } else if a.channels != b.channels {
            "channels"
        } else if !a.name.is_empty() && a.name != b.name {
            "name"
        } else if (0..3).any(|k| (a.offset[k] - b.offset[k]).abs() > tolerance) {
            "offset"
        } else {
            continue;
        };
        return Err(SourceMismatch::Skeleton {
            index,
            name: b.name.clone(),
            what,
        });
    }
    if h.channel_count() != source.channels() || h.frame_count() as usize != source.frames() {
        return Err(SourceMismatch::Shape {
            clip_frames: h.frame_count() as usize,
            clip_channels: h.channel_count(),
            frames: source.frames(),
            channels: source.channels(),
        });
    }
    let frames = decode_all(clip)?;
    Ok(fixed::from_fixed(
        &source.skeleton,
        source.frame_time,
        &frames,
        metres_per_unit,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
    use crate::{generate, units};

    #[test]
    fn a_clip_plays_against_its_source_and_not_another() {
        let m = generate::animatronic_demo();
        let metres = units::detect(&m).metres();
        let opts = EncodeOptions {
            key_bits: None,
            codec: CodecChoice::Index,
            bound: Bound::from_specs(&["1deg".parse::<BoundSpec>().unwrap()]),
            metres_per_unit: metres,
            key_interval: None,
            index_layout: Default::default(),
            pattern: Default::default(),
        };
        let bytes = encode::encode(&m, &opts).unwrap().bytes;
        let clip = Clip::parse(&bytes).unwrap();
        let back = decode_against(&clip, &m, metres).unwrap();
        assert_eq!((back.frames(), back.channels()), (m.frames(), m.channels()));

        let mut short = m.clone();
        short.values.truncate(100 * m.channels());
        assert!(matches!(
            decode_against(&clip, &short, metres),
            Err(SourceMismatch::Shape { clip_frames, frames: 100, .. }) if clip_frames == m.frames()
        ));
        let mut longer = m.clone();
        longer.skeleton.joints[2].offset[1] += 1.0;
        let e = decode_against(&clip, &longer, metres).unwrap_err();
        assert!(
            matches!(
                e,
                SourceMismatch::Skeleton {
                    index: 2,
                    what: "offset",
                    ..
                }
            ),
            "{e}"
        );
        let mut renamed = m.clone();
        renamed.skeleton.joints[3].name = "Other".into();
        let e = decode_against(&clip, &renamed, metres).unwrap_err();
        assert_eq!(
            e.to_string(),
            "its skeleton differs from the source's at joint 3 (Other): name"
        );
    }
}
