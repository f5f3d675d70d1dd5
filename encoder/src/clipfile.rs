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
