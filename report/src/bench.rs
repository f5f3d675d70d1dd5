//! `mocap bench`: encodes every file of the given folders at each error
//! bound and prints one rate–distortion table with per-folder totals
//! (total f32 bytes / total clip bytes). Figures, never assertions.

use std::path::{Path, PathBuf};

use std::time::Instant;

use mocap_encoder::bvh::BvhError;
use mocap_encoder::encode::{
    self, Bound, BoundError, BoundSpec, CodecChoice, EncodeError, EncodeOptions,
};

/// One row of the table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Folder name.
    pub group: String,
    /// File name.
    pub file: String,
    /// The bound, as given.
    pub bound: String,
    /// The codec asked for (`auto` rows name the one chosen in `chosen`).
    pub codec: String,
    /// The codec that made the clip.
    pub chosen: String,
    /// Frames × channels × 4.
    pub f32_bytes: usize,
    /// Input file size.
    pub file_bytes: usize,
    /// Metrics of the encoded clip.
    pub metrics: mocap_encoder::metrics::Metrics,
    /// Key interval chosen.
    pub key_interval: u16,
    /// Wall-clock seconds of the encode (search included).
    pub encode_seconds: f64,
}

/// Why the bench stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BenchError {
    /// A `--max-error` value does not parse.
    #[error(transparent)]
    Bound(#[from] BoundError),
    /// A folder cannot be listed.
    #[error(transparent)]
    Folder(#[from] std::io::Error),
    /// A file is not BVH.
    #[error(transparent)]
    Bvh(#[from] BvhError),
    /// A motion file (BVH or AMC/ASF) does not read.
    #[error(transparent)]
    Input(#[from] mocap_encoder::input::InputError),
    /// A file cannot be encoded at a bound.
    #[error("{}: {source}", file.display())]
    Encode {
        /// The file.
        file: PathBuf,
        /// Why.
        source: EncodeError,
    },
}

fn group_of(p: &Path) -> String {
    p.parent()
        .and_then(|d| d.file_name())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Where a bench reports as it runs.
pub trait Report {
    /// The progress of encode `at` (from 0) of `total` (one file with one
    /// codec at one bound, `label`).
    fn encode(&self, at: usize, total: usize, label: &str) -> Box<dyn encode::Progress + '_>;
    /// A finished encode's line (`  file codec @ bound: N bytes, ratio R`).
    fn line(&self, line: &str);
}

/// [`Report`] on stderr: each encode's line, no progress.
pub struct Stderr;

impl Report for Stderr {
    fn encode(&self, _: usize, _: usize, _: &str) -> Box<dyn encode::Progress + '_> {
        Box::new(encode::Silent)
    }

    fn line(&self, line: &str) {
        eprintln!("{line}");
    }
}

/// Runs the bench; each encode's line goes to stderr.
/// `bounds` are `+`-joined specs (`50mm+arms:10mm`), each one column of
/// the table.
pub fn run(
    paths: &[PathBuf],
    codecs: &[CodecChoice],
    bounds: &[String],
) -> Result<Vec<Row>, BenchError> {
    run_with(paths, codecs, bounds, &Stderr)
}

/// [`run`], reporting to `report`.
pub fn run_with(
    paths: &[PathBuf],
    codecs: &[CodecChoice],
    bounds: &[String],
    report: &dyn Report,
) -> Result<Vec<Row>, BenchError> {
    let specs = bounds
        .iter()
        .map(|b| {
            b.split('+')
                .map(|s| s.parse::<BoundSpec>())
                .collect::<Result<Vec<_>, _>>()
                .map(|v| Bound::from_specs(&v))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let files = mocap_encoder::input::expand(paths)?;
    let total = files.len() * codecs.len() * specs.len();
    let mut rows = Vec::new();
    for file in &files {
        let input = mocap_encoder::input::read_motion(file, None)?;
        let unit = input.unit_or_detect();
        let m = input.motion;
        let file_bytes = std::fs::metadata(file)
            .map(|md| md.len() as usize)
            .unwrap_or(0);
        for (&codec, (bound, name)) in codecs
            .iter()
            .flat_map(|c| std::iter::repeat(c).zip(specs.iter().zip(bounds)))
        {
            let opts = EncodeOptions {
                codec,
                bound: *bound,
                metres_per_unit: unit.metres(),
                key_interval: None,
            };
            let t = Instant::now();
            let label = format!("{} {} @ {name}", file.display(), codec.name());
            let progress = report.encode(rows.len(), total, &label);
            let enc = encode::encode_with(&m, &opts, progress.as_ref()).map_err(|source| {
                BenchError::Encode {
                    file: file.clone(),
                    source,
                }
            })?;
            let mut metrics = enc.metrics;
            metrics.ratio_file = file_bytes as f64 / enc.bytes.len() as f64;
            report.line(&format!(
                "  {label}: {} bytes, ratio {:.1}",
                enc.bytes.len(),
                metrics.ratio_f32
            ));
            rows.push(Row {
                group: group_of(file),
                file: file
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                bound: name.clone(),
                codec: codec.name().into(),
                chosen: enc.codec.name().into(),
                f32_bytes: m.frames() * m.channels() * 4,
                file_bytes,
                metrics,
                key_interval: enc.key_interval,
                encode_seconds: t.elapsed().as_secs_f64(),
            });
        }
    }
    Ok(rows)
}

/// The table as Markdown, with per-folder totals per codec and bound.
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| folder | file | codec | bound | frames×ch | bytes | ratio f32 | ratio file | ARMS mm | max mm | d % | angle RMS ° | angle max ° | K |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let m = &r.metrics;
        s += &format!(
            "| {} | {} | {} | {} | {}×{} | {} | {:.2} | {:.1} | {:.2} | {:.2} | {:.2} | {:.3} | {:.3} | {} |\n",
            r.group, r.file, r.chosen, r.bound, m.frames, m.channels, m.bytes, m.ratio_f32, m.ratio_file,
            m.arms_mm, m.max_joint_err_mm, m.distortion_pct, m.angle_rms_deg, m.angle_max_deg, r.key_interval
        );
    }
    s += "\n| folder | codec | bound | files | total f32 bytes | total clip bytes | aggregate ratio | worst ARMS mm | worst joint max mm | worst angle max ° | mean d % | encode s |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    let mut keys: Vec<(String, String, String)> = rows
        .iter()
        .map(|r| (r.group.clone(), r.codec.clone(), r.bound.clone()))
        .collect();
    keys.dedup();
    keys.sort();
    keys.dedup();
    for (g, c, b) in keys {
        let sel: Vec<&Row> = rows
            .iter()
            .filter(|r| r.group == g && r.codec == c && r.bound == b)
            .collect();
        let f32b: usize = sel.iter().map(|r| r.f32_bytes).sum();
        let clip: usize = sel.iter().map(|r| r.metrics.bytes).sum();
        let amax = sel
            .iter()
            .map(|r| r.metrics.angle_max_deg)
            .fold(0.0, f64::max);
        let jmax = sel
            .iter()
            .map(|r| r.metrics.max_joint_err_mm)
            .fold(0.0, f64::max);
        let arms = sel.iter().map(|r| r.metrics.arms_mm).fold(0.0, f64::max);
        let d = sel.iter().map(|r| r.metrics.distortion_pct).sum::<f64>() / sel.len().max(1) as f64;
        let secs: f64 = sel.iter().map(|r| r.encode_seconds).sum();
        s += &format!(
            "| {g} | {c} | {b} | {} | {f32b} | {clip} | {:.2} | {arms:.2} | {jmax:.1} | {amax:.3} | {d:.2} | {secs:.2} |\n",
            sel.len(),
            f32b as f64 / clip.max(1) as f64
        );
    }
    s
}
