//! C3D marker files in `mocap encode` and `mocap eval`: dispatched by the
//! `.c3d` extension ([`is_marker_file`]), kept apart from the BVH path so
//! that each command's change is one `if` at its top.

use std::path::Path;

use mocap_encoder::c3d::{self, UnitSource};
use mocap_encoder::codec::index::IndexLayout;
use mocap_encoder::encode::{Bound, BoundSpec, EncodeOptions};
use mocap_encoder::markers::{self, EncodedMarkers, MarkerClip, MarkerError, MissingMask};
use mocap_encoder::units::LengthUnit;
use mocap_encoder::{clipfile, codec::CodecChoice};

use super::{parse_clip, read_clip, UnitArg};

/// True for a C3D marker file (`.c3d`, any case).
pub fn is_marker_file(path: &Path) -> bool {
    c3d::is_c3d(path)
}

/// Reads a C3D file as a marker clip; the unit is the file's (`POINT:UNITS`,
/// else C3D's mm) unless `--units` names one. Prints what was read.
pub fn read(path: &Path, units: &UnitArg) -> super::Result<(MarkerClip, LengthUnit)> {
    let c = c3d::read_file(path)?;
    let clip = c.to_markers();
    let (unit, from) = match units {
        UnitArg::Fixed(u) => (*u, "--units".to_string()),
        UnitArg::Auto => (
            clip.unit,
            match &c.unit_source {
                UnitSource::Parameter(t) => format!("POINT:UNITS '{t}'"),
                UnitSource::Default => "no POINT:UNITS: C3D's mm".to_string(),
            },
        ),
    };
    let mask = &clip.missing;
    eprintln!(
        "{}: C3D ({} {}), {} frames × {} markers at {} Hz, units {unit} ({from}), {} samples missing ({:.1} %) in {} runs",
        path.display(),
        c.processor.name(),
        if c.float { "float" } else { "integer" },
        c.frames,
        c.points,
        c.rate_hz,
        mask.count(),
        100.0 * c.missing_fraction(),
        mask.runs()
    );
    Ok((clip, unit))
}

/// The bound of a marker clip: lengths only (markers have no rotation
/// channel); 1 mm when none is given.
pub fn bound(specs: &[BoundSpec]) -> super::Result<Bound> {
    if specs.iter().any(|s| matches!(s, BoundSpec::Degrees(_))) {
        return Err(
            "a marker clip has no rotation channels: give its bound as a length \
             (e.g. --max-error 5mm, the largest marker position error)"
                .into(),
        );
    }
    if specs.iter().any(|s| matches!(s, BoundSpec::Slide(_))) {
        return Err(
            "a marker clip has no skeleton, so no feet to keep from sliding: \
                    give its bound as a length (e.g. --max-error 5mm)"
                .into(),
        );
    }
    if specs.is_empty() {
        return Ok(Bound::from_specs(&[BoundSpec::Millimetres(1.0)]));
    }
    Ok(Bound::from_specs(specs))
}

/// `mocap encode markers.c3d`: fills the missing samples, encodes, proves the
/// bound, flags the missing samples in the clip (SPEC.md §3.7).
pub fn encode(
    input: &Path,
    units: &UnitArg,
    specs: &[BoundSpec],
    codec: CodecChoice,
    key_interval: Option<u16>,
) -> super::Result<Vec<u8>> {
    let bound = bound(specs)?;
    let (clip, unit) = read(input, units)?;
    eprintln!("encoding ({codec:?}, bound {bound}; missing samples filled for coding, flagged in the clip)…");
    let opts = options(codec, Default::default(), bound, unit, key_interval);
    let enc = markers::encode_markers(&clip, &opts)?;
    print_summary(&enc, &opts.bound);
    Ok(enc.encoded.bytes)
}

/// One codec's (and `index` layout's) marker clip, or why it could not
/// make one.
pub type MarkerAttempt = (
    (CodecChoice, IndexLayout),
    Result<EncodedMarkers, MarkerError>,
);

/// Each codec and `index` layout of `variants` coding the marker file
/// (read once), for `--target`'s choice: the marker clips, or why a codec
/// could not make one.
pub fn encode_each(
    input: &Path,
    units: &UnitArg,
    specs: &[BoundSpec],
    variants: &[(CodecChoice, IndexLayout)],
    key_interval: Option<u16>,
) -> super::Result<Vec<MarkerAttempt>> {
    let bound = bound(specs)?;
    let (clip, unit) = read(input, units)?;
    eprintln!(
        "encoding with each codec (bound {bound}; missing samples filled for coding, flagged in the clip)…"
    );
    Ok(variants
        .iter()
        .map(|&(codec, index_layout)| {
            let opts = options(codec, index_layout, bound, unit, key_interval);
            ((codec, index_layout), markers::encode_markers(&clip, &opts))
        })
        .collect())
}

/// The encoder's options for a marker clip.
fn options(
    codec: CodecChoice,
    index_layout: IndexLayout,
    bound: Bound,
    unit: LengthUnit,
    key_interval: Option<u16>,
) -> EncodeOptions {
    EncodeOptions {
        key_bits: None,
        codec,
        bound,
        metres_per_unit: unit.metres(),
        key_interval,
        index_layout,
        pattern: Default::default(),
    }
}

/// The line `mocap encode` prints for a marker clip.
fn print_summary(enc: &EncodedMarkers, bound: &Bound) {
    let x = &enc.error;
    println!(
        "{} bytes, ratio {:.2}:1 vs f32, marker error max {:.2} mm ({} at frame {}), ARMS {:.2} mm, RMS {:.2} mm over {} present samples; {} missing samples flagged (bound {bound} holds on the present samples; {})",
        enc.encoded.bytes.len(),
        enc.encoded.metrics.ratio_f32,
        x.max_mm,
        x.max_marker,
        x.max_frame,
        x.arms_mm,
        x.rms_mm,
        x.present,
        x.missing,
        enc.encoded.codec.name()
    );
}

/// `mocap eval markers.c3d clip.mcb`: marker position error over the present
/// samples, and whether the clip flags exactly the file's missing samples.
pub fn eval(input: &Path, clip_path: &Path, units: &UnitArg, json: bool) -> super::Result {
    let (clip, unit) = read(input, units)?;
    let bytes = read_clip(clip_path)?;
    let parsed = parse_clip(clip_path, &bytes)?;
    let filled = markers::fill(&clip.motion, &clip.missing);
    let back = clipfile::decode_against(&parsed, &filled, unit.metres()).map_err(|e| {
        format!(
            "{} does not play against {}: {e}",
            clip_path.display(),
            input.display()
        )
    })?;
    let error = markers::marker_errors(&clip.motion, &back, &clip.missing, unit.metres());
    let theirs = MissingMask::of_clip(&parsed)
        .unwrap_or_else(|| MissingMask::none(clip.missing.frames, clip.missing.markers));
    let ratio_f32 = (filled.frames() * filled.channels() * 4) as f64 / bytes.len().max(1) as f64;
    let runs = clip.missing.runs();
    let matches = theirs == clip.missing;
    let x = &error;
    if json {
        let mut v = serde_json::to_value(x)?;
        if let Some(o) = v.as_object_mut() {
            o.insert("bytes".into(), bytes.len().into());
            o.insert("ratio_f32".into(), ratio_f32.into());
            o.insert("missing_runs".into(), runs.into());
            o.insert("mask_matches".into(), matches.into());
            o.insert("frames".into(), clip.missing.frames.into());
            o.insert("markers".into(), clip.missing.markers.into());
        }
        println!("{v}");
        return Ok(());
    }
    println!("bytes               {}", bytes.len());
    println!("ratio vs f32        {ratio_f32:.2}:1");
    println!(
        "marker error max    {:.3} mm ({} at frame {})",
        x.max_mm, x.max_marker, x.max_frame
    );
    println!(
        "marker error RMS    {:.3} mm (mean {:.3} mm)",
        x.rms_mm, x.mean_mm
    );
    println!("marker error ARMS   {:.3} mm", x.arms_mm);
    println!("present samples     {}", x.present);
    println!(
        "missing samples     {} ({:.1} %) in {} runs: {}",
        x.missing,
        100.0 * x.missing as f64 / (x.missing + x.present).max(1) as f64,
        runs,
        if matches {
            "the clip flags exactly these (SPEC.md §3.7)".to_string()
        } else {
            format!(
                "the clip flags {} samples, not these (SPEC.md §3.7)",
                theirs.count()
            )
        }
    );
    println!(
        "frames×markers      {}×{}",
        clip.missing.frames, clip.missing.markers
    );
    Ok(())
}

/// The `mocap view` page of a C3D file and, optionally, its clip: the
/// filled markers (the clip's source), missing samples drawn hollow.
pub fn view(
    input: &Path,
    clip_path: Option<&Path>,
    units: &UnitArg,
) -> super::Result<mocap_report::view::Page> {
    let (clip, unit) = read(input, units)?;
    let filled = markers::fill(&clip.motion, &clip.missing);
    let decoded = match clip_path {
        Some(path) => {
            let bytes = read_clip(path)?;
            let parsed = parse_clip(path, &bytes)?;
            let back = clipfile::decode_against(&parsed, &filled, unit.metres()).map_err(|e| {
                format!(
                    "{} does not play against {}: {e}",
                    path.display(),
                    input.display()
                )
            })?;
            Some((back, bytes.len()))
        }
        None => None,
    };
    let (source, clip_name) = (
        mocap_report::view::file_name(input),
        clip_path.map(mocap_report::view::file_name),
    );
    let names = mocap_report::view::Names {
        source: &source,
        clip: clip_name.as_deref(),
        source_bytes: std::fs::metadata(input).map_or(0, |m| m.len() as usize),
    };
    Ok(mocap_report::view::page_with_missing(
        &filled,
        unit,
        decoded.as_ref().map(|(b, n)| (b, *n)),
        &names,
        Some(&clip.missing),
    )?)
}
