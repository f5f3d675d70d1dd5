//! `mocap eval`: decode a clip with the `no_std` decoder and measure it
//! against its source BVH (text or JSON; `--plot` the per-frame error), or
//! a marker clip against its C3D file ([`super::markers::eval`]).

use std::path::PathBuf;

use mocap_encoder::{clipfile, metrics};
use mocap_report::plot;

use super::{parse_clip, read_clip, MotionArgs, UnitArg};

#[derive(clap::Args)]
pub struct Args {
    /// The source motion: BVH, AMC with its ASF (`--skeleton`, or the
    /// `.asf` beside it), or a C3D marker file (`.c3d`).
    input: PathBuf,
    /// The clip.
    clip: PathBuf,
    #[command(flatten)]
    motion: MotionArgs,
    /// One JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Length unit of the input.
    #[arg(long, default_value = "auto")]
    units: UnitArg,
    /// Also draw the per-frame joint-position error (`.svg` or `.png`).
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(a: Args) -> super::Result {
    if super::markers::is_marker_file(&a.input) {
        if a.plot.is_some() {
            return Err("--plot is not drawn for marker clips yet".into());
        }
        return super::markers::eval(&a.input, &a.clip, &a.units, a.json);
    }
    let input = a.motion.read(&a.input)?;
    let unit = a.units.resolve(&input);
    let m = input.motion;
    let bytes = read_clip(&a.clip)?;
    let clip = parse_clip(&a.clip, &bytes)?;
    let back = clipfile::decode_against(&clip, &m, unit.metres()).map_err(|e| {
        format!(
            "{} does not play against {}: {e}",
            a.clip.display(),
            a.input.display()
        )
    })?;
    let file_bytes = std::fs::metadata(&a.input)
        .map(|x| x.len() as usize)
        .unwrap_or(0);
    let x = metrics::compare(&m, &back, unit.metres(), None, bytes.len(), file_bytes);
    if let Some(p) = &a.plot {
        plot::frame_error_plot(p, &m, &back, unit.metres(), &a.clip.display().to_string())?;
        eprintln!("wrote {}", p.display());
    }
    if a.json {
        println!("{}", serde_json::to_string(&x)?);
    } else {
        println!("bytes            {}", x.bytes);
        println!("ratio vs f32     {:.2}:1", x.ratio_f32);
        println!("ratio vs file    {:.2}:1", x.ratio_file);
        println!("ARMS             {:.3} mm", x.arms_mm);
        println!(
            "max joint error  {:.3} mm ({} at frame {})",
            x.max_joint_err_mm, x.max_joint_err_joint, x.max_joint_err_frame
        );
        println!("distortion d     {:.3} %", x.distortion_pct);
        println!(
            "angle RMS / max  {:.4}° / {:.4}°",
            x.angle_rms_deg, x.angle_max_deg
        );
        if x.foot_pairs > 0 {
            println!(
                "foot slide       {:.1} mm/s (source {:.1} mm/s) over {} planted foot-frames",
                x.foot_slide_mm_s, x.foot_slide_source_mm_s, x.foot_pairs
            );
            println!("foot height err  {:.2} mm", x.foot_height_err_mm);
        }
        println!("frames×channels  {}×{}", x.frames, x.channels);
    }
    Ok(())
}
