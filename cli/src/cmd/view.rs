//! `mocap view`: one self-contained HTML page that plays a BVH as a 3-D
//! skeleton, with its decoded `.mcb` clip overlaid and coloured by error,
//! or a servo clip's (or a show's) pulse curves against its limits
//! (`mocap_report::view`).

use std::path::{Path, PathBuf};

use mocap_report::view::{self, ServoSource};

use super::{write, MotionArgs, UnitArg};

#[derive(clap::Args)]
pub struct Args {
    /// The source motion (BVH, or AMC with its ASF), or a servo clip or
    /// show (`.mcb`) to view alone.
    input: PathBuf,
    #[command(flatten)]
    motion: MotionArgs,
    /// The BVH's `.mcb` clip: a motion clip, shown decoded beside it, or a
    /// servo clip (with `--rig`), its curves beside the rig's signals.
    clip: Option<PathBuf>,
    /// Output page (default: the input's stem + `.html`, in the current folder).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Length unit of the input.
    #[arg(long, default_value = "auto")]
    units: UnitArg,
    /// The rig file a servo clip was encoded with (its source BVH first),
    /// or the rig a motion show plays through.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// A show: the command script to run it with (as `mocap play --cues`;
    /// without one, its first cue list runs, or its first clip plays).
    #[arg(long)]
    cues: Option<PathBuf>,
    /// A show: the most seconds it plays when its script has no `end`.
    #[arg(long, default_value_t = 60.0)]
    duration: f64,
}

fn is_clip(p: &Path) -> bool {
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("mcb"))
}

pub fn run(a: Args) -> super::Result {
    let unit = a.units.fixed();
    let out = a.output.clone().unwrap_or_else(|| {
        let stem = a.input.file_stem().unwrap_or(a.input.as_os_str());
        PathBuf::from(stem).with_extension("html")
    });
    let is_show = is_clip(&a.input)
        && std::fs::read(&a.input).is_ok_and(|b| mocap_decoder::Show::parse(&b).is_ok());
    if is_show || is_clip(&a.input) || a.rig.is_some() || a.cues.is_some() {
        let (page, what) = match (&a.clip, &a.rig) {
            _ if is_show || a.cues.is_some() => {
                if a.clip.is_some() {
                    return Err(format!("{}: a show is viewed alone", a.input.display()).into());
                }
                let page =
                    view::load_show(&a.input, a.cues.as_deref(), a.rig.as_deref(), a.duration)?;
                (page, "ticks of the show")
            }
            (None, _) => (view::load_servo(&a.input, None)?, "ticks"),
            (Some(clip), Some(rig)) => {
                let source = ServoSource {
                    bvh: &a.input,
                    rig,
                    unit,
                };
                (view::load_servo(clip, Some(source))?, "ticks")
            }
            (Some(_), None) => {
                return Err(format!(
                    "{}: give the source BVH first (mocap view walk.bvh walk.mcb)",
                    a.input.display()
                )
                .into())
            }
        };
        write(&out, page.html.as_bytes())?;
        eprintln!(
            "wrote {} ({} bytes; {} servos × {} {what}; the playback loop changed the command at {} ticks)",
            out.display(),
            page.html.len(),
            page.servos,
            page.ticks,
            page.shaped_ticks
        );
        if let Some(e) = page.max_error_us {
            eprintln!("largest pulse difference, decoded against the source: {e:.2} µs");
        }
        return Ok(());
    }
    let page = if super::markers::is_marker_file(&a.input) {
        super::markers::view(&a.input, a.clip.as_deref(), &a.units)?
    } else {
        view::load_with(&a.input, a.clip.as_deref(), unit, &a.motion.options())?
    };
    write(&out, page.html.as_bytes())?;
    eprintln!(
        "wrote {} ({} bytes; {} frames × {} joints, positions to {} mm)",
        out.display(),
        page.html.len(),
        page.frames,
        page.joints,
        page.quantum_mm
    );
    if let Some(m) = &page.metrics {
        eprintln!(
            "ARMS {:.3} mm, max joint error {:.3} mm ({} at frame {}: the page's worst frame)",
            m.arms_mm, m.max_joint_err_mm, m.max_joint_err_joint, m.max_joint_err_frame
        );
    }
    Ok(())
}
