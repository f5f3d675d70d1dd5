//! The BVH reader, forward kinematics and unit detection on the real
//! motion-capture corpus described in the corpus README (`cmu/` and
//! `iclone-cmu/`).
//!
//! The corpus is found through the `MOCAP_CORPUS` environment variable (a
//! relative path is taken relative to the workspace root), by default
//! `../shared/data` next to the workspace. When it is missing every test
//! prints `SKIPPED: …` to stderr and returns.

use mocap_encoder::motion::{ChannelKind, Motion};
use mocap_encoder::{bvh, kinematics, units};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// cmu/: file, frames (all: 31 joints, 96 channels, 120 Hz).
const CMU: [(&str, usize); 6] = [
    ("35_01.bvh", 359),
    ("35_17.bvh", 168),
    ("16_07.bvh", 423),
    ("06_05.bvh", 386),
    ("09_01.bvh", 149),
    ("05_04.bvh", 1200),
];

/// iclone-cmu/: file, root, joints (End Sites excluded), channels, frames.
const ICLONE: [(&str, &str, usize, usize, usize); 16] = [
    ("002_01.bvh", "RL_BoneRoot", 101, 306, 171),
    ("002_02.bvh", "RL_BoneRoot", 101, 306, 148),
    ("002_03.bvh", "RL_BoneRoot", 101, 306, 86),
    ("002_04.bvh", "CC_Base_Hip", 100, 303, 241),
    ("002_09.bvh", "CC_Base_Hip", 100, 303, 517),
    ("005_01.bvh", "CC_Base_Hip", 100, 303, 299),
    ("005_03.bvh", "CC_Base_Hip", 100, 303, 216),
    ("005_11.bvh", "CC_Base_Hip", 100, 303, 296),
    ("006_01.bvh", "CC_Base_Hip", 100, 303, 246),
    ("006_05.bvh", "CC_Base_Hip", 100, 303, 192),
    ("006_14.bvh", "CC_Base_Hip", 100, 303, 239),
    ("007_01.bvh", "RL_BoneRoot", 101, 306, 157),
    ("007_02.bvh", "CC_Base_Hip", 100, 303, 164),
    ("007_03.bvh", "CC_Base_Hip", 100, 303, 208),
    ("007_08.bvh", "CC_Base_Hip", 100, 303, 181),
    ("007_12.bvh", "CC_Base_Hip", 100, 303, 132),
];

/// The corpus folder, or `None` (after a visible SKIPPED line) if absent.
fn corpus() -> Option<PathBuf> {
    let dir = mocap_tests::corpus_dir();
    if dir.is_dir() {
        Some(dir.canonicalize().unwrap_or(dir))
    } else {
        mocap_tests::corpus_files("cmu").map(|_| dir)
    }
}

/// Every `.bvh` file of a corpus subfolder, sorted; the subfolder must exist.
fn bvh_files(corpus: &Path, sub: &str) -> Vec<PathBuf> {
    let dir = corpus.join(sub);
    let entries = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("corpus at {} has no {sub}/: {e}", corpus.display()));
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("bvh")))
        .collect();
    files.sort();
    files
}

fn read(path: &Path) -> Motion {
    bvh::read_file(path).unwrap_or_else(|e| panic!("{e}"))
}

fn joint_index(m: &Motion, name: &str) -> usize {
    m.skeleton
        .joints
        .iter()
        .position(|j| j.name == name)
        .unwrap_or_else(|| panic!("no joint {name}"))
}

/// Non-End-Site joints.
fn real_joints(m: &Motion) -> usize {
    m.skeleton.joints.iter().filter(|j| !j.end_site).count()
}

/// Lowest Y of any foot or toe joint (End Sites included).
fn lowest_foot_y(m: &Motion, pos: &[[f64; 3]]) -> f64 {
    m.skeleton
        .joints
        .iter()
        .zip(pos)
        .filter(|(j, _)| j.name.contains("Foot") || j.name.contains("Toe"))
        .map(|(_, p)| p[1])
        .fold(f64::INFINITY, f64::min)
}

fn check_structure(m: &Motion, name: &str) {
    for (i, j) in m.skeleton.joints.iter().enumerate() {
        if let Some(p) = j.parent {
            assert!(p < i, "{name}: {} comes before its parent", j.name);
        }
        if j.end_site {
            assert!(j.channels.is_empty(), "{name}: End Site with channels");
            assert!(
                j.name.ends_with("_End"),
                "{name}: End Site named {}",
                j.name
            );
        }
    }
    assert!(m.values.iter().all(|v| v.is_finite()));
    assert_eq!(m.values.len(), m.frames() * m.channels());
}

#[test]
fn cmu_files_match_the_readme() {
    let Some(corpus) = corpus() else { return };
    let files = bvh_files(&corpus, "cmu");
    for (file, _) in CMU {
        assert!(
            files.iter().any(|p| p.ends_with(file)),
            "cmu/{file} is missing"
        );
    }
    let mut names: Option<Vec<String>> = None;
    for path in &files {
        let m = read(path);
        let file = path.file_name().and_then(|f| f.to_str()).unwrap_or("?");
        check_structure(&m, file);
        assert_eq!(real_joints(&m), 31, "{file}: joints");
        assert_eq!(m.channels(), 96, "{file}: channels");
        assert!(
            (m.frame_time - 0.0083333).abs() < 1e-9,
            "{file}: frame time"
        );
        let root = &m.skeleton.joints[0];
        assert_eq!(root.name, "Hips");
        assert_eq!(root.channels.len(), 6);
        use ChannelKind::*;
        for j in m.skeleton.joints.iter().skip(1).filter(|j| !j.end_site) {
            assert_eq!(
                j.channels,
                [Zrotation, Yrotation, Xrotation],
                "{file}: {}",
                j.name
            );
        }
        if let Some(&(_, frames)) = CMU.iter().find(|(f, _)| *f == file) {
            assert_eq!(m.frames(), frames, "{file}: frames");
        }
        assert_eq!(units::detect(&m), units::LengthUnit::Cmu, "{file}: unit");
        // All files share the same joint names and order.
        let these: Vec<String> = m.skeleton.joints.iter().map(|j| j.name.clone()).collect();
        match &names {
            None => names = Some(these),
            Some(first) => assert_eq!(first, &these, "{file}: joint names"),
        }
    }
}

#[test]
fn iclone_files_match_the_readme() {
    let Some(corpus) = corpus() else { return };
    let files = bvh_files(&corpus, "iclone-cmu");
    for (file, ..) in ICLONE {
        assert!(
            files.iter().any(|p| p.ends_with(file)),
            "iclone-cmu/{file} is missing"
        );
    }
    for path in &files {
        let m = read(path);
        let file = path.file_name().and_then(|f| f.to_str()).unwrap_or("?");
        check_structure(&m, file);
        assert!(
            matches!(m.channels(), 303 | 306),
            "{file}: {} channels",
            m.channels()
        );
        assert!((m.frame_time - 0.016667).abs() < 1e-9, "{file}: frame time");
        if let Some(&(_, root, joints, channels, frames)) = ICLONE.iter().find(|(f, ..)| *f == file)
        {
            assert_eq!(m.skeleton.joints[0].name, root, "{file}: root");
            assert_eq!(real_joints(&m), joints, "{file}: joints");
            assert_eq!(m.channels(), channels, "{file}: channels");
            assert_eq!(m.frames(), frames, "{file}: frames");
        }
        assert_eq!(units::detect(&m), units::LengthUnit::Cm, "{file}: unit");
    }
}

#[test]
fn cmu_hips_stand_17_units_above_the_feet() {
    let Some(corpus) = corpus() else { return };
    let mut pos = Vec::new();
    for path in bvh_files(&corpus, "cmu") {
        let m = read(&path);
        kinematics::joint_positions(&m.skeleton, m.frame(0), &mut pos);
        let hips = pos[joint_index(&m, "Hips")][1];
        let above = hips - lowest_foot_y(&m, &pos);
        assert!(
            (15.5..=19.5).contains(&above),
            "{}: hips {above:.2} units above the lowest foot",
            path.display()
        );
        // In metres that is a human pelvis height.
        let metres = above * units::LengthUnit::Cmu.metres();
        assert!((0.85..=1.1).contains(&metres), "{metres} m");
    }
}

#[test]
fn iclone_root_offset_is_honoured() {
    let Some(corpus) = corpus() else { return };
    let mut pos = Vec::new();
    for path in bvh_files(&corpus, "iclone-cmu") {
        let m = read(&path);
        let file = path.display();
        let metres = units::detect(&m).metres();
        let hip = joint_index(&m, "CC_Base_Hip");
        // Frame 1 is a T-pose standing on the floor (y = 0).
        kinematics::joint_positions(&m.skeleton, m.frame(0), &mut pos);
        let feet = lowest_foot_y(&m, &pos) * metres;
        let hips = pos[hip][1] * metres;
        assert!((-0.05..=0.2).contains(&feet), "{file}: feet at {feet:.3} m");
        assert!((0.95..=1.2).contains(&hips), "{file}: hips at {hips:.3} m");
        assert!(
            (0.85..=1.15).contains(&(hips - feet)),
            "{file}: hips {:.3} m above the feet",
            hips - feet
        );
        // Control: forgetting the OFFSET puts the figure about a metre
        // below the floor, so the checks above do depend on it.
        let mut dropped = m.clone();
        dropped.skeleton.joints[hip].offset = [0.0; 3];
        kinematics::joint_positions(&dropped.skeleton, dropped.frame(0), &mut pos);
        let feet_without = lowest_foot_y(&dropped, &pos) * metres;
        assert!(
            feet_without < -0.7,
            "{file}: OFFSET-less feet at {feet_without:.3} m"
        );
    }
}

fn assert_close(a: &Motion, b: &Motion, tol: f64, file: &str) {
    assert_eq!(a.skeleton.joints.len(), b.skeleton.joints.len(), "{file}");
    for (x, y) in a.skeleton.joints.iter().zip(&b.skeleton.joints) {
        assert_eq!(
            (&x.name, x.parent, &x.channels, x.end_site),
            (&y.name, y.parent, &y.channels, y.end_site),
            "{file}"
        );
        for k in 0..3 {
            assert!(
                (x.offset[k] - y.offset[k]).abs() <= tol,
                "{file}: {}",
                x.name
            );
        }
    }
    assert!((a.frame_time - b.frame_time).abs() <= tol, "{file}");
    assert_eq!(a.values.len(), b.values.len(), "{file}");
    let worst = a
        .values
        .iter()
        .zip(&b.values)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(worst <= tol, "{file}: values differ by {worst}");
}

#[test]
fn every_file_round_trips_through_the_writer() {
    let Some(corpus) = corpus() else { return };
    for sub in ["cmu", "iclone-cmu"] {
        for path in bvh_files(&corpus, sub) {
            let m = read(&path);
            let file = path.display().to_string();
            let text = bvh::write_string(&m);
            let back = bvh::parse_str(&text, &file).unwrap_or_else(|e| panic!("{e}"));
            assert_close(&m, &back, 1e-5, &file);
        }
    }
}

#[test]
fn reader_is_fast() {
    let Some(corpus) = corpus() else { return };
    let largest = bvh_files(&corpus, "iclone-cmu")
        .into_iter()
        .chain(bvh_files(&corpus, "cmu"))
        .max_by_key(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0));
    let Some(path) = largest else {
        panic!("no BVH files in {}", corpus.display())
    };
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    let start = Instant::now();
    let m = bvh::parse_str(&text, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
    let elapsed = start.elapsed();
    eprintln!(
        "parsed {} ({} KB, {} frames × {} channels) in {:.1} ms",
        path.display(),
        text.len() / 1024,
        m.frames(),
        m.channels(),
        elapsed.as_secs_f64() * 1e3
    );
    // The target is well under 100 ms in release; this bound only catches
    // gross regressions on slow or unoptimised builds.
    assert!(elapsed.as_secs_f64() < 1.0, "parsing took {elapsed:?}");
}
