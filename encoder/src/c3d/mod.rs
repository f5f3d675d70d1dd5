//! C3D marker files (c3d.org): 3-D marker trajectories, no skeleton.
//!
//! Read by hand rather than with the `c3dio` crate: its error type
//! (`C3dParseError`: `NotEnoughData`, `InvalidParameterData`, …) carries no
//! byte offset, so a malformed file could not be reported where it breaks,
//! and it brings `ndarray` and a reader/writer for much more than markers.
//! This reader covers what the encoder needs — points, labels, rate, units,
//! missing samples, stepping over analog samples — in the three encodings,
//! and every error is a [`C3dError`] naming the file and the byte offset.
//! Every read is bounds-checked (no indexing of file data), so no input
//! makes it panic (`tests.rs` reads every truncation of its files).
//!
//! What it reads:
//!
//! * the header block (block 1): byte 0 the parameter block pointer, byte 1
//!   `0x50`; words 2 point count, 3 analog values per frame, 4–5 first and
//!   last frame, 7–8 scale (float), 9 data start block, 11–12 frame rate
//!   (float);
//! * the parameter section: its header's processor type (byte 3: 84 Intel,
//!   85 DEC, 86 MIPS) sets the encoding of every word and float, the header's
//!   included; `POINT:USED`, `POINT:SCALE`, `POINT:RATE`, `POINT:FRAMES`,
//!   `POINT:DATA_START`, `POINT:UNITS`, `POINT:LABELS` (then `LABELS2`,
//!   `LABELS3`, … for more points), `ANALOG:USED`/`ANALOG:RATE` (checked
//!   against the header's analog count); for takes of more than 65 535
//!   frames, whose header words cannot count them, `TRIAL:ACTUAL_START_FIELD`
//!   and `TRIAL:ACTUAL_END_FIELD` (two int16 words each, low word first: a
//!   32-bit frame number, as Vicon writes them) or else `POINT:LONG_FRAMES`
//!   (a float, as C3Dserver writes it) give the frame range;
//! * the data section: per frame, 4 values per point (x, y, z, residual
//!   word) then the analog samples (skipped). Scale > 0: int16 values
//!   × scale; scale < 0: floats in the processor's format (DEC's VAX
//!   F-format converted exactly, [`bytes::dec_f32`]). A sample is *missing*
//!   when its residual is negative — the int16 word's sign bit (the high
//!   byte holds the camera mask) for integer data, the float's value for
//!   float data. Missing samples are reported in the mask, never filled
//!   here (their coordinates read as 0).
//!
//! Integers are little-endian for Intel and DEC, big-endian for MIPS; floats
//! are IEEE little-endian (Intel), VAX F (DEC), IEEE big-endian (MIPS).

mod bytes;
mod params;
#[cfg(test)]
mod tests;

use std::fmt;
use std::path::Path;

use crate::markers::{marker_skeleton, MarkerClip, MissingMask};
use crate::motion::Motion;
use crate::units::LengthUnit;
use bytes::Bytes;
use params::Params;

/// A C3D reading error: the file, the byte offset where it breaks (none for
/// an I/O error) and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct C3dError {
    /// The file name as given to the reader.
    pub file: String,
    /// Byte offset of the offending value (`None`: the file could not be read).
    pub offset: Option<usize>,
    /// What went wrong.
    pub message: String,
}

impl C3dError {
    fn at(file: &str, offset: usize, message: impl Into<String>) -> C3dError {
        C3dError {
            file: file.to_string(),
            offset: Some(offset),
            message: message.into(),
        }
    }
}

impl fmt::Display for C3dError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.offset {
            Some(at) => write!(f, "{}: byte {at}: {}", self.file, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for C3dError {}

/// The processor type of the parameter section: the file's number encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Processor {
    /// 84: little-endian integers, IEEE floats.
    Intel,
    /// 85: little-endian integers, VAX F-format floats.
    Dec,
    /// 86: big-endian integers and IEEE floats.
    Mips,
}

impl Processor {
    /// The parameter section's code (84, 85, 86).
    pub fn code(self) -> u8 {
        match self {
            Processor::Intel => 84,
            Processor::Dec => 85,
            Processor::Mips => 86,
        }
    }

    /// `Intel`, `DEC` or `MIPS`.
    pub fn name(self) -> &'static str {
        match self {
            Processor::Intel => "Intel",
            Processor::Dec => "DEC",
            Processor::Mips => "MIPS",
        }
    }
}

/// Where the length unit came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UnitSource {
    /// `POINT:UNITS`, as written.
    Parameter(String),
    /// No `POINT:UNITS`: C3D's millimetres.
    Default,
}

/// A read C3D file: its points frame by frame and which samples are missing.
#[derive(Clone, Debug, PartialEq)]
pub struct C3d {
    /// The number encoding.
    pub processor: Processor,
    /// True for float data (scale < 0), false for scaled int16.
    pub float: bool,
    /// The point scale (`POINT:SCALE`, else the header's).
    pub scale: f64,
    /// Frames.
    pub frames: usize,
    /// The header's first frame number (1-based in the file).
    pub first_frame: usize,
    /// Points (markers) per frame.
    pub points: usize,
    /// Analog values per frame (skipped).
    pub analog_per_frame: usize,
    /// Frames per second (`POINT:RATE`, else the header's).
    pub rate_hz: f64,
    /// One label per point, trimmed (`None`: no label for it in the file).
    pub labels: Vec<Option<String>>,
    /// Length unit of the coordinates.
    pub unit: LengthUnit,
    /// Where [`C3d::unit`] came from.
    pub unit_source: UnitSource,
    /// `positions[frame * points + point]`, in [`C3d::unit`]; 0 where missing.
    pub positions: Vec<[f64; 3]>,
    /// `missing[frame * points + point]`: the residual is negative.
    pub missing: Vec<bool>,
}

/// Reads a C3D file.
pub fn read_file(path: &Path) -> Result<C3d, C3dError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| C3dError {
        file: file.clone(),
        offset: None,
        message: format!("cannot read file: {e}"),
    })?;
    parse(&bytes, &file)
}

/// Reads a C3D file into a marker clip ([`C3d::to_markers`]).
pub fn read_markers(path: &Path) -> Result<MarkerClip, C3dError> {
    read_file(path).map(|c| c.to_markers())
}

/// True when `path` has the `.c3d` extension (any case): what the `mocap`
/// commands dispatch on.
pub fn is_c3d(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("c3d"))
}

const BLOCK: usize = 512;

/// Parses the bytes of a C3D file; `file` names it in errors.
pub fn parse(data: &[u8], file: &str) -> Result<C3d, C3dError> {
    let mut b = Bytes {
        data,
        file,
        processor: Processor::Intel,
    };
    let param_block = b.u8(0, "the header's parameter block pointer")?;
    let key = b.u8(1, "the header's key byte")?;
    if key != 0x50 {
        return Err(b.err(
            1,
            format!("not a C3D file: byte 1 is {key:#04x}, C3D has 0x50"),
        ));
    }
    if param_block < 2 {
        return Err(b.err(
            0,
            format!("parameter block pointer is {param_block}: the parameters start at block 2 or later (block 1 is the header)"),
        ));
    }
    let param_at = (usize::from(param_block) - 1) * BLOCK;
    if param_at + 4 > data.len() {
        return Err(b.err(
            0,
            format!(
                "parameter block pointer {param_block} points to byte {param_at}, past the end of the file ({} bytes)",
                data.len()
            ),
        ));
    }
    let param_blocks = usize::from(b.u8(param_at + 2, "the parameter section's block count")?);
    let code = b.u8(param_at + 3, "the processor type")?;
    b.processor = match code {
        84 => Processor::Intel,
        85 => Processor::Dec,
        86 => Processor::Mips,
        _ => {
            return Err(b.err(
                param_at + 3,
                format!("unknown processor type {code} (84 Intel, 85 DEC, 86 MIPS)"),
            ))
        }
    };
    // The header, in the processor's encoding.
    let h_points = usize::from(b.u16(2, "the header's point count")?);
    let h_analog = usize::from(b.u16(4, "the header's analog count")?);
    let first = usize::from(b.u16(6, "the header's first frame")?);
    let last = usize::from(b.u16(8, "the header's last frame")?);
    let h_scale = b.f32(12, "the header's scale")?;
    let h_data_block = usize::from(b.u16(16, "the header's data start block")?);
    let h_rate = b.f32(20, "the header's frame rate")?;

    let params = Params::parse(&b, param_at, param_blocks.max(1))?;

    // Points.
    let points = match params.count(&b, "POINT", "USED")? {
        Some(n) if n != h_points => {
            return Err(b.err(
                params.record_at("POINT", "USED").unwrap_or(2),
                format!("POINT:USED is {n}, the header says {h_points} points"),
            ))
        }
        _ => h_points,
    };
    // Frames: TRIAL's 32-bit range or POINT:LONG_FRAMES for long takes,
    // else the header's range, checked against POINT:FRAMES.
    let (first, frames) = match long_frames(&b, &params)? {
        Some(range) => range,
        None => {
            if last < first {
                return Err(b.err(
                    8,
                    format!("last frame {last} is before the first frame {first}"),
                ));
            }
            let frames = last - first + 1;
            if let Some(n) = params.count(&b, "POINT", "FRAMES")? {
                if n != frames {
                    return Err(b.err(
                        params.record_at("POINT", "FRAMES").unwrap_or(6),
                        format!(
                            "POINT:FRAMES is {n}, the header's frames {first}..={last} are {frames}"
                        ),
                    ));
                }
            }
            (first, frames)
        }
    };
    // Scale: its sign says integer or float data.
    let scale = params.number(&b, "POINT", "SCALE")?.unwrap_or(h_scale);
    if scale == 0.0 {
        return Err(b.err(
            params.record_at("POINT", "SCALE").unwrap_or(12),
            "point scale is 0 (> 0: scaled int16 data, < 0: float data)",
        ));
    }
    if (scale < 0.0) != (h_scale < 0.0) && h_scale != 0.0 {
        return Err(b.err(
            12,
            format!("the header's scale {h_scale} and POINT:SCALE {scale} disagree on integer or float data"),
        ));
    }
    let float = scale < 0.0;
    // Rate.
    let rate_hz = params.number(&b, "POINT", "RATE")?.unwrap_or(h_rate);
    if rate_hz <= 0.0 {
        return Err(b.err(
            params.record_at("POINT", "RATE").unwrap_or(20),
            format!("frame rate {rate_hz} Hz is not positive"),
        ));
    }
    // Data start.
    let data_block = match params.count(&b, "POINT", "DATA_START")? {
        Some(n) if n != h_data_block => {
            return Err(b.err(
                params.record_at("POINT", "DATA_START").unwrap_or(16),
                format!("POINT:DATA_START is block {n}, the header says block {h_data_block}"),
            ))
        }
        _ => h_data_block,
    };
    if data_block < 2 {
        return Err(b.err(
            16,
            format!("data start block is {data_block}: the data start at block 2 or later"),
        ));
    }
    // Analog values per frame: the header's, checked against ANALOG:USED × rate ratio.
    if let (Some(used), Some(arate)) = (
        params.count(&b, "ANALOG", "USED")?,
        params.number(&b, "ANALOG", "RATE")?,
    ) {
        let per = arate / rate_hz;
        let expected = used as f64 * per;
        if used > 0 && (per.fract() != 0.0 || expected != h_analog as f64) {
            return Err(b.err(
                4,
                format!(
                    "the header has {h_analog} analog values per frame; ANALOG:USED {used} at {arate} Hz over {rate_hz} Hz frames gives {expected}"
                ),
            ));
        }
    }
    // Units.
    let (unit, unit_source) = match params.strings(&b, "POINT", "UNITS")? {
        Some(list) => {
            let (text, at) = list.into_iter().next().unwrap_or((String::new(), 0));
            let unit = unit_of(&text).ok_or_else(|| {
                b.err(
                    at,
                    format!("POINT:UNITS '{text}' is not a length unit (mm, cm, m, in)"),
                )
            })?;
            (unit, UnitSource::Parameter(text))
        }
        None => (LengthUnit::Mm, UnitSource::Default),
    };
    // Labels: LABELS, LABELS2, LABELS3, …
    let mut labels: Vec<Option<String>> = Vec::with_capacity(points);
    for k in 1.. {
        let name = if k == 1 {
            "LABELS".to_string()
        } else {
            format!("LABELS{k}")
        };
        let Some(list) = params.strings(&b, "POINT", &name)? else {
            break;
        };
        labels.extend(list.into_iter().map(|(s, _)| (!s.is_empty()).then_some(s)));
        if labels.len() >= points {
            break;
        }
    }
    labels.resize(points, None);

    // The data.
    let word = if float { 4 } else { 2 };
    let frame_bytes = (points * 4 + h_analog) * word;
    let data_at = (data_block - 1) * BLOCK;
    // Every frame must be in the file (before anything is allocated for them).
    if let Some(whole) = data.len().saturating_sub(data_at).checked_div(frame_bytes) {
        if whole < frames {
            let at = data_at + whole * frame_bytes;
            return Err(b.err(
                at,
                format!(
                    "file ends inside frame {} of {frames} ({frame_bytes} bytes at byte {at}, the file has {})",
                    whole + 1,
                    data.len()
                ),
            ));
        }
    }
    let mut positions = Vec::with_capacity(frames * points);
    let mut missing = Vec::with_capacity(frames * points);
    for f in 0..frames {
        let at = data_at + f * frame_bytes;
        for p in 0..points {
            let at = at + p * 4 * word;
            let (xyz, gone) = if float {
                let r = b.f32(at + 12, "a residual")?;
                let gone = r < 0.0;
                let mut xyz = [0.0; 3];
                if !gone {
                    for (k, v) in xyz.iter_mut().enumerate() {
                        *v = b.f32_named(at + 4 * k, || coordinate(f, p, k))?;
                    }
                }
                (xyz, gone)
            } else {
                let gone = b.i16(at + 6, "a residual word")? < 0;
                let mut xyz = [0.0; 3];
                if !gone {
                    for (k, v) in xyz.iter_mut().enumerate() {
                        *v = f64::from(b.i16(at + 2 * k, "a coordinate")?) * scale;
                    }
                }
                (xyz, gone)
            };
            positions.push(xyz);
            missing.push(gone);
        }
    }
    Ok(C3d {
        processor: b.processor,
        float,
        scale,
        frames,
        first_frame: first,
        points,
        analog_per_frame: h_analog,
        rate_hz,
        labels,
        unit,
        unit_source,
        positions,
        missing,
    })
}

/// The first frame and frame count of a take longer than the header's
/// 16-bit words can count: `TRIAL:ACTUAL_START_FIELD`/`ACTUAL_END_FIELD`
/// (each two int16 words, low first) when both are present, else
/// `POINT:LONG_FRAMES` (first frame 1); `None` when neither is (or the
/// range fits the header, which then stays the authority).
fn long_frames(b: &Bytes<'_>, params: &Params) -> Result<Option<(usize, usize)>, C3dError> {
    let field = |name: &str| -> Result<Option<u32>, C3dError> {
        let Some(p) = params.get("TRIAL", name) else {
            return Ok(None);
        };
        let what = format!("TRIAL:{name}");
        if p.kind != 2 || p.elements() != 2 {
            return Err(b.err(
                p.record_at,
                format!(
                    "{what} must be two int16 words (type {}, {} elements)",
                    p.kind,
                    p.elements()
                ),
            ));
        }
        let lo = b.u16(p.data_at, &what)?;
        let hi = b.u16(p.data_at + 2, &what)?;
        Ok(Some(u32::from(lo) | u32::from(hi) << 16))
    };
    if let (Some(start), Some(end)) = (field("ACTUAL_START_FIELD")?, field("ACTUAL_END_FIELD")?) {
        if end < start {
            return Err(b.err(
                params.record_at("TRIAL", "ACTUAL_END_FIELD").unwrap_or(8),
                format!("TRIAL:ACTUAL_END_FIELD {end} is before ACTUAL_START_FIELD {start}"),
            ));
        }
        let frames = (end - start) as usize + 1;
        if frames > usize::from(u16::MAX) {
            return Ok(Some((start as usize, frames)));
        }
        return Ok(None);
    }
    match params.count(b, "POINT", "LONG_FRAMES")? {
        Some(n) if n > usize::from(u16::MAX) => Ok(Some((1, n))),
        _ => Ok(None),
    }
}

fn coordinate(frame: usize, point: usize, axis: usize) -> String {
    format!(
        "the {} coordinate of point {} at frame {}",
        ["x", "y", "z"].get(axis).copied().unwrap_or("?"),
        point + 1,
        frame + 1
    )
}

/// `POINT:UNITS` text as a length unit.
fn unit_of(text: &str) -> Option<LengthUnit> {
    let t = text.trim().to_ascii_lowercase();
    Some(match t.as_str() {
        "mm" | "millimeter" | "millimeters" | "millimetre" | "millimetres" => LengthUnit::Mm,
        "cm" | "centimeter" | "centimeters" | "centimetre" | "centimetres" => LengthUnit::Cm,
        "m" | "meter" | "meters" | "metre" | "metres" => LengthUnit::M,
        "in" | "inch" | "inches" => LengthUnit::In,
        _ => return None,
    })
}

impl C3d {
    /// What was read, in one line: encoding, data type, frames, rate,
    /// points, analog values per frame, unit and the missing fraction.
    pub fn summary(&self) -> String {
        format!(
            "{} {} data, {} frames at {} Hz, {} points, {} analog values per frame, unit {} ({:?}), {:.1} % of samples missing",
            self.processor.name(),
            if self.float { "float" } else { "integer" },
            self.frames,
            self.rate_hz,
            self.points,
            self.analog_per_frame,
            self.unit,
            self.unit_source,
            100.0 * self.missing_fraction()
        )
    }

    /// The fraction of samples (frame × point) that are missing.
    pub fn missing_fraction(&self) -> f64 {
        let n = self.missing.iter().filter(|&&m| m).count();
        n as f64 / self.missing.len().max(1) as f64
    }

    /// Marker names: the labels trimmed, `P01`, `P02`, … for points
    /// without one, a repeated name made unique with `_2`, `_3`, …
    pub fn marker_names(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::with_capacity(self.points);
        for (i, l) in self.labels.iter().enumerate() {
            let base = l.clone().unwrap_or_else(|| format!("P{:02}", i + 1));
            let mut name = base.clone();
            let mut k = 2;
            while names.contains(&name) {
                name = format!("{base}_{k}");
                k += 1;
            }
            names.push(name);
        }
        names
    }

    /// The markers as a motion — one root joint per marker, named by
    /// [`C3d::marker_names`], channels `Xposition Yposition Zposition`,
    /// offset 0, no End Sites; values in [`C3d::unit`], 0 where missing —
    /// with the missing mask and the unit.
    pub fn to_markers(&self) -> MarkerClip {
        MarkerClip {
            motion: Motion {
                skeleton: marker_skeleton(self.marker_names()),
                frame_time: 1.0 / self.rate_hz,
                values: self.positions.iter().flatten().copied().collect(),
            },
            missing: MissingMask {
                frames: self.frames,
                markers: self.points,
                missing: self.missing.clone(),
            },
            unit: self.unit,
        }
    }
}
