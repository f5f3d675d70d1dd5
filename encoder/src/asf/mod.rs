//! ASF (skeleton) + AMC (motion) reader: the Acclaim format the CMU
//! database distributes natively, converted into the same [`Motion`] model
//! the BVH reader builds.
//!
//! Hand-written: no maintained Rust crate reads ASF/AMC (the few on
//! crates.io are unmaintained toys without error positions), and the format
//! is small. `skeleton` reads the ASF, `motion` the AMC, `convert` bakes the
//! two into a [`Motion`].
//!
//! # What is read
//!
//! * LF, CRLF or lone CR line endings, tabs and any whitespace, a UTF-8 BOM,
//!   `#` comments anywhere (to the end of the line), keywords and dof names
//!   in any case (bone names are matched exactly);
//! * ASF: `:version`, `:name`, `:units` (`mass`, `length`, `angle deg|rad`),
//!   `:documentation` (free text, kept), `:root` (`order`, `axis`,
//!   `position`, `orientation`), `:bonedata` (`begin`/`end` blocks with `id`,
//!   `name`, `direction`, `length`, `axis x y z ORDER`, `dof` (any subset and
//!   order of `rx ry rz tx ty tz l`), `limits` (one `(lo hi)` pair per dof,
//!   on the `limits` line and the lines after it, `inf` allowed), `bodymass`
//!   and `cofmass` (ignored)), `:hierarchy` (`begin`, `parent child…` lines,
//!   `end`); other sections are skipped;
//! * AMC: header lines (`:FULLY-SPECIFIED`, `:DEGREES`, `:RADIANS`, other
//!   `:` lines ignored), then frames: a frame-number line (frames numbered
//!   consecutively) followed by one line per bone with dof, `name v1 v2 …`
//!   with the values in that bone's `dof` order (the root's in its `:root
//!   order`), in any order of bones. Bones without dof have no line (a line
//!   with no value is accepted).
//!
//! Angles of the ASF (`axis`, `orientation`, rotation limits) are in the
//! ASF's `:units angle`; AMC values in the AMC's `:DEGREES`/`:RADIANS`,
//! else the ASF's unit. Lengths stay in the file's unit: `:units length
//! 0.45` is the CMU unit (1/0.45 inch, [`LengthUnit::Cmu`]), reported by
//! [`AsfMotion::declared_unit`]; other length factors report no unit (the
//! caller falls back to [`crate::units::detect`]).
//!
//! # Conversion (baking)
//!
//! As standard converters do: one joint per ASF bone, placed at its parent
//! bone's tip (the root's children at the root), an End Site at the tip of
//! every bone without children; every joint frame is world-aligned in the
//! rest pose, so a joint's OFFSET is its parent bone's `direction ×
//! length` (ASF directions are in world coordinates; normalised on
//! reading) and the root's OFFSET is `:root position`. A bone's rotation in
//! its parent's frame is `C·M·C⁻¹`, `C` the bone's `axis` rotation and `M`
//! the product of its dof rotations. See `convert` for the channels.
//!
//! AMC files carry no frame rate: CMU captured at 120 Hz, the default
//! ([`DEFAULT_FRAME_TIME`]); [`AmcOptions::frame_time`] overrides it.
//!
//! Every error names the file, the 1-based line and column; see
//! [`AsfError`].

mod convert;
mod motion;
mod skeleton;

use std::fmt;
use std::path::Path;

pub use convert::{bake, BakeReport, EULER_ORDER};
pub use motion::{parse_amc, Amc, LIMIT_TOLERANCE};
pub use skeleton::{parse_asf, AngleUnit, Asf, AsfBone, AsfRoot, AsfUnits, Dof};

use crate::motion::Motion;
use crate::units::LengthUnit;

/// The frame time of AMC files, which do not state one: CMU's 120 Hz.
pub const DEFAULT_FRAME_TIME: f64 = 1.0 / 120.0;

/// An ASF or AMC reading error with its position in the source text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AsfError {
    /// The file name as given to the reader.
    pub file: String,
    /// 1-based line of the offending token (0 for I/O errors and errors of
    /// the whole file).
    pub line: usize,
    /// 1-based column, in characters, of the offending token (0 when
    /// unknown).
    pub column: usize,
    /// What went wrong.
    pub message: String,
}

impl fmt::Display for AsfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        crate::located::write_located(f, &self.file, self.line, self.column, &self.message)
    }
}

impl std::error::Error for AsfError {}

impl AsfError {
    /// An error at `line` and `column` (a known line with column 0 is
    /// placed at column 1: the line itself).
    pub(crate) fn new(file: &str, line: usize, column: usize, message: impl Into<String>) -> Self {
        AsfError {
            file: file.to_string(),
            line,
            column: if line > 0 { column.max(1) } else { column },
            message: message.into(),
        }
    }
}

/// How an AMC is read: its frame time (AMC files state none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmcOptions {
    /// Seconds per frame (default [`DEFAULT_FRAME_TIME`], CMU's 120 Hz).
    pub frame_time: f64,
}

impl Default for AmcOptions {
    fn default() -> Self {
        AmcOptions {
            frame_time: DEFAULT_FRAME_TIME,
        }
    }
}

/// An ASF + AMC pair read and baked: the motion, the skeleton as the ASF
/// states it (limits included), and what the reading found.
#[derive(Clone, Debug)]
pub struct AsfMotion {
    /// The baked motion (BVH model).
    pub motion: Motion,
    /// The ASF skeleton as read.
    pub asf: Asf,
    /// The AMC frames as read.
    pub amc: Amc,
    /// What the conversion measured.
    pub report: BakeReport,
}

impl AsfMotion {
    /// The length unit the ASF declares: `:units length 0.45` is the CMU
    /// unit; `None` for other factors.
    pub fn declared_unit(&self) -> Option<LengthUnit> {
        self.asf.units.length_unit()
    }

    /// Frames with at least one dof value outside its `limits`.
    pub fn frames_outside_limits(&self) -> usize {
        self.amc.frames_outside_limits(&self.asf)
    }
}

/// Reads a file as text (invalid UTF-8 replaced), the error naming it.
fn read_text(path: &Path) -> Result<String, AsfError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path)
        .map_err(|e| AsfError::new(&file, 0, 0, format!("cannot read file: {e}")))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// Reads and parses an ASF file.
pub fn read_asf(path: &Path) -> Result<Asf, AsfError> {
    parse_asf(&read_text(path)?, &path.display().to_string())
}

/// Reads an ASF and an AMC file and bakes them into a [`Motion`].
pub fn read_files(asf: &Path, amc: &Path, opts: &AmcOptions) -> Result<AsfMotion, AsfError> {
    let skeleton = read_asf(asf)?;
    let amc_name = amc.display().to_string();
    let frames = parse_amc(&read_text(amc)?, &amc_name, &skeleton)?;
    from_parts(skeleton, frames, &amc_name, opts)
}

/// Parses ASF and AMC texts and bakes them; the names are only used in
/// error messages.
pub fn parse_strs(
    asf: &str,
    asf_name: &str,
    amc: &str,
    amc_name: &str,
    opts: &AmcOptions,
) -> Result<AsfMotion, AsfError> {
    let skeleton = parse_asf(asf, asf_name)?;
    let frames = parse_amc(amc, amc_name, &skeleton)?;
    from_parts(skeleton, frames, amc_name, opts)
}

fn from_parts(
    asf: Asf,
    amc: Amc,
    amc_name: &str,
    opts: &AmcOptions,
) -> Result<AsfMotion, AsfError> {
    if !(opts.frame_time.is_finite() && opts.frame_time > 0.0) {
        return Err(AsfError::new(
            amc_name,
            0,
            0,
            format!("frame time {} s is not a positive number", opts.frame_time),
        ));
    }
    let (motion, report) = bake(&asf, &amc, opts.frame_time, amc_name)?;
    Ok(AsfMotion {
        motion,
        asf,
        amc,
        report,
    })
}

/// Line and column helpers shared by the ASF and AMC readers.
pub(crate) mod text {
    /// Splits `text` into physical lines (LF, CRLF or lone CR), without a
    /// leading BOM: `(1-based line number, line)`.
    pub fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut rest = text;
        let mut no = 0;
        std::iter::from_fn(move || {
            if rest.is_empty() {
                return None;
            }
            no += 1;
            let cut = rest.find(['\n', '\r']);
            let (line, next) = match cut {
                Some(i) => {
                    let skip = if rest[i..].starts_with("\r\n") { 2 } else { 1 };
                    (&rest[..i], &rest[i + skip..])
                }
                None => (rest, ""),
            };
            rest = next;
            Some((no, line))
        })
    }

    /// The line without its `#` comment.
    pub fn uncomment(line: &str) -> &str {
        match line.find('#') {
            Some(i) => &line[..i],
            None => line,
        }
    }

    /// The 1-based character column of byte `byte` of `line`.
    pub fn column(line: &str, byte: usize) -> usize {
        let mut b = byte.min(line.len());
        while !line.is_char_boundary(b) {
            b -= 1;
        }
        line[..b].chars().count() + 1
    }

    /// Whitespace-separated tokens of `line` with their byte offsets;
    /// with `parens`, `(` and `)` are tokens of their own.
    pub fn tokens(line: &str, parens: bool) -> Vec<(usize, &str)> {
        let mut out = Vec::new();
        let bytes = line.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            let b = bytes[i];
            if b.is_ascii_whitespace() {
                i += 1;
                continue;
            }
            if parens && (b == b'(' || b == b')') {
                out.push((i, &line[i..i + 1]));
                i += 1;
                continue;
            }
            let start = i;
            while i < bytes.len()
                && !bytes[i].is_ascii_whitespace()
                && !(parens && (bytes[i] == b'(' || bytes[i] == b')'))
            {
                i += 1;
            }
            out.push((start, &line[start..i]));
        }
        out
    }
}
