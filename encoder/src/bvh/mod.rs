//! BVH (Biovision Hierarchy) reader and writer.
//!
//! The reader accepts the whole format as real exporters write it:
//!
//! * any number of `ROOT`s, each a tree of `JOINT`s and `End Site`s;
//! * any channel subset and order per joint (0 to 6 channels, each kind at
//!   most once, names case-insensitive), position channels on any joint;
//! * LF, CRLF or lone CR line endings, tabs and arbitrary whitespace, a UTF-8
//!   byte-order mark, `{`/`}` on the keyword's line or on their own line;
//! * numbers in any form Rust's `f64` parser takes (`1e-3`, `-.5`, `5.`,
//!   `+3`, `1E+02`), except NaN and infinities, which are rejected;
//! * `Frames:` and `Frame Time:` with flexible spacing and case.
//!
//! In the `MOTION` section a frame row is exactly one line holding exactly
//! one value per channel; the number of rows must equal `Frames`. Blank lines
//! (e.g. at the end of the file) are ignored. End Sites become joints with
//! [`Joint::end_site`](crate::motion::Joint::end_site) set, no channels, and the name `<parent>_End`
//! (`<parent>_End2`, `<parent>_End3`, … for further End Sites of the same
//! parent).
//!
//! Every error names the file, the 1-based line and the 1-based column (in
//! characters) of the offending token; see [`BvhError`].
//!
//! The writer ([`write_string`], [`write_file`]) produces the conventional
//! layout (tab indentation, `Frame Time: {:.7}`, values with at most six
//! decimals), so `parse_str(&write_string(&m))` reproduces `m` to within
//! 1e-6.
//!
//! `lexer` splits the text into tokens and lines, `reader` builds the
//! skeleton and the frames from them, `writer` renders a motion.

mod lexer;
mod reader;
mod writer;

use std::fmt;
use std::path::Path;

use crate::motion::{Motion, Skeleton};
use lexer::Lexer;
pub use writer::{write_file, write_string};

/// A BVH reading error with its position in the source text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BvhError {
    /// The file name as given to the reader.
    pub file: String,
    /// 1-based line of the offending token (0 for I/O errors).
    pub line: usize,
    /// 1-based column, in characters, of the offending token (0 for I/O
    /// errors).
    pub column: usize,
    /// What went wrong.
    pub message: String,
}

impl fmt::Display for BvhError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        crate::located::write_located(f, &self.file, self.line, self.column, &self.message)
    }
}

impl std::error::Error for BvhError {}

/// The name given to the `k`-th End Site (1-based) of joint `parent`:
/// `<parent>_End`, then `<parent>_End2`, …
pub fn end_site_name(parent: &str, k: usize) -> String {
    match k {
        1 => format!("{parent}_End"),
        k => format!("{parent}_End{k}"),
    }
}

/// Reads and parses a BVH file. I/O errors are reported as a [`BvhError`]
/// with line and column 0. Bytes that are not valid UTF-8 (e.g. Latin-1 joint
/// names) are replaced by U+FFFD rather than rejected.
pub fn read_file(path: &Path) -> Result<Motion, BvhError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| BvhError {
        file: file.clone(),
        line: 0,
        column: 0,
        message: format!("cannot read file: {e}"),
    })?;
    parse_str(&String::from_utf8_lossy(&bytes), &file)
}

/// Parses BVH text. `file` is only used in error messages.
pub fn parse_str(text: &str, file: &str) -> Result<Motion, BvhError> {
    let mut lx = Lexer::new(text, file);
    let (joints, motion_kw) = reader::parse_hierarchy(&mut lx)?;
    let skeleton = Skeleton { joints };
    let channels = skeleton.channel_count();
    if channels == 0 {
        return Err(lx.error(
            motion_kw,
            "the hierarchy declares no channels (no CHANNELS lines), so there is no motion to read",
        ));
    }
    let (frame_time, values) = reader::parse_motion(&mut lx, channels)?;
    Ok(Motion {
        skeleton,
        frame_time,
        values,
    })
}

#[cfg(test)]
mod tests;
