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
pub mod markers;
pub mod play;
pub mod send;
pub mod show;
pub mod target;
pub mod track;
pub mod view;

use std::path::{Path, PathBuf};

use mocap_decoder::Clip;
use mocap_encoder::codec::CodecChoice;
use mocap_encoder::input::{self, Input, InputOptions};
use mocap_encoder::units::LengthUnit;

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
    /// Motion pattern indexing: body-part nodes, segments as references to
    /// time-normalised patterns (SPEC.md §11).
    Pattern,
    /// Repeated motion: primary clips as splines, repeated clips as a
    /// reference map into their primary plus residuals (SPEC.md §12).
    Rma,
    /// Every codec; keep the smallest clip that meets the bound.
    Auto,
}

impl From<CodecArg> for CodecChoice {
    fn from(c: CodecArg) -> Self {
        match c {
            CodecArg::Index => CodecChoice::Index,
            CodecArg::PcaSpline => CodecChoice::PcaSpline,
            CodecArg::Predictive => CodecChoice::Predictive,
            CodecArg::Pattern => CodecChoice::Pattern,
            CodecArg::Rma => CodecChoice::Rma,
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
    /// The unit of `input`: fixed, else the one the file declares (an
    /// ASF's `:units length`), else guessed from the skeleton's height.
    pub fn resolve(&self, input: &Input) -> LengthUnit {
        match self {
            UnitArg::Auto => input.unit_or_detect(),
            UnitArg::Fixed(u) => *u,
        }
    }

    /// The fixed unit, or `None` for `auto`.
    pub fn fixed(&self) -> Option<LengthUnit> {
        match self {
            UnitArg::Auto => None,
            UnitArg::Fixed(u) => Some(*u),
        }
    }
}

/// `--skeleton` and `--fps`: how an `.amc` input is read.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct MotionArgs {
    /// The ASF skeleton of an `.amc` input (default: the `.asf` beside it
    /// named as the AMC, or as its name up to the first `_`, CMU's naming:
    /// 16_15.amc → 16.asf).
    #[arg(long)]
    skeleton: Option<PathBuf>,
    /// Frame rate of an `.amc` input, which states none (default: 120,
    /// CMU's capture rate).
    #[arg(long, value_parser = parse_fps)]
    fps: Option<f64>,
}

fn parse_fps(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("'{s}' is not a positive frame rate in Hz")),
    }
}

impl MotionArgs {
    /// The library's options.
    pub fn options(&self) -> InputOptions {
        InputOptions {
            skeleton: self.skeleton.clone(),
            frame_time: self.fps.map(|f| 1.0 / f),
        }
    }

    /// Reads `path` (BVH, or AMC with its ASF); warns on stderr when AMC
    /// frames leave the ASF's limits.
    pub fn read(&self, path: &Path) -> Result<Input, input::InputError> {
        let i = input::read_motion_with(path, &self.options())?;
        warn_limits(path, &i);
        Ok(i)
    }
}

/// `mocap: warning: …` when frames of an AMC leave its ASF's `limits`.
pub fn warn_limits(path: &Path, i: &Input) {
    let n = i.frames_outside_limits();
    let Some(a) = i.asf.as_ref().filter(|_| n > 0) else {
        return;
    };
    let mut worst = a.amc.limit_violations(&a.asf);
    worst.sort_by_key(|&(_, _, frames)| std::cmp::Reverse(frames));
    let list: Vec<String> = worst
        .iter()
        .take(3)
        .map(|&(b, k, frames)| {
            let bone = &a.asf.bones[b];
            format!("{} {}: {frames}", bone.name, bone.dof[k].name())
        })
        .collect();
    eprintln!(
        "mocap: warning: {}: {n} of {} frames have dof values outside the ASF's limits ({}{})",
        path.display(),
        i.motion.frames(),
        list.join(", "),
        if worst.len() > 3 { ", …" } else { "" }
    );
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

/// A `play` or `send` that Ctrl-C or SIGTERM stopped, after it sent what
/// brings the servos to rest; `mocap` exits with 130.
#[derive(Debug)]
pub struct Stopped(pub String);

impl std::fmt::Display for Stopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Stopped {}

/// Set by Ctrl-C / SIGTERM while a [`Destination`] writes.
static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

impl Destination {
    /// Writes `chunks` in order, chunk `i` not before `due(i)` after the
    /// start unless `--fast`; returns the path written and, when Ctrl-C or
    /// SIGTERM stopped it before chunk `i`, `Some((i, n))` — it then wrote
    /// the `n` chunks of `rest(i)` (what brings the servos to rest from
    /// there) paced one chunk per `period`. A write that fails (a port unplugged) names the port
    /// and says where the servos are left.
    pub fn write(
        &self,
        chunks: &[Vec<u8>],
        due: impl Fn(usize) -> std::time::Duration,
        period: std::time::Duration,
        rest: impl Fn(usize) -> Result<Vec<Vec<u8>>, String>,
    ) -> Result<(PathBuf, Option<(usize, usize)>), String> {
        use std::sync::atomic::Ordering;
        let dest = self
            .port
            .clone()
            .or_else(|| self.output.clone())
            .ok_or("give --port or --output")?;
        let fail = |e: std::io::Error| {
            if self.port.is_some() {
                format!(
                    "{}: {e} (unplugged? the controller holds its last command; the firmware's \
                     streaming mode parks the servos after its stream timeout)",
                    dest.display()
                )
            } else {
                format!("{}: {e}", dest.display())
            }
        };
        let mut file = std::fs::File::create(&dest).map_err(fail)?;
        // One handler per process (a second `set_handler` fails): set it once.
        static HANDLER: std::sync::Once = std::sync::Once::new();
        HANDLER.call_once(|| {
            // Without a handler Ctrl-C kills the process as before: no worse.
            let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::SeqCst));
        });
        let start = std::time::Instant::now();
        for (i, chunk) in chunks.iter().enumerate() {
            if !self.fast {
                let at = start + due(i);
                // Sleep in slices, so a stop is seen within one of them.
                while std::time::Instant::now() < at && !STOP.load(Ordering::SeqCst) {
                    let left = at.saturating_duration_since(std::time::Instant::now());
                    std::thread::sleep(left.min(std::time::Duration::from_millis(5)));
                }
            }
            if STOP.load(Ordering::SeqCst) {
                let tail = rest(i)?;
                let t0 = std::time::Instant::now();
                for (k, c) in tail.iter().enumerate() {
                    if !self.fast {
                        let at = t0 + period * k as u32;
                        std::thread::sleep(at.saturating_duration_since(std::time::Instant::now()));
                    }
                    std::io::Write::write_all(&mut file, c).map_err(fail)?;
                }
                return Ok((dest, Some((i, tail.len()))));
            }
            std::io::Write::write_all(&mut file, chunk).map_err(fail)?;
        }
        Ok((dest, None))
    }
}
