//! How the input readers (BVH, rig files) print an error at a place in a
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
