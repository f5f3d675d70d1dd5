//! `mocap info`: a clip's header, rig and sections; each codec describes its
//! own section ([`mocap_encoder::codec::describe_section`]).

use std::path::PathBuf;

use mocap_decoder::Clip;
use mocap_encoder::codec;

use super::{parse_clip, read_clip};

#[derive(clap::Args)]
pub struct Args {
    /// Input .mcb clip.
    input: PathBuf,
    /// List every channel.
    #[arg(long)]
    channels: bool,
}

pub fn run(a: Args) -> super::Result {
    let bytes = read_clip(&a.input)?;
    let clip = parse_clip(&a.input, &bytes)?;
    print!("{}", info_text(&clip, a.channels));
    Ok(())
}

fn info_text(clip: &Clip<'_>, list_channels: bool) -> String {
    let h = clip.header();
    let mut s = format!(
        "clip: {} bytes, version {}, {} frames × {} channels, {:.3} Hz ({} ns/frame), {:.3} s, {} joints, source unit {} nm\n",
        clip.bytes().len(),
        mocap_decoder::consts::VERSION,
        h.frame_count(),
        h.channel_count(),
        1e9 / f64::from(h.frame_time_ns()),
        h.frame_time_ns(),
        h.duration_us() as f64 * 1e-6,
        h.joint_count(),
        h.source_unit_nm()
    );
    if let Some(rig) = clip.rig() {
        s += &format!(
            "servo clip: {} servos at {:.3} Hz (channel i = servo i, millidegrees of travel)\n",
            rig.servo_count(),
            f64::from(rig.rate_mhz()) / 1000.0
        );
        s += &match clip.rig_digest() {
            Some(d) => format!(
                "rig digest: {d:08x} (SPEC.md §3.6; `mocap play --rig figure.toml` and the firmware compare it with the figure's)\n"
            ),
            None => "rig digest: none (encoded before SPEC.md §3.6: only the rig table identifies the rig)\n".to_string(),
        };
    }
    for sec in clip.sections() {
        s += &format!("section {:#04x}: {} bytes\n", sec.id, sec.bytes.len());
        if let Some(text) = codec::describe_section(sec.id, sec.bytes, h, list_channels) {
            s += &text;
        }
    }
    s
}
