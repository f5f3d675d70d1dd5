//! `mocap bench`: encodes every file of the given folders at each error
//! bound with each method — our codecs and the size references users would
//! pick instead ([`baseline`]) — and prints one rate–distortion table with
//! per-folder totals. Figures, never assertions.
//!
//! Sizes: a row's `metrics.bytes` is its size *with* the skeleton header
//! (`header_bytes`): for our codecs the whole `.mcb` file, whose header is
//! its non-codec sections (the compact header, and a marker clip's
//! missing-sample mask); for a baseline its own bytes (parameters and
//! payload, compressed where it compresses) plus the header our clip of the
//! same input carries (the compact header of the input's ranges, and the
//! same mask). "Without header" subtracts `header_bytes` on both sides.

pub mod baseline;

use std::path::{Path, PathBuf};
use std::time::Instant;

use mocap_encoder::bvh::BvhError;
use mocap_encoder::c3d::{self, C3dError};
use mocap_encoder::container::HeaderWire;
use mocap_encoder::encode::{
    self, Bound, BoundError, BoundSpec, CodecChoice, EncodeError, EncodeOptions, Encoded,
    Reference, AUTO_CODECS,
};
use mocap_encoder::markers::{self, MarkerClip, MarkerError};
use mocap_encoder::motion::Motion;

pub use baseline::Baseline;

/// What a row is coded with: one of our codecs or a baseline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// A codec of the format (`auto`: the smallest of [`AUTO_CODECS`]).
    Codec(CodecChoice),
    /// A size reference.
    Baseline(Baseline),
}

impl Method {
    /// The name in tables and rows.
    pub fn name(self) -> &'static str {
        match self {
            Method::Codec(c) => c.name(),
            Method::Baseline(b) => b.name(),
        }
    }
}

/// One row of the table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Folder name.
    pub group: String,
    /// File name.
    pub file: String,
    /// The bound, as given.
    pub bound: String,
    /// The method asked for (`auto` rows name the codec chosen in `chosen`).
    pub codec: String,
    /// The codec that made the clip (the baseline's name for a baseline).
    pub chosen: String,
    /// Frames × channels × 4.
    pub f32_bytes: usize,
    /// Input file size.
    pub file_bytes: usize,
    /// The skeleton header in `metrics.bytes` (see the module documentation).
    pub header_bytes: usize,
    /// Metrics, measured on the decoded motion; `bytes` and `ratio_f32`
    /// with the header.
    pub metrics: mocap_encoder::metrics::Metrics,
    /// `f32_bytes / (metrics.bytes − header_bytes)`.
    pub ratio_f32_without_header: f64,
    /// `8 · (metrics.bytes − header_bytes) / (frames × channels)`.
    pub bits_per_value: f64,
    /// Whether the bound holds on the measured metrics (always for our
    /// codecs and the tuned baselines; `raw16` is what it is).
    pub holds: bool,
    /// Key interval chosen (index codec; predictive block length).
    pub key_interval: u16,
    /// Frames in repeated clips (`rma` clips; `None` for the others).
    pub repeated_frames: Option<usize>,
    /// Wall-clock seconds of the encode (search included; `auto` derived
    /// from the three codecs' rows: the sum of their times).
    pub encode_seconds: f64,
}

impl Row {
    /// Bytes without the skeleton header.
    pub fn bytes_without_header(&self) -> usize {
        self.metrics.bytes.saturating_sub(self.header_bytes)
    }
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
    /// A C3D marker file does not read.
    #[error(transparent)]
    C3d(#[from] C3dError),
    /// A file cannot be encoded at a bound.
    #[error("{}: {source}", file.display())]
    Encode {
        /// The file.
        file: PathBuf,
        /// Why.
        source: EncodeError,
    },
    /// A marker file cannot be encoded at a bound.
    #[error("{}: {source}", file.display())]
    Markers {
        /// The file.
        file: PathBuf,
        /// Why.
        source: MarkerError,
    },
    /// A baseline cannot code a file at a bound.
    #[error("{}: {source}", file.display())]
    Baseline {
        /// The file.
        file: PathBuf,
        /// Why.
        source: baseline::BaselineError,
    },
}

fn group_of(p: &Path) -> String {
    p.parent()
        .and_then(|d| d.file_name())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Parses `--max-error` values, `+`-joined specs each (`50mm+arms:10mm`).
pub fn parse_bounds(bounds: &[String]) -> Result<Vec<Bound>, BoundError> {
    bounds
        .iter()
        .map(|b| {
            b.split('+')
                .map(|s| s.parse::<BoundSpec>())
                .collect::<Result<Vec<_>, _>>()
                .map(|v| Bound::from_specs(&v))
        })
        .collect()
}

/// One input file as the bench codes it.
struct Source {
    path: PathBuf,
    /// The motion the codecs code (a marker clip's filled in).
    motion: Motion,
    metres_per_unit: f64,
    /// A C3D marker clip as read (its motion with holes, its mask).
    markers: Option<MarkerClip>,
    file_bytes: usize,
}

impl Source {
    fn read(path: &Path) -> Result<Source, BenchError> {
        let file_bytes = std::fs::metadata(path).map_or(0, |md| md.len() as usize);
        if c3d::is_c3d(path) {
            let clip = c3d::read_file(path)?.to_markers();
            return Ok(Source {
                path: path.to_path_buf(),
                motion: markers::fill(&clip.motion, &clip.missing),
                metres_per_unit: clip.unit.metres(),
                markers: Some(clip),
                file_bytes,
            });
        }
        let input = mocap_encoder::input::read_motion(path, None)?;
        Ok(Source {
            path: path.to_path_buf(),
            metres_per_unit: input.unit_or_detect().metres(),
            motion: input.motion,
            markers: None,
            file_bytes,
        })
    }

    fn name(&self) -> String {
        self.path
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    }

    /// Encodes with one of our codecs (a marker clip with its mask).
    fn encode(
        &self,
        codec: CodecChoice,
        bound: &Bound,
        progress: &dyn encode::Progress,
    ) -> Result<(Encoded, f64), BenchError> {
        let opts = EncodeOptions {
            key_bits: None,
            codec,
            bound: *bound,
            metres_per_unit: self.metres_per_unit,
            key_interval: None,
            index_layout: Default::default(),
            pattern: Default::default(),
        };
        let t = Instant::now();
        let enc = match &self.markers {
            Some(clip) => {
                markers::encode_markers(clip, &opts)
                    .map_err(|source| BenchError::Markers {
                        file: self.path.clone(),
                        source,
                    })?
                    .encoded
            }
            None => encode::encode_with(&self.motion, &opts, progress).map_err(|source| {
                BenchError::Encode {
                    file: self.path.clone(),
                    source,
                }
            })?,
        };
        Ok((enc, t.elapsed().as_secs_f64()))
    }

    /// The header a baseline is charged: our compact header of the input's
    /// ranges, and a marker clip's mask section.
    fn baseline_header(&self, reference: &Reference) -> usize {
        let header = HeaderWire::new(&self.motion, self.metres_per_unit, reference.fixed());
        header.to_compact().len()
            + self
                .markers
                .as_ref()
                .map(|c| &c.missing)
                .filter(|m| m.count() > 0)
                .map_or(0, |m| m.to_section().len())
    }
}

/// The non-codec sections of a clip (its header, a marker clip's mask).
fn clip_header_bytes(clip: &[u8]) -> usize {
    match mocap_decoder::Clip::parse(clip) {
        Ok(c) => c
            .sections()
            .filter(|s| s.id != c.codec_id())
            .map(|s| s.bytes.len())
            .sum(),
        Err(_) => 0,
    }
}

/// Frames in the repeated clips of an `rma` clip (`None` for other codecs).
fn repeated_frames(clip: &[u8]) -> Option<usize> {
    Some(mocap_encoder::codec::rma::section::inspect_clip(clip)?.repeated_frames)
}

/// The parts of a row every method fills the same way.
struct RowOf<'a> {
    source: &'a Source,
    bound: &'a Bound,
    bound_name: &'a str,
    report: &'a dyn Report,
}

impl RowOf<'_> {
    /// The row of one of our clips.
    fn clip(&self, method: Method, enc: &Encoded, encode_seconds: f64) -> Row {
        Row {
            repeated_frames: repeated_frames(&enc.bytes),
            ..self.row(
                method,
                enc.codec.name(),
                enc.metrics.clone(),
                clip_header_bytes(&enc.bytes),
                enc.key_interval,
                encode_seconds,
            )
        }
    }

    fn row(
        &self,
        method: Method,
        chosen: &str,
        mut metrics: mocap_encoder::metrics::Metrics,
        header_bytes: usize,
        key_interval: u16,
        encode_seconds: f64,
    ) -> Row {
        let s = self.source;
        let m = &s.motion;
        let values = m.frames() * m.channels();
        metrics.ratio_file = s.file_bytes as f64 / metrics.bytes.max(1) as f64;
        let without = metrics.bytes.saturating_sub(header_bytes);
        self.report.line(&format!(
            "  {} {} @ {}: {} bytes, ratio {:.1}",
            s.path.display(),
            method.name(),
            self.bound_name,
            metrics.bytes,
            metrics.ratio_f32
        ));
        Row {
            group: group_of(&s.path),
            file: s.name(),
            bound: self.bound_name.to_string(),
            codec: method.name().into(),
            chosen: chosen.into(),
            f32_bytes: values * 4,
            file_bytes: s.file_bytes,
            header_bytes,
            holds: self.bound.holds(&metrics),
            ratio_f32_without_header: (values * 4) as f64 / without.max(1) as f64,
            bits_per_value: 8.0 * without as f64 / values.max(1) as f64,
            metrics,
            key_interval,
            repeated_frames: None,
            encode_seconds,
        }
    }
}

/// `auto` from the rows of the three codecs it tries ([`encode::smallest`];
/// its time the sum of theirs), `None` while one of them is missing.
fn auto_from(ours: &[(CodecChoice, Encoded, f64)]) -> Option<Result<(Encoded, f64), EncodeError>> {
    let picked: Vec<&(CodecChoice, Encoded, f64)> = AUTO_CODECS
        .iter()
        .filter_map(|c| ours.iter().find(|o| o.0 == *c))
        .collect();
    if picked.len() < AUTO_CODECS.len() {
        return None;
    }
    let secs = picked.iter().map(|o| o.2).sum();
    Some(encode::smallest(picked.iter().map(|o| (o.0, Ok(o.1.clone())))).map(|e| (e, secs)))
}

/// Runs the bench; progress goes to stderr. `bounds` are `+`-joined specs
/// (`50mm+arms:10mm`), each one column of the table. Folders give their
/// `.bvh`, `.amc` and `.c3d` files; a C3D marker clip is coded on its
/// filled motion (missing samples filled as `mocap encode` fills them, the
/// mask in the header) and skips the angle bounds (it has no rotation
/// channels). `auto`, when the three codecs it tries are also asked for, is
/// taken from their rows (the choice [`encode::smallest`] makes) instead of
/// encoding them again.
pub fn run(
    paths: &[PathBuf],
    methods: &[Method],
    bounds: &[String],
) -> Result<Vec<Row>, BenchError> {
    run_with(paths, methods, bounds, &Stderr)
}

/// Where a bench reports as it runs.
pub trait Report {
    /// The progress of encode `at` (from 0) of about `total` (one file with
    /// one method at one bound, `label`).
    fn encode(&self, at: usize, total: usize, label: &str) -> Box<dyn encode::Progress + '_>;
    /// A finished row's line (`  file method @ bound: N bytes, ratio R`),
    /// or a note.
    fn line(&self, line: &str);
}

/// [`Report`] on stderr: each row's line, no progress.
pub struct Stderr;

impl Report for Stderr {
    fn encode(&self, _: usize, _: usize, _: &str) -> Box<dyn encode::Progress + '_> {
        Box::new(encode::Silent)
    }

    fn line(&self, line: &str) {
        eprintln!("{line}");
    }
}

/// [`run`], reporting to `report`.
pub fn run_with(
    paths: &[PathBuf],
    methods: &[Method],
    bounds: &[String],
    report: &dyn Report,
) -> Result<Vec<Row>, BenchError> {
    let specs = parse_bounds(bounds)?;
    let files = mocap_encoder::input::expand_where(paths, |p| {
        mocap_encoder::input::is_motion_file(p) || c3d::is_c3d(p)
    })?;
    let derive_auto = AUTO_CODECS
        .iter()
        .all(|c| methods.contains(&Method::Codec(*c)));
    let total = files.len() * methods.len() * specs.len();
    let mut rows = Vec::new();
    for file in &files {
        let source = Source::read(file)?;
        let needs_reference = methods.iter().any(|m| matches!(m, Method::Baseline(_)));
        let reference =
            needs_reference.then(|| Reference::new(&source.motion, source.metres_per_unit));
        let baseline_header = reference.as_ref().map_or(0, |r| source.baseline_header(r));
        // raw16 is not tuned: coded once per file, its row repeated per bound.
        let mut raw16: Option<(baseline::Coded, f64)> = None;
        for (bound, name) in specs.iter().zip(bounds) {
            if source.markers.is_some() && bound.angle_deg.is_some() {
                report.line(&format!(
                    "  {}: skipped at {name}: a marker clip has no rotation channels (give a length)",
                    file.display()
                ));
                continue;
            }
            let of = RowOf {
                source: &source,
                bound,
                bound_name: name,
                report,
            };
            let mut ours: Vec<(CodecChoice, Encoded, f64)> = Vec::new();
            for &method in methods {
                let label = format!("{} {} @ {name}", file.display(), method.name());
                let progress = report.encode(rows.len(), total, &label);
                let progress = progress.as_ref();
                match method {
                    Method::Codec(CodecChoice::Auto) if derive_auto => {
                        let (enc, secs) = match auto_from(&ours) {
                            Some(picked) => picked.map_err(|source| BenchError::Encode {
                                file: file.clone(),
                                source,
                            })?,
                            // The three codecs come later in the list.
                            None => source.encode(CodecChoice::Auto, bound, progress)?,
                        };
                        rows.push(of.clip(method, &enc, secs));
                    }
                    Method::Codec(codec) => {
                        let (enc, secs) = source.encode(codec, bound, progress)?;
                        rows.push(of.clip(method, &enc, secs));
                        ours.push((codec, enc, secs));
                    }
                    Method::Baseline(b) => {
                        let Some(reference) = reference.as_ref() else {
                            continue;
                        };
                        let (coded, secs) =
                            match (&raw16, b.tuned()) {
                                (Some(done), false) => done.clone(),
                                _ => {
                                    let t = Instant::now();
                                    let c = baseline::code(
                                        b,
                                        &source.motion,
                                        reference,
                                        bound,
                                        baseline_header,
                                    )
                                    .map_err(|source| BenchError::Baseline {
                                        file: file.clone(),
                                        source,
                                    })?;
                                    (c, t.elapsed().as_secs_f64())
                                }
                            };
                        if !b.tuned() {
                            raw16 = Some((coded.clone(), secs));
                        }
                        let row = of.row(method, b.name(), coded.metrics, baseline_header, 0, secs);
                        rows.push(row);
                    }
                }
            }
        }
    }
    Ok(rows)
}

/// Both tables: every row, then the per-folder totals ([`summary`]).
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| folder | file | codec | bound | frames×ch | bytes | ratio f32 | ratio f32 w/o header | ratio file | bits/ch/frame | ARMS mm | max mm | d % | angle RMS ° | angle max ° | foot slide mm/s (source) | foot h mm | holds | K | repeated frames | encode s |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let m = &r.metrics;
        let codec = if r.codec == r.chosen {
            r.codec.clone()
        } else {
            format!("{} ({})", r.codec, r.chosen)
        };
        s += &format!(
            "| {} | {} | {codec} | {} | {}×{} | {} | {:.2} | {:.2} | {:.1} | {:.3} | {:.2} | {:.2} | {:.2} | {:.3} | {:.3} | {} | {} | {} | {} | {} | {:.2} |\n",
            r.group, r.file, r.bound, m.frames, m.channels, m.bytes, m.ratio_f32,
            r.ratio_f32_without_header, m.ratio_file, r.bits_per_value,
            m.arms_mm, m.max_joint_err_mm, m.distortion_pct, m.angle_rms_deg, m.angle_max_deg,
            foot_slide(m.foot_pairs, m.foot_slide_mm_s, m.foot_slide_source_mm_s),
            if m.foot_pairs > 0 { format!("{:.2}", m.foot_height_err_mm) } else { "–".into() },
            if r.holds { "yes" } else { "**no**" }, r.key_interval,
            r.repeated_frames.map_or_else(|| "–".to_string(), |f| format!("{f} ({:.1} %)", 100.0 * f as f64 / m.frames.max(1) as f64)),
            r.encode_seconds
        );
    }
    s.push('\n');
    s + &summary(rows)
}

/// A foot slide cell: the decoded feet's and, in brackets, the source's
/// (mm/s); a dash when the source never plants a foot.
fn foot_slide(pairs: usize, slide: f64, source: f64) -> String {
    if pairs == 0 {
        return "–".into();
    }
    format!("{slide:.0} ({source:.0})")
}

/// Whether a row is a baseline's.
fn is_baseline(r: &Row) -> bool {
    Baseline::ALL.iter().any(|b| b.name() == r.codec)
}

/// Per folder and bound (as they first appear): the smallest total of our
/// codecs against the smallest total of the tuned baselines, with the
/// header and without it (each side's smallest without it). Empty unless
/// the rows hold both.
pub fn versus(rows: &[Row]) -> String {
    struct Total<'a> {
        codec: &'a str,
        with: usize,
        without: usize,
    }
    /// The first of the smallest: `auto` names a codec when it ties one.
    fn best<'a, 'b>(v: &[&'a Total<'b>], f: fn(&Total) -> usize) -> Option<&'a Total<'b>> {
        v.iter()
            .copied()
            .reduce(|a, t| if f(t) < f(a) { t } else { a })
    }
    let groups = summary_groups(rows);
    let totals: Vec<(&Row, Total)> = groups
        .iter()
        .filter_map(|sel| {
            let first = *sel.first()?;
            let t = Total {
                codec: &first.codec,
                with: sel.iter().map(|r| r.metrics.bytes).sum(),
                without: sel.iter().map(|r| r.bytes_without_header()).sum(),
            };
            Some((first, t))
        })
        .collect();
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for (r, _) in &totals {
        if !keys.contains(&(r.group.as_str(), r.bound.as_str())) {
            keys.push((&r.group, &r.bound));
        }
    }
    let mut s = String::new();
    for (g, b) in keys {
        let side = |baseline: bool| {
            totals
                .iter()
                .filter(|(r, _)| r.group == g && r.bound == b && is_baseline(r) == baseline)
                .filter(|(r, _)| r.codec != Baseline::Raw16.name())
                .map(|(_, t)| t)
                .collect::<Vec<_>>()
        };
        let (ours, theirs) = (side(false), side(true));
        let (Some(o), Some(t), Some(ow), Some(tw)) = (
            best(&ours, |t| t.with),
            best(&theirs, |t| t.with),
            best(&ours, |t| t.without),
            best(&theirs, |t| t.without),
        ) else {
            continue;
        };
        let more = |a: usize, b: usize| 100.0 * (a as f64 / b.max(1) as f64 - 1.0);
        s += &format!(
            "| {g} | {b} | {} {} | {} {} | {:+.1} % | {} {} | {} {} | {:+.1} % |\n",
            o.with,
            o.codec,
            t.with,
            t.codec,
            more(t.with, o.with),
            ow.without,
            ow.codec,
            tw.without,
            tw.codec,
            more(tw.without, ow.without),
        );
    }
    if s.is_empty() {
        return s;
    }
    String::from(
        "| folder | bound | ours: smallest total bytes | best baseline (not raw16) | baseline larger by | ours w/o header | best baseline w/o header | larger by |\n|---|---|---|---|---|---|---|---|\n",
    ) + &s
}

/// Per folder, bound and method (in the order they first appear): totals
/// over the folder's files. Ratios are total f32 bytes over total bytes
/// with and without the header; bits per channel per frame are without it.
pub fn summary(rows: &[Row]) -> String {
    let mut s = String::from(
        "| folder | codec | bound | files | total f32 bytes | total bytes | ratio f32 | ratio f32 w/o header | bits/ch/frame | worst ARMS mm | worst max mm | worst angle max ° | mean d % | foot slide mm/s (source) | foot h mm | bound holds | encode s |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for sel in summary_groups(rows) {
        let Some(first) = sel.first() else { continue };
        let f32b: usize = sel.iter().map(|r| r.f32_bytes).sum();
        let total: usize = sel.iter().map(|r| r.metrics.bytes).sum();
        let without: usize = sel.iter().map(|r| r.bytes_without_header()).sum();
        let worst = |f: fn(&Row) -> f64| sel.iter().map(|r| f(r)).fold(0.0, f64::max);
        let d = sel.iter().map(|r| r.metrics.distortion_pct).sum::<f64>() / sel.len() as f64;
        let secs: f64 = sel.iter().map(|r| r.encode_seconds).sum();
        let holds = sel.iter().filter(|r| r.holds).count();
        // Foot figures weighed by each file's planted foot-frames.
        let pairs: usize = sel.iter().map(|r| r.metrics.foot_pairs).sum();
        let mean = |f: fn(&Row) -> f64| {
            sel.iter()
                .map(|r| f(r) * r.metrics.foot_pairs as f64)
                .sum::<f64>()
                / pairs.max(1) as f64
        };
        let slide = foot_slide(
            pairs,
            mean(|r| r.metrics.foot_slide_mm_s),
            mean(|r| r.metrics.foot_slide_source_mm_s),
        );
        let height = if pairs > 0 {
            format!("{:.2}", mean(|r| r.metrics.foot_height_err_mm))
        } else {
            "–".into()
        };
        s += &format!(
            "| {} | {} | {} | {} | {f32b} | {total} | {:.2} | {:.2} | {:.3} | {:.2} | {:.1} | {:.3} | {d:.2} | {slide} | {height} | {holds}/{} | {secs:.2} |\n",
            first.group,
            first.codec,
            first.bound,
            sel.len(),
            f32b as f64 / total.max(1) as f64,
            f32b as f64 / without.max(1) as f64,
            8.0 * without as f64 / (f32b / 4).max(1) as f64,
            worst(|r| r.metrics.arms_mm),
            worst(|r| r.metrics.max_joint_err_mm),
            worst(|r| r.metrics.angle_max_deg),
            sel.len(),
        );
    }
    s
}

/// The rows of each (folder, bound, method), ordered by folder, bound and
/// method as they first appear.
pub fn summary_groups(rows: &[Row]) -> Vec<Vec<&Row>> {
    fn index(seen: &mut Vec<String>, v: &str) -> usize {
        seen.iter().position(|s| s == v).unwrap_or_else(|| {
            seen.push(v.to_string());
            seen.len() - 1
        })
    }
    let (mut groups, mut bounds, mut codecs) = (Vec::new(), Vec::new(), Vec::new());
    let mut keyed: Vec<((usize, usize, usize), &Row)> = rows
        .iter()
        .map(|r| {
            let k = (
                index(&mut groups, &r.group),
                index(&mut bounds, &r.bound),
                index(&mut codecs, &r.codec),
            );
            (k, r)
        })
        .collect();
    keyed.sort_by_key(|(k, _)| *k);
    let mut out: Vec<Vec<&Row>> = Vec::new();
    let mut last = None;
    for (k, r) in keyed {
        if last != Some(k) {
            out.push(Vec::new());
            last = Some(k);
        }
        if let Some(v) = out.last_mut() {
            v.push(r);
        }
    }
    out
}
