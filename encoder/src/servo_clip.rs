//! Servo clips (`mocap encode --rig`): the rig's servo signals coded in
//! servo space. The clip's skeleton is the rig — one root joint per servo,
//! named after it, with one `Zrotation` channel holding the servo angle in
//! degrees of travel — and the rig table (SPEC.md §3.5) maps each decoded
//! angle to its pulse with the servo's limits, so the MCU writes decoded
//! values straight to its outputs.

use mocap_decoder::{consts, Clip, RigServo};

use crate::clipfile;
use crate::container::{assemble, varint, zigzag};
use crate::motion::{ChannelKind, Joint, Motion, Skeleton};
use crate::rig::{Rig, Servo, ServoTracks};

/// The servo signals as a motion: servo `i` is root joint `i` with one
/// `Zrotation` channel, in degrees of servo travel.
pub fn servo_motion(rig: &Rig, tracks: &ServoTracks) -> Motion {
    let joints = rig
        .servos
        .iter()
        .map(|s| Joint {
            name: s.name.clone(),
            parent: None,
            offset: [0.0; 3],
            channels: vec![ChannelKind::Zrotation],
            end_site: false,
        })
        .collect();
    let frames = tracks.frames();
    let n = tracks.servos.len();
    let mut values = vec![0.0; frames * n];
    for (i, t) in tracks.servos.iter().enumerate() {
        for (f, a) in t.angles.iter().enumerate() {
            values[f * n + i] = *a;
        }
    }
    Motion {
        skeleton: Skeleton { joints },
        frame_time: tracks.frame_time,
        values,
    }
}

/// A rig servo as the rig table stores it (SPEC.md §3.5): integer
/// millidegrees and quarter-microseconds, the form the decoder and the
/// firmware map and limit with.
pub fn table_entry(s: &Servo) -> RigServo {
    let mdeg = |v: f64| (v * 1000.0).round() as i32;
    let qus = |us: f64| (us * 4.0).round().clamp(0.0, f64::from(u16::MAX)) as u16;
    RigServo {
        output: s.output,
        angle_lo_mdeg: mdeg(s.angle[0]),
        angle_hi_mdeg: mdeg(s.angle[1]),
        pulse_lo_qus: qus(s.pulse[0]),
        pulse_hi_qus: qus(s.pulse[1]),
        neutral_qus: s.neutral_quarter_us(),
        max_speed_mdeg_s: s.max_speed.map_or(0, |v| {
            (v * 1000.0).round().clamp(1.0, f64::from(u32::MAX)) as u32
        }),
    }
}

/// The rig's servo rate in millihertz.
pub fn rate_mhz(rig: &Rig) -> u32 {
    (rig.rate_hz * 1000.0)
        .round()
        .clamp(1.0, f64::from(u32::MAX)) as u32
}

/// The rig section (SPEC.md §3.5).
pub fn rig_section(rig: &Rig) -> Vec<u8> {
    let mut out = Vec::new();
    varint(&mut out, rate_mhz(rig));
    varint(&mut out, rig.servos.len() as u32);
    for s in rig.servos.iter().map(table_entry) {
        out.extend_from_slice(&s.output.to_le_bytes());
        zigzag(&mut out, s.angle_lo_mdeg);
        zigzag(&mut out, s.angle_hi_mdeg);
        varint(&mut out, u32::from(s.pulse_lo_qus));
        varint(&mut out, u32::from(s.pulse_hi_qus));
        varint(&mut out, u32::from(s.neutral_qus));
        varint(&mut out, s.max_speed_mdeg_s);
    }
    out
}

/// `clip` with the rig section added (after the header).
pub fn attach_rig(clip: &[u8], rig: &Rig) -> Result<Vec<u8>, String> {
    let parsed = Clip::parse(clip).map_err(|e| format!("internal error: {e}"))?;
    let mut sections: Vec<(u8, Vec<u8>)> = Vec::new();
    for s in parsed.sections() {
        sections.push((s.id, s.bytes.to_vec()));
        if s.id == consts::SECTION_HEADER || s.id == consts::SECTION_HEADER_COMPACT {
            sections.push((consts::SECTION_RIG, rig_section(rig)));
        }
    }
    let bytes = assemble(&sections);
    Clip::parse(&bytes).map_err(|e| format!("internal error: rig table rejected: {e}"))?;
    Ok(bytes)
}

/// Pulses (¼ µs) a servo clip decodes to, `[servo][frame]`, through the
/// decoder's own mapping (`RigServo::pulse_qus`).
pub fn decoded_pulses(clip: &Clip<'_>) -> Result<Vec<Vec<u16>>, String> {
    let rig = clip.rig().ok_or("not a servo clip (no rig table)")?;
    let frames = clipfile::decode_all(clip).map_err(|e| e.to_string())?;
    let n = clip.header().channel_count().max(1);
    Ok(rig
        .servos()
        .enumerate()
        .map(|(i, s)| {
            frames
                .iter()
                .skip(i)
                .step_by(n)
                .map(|&v| s.pulse_qus(v))
                .collect()
        })
        .collect())
}
