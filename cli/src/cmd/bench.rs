//! `mocap bench`: the rate–distortion table over files or folders of BVH
//! (Markdown on stdout; `--json` rows, `--plot` the picture).

use std::path::PathBuf;

use mocap_encoder::codec::CodecChoice;
use mocap_report::{bench, plot};

use super::{write, CodecArg};

#[derive(clap::Args)]
pub struct Args {
    /// BVH files or folders.
    paths: Vec<PathBuf>,
    /// Error bounds, repeatable; `+` joins several into one
    /// (`50mm+arms:10mm`).
    #[arg(long = "max-error", default_values = ["1deg", "0.25deg"])]
    max_error: Vec<String>,
    /// Codecs, repeatable (`auto` keeps the smallest per file).
    #[arg(long, value_enum, default_values = ["index"])]
    codec: Vec<CodecArg>,
    /// Write the rows as JSON here too.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Also draw the rate–distortion plot (`.svg` or `.png`).
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(a: Args) -> super::Result {
    let codecs: Vec<CodecChoice> = a.codec.iter().map(|&c| c.into()).collect();
    let rows = bench::run(&a.paths, &codecs, &a.max_error)?;
    print!("{}", bench::markdown(&rows));
    if let Some(p) = &a.json {
        write(p, serde_json::to_string_pretty(&rows)?.as_bytes())?;
    }
    if let Some(p) = &a.plot {
        plot::rate_distortion_plot(p, &rows)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
