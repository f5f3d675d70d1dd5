//! Committed snapshots of the firmware's UART output
//! (`tests/snapshots/<case>.out`, format in `tests/snapshots/README.md`),
//! defmt-style: a run is compared with its snapshot, a failure shows where
//! the lines differ, and `MOCAP_BLESS=1` (the switch of the golden clips)
//! overwrites the snapshot with what the run printed.

use std::fmt::Write as _;
use std::path::PathBuf;

const CRC64: crc::Crc<u64> = crc::Crc::<u64>::new(&crc::CRC_64_ECMA_182);

/// Lines shown at the start of a snapshot; the last line is shown too, the
/// rest only counted in the digest.
pub const HEAD_LINES: usize = 4;

/// Where the snapshots live.
pub fn snapshot_dir() -> PathBuf {
    crate::workspace_root().join("tests/snapshots")
}

/// Whether `MOCAP_BLESS` asks to overwrite snapshots (and golden files).
pub fn bless() -> bool {
    std::env::var_os("MOCAP_BLESS").is_some_and(|v| v != "0")
}

/// The snapshot text of `data` (UART data lines, each ending in `\n`): a
/// summary line with the line and byte counts and the CRC-64/ECMA-182 of
/// all of `data`, the first [`HEAD_LINES`] lines, a line saying how many
/// are left out, and the last line.
pub fn render(data: &str) -> String {
    let lines: Vec<&str> = data.lines().collect();
    let mut s = String::new();
    writeln!(
        s,
        "# {} lines, {} bytes, crc64 {:016x}",
        lines.len(),
        data.len(),
        CRC64.checksum(data.as_bytes())
    )
    .unwrap();
    if lines.len() <= HEAD_LINES + 1 {
        for l in &lines {
            writeln!(s, "{l}").unwrap();
        }
    } else {
        for l in &lines[..HEAD_LINES] {
            writeln!(s, "{l}").unwrap();
        }
        writeln!(s, "# … {} lines …", lines.len() - HEAD_LINES - 1).unwrap();
        writeln!(s, "{}", lines[lines.len() - 1]).unwrap();
    }
    s
}

/// Where two texts first differ, readably: line counts and the first
/// differing lines (at most three) with their numbers. Empty if equal.
pub fn first_difference(expected: &str, actual: &str) -> String {
    if expected == actual {
        return String::new();
    }
    let (e, a): (Vec<&str>, Vec<&str>) = (expected.lines().collect(), actual.lines().collect());
    let mut s = format!(
        "{} lines expected, {} got ({} vs {} bytes)",
        e.len(),
        a.len(),
        expected.len(),
        actual.len()
    );
    let mut shown = 0;
    for i in 0..e.len().max(a.len()) {
        let (x, y) = (e.get(i), a.get(i));
        if x != y {
            let _ = write!(
                s,
                "\n  line {}:\n    expected: {}\n    got:      {}",
                i + 1,
                x.map_or("(none)", |l| clip_line(l)),
                y.map_or("(none)", |l| clip_line(l))
            );
            shown += 1;
            if shown == 3 {
                break;
            }
        }
    }
    s
}

/// A line cut to a readable width.
fn clip_line(l: &str) -> &str {
    match l.char_indices().nth(160) {
        Some((i, _)) => &l[..i],
        None => l,
    }
}

/// Compares the firmware's UART data lines of `case` with
/// `tests/snapshots/<case>.out`; with [`bless`], the first call of a case
/// in the run writes the snapshot instead (later calls compare with it). On a difference it panics with [`first_difference`] of the
/// snapshot texts and writes the whole output to
/// `target/qemu-parity/<case>.actual.out`.
pub fn check_snapshot(case: &str, data: &str) {
    let path = snapshot_dir().join(format!("{case}.out"));
    let got = render(data);
    // A case blessed earlier in this run (another board) is compared with
    // what was blessed, so the boards still have to agree.
    static BLESSED: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    let first_bless = bless() && {
        let mut blessed = BLESSED.lock().unwrap_or_else(|e| e.into_inner());
        let first = !blessed.iter().any(|c| c == case);
        if first {
            blessed.push(case.to_string());
        }
        first
    };
    if first_bless {
        std::fs::create_dir_all(snapshot_dir()).unwrap();
        if std::fs::read_to_string(&path).ok().as_deref() != Some(got.as_str()) {
            std::fs::write(&path, &got).unwrap();
            eprintln!("blessed {}", path.display());
        }
        return;
    }
    let Ok(expected) = std::fs::read_to_string(&path) else {
        panic!(
            "no snapshot {} — run with MOCAP_BLESS=1 to write it",
            path.display()
        );
    };
    if expected == got {
        return;
    }
    let dir = crate::workspace_root().join("target/qemu-parity");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{case}.actual.out")), data).unwrap();
    panic!(
        "{case}: the firmware's UART output differs from its snapshot \
         tests/snapshots/{case}.out\n{}\n(whole output in target/qemu-parity/{case}.actual.out; \
         MOCAP_BLESS=1 accepts it)",
        snapshot_difference(&expected, &got)
    );
}

/// A rendered snapshot: its summary line, and the data lines it shows with
/// their line numbers (from 1).
fn parse_rendered(text: &str) -> (&str, Vec<(usize, &str)>) {
    let mut lines = text.lines();
    let summary = lines.next().unwrap_or("");
    let mut shown = Vec::new();
    let mut n = 0;
    for l in lines {
        let skipped = l
            .strip_prefix("# … ")
            .and_then(|r| r.strip_suffix(" lines …"))
            .and_then(|k| k.parse::<usize>().ok());
        match skipped {
            Some(k) => n += k,
            None => {
                n += 1;
                shown.push((n, l));
            }
        }
    }
    (summary, shown)
}

/// Line `n` of `shown`, if the snapshot shows it.
fn shown_line<'a>(shown: &[(usize, &'a str)], n: usize) -> Option<&'a str> {
    shown.iter().find(|&&(m, _)| m == n).map(|&(_, l)| l)
}

/// How two rendered snapshots differ: both summary lines, then the first
/// differing data lines shown (at most three), numbered as in the output.
pub fn snapshot_difference(expected: &str, got: &str) -> String {
    let (es, e) = parse_rendered(expected);
    let (gs, g) = parse_rendered(got);
    let mut s = format!("  snapshot: {es}\n  this run: {gs}");
    let mut numbers: Vec<usize> = e.iter().chain(&g).map(|&(n, _)| n).collect();
    numbers.sort_unstable();
    numbers.dedup();
    let mut shown = 0;
    for n in numbers {
        let (x, y) = (shown_line(&e, n), shown_line(&g, n));
        if x != y && shown < 3 {
            let _ = write!(
                s,
                "\n  line {n}:\n    expected: {}\n    got:      {}",
                x.map_or("(not shown)", clip_line),
                y.map_or("(not shown)", clip_line)
            );
            shown += 1;
        }
    }
    if shown == 0 {
        s += "\n  the lines shown agree: the difference is in lines the snapshot only counts";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn render_keeps_head_and_last_line() {
        let data: String = (0..10).map(|i| format!("f {i}\n")).collect();
        let r = render(&data);
        let lines: Vec<&str> = r.lines().collect();
        assert!(lines[0].starts_with("# 10 lines, 40 bytes, crc64 "));
        assert_eq!(lines[1..5], ["f 0", "f 1", "f 2", "f 3"]);
        assert_eq!(lines[5..], ["# … 5 lines …", "f 9"]);
        assert_eq!(
            render("a\nb\n").lines().skip(1).collect::<Vec<_>>(),
            ["a", "b"]
        );
        assert_eq!(render("").lines().count(), 1);
    }

    #[test]
    fn snapshot_differences_are_numbered_as_the_output() {
        let a: String = (0..10).map(|i| format!("f {i}\n")).collect();
        let b = a.replace("f 2\n", "f x\n");
        let d = snapshot_difference(&render(&a), &render(&b));
        assert!(
            d.contains("line 3:\n    expected: f 2\n    got:      f x"),
            "{d}"
        );
        let c = a.replace("f 6\n", "f y\n");
        let d = snapshot_difference(&render(&a), &render(&c));
        assert!(
            d.contains("the difference is in lines the snapshot only counts"),
            "{d}"
        );
        let d = snapshot_difference(&render(&a), &render("f 0\n"));
        assert!(
            d.contains("line 2:\n    expected: f 1\n    got:      (not shown)"),
            "{d}"
        );
    }

    #[test]
    fn differences_name_the_line() {
        assert_eq!(first_difference("a\nb\n", "a\nb\n"), "");
        let d = first_difference("a\nb\nc\n", "a\nx\nc\nd\n");
        assert!(d.starts_with("3 lines expected, 4 got"), "{d}");
        assert!(
            d.contains("line 2:\n    expected: b\n    got:      x"),
            "{d}"
        );
        assert!(
            d.contains("line 4:\n    expected: (none)\n    got:      d"),
            "{d}"
        );
    }
}
