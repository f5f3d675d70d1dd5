//! Reader and writer tests: every accepted form, every error with its
//! line and column, and the round trip through the writer.

use super::writer::push_number;
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
    let no_channels =
        "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION\nFrames: 1\nFrame Time: 1\n\n";
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
