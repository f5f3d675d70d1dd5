//! Long inputs (issue 15): clips of any length made by `generate::long_take`
//! encode within their bound, and the bytes do not depend on the number of
//! threads the encoder runs on. Timings are reported by
//! `scripts/scaling.sh`, never asserted here.

use mocap_decoder::Clip;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::generate::{self, LongOptions};
use mocap_encoder::motion::Motion;
use mocap_encoder::{bvh, clipfile, fixed, metrics, units};
use mocap_tests::corpus_file;

fn options(codec: CodecChoice, bound: &str, m: &Motion) -> (EncodeOptions, Vec<BoundSpec>) {
    let specs: Vec<BoundSpec> = bound.split('+').map(|s| s.parse().unwrap()).collect();
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound::from_specs(&specs),
        metres_per_unit: units::detect(m).metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    (opts, specs)
}

/// Encodes, decodes with the `no_std` decoder and checks every bound
/// independently of the encoder's own measurement.
fn within_bound(name: &str, m: &Motion, codec: CodecChoice, bound: &str) {
    let (opts, specs) = options(codec, bound, m);
    let enc = encode::encode(m, &opts).unwrap_or_else(|e| panic!("{name} {codec:?}: {e}"));
    let clip = Clip::parse(&enc.bytes).unwrap();
    let frames = clipfile::decode_all(&clip).unwrap();
    assert_eq!(frames.len(), m.frames() * m.channels());
    let mpu = opts.metres_per_unit;
    let back = fixed::from_fixed(&m.skeleton, m.frame_time, &frames, mpu);
    let x = metrics::compare(m, &back, mpu, None, enc.bytes.len(), 0);
    assert_eq!(x, enc.metrics, "{name}: the encoder's own metrics differ");
    for spec in &specs {
        match *spec {
            BoundSpec::Degrees(d) => assert!(x.angle_max_deg <= d, "{name}: {x:?}"),
            BoundSpec::Millimetres(mm) => assert!(x.max_joint_err_mm <= mm, "{name}: {x:?}"),
            BoundSpec::Arms(mm) => assert!(x.arms_mm <= mm, "{name}: {x:?}"),
            BoundSpec::Slide(v) => assert!(
                x.foot_slide_mm_s - x.foot_slide_source_mm_s <= v,
                "{name}: {x:?}"
            ),
        }
    }
    eprintln!(
        "{name} {codec:?} @ {bound}: {} frames, {} bytes, ratio {:.1}, joint max {:.2} mm, ARMS {:.2} mm, angle max {:.3}°",
        m.frames(),
        enc.bytes.len(),
        x.ratio_f32,
        x.max_joint_err_mm,
        x.arms_mm,
        x.angle_max_deg
    );
}

fn walk(frames: usize, fps: Option<f64>) -> Option<Motion> {
    let take = bvh::read_file(&corpus_file("cmu", "35_01.bvh")?).unwrap();
    let opts = LongOptions {
        skip: 1,
        fps,
        ..LongOptions::new(frames)
    };
    Some(generate::long_take(&take, &opts).unwrap())
}

/// 35_01 (a steady walk of 3 s) walked on for 5 000 frames: no change of
/// behaviour for PPCA to cut at, and the root travels tens of metres (one
/// segment over it put root coefficients out of the format's range).
#[test]
fn pca_spline_encodes_a_long_walk_within_the_bound() {
    let Some(m) = walk(5000, None) else {
        return;
    };
    within_bound("35_01 × 5000", &m, CodecChoice::PcaSpline, "50mm+arms:10mm");
}

/// The user's shape: a walk of 7 134 frames at 30 Hz.
#[test]
fn a_30_hz_walk_encodes_with_pca_spline_and_predictive() {
    let Some(m) = walk(7134, Some(30.0)) else {
        return;
    };
    within_bound(
        "35_01 30 Hz × 7134",
        &m,
        CodecChoice::PcaSpline,
        "50mm+arms:10mm",
    );
    within_bound("35_01 30 Hz × 7134", &m, CodecChoice::Predictive, "1deg");
}

/// The shipped demo walked on (no corpus needed), encoded on one thread and
/// on three: the same bytes.
#[test]
fn bytes_do_not_depend_on_the_thread_count() {
    let demo = generate::animatronic_demo();
    let m = generate::long_take(&demo, &LongOptions::new(2000)).unwrap();
    for (codec, bound) in [
        (CodecChoice::PcaSpline, "50mm+arms:10mm"),
        (CodecChoice::PcaSpline, "1deg"),
        (CodecChoice::Predictive, "20mm"),
    ] {
        let (opts, _) = options(codec, bound, &m);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| encode::encode(&m, &opts).unwrap().bytes)
        };
        let one = on(1);
        assert_eq!(one, on(3), "{codec:?} @ {bound}");
        eprintln!(
            "{codec:?} @ {bound}: {} bytes on 1 and 3 threads",
            one.len()
        );
    }
}
