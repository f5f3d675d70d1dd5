//! `mocap bench`: the rate–distortion table over files or folders of motion
//! (Markdown on stdout; `--json` rows, `--plot` the picture), our codecs
//! beside what users pick instead (`--baselines`).

use std::path::PathBuf;

use mocap_encoder::codec::CodecChoice;
use mocap_report::bench::{self, Baseline, Method};
use mocap_report::plot;

use super::write;
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

/// `--codec` of `mocap bench`: our codecs and the size references.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchCodecArg {
    /// Low-resolution model-based indexing (SPEC.md §4).
    Index,
    /// Segment PCA + key-frame splines (SPEC.md §5).
    PcaSpline,
    /// Prediction from the last two values, residuals range-coded (SPEC.md §5b).
    Predictive,
    /// Motion pattern indexing (SPEC.md §11); each file alone (shows:
    /// `report/examples/pattern_db.rs`).
    Pattern,
    /// Repeated motion analysis (SPEC.md §12).
    Rma,
    /// Every codec; keep the smallest clip that meets the bound.
    Auto,
    /// Baseline: every channel of every frame as 16 bits at a step fitting
    /// its range (not tuned to the bound: its error is reported).
    Raw16,
    /// Baseline: uniform quantisation at the bound, frame differences as
    /// varints, zstd -19.
    #[value(alias = "quant-zstd")]
    Zstd,
    /// Baseline: the same stream as `zstd`, compressed by xz -9e.
    #[value(alias = "quant-xz")]
    Xz,
    /// Baseline: greedy key reduction per channel, linear interpolation
    /// within the bound, keys as (frame gap, quantised value) varints.
    KeyframeLinear,
}

impl From<BenchCodecArg> for Method {
    fn from(c: BenchCodecArg) -> Self {
        match c {
            BenchCodecArg::Index => Method::Codec(CodecChoice::Index),
            BenchCodecArg::PcaSpline => Method::Codec(CodecChoice::PcaSpline),
            BenchCodecArg::Predictive => Method::Codec(CodecChoice::Predictive),
            BenchCodecArg::Pattern => Method::Codec(CodecChoice::Pattern),
            BenchCodecArg::Rma => Method::Codec(CodecChoice::Rma),
            BenchCodecArg::Auto => Method::Codec(CodecChoice::Auto),
            BenchCodecArg::Raw16 => Method::Baseline(Baseline::Raw16),
            BenchCodecArg::Zstd => Method::Baseline(Baseline::QuantZstd),
            BenchCodecArg::Xz => Method::Baseline(Baseline::QuantXz),
            BenchCodecArg::KeyframeLinear => Method::Baseline(Baseline::KeyframeLinear),
        }
    }
}

/// The arguments (the command's help text is its doc in `main.rs`).
#[derive(clap::Args)]
pub struct Args {
    /// Motion files or folders (.bvh, .amc with its .asf, .c3d marker files;
    /// a marker file skips angle bounds).
    paths: Vec<PathBuf>,
    /// Error bounds, repeatable; `+` joins several into one
    /// (`50mm+arms:10mm`).
    #[arg(long = "max-error", visible_alias = "bound", default_values = ["1deg", "0.25deg"])]
    max_error: Vec<String>,
    /// Codecs and baselines, repeatable, in the table's order (`auto` keeps
    /// the smallest of our codecs per file).
    #[arg(long, value_enum, default_values = ["index"])]
    codec: Vec<BenchCodecArg>,
    /// Add every baseline (raw16, zstd, xz, keyframe-linear) after the
    /// codecs.
    #[arg(long)]
    baselines: bool,
    /// Print only the per-folder totals, not every file's row (then, with
    /// baselines and codecs, the smallest of each side per folder and
    /// bound, in both cases).
    #[arg(long)]
    summary: bool,
    /// Write the rows as JSON here too.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Also draw the rate–distortion plot and the ratio bars (`.svg` or
    /// `.png`).
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// The methods asked for, in order, each once.
fn methods(a: &Args) -> Vec<Method> {
    let mut out: Vec<Method> = Vec::new();
    let baselines = a
        .baselines
        .then_some(Baseline::ALL.map(Method::Baseline))
        .into_iter()
        .flatten();
    for m in a.codec.iter().map(|&c| Method::from(c)).chain(baselines) {
        if !out.contains(&m) {
            out.push(m);
        }
    }
    out
}

pub fn run(a: Args) -> super::Result {
    let bar = BarReport(Bar::new(1));
    let rows = bench::run_with(&a.paths, &methods(&a), &a.max_error, &bar);
    bar.0.finish();
    let rows = rows?;
    if a.summary {
        print!("{}", bench::summary(&rows));
    } else {
        print!("{}", bench::markdown(&rows));
    }
    let versus = bench::versus(&rows);
    if !versus.is_empty() {
        print!("\n{versus}");
    }
    if let Some(p) = &a.json {
        write(p, serde_json::to_string_pretty(&rows)?.as_bytes())?;
    }
    if let Some(p) = &a.plot {
        plot::rate_distortion_plot(p, &rows)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
