//! How the input readers (BVH, rig and show files) place an error in a
//! file: `file:line:column: message`, or `file: message` when there is no
//! position (an I/O error, line 0).

use std::fmt;

/// Writes `file:line:column: message`, or `file: message` for line 0.
pub(crate) fn write_located(
    f: &mut fmt::Formatter<'_>,
    file: &str,
    line: usize,
    column: usize,
    message: &str,
) -> fmt::Result {
    if line == 0 {
        write!(f, "{file}: {message}")
    } else {
        write!(f, "{file}:{line}:{column}: {message}")
    }
}

/// A 1-based line and column (in characters) in a text file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Position {
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// 1-based column in characters (0 when unknown).
    pub column: usize,
}

impl Position {
    /// The position of byte offset `byte` in `text` (clamped to the text,
    /// and moved back to a character boundary).
    pub fn of_byte(text: &str, byte: usize) -> Position {
        let mut b = byte.min(text.len());
        while !text.is_char_boundary(b) {
            b -= 1;
        }
        let before = &text[..b];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        Position {
            line: before.matches('\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

/// An error at a place in a text file (rig files, show files):
/// `file:line:column: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LocatedError {
    /// The file name as given to the reader.
    pub file: String,
    /// 1-based line (0 for I/O errors).
    pub line: usize,
    /// 1-based column in characters (0 for I/O errors).
    pub column: usize,
    /// What went wrong.
    pub message: String,
}

impl LocatedError {
    pub(crate) fn at(file: &str, pos: Position, message: impl Into<String>) -> LocatedError {
        LocatedError {
            file: file.to_string(),
            line: pos.line,
            column: pos.column,
            message: message.into(),
        }
    }
}

impl fmt::Display for LocatedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_located(f, &self.file, self.line, self.column, &self.message)
    }
}

impl std::error::Error for LocatedError {}
