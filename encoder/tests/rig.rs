//! Servo rigs (src/rig.rs): the example rig, error positions, the mapping
//! from channels to pulses on synthetic motions (clamping, inversion,
//! reversed servos, speed and acceleration limits, garbage input); the
//! example rig on the CMU corpus is tests/tests/corpus_rig.rs.

use std::path::PathBuf;

use mocap_encoder::bvh;
use mocap_encoder::motion::Motion;
use mocap_encoder::rig::{servo_error, LimitKind, Rig, RigError, ServoTracks};

fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn example_rig_text() -> String {
    std::fs::read_to_string(workspace_root().join("assets/rigs/cmu_upper_body.toml")).unwrap()
}

/// The 31 joints of the CMU skeleton, in file order.
const CMU_JOINTS: [&str; 31] = [
    "Hips",
    "LHipJoint",
    "LeftUpLeg",
    "LeftLeg",
    "LeftFoot",
    "LeftToeBase",
    "RHipJoint",
    "RightUpLeg",
    "RightLeg",
    "RightFoot",
    "RightToeBase",
    "LowerBack",
    "Spine",
    "Spine1",
    "Neck",
    "Neck1",
    "Head",
    "LeftShoulder",
    "LeftArm",
    "LeftForeArm",
    "LeftHand",
    "LeftFingerBase",
    "LeftHandIndex1",
    "LThumb",
    "RightShoulder",
    "RightArm",
    "RightForeArm",
    "RightHand",
    "RightFingerBase",
    "RightHandIndex1",
    "RThumb",
];

/// A BVH with the given joints (all children of the first, which gets the
/// 6 root channels; the others `Zrotation Yrotation Xrotation`) and the
/// given frames.
fn star_bvh(joints: &[&str], frame_time: f64, frames: &[Vec<f64>]) -> String {
    let mut s = format!(
        "HIERARCHY\nROOT {}\n{{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n",
        joints[0]
    );
    for j in &joints[1..] {
        s += &format!(
            " JOINT {j}\n {{\n  OFFSET 0 1 0\n  CHANNELS 3 Zrotation Yrotation Xrotation\n  End Site\n  {{\n   OFFSET 0 1 0\n  }}\n }}\n"
        );
    }
    s += &format!(
        "}}\nMOTION\nFrames: {}\nFrame Time: {frame_time}\n",
        frames.len()
    );
    for f in frames {
        let row: Vec<String> = f.iter().map(|v| v.to_string()).collect();
        s += &row.join(" ");
        s += "\n";
    }
    s
}

/// A motion on joints `Hips` and `Neck` (9 channels) at `rate` Hz whose
/// `Neck.Yrotation` (channel 7) follows `neck_y`; everything else is 0.
fn neck_motion(rate: f64, neck_y: &[f64]) -> Motion {
    let frames: Vec<Vec<f64>> = neck_y
        .iter()
        .map(|&v| {
            let mut row = vec![0.0; 9];
            row[7] = v;
            row
        })
        .collect();
    bvh::parse_str(
        &star_bvh(&["Hips", "Neck"], 1.0 / rate, &frames),
        "neck.bvh",
    )
    .unwrap()
}

fn one_servo(body: &str) -> Rig {
    let text = format!("[rig]\nname = \"t\"\n\n[[servo]]\nname = \"s\"\noutput = 0\n{body}");
    Rig::parse(&text, "t.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn tracks(rig: &Rig, m: &Motion) -> ServoTracks {
    let ch = rig.resolve(&m.skeleton).unwrap_or_else(|e| panic!("{e}"));
    rig.servo_tracks(m, &ch, 0.01)
}

fn parse_err(text: &str) -> RigError {
    Rig::parse(text, "rig.toml").expect_err("should not parse")
}

// ---------------------------------------------------------------------------
// The example rig
// ---------------------------------------------------------------------------

#[test]
fn example_rig_parses_and_resolves_on_the_cmu_skeleton() {
    let rig =
        Rig::parse(&example_rig_text(), "cmu_upper_body.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rig.name, "cmu-upper-body");
    assert_eq!(rig.rate_hz, 50.0);
    assert!(
        (12..=20).contains(&rig.servos.len()),
        "{} servos",
        rig.servos.len()
    );
    let mut outputs: Vec<u16> = rig.servos.iter().map(|s| s.output).collect();
    outputs.sort_unstable();
    outputs.dedup();
    assert_eq!(outputs.len(), rig.servos.len());
    for s in &rig.servos {
        assert!(
            s.angle[1] - s.angle[0] <= 180.0,
            "{}: more than a hobby servo's travel",
            s.name
        );
        assert!(s.max_speed.is_some() && s.max_accel.is_some(), "{}", s.name);
    }
    // A reversed servo and an inverted one are in the example.
    assert!(rig.servos.iter().any(|s| s.pulse[0] > s.pulse[1]));
    assert!(rig.servos.iter().any(|s| s.invert));

    // Resolves on a skeleton with the CMU joint names and channel layout.
    let m = bvh::parse_str(
        &star_bvh(&CMU_JOINTS, 1.0 / 120.0, &[vec![0.0; 6 + 3 * 30]]),
        "cmu.bvh",
    )
    .unwrap();
    let ch = rig.resolve(&m.skeleton).unwrap_or_else(|e| panic!("{e}"));
    let names = m.skeleton.channel_names();
    for (s, &c) in rig.servos.iter().zip(&ch) {
        assert_eq!(names[c], s.channel);
    }
    // The rest pose maps inside every range.
    let t = rig.servo_tracks(&m, &ch, 0.0254 / 0.45);
    for (s, tr) in rig.servos.iter().zip(&t.servos) {
        let (lo, hi) = s.quarter_us_range();
        assert!((lo..=hi).contains(&tr.pulses[0]));
    }
}

// ---------------------------------------------------------------------------
// Errors: file:line:col
// ---------------------------------------------------------------------------

const GOOD: &str = r#"[rig]
name = "t"
rate_hz = 50

[[servo]]
name = "neck_pan"
output = 0
channel = "Neck.Yrotation"
angle = [-60.0, 60.0]
pulse = [1000, 2000]
"#;

#[test]
fn unknown_key_names_line_and_column() {
    let text = GOOD.replace("output = 0\n", "output = 0\nspeed = 100\n");
    let e = parse_err(&text);
    assert_eq!(
        (e.file.as_str(), e.line, e.column),
        ("rig.toml", 8, 1),
        "{e}"
    );
    assert!(
        e.message.contains("unknown field") && e.message.contains("speed"),
        "{e}"
    );
    assert!(e.to_string().starts_with("rig.toml:8:1: "), "{e}");

    let text = GOOD.replace("rate_hz = 50\n", "rate_hz = 50\nfps = 3\n");
    let e = parse_err(&text);
    assert_eq!((e.line, e.column), (4, 1), "{e}");

    let e = parse_err(&format!("{GOOD}\n[servos]\nx = 1\n"));
    assert_eq!((e.line, e.column), (12, 2), "{e}");
}

#[test]
fn unknown_channel_names_line_column_and_suggests() {
    let text = GOOD.replace("\"Neck.Yrotation\"", "\"Nek.Yrotation\"");
    let rig = Rig::parse(&text, "rig.toml").unwrap();
    let m = neck_motion(10.0, &[0.0]);
    let e = rig.resolve(&m.skeleton).unwrap_err();
    assert_eq!(
        e.to_string(),
        "rig.toml:8:11: unknown channel \"Nek.Yrotation\" (did you mean \"Neck.Yrotation\"?)"
    );
    // A joint that exists without that channel kind.
    let text = GOOD.replace(
        "channel = \"Neck.Yrotation\"",
        "channel   =   \"Neck.Xposition\"",
    );
    let e = Rig::parse(&text, "rig.toml")
        .unwrap()
        .resolve(&m.skeleton)
        .unwrap_err();
    assert_eq!((e.line, e.column), (8, 15), "{e}");
    assert!(
        e.message
            .contains("has only Zrotation, Yrotation, Xrotation"),
        "{e}"
    );
    // Nothing close: no suggestion.
    let text = GOOD.replace("Neck.Yrotation", "Pelvis.Yrotation");
    let e = Rig::parse(&text, "rig.toml")
        .unwrap()
        .resolve(&m.skeleton)
        .unwrap_err();
    assert_eq!(e.message, "unknown channel \"Pelvis.Yrotation\"");
    // A malformed channel and an unknown kind fail at parse time.
    let e = parse_err(&GOOD.replace("Neck.Yrotation", "NeckYrotation"));
    assert_eq!((e.line, e.column), (8, 11), "{e}");
    let e = parse_err(&GOOD.replace("Neck.Yrotation", "Neck.Yrot"));
    assert!(e.message.contains("unknown channel kind \"Yrot\""), "{e}");
}

#[test]
fn bad_values_name_line_and_column() {
    let cases: &[(&str, &str, (usize, usize), &str)] = &[
        (
            "angle = [-60.0, 60.0]",
            "angle = [60.0, -60.0]",
            (9, 9),
            "bad angle range",
        ),
        (
            "angle = [-60.0, 60.0]",
            "angle = [10, 10]",
            (9, 9),
            "bad angle range",
        ),
        (
            "angle = [-60.0, 60.0]",
            "angle = [nan, 10]",
            (9, 9),
            "bad angle range",
        ),
        (
            "angle = [-60.0, 60.0]",
            "angle = [1, 2, 3]",
            (9, 9),
            "bad angle range",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [1000]",
            (10, 9),
            "bad pulse range",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [300, 2000]",
            (10, 9),
            "outside 400..=2600",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [1000, 2700]",
            (10, 9),
            "outside 400..=2600",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [1500, 1500]",
            (10, 9),
            "must differ",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [1000, 2000]\nneutral = 2100",
            (11, 11),
            "neutral 2100 µs is outside",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [2000, 1000]\nneutral = 900",
            (11, 11),
            "outside the pulse range",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [1000, 2000]\nmax_speed = -5",
            (11, 13),
            "max_speed",
        ),
        (
            "pulse = [1000, 2000]",
            "pulse = [1000, 2000]\nmax_accel = 0",
            (11, 13),
            "max_accel",
        ),
        ("output = 0", "output = -1", (7, 10), ""),
        ("output = 0", "output = \"a\"", (7, 10), ""),
        (
            "channel = \"Neck.Yrotation\"",
            "channel = \"Neck.Yrotation\"\nscale = 0",
            (9, 9),
            "scale",
        ),
        ("rate_hz = 50", "rate_hz = 0", (3, 11), "rate_hz"),
    ];
    for &(from, to, (line, column), needle) in cases {
        let text = GOOD.replace(from, to);
        assert_ne!(text, GOOD);
        let e = parse_err(&text);
        assert_eq!((e.line, e.column), (line, column), "{to:?}: {e}");
        assert!(e.message.contains(needle), "{to:?}: {e}");
    }
}

#[test]
fn duplicates_and_missing_pieces() {
    let two = format!(
        "{GOOD}\n[[servo]]\nname = \"other\"\noutput = 0\nchannel = \"Neck.Xrotation\"\nangle = [-1, 1]\npulse = [1400, 1600]\n"
    );
    let e = parse_err(&two);
    assert_eq!((e.line, e.column), (14, 10), "{e}");
    assert!(
        e.message.contains("output 0 is already used (line 7)"),
        "{e}"
    );

    let e = parse_err(&two.replace("\"other\"", "\"neck_pan\""));
    assert_eq!((e.line, e.column), (13, 8), "{e}");
    assert!(e.message.contains("duplicate servo name"), "{e}");

    let e = parse_err(&GOOD.replace("pulse = [1000, 2000]\n", ""));
    assert_eq!(e.message, "missing key `pulse` in [[servo]]");
    assert_eq!(e.line, 5, "{e}");

    let e = parse_err("[rig]\nname = \"empty\"\n");
    assert!(e.message.contains("no servos"), "{e}");
    assert_eq!(e.line, 1);

    let e = parse_err("[[servo]]\nname = \"x\"\n");
    assert!(e.message.contains("rig"), "{e}");

    let e = parse_err("[rig\nname = 1");
    assert_eq!(e.line, 1, "{e}");

    let e = Rig::read_file(std::path::Path::new("/nonexistent/rig.toml")).unwrap_err();
    assert_eq!((e.line, e.column), (0, 0));
    assert!(
        e.to_string()
            .starts_with("/nonexistent/rig.toml: cannot read"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------
// Mapping
// ---------------------------------------------------------------------------

#[test]
fn clamps_to_the_angle_range_and_reports_it() {
    let rig = one_servo("channel = \"Neck.Yrotation\"\nangle = [-45, 45]\npulse = [1000, 2000]\n");
    let m = neck_motion(10.0, &[0.0, 30.0, 50.0, 70.0, 40.0, -60.0, -45.0, 0.0]);
    let t = tracks(&rig, &m);
    let s = &t.servos[0];
    assert_eq!(
        s.pulses,
        vec![6000, 7333, 8000, 8000, 7778, 4000, 4000, 6000]
    );
    let r = &s.report;
    assert_eq!(r.frames, 8);
    assert_eq!(r.range.frames, 3);
    assert!((r.range.worst - 25.0).abs() < 1e-9);
    assert_eq!(r.range.worst_frame, Some(3));
    assert_eq!(r.speed.frames + r.accel.frames + r.non_finite, 0);
    let kinds: Vec<(LimitKind, usize, usize)> = r
        .events
        .iter()
        .map(|e| (e.kind, e.first_frame, e.last_frame))
        .collect();
    assert_eq!(
        kinds,
        vec![(LimitKind::AboveRange, 2, 3), (LimitKind::BelowRange, 5, 5)]
    );
    assert!(t
        .events_text(0.0)
        .contains("s: frames 2-3: above range, worst 25.00° beyond at frame 3"));
    assert!(t.to_string().contains("Neck.Yrotation"));
}

#[test]
fn expression_inversion_and_reversed_pulses() {
    let values = [-30.0, -10.0, 0.0, 10.0, 30.0];
    let m = neck_motion(10.0, &values);
    let plain =
        one_servo("channel = \"Neck.Yrotation\"\nangle = [-45, 45]\npulse = [1000, 2000]\n");
    let inverted = one_servo(
        "channel = \"Neck.Yrotation\"\ninvert = true\nangle = [-45, 45]\npulse = [1000, 2000]\n",
    );
    let reversed =
        one_servo("channel = \"Neck.Yrotation\"\nangle = [-45, 45]\npulse = [2000, 1000]\n");
    let p = &tracks(&plain, &m).servos[0].pulses;
    let i = &tracks(&inverted, &m).servos[0].pulses;
    let r = &tracks(&reversed, &m).servos[0].pulses;
    assert_eq!(p, &vec![4667, 5556, 6000, 6444, 7333]);
    // Inverting the angle and reversing the servo are the same on a
    // symmetric range: both mirror about 1500 µs.
    assert_eq!(i, r);
    for (a, b) in p.iter().zip(i) {
        assert_eq!(a + b, 12000);
    }
    // Scale and offset: angle = 2 * v - 20, clamped to [0, 90].
    let scaled = one_servo(
        "channel = \"Neck.Yrotation\"\nscale = 2.0\noffset = -20\nangle = [0, 90]\npulse = [1000, 2000]\n",
    );
    let t = tracks(&scaled, &m);
    let s = &t.servos[0];
    assert_eq!(s.angles, vec![0.0, 0.0, 0.0, 0.0, 40.0]);
    assert_eq!(s.report.range.frames, 3);
    assert!((s.report.range.worst - 80.0).abs() < 1e-9);
    assert_eq!(s.report.range.worst_frame, Some(0));
    // Inverse helper: the pulses read back as angles.
    let servo = &scaled.servos[0];
    for (&q, &a) in s.pulses.iter().zip(&s.angles) {
        assert!((servo.quarter_us_to_angle(q) - a).abs() <= 0.25 * servo.degrees_per_us());
    }
}

#[test]
fn position_channels_work_in_millimetres() {
    // Hips.Xposition in centimetres (0.01 m per unit): 10 cm = 100 mm.
    let rig = one_servo(
        "channel = \"Hips.Xposition\"\nscale = 0.1\nangle = [-45, 45]\npulse = [1000, 2000]\n",
    );
    let frames = vec![
        vec![0.0; 9],
        [vec![10.0], vec![0.0; 8]].concat(),
        [vec![-100.0], vec![0.0; 8]].concat(),
    ];
    let m = bvh::parse_str(&star_bvh(&["Hips", "Neck"], 0.1, &frames), "p.bvh").unwrap();
    let t = tracks(&rig, &m);
    let a = &t.servos[0].angles;
    assert!(
        a[0] == 0.0 && (a[1] - 10.0).abs() < 1e-9 && a[2] == -45.0,
        "{a:?}"
    );
    assert_eq!(t.servos[0].report.range.frames, 1);
    // No unwrapping for positions: 1000 mm is not 280 mm.
    assert_eq!(t.servos[0].report.rewraps, 0);
}

#[test]
fn unwraps_across_the_180_degree_seam() {
    // A channel turning steadily through ±180°: the file wraps it, the servo
    // (centred on 180° by the offset) must not jump.
    let values: Vec<f64> = (0..40)
        .map(|i| mocap_encoder::fixed::wrap_degrees(160.0 + 2.0 * f64::from(i)))
        .collect();
    assert!(values.iter().any(|&v| v < 0.0));
    let rig = one_servo(
        "channel = \"Neck.Yrotation\"\noffset = -180\nangle = [-90, 90]\npulse = [500, 2500]\n",
    );
    let t = tracks(&rig, &neck_motion(10.0, &values));
    let s = &t.servos[0];
    for (f, w) in s.angles.windows(2).enumerate() {
        assert!((w[1] - w[0] - 2.0).abs() < 1e-9, "frame {f}: {w:?}");
    }
    assert!(s.report.is_clean(), "{:?}", s.report);

    // A channel that wound up a full turn (as shoulders do in the CMU dance)
    // is brought back into reach instead of sitting at the end stop.
    let wound: Vec<f64> = (0..100).map(|i| -300.0 - 0.1 * f64::from(i)).collect();
    let rig = one_servo("channel = \"Neck.Yrotation\"\nangle = [-90, 90]\npulse = [500, 2500]\n");
    let t = tracks(&rig, &neck_motion(10.0, &wound));
    assert!((t.servos[0].angles[0] - 60.0).abs() < 1e-9);
    assert_eq!(t.servos[0].report.range.frames, 0);
}

#[test]
fn speed_limit_makes_the_servo_lag_not_jump() {
    // 10 Hz, 100 deg/s: at most 10° per frame. A 0 → 80 → -80 step pattern.
    let rate = 10.0;
    let max_speed = 100.0;
    let mut values = vec![0.0; 3];
    values.extend(vec![80.0; 12]);
    values.extend(vec![-80.0; 20]);
    let rig = one_servo(&format!(
        "channel = \"Neck.Yrotation\"\nangle = [-90, 90]\npulse = [500, 2500]\nmax_speed = {max_speed}\n"
    ));
    let servo = &rig.servos[0];
    let t = tracks(&rig, &neck_motion(rate, &values));
    let s = &t.servos[0];
    let max_step = max_speed / rate;
    for (f, w) in s.angles.windows(2).enumerate() {
        assert!(
            (w[1] - w[0]).abs() <= max_step + 1e-9,
            "frame {}: {w:?}",
            f + 1
        );
    }
    // In pulses, up to one quarter-µs of rounding more.
    let max_q = max_step / servo.degrees_per_us() * 4.0 + 1.0;
    for w in s.pulses.windows(2) {
        assert!(f64::from(w[1].abs_diff(w[0])) <= max_q, "{w:?}");
    }
    // It arrives: 80° in 8 frames, 160° in 16.
    assert_eq!(s.angles[3 + 7], 80.0);
    assert_eq!(s.angles[15 + 15], -80.0);
    let r = &s.report;
    assert_eq!(r.speed.frames, 7 + 15);
    assert!((r.speed.worst - 150.0).abs() < 1e-9, "{r:?}");
    assert_eq!(r.speed.worst_frame, Some(15));
    assert_eq!(r.accel.frames, 0);
    let ev: Vec<_> = r
        .events
        .iter()
        .map(|e| (e.kind, e.first_frame, e.last_frame))
        .collect();
    assert_eq!(
        ev,
        vec![(LimitKind::Speed, 3, 9), (LimitKind::Speed, 15, 29)]
    );
}

#[test]
fn accel_limit_ramps_and_brakes_without_leaving_the_range() {
    let rate = 50.0;
    let (max_speed, max_accel) = (200.0, 1000.0);
    // Steps between the ends of the range, and a fast sine.
    let values: Vec<f64> = (0..400)
        .map(|i| {
            let t = f64::from(i) / rate;
            if i < 200 {
                if (i / 50) % 2 == 0 {
                    45.0
                } else {
                    -45.0
                }
            } else {
                60.0 * (t * 9.0).sin()
            }
        })
        .collect();
    let rig = one_servo(&format!(
        "channel = \"Neck.Yrotation\"\nangle = [-45, 45]\npulse = [1000, 2000]\nmax_speed = {max_speed}\nmax_accel = {max_accel}\n"
    ));
    let t = tracks(&rig, &neck_motion(rate, &values));
    let s = &t.servos[0];
    let (step, dstep) = (max_speed / rate, max_accel / rate / rate);
    let mut prev_step = 0.0;
    for (f, w) in s.angles.windows(2).enumerate() {
        let d = w[1] - w[0];
        assert!(d.abs() <= step + 1e-9, "frame {}: step {d}", f + 1);
        assert!(
            (d - prev_step).abs() <= dstep + 1e-9,
            "frame {}: accel",
            f + 1
        );
        assert!((-45.0..=45.0).contains(&w[1]));
        prev_step = d;
    }
    assert!(s.pulses.iter().all(|q| (4000..=8000).contains(q)));
    assert!(s.report.accel.frames > 0 && s.report.range.frames > 0);
    // Settles on each plateau.
    assert_eq!(s.angles[49], 45.0);
    assert_eq!(s.angles[99], -45.0);
}

/// SplitMix64: deterministic pseudo-random numbers.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

#[test]
fn garbage_input_never_leaves_the_pulse_range() {
    let specials = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MAX,
        f64::MIN,
        1e300,
        -1e300,
        1e-300,
        0.0,
        -0.0,
        179.999,
        -180.0,
    ];
    let rigs = [
        "channel = \"Neck.Yrotation\"\nangle = [-45, 45]\npulse = [1000, 2000]\nneutral = 1200\n",
        "channel = \"Neck.Yrotation\"\nscale = -1e300\noffset = 5\nangle = [0, 126]\npulse = [2200, 800]\nmax_speed = 300\nmax_accel = 3000\n",
        "channel = \"Hips.Yposition\"\nscale = 1e10\nangle = [-90, 90]\npulse = [500, 2500]\nmax_speed = 1\n",
        "channel = \"Neck.Yrotation\"\ninvert = true\nangle = [-0.001, 0.001]\npulse = [1499.9, 1500.1]\nmax_accel = 1e-3\n",
    ];
    let mut rng = Rng(7);
    for (k, body) in rigs.iter().enumerate() {
        let rig = one_servo(body);
        let servo = &rig.servos[0];
        let (lo, hi) = servo.quarter_us_range();
        for round in 0..20 {
            let mut m = neck_motion(120.0, &vec![0.0; 300]);
            for v in m.values.iter_mut() {
                let r = rng.next();
                *v = match r % 4 {
                    0 => specials[(r >> 8) as usize % specials.len()],
                    1 => f64::from_bits(rng.next()),
                    2 => (rng.next() as i64 as f64) * 1e-12,
                    _ => ((rng.next() % 720_000) as f64) / 1000.0 - 360.0,
                };
            }
            let t = tracks(&rig, &m);
            let s = &t.servos[0];
            assert_eq!(s.pulses.len(), 300);
            assert!(
                s.pulses.iter().all(|q| (lo..=hi).contains(q)),
                "rig {k} round {round}: pulse outside {lo}..={hi}"
            );
            assert!(s.angles.iter().all(|a| a.is_finite()));
            let c = s.channel;
            let bad = (0..300)
                .filter(|&f| !m.values[f * 9 + c].is_finite())
                .count();
            assert!(
                s.report.non_finite >= bad,
                "rig {k}: {} < {bad}",
                s.report.non_finite
            );
            if bad > 0 {
                assert!(s.report.first_non_finite.is_some());
                assert!(s
                    .report
                    .events
                    .iter()
                    .any(|e| e.kind == LimitKind::NonFinite));
            }
        }
    }
    // A lone NaN becomes the neutral pulse (no limits on this servo).
    let rig = one_servo(rigs[0]);
    let mut m = neck_motion(10.0, &[10.0, 0.0, 10.0]);
    m.values[9 + 7] = f64::NAN;
    let t = tracks(&rig, &m);
    assert_eq!(t.servos[0].pulses[1], 4800);
    assert_eq!(t.servos[0].report.non_finite, 1);
    assert_eq!(t.servos[0].report.first_non_finite, Some(1));
    assert!(t
        .events_text(0.0)
        .contains("frame 1: non-finite value, neutral used"));
}

#[test]
fn servo_error_between_tracks() {
    let rig = one_servo("channel = \"Neck.Yrotation\"\nangle = [-45, 45]\npulse = [1000, 2000]\n");
    let a = tracks(&rig, &neck_motion(10.0, &[0.0, 9.0, 18.0]));
    let b = tracks(&rig, &neck_motion(10.0, &[0.0, 9.9, 18.0]));
    let e = a.error_against(&b);
    assert_eq!(e.len(), 1);
    assert_eq!(e[0].frames, 3);
    assert_eq!(e[0].worst_frame, Some(1));
    assert!((e[0].max_us - 10.0).abs() <= 0.25, "{:?}", e[0]);
    let direct = servo_error(&a.servos[0].pulses, &b.servos[0].pulses);
    assert_eq!(direct, e[0]);
    assert!((e[0].max_us * rig.servos[0].degrees_per_us() - 0.9).abs() < 0.03);
}
