//! Encode → decode of every motion file of the corpus with every codec at
//! 1°, 20 mm and 50 mm + ARMS 10 mm (issue 15's "every file under the
//! corpus encodes with every codec within its bound"), with the measured
//! error within the requested bound (measured by decoding with the `no_std` decoder and
//! independently re-measured here from the decoded clip), and the
//! `mocap view` page of every file with each encoding: it is built, holds
//! every frame and joint, and shows `mocap eval`'s figures.

use mocap_decoder::Clip;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{bvh, clipfile, fixed, input, metrics, units};
use mocap_report::view;
use mocap_tests::{corpus_dir, corpus_files, corpus_tree};
use std::collections::BTreeMap;
use std::path::Path;

/// The largest page per second of motion and per joint: the issue's
/// 2 MB for 10 s of the 31-joint CMU skeleton at 120 Hz with its decoded
/// version (05_04's page is 0.87 MB, BENCHMARKS.md / README).
const PAGE_BYTES_PER_JOINT_SECOND: f64 = 2_000_000.0 / (10.0 * 31.0);

/// The view page of `m` and its decoded version `back` (clip of `bytes`
/// bytes, measured as `x`): built without error, every frame and joint in
/// it, the metrics `mocap eval` prints, within the size budget.
fn check_page(
    file: &std::path::Path,
    m: &mocap_encoder::motion::Motion,
    back: &mocap_encoder::motion::Motion,
    unit: units::LengthUnit,
    bytes: usize,
    x: &metrics::Metrics,
) {
    let source_bytes = std::fs::metadata(file).unwrap().len() as usize;
    let name = file.file_name().unwrap().to_string_lossy();
    let names = view::Names {
        source: &name,
        clip: Some("clip.mcb"),
        source_bytes,
    };
    let page = view::page(m, unit, Some((back, bytes)), &names)
        .unwrap_or_else(|e| panic!("{}: mocap view: {e}", file.display()));
    assert_eq!(page.frames, m.frames(), "{}", file.display());
    assert_eq!(page.joints, m.skeleton.joints.len(), "{}", file.display());
    let shown = page.metrics.as_ref().unwrap();
    // The page's measures are eval's (with the ratio to the source file).
    let same = metrics::Metrics {
        ratio_file: x.ratio_file,
        ..shown.clone()
    };
    assert_eq!(&same, x, "{}: the page's figures", file.display());
    assert!(shown.ratio_file > 0.0);
    let seconds = m.frames() as f64 * m.frame_time;
    let budget = PAGE_BYTES_PER_JOINT_SECOND * seconds.max(1.0) * page.joints as f64;
    assert!(
        (page.html.len() as f64) < budget,
        "{}: page of {} bytes over {budget:.0}",
        file.display(),
        page.html.len()
    );
}

/// Encodes one motion file (BVH, or AMC with its ASF) with `codec` at
/// `bound` (`+`-joined specs), decodes the bytes with the `no_std` decoder,
/// measures again independently and checks the bound and the view page;
/// returns (f32 bytes, clip bytes).
fn roundtrip_file(file: &Path, codec: CodecChoice, bound: &str) -> (usize, usize) {
    let specs: Vec<BoundSpec> = bound.split('+').map(|s| s.parse().unwrap()).collect();
    let b = Bound::from_specs(&specs);
    let read = input::read_motion(file, None).unwrap_or_else(|e| panic!("{e}"));
    let m = &read.motion;
    let unit = read.unit_or_detect();
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: b,
        metres_per_unit: unit.metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    let enc = encode::encode(m, &opts).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    // Independent check: decode the bytes again, measure again.
    let clip = Clip::parse(&enc.bytes).unwrap();
    let frames = clipfile::decode_all(&clip).unwrap();
    let back = fixed::from_fixed(&m.skeleton, m.frame_time, &frames, unit.metres());
    let x = metrics::compare(m, &back, unit.metres(), None, enc.bytes.len(), 0);
    assert_eq!(
        x,
        enc.metrics,
        "{}: encoder's own metrics differ",
        file.display()
    );
    assert!(b.holds(&x), "{} at {bound}: {x:?}", file.display());
    for spec in &specs {
        match *spec {
            BoundSpec::Degrees(d) => assert!(x.angle_max_deg <= d, "{}", file.display()),
            BoundSpec::Millimetres(mm) => assert!(x.max_joint_err_mm <= mm, "{}", file.display()),
            BoundSpec::Arms(mm) => assert!(x.arms_mm <= mm, "{}", file.display()),
            BoundSpec::Slide(v) => assert!(
                x.foot_slide_mm_s - x.foot_slide_source_mm_s <= v,
                "{}",
                file.display()
            ),
        }
    }
    // The clip plays against its source: same joints and channels.
    clipfile::decode_against(&clip, m, unit.metres()).unwrap();
    check_page(file, m, &back, unit, enc.bytes.len(), &x);
    eprintln!(
        "{} {codec:?} @ {bound}: {} frames × {} channels, {} bytes, ratio {:.2}, angle max {:.3}°, joint max {:.2} mm, ARMS {:.2} mm",
        file.display(),
        m.frames(),
        m.channels(),
        enc.bytes.len(),
        x.ratio_f32,
        x.angle_max_deg,
        x.max_joint_err_mm,
        x.arms_mm
    );
    (m.frames() * m.channels() * 4, enc.bytes.len())
}

/// Encodes every motion file under the corpus (every folder, recursively:
/// `.bvh`, and `.amc` with its `.asf`; the C3D marker files are
/// c3d_corpus.rs's) with `codec` at `bound`; returns each folder's
/// aggregate ratio (total f32 bytes / total clip bytes), or `None` without
/// the corpus (a visible skip).
fn every_motion_file(codec: CodecChoice, bound: &str) -> Option<BTreeMap<String, f64>> {
    let root = corpus_dir();
    let files: Vec<_> = corpus_tree()?
        .into_iter()
        .filter(|p| input::is_motion_file(p))
        .collect();
    assert!(
        files.len() >= 25,
        "{} motion files under {}",
        files.len(),
        root.display()
    );
    let mut folders: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    for file in &files {
        let (raw, clip) = roundtrip_file(file, codec, bound);
        let folder = file
            .parent()
            .and_then(|d| d.strip_prefix(&root).ok())
            .map_or_else(String::new, |d| d.display().to_string());
        let e = folders.entry(folder).or_default();
        e.0 += raw;
        e.1 += clip;
    }
    let ratios: BTreeMap<String, f64> = folders
        .into_iter()
        .map(|(f, (raw, clip))| (f, raw as f64 / clip as f64))
        .collect();
    eprintln!(
        "{codec:?} @ {bound}: {} files, aggregate ratio per folder {ratios:.2?}",
        files.len()
    );
    Some(ratios)
}

#[test]
fn index_every_file_at_1deg() {
    every_motion_file(CodecChoice::Index, "1deg");
}

#[test]
fn index_every_file_at_20mm() {
    every_motion_file(CodecChoice::Index, "20mm");
}

#[test]
fn index_every_file_at_50mm_and_arms_10mm() {
    every_motion_file(CodecChoice::Index, "50mm+arms:10mm");
}

#[test]
fn index_cmu_at_quarter_deg() {
    let Some(files) = corpus_files("cmu") else {
        return;
    };
    for file in &files {
        roundtrip_file(file, CodecChoice::Index, "0.25deg");
    }
}

#[test]
fn pca_spline_every_file_at_1deg() {
    every_motion_file(CodecChoice::PcaSpline, "1deg");
}

#[test]
fn pca_spline_every_file_at_20mm() {
    every_motion_file(CodecChoice::PcaSpline, "20mm");
}

#[test]
fn pca_spline_every_file_at_50mm_and_arms_10mm() {
    let Some(r) = every_motion_file(CodecChoice::PcaSpline, "50mm+arms:10mm") else {
        return;
    };
    // Issue 3's operating point: target 50:1 on cmu/, measured 50.90:1
    // (BENCHMARKS.md); the guards leave a little room for floating-point
    // differences between machines.
    assert!(r["cmu"] >= 49.0, "cmu aggregate ratio {:.2}", r["cmu"]);
    assert!(
        r["iclone-cmu"] >= 31.0,
        "iclone-cmu aggregate ratio {:.2}",
        r["iclone-cmu"]
    );
}

#[test]
fn predictive_every_file_at_1deg() {
    every_motion_file(CodecChoice::Predictive, "1deg");
}

#[test]
fn predictive_every_file_at_20mm() {
    every_motion_file(CodecChoice::Predictive, "20mm");
}

#[test]
fn predictive_every_file_at_50mm_and_arms_10mm() {
    every_motion_file(CodecChoice::Predictive, "50mm+arms:10mm");
}

#[test]
fn pattern_every_file_at_1deg() {
    every_motion_file(CodecChoice::Pattern, "1deg");
}

#[test]
fn pattern_every_file_at_50mm_and_arms_10mm() {
    every_motion_file(CodecChoice::Pattern, "50mm+arms:10mm");
}

#[test]
fn rma_every_file_at_50mm_and_arms_10mm() {
    every_motion_file(CodecChoice::Rma, "50mm+arms:10mm");
}

/// A foot-slide bound on a walk (cmu/35_01): `predictive` slides the feet
/// most at 50 mm + ARMS 10 mm; with `slide:100mm/s` on top the clip is
/// proven within it (checked again here from the decoded clip), and it
/// costs bytes.
#[test]
fn a_slide_bound_keeps_the_feet_planted() {
    let Some(file) = mocap_tests::corpus_file("cmu", "35_01.bvh") else {
        return;
    };
    // Without the slide bound (its round trip is predictive_every_file's).
    let m = bvh::read_file(&file).unwrap();
    let opts = EncodeOptions {
        key_bits: None,
        codec: CodecChoice::Predictive,
        bound: Bound::from_specs(&["50mm".parse().unwrap(), "arms:10mm".parse().unwrap()]),
        metres_per_unit: units::detect(&m).metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    let free = encode::encode(&m, &opts).unwrap();
    let plain = free.bytes.len();
    let free = free.metrics;
    assert!(free.foot_pairs > 100, "a walk plants its feet: {free:?}");
    assert!(
        free.foot_slide_mm_s - free.foot_slide_source_mm_s > 100.0,
        "without the bound the feet slide more: {free:?}"
    );
    let (_, held) = roundtrip_file(
        &file,
        CodecChoice::Predictive,
        "50mm+arms:10mm+slide:100mm/s",
    );
    assert!(
        held > plain,
        "keeping the feet costs bytes: {held} vs {plain}"
    );
}

#[test]
fn auto_picks_the_smaller_codec() {
    let Some(files) = corpus_files("cmu") else {
        return;
    };
    let m = bvh::read_file(&files[0]).unwrap();
    let bound = Bound::from_specs(&["50mm".parse().unwrap()]);
    let size = |codec| {
        let opts = EncodeOptions {
            key_bits: None,
            codec,
            bound,
            metres_per_unit: units::detect(&m).metres(),
            key_interval: None,
            index_layout: Default::default(),
            pattern: Default::default(),
        };
        encode::encode(&m, &opts).unwrap()
    };
    let auto = size(CodecChoice::Auto);
    let best = size(CodecChoice::Index)
        .bytes
        .len()
        .min(size(CodecChoice::PcaSpline).bytes.len())
        .min(size(CodecChoice::Predictive).bytes.len())
        .min(size(CodecChoice::Pattern).bytes.len())
        .min(size(CodecChoice::Rma).bytes.len());
    assert_eq!(auto.bytes.len(), best);
    assert_ne!(auto.codec, CodecChoice::Auto);
}

#[test]
fn index_35_01_reaches_ratio_6_at_1deg() {
    let Some(files) = corpus_files("cmu") else {
        return;
    };
    let Some(f) = files.iter().find(|p| p.ends_with("35_01.bvh")) else {
        panic!("35_01.bvh missing from the corpus");
    };
    let m = bvh::read_file(f).unwrap();
    let opts = EncodeOptions {
        key_bits: None,
        codec: CodecChoice::Index,
        bound: Bound::from_specs(&["1deg".parse().unwrap()]),
        metres_per_unit: units::detect(&m).metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    let enc = encode::encode(&m, &opts).unwrap();
    eprintln!("35_01 @ 1deg: {:?}", enc.metrics);
    assert!(enc.metrics.angle_max_deg <= 1.0);
    assert!(
        enc.metrics.ratio_f32 >= 6.0,
        "ratio {}",
        enc.metrics.ratio_f32
    );
}
