use super::resolve::closest;
use super::shape::{brake_step, limited_step, rewrap, Binding};
use super::*;

const ONE: &str = r#"
[rig]
name = "t"

[[servo]]
name = "s"
output = 3
channel = "Neck.yrotation"
angle = [-45, 45]
pulse = [1000, 2000]
"#;

#[test]
fn defaults_and_kind_case() {
    let rig = Rig::parse(ONE, "t.toml").unwrap();
    assert_eq!(rig.rate_hz, DEFAULT_RATE_HZ);
    let s = &rig.servos[0];
    assert_eq!(s.channel, "Neck.Yrotation");
    assert_eq!(s.kind, ChannelKind::Yrotation);
    assert_eq!((s.scale, s.offset, s.invert), (1.0, 0.0, false));
    assert_eq!(s.neutral, 1500.0);
    assert_eq!((s.max_speed, s.max_accel), (None, None));
    assert_eq!(
        s.channel_at,
        Position {
            line: 8,
            column: 11
        }
    );
}

#[test]
fn position_of_byte_counts_characters() {
    let t = "ab\nµµx\n";
    assert_eq!(Position::of_byte(t, 0), Position { line: 1, column: 1 });
    assert_eq!(Position::of_byte(t, 3), Position { line: 2, column: 1 });
    // 'x' is byte 7 (µ is two bytes) but character column 3.
    assert_eq!(Position::of_byte(t, 7), Position { line: 2, column: 3 });
    // Inside a multi-byte character: moved back to its start.
    assert_eq!(Position::of_byte(t, 4), Position { line: 2, column: 1 });
    assert_eq!(Position::of_byte(t, 99).line, 3);
}

#[test]
fn mapping_and_inverse() {
    let rig = Rig::parse(ONE, "t.toml").unwrap();
    let s = &rig.servos[0];
    assert_eq!(s.angle_to_quarter_us(0.0), 6000);
    assert_eq!(s.angle_to_quarter_us(-45.0), 4000);
    assert_eq!(s.angle_to_quarter_us(45.0), 8000);
    assert_eq!(s.angle_to_quarter_us(1e9), 8000);
    assert_eq!(s.angle_to_quarter_us(f64::NEG_INFINITY), 4000);
    assert_eq!(s.angle_to_quarter_us(f64::NAN), 6000);
    assert_eq!(s.quarter_us_to_angle(7000), 22.5);
    assert!((s.degrees_per_us() - 0.09).abs() < 1e-12);
    for q in (4000..=8000).step_by(7) {
        assert_eq!(s.angle_to_quarter_us(s.quarter_us_to_angle(q)), q);
    }
}

#[test]
fn limiter_without_accel_is_a_speed_clamp() {
    assert_eq!(
        limited_step(5.0, 0.0, 2.0, f64::INFINITY),
        (2.0, Binding::Speed)
    );
    assert_eq!(
        limited_step(-5.0, 0.0, 2.0, f64::INFINITY),
        (-2.0, Binding::Speed)
    );
    assert_eq!(
        limited_step(1.5, 0.0, 2.0, f64::INFINITY),
        (1.5, Binding::None)
    );
}

#[test]
fn brake_step_is_the_exact_discrete_stopping_step() {
    let stop = |d: f64, u: f64| {
        let (mut d, mut s) = (d, 0.0);
        while d > 0.0 {
            s += d;
            d -= u;
        }
        s
    };
    for &u in &[0.1, 0.4, 1.0, 3.0] {
        for i in 0..500 {
            let dist = f64::from(i) * 0.173;
            let d = brake_step(dist, u);
            assert!(stop(d, u) <= dist + 1e-9, "u {u} dist {dist}: d {d}");
            assert!(stop(d + 1e-6, u) > dist - 1e-9 || dist == 0.0);
        }
    }
    assert_eq!(brake_step(0.0, 1.0), 0.0);
    assert_eq!(brake_step(f64::NAN, 1.0), 0.0);
}

#[test]
fn limiter_brakes_without_overshoot_on_a_step() {
    // A 100° step with 1°/frame² acceleration: position rises
    // monotonically, never overshoots, and arrives.
    let (mut p, mut d) = (0.0f64, 0.0f64);
    let mut prev = 0.0;
    for _ in 0..200 {
        let (s, _) = limited_step(100.0 - p, d, f64::INFINITY, 1.0);
        assert!((s - d).abs() <= 1.0 + 1e-12);
        d = s;
        p += s;
        assert!(p <= 100.0 + 1e-9, "overshoot to {p}");
        assert!(p >= prev - 1e-12);
        prev = p;
    }
    assert!((p - 100.0).abs() < 1e-6, "did not arrive: {p}");
}

#[test]
fn rewrap_moves_drifted_turns_back_in_reach() {
    // A channel that has drifted a full turn below the range [-90, 90]
    // (-300 is +60) comes back to +60; one switch.
    let mut v = vec![-300.0, -301.0, -299.0];
    assert_eq!(rewrap(&mut v, [-90.0, 90.0]), 0);
    assert_eq!(v, vec![60.0, 59.0, 61.0]);
    // Passing slowly through the unreachable side switches once, not on
    // every frame.
    let mut w: Vec<f64> = (0..=72).map(|i| 80.0 + 5.0 * f64::from(i)).collect();
    let n = rewrap(&mut w, [-90.0, 90.0]);
    assert_eq!(n, 1);
    assert!(w.iter().all(|v| (-200.0..=280.0).contains(v)));
}

#[test]
fn rewrap_agrees_with_fixed_unwrap_in_reach() {
    // A wrapped random walk around 0 that stays within reach: the same
    // as fixed::unwrap_degrees, no switches.
    let mut x = 0.0f64;
    let mut seed = 1u64;
    let walk: Vec<f64> = (0..2000)
        .map(|_| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            x = (x + ((seed >> 33) as f64 / 2f64.powi(31) - 0.5) * 20.0).clamp(-170.0, 170.0);
            crate::fixed::wrap_degrees(x + 180.0)
        })
        .collect();
    let mut expected = walk.clone();
    crate::fixed::unwrap_degrees(&mut expected);
    let mut got = walk.clone();
    // Range centred on 180: the first value's own branch is nearest.
    assert_eq!(rewrap(&mut got, [0.0, 360.0]), 0);
    for (g, e) in got.iter().zip(&expected) {
        assert!((g - e - (got[0] - expected[0])).abs() < 1e-9);
    }
    // Non-finite values are skipped without breaking continuity.
    let mut v = vec![170.0, f64::NAN, -175.0, f64::INFINITY, f64::MAX, -160.0];
    rewrap(&mut v, [90.0, 270.0]);
    assert_eq!(v[0], 170.0);
    assert!(v[1].is_nan() && v[3].is_nan() && v[4].is_nan());
    assert_eq!((v[2], v[5]), (185.0, 200.0));
}

#[test]
fn suggestions() {
    let names = ["Hips", "Neck", "Neck1", "LeftForeArm", "Head"];
    assert_eq!(closest("Nek", &names), Some("Neck"));
    assert_eq!(closest("neck", &names), Some("Neck"));
    assert_eq!(closest("LeftForearm", &names), Some("LeftForeArm"));
    assert_eq!(closest("LeftFroeArm", &names), Some("LeftForeArm"));
    assert_eq!(closest("Pelvis", &names), None);
    assert_eq!(closest("Hand", &names), None);
}

#[test]
fn servo_error_in_us() {
    let e = servo_error(&[6000, 6004, 6000], &[6000, 6000, 6008]);
    assert_eq!(e.frames, 3);
    assert_eq!(e.max_us, 2.0);
    assert_eq!(e.worst_frame, Some(2));
    assert!((e.rms_us - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
}
