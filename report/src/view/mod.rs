//! `mocap view`: one self-contained HTML page that plays a motion as a 3-D
//! skeleton — the source BVH and, with its `.mcb` clip, the decoded motion
//! overlaid, coloured by per-joint error, with a per-frame error strip.
//!
//! Joint positions come from the encoder's forward kinematics
//! ([`mocap_encoder::metrics::positions_mm`]); the decoded motion is the
//! clip decoded by the `no_std` decoder against its source
//! ([`mocap_encoder::clipfile::decode_against`], as `mocap eval` does), and
//! the summary and worst frame are `mocap eval`'s
//! ([`mocap_encoder::metrics::compare`]). The data is packed as [`pack`]
//! describes and embedded as JSON in a `<script type="application/json">`;
//! the page's HTML, CSS and JavaScript are the files beside this one
//! (`page.html`, `viewer.css`, `controls.html` and `player.js` — the
//! playback controls and clock — and `viewer.js`), compiled in: no server, no network. A servo clip gets
//! its own page ([`servo`]: `servo.html`, `servo.js`).
//!
//! The page exposes its state on `<body>` for tests: `data-ready="1"` once
//! drawn, `data-frame` (the frame shown), `data-playing`, `data-frames`,
//! `data-worst` (with a clip), `data-view` (the 3-D view's rectangle,
//! `x,y,w,h` in CSS pixels), `data-probe` (the last joint's unpacked
//! position at the frame shown, the decoded one's and the frame's largest
//! joint error, mm); the URL hash `#frame=worst`, `#frame=123`,
//! `&paused=1`, `&speed=2`, `&loop=0`, `&side=1` sets it on load.

pub mod pack;
pub mod servo;

pub use servo::{load_servo, load_show, ServoPage, ServoSource};

use std::path::{Path, PathBuf};

use base64::Engine as _;
use mocap_encoder::bvh::BvhError;
use mocap_encoder::clipfile::{self, SourceMismatch};
use mocap_encoder::input::InputOptions;
use mocap_encoder::metrics::{self, Metrics};
use mocap_encoder::motion::Motion;
use mocap_encoder::units::{self, LengthUnit};
use serde::Serialize;

const PAGE: &str = include_str!("page.html");
const CSS: &str = include_str!("viewer.css");
const CONTROLS: &str = include_str!("controls.html");
const JS: &str = concat!(include_str!("player.js"), include_str!("viewer.js"));
const SERVO_PAGE: &str = include_str!("servo.html");
const SERVO_JS: &str = concat!(include_str!("player.js"), include_str!("servo.js"));

/// Why a view page could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewError {
    /// A file cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The BVH file does not parse (the error names the file).
    #[error(transparent)]
    Bvh(#[from] BvhError),
    /// The source motion (BVH or ASF/AMC) does not read.
    #[error(transparent)]
    Input(#[from] mocap_encoder::input::InputError),
    /// The `.mcb` clip does not parse.
    #[error("{}: {source}", path.display())]
    Clip {
        /// The clip.
        path: PathBuf,
        /// Why.
        source: mocap_decoder::Error,
    },
    /// The clip is not an encoding of the BVH file.
    #[error("{} does not play against {}: {source}", clip.display(), bvh.display())]
    Mismatch {
        /// The clip.
        clip: PathBuf,
        /// The BVH file.
        bvh: PathBuf,
        /// What differs.
        source: SourceMismatch,
    },
    /// The motion has no frames or no joints.
    #[error("{name}: no frames to show")]
    NoFrames {
        /// The source's name.
        name: String,
    },
    /// A servo clip (or a motion clip given as one) cannot be played.
    #[error("{}: {source}", path.display())]
    Servo {
        /// The clip.
        path: PathBuf,
        /// Why.
        source: mocap_encoder::play::PlayError,
    },
    /// A clip given as a servo clip is a motion clip.
    #[error("{}: not a servo clip (give its source BVH first to view a motion clip)", path.display())]
    NotServo {
        /// The clip.
        path: PathBuf,
    },
    /// The rig file does not read, or does not fit the source BVH (the
    /// error names the file).
    #[error(transparent)]
    Rig(Box<mocap_encoder::rig::RigError>),
    /// A show's command script does not parse (the error names the file
    /// and line).
    #[error(transparent)]
    Script(mocap_encoder::located::LocatedError),
    /// A servo clip is not an encoding of this rig and source.
    #[error("{} does not play against {}: {what}", clip.display(), rig.display())]
    ServoMismatch {
        /// The clip.
        clip: PathBuf,
        /// The rig file.
        rig: PathBuf,
        /// What differs.
        what: String,
    },
    /// A joint moves too far in one frame to pack (more than 3.2 km).
    #[error("{name}: a joint moves more than 3.2 km between frames or from its decoded position")]
    TooFar {
        /// The source's name.
        name: String,
    },
}

/// A page and what it shows.
#[derive(Clone, Debug)]
pub struct Page {
    /// The whole HTML file.
    pub html: String,
    /// Frames.
    pub frames: usize,
    /// Joints, End Sites included.
    pub joints: usize,
    /// Millimetres per position step in the page ([`pack`]).
    pub quantum_mm: f64,
    /// With a clip: `mocap eval`'s measures (the worst frame is
    /// `max_joint_err_frame`).
    pub metrics: Option<Metrics>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct JointData<'a> {
    name: &'a str,
    parent: Option<usize>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct PageData<'a> {
    format: u32,
    source: &'a str,
    clip: Option<&'a str>,
    unit: &'a str,
    frames: usize,
    frame_time: f64,
    joints: Vec<JointData<'a>>,
    quantum_mm: f64,
    first: &'a [i64],
    deltas: &'a str,
    residuals: Option<&'a str>,
    error_quantum_mm: f64,
    errors: Option<&'a str>,
    worst_frame: Option<usize>,
    metrics: Option<&'a Metrics>,
    /// Marker clips: one bit per (frame, joint), frame-major, LSB first,
    /// base64 — the samples the source does not have (drawn hollow, never
    /// as data: the positions there are the encoder's fill).
    missing: Option<String>,
    missing_count: usize,
}

/// Reads `bvh` (units `unit`, or detected from its height), decodes `clip`
/// against it when given, and builds the page.
pub fn load(bvh: &Path, clip: Option<&Path>, unit: Option<LengthUnit>) -> Result<Page, ViewError> {
    load_with(bvh, clip, unit, &InputOptions::default())
}

/// [`load`] of any motion source ([`mocap_encoder::input`]: BVH, or AMC
/// with its ASF as `input` says); units `unit`, else the one the source
/// declares, else detected from its height.
pub fn load_with(
    bvh: &Path,
    clip: Option<&Path>,
    unit: Option<LengthUnit>,
    input: &InputOptions,
) -> Result<Page, ViewError> {
    let read = mocap_encoder::input::read_motion_with(bvh, input)?;
    let unit = unit
        .or(read.unit)
        .unwrap_or_else(|| units::detect(&read.motion));
    let m = read.motion;
    let read = |path: &Path| {
        std::fs::read(path).map_err(|source| ViewError::Read {
            path: path.to_path_buf(),
            source,
        })
    };
    let source_bytes = read(bvh)?.len();
    let decoded = match clip {
        Some(path) => {
            let bytes = read(path)?;
            let c = mocap_decoder::Clip::parse(&bytes).map_err(|source| ViewError::Clip {
                path: path.to_path_buf(),
                source,
            })?;
            let back = clipfile::decode_against(&c, &m, unit.metres()).map_err(|source| {
                ViewError::Mismatch {
                    clip: path.to_path_buf(),
                    bvh: bvh.to_path_buf(),
                    source,
                }
            })?;
            Some((back, bytes.len()))
        }
        None => None,
    };
    let (source_name, clip_name) = (file_name(bvh), clip.map(file_name));
    let names = Names {
        source: &source_name,
        clip: clip_name.as_deref(),
        source_bytes,
    };
    page(&m, unit, decoded.as_ref().map(|(b, n)| (b, *n)), &names)
}

/// The name a page shows for `p`: its file name (the whole path if it has none).
pub fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The names a page shows and the source's size in bytes (for the
/// ratio of `mocap eval`).
#[derive(Clone, Copy, Debug)]
pub struct Names<'a> {
    /// The source's file name.
    pub source: &'a str,
    /// The clip's file name.
    pub clip: Option<&'a str>,
    /// The source file's bytes.
    pub source_bytes: usize,
}

/// The page of `original` (lengths in `unit`) and, optionally, its decoded
/// version with the clip's size in bytes (same skeleton and frames, as
/// [`clipfile::decode_against`] returns it). Errors name the source by
/// `names.source`.
pub fn page(
    original: &Motion,
    unit: LengthUnit,
    decoded: Option<(&Motion, usize)>,
    names: &Names<'_>,
) -> Result<Page, ViewError> {
    page_with_missing(original, unit, decoded, names, None)
}

/// [`page`] of a marker clip: `original` is the filled motion
/// ([`mocap_encoder::markers::fill`]) and `missing` says which of its
/// samples the source lacks; the page draws those hollow and leaves out
/// the bones to them, so no invented sample passes for data.
pub fn page_with_missing(
    original: &Motion,
    unit: LengthUnit,
    decoded: Option<(&Motion, usize)>,
    names: &Names<'_>,
    missing: Option<&mocap_encoder::markers::MissingMask>,
) -> Result<Page, ViewError> {
    let frames = original.frames();
    let joints = original.skeleton.joints.len();
    let name = || names.source.to_string();
    if frames == 0 || joints == 0 {
        return Err(ViewError::NoFrames { name: name() });
    }
    let mpu = unit.metres();
    let source = metrics::Source::of(original, mpu);
    let a = &source.positions;
    let b = decoded.map(|(d, _)| metrics::positions_mm(d, mpu));
    let packed = pack::pack_positions(a, b.as_deref(), joints)
        .ok_or_else(|| ViewError::TooFar { name: name() })?;
    let errors: Option<Vec<f64>> = b.as_ref().map(|b| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
            .collect()
    });
    let packed_errors = errors.as_deref().map(pack::pack_errors);
    let metrics = decoded.map(|(d, bytes)| {
        metrics::compare(original, d, mpu, Some(&source), bytes, names.source_bytes)
    });
    let data = PageData {
        format: 1,
        source: names.source,
        clip: names.clip,
        unit: unit.name(),
        frames,
        frame_time: original.frame_time,
        joints: original
            .skeleton
            .joints
            .iter()
            .map(|j| JointData {
                name: &j.name,
                parent: j.parent,
            })
            .collect(),
        quantum_mm: packed.quantum_mm,
        first: &packed.first,
        deltas: &packed.deltas,
        residuals: packed.residuals.as_deref(),
        error_quantum_mm: packed_errors.as_ref().map_or(0.0, |e| e.0),
        errors: packed_errors.as_ref().map(|e| e.1.as_str()),
        worst_frame: metrics.as_ref().map(|m| m.max_joint_err_frame),
        metrics: metrics.as_ref(),
        missing: missing.map(|mask| {
            let mut bits = vec![0u8; (frames * joints).div_ceil(8)];
            for f in 0..frames {
                for j in 0..joints {
                    if mask.is_missing(f, j) {
                        let i = f * joints + j;
                        bits[i / 8] |= 1 << (i % 8);
                    }
                }
            }
            base64::engine::general_purpose::STANDARD.encode(bits)
        }),
        missing_count: missing.map_or(0, |mask| mask.count()),
    };
    let json = serde_json::to_string(&data).expect("page data serialises");
    let title = match names.clip {
        Some(c) => format!("{} + {c}", names.source),
        None => names.source.to_string(),
    };
    Ok(Page {
        html: fill(PAGE, JS, &title, &json),
        frames,
        joints,
        quantum_mm: packed.quantum_mm,
        metrics,
    })
}

/// A page template (`page.html`, `servo.html`) with its title, the shared
/// style and playback controls (`controls.html`, driven by `player.js`), its
/// data and its script in place. In the JSON every `<` becomes
/// `\u003c`, so no name in it can end the script element.
fn fill(page: &str, js: &str, title: &str, json: &str) -> String {
    let title = title
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    let json = json.replace('<', "\\u003c");
    let mut out = String::with_capacity(page.len() + CSS.len() + js.len() + json.len());
    let mut rest = page;
    for (marker, value) in [
        ("{{TITLE}}", title.as_str()),
        ("{{CSS}}", CSS),
        ("{{CONTROLS}}", CONTROLS),
        ("{{DATA}}", json.as_str()),
        ("{{JS}}", js),
    ] {
        let (before, after) = rest
            .split_once(marker)
            .unwrap_or_else(|| panic!("a page template lacks {marker} (in this order)"));
        out.push_str(before);
        out.push_str(value);
        rest = after;
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_template_takes_every_part_once_and_escapes_names() {
        for (page, js) in [(PAGE, JS), (SERVO_PAGE, SERVO_JS)] {
            let html = fill(page, js, "a<b>&c", r#"{"name":"</script><!--"}"#);
            assert!(html.contains("<title>a&lt;b&gt;&amp;c</title>"));
            assert!(html.contains(r#"{"name":"\u003c/script>\u003c!--"}"#));
            for marker in ["{{TITLE}}", "{{CSS}}", "{{CONTROLS}}", "{{DATA}}", "{{JS}}"] {
                assert!(!html.contains(marker), "{marker}");
            }
            assert_eq!(html.matches("</script>").count(), 2);
        }
    }

    #[test]
    fn the_demo_page_holds_its_frames_and_worst_frame() {
        let m = mocap_encoder::generate::animatronic_demo();
        let unit = units::detect(&m);
        // A decoded version that is the original moved 3 mm up at frame 7.
        let mut d = m.clone();
        let root_y = m.skeleton.joints[0]
            .channels
            .iter()
            .position(|c| *c == mocap_encoder::motion::ChannelKind::Yposition)
            .unwrap();
        let c = m.channels();
        d.values[7 * c + root_y] += 0.003 / unit.metres();
        let names = Names {
            source: "demo.bvh",
            clip: Some("demo.mcb"),
            source_bytes: 1,
        };
        let p = page(&m, unit, Some((&d, 100)), &names).unwrap();
        assert_eq!(p.frames, m.frames());
        let x = p.metrics.unwrap();
        assert_eq!(x.max_joint_err_frame, 7);
        assert!((x.max_joint_err_mm - 3.0).abs() < 1e-6);
        assert!(p.html.contains("\"worstFrame\":7"));
        assert!(p.html.len() < 200_000, "{}", p.html.len());
    }
}
