//! Servo clips (`mocap encode --rig`): the rig's servo signals coded in
//! servo space. The clip's skeleton is the rig — one root joint per servo,
//! named after it, with one `Zrotation` channel holding the servo angle in
//! degrees of travel — and the rig table (SPEC.md §3.5) maps each decoded
//! angle to its pulse with the servo's limits, so the MCU writes decoded
//! values straight to its outputs.

use mocap_decoder::{consts, Clip, Player};

use crate::container::assemble;
use crate::motion::{ChannelKind, Joint, Motion, Skeleton};
use crate::rig::{Rig, ServoTracks};

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

/// The rig section (SPEC.md §3.5).
pub fn rig_section(rig: &Rig) -> Vec<u8> {
    let mut out = Vec::new();
    let varint = |out: &mut Vec<u8>, v: u32| {
        out.extend_from_slice(&postcard::to_stdvec(&v).expect("u32"));
    };
    let zigzag = |out: &mut Vec<u8>, v: i32| {
        out.extend_from_slice(&postcard::to_stdvec(&v).expect("i32"));
    };
    varint(
        &mut out,
        (rig.rate_hz * 1000.0)
            .round()
            .clamp(1.0, f64::from(u32::MAX)) as u32,
    );
    varint(&mut out, rig.servos.len() as u32);
    for s in &rig.servos {
        out.extend_from_slice(&s.output.to_le_bytes());
        zigzag(&mut out, (s.angle[0] * 1000.0).round() as i32);
        zigzag(&mut out, (s.angle[1] * 1000.0).round() as i32);
        varint(&mut out, (s.pulse[0] * 4.0).round() as u32);
        varint(&mut out, (s.pulse[1] * 4.0).round() as u32);
        varint(&mut out, u32::from(s.neutral_quarter_us()));
        varint(
            &mut out,
            s.max_speed.map_or(0, |v| {
                (v * 1000.0).round().clamp(1.0, f64::from(u32::MAX)) as u32
            }),
        );
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
    let servos: Vec<_> = rig.servos().collect();
    let n = clip.header().channel_count();
    let mut player = Box::new(Player::<4096>::new(clip).map_err(|e| e.to_string())?);
    let mut out = vec![0i32; n];
    let mut pulses = vec![Vec::new(); n];
    while player
        .next_frame(&mut out)
        .map_err(|e| e.to_string())?
        .is_some()
    {
        for ((p, s), v) in pulses.iter_mut().zip(&servos).zip(&out) {
            p.push(s.pulse_qus(*v));
        }
    }
    Ok(pulses)
}
