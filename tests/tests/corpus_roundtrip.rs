//! Encode → decode of every corpus file with the measured error within the
//! requested bound (measured by decoding with the `no_std` decoder and
//! independently re-measured here from the decoded clip), and the
//! `mocap view` page of every file with each encoding: it is built, holds
//! every frame and joint, and shows `mocap eval`'s figures.

use mocap_decoder::Clip;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{bvh, clipfile, fixed, metrics, units};
use mocap_report::view;
use mocap_tests::corpus_files;

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

/// Encodes every file of `folder` with `codec` at `bound` (`+`-joined
/// specs) and returns the aggregate ratio (total f32 bytes / total clip
/// bytes).
fn roundtrip(folder: &str, codec: CodecChoice, bound: &str) -> f64 {
    let Some(files) = corpus_files(folder) else {
        return f64::NAN;
    };
    assert!(!files.is_empty(), "no .bvh files in {folder}");
    let specs: Vec<BoundSpec> = bound.split('+').map(|s| s.parse().unwrap()).collect();
    let b = Bound::from_specs(&specs);
    let (mut raw, mut clips) = (0usize, 0usize);
    for file in &files {
        let m = bvh::read_file(file).unwrap();
        let unit = units::detect(&m);
        let opts = EncodeOptions {
            codec,
            bound: b,
            metres_per_unit: unit.metres(),
            key_interval: None,
        };
        let enc = encode::encode(&m, &opts).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        // Independent check: decode the bytes again, measure again.
        let clip = Clip::parse(&enc.bytes).unwrap();
        let frames = clipfile::decode_all(&clip).unwrap();
        let back = fixed::from_fixed(&m.skeleton, m.frame_time, &frames, unit.metres());
        let x = metrics::compare(&m, &back, unit.metres(), None, enc.bytes.len(), 0);
        assert_eq!(
            x,
            enc.metrics,
            "{}: encoder's own metrics differ",
            file.display()
        );
        assert!(b.holds(&x), "{} at {bound}: {x:?}", file.display());
        check_page(file, &m, &back, unit, enc.bytes.len(), &x);
        for spec in &specs {
            match *spec {
                BoundSpec::Degrees(d) => assert!(x.angle_max_deg <= d),
                BoundSpec::Millimetres(mm) => assert!(x.max_joint_err_mm <= mm),
                BoundSpec::Arms(mm) => assert!(x.arms_mm <= mm),
            }
        }
        raw += m.frames() * m.channels() * 4;
        clips += enc.bytes.len();
        eprintln!(
            "{folder}/{} {codec:?} @ {bound}: {} bytes, ratio {:.2}, angle max {:.3}°, joint max {:.2} mm, ARMS {:.2} mm",
            file.file_name().unwrap().to_string_lossy(),
            enc.bytes.len(),
            x.ratio_f32,
            x.angle_max_deg,
            x.max_joint_err_mm,
            x.arms_mm
        );
    }
    let ratio = raw as f64 / clips as f64;
    eprintln!("{folder} {codec:?} @ {bound}: aggregate ratio {ratio:.2}");
    ratio
}

#[test]
fn cmu_at_1deg() {
    roundtrip("cmu", CodecChoice::Index, "1deg");
}

#[test]
fn cmu_at_quarter_deg() {
    roundtrip("cmu", CodecChoice::Index, "0.25deg");
}

#[test]
fn cmu_at_20mm() {
    roundtrip("cmu", CodecChoice::Index, "20mm");
}

#[test]
fn iclone_at_1deg() {
    roundtrip("iclone-cmu", CodecChoice::Index, "1deg");
}

#[test]
fn iclone_at_20mm() {
    roundtrip("iclone-cmu", CodecChoice::Index, "20mm");
}

#[test]
fn pca_spline_cmu_at_50mm_and_arms_10mm() {
    // Issue 3's operating point: target 50:1, measured 50.90:1
    // (BENCHMARKS.md); the guard leaves a little room for floating-point
    // differences between machines.
    let r = roundtrip("cmu", CodecChoice::PcaSpline, "50mm+arms:10mm");
    assert!(r.is_nan() || r >= 49.0, "aggregate ratio {r:.2}");
}

#[test]
fn pca_spline_cmu_at_1deg() {
    roundtrip("cmu", CodecChoice::PcaSpline, "1deg");
}

#[test]
fn pca_spline_iclone_at_50mm_and_arms_10mm() {
    let r = roundtrip("iclone-cmu", CodecChoice::PcaSpline, "50mm+arms:10mm");
    assert!(r.is_nan() || r >= 31.0, "aggregate ratio {r:.2}");
}

#[test]
fn predictive_cmu_at_1deg() {
    roundtrip("cmu", CodecChoice::Predictive, "1deg");
}

#[test]
fn predictive_cmu_at_50mm_and_arms_10mm() {
    roundtrip("cmu", CodecChoice::Predictive, "50mm+arms:10mm");
}

#[test]
fn predictive_iclone_at_20mm() {
    roundtrip("iclone-cmu", CodecChoice::Predictive, "20mm");
}

#[test]
fn cmu_long_at_1deg() {
    roundtrip("cmu-long", CodecChoice::Index, "1deg");
}

#[test]
fn pca_spline_cmu_long_at_50mm_and_arms_10mm() {
    roundtrip("cmu-long", CodecChoice::PcaSpline, "50mm+arms:10mm");
}

#[test]
fn predictive_cmu_long_at_1deg() {
    roundtrip("cmu-long", CodecChoice::Predictive, "1deg");
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
            codec,
            bound,
            metres_per_unit: units::detect(&m).metres(),
            key_interval: None,
        };
        encode::encode(&m, &opts).unwrap()
    };
    let auto = size(CodecChoice::Auto);
    let best = size(CodecChoice::Index)
        .bytes
        .len()
        .min(size(CodecChoice::PcaSpline).bytes.len())
        .min(size(CodecChoice::Predictive).bytes.len());
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
        codec: CodecChoice::Index,
        bound: Bound::from_specs(&["1deg".parse().unwrap()]),
        metres_per_unit: units::detect(&m).metres(),
        key_interval: None,
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
