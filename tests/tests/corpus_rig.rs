//! The example servo rig on the CMU corpus: limits and speed hold.

use mocap_encoder::bvh;
use mocap_encoder::rig::Rig;
use mocap_tests::{corpus_file, workspace_root};

/// Prints the clamp report of the example rig on the walk and the dance
/// (see it with `cargo test -p mocap-tests --test corpus_rig -- --nocapture`).
#[test]
fn corpus_example_rig_on_walk_and_dance() {
    let rig = Rig::read_file(&workspace_root().join("assets/rigs/cmu_upper_body.toml")).unwrap();
    for clip in ["35_01", "05_04"] {
        let Some(path) = corpus_file("cmu", &format!("{clip}.bvh")) else {
            return;
        };
        let m = bvh::read_file(&path).unwrap();
        let ch = rig.resolve(&m.skeleton).unwrap_or_else(|e| panic!("{e}"));
        let unit = mocap_encoder::units::detect(&m);
        let t = rig.servo_tracks(&m, &ch, unit.metres());
        eprintln!("--- cmu/{clip}.bvh ---\n{t}");
        eprint!("{}", t.events_text(1.0));
        assert_eq!(t.frames(), m.frames());
        let dt = m.frame_time;
        for (s, tr) in rig.servos.iter().zip(&t.servos) {
            let (lo, hi) = s.quarter_us_range();
            assert!(
                tr.pulses.iter().all(|q| (lo..=hi).contains(q)),
                "{}",
                s.name
            );
            let max_step = s.max_speed.unwrap() * dt + 1e-9;
            assert!(
                tr.angles
                    .windows(2)
                    .all(|w| (w[1] - w[0]).abs() <= max_step),
                "{}: step above max_speed",
                s.name
            );
            assert_eq!(tr.report.non_finite, 0);
        }
    }
}
