//! `mocap bench`: the rate–distortion table over files or folders of BVH
//! (Markdown on stdout; `--json` rows, `--plot` the picture).

use std::path::PathBuf;

use mocap_encoder::codec::CodecChoice;
use mocap_report::{bench, plot};

use super::{write, CodecArg};
use crate::progress::{Bar, Nested};

/// The bench's encodes on one bar, their lines above it.
struct BarReport(Bar);

impl bench::Report for BarReport {
    fn encode(
        &self,
        at: usize,
        total: usize,
        label: &str,
    ) -> Box<dyn mocap_encoder::encode::Progress + '_> {
        Box::new(Nested {
            bar: &self.0,
            at,
            units: total,
            label: label.to_string(),
        })
    }

    fn line(&self, line: &str) {
        self.0.println(line);
    }
}

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
    let bar = BarReport(Bar::new(1));
    let rows = bench::run_with(&a.paths, &codecs, &a.max_error, &bar);
    bar.0.finish();
    let rows = rows?;
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
