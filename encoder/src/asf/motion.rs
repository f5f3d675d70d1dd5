//! The AMC reader: frames of dof values against a parsed ASF.

use std::collections::HashMap;

use super::skeleton::{AngleUnit, Asf, Dof};
use super::text::{column, lines, uncomment};
use super::AsfError;

/// The frames of an AMC file, as read: per frame, every segment's dof
/// values (rotations converted to degrees) in the file's dof order.
#[derive(Clone, Debug, PartialEq)]
pub struct Amc {
    /// `:FULLY-SPECIFIED` was present.
    pub fully_specified: bool,
    /// The angle unit of the file's values (`:DEGREES`/`:RADIANS`, else the
    /// ASF's).
    pub angle: AngleUnit,
    /// The number of the first frame (CMU: 1).
    pub first_frame: i64,
    /// Where each segment's values start in a frame row: segment 0 is the
    /// root (its `order`), segment `1 + b` bone `b` (its `dof`).
    pub offsets: Vec<usize>,
    /// Values per frame (the sum of every segment's dof).
    pub width: usize,
    /// Row-major values: `values[frame * width + offsets[segment] + k]`.
    pub values: Vec<f64>,
}

impl Amc {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.values.len().checked_div(self.width).unwrap_or(0)
    }

    /// The values of `segment` (0 = root, `1 + b` = bone `b`) in `frame`.
    pub fn segment(&self, frame: usize, segment: usize, asf: &Asf) -> &[f64] {
        let n = segment_dof(asf, segment).len();
        let at = frame * self.width + self.offsets[segment];
        &self.values[at..at + n]
    }

    /// Frames with at least one bone dof value outside its `limits` (the
    /// root has none) by more than [`LIMIT_TOLERANCE`].
    pub fn frames_outside_limits(&self, asf: &Asf) -> usize {
        (0..self.frames())
            .filter(|&f| {
                asf.bones.iter().enumerate().any(|(b, bone)| {
                    let v = self.segment(f, 1 + b, asf);
                    bone.limits
                        .iter()
                        .zip(v)
                        .any(|(&(lo, hi), &x)| outside(x, lo, hi))
                })
            })
            .count()
    }

    /// For every bone dof with limits that some frame leaves: `(bone,
    /// dof index, frames outside)`.
    pub fn limit_violations(&self, asf: &Asf) -> Vec<(usize, usize, usize)> {
        let mut out = Vec::new();
        for (b, bone) in asf.bones.iter().enumerate() {
            for (k, &(lo, hi)) in bone.limits.iter().enumerate() {
                let n = (0..self.frames())
                    .filter(|&f| {
                        let x = self.segment(f, 1 + b, asf)[k];
                        outside(x, lo, hi)
                    })
                    .count();
                if n > 0 {
                    out.push((b, k, n));
                }
            }
        }
        out
    }
}

/// How far past a limit a value may lie and still count as inside: CMU
/// writes 0 as ±1e-14 (`lclavicle -1.16413e-014 -2.38542e-014` against
/// `(0.0 20.0)`), which is not a violation.
pub const LIMIT_TOLERANCE: f64 = 1e-6;

fn outside(x: f64, lo: f64, hi: f64) -> bool {
    x < lo - LIMIT_TOLERANCE || x > hi + LIMIT_TOLERANCE
}

/// The dof of a segment: the root's `order` or a bone's `dof`.
pub(super) fn segment_dof(asf: &Asf, segment: usize) -> &[Dof] {
    match segment {
        0 => &asf.root.order,
        s => &asf.bones[s - 1].dof,
    }
}

fn segment_name(asf: &Asf, segment: usize) -> &str {
    match segment {
        0 => "root",
        s => &asf.bones[s - 1].name,
    }
}

/// Parses AMC text against `asf`. `file` is only used in error messages.
pub fn parse_amc(text: &str, file: &str, asf: &Asf) -> Result<Amc, AsfError> {
    let segments = 1 + asf.bones.len();
    let mut offsets = Vec::with_capacity(segments);
    let mut width = 0;
    for s in 0..segments {
        offsets.push(width);
        width += segment_dof(asf, s).len();
    }
    let index: HashMap<&str, usize> = std::iter::once(("root", 0))
        .chain(
            asf.bones
                .iter()
                .enumerate()
                .map(|(b, bone)| (bone.name.as_str(), 1 + b)),
        )
        .collect();
    // Degrees per unit of each value of a frame row (1 for translations).
    let mut amc = Amc {
        fully_specified: false,
        angle: asf.units.angle,
        first_frame: 0,
        offsets,
        width,
        values: Vec::new(),
    };
    let mut scale: Vec<f64> = Vec::new();
    let mut frame: Option<(i64, usize)> = None;
    // The frame (1-based count) in which each segment last had its line.
    let mut seen = vec![0usize; segments];
    let mut frames = 0usize;
    let err = |no: usize, line: &str, byte: usize, msg: String| {
        AsfError::new(file, no, column(line, byte), msg)
    };
    let check_complete = |seen: &[usize], frames: usize, at: Option<(i64, usize)>| {
        let Some((n, line)) = at else { return Ok(()) };
        match (0..segments).find(|&s| seen[s] != frames && !segment_dof(asf, s).is_empty()) {
            Some(s) => Err(AsfError::new(
                file,
                line,
                1,
                format!(
                    "frame {n} has no line for bone '{}' ({} dof)",
                    segment_name(asf, s),
                    segment_dof(asf, s).len()
                ),
            )),
            None => Ok(()),
        }
    };
    for (no, raw) in lines(text) {
        let line = uncomment(raw);
        let body = line.trim_start();
        if body.is_empty() {
            continue;
        }
        let start = line.len() - body.len();
        if body.starts_with(':') {
            if frame.is_some() {
                return Err(err(
                    no,
                    line,
                    start,
                    format!("header line '{}' after the first frame", body.trim_end()),
                ));
            }
            let kw = body.split_ascii_whitespace().next().unwrap_or(body);
            if kw.eq_ignore_ascii_case(":FULLY-SPECIFIED") {
                amc.fully_specified = true;
            } else if kw.eq_ignore_ascii_case(":DEGREES") {
                amc.angle = AngleUnit::Deg;
            } else if kw.eq_ignore_ascii_case(":RADIANS") {
                amc.angle = AngleUnit::Rad;
            }
            continue;
        }
        let mut toks = body.split_ascii_whitespace();
        let name = toks.next().unwrap_or_default();
        if name.as_bytes()[0].is_ascii_digit() || name.starts_with('-') {
            // A frame-number line.
            let n: i64 = name.parse().map_err(|_| {
                err(
                    no,
                    line,
                    start,
                    format!("expected a frame number or a bone name, found '{name}'"),
                )
            })?;
            if let Some(t) = toks.next() {
                let at = t.as_ptr() as usize - line.as_ptr() as usize;
                return Err(err(
                    no,
                    line,
                    at,
                    format!("unexpected '{t}' after frame number {n}"),
                ));
            }
            check_complete(&seen, frames, frame)?;
            match frame {
                None => amc.first_frame = n,
                Some((prev, _)) if n != prev + 1 => {
                    return Err(err(
                        no,
                        line,
                        start,
                        format!(
                        "frame {n} follows frame {prev} (frames must be numbered consecutively)"
                    ),
                    ))
                }
                Some(_) => {}
            }
            if scale.is_empty() {
                let deg = amc.angle.degrees();
                scale = (0..segments)
                    .flat_map(|s| segment_dof(asf, s).iter())
                    .map(|d| if d.is_rotation() { deg } else { 1.0 })
                    .collect();
            }
            frame = Some((n, no));
            frames += 1;
            amc.values.resize(frames * width, f64::NAN);
            continue;
        }
        let Some((n, _)) = frame else {
            return Err(err(
                no,
                line,
                start,
                format!("bone line '{name}' before the first frame number"),
            ));
        };
        let Some(&s) = index.get(name) else {
            return Err(err(
                no,
                line,
                start,
                format!("unknown bone '{name}' (not in the ASF)"),
            ));
        };
        if seen[s] == frames {
            return Err(err(
                no,
                line,
                start,
                format!("bone '{name}' appears twice in frame {n}"),
            ));
        }
        seen[s] = frames;
        let dof = segment_dof(asf, s);
        let base = (frames - 1) * width + amc.offsets[s];
        let mut k = 0;
        for t in toks {
            let at = || t.as_ptr() as usize - line.as_ptr() as usize;
            if k == dof.len() {
                return Err(err(
                    no,
                    line,
                    at(),
                    format!(
                        "bone '{name}' has {} dof ({}) but the line has more values",
                        dof.len(),
                        dof_names(dof)
                    ),
                ));
            }
            let v: f64 = match t.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                _ => {
                    return Err(err(
                        no,
                        line,
                        at(),
                        format!(
                            "bone '{name}' {}: expected a finite number, found '{t}'",
                            dof[k].name()
                        ),
                    ))
                }
            };
            amc.values[base + k] = v * scale[amc.offsets[s] + k];
            k += 1;
        }
        if k < dof.len() {
            return Err(err(
                no,
                line,
                line.trim_end().len(),
                format!(
                    "bone '{name}' has {} dof ({}) but the line has {k} value{}",
                    dof.len(),
                    dof_names(dof),
                    if k == 1 { "" } else { "s" }
                ),
            ));
        }
    }
    check_complete(&seen, frames, frame)?;
    if frames == 0 {
        return Err(AsfError::new(
            file,
            0,
            0,
            "no frames (no frame-number line)",
        ));
    }
    Ok(amc)
}

fn dof_names(dof: &[Dof]) -> String {
    dof.iter().map(|d| d.name()).collect::<Vec<_>>().join(" ")
}
