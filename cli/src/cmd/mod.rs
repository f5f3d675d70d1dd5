//! The subcommands, one module each, and what several of them share:
//! reading and writing files with the path in the message, the `--units`
//! and `--codec` arguments, and the `--port`/`--output` destination of
//! `play` and `send`.

pub mod bench;
pub mod decode;
pub mod encode;
pub mod eval;
pub mod generate;
pub mod info;
pub mod play;
pub mod send;
pub mod track;

use std::path::{Path, PathBuf};

use mocap_decoder::Clip;
use mocap_encoder::codec::CodecChoice;
use mocap_encoder::motion::Motion;
use mocap_encoder::units::{self, LengthUnit};

/// What a subcommand returns: the library's typed errors (and the CLI's own
/// messages), printed by `main` as `mocap: error: …`.
pub type Result<T = (), E = Box<dyn std::error::Error>> = std::result::Result<T, E>;

/// `--codec`: the library's [`CodecChoice`] as a command-line value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CodecArg {
    /// Low-resolution model-based indexing (SPEC.md §4).
    Index,
    /// Segment PCA + key-frame splines (SPEC.md §5).
    PcaSpline,
    /// Prediction from the last two values, residuals range-coded (SPEC.md §5b).
    Predictive,
    /// Every codec; keep the smallest clip that meets the bound.
    Auto,
}

impl From<CodecArg> for CodecChoice {
    fn from(c: CodecArg) -> Self {
        match c {
            CodecArg::Index => CodecChoice::Index,
            CodecArg::PcaSpline => CodecChoice::PcaSpline,
            CodecArg::Predictive => CodecChoice::Predictive,
            CodecArg::Auto => CodecChoice::Auto,
        }
    }
}

/// `--units`: a fixed length unit, or `auto` (from the skeleton's height).
#[derive(Clone, Debug)]
pub enum UnitArg {
    Auto,
    Fixed(LengthUnit),
}

impl std::str::FromStr for UnitArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            Ok(UnitArg::Auto)
        } else {
            s.parse::<LengthUnit>()
                .map(UnitArg::Fixed)
                .map_err(|e| e.to_string())
        }
    }
}

impl UnitArg {
    /// The unit of `m`.
    pub fn resolve(&self, m: &Motion) -> LengthUnit {
        match self {
            UnitArg::Auto => units::detect(m),
            UnitArg::Fixed(u) => *u,
        }
    }
}

/// A file's bytes; the message names the file.
pub fn read_clip(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// A clip parsed by the `no_std` decoder; the message names the file.
pub fn parse_clip<'a>(path: &Path, bytes: &'a [u8]) -> Result<Clip<'a>, String> {
    Clip::parse(bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes a file; the message names it.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Where `play` and `send` write, and whether they keep real time.
#[derive(clap::Args, Debug)]
pub struct Destination {
    /// Serial device to write to (e.g. /dev/ttyACM0; set its line speed
    /// beforehand, e.g. `stty -F /dev/ttyUSB0 115200 raw`).
    #[arg(long, conflicts_with = "output", required_unless_present = "output")]
    port: Option<PathBuf>,
    /// Write the bytes to this file instead of a port.
    #[arg(long)]
    output: Option<PathBuf>,
    /// Do not pace the writes in real time.
    #[arg(long)]
    fast: bool,
}

impl Destination {
    /// Writes `chunks` in order, chunk `i` not before `due(i)` after the
    /// start unless `--fast`; returns the path written.
    pub fn write(
        &self,
        chunks: &[Vec<u8>],
        due: impl Fn(usize) -> std::time::Duration,
    ) -> Result<PathBuf, String> {
        let dest = self
            .port
            .clone()
            .or_else(|| self.output.clone())
            .ok_or("give --port or --output")?;
        let fail = |e: std::io::Error| format!("{}: {e}", dest.display());
        let mut file = std::fs::File::create(&dest).map_err(fail)?;
        let start = std::time::Instant::now();
        for (i, chunk) in chunks.iter().enumerate() {
            if !self.fast {
                let at = start + due(i);
                std::thread::sleep(at.saturating_duration_since(std::time::Instant::now()));
            }
            std::io::Write::write_all(&mut file, chunk).map_err(fail)?;
        }
        Ok(dest)
    }
}
