//! `mocap play`: a clip through a servo rig into servo-controller commands
//! (Maestro, SSC-32), to a port in real time or to a file.

use std::path::PathBuf;

use mocap_encoder::play::{self, Protocol};
use mocap_encoder::rig::Rig;

use super::{parse_clip, read_clip, Destination};

#[derive(clap::Args)]
pub struct Args {
    /// Input .mcb clip.
    clip: PathBuf,
    /// Rig file (TOML, see assets/rigs/README.md); not needed for a
    /// servo clip (`encode --rig`), which carries its rig table.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// Servo controller protocol.
    #[arg(long, value_enum)]
    protocol: ProtocolArg,
    #[command(flatten)]
    dest: Destination,
    /// Servo ticks per second (default: the rig's rate_hz).
    #[arg(long)]
    rate: Option<f64>,
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
    let c = parse_clip(&a.clip, &bytes)?;
    let s = match &a.rig {
        Some(rig) => {
            let rig = Rig::read_file(rig)?;
            play::servo_stream(&c, &rig, protocol, a.rate)?
        }
        None => play::servo_clip_stream(&c, protocol, a.rate)?,
    };
    if let Some(t) = &s.tracks {
        eprint!("{t}");
    }
    let rate = s.rate_hz;
    let period = std::time::Duration::from_secs_f64(1.0 / rate);
    let dest = a.dest.write(&s.ticks, |i| period * i as u32)?;
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
