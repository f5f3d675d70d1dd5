//! The BVH writer: the conventional layout (tab indentation,
//! `Frame Time: {:.7}`, values with at most six decimals).

use std::fmt::Write as _;
use std::path::Path;

use crate::motion::Motion;

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
pub(super) fn push_number(out: &mut String, v: f64) {
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
