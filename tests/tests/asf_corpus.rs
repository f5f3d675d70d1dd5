//! The ASF/AMC reader on CMU's native files (corpus `asf-amc/`): forward
//! kinematics against another converter's BVH of the same take, and how
//! the conversion bakes CMU's skeleton. The round trips with every codec at
//! every bound are corpus_roundtrip.rs's (every motion file of the corpus).

use mocap_encoder::asf::{self, AmcOptions};
use mocap_encoder::motion::Motion;
use mocap_encoder::units::LengthUnit;
use mocap_encoder::{bvh, kinematics};
use mocap_tests::corpus_file;

fn read(asf_name: &str, amc_name: &str) -> Option<asf::AsfMotion> {
    let a = corpus_file("asf-amc", asf_name)?;
    let m = corpus_file("asf-amc", amc_name)?;
    Some(asf::read_files(&a, &m, &AmcOptions::default()).unwrap())
}

/// Per common joint name, the world positions in mm of every frame.
fn positions_mm(m: &Motion, mm_per_unit: f64) -> Vec<Vec<[f64; 3]>> {
    let all = kinematics::all_positions(m);
    let n = m.skeleton.joints.len();
    (0..n)
        .map(|j| {
            (0..m.frames())
                .map(|f| all[f * n + j].map(|v| v * mm_per_unit))
                .collect()
        })
        .collect()
}

/// FK joint positions of our conversion of `16.asf` + `16_15.amc` against
/// `16_15_other_converter.bvh`, the same take converted by another tool,
/// every frame and every joint both have (matched by name, End Sites
/// included: 36 of our 38 joints; the other drops `lhipjoint`/`rhipjoint`,
/// whose tips are its `lfemur`/`rfemur`).
///
/// Two differences, both the other converter's:
///
/// * its root OFFSET is frame 0's root position (6.939 97.422 −151.953 cm)
///   while its root position channels are absolute, so read as BVH (the
///   OFFSET plus the channels) its figure stands 1.806 m off, every frame:
///   the test zeroes that OFFSET;
/// * it keeps one key every 4th AMC frame (30 Hz) and fills the three frames
///   between by interpolating its own Euler channels: on the keyed frames
///   (0, 4, 8, …) every joint agrees to 0.006 mm (measured; its six
///   significant digits in cm); between them the difference is its interpolation
///   (mean ~1.5 mm over all frames; 439 mm at the left fingers in frames
///   1–3, where the AMC's left arm jumps from the dropout pose `lhumerus 0 0
///   0` to the motion within one frame and the interpolation smooths the
///   jump away).
#[test]
fn fk_matches_the_other_converter() {
    let Some(ours) = read("16.asf", "16_15.amc") else {
        return;
    };
    let Some(other) = corpus_file("asf-amc", "16_15_other_converter.bvh") else {
        return;
    };
    let mut other = bvh::read_file(&other).unwrap();
    assert_eq!(ours.declared_unit(), Some(LengthUnit::Cmu));
    assert_eq!(ours.motion.frames(), other.frames());
    // Its root OFFSET repeats frame 0's absolute root position.
    let root_offset = other.skeleton.joints[0].offset;
    assert_eq!(&other.frame(0)[..3], &root_offset[..]);
    other.skeleton.joints[0].offset = [0.0; 3];
    let a = positions_mm(&ours.motion, LengthUnit::Cmu.metres() * 1000.0);
    // The other converter writes centimetres.
    let b = positions_mm(&other, 10.0);
    // (max, sum, count) over the keyed frames and over all frames.
    let mut keyed = (0.0f64, 0.0, 0usize);
    let mut all = (0.0f64, 0.0, 0usize);
    let mut worst = (String::new(), 0usize);
    let mut joints = 0;
    for (jb, joint) in other.skeleton.joints.iter().enumerate() {
        let ja = ours
            .motion
            .skeleton
            .joints
            .iter()
            .position(|j| j.name == joint.name)
            .unwrap_or_else(|| panic!("joint {} of the other BVH not in ours", joint.name));
        joints += 1;
        for f in 0..other.frames() {
            let (p, q) = (a[ja][f], b[jb][f]);
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            if d > all.0 {
                worst = (joint.name.clone(), f);
            }
            all = (all.0.max(d), all.1 + d, all.2 + 1);
            if f % 4 == 0 {
                keyed = (keyed.0.max(d), keyed.1 + d, keyed.2 + 1);
            }
        }
    }
    let (keyed_mean, all_mean) = (keyed.1 / keyed.2 as f64, all.1 / all.2 as f64);
    eprintln!(
        "16_15 FK vs the other converter, {joints} joints: keyed frames (every 4th, {}): max {:.4} mm, mean {keyed_mean:.4} mm; all {} frames: max {:.2} mm ({} frame {}), mean {all_mean:.3} mm",
        keyed.2 / joints,
        keyed.0,
        other.frames(),
        all.0,
        worst.0,
        worst.1
    );
    assert_eq!(joints, 36);
    assert!(keyed.0 < 0.01, "keyed frames max {} mm", keyed.0);
    assert!(all_mean < 2.0, "all frames mean {all_mean} mm");
}

const TAKES: [(&str, &str); 2] = [("16.asf", "16_15.amc"), ("13.asf", "13_39.amc")];

/// The conversion's channels on CMU's skeleton, and how far its baked
/// Euler angles stay from gimbal lock; 13_39 (LF) reads like 16_15 (CRLF).
#[test]
fn channels_of_the_cmu_skeleton() {
    for (a, m) in TAKES {
        let Some(r) = read(a, m) else {
            return;
        };
        let sk = &r.motion.skeleton;
        // root + 30 bones + 7 End Sites (head, fingers, thumbs, toes).
        assert_eq!(sk.joints.len(), 38, "{m}");
        assert_eq!(sk.joints.iter().filter(|j| j.end_site).count(), 7);
        let hip = sk.joints.iter().find(|j| j.name == "lhipjoint").unwrap();
        assert!(hip.channels.is_empty() && !hip.end_site);
        eprintln!(
            "{m}: {} frames, {} channels ({} joints as their own dof, {} baked ZYX; largest |Y| {:.1}°), {} frames outside the limits",
            r.motion.frames(),
            r.motion.channels(),
            r.report.direct_joints,
            r.report.baked_joints,
            r.report.max_middle_angle_deg,
            r.frames_outside_limits()
        );
        assert!(r.report.max_middle_angle_deg < 85.0);
    }
}

/// AMC parsing speed (the ASF read once; parse only, then parse + bake):
/// `cargo test --release -p mocap-tests --test asf_corpus throughput -- --nocapture`.
#[test]
fn throughput() {
    let (Some(a), Some(m)) = (
        corpus_file("asf-amc", "16.asf"),
        corpus_file("asf-amc", "16_15.amc"),
    ) else {
        return;
    };
    let skeleton = asf::read_asf(&a).unwrap();
    let text = std::fs::read_to_string(&m).unwrap();
    let reps = 20;
    let t = std::time::Instant::now();
    for _ in 0..reps {
        std::hint::black_box(asf::parse_amc(&text, "16_15.amc", &skeleton).unwrap());
    }
    let parse = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    for _ in 0..reps {
        let amc = asf::parse_amc(&text, "16_15.amc", &skeleton).unwrap();
        std::hint::black_box(asf::bake(&skeleton, &amc, 1.0 / 120.0, "16_15.amc").unwrap());
    }
    let both = t.elapsed().as_secs_f64();
    let mb = (text.len() * reps) as f64 / 1e6;
    eprintln!(
        "AMC 16_15 ({} bytes): parse {:.0} MB/s, parse + bake {:.0} MB/s",
        text.len(),
        mb / parse,
        mb / both
    );
}
