//! `mocap send`: a clip uploaded to the firmware's streaming mode, or its
//! live poses at the rig's rate (postcard + COBS + CRC frames, SPEC.md §8).

use std::path::PathBuf;

use mocap_encoder::play;

use super::{parse_clip, read_clip, Destination};

#[derive(clap::Args)]
pub struct Args {
    /// Input .mcb clip.
    clip: PathBuf,
    #[command(flatten)]
    dest: Destination,
    /// Line rate used for pacing the clip upload, bit/s (8N1).
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Ask the firmware to loop the clip.
    #[arg(long = "loop", conflicts_with = "poses")]
    looped: bool,
    /// Send the whole upload (every chunk in order, then `Play`) this many times: a
    /// carousel for a lossy line without a way back. The firmware keeps each chunk from
    /// whichever pass brings it intact and starts the clip once it has every chunk and a
    /// `Play`; a `Play` that comes first is remembered. At 1 % corrupted bytes the demo's
    /// 19-chunk servo clip arrives whole with 1 pass never, 8 passes 87 %, 16 passes
    /// 100 % (BENCHMARKS.md §5). Each pass costs the clip's bytes again.
    #[arg(long, default_value_t = 1, conflicts_with = "poses",
          value_parser = clap::value_parser!(u32).range(1..))]
    passes: u32,
    /// Send live poses (a servo clip's pulses at its rig's rate, paced in real time
    /// unless --fast) instead of uploading the clip.
    #[arg(long)]
    poses: bool,
    /// A show (SPEC.md §9) in the firmware's flash: send this command script's commands
    /// (`mocap play --cues` format) as `Show` frames (SPEC.md §8.2), each a second before
    /// its time, instead of a clip.
    #[arg(long, conflicts_with_all = ["poses", "looped"])]
    cues: Option<PathBuf>,
}

pub fn run(a: Args) -> super::Result {
    let bytes = read_clip(&a.clip)?;
    if bytes.get(4) == Some(&mocap_decoder::consts::VERSION_SHOW) {
        return send_commands(&a, &bytes);
    }
    if a.cues.is_some() {
        return Err(format!(
            "{}: --cues goes with a show (mocap show build)",
            a.clip.display()
        )
        .into());
    }
    let c = parse_clip(&a.clip, &bytes)?;
    if a.poses {
        let p = play::pose_frames(&c)?;
        let period = std::time::Duration::from_secs_f64(1000.0 / f64::from(p.rate_mhz.max(1)));
        let (dest, stopped) = a.dest.write(
            &p.frames,
            |i| std::time::Duration::from_micros(p.due_us(i)),
            period,
            |_| Ok(vec![play::stop_frame().map_err(|e| e.to_string())?]),
        )?;
        if let Some((i, _)) = stopped {
            return Err(super::Stopped(format!(
                "{}: after {i} of {} frames; sent Stop (the firmware parks every servo at its speed limits)",
                dest.display(),
                p.frames.len()
            ))
            .into());
        }
        eprintln!(
            "{}: {} poses at {} Hz, {} frames, {} bytes",
            dest.display(),
            p.frames.len() - 2,
            f64::from(p.rate_mhz) / 1000.0,
            p.frames.len(),
            p.frames.iter().map(Vec::len).sum::<usize>()
        );
        return Ok(());
    }
    let frames = play::clip_frames(&bytes, a.looped, a.passes)?;
    // Frame i goes out once the bytes before it have crossed the
    // line: 10 bits per byte on an 8N1 line.
    let before: Vec<usize> = frames
        .iter()
        .scan(0, |sent, f| {
            let at = *sent;
            *sent += f.len();
            Some(at)
        })
        .collect();
    let bit = 1.0 / f64::from(a.baud.max(1));
    let (dest, stopped) = a.dest.write(
        &frames,
        |i| std::time::Duration::from_secs_f64(before[i] as f64 * 10.0 * bit),
        std::time::Duration::ZERO,
        |_| Ok(vec![play::stop_frame().map_err(|e| e.to_string())?]),
    )?;
    if let Some((i, _)) = stopped {
        return Err(super::Stopped(format!(
            "{}: upload stopped after {i} of {} frames; sent Stop",
            dest.display(),
            frames.len()
        ))
        .into());
    }
    eprintln!(
        "{}: {} pass(es), {} frames, {} bytes",
        dest.display(),
        a.passes,
        frames.len(),
        frames.iter().map(Vec::len).sum::<usize>()
    );
    Ok(())
}

/// A show's command script as `Show` frames, paced by their due times.
fn send_commands(a: &Args, bytes: &[u8]) -> super::Result {
    use mocap_encoder::show::play::{command_frames, Script};
    let show =
        mocap_decoder::Show::parse(bytes).map_err(|e| format!("{}: {e}", a.clip.display()))?;
    let Some(cues) = &a.cues else {
        return Err(format!(
            "{}: a show lives in the firmware's flash; send its commands with --cues cues.txt",
            a.clip.display()
        )
        .into());
    };
    let text = std::fs::read_to_string(cues).map_err(|e| format!("{}: {e}", cues.display()))?;
    let script = Script::parse(&text, &cues.display().to_string(), &show)?;
    let timed = command_frames(&script)?;
    let frames: Vec<Vec<u8>> = timed.iter().map(|(_, f)| f.clone()).collect();
    let (dest, stopped) = a.dest.write(
        &frames,
        |i| std::time::Duration::from_micros(timed[i].0),
        std::time::Duration::ZERO,
        |_| Ok(vec![play::stop_frame().map_err(|e| e.to_string())?]),
    )?;
    if let Some((i, _)) = stopped {
        return Err(super::Stopped(format!(
            "{}: after {i} of {} frames; sent Stop",
            dest.display(),
            frames.len()
        ))
        .into());
    }
    eprintln!(
        "{}: {} commands, {} frames, {} bytes",
        dest.display(),
        script.commands.len(),
        frames.len(),
        frames.iter().map(Vec::len).sum::<usize>()
    );
    Ok(())
}
