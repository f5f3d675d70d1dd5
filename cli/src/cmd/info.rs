//! `mocap info`: a clip's header, rig and sections; each codec describes its
//! own section ([`mocap_encoder::codec::describe_section`]).

use std::path::PathBuf;

use mocap_decoder::{Clip, Show};
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
    if bytes.get(4) == Some(&mocap_decoder::consts::VERSION_SHOW) {
        let show = Show::parse(&bytes).map_err(|e| format!("{}: {e}", a.input.display()))?;
        print!("{}", show_text(&show, a.channels)?);
        return Ok(());
    }
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
    if let Some(m) = clip.missing() {
        s += &missing_text(clip, &m, list_channels);
    }
    for sec in clip.sections() {
        s += &format!("section {:#04x}: {} bytes\n", sec.id, sec.bytes.len());
        if let Some(text) = codec::describe_section(sec.id, sec.bytes, h, list_channels) {
            s += &text;
        }
    }
    s
}

/// The missing samples of a marker clip (SPEC.md §3.7): count and runs; with
/// `--channels` each marker's runs.
fn missing_text(clip: &Clip<'_>, m: &mocap_decoder::Missing<'_>, per_marker: bool) -> String {
    let samples = u64::from(m.frames()) * u64::from(m.markers());
    let mut s = format!(
        "missing samples: {} of {} ({:.1} %) in {} runs (SPEC.md §3.7; the decoded frames hold the encoder's fill there)\n",
        m.count(),
        samples,
        100.0 * f64::from(m.count()) / samples.max(1) as f64,
        m.run_count()
    );
    let names: Vec<&str> = clip.header().joints().map(|j| j.name).collect();
    for k in 0..m.markers() {
        let runs: Vec<String> = m
            .runs(k)
            .map(|(start, len)| match len {
                1 => format!("{start}"),
                _ => format!("{start}–{}", start + len - 1),
            })
            .collect();
        if per_marker && !runs.is_empty() {
            let name = names.get(k as usize).copied().unwrap_or("");
            s += &format!("  {name}: frames {}\n", runs.join(", "));
        }
    }
    s
}

/// `mocap info` of a show (SPEC.md §9): the shared header, the clips, the
/// cue lists and triggers, the sections.
fn show_text(show: &Show<'_>, list_channels: bool) -> super::Result<String> {
    use mocap_decoder::show::cues::{Action, TriggerKind};
    let h = show.header();
    let mut s = format!(
        "show: {} bytes, version {}, {} clips, {} frames in all × {} channels, {:.3} Hz, {} joints\n",
        show.bytes().len(),
        mocap_decoder::consts::VERSION_SHOW,
        show.clip_count(),
        h.frame_count(),
        h.channel_count(),
        1e9 / f64::from(h.frame_time_ns()),
        h.joint_count()
    );
    if let Some(rig) = show.rig() {
        s += &format!(
            "servo show: {} servos at {:.3} Hz; rig digest {}\n",
            rig.servo_count(),
            f64::from(rig.rate_mhz()) / 1000.0,
            show.rig_digest()
                .map_or("none".to_string(), |d| format!("{d:08x}"))
        );
    }
    let name = |i: u16| show.entry(i).map(|e| e.name).unwrap_or("?");
    for i in 0..show.clip_count() {
        let e = show.entry(i)?;
        let clip = show.clip(i)?;
        let codec_bytes = show
            .sections()
            .nth(usize::from(e.codec_section))
            .map_or(0, |(_, len)| len);
        let looping = e.looping.map_or(String::new(), |l| {
            format!(", loops {}..{} (seam {} frames)", l.start, l.end, l.seam)
        });
        s += &format!(
            "clip {i} `{}`: {} frames, {:.3} s, {} ({codec_bytes} bytes, section {}){looping}\n",
            e.name,
            e.frames,
            clip.header().duration_us() as f64 * 1e-6,
            mocap_encoder::show::section_name(clip.codec_id()),
            e.codec_section
        );
        if list_channels {
            if let Some(sec) = clip.sections().nth(usize::from(e.codec_section)) {
                if let Some(text) = codec::describe_section(sec.id, sec.bytes, clip.header(), true)
                {
                    s += &text;
                }
            }
        }
    }
    if let Some(c) = show.cues() {
        s += &format!("default transition {} ms\n", c.default_fade_ms);
        for l in 0..c.list_count() {
            let Some(list) = c.list(l) else { continue };
            s += &format!("cue list `{}`: {} cues\n", list.name, list.len());
            for cue in list.cues() {
                let what = match cue.action {
                    Action::Play(k) => format!("play `{}`", name(k)),
                    Action::Fade { clip, ms } => format!("fade to `{}` over {ms} ms", name(clip)),
                    Action::Queue(k) => format!("queue `{}`", name(k)),
                    Action::Stop => "stop".into(),
                    Action::Hold => "hold".into(),
                    Action::Resume => "resume".into(),
                    Action::Loop(on) => format!("loop {}", if on { "on" } else { "off" }),
                    Action::Gpio { pin, level } => {
                        format!("gpio {pin} {}", if level { "high" } else { "low" })
                    }
                    Action::Serial(b) => format!("serial {b:02x?}"),
                };
                s += &format!("  {:>9.3} s  {what}\n", f64::from(cue.at_ms) / 1000.0);
            }
        }
        if c.idle_count() > 0 {
            let idle: Vec<String> = (0..c.idle_count())
                .filter_map(|k| c.idle(k))
                .map(|k| format!("`{}`", name(k)))
                .collect();
            s += &format!("idle clips: {}\n", idle.join(", "));
        }
        for k in 0..c.trigger_count() {
            let Some(t) = c.trigger(k) else { continue };
            let targets: Vec<String> = (0..t.target_count())
                .filter_map(|j| t.target(j))
                .map(|j| match t.kind {
                    TriggerKind::Clip => format!("clip `{}`", name(j)),
                    TriggerKind::List => format!("list `{}`", c.list(j).map_or("?", |l| l.name)),
                })
                .collect();
            s += &format!(
                "trigger input {}: {} (cooldown {} ms)\n",
                t.input,
                targets.join(" | "),
                t.cooldown_ms
            );
        }
    }
    for (i, (id, len)) in show.sections().enumerate() {
        s += &format!(
            "section {i} {id:#04x} {}: {len} bytes\n",
            mocap_encoder::show::section_name(id)
        );
    }
    Ok(s)
}
