//! `mocap view`: one self-contained HTML page that plays a BVH as a 3-D
//! skeleton, with its decoded `.mcb` clip overlaid and coloured by error
//! (`mocap_report::view`).

use std::path::PathBuf;

use mocap_report::view;

use super::{write, UnitArg};

#[derive(clap::Args)]
pub struct Args {
    /// The source BVH.
    input: PathBuf,
    /// Its `.mcb` clip, shown decoded beside it.
    clip: Option<PathBuf>,
    /// Output page (default: the input's stem + `.html`, in the current folder).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Length unit of the input.
    #[arg(long, default_value = "auto")]
    units: UnitArg,
}

pub fn run(a: Args) -> super::Result {
    let unit = match a.units {
        UnitArg::Auto => None,
        UnitArg::Fixed(u) => Some(u),
    };
    let page = view::load(&a.input, a.clip.as_deref(), unit)?;
    let out = a.output.unwrap_or_else(|| {
        let stem = a.input.file_stem().unwrap_or(a.input.as_os_str());
        PathBuf::from(stem).with_extension("html")
    });
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
