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
//! [`Joint::end_site`] set, no channels, and the name `<parent>_End`
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

use crate::motion::{ChannelKind, Joint, Motion, Skeleton};
use std::fmt::{self, Write as _};
use std::path::Path;

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
        write!(
            f,
            "{}:{}:{}: {}",
            self.file, self.line, self.column, self.message
        )
    }
}

impl std::error::Error for BvhError {}

/// Reads and parses a BVH file. I/O errors are reported as a [`BvhError`]
/// with line and column 0. Bytes that are not valid UTF-8 (e.g. Latin-1 joint
/// names) are replaced by U+FFFD rather than rejected.
/// The name given to the `k`-th End Site (1-based) of joint `parent`:
/// `<parent>_End`, then `<parent>_End2`, …
pub fn end_site_name(parent: &str, k: usize) -> String {
    match k {
        1 => format!("{parent}_End"),
        k => format!("{parent}_End{k}"),
    }
}

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
    let (joints, motion_kw) = parse_hierarchy(&mut lx)?;
    let skeleton = Skeleton { joints };
    let channels = skeleton.channel_count();
    if channels == 0 {
        return Err(lx.error(
            motion_kw,
            "the hierarchy declares no channels (no CHANNELS lines), so there is no motion to read",
        ));
    }
    let (frame_time, values) = parse_motion(&mut lx, channels)?;
    Ok(Motion {
        skeleton,
        frame_time,
        values,
    })
}

/// Renders a motion as BVH text in the conventional layout.
///
/// Joints are written depth first from each root, children in index order;
/// for a skeleton in the documented depth-first order (as the reader builds
/// it) that is the skeleton's own order. A joint with `end_site` set, no
/// channels and no children is written as `End Site` (its name is not
/// stored in BVH). Values are written with up to six decimals, so NaN or
/// infinite values produce text the reader rejects.
pub fn write_string(m: &Motion) -> String {
    let joints = &m.skeleton.joints;
    let n = joints.len();
    let mut children = vec![Vec::new(); n];
    let mut is_root = vec![false; n];
    for (i, j) in joints.iter().enumerate() {
        match j.parent {
            Some(p) if p < n && p != i => children[p].push(i),
            _ => is_root[i] = true,
        }
    }

    let channels = m.channels();
    let frames = m.frames();
    let mut out = String::with_capacity(256 + 64 * n + frames * channels * 10);
    out.push_str("HIERARCHY\n");

    // Iterative depth-first walk: (joint, closing?) events.
    let mut order = Vec::with_capacity(n);
    let mut stack: Vec<(usize, bool)> = (0..n)
        .rev()
        .filter(|&r| is_root[r])
        .map(|r| (r, false))
        .collect();
    let mut depth = 0usize;
    while let Some((j, closing)) = stack.pop() {
        if closing {
            depth -= 1;
            indent(&mut out, depth);
            out.push_str("}\n");
            continue;
        }
        let joint = &joints[j];
        indent(&mut out, depth);
        let as_end_site = joint.end_site && joint.channels.is_empty() && children[j].is_empty();
        if is_root[j] {
            let _ = writeln!(out, "ROOT {}", joint.name);
        } else if as_end_site {
            out.push_str("End Site\n");
        } else {
            let _ = writeln!(out, "JOINT {}", joint.name);
        }
        indent(&mut out, depth);
        out.push_str("{\n");
        depth += 1;
        indent(&mut out, depth);
        out.push_str("OFFSET");
        for v in joint.offset {
            out.push(' ');
            push_number(&mut out, v);
        }
        out.push('\n');
        if is_root[j] || !as_end_site {
            indent(&mut out, depth);
            let _ = write!(out, "CHANNELS {}", joint.channels.len());
            for k in &joint.channels {
                out.push(' ');
                out.push_str(k.name());
            }
            out.push('\n');
        }
        order.push(j);
        stack.push((j, true));
        stack.extend(children[j].iter().rev().map(|&c| (c, false)));
    }

    // Channel ranges in the model's frame rows, visited in written order.
    let mut start = Vec::with_capacity(n);
    let mut acc = 0;
    for j in joints {
        start.push(acc);
        acc += j.channels.len();
    }
    let ranges: Vec<(usize, usize)> = order
        .iter()
        .map(|&j| (start[j], start[j] + joints[j].channels.len()))
        .filter(|r| r.0 < r.1)
        .collect();

    out.push_str("MOTION\n");
    let _ = writeln!(out, "Frames: {frames}");
    let _ = writeln!(out, "Frame Time: {:.7}", m.frame_time);
    for f in 0..frames {
        let row = m.frame(f);
        let mut first = true;
        for &(a, b) in &ranges {
            for &v in &row[a..b] {
                if !first {
                    out.push(' ');
                }
                first = false;
                push_number(&mut out, v);
            }
        }
        out.push('\n');
    }
    out
}

/// Writes a motion to a BVH file (see [`write_string`]).
pub fn write_file(m: &Motion, path: &Path) -> std::io::Result<()> {
    std::fs::write(path, write_string(m))
}

fn indent(out: &mut String, depth: usize) {
    out.extend(std::iter::repeat_n('\t', depth));
}

/// Appends `v` with at most six decimals, trailing zeros trimmed.
fn push_number(out: &mut String, v: f64) {
    let start = out.len();
    let _ = write!(out, "{v:.6}");
    if out[start..].contains('.') {
        let trimmed = out.trim_end_matches('0').len();
        out.truncate(trimmed);
        if out.ends_with('.') {
            out.pop();
        }
    }
    if &out[start..] == "-0" {
        out.truncate(start);
        out.push('0');
    }
}

// ---------------------------------------------------------------------------
// Lexing

/// A token: a byte range of the source plus where its line starts.
#[derive(Clone, Copy, Debug)]
struct Token {
    start: usize,
    end: usize,
    line: usize,
    line_start: usize,
}

/// One physical line of the MOTION section (without its line break).
#[derive(Clone, Copy, Debug)]
struct Line {
    start: usize,
    end: usize,
    line: usize,
}

/// Whitespace inside a line.
fn is_blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | 0x0b | 0x0c)
}

struct Lexer<'a> {
    text: &'a str,
    bytes: &'a [u8],
    file: &'a str,
    pos: usize,
    line: usize,
    line_start: usize,
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str, file: &'a str) -> Self {
        let pos = if text.starts_with('\u{feff}') { 3 } else { 0 };
        Lexer {
            text,
            bytes: text.as_bytes(),
            file,
            pos,
            line: 1,
            line_start: pos,
        }
    }

    fn str(&self, t: Token) -> &'a str {
        &self.text[t.start..t.end]
    }

    /// An error at byte `pos` of line `line` (which starts at `line_start`).
    fn error_at(
        &self,
        line: usize,
        line_start: usize,
        pos: usize,
        message: impl Into<String>,
    ) -> BvhError {
        BvhError {
            file: self.file.to_owned(),
            line,
            column: self.text[line_start..pos].chars().count() + 1,
            message: message.into(),
        }
    }

    fn error(&self, t: Token, message: impl Into<String>) -> BvhError {
        self.error_at(t.line, t.line_start, t.start, message)
    }

    /// An error at the current position.
    fn error_here(&self, message: impl Into<String>) -> BvhError {
        self.error_at(self.line, self.line_start, self.pos, message)
    }

    /// Consumes one line break (LF, CRLF or CR) if the cursor is on one.
    fn eat_newline(&mut self) -> bool {
        match self.bytes.get(self.pos) {
            Some(b'\n') => self.pos += 1,
            Some(b'\r') => {
                self.pos += 1;
                if self.bytes.get(self.pos) == Some(&b'\n') {
                    self.pos += 1;
                }
            }
            _ => return false,
        }
        self.line += 1;
        self.line_start = self.pos;
        true
    }

    fn skip_inline_blanks(&mut self) {
        while self.bytes.get(self.pos).is_some_and(|&b| is_blank(b)) {
            self.pos += 1;
        }
    }

    /// The next token, possibly on a later line.
    fn next(&mut self) -> Option<Token> {
        loop {
            self.skip_inline_blanks();
            if !self.eat_newline() {
                break;
            }
        }
        self.scan()
    }

    /// The next token if there is one before the end of the current line.
    fn next_on_line(&mut self) -> Option<Token> {
        self.skip_inline_blanks();
        self.scan()
    }

    /// Scans a token at the cursor: `{`, `}`, or a run of other non-blank
    /// characters.
    fn scan(&mut self) -> Option<Token> {
        let start = self.pos;
        match self.bytes.get(start) {
            None | Some(b'\n' | b'\r') => return None,
            Some(b'{' | b'}') => self.pos += 1,
            Some(_) => {
                while self
                    .bytes
                    .get(self.pos)
                    .is_some_and(|&b| !is_blank(b) && !matches!(b, b'\n' | b'\r' | b'{' | b'}'))
                {
                    self.pos += 1;
                }
            }
        }
        Some(Token {
            start,
            end: self.pos,
            line: self.line,
            line_start: self.line_start,
        })
    }

    /// Puts back a token scanned on the current line.
    fn unread(&mut self, t: Token) {
        debug_assert_eq!(t.line, self.line);
        self.pos = t.start;
    }

    /// The next physical line (including the rest of the current one).
    fn next_line(&mut self) -> Option<Line> {
        if self.pos >= self.bytes.len() {
            return None;
        }
        let start = self.pos;
        let len = self.bytes[start..]
            .iter()
            .position(|&b| b == b'\n' || b == b'\r')
            .unwrap_or(self.bytes.len() - start);
        self.pos = start + len;
        let line = Line {
            start,
            end: self.pos,
            line: self.line,
        };
        self.eat_newline();
        Some(line)
    }

    fn line_is_blank(&self, l: Line) -> bool {
        self.bytes[l.start..l.end].iter().all(|&b| is_blank(b))
    }

    fn parse_f64(&self, t: Token, what: &str) -> Result<f64, BvhError> {
        match self.str(t).parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.number_error(t, what)),
        }
    }

    /// The error for a token that is not a finite number.
    fn number_error(&self, t: Token, what: &str) -> BvhError {
        let s = self.str(t);
        if s.parse::<f64>().is_ok() {
            self.error(t, format!("{what} '{s}' is not a finite number"))
        } else {
            self.error(t, format!("expected a number for {what}, found '{s}'"))
        }
    }
}

/// Describes a token (or the end of input) for error messages.
fn describe(lx: &Lexer<'_>, t: Option<Token>) -> String {
    match t {
        Some(t) => format!("'{}'", lx.str(t)),
        None => "end of file".to_owned(),
    }
}

// ---------------------------------------------------------------------------
// HIERARCHY

/// A joint whose `{` has been read but not its `}`.
struct Open {
    joint: usize,
    line: usize,
    has_offset: bool,
    has_channels: bool,
    has_children: bool,
    end_site: bool,
    end_sites: usize,
}

/// Parses from the start of the text through the `MOTION` keyword, which is
/// returned for error positions.
fn parse_hierarchy(lx: &mut Lexer<'_>) -> Result<(Vec<Joint>, Token), BvhError> {
    match lx.next() {
        Some(t) if lx.str(t).eq_ignore_ascii_case("HIERARCHY") => {}
        Some(t) => {
            return Err(lx.error(
                t,
                format!(
                    "expected HIERARCHY at the start of a BVH file, found '{}'",
                    lx.str(t)
                ),
            ))
        }
        None => return Err(lx.error_here("empty file: expected HIERARCHY")),
    }

    let mut joints: Vec<Joint> = Vec::new();
    let mut stack: Vec<Open> = Vec::new();
    loop {
        let tok = lx.next();
        let Some(open) = stack.last_mut() else {
            // Between roots.
            match tok {
                Some(t) if lx.str(t).eq_ignore_ascii_case("ROOT") => {
                    let name = read_name(lx, t)?;
                    expect_open_brace(lx, "ROOT", &name)?;
                    stack.push(open_joint(&mut joints, name, None, t.line, false));
                }
                Some(t) if lx.str(t).eq_ignore_ascii_case("MOTION") => {
                    if joints.is_empty() {
                        return Err(lx.error(t, "MOTION before any ROOT: the hierarchy is empty"));
                    }
                    return Ok((joints, t));
                }
                Some(t) if lx.str(t) == "}" => {
                    return Err(lx.error(t, "unmatched '}' (no joint is open)"));
                }
                Some(t) => {
                    return Err(lx.error(
                        t,
                        format!("unknown keyword '{}' (expected ROOT or MOTION)", lx.str(t)),
                    ))
                }
                None => {
                    return Err(lx.error_here(if joints.is_empty() {
                        "unexpected end of file: expected ROOT"
                    } else {
                        "unexpected end of file: expected MOTION"
                    }))
                }
            }
            continue;
        };

        let jname = joints[open.joint].name.clone();
        let Some(t) = tok else {
            return Err(lx.error_here(format!(
                "unexpected end of file: '{}' opened at line {} is not closed with '}}'",
                jname, open.line
            )));
        };
        let word = lx.str(t);
        if word.eq_ignore_ascii_case("OFFSET") {
            if open.has_offset {
                return Err(lx.error(t, format!("second OFFSET in '{jname}'")));
            }
            open.has_offset = true;
            let mut offset = [0.0; 3];
            for (axis, v) in offset.iter_mut().enumerate() {
                let Some(n) = lx.next_on_line() else {
                    return Err(
                        lx.error_here(format!("OFFSET of '{jname}' has {axis} values, expected 3"))
                    );
                };
                *v = lx.parse_f64(n, "OFFSET")?;
            }
            if let Some(extra) = lx.next_on_line() {
                if matches!(lx.str(extra), "{" | "}") {
                    lx.unread(extra);
                } else {
                    return Err(lx.error(
                        extra,
                        format!(
                            "OFFSET of '{jname}' has more than 3 values (found '{}')",
                            lx.str(extra)
                        ),
                    ));
                }
            }
            joints[open.joint].offset = offset;
        } else if word.eq_ignore_ascii_case("CHANNELS") {
            if open.end_site {
                return Err(lx.error(t, "an End Site cannot have CHANNELS"));
            }
            if open.has_channels {
                return Err(lx.error(t, format!("second CHANNELS line in '{jname}'")));
            }
            if open.has_children {
                return Err(lx.error(
                    t,
                    format!("CHANNELS of '{jname}' must come before its child joints"),
                ));
            }
            open.has_channels = true;
            joints[open.joint].channels = read_channels(lx, &jname)?;
        } else if word.eq_ignore_ascii_case("JOINT") {
            if open.end_site {
                return Err(lx.error(t, "an End Site cannot have child joints"));
            }
            open.has_children = true;
            let parent = open.joint;
            let name = read_name(lx, t)?;
            expect_open_brace(lx, "JOINT", &name)?;
            stack.push(open_joint(&mut joints, name, Some(parent), t.line, false));
        } else if word.eq_ignore_ascii_case("End") {
            match lx.next_on_line() {
                Some(s) if lx.str(s).eq_ignore_ascii_case("Site") => {}
                other => {
                    let found = describe(lx, other);
                    return Err(lx.error(
                        t,
                        format!("expected 'End Site', found 'End' followed by {found}"),
                    ));
                }
            }
            if open.end_site {
                return Err(lx.error(t, "an End Site cannot have child joints"));
            }
            open.has_children = true;
            open.end_sites += 1;
            let name = end_site_name(&jname, open.end_sites);
            let parent = open.joint;
            expect_open_brace(lx, "End Site", &jname)?;
            stack.push(open_joint(&mut joints, name, Some(parent), t.line, true));
        } else if word == "}" {
            if !open.has_offset {
                let what = if open.end_site {
                    "End Site of"
                } else {
                    "joint"
                };
                let owner = if open.end_site {
                    joints[open.joint]
                        .parent
                        .map_or(jname.clone(), |p| joints[p].name.clone())
                } else {
                    jname
                };
                return Err(lx.error(t, format!("{what} '{owner}' has no OFFSET")));
            }
            stack.pop();
        } else if word == "{" {
            return Err(lx.error(t, format!("unexpected '{{' inside '{jname}'")));
        } else if word.eq_ignore_ascii_case("MOTION") || word.eq_ignore_ascii_case("ROOT") {
            return Err(lx.error(
                t,
                format!(
                    "expected '}}' to close '{}' (opened at line {}), found '{word}'",
                    jname, open.line
                ),
            ));
        } else {
            return Err(lx.error(
                t,
                format!(
                    "unknown keyword '{word}' in '{jname}' (expected OFFSET, CHANNELS, JOINT, End Site or '}}')"
                ),
            ));
        }
    }
}

fn open_joint(
    joints: &mut Vec<Joint>,
    name: String,
    parent: Option<usize>,
    line: usize,
    end_site: bool,
) -> Open {
    joints.push(Joint {
        name,
        parent,
        offset: [0.0; 3],
        channels: Vec::new(),
        end_site,
    });
    Open {
        joint: joints.len() - 1,
        line,
        has_offset: false,
        has_channels: false,
        has_children: false,
        end_site,
        end_sites: 0,
    }
}

/// Reads a joint name: the rest of the keyword's line up to an optional `{`
/// (names may contain spaces).
fn read_name(lx: &mut Lexer<'_>, keyword: Token) -> Result<String, BvhError> {
    let mut span: Option<(usize, usize)> = None;
    while let Some(t) = lx.next_on_line() {
        if matches!(lx.str(t), "{" | "}") {
            lx.unread(t);
            break;
        }
        span = Some((span.map_or(t.start, |s| s.0), t.end));
    }
    match span {
        Some((a, b)) => Ok(lx.text[a..b].to_owned()),
        None => Err(lx.error_at(
            keyword.line,
            keyword.line_start,
            keyword.end,
            format!("expected a joint name after {}", lx.str(keyword)),
        )),
    }
}

fn expect_open_brace(lx: &mut Lexer<'_>, keyword: &str, name: &str) -> Result<(), BvhError> {
    match lx.next() {
        Some(t) if lx.str(t) == "{" => Ok(()),
        Some(t) => Err(lx.error(
            t,
            format!(
                "expected '{{' after {keyword} {name}, found '{}'",
                lx.str(t)
            ),
        )),
        None => Err(lx.error_here(format!(
            "unexpected end of file: expected '{{' after {keyword} {name}"
        ))),
    }
}

/// Reads `<count> <name>…` after a CHANNELS keyword, all on its line.
fn read_channels(lx: &mut Lexer<'_>, joint: &str) -> Result<Vec<ChannelKind>, BvhError> {
    let Some(ct) = lx.next_on_line() else {
        return Err(lx.error_here("expected a channel count after CHANNELS"));
    };
    let count: usize = lx.str(ct).parse().map_err(|_| {
        lx.error(
            ct,
            format!(
                "expected a channel count after CHANNELS, found '{}'",
                lx.str(ct)
            ),
        )
    })?;
    if count > 6 {
        return Err(lx.error(
            ct,
            format!("CHANNELS {count} in '{joint}': a joint has at most 6 channels"),
        ));
    }
    let mut kinds = Vec::with_capacity(count);
    for i in 0..count {
        let Some(t) = lx.next_on_line() else {
            return Err(lx.error_here(format!(
                "CHANNELS {count} in '{joint}' lists only {i} channel names"
            )));
        };
        let Some(kind) = ChannelKind::from_name(lx.str(t)) else {
            return Err(lx.error(
                t,
                format!(
                    "unknown channel '{}' (expected Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation)",
                    lx.str(t)
                ),
            ));
        };
        if kinds.contains(&kind) {
            return Err(lx.error(t, format!("channel {kind} listed twice in '{joint}'")));
        }
        kinds.push(kind);
    }
    if let Some(extra) = lx.next_on_line() {
        if matches!(lx.str(extra), "{" | "}") {
            lx.unread(extra);
        } else {
            return Err(lx.error(
                extra,
                format!(
                    "CHANNELS {count} in '{joint}' lists more than {count} channel names (found '{}')",
                    lx.str(extra)
                ),
            ));
        }
    }
    Ok(kinds)
}

// ---------------------------------------------------------------------------
// MOTION

/// Parses everything after the `MOTION` keyword: header lines and rows.
fn parse_motion(lx: &mut Lexer<'_>, channels: usize) -> Result<(f64, Vec<f64>), BvhError> {
    if let Some(t) = lx.next_on_line() {
        return Err(lx.error(t, format!("unexpected '{}' after MOTION", lx.str(t))));
    }
    lx.eat_newline();

    let frames_tok = header_line(lx, &["Frames"], "Frames:")?;
    let frames: usize = lx.str(frames_tok).parse().map_err(|_| {
        lx.error(
            frames_tok,
            format!(
                "Frames: expected a whole number, found '{}'",
                lx.str(frames_tok)
            ),
        )
    })?;
    if frames == 0 {
        return Err(lx.error(frames_tok, "Frames: 0: a motion needs at least one frame"));
    }

    let ft_tok = header_line(lx, &["Frame", "Time"], "Frame Time:")?;
    let frame_time = lx.parse_f64(ft_tok, "Frame Time")?;
    if frame_time <= 0.0 {
        return Err(lx.error(
            ft_tok,
            format!(
                "Frame Time must be greater than 0, found '{}'",
                lx.str(ft_tok)
            ),
        ));
    }

    // Never trust the header for the allocation size: each value takes at
    // least two bytes of text.
    let remaining = lx.bytes.len() - lx.pos;
    let capacity = frames.saturating_mul(channels).min(remaining / 2 + 1);
    let mut values = Vec::with_capacity(capacity);
    let bytes = lx.bytes;
    let mut rows = 0usize;
    while let Some(l) = lx.next_line() {
        if lx.line_is_blank(l) {
            continue;
        }
        if rows == frames {
            let mut extra = 1;
            while let Some(m) = lx.next_line() {
                if !lx.line_is_blank(m) {
                    extra += 1;
                }
            }
            let first = first_non_blank(bytes, l);
            return Err(lx.error_at(
                l.line,
                l.start,
                first,
                format!(
                    "header says Frames: {frames} but {} rows follow",
                    frames + extra
                ),
            ));
        }
        rows += 1;
        let mut i = l.start;
        let mut count = 0usize;
        let mut last_end = l.start;
        loop {
            while i < l.end && is_blank(bytes[i]) {
                i += 1;
            }
            if i >= l.end {
                break;
            }
            let s = i;
            while i < l.end && !is_blank(bytes[i]) {
                i += 1;
            }
            if count == channels {
                let total = count + count_fields(&bytes[s..l.end]);
                return Err(lx.error_at(
                    l.line,
                    l.start,
                    s,
                    format!(
                        "frame row {rows} has {total} values, expected {channels} (from CHANNELS lines)"
                    ),
                ));
            }
            let tok = Token {
                start: s,
                end: i,
                line: l.line,
                line_start: l.start,
            };
            match lx.str(tok).parse::<f64>() {
                Ok(v) if v.is_finite() => values.push(v),
                _ => return Err(lx.number_error(tok, &format!("frame row {rows}"))),
            }
            count += 1;
            last_end = i;
        }
        if count < channels {
            return Err(lx.error_at(
                l.line,
                l.start,
                last_end,
                format!(
                    "frame row {rows} has {count} values, expected {channels} (from CHANNELS lines)"
                ),
            ));
        }
    }
    if rows < frames {
        return Err(lx.error(
            frames_tok,
            format!("header says Frames: {frames} but {rows} rows follow"),
        ));
    }
    Ok((frame_time, values))
}

fn first_non_blank(bytes: &[u8], l: Line) -> usize {
    (l.start..l.end)
        .find(|&i| !is_blank(bytes[i]))
        .unwrap_or(l.start)
}

/// Number of blank-separated fields in `s`.
fn count_fields(s: &[u8]) -> usize {
    s.split(|&b| is_blank(b)).filter(|f| !f.is_empty()).count()
}

/// Reads the next non-blank line as `<words> : <value>` (words matched
/// case-insensitively, whitespace between words and around `:` optional) and
/// returns the value token. `label` is the header as shown in messages.
fn header_line(lx: &mut Lexer<'_>, words: &[&str], label: &str) -> Result<Token, BvhError> {
    let l = loop {
        match lx.next_line() {
            Some(l) if lx.line_is_blank(l) => continue,
            Some(l) => break l,
            None => {
                return Err(lx.error_here(format!("unexpected end of file: expected '{label}'")))
            }
        }
    };
    let b = lx.bytes;
    let skip = |mut i: usize| {
        while i < l.end && is_blank(b[i]) {
            i += 1;
        }
        i
    };
    let err = |at: usize, msg: String| lx.error_at(l.line, l.start, at, msg);
    let first = skip(l.start);
    let found = || {
        let text = lx.text[first..l.end].trim_end();
        let short: String = text.chars().take(40).collect();
        short
    };
    let mut i = first;
    for w in words {
        let matches = b
            .get(i..i + w.len())
            .is_some_and(|s| s.eq_ignore_ascii_case(w.as_bytes()));
        if !matches {
            return Err(err(
                first,
                format!("expected '{label}', found '{}'", found()),
            ));
        }
        i = skip(i + w.len());
    }
    if b.get(i) != Some(&b':') || i >= l.end {
        return Err(err(
            i,
            format!("expected ':' in '{label}', found '{}'", found()),
        ));
    }
    i = skip(i + 1);
    if i >= l.end {
        return Err(err(i, format!("missing value after '{label}'")));
    }
    let s = i;
    while i < l.end && !is_blank(b[i]) {
        i += 1;
    }
    let tok = Token {
        start: s,
        end: i,
        line: l.line,
        line_start: l.start,
    };
    let rest = skip(i);
    if rest < l.end {
        return Err(err(
            rest,
            format!("unexpected text after '{label} {}'", lx.str(tok)),
        ));
    }
    Ok(tok)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::ChannelKind::*;

    fn parse(text: &str) -> Motion {
        parse_str(text, "t.bvh").unwrap_or_else(|e| panic!("{e}"))
    }

    fn parse_err(text: &str) -> BvhError {
        match parse_str(text, "t.bvh") {
            Ok(_) => panic!("expected an error"),
            Err(e) => e,
        }
    }

    fn assert_err(text: &str, line: usize, column: usize, needle: &str) {
        let e = parse_err(text);
        assert!(
            e.message.contains(needle),
            "message '{}' lacks '{needle}'",
            e.message
        );
        assert_eq!(
            (e.line, e.column),
            (line, column),
            "position of '{}'",
            e.message
        );
    }

    const SIMPLE: &str = "HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 5 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.0083333
1 2 3 4 5 6 7 8 9
-1 -2 -3 -4 -5 -6 -7 -8 -9
";

    #[test]
    fn parses_simple_file() {
        let m = parse(SIMPLE);
        let j = &m.skeleton.joints;
        assert_eq!(j.len(), 3);
        assert_eq!(j[0].name, "Hips");
        assert_eq!(j[0].parent, None);
        assert_eq!(
            j[0].channels,
            vec![Xposition, Yposition, Zposition, Zrotation, Yrotation, Xrotation]
        );
        assert_eq!(j[1].name, "Spine");
        assert_eq!(j[1].parent, Some(0));
        assert_eq!(j[1].offset, [0.0, 10.0, 0.0]);
        assert_eq!(j[1].channels, vec![Zrotation, Xrotation, Yrotation]);
        assert_eq!(j[2].name, "Spine_End");
        assert!(j[2].end_site);
        assert!(j[2].channels.is_empty());
        assert_eq!(j[2].parent, Some(1));
        assert_eq!(j[2].offset, [0.0, 5.0, 0.0]);
        assert_eq!(m.frames(), 2);
        assert_eq!(m.channels(), 9);
        assert!((m.frame_time - 0.0083333).abs() < 1e-12);
        assert_eq!(m.frame(1)[8], -9.0);
    }

    #[test]
    fn any_channel_subset_and_order_and_case() {
        let text = "HIERARCHY
ROOT A
{
  OFFSET 0 0 0
  CHANNELS 1 yposition
  JOINT B
  {
    OFFSET 1 0 0
    CHANNELS 2 ZROTATION xRotation
    JOINT C
    {
      OFFSET 1 0 0
      CHANNELS 6 Yrotation Zposition Xrotation Xposition Zrotation Yposition
      JOINT D
      {
        OFFSET 1 0 0
        CHANNELS 5 Xposition Yposition Zrotation Yrotation Xrotation
      }
    }
  }
}
MOTION
Frames: 1
Frame Time: 0.5
1 2 3 4 5 6 7 8 9 10 11 12 13 14
";
        let m = parse(text);
        let j = &m.skeleton.joints;
        assert_eq!(j[0].channels, vec![Yposition]);
        assert_eq!(j[1].channels, vec![Zrotation, Xrotation]);
        assert_eq!(
            j[2].channels,
            vec![Yrotation, Zposition, Xrotation, Xposition, Zrotation, Yposition]
        );
        assert_eq!(j[3].channels.len(), 5);
        // A joint without children and without End Site is fine.
        assert!(!j[3].end_site);
        assert_eq!(m.channels(), 14);
        assert_eq!(m.frame(0)[13], 14.0);
    }

    #[test]
    fn multiple_roots_and_several_end_sites() {
        let text = "HIERARCHY
ROOT A
{
OFFSET 0 0 0
CHANNELS 3 Xposition Yposition Zposition
End Site
{
OFFSET 0 1 0
}
End Site
{
OFFSET 0 2 0
}
}
ROOT B
{
OFFSET 5 0 0
CHANNELS 1 Zrotation
}
MOTION
Frames: 1
Frame Time: 1
0 0 0 90
";
        let m = parse(text);
        let names: Vec<_> = m.skeleton.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, ["A", "A_End", "A_End2", "B"]);
        assert_eq!(m.skeleton.joints[3].parent, None);
        assert_eq!(m.skeleton.joints[3].offset, [5.0, 0.0, 0.0]);
    }

    #[test]
    fn line_endings_whitespace_and_braces_on_keyword_line() {
        let lf = SIMPLE;
        let crlf = SIMPLE.replace('\n', "\r\n");
        let cr = SIMPLE.replace('\n', "\r");
        let messy = SIMPLE
            .replace("ROOT Hips\n{", "ROOT   Hips {")
            .replace("End Site\n\t\t{", "End\tSite{")
            .replace(" 0 0 0\n", " 0\t 0  0   \n")
            .replace("1 2 3", "\t 1    2\t3  ")
            .replace('\t', " \t  ");
        let reference = parse(lf);
        for text in [crlf.as_str(), cr.as_str(), messy.as_str()] {
            assert_eq!(parse(text), reference, "{text:?}");
        }
    }

    #[test]
    fn byte_order_mark_and_trailing_blank_lines() {
        let text = format!("\u{feff}{SIMPLE}\n\n  \t\n\r\n");
        assert_eq!(parse(&text), parse(SIMPLE));
    }

    #[test]
    fn joint_names_may_contain_spaces() {
        let text = SIMPLE.replace("JOINT Spine", "JOINT Spine Lower");
        let m = parse(&text);
        assert_eq!(m.skeleton.joints[1].name, "Spine Lower");
        assert_eq!(m.skeleton.joints[2].name, "Spine Lower_End");
    }

    #[test]
    fn number_forms() {
        let text = SIMPLE.replace("OFFSET 0 10 0", "OFFSET +3 -.5 5.").replace(
            "1 2 3 4 5 6 7 8 9",
            "1e-3 -.5 5. +3 1E+02 -0 0.25 1e2 -7E-1",
        );
        let m = parse(&text);
        assert_eq!(m.skeleton.joints[1].offset, [3.0, -0.5, 5.0]);
        assert_eq!(
            m.frame(0),
            &[1e-3, -0.5, 5.0, 3.0, 100.0, 0.0, 0.25, 100.0, -0.7]
        );
    }

    #[test]
    fn flexible_motion_headers() {
        for (frames, time) in [
            ("Frames:2", "Frame Time:0.0083333"),
            ("Frames :   2  ", "Frame   Time :\t0.0083333"),
            ("FRAMES: 2", "frame time: 0.0083333"),
            ("\tFrames:\t2", "FrameTime: 0.0083333"),
        ] {
            let text = SIMPLE
                .replace("Frames: 2", frames)
                .replace("Frame Time: 0.0083333", time);
            assert_eq!(parse(&text), parse(SIMPLE), "{frames} / {time}");
        }
        // Blank lines between headers and data are tolerated too.
        let text = SIMPLE
            .replace("MOTION\n", "MOTION\n\n")
            .replace("0.0083333\n", "0.0083333\n\n");
        assert_eq!(parse(&text), parse(SIMPLE));
    }

    #[test]
    fn row_value_count_errors() {
        let short = SIMPLE.replace("-1 -2 -3 -4 -5 -6 -7 -8 -9", "-1 -2 -3 -4 -5 -6 -7 -8");
        assert_err(
            &short,
            20,
            24,
            "frame row 2 has 8 values, expected 9 (from CHANNELS lines)",
        );
        let long = SIMPLE.replace("1 2 3 4 5 6 7 8 9", "1 2 3 4 5 6 7 8 9 10 11");
        assert_err(
            &long,
            19,
            19,
            "frame row 1 has 11 values, expected 9 (from CHANNELS lines)",
        );
        // Two frames on one line are not a row each.
        let joined = SIMPLE.replace("7 8 9\n-1", "7 8 9 -1");
        assert_err(&joined, 19, 19, "has 18 values, expected 9");
    }

    #[test]
    fn frame_count_errors() {
        let fewer = SIMPLE.replace("Frames: 2", "Frames: 3");
        assert_err(&fewer, 17, 9, "header says Frames: 3 but 2 rows follow");
        let more = SIMPLE.replace("Frames: 2", "Frames: 1");
        assert_err(&more, 20, 1, "header says Frames: 1 but 2 rows follow");
        let zero = SIMPLE.replace("Frames: 2", "Frames: 0");
        assert_err(&zero, 17, 9, "at least one frame");
        let bad = SIMPLE.replace("Frames: 2", "Frames: 2.5");
        assert_err(&bad, 17, 9, "whole number");
        let missing = SIMPLE.replace("Frames: 2\n", "");
        assert_err(&missing, 17, 1, "expected 'Frames:'");
        let colon = SIMPLE.replace("Frames: 2", "Frames 2");
        assert_err(&colon, 17, 8, "expected ':'");
        let trailing = SIMPLE.replace("Frames: 2", "Frames: 2 x");
        assert_err(&trailing, 17, 11, "unexpected text");
    }

    #[test]
    fn frame_time_errors() {
        for (t, needle) in [
            ("0", "greater than 0"),
            ("-0.1", "greater than 0"),
            ("nan", "not a finite number"),
            ("abc", "expected a number"),
        ] {
            let text = SIMPLE.replace("0.0083333", t);
            assert_err(&text, 18, 13, needle);
        }
        let text = SIMPLE.replace("Frame Time: 0.0083333\n", "");
        assert_err(&text, 18, 1, "expected 'Frame Time:'");
    }

    #[test]
    fn non_finite_values_are_rejected() {
        for bad in ["NaN", "inf", "-infinity", "1e999"] {
            let text = SIMPLE.replace("1 2 3 4 5", &format!("1 2 {bad} 4 5"));
            assert_err(&text, 19, 5, "not a finite number");
        }
        let text = SIMPLE.replace("OFFSET 0 10 0", "OFFSET 0 NaN 0");
        assert_err(&text, 8, 12, "not a finite number");
        let text = SIMPLE.replace("1 2 3 4 5", "1 2 3,5 4 5");
        assert_err(
            &text,
            19,
            5,
            "expected a number for frame row 1, found '3,5'",
        );
    }

    #[test]
    fn structural_errors_name_the_token() {
        let unknown = SIMPLE.replace("\tJOINT Spine", "\tJOINTS Spine");
        assert_err(&unknown, 6, 2, "unknown keyword 'JOINTS'");
        let channel = SIMPLE.replace(
            "Zrotation Xrotation Yrotation",
            "Zrotation Wrotation Yrotation",
        );
        assert_err(&channel, 9, 24, "unknown channel 'Wrotation'");
        let seven = SIMPLE.replace("CHANNELS 3 Zrotation", "CHANNELS 7 Zrotation");
        assert_err(&seven, 9, 12, "at most 6 channels");
        let dup = SIMPLE.replace(
            "Zrotation Xrotation Yrotation",
            "Zrotation Xrotation Zrotation",
        );
        assert_err(&dup, 9, 34, "listed twice");
        let fewer = SIMPLE.replace(
            "CHANNELS 3 Zrotation Xrotation Yrotation",
            "CHANNELS 3 Zrotation Xrotation",
        );
        assert_err(&fewer, 9, 33, "lists only 2 channel names");
        let more = SIMPLE.replace(
            "CHANNELS 3 Zrotation Xrotation Yrotation",
            "CHANNELS 2 Zrotation Xrotation Yrotation",
        );
        assert_err(&more, 9, 34, "more than 2 channel names");
        let offset = SIMPLE.replace("OFFSET 0 10 0", "OFFSET 0 10");
        assert_err(&offset, 8, 14, "has 2 values, expected 3");
        let no_offset = SIMPLE.replace("\t\t\tOFFSET 0 5 0\n", "");
        assert_err(&no_offset, 12, 3, "End Site of 'Spine' has no OFFSET");
        let site_channels = SIMPLE.replace("OFFSET 0 5 0", "OFFSET 0 5 0\nCHANNELS 1 Xrotation");
        assert_err(&site_channels, 13, 1, "End Site cannot have CHANNELS");
        let end = SIMPLE.replace("End Site", "End Sight");
        assert_err(&end, 10, 3, "expected 'End Site'");
        let name = SIMPLE.replace("JOINT Spine", "JOINT");
        assert_err(&name, 6, 7, "expected a joint name after JOINT");
    }

    #[test]
    fn brace_errors() {
        // Missing closing brace of Hips: MOTION arrives while Hips is open.
        let unclosed = SIMPLE.replacen("}\nMOTION", "MOTION", 1);
        assert_err(
            &unclosed,
            15,
            1,
            "expected '}' to close 'Hips' (opened at line 2)",
        );
        let extra = SIMPLE.replace("}\nMOTION", "}\n}\nMOTION");
        assert_err(&extra, 16, 1, "unmatched '}'");
        let no_open = SIMPLE.replace("\tJOINT Spine\n\t{", "\tJOINT Spine\n\tOFFSET");
        assert_err(
            &no_open,
            7,
            2,
            "expected '{' after JOINT Spine, found 'OFFSET'",
        );
        let eof = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n";
        assert_err(eof, 5, 1, "'A' opened at line 2 is not closed");
    }

    #[test]
    fn empty_and_degenerate_inputs() {
        assert_err("", 1, 1, "empty file");
        assert_err("  \n\n", 3, 1, "empty file");
        assert_err("HIERARCHIE\n", 1, 1, "expected HIERARCHY");
        assert_err("HIERARCHY\nMOTION\n", 2, 1, "MOTION before any ROOT");
        assert_err("HIERARCHY\n", 2, 1, "expected ROOT");
        let no_channels = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION\nFrames: 1\nFrame Time: 1\n\n";
        assert_err(no_channels, 7, 1, "no channels");
        let no_rows = SIMPLE.split("1 2 3").next().unwrap_or_default().to_owned();
        assert_err(&no_rows, 17, 9, "but 0 rows follow");
    }

    #[test]
    fn error_display_format() {
        let e = parse_err(&SIMPLE.replace("JOINT Spine", "JOYNT Spine"));
        assert_eq!(
            e.to_string(),
            "t.bvh:6:2: unknown keyword 'JOYNT' in 'Hips' (expected OFFSET, CHANNELS, JOINT, End Site or '}')"
        );
        let e = read_file(Path::new("/nonexistent/dir/x.bvh")).unwrap_err();
        assert_eq!((e.line, e.column), (0, 0));
        assert!(e.message.starts_with("cannot read file"));
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        // "\tJOINT Épine { " is 15 characters but 16 bytes.
        let text = SIMPLE.replace("JOINT Spine", "JOINT Épine { BOGUS");
        let e = parse_err(&text);
        assert_eq!((e.line, e.column), (6, 16), "{e}");
        assert!(e.message.contains("'BOGUS' in 'Épine'"), "{e}");
    }

    fn assert_close(a: &Motion, b: &Motion, tol: f64) {
        assert_eq!(a.skeleton.joints.len(), b.skeleton.joints.len());
        for (x, y) in a.skeleton.joints.iter().zip(&b.skeleton.joints) {
            assert_eq!(x.name, y.name);
            assert_eq!(x.parent, y.parent);
            assert_eq!(x.channels, y.channels);
            assert_eq!(x.end_site, y.end_site);
            for k in 0..3 {
                assert!((x.offset[k] - y.offset[k]).abs() <= tol);
            }
        }
        assert!((a.frame_time - b.frame_time).abs() <= tol);
        assert_eq!(a.values.len(), b.values.len());
        for (x, y) in a.values.iter().zip(&b.values) {
            assert!((x - y).abs() <= tol, "{x} vs {y}");
        }
    }

    #[test]
    fn round_trip() {
        let mut m = parse(SIMPLE);
        m.frame_time = 1.0 / 120.0;
        for (i, v) in m.values.iter_mut().enumerate() {
            *v = (i as f64 * 1.37).sin() * 10f64.powi(i as i32 % 5 - 2) - 0.0000004;
        }
        m.skeleton.joints[1].offset = [1.0 / 3.0, -2.5e-7, 1234.5678901];
        let text = write_string(&m);
        let back = parse(&text);
        assert_close(&m, &back, 1e-6);
        // Writing again is stable.
        assert_eq!(write_string(&back), text);
    }

    #[test]
    fn writer_layout() {
        let m = parse(SIMPLE);
        let text = write_string(&m);
        // The canonical layout writes SIMPLE back exactly.
        let expected = SIMPLE;
        assert_eq!(text, expected);
    }

    #[test]
    fn writer_numbers() {
        let mut s = String::new();
        for v in [0.0, -0.0, -0.0000001, 1.5, -2.25, 100.0, 0.1234567, 1e-7] {
            push_number(&mut s, v);
            s.push(' ');
        }
        assert_eq!(s, "0 0 0 1.5 -2.25 100 0.123457 0 ");
    }

    #[test]
    fn multiple_roots_round_trip() {
        let text = "HIERARCHY
ROOT A
{
\tOFFSET 0 0 0
\tCHANNELS 1 Xposition
}
ROOT B
{
\tOFFSET 1 2 3
\tCHANNELS 2 Zrotation Xrotation
\tEnd Site
\t{
\t\tOFFSET 0 1 0
\t}
}
MOTION
Frames: 1
Frame Time: 0.0166667
1.5 2 -3
";
        let m = parse(text);
        assert_eq!(write_string(&m), text);
    }
}
