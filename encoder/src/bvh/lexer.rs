//! The BVH lexer: tokens (byte ranges with their line) and physical lines,
//! blanks and line breaks of every kind, errors with line and column.

use super::BvhError;

/// A token: a byte range of the source plus where its line starts.
#[derive(Clone, Copy, Debug)]
pub(super) struct Token {
    pub(super) start: usize,
    pub(super) end: usize,
    pub(super) line: usize,
    pub(super) line_start: usize,
}

/// One physical line of the MOTION section (without its line break).
#[derive(Clone, Copy, Debug)]
pub(super) struct Line {
    pub(super) start: usize,
    pub(super) end: usize,
    pub(super) line: usize,
}

/// Whitespace inside a line.
pub(super) fn is_blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | 0x0b | 0x0c)
}

pub(super) struct Lexer<'a> {
    pub(super) text: &'a str,
    pub(super) bytes: &'a [u8],
    pub(super) file: &'a str,
    pub(super) pos: usize,
    pub(super) line: usize,
    pub(super) line_start: usize,
}

impl<'a> Lexer<'a> {
    pub(super) fn new(text: &'a str, file: &'a str) -> Self {
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

    pub(super) fn str(&self, t: Token) -> &'a str {
        &self.text[t.start..t.end]
    }

    /// An error at byte `pos` of line `line` (which starts at `line_start`).
    pub(super) fn error_at(
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

    pub(super) fn error(&self, t: Token, message: impl Into<String>) -> BvhError {
        self.error_at(t.line, t.line_start, t.start, message)
    }

    /// An error at the current position.
    pub(super) fn error_here(&self, message: impl Into<String>) -> BvhError {
        self.error_at(self.line, self.line_start, self.pos, message)
    }

    /// Consumes one line break (LF, CRLF or CR) if the cursor is on one.
    pub(super) fn eat_newline(&mut self) -> bool {
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

    pub(super) fn skip_inline_blanks(&mut self) {
        while self.bytes.get(self.pos).is_some_and(|&b| is_blank(b)) {
            self.pos += 1;
        }
    }

    /// The next token, possibly on a later line.
    pub(super) fn next(&mut self) -> Option<Token> {
        loop {
            self.skip_inline_blanks();
            if !self.eat_newline() {
                break;
            }
        }
        self.scan()
    }

    /// The next token if there is one before the end of the current line.
    pub(super) fn next_on_line(&mut self) -> Option<Token> {
        self.skip_inline_blanks();
        self.scan()
    }

    /// Scans a token at the cursor: `{`, `}`, or a run of other non-blank
    /// characters.
    pub(super) fn scan(&mut self) -> Option<Token> {
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

    /// Fails with `too_many(found)` if a value follows on the current line;
    /// a brace there is put back (it opens or closes the next block).
    pub(super) fn expect_line_end(
        &mut self,
        too_many: impl FnOnce(&str) -> String,
    ) -> Result<(), BvhError> {
        match self.next_on_line() {
            Some(t) if matches!(self.str(t), "{" | "}") => {
                self.unread(t);
                Ok(())
            }
            Some(t) => Err(self.error(t, too_many(self.str(t)))),
            None => Ok(()),
        }
    }

    /// Puts back a token scanned on the current line.
    pub(super) fn unread(&mut self, t: Token) {
        debug_assert_eq!(t.line, self.line);
        self.pos = t.start;
    }

    /// The next physical line (including the rest of the current one).
    pub(super) fn next_line(&mut self) -> Option<Line> {
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

    pub(super) fn line_is_blank(&self, l: Line) -> bool {
        self.bytes[l.start..l.end].iter().all(|&b| is_blank(b))
    }

    pub(super) fn parse_f64(&self, t: Token, what: &str) -> Result<f64, BvhError> {
        match self.str(t).parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.number_error(t, what)),
        }
    }

    /// The error for a token that is not a finite number.
    pub(super) fn number_error(&self, t: Token, what: &str) -> BvhError {
        let s = self.str(t);
        if s.parse::<f64>().is_ok() {
            self.error(t, format!("{what} '{s}' is not a finite number"))
        } else {
            self.error(t, format!("expected a number for {what}, found '{s}'"))
        }
    }
}

/// Describes a token (or the end of input) for error messages.
pub(super) fn describe(lx: &Lexer<'_>, t: Option<Token>) -> String {
    match t {
        Some(t) => format!("'{}'", lx.str(t)),
        None => "end of file".to_owned(),
    }
}
