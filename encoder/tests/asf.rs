//! The ASF/AMC reader on small inline files: what it accepts (CRLF,
//! comments, case, radians, bones without dof), how it bakes (channels,
//! offsets, FK against a hand computation), and its errors (file:line:col).

use mocap_encoder::asf::{self, AmcOptions, AsfError};
use mocap_encoder::kinematics;
use mocap_encoder::motion::ChannelKind::*;
use mocap_encoder::units::LengthUnit;

const ASF: &str = "# a comment
:version 1.10
:name test
:units
  mass 1.0
  length 0.45
  angle deg
:documentation
  free text: begin end (whatever)
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name hip
     direction 0 -1 0
     length 2
     axis 0 0 0  XYZ
  end
  begin
     id 2
     name knee
     direction 0 -1 0
     length 3
     axis 0 0 90 XYZ
    dof rx
    limits (-10.0 170.0)
  end
  begin
     id 3
     name chest
     direction 0 1 0
     length 4
     axis 0 0 0 XYZ
    dof rx ry rz
    limits (-20 45)
           (-30 30) # a comment inside limits
           (-30.0 30.0)
  end
:hierarchy
  begin
    root hip chest
    hip knee
  end
";

const AMC: &str = "#!OML:ASF test.asf
:FULLY-SPECIFIED
:DEGREES
1
root 1 2 3 0 0 0
knee 90
chest 0 0 0
2
chest 10 20 30
knee 0
root 0 0 0 0 90 0
";

fn parse(asf: &str, amc: &str) -> Result<asf::AsfMotion, AsfError> {
    asf::parse_strs(asf, "t.asf", amc, "t.amc", &AmcOptions::default())
}

fn err(asf: &str, amc: &str) -> String {
    parse(asf, amc).unwrap_err().to_string()
}

#[test]
fn reads_and_bakes() {
    let r = parse(ASF, AMC).unwrap();
    assert_eq!(r.declared_unit(), Some(LengthUnit::Cmu));
    assert_eq!(r.asf.name.as_deref(), Some("test"));
    assert!(r.asf.documentation.contains("free text"));
    assert_eq!(r.asf.bones[2].limits[1], (-30.0, 30.0));
    let m = &r.motion;
    assert_eq!(m.frames(), 2);
    assert!((m.frame_time - 1.0 / 120.0).abs() < 1e-15);
    let names: Vec<&str> = m.skeleton.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names,
        ["root", "hip", "knee", "knee_End", "chest", "chest_End"]
    );
    let j = &m.skeleton.joints;
    assert_eq!(
        j[0].channels,
        [Xposition, Yposition, Zposition, Zrotation, Yrotation, Xrotation]
    );
    // No dof: no channels (not an End Site).
    assert!(j[1].channels.is_empty() && !j[1].end_site);
    // A 1-dof bone with a non-identity axis: three baked channels.
    assert_eq!(j[2].channels, [Zrotation, Yrotation, Xrotation]);
    assert_eq!(j[2].offset, [0.0, -2.0, 0.0]);
    assert_eq!(j[3].offset, [0.0, -3.0, 0.0]);
    assert!(j[3].end_site);
    // Identity axis: its own dof, reversed (R = Rz·Ry·Rx).
    assert_eq!(j[4].channels, [Zrotation, Yrotation, Xrotation]);
    assert_eq!(j[4].offset, [0.0; 3]);
    // Frame 2's chest line lists rx ry rz = 10 20 30: channels z y x.
    let f = m.frame(1);
    assert_eq!(&f[9..12], &[30.0, 20.0, 10.0]);

    // FK by hand. Frame 1: knee axis C = Rz(90) maps the bone's local x to
    // world y; 90° about local x is 90° about world +Y at the knee, which
    // leaves the shin (along −Y) alone.
    let mut p = Vec::new();
    kinematics::joint_positions(&m.skeleton, m.frame(0), &mut p);
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9);
    assert!(close(p[0], [1.0, 2.0, 3.0]), "{:?}", p[0]);
    assert!(close(p[2], [1.0, 0.0, 3.0]), "{:?}", p[2]);
    assert!(close(p[3], [1.0, -3.0, 3.0]), "{:?}", p[3]);
    // Frame 2: root turned 90° about Y; knee rx 0.
    kinematics::joint_positions(&m.skeleton, m.frame(1), &mut p);
    assert!(close(p[3], [0.0, -5.0, 0.0]), "{:?}", p[3]);
}

#[test]
fn crlf_radians_and_case() {
    let asf = ASF
        .replace(":units", ":UNITS")
        .replace("angle deg", "angle rad")
        .replace("axis 0 0 90 XYZ", "AXIS 0 0 1.5707963267948966 xyz")
        .replace("(-20 45)", "(-1 1)")
        .replace('\n', "\r\n");
    let amc = AMC
        .replace(":DEGREES", ":RADIANS")
        .replace("knee 90", "knee 1.5707963267948966")
        .replace('\n', "\r\n");
    let a = parse(&asf, &amc).unwrap();
    let b = parse(ASF, AMC).unwrap();
    assert_eq!(a.asf.bones[2].limits[0].1, 1.0f64.to_degrees());
    // Same motion once the chest's 10 20 30 are read as radians.
    let (fa, fb) = (a.motion.frame(0), b.motion.frame(0));
    for (x, y) in fa.iter().zip(fb) {
        assert!((x - y).abs() < 1e-9, "{fa:?} {fb:?}");
    }
    assert!((a.motion.frame(1)[9] - 30f64.to_degrees()).abs() < 1e-9);
    // Lone CR line endings too.
    let cr = parse(&ASF.replace('\n', "\r"), &AMC.replace('\n', "\r")).unwrap();
    assert_eq!(cr.motion, b.motion);
}

#[test]
fn frame_time_is_an_option() {
    let r = asf::parse_strs(ASF, "t.asf", AMC, "t.amc", &AmcOptions { frame_time: 0.01 }).unwrap();
    assert_eq!(r.motion.frame_time, 0.01);
}

#[test]
fn limits_are_counted() {
    let r = parse(ASF, &AMC.replace("knee 90", "knee 171")).unwrap();
    assert_eq!(r.frames_outside_limits(), 1);
    assert_eq!(r.amc.limit_violations(&r.asf), vec![(1, 0, 1)]);
    assert_eq!(parse(ASF, AMC).unwrap().frames_outside_limits(), 0);
}

#[test]
fn amc_errors_name_file_line_and_column() {
    let cases = [
        (
            AMC.replace("knee 90", "kne 90"),
            "t.amc:6:1: unknown bone 'kne' (not in the ASF)",
        ),
        (
            AMC.replace("knee 90", "knee 90 1"),
            "t.amc:6:9: bone 'knee' has 1 dof (rx) but the line has more values",
        ),
        (
            AMC.replace("chest 10 20 30", "chest 10 20"),
            "t.amc:9:12: bone 'chest' has 3 dof (rx ry rz) but the line has 2 values",
        ),
        (
            AMC.replace("knee 0\n", ""),
            "t.amc:8:1: frame 2 has no line for bone 'knee' (1 dof)",
        ),
        (
            AMC.replace("knee 90\n", ""),
            "t.amc:4:1: frame 1 has no line for bone 'knee' (1 dof)",
        ),
        (
            AMC.replace("knee 90", "knee nan"),
            "t.amc:6:6: bone 'knee' rx: expected a finite number, found 'nan'",
        ),
        (
            AMC.replace("\n2\n", "\n3\n"),
            "t.amc:8:1: frame 3 follows frame 1 (frames must be numbered consecutively)",
        ),
        (
            AMC.replace("\n1\n", "\n"),
            "t.amc:4:1: bone line 'root' before the first frame number",
        ),
        (
            AMC.replace("chest 0 0 0", "chest 0 0 0\nknee 1"),
            "t.amc:8:1: bone 'knee' appears twice in frame 1",
        ),
        (
            ":FULLY-SPECIFIED\n".to_string(),
            "t.amc: no frames (no frame-number line)",
        ),
    ];
    let mut bad = Vec::new();
    for (amc, want) in cases {
        let got = err(ASF, &amc);
        if got != want {
            bad.push(format!("got  {got}\nwant {want}"));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
    // CRLF does not move columns.
    assert_eq!(
        err(ASF, &AMC.replace("knee 90", "kne 90").replace('\n', "\r\n")),
        "t.amc:6:1: unknown bone 'kne' (not in the ASF)"
    );
}

#[test]
fn asf_errors_name_file_line_and_column() {
    let cases = [
        (
            ASF.replace("    hip knee\n", ""),
            "t.asf:23:1: bone 'knee' is missing from the :hierarchy (no parent names it)",
        ),
        (
            ASF.replace("    hip knee\n", "    hip knee\n    knee hip\n"),
            "t.asf:47:10: bone 'hip' has a second parent (first given on line 45)",
        ),
        (
            ASF.replace("root hip chest", "root chest\n    knee hip"),
            "t.asf:46:1: the :hierarchy has a cycle (hip → knee → back), not reached from the root",
        ),
        (
            ASF.replace("hip knee", "hip kne"),
            "t.asf:46:9: unknown bone 'kne' in :hierarchy (not in :bonedata)",
        ),
        (
            ASF.replace("dof rx\n", "dof rx rw\n"),
            "t.asf:29:12: unknown dof 'rw' (expected rx, ry, rz, tx, ty, tz or l)",
        ),
        (
            ASF.replace("length 3", "length nan"),
            "t.asf:27:13: length: expected a finite number, found 'nan'",
        ),
        (
            ASF.replace("direction 0 1 0", "direction 0 1"),
            "t.asf:35:19: direction: expected 3 numbers, found 2",
        ),
        (
            ASF.replace("           (-30.0 30.0)\n", ""),
            "t.asf:39:5: bone 'chest': 2 limits for 3 dof",
        ),
        (
            ASF.replace("axis 0 0 90 XYZ", "axis 0 0 90 XYX"),
            "t.asf:28:18: axis order 'XYX': expected a permutation of XYZ (e.g. XYZ, ZYX)",
        ),
        (
            ASF.replace("angle deg", "angle grad"),
            "t.asf:7:9: angle: expected deg or rad, found 'grad'",
        ),
        (
            ASF.replace("     length 3\n", ""),
            "t.asf:23:1: bone 'knee' has no length",
        ),
        (
            ASF.replace("name chest", "name hip"),
            "t.asf:34:11: bone 'hip' is defined twice",
        ),
        (
            ASF.replace("     id 3\n", "     id 3\n     colour red\n"),
            "t.asf:34:6: unknown bone attribute 'colour' (expected id, name, direction, length, axis, dof, limits, bodymass, cofmass or end)",
        ),
    ];
    let mut bad = Vec::new();
    for (asf, want) in cases {
        let got = err(&asf, AMC);
        if got != want {
            bad.push(format!("got  {got}\nwant {want}"));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn files_on_disk_and_the_input_entry_point() {
    let dir = std::env::temp_dir().join(format!("mocap-asf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("7.asf"), ASF).unwrap();
    std::fs::write(dir.join("7_01.amc"), AMC).unwrap();
    let amc = dir.join("7_01.amc");
    // CMU naming: 7_01.amc → 7.asf beside it.
    let i = mocap_encoder::input::read_motion(&amc, None).unwrap();
    assert_eq!(i.unit, Some(LengthUnit::Cmu));
    assert_eq!(i.motion.frames(), 2);
    assert_eq!(i.asf.as_ref().unwrap().skeleton_path, dir.join("7.asf"));
    // The pair the other way round.
    let j = mocap_encoder::input::read_motion(&dir.join("7.asf"), Some(&amc)).unwrap();
    assert_eq!(j.motion, i.motion);
    // No skeleton beside it.
    std::fs::write(dir.join("8_01.amc"), AMC).unwrap();
    let e = mocap_encoder::input::read_motion(&dir.join("8_01.amc"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no skeleton") && e.contains("8.asf"), "{e}");
    // An AMC error names the AMC file.
    std::fs::write(dir.join("7_02.amc"), AMC.replace("knee 90", "kne 90")).unwrap();
    let e = mocap_encoder::input::read_motion(&dir.join("7_02.amc"), None)
        .unwrap_err()
        .to_string();
    assert!(
        e.ends_with("7_02.amc:6:1: unknown bone 'kne' (not in the ASF)"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
