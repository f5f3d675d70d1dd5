//! The BVH reader: the `HIERARCHY` (roots, joints, End Sites, offsets,
//! channels) and the `MOTION` section (frame count, frame time, one row per
//! frame).

use super::lexer::{describe, is_blank, Lexer, Line, Token};
use super::{end_site_name, BvhError};
use crate::motion::{ChannelKind, Joint};

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
pub(super) fn parse_hierarchy(lx: &mut Lexer<'_>) -> Result<(Vec<Joint>, Token), BvhError> {
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
            lx.expect_line_end(|found| {
                format!("OFFSET of '{jname}' has more than 3 values (found '{found}')")
            })?;
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
    lx.expect_line_end(|found| {
        format!(
            "CHANNELS {count} in '{joint}' lists more than {count} channel names (found '{found}')"
        )
    })?;
    Ok(kinds)
}

// MOTION

/// Parses everything after the `MOTION` keyword: header lines and rows.
pub(super) fn parse_motion(
    lx: &mut Lexer<'_>,
    channels: usize,
) -> Result<(f64, Vec<f64>), BvhError> {
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
