//! `mocap generate`: the procedural demo clip the project ships, and
//! `mocap generate long`: a long input made from a real take (issue 15).

use std::path::PathBuf;

use mocap_encoder::generate::{self, LongOptions};
use mocap_encoder::{bvh, input};

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    #[command(subcommand)]
    command: Option<Generate>,
    /// Output BVH file (the demo clip).
    #[arg(short, long, required = true)]
    output: Option<PathBuf>,
}

#[derive(clap::Subcommand)]
enum Generate {
    /// A long input: a take repeated with its root path and heading
    /// continued (each repetition starts where the previous one ended,
    /// the pose blended across the seam), e.g. 100 000 frames of a walk.
    Long(LongArgs),
}

#[derive(clap::Args)]
struct LongArgs {
    /// The take: a BVH file (or an AMC with its ASF).
    #[arg(long)]
    from: PathBuf,
    /// The ASF skeleton of an `.amc` take (default: the `.asf` beside it;
    /// AMC takes are read at 120 Hz, CMU's rate).
    #[arg(long)]
    skeleton: Option<PathBuf>,
    /// Frames of the result.
    #[arg(long)]
    frames: usize,
    /// Frames dropped from the take's start first (CMU's first frame is a
    /// reference pose: 1 drops it).
    #[arg(long, default_value_t = 0)]
    skip: usize,
    /// Frame rate of the result in Hz (the take resampled, linearly;
    /// default: the take's).
    #[arg(long)]
    fps: Option<f64>,
    /// Seconds over which the pose difference at each seam is blended out.
    #[arg(long, default_value_t = LongOptions::DEFAULT_BLEND_SECONDS)]
    blend: f64,
    /// Output BVH file.
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(a: Args) -> super::Result {
    if let Some(Generate::Long(l)) = a.command {
        return long(l);
    }
    let output = a.output.ok_or("--output is required")?;
    bvh::write_file(&generate::animatronic_demo(), &output)
        .map_err(|e| format!("{}: {e}", output.display()))?;
    eprintln!("wrote {}", output.display());
    Ok(())
}

fn long(a: LongArgs) -> super::Result {
    let take = input::read_motion(&a.from, a.skeleton.as_deref())?;
    super::warn_limits(&a.from, &take);
    let opts = LongOptions {
        frames: a.frames,
        skip: a.skip,
        fps: a.fps,
        blend_seconds: a.blend,
    };
    let m = generate::long_take(&take.motion, &opts)?;
    bvh::write_file(&m, &a.output).map_err(|e| format!("{}: {e}", a.output.display()))?;
    eprintln!(
        "wrote {}: {} frames at {:.1} Hz from {} ({} frames)",
        a.output.display(),
        m.frames(),
        1.0 / m.frame_time,
        a.from.display(),
        take.motion.frames()
    );
    Ok(())
}
