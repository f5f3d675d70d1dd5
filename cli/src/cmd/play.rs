//! `mocap play`: a clip through a servo rig into servo-controller commands
//! (Maestro, SSC-32), to a port in real time or to a file.

use std::path::PathBuf;

use mocap_encoder::play::{self, Figure, FigureReport, Fit, Identity, Policy, Protocol};

use mocap_encoder::rig::Rig;

use super::{parse_clip, read_clip, Destination};

#[derive(clap::Args)]
pub struct Args {
    /// Input .mcb clip.
    clip: PathBuf,
    /// Rig file (TOML, see assets/rigs/README.md). For a motion clip: the
    /// rig that maps it to servos. For a servo clip (`encode --rig`, which
    /// carries its own rig table): the figure's hard limits — every pulse
    /// also held to this rig's pulse ranges, speeds and accelerations, the
    /// return to rest at its neutrals, every clamp reported.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// With --rig on a servo clip made for another rig: `refuse` it,
    /// play it clamped only if its every servo lies inside the figure's
    /// limits (`clamp-if-inside`, the firmware's default), or play it
    /// clamped whatever its rig says (`clamp`).
    #[arg(long, value_enum, default_value = "clamp-if-inside", requires = "rig")]
    policy: PolicyArg,
    /// Servo controller protocol.
    #[arg(long, value_enum)]
    protocol: ProtocolArg,
    #[command(flatten)]
    dest: Destination,
    /// Servo ticks per second (default: the rig's rate_hz).
    #[arg(long)]
    rate: Option<f64>,
    /// Power levels (SPEC.md §6.1): `LEVEL[@TIME],…`, e.g. `2` or
    /// `0,3@2s,0@4.5s`. At level L the clip is sampled every 2^L-th tick
    /// (0 to 4) and the ticks between interpolated, as the firmware does to
    /// save power; a change never jumps. Default: level 0, every tick.
    #[arg(long)]
    power: Option<String>,
    /// A show (SPEC.md §9): the command script to run it with (one
    /// `<seconds> <command>` per line: list, trigger, play, fade, queue,
    /// loop, hold, resume, stop, end). Without one, the show's first cue
    /// list runs (or its first clip plays).
    #[arg(long)]
    cues: Option<PathBuf>,
    /// A show: the most seconds it plays when its script has no `end`.
    #[arg(long, default_value_t = 600.0)]
    duration: f64,
}

/// `--policy`: `mocap_servo::Policy` as a command-line value.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum PolicyArg {
    /// Refuse a clip made for another rig.
    Refuse,
    /// Play it clamped if its every servo lies inside the hard limits.
    ClampIfInside,
    /// Play it clamped whatever its rig says.
    Clamp,
}

/// `--protocol`: [`Protocol`] as a command-line value.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum ProtocolArg {
    /// Pololu Maestro compact protocol: Set Target `0x84 ch low7 high7`
    /// in quarter-microseconds.
    Maestro,
    /// Lynxmotion SSC-32 group move: `#<ch>P<µs>…T<ms>\r`.
    Ssc32,
}

pub fn run(a: Args) -> super::Result {
    let protocol = match a.protocol {
        ProtocolArg::Maestro => Protocol::Maestro,
        ProtocolArg::Ssc32 => Protocol::Ssc32,
    };
    let bytes = read_clip(&a.clip)?;
    let policy = match a.policy {
        PolicyArg::Refuse => Policy::Refuse,
        PolicyArg::ClampIfInside => Policy::ClampIfInside,
        PolicyArg::Clamp => Policy::ClampAlways,
    };
    let power = match &a.power {
        Some(text) => play::parse_power(text).map_err(|e| format!("--power: {e}"))?,
        None => Vec::new(),
    };
    if bytes.get(4) == Some(&mocap_decoder::consts::VERSION_SHOW) {
        if !power.is_empty() {
            return Err(format!(
                "{}: --power plays one clip; a show's players sample every tick",
                a.clip.display()
            )
            .into());
        }
        let s = play_show(&a, &bytes, protocol, policy)?;
        return send(&a, &s);
    }
    if a.cues.is_some() {
        return Err(format!(
            "{}: --cues plays a show (mocap show build); this is one clip",
            a.clip.display()
        )
        .into());
    }
    let c = parse_clip(&a.clip, &bytes)?;
    let s = match &a.rig {
        Some(rig) if c.rig().is_some() => {
            let figure = Figure::from_rig(&Rig::read_file(rig)?, policy);
            play::servo_clip_stream_at(&c, Some(&figure), protocol, a.rate, &power)?
        }
        Some(rig) => {
            let rig = Rig::read_file(rig)?;
            play::servo_stream_at(&c, &rig, protocol, a.rate, &power)?
        }
        None => play::servo_clip_stream_at(&c, None, protocol, a.rate, &power)?,
    };
    send(&a, &s)
}

/// A show run by its command script (or its first cue list) at the rig's
/// rate, its output events on stderr.
fn play_show(
    a: &Args,
    bytes: &[u8],
    protocol: Protocol,
    policy: Policy,
) -> super::Result<play::ServoStream> {
    use mocap_encoder::show::play::{show_stream, Script};
    let show =
        mocap_decoder::Show::parse(bytes).map_err(|e| format!("{}: {e}", a.clip.display()))?;
    if a.rate.is_some() {
        return Err("a show plays at its rig's rate (no --rate)".into());
    }
    let script = match &a.cues {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            Script::parse(&text, &p.display().to_string(), &show)?
        }
        None => Script::first_list_or_clip(&show),
    };
    let rig = a.rig.as_ref().map(|r| Rig::read_file(r)).transpose()?;
    let figure = match (&rig, show.rig()) {
        (Some(r), Some(_)) => Some(Figure::from_rig(r, policy)),
        _ => None,
    };
    let motion_rig = if show.rig().is_none() {
        rig.as_ref()
    } else {
        None
    };
    let played = show_stream(
        &show,
        &script,
        protocol,
        motion_rig,
        figure.as_ref(),
        a.duration,
    )?;
    for (_, line) in &played.events {
        eprintln!("{line}");
    }
    Ok(played.stream)
}

/// Writes a played stream to the port or file, Ctrl-C returning every
/// servo to rest.
fn send(a: &Args, s: &play::ServoStream) -> super::Result {
    if let Some(t) = &s.tracks {
        eprint!("{t}");
    }
    if let Some(f) = &s.figure {
        eprint!("{}", figure_text(f));
    }
    let rate = s.rate_hz;
    let period = std::time::Duration::from_secs_f64(1.0 / rate);
    let rest = |i: usize| s.rest_after(i).map_err(|e| e.to_string());
    let (dest, stopped) = a
        .dest
        .write(&s.ticks, |i| period * i as u32, period, rest)?;
    if let Some((i, back)) = stopped {
        return Err(super::Stopped(format!(
            "{}: after {i} of {} ticks; every servo returned to rest in {back} ticks at its speed limits",
            dest.display(),
            s.ticks.len()
        ))
        .into());
    }
    eprintln!(
        "{}: {} ticks at {rate} Hz ({} of the clip, {} back to neutral), {} bytes",
        dest.display(),
        s.ticks.len(),
        s.clip_ticks,
        s.ticks.len() - s.clip_ticks,
        s.ticks.iter().map(Vec::len).sum::<usize>()
    );
    Ok(())
}

/// What the figure's hard limits did, for stderr.
fn figure_text(f: &FigureReport) -> String {
    let mut t = String::from("figure: ");
    t += match (f.identity, f.fit) {
        (Identity::Same, _) => "the clip was made for this rig (rig table and digest)",
        (Identity::SameTable, _) => {
            "the clip was made for this rig (its rig table; it carries no rig digest)"
        }
        (Identity::OtherDigest, _) => {
            "the clip has this rig's table but another rig digest (other speed or acceleration limits): played clamped"
        }
        (Identity::OtherTable, Fit::Inside) => {
            "the clip was made for another rig, every servo inside the hard limits"
        }
        (Identity::OtherTable, _) => {
            "the clip was made for another rig, which leaves the hard limits: played clamped"
        }
    };
    t.push('\n');
    let clamped: Vec<String> = f
        .clamps
        .iter()
        .filter(|c| c.ticks > 0)
        .map(|c| {
            format!(
                "output {}: {} ticks, at most {} µs",
                c.output,
                c.ticks,
                f64::from(c.worst_qus) / 4.0
            )
        })
        .collect();
    if clamped.is_empty() {
        t += "figure: no pulse changed by the hard limits\n";
    } else {
        t += &format!(
            "figure: hard limits changed pulses of {}\n",
            clamped.join("; ")
        );
    }
    t
}
