//! `mocap decode`: a clip back to BVH, or to the firmware's UART text.

use std::path::PathBuf;

use mocap_encoder::{bvh, clipfile};

use super::{parse_clip, read_clip, write};

#[derive(clap::Args)]
pub struct Args {
    /// Input .mcb clip.
    input: PathBuf,
    /// Output file (BVH unless --text).
    #[arg(short, long)]
    output: PathBuf,
    /// Write the firmware's UART text format instead of BVH.
    #[arg(long)]
    text: bool,
}

pub fn run(a: Args) -> super::Result {
    let bytes = read_clip(&a.input)?;
    let clip = parse_clip(&a.input, &bytes)?;
    if a.text {
        let frames = clipfile::decode_all(&clip)?;
        let s = clipfile::uart_text(&frames, clip.header().channel_count());
        write(&a.output, s.as_bytes())?;
    } else {
        let m = clipfile::to_motion(&clip)?;
        bvh::write_file(&m, &a.output).map_err(|e| format!("{}: {e}", a.output.display()))?;
    }
    eprintln!("wrote {}", a.output.display());
    Ok(())
}
