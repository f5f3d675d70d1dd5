//! `mocap generate`: the procedural demo clip the project ships.

use std::path::PathBuf;

use mocap_encoder::{bvh, generate};

#[derive(clap::Args)]
pub struct Args {
    /// Output BVH file.
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(a: Args) -> super::Result {
    bvh::write_file(&generate::animatronic_demo(), &a.output)
        .map_err(|e| format!("{}: {e}", a.output.display()))?;
    eprintln!("wrote {}", a.output.display());
    Ok(())
}
