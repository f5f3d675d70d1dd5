//! The `mocap` binary end to end on the shipped demo clip: each subcommand
//! runs, writes what it says, and prints the library's errors as
//! `mocap: error: …` with the messages users read.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mocap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mocap"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("run mocap")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn encode_info_eval_decode_the_demo() {
    let d = out_dir("demo");
    let clip = d.join("demo.mcb");
    let clip = clip.to_str().expect("utf-8 path");
    let o = mocap(&[
        "encode",
        "assets/animatronic_demo.bvh",
        "-o",
        clip,
        "--emit",
        "rust",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let shipped = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../firmware-example/clips/demo.mcb"
    ))
    .expect("shipped clip");
    assert_eq!(std::fs::read(clip).expect("clip"), shipped);
    assert!(text(&o.stdout).contains("(bound 1° holds; index, key interval"));
    assert!(d.join("demo.rs").exists());

    let o = mocap(&["info", clip, "--channels"]);
    assert!(o.status.success());
    let info = text(&o.stdout);
    assert!(info.starts_with(&format!("clip: {} bytes, version 1,", shipped.len())));
    assert!(info.contains("  index codec: key interval"), "{info}");

    let o = mocap(&["eval", "assets/animatronic_demo.bvh", clip, "--json"]);
    assert!(o.status.success());
    assert!(text(&o.stdout).starts_with('{'));

    let bvh = d.join("back.bvh");
    let o = mocap(&["decode", clip, "-o", bvh.to_str().expect("utf-8 path")]);
    assert!(o.status.success());
    assert!(text(&std::fs::read(bvh).expect("bvh")).starts_with("HIERARCHY"));
}

#[test]
fn errors_read_as_before() {
    let o = mocap(&[
        "encode",
        "--max-error",
        "1q",
        "assets/animatronic_demo.bvh",
        "-o",
        "x.mcb",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("error bound '1q': unit 'q' is not deg, mm or cm"));

    let o = mocap(&["bench", "assets/animatronic_demo.bvh", "--max-error", "1q"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        text(&o.stderr),
        "mocap: error: error bound '1q': unit 'q' is not deg, mm or cm\n"
    );

    let o = mocap(&["encode", "/nonexistent.bvh", "-o", "x.mcb"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).starts_with("mocap: error: /nonexistent.bvh: cannot read file: "));

    let d = out_dir("errors");
    let s = d.join("s.mcb");
    let o = mocap(&[
        "encode",
        "assets/animatronic_demo.bvh",
        "--rig",
        "assets/rigs/animatronic_demo.toml",
        "--max-error",
        "5mm",
        "-o",
        s.to_str().expect("utf-8 path"),
    ]);
    assert_eq!(
        text(&o.stderr),
        "mocap: error: a servo clip's bound is in degrees of servo travel (e.g. --max-error 0.5deg)\n"
    );
}

/// `mocap play SERVO_CLIP --rig FIGURE`: the figure's hard limits. A clip
/// for the figure's own rig plays and says so; `--policy` without `--rig` is
/// a usage error; a clip for another rig that leaves the limits is refused
/// (exit 1, the reason on stderr) unless `--policy clamp`, which reports
/// every servo it clamped.
#[test]
fn play_holds_a_servo_clip_to_the_figure() {
    let d = out_dir("figure");
    let path = |n: &str| d.join(n).to_str().expect("utf-8 path").to_owned();
    let rig = "assets/rigs/animatronic_demo.toml";
    let encode_for = |rig: &str, clip: &str| {
        let args = ["encode", "assets/animatronic_demo.bvh", "--rig", rig];
        let o = mocap(&[&args[..], &["--max-error", "0.5deg", "-o", clip]].concat());
        assert!(o.status.success(), "{}", text(&o.stderr));
    };
    let out = path("out.bin");
    let play = |clip: &str, extra: &[&str]| {
        let args = [
            "play",
            clip,
            "--protocol",
            "maestro",
            "--fast",
            "--output",
            &out,
        ];
        mocap(&[&args[..], extra].concat())
    };
    let own = path("own.mcb");
    encode_for(rig, &own);
    let o = play(&own, &["--rig", rig]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("figure: the clip was made for this rig"));

    let o = play(&own, &["--policy", "clamp"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));

    // The figure's rig with output 0 widened to 500–2500 µs: a bigger sibling.
    let toml = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../assets/rigs/animatronic_demo.toml"
    ))
    .expect("rig");
    let wide_toml = toml.replacen("pulse = [1000, 2000]", "pulse = [500, 2500]", 1);
    assert_ne!(wide_toml, toml);
    let wide_rig = path("wide.toml");
    std::fs::write(&wide_rig, wide_toml).expect("write rig");
    let wide = path("wide.mcb");
    encode_for(&wide_rig, &wide);
    let o = play(&wide, &["--rig", rig]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("servo output 0 leaves the figure's hard limits"),
        "{}",
        text(&o.stderr)
    );
    let o = play(&wide, &["--rig", rig, "--policy", "clamp"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.contains("played clamped"), "{err}");
    assert!(
        err.contains("hard limits changed pulses of output"),
        "{err}"
    );

    // The same table, another mechanism (neck_pan's acceleration limit halved): only the rig
    // digest (SPEC.md §3.6, shown by `mocap info`) tells the clips apart.
    let slow_toml = toml.replacen("max_accel = 5000.0", "max_accel = 2500.0", 1);
    assert_ne!(slow_toml, toml);
    let slow_rig = path("slow.toml");
    std::fs::write(&slow_rig, slow_toml).expect("write rig");
    let slow = path("slow.mcb");
    encode_for(&slow_rig, &slow);
    let digest = |clip: &str| {
        let o = mocap(&["info", clip]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let out = text(&o.stdout);
        out.lines()
            .find_map(|l| l.strip_prefix("rig digest: "))
            .map(|l| l[..8].to_string())
            .unwrap_or_else(|| panic!("no rig digest line:\n{out}"))
    };
    assert_ne!(digest(&own), digest(&slow));
    let o = play(&slow, &["--rig", rig, "--policy", "refuse"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("refused by the figure's policy"),
        "{}",
        text(&o.stderr)
    );
    let o = play(&slow, &["--rig", rig]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("another rig digest"),
        "{}",
        text(&o.stderr)
    );
}

/// `mocap ARGS` in real time, sent SIGINT (Ctrl-C) after about one second.
fn interrupted(args: &[&str]) -> Output {
    let child = Command::new(env!("CARGO_BIN_EXE_mocap"))
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .args(args)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mocap runs");
    std::thread::sleep(std::time::Duration::from_millis(1000));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    child.wait_with_output().expect("mocap ends")
}

/// `mocap play` stopped by Ctrl-C (SIGINT) mid-clip: it sends what it would have sent up to
/// there, then brings every servo back to rest at its speed limits, and exits 130 saying so.
#[test]
fn play_stopped_by_ctrl_c_returns_the_servos_to_rest() {
    let d = out_dir("stop");
    let path = |n: &str| d.join(n).to_str().expect("utf-8 path").to_owned();
    let rig = "assets/rigs/animatronic_demo.toml";
    let clip = path("own.mcb");
    let args = ["encode", "assets/animatronic_demo.bvh", "--rig", rig];
    let o = mocap(&[&args[..], &["--max-error", "0.5deg", "-o", &clip]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let play = [
        "play",
        &clip,
        "--rig",
        rig,
        "--protocol",
        "maestro",
        "--output",
    ];
    let whole = path("whole.bin");
    let o = mocap(&[&play[..], &[&whole, "--fast"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let whole = std::fs::read(&whole).expect("whole stream");

    // In real time (the clip lasts 8 s); SIGINT after about one second.
    let stopped = path("stopped.bin");
    let o = interrupted(&[&play[..], &[&stopped]].concat());
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("mocap: stopped:") && err.contains("returned to rest"),
        "{err}"
    );
    let got = std::fs::read(&stopped).expect("stopped stream");
    // 12 servos, a 4-byte Set Target each: 48 bytes a tick.
    let tick = 48;
    assert_eq!(got.len() % tick, 0);
    let ticks: Vec<&[u8]> = got.chunks(tick).collect();
    assert!(ticks.len() < whole.len() / tick, "not stopped early");
    // Where it stopped: the longest prefix of the whole stream's ticks.
    let same = ticks
        .iter()
        .zip(whole.chunks(tick))
        .take_while(|(a, b)| **a == *b)
        .count();
    assert!(same > 10, "stopped after {same} ticks");
    let pulse = |c: &[u8]| u16::from(c[2]) | u16::from(c[3]) << 7;
    // The figure's neutrals: the whole stream's last tick.
    let neutral: Vec<u16> = whole[whole.len() - tick..].chunks(4).map(pulse).collect();
    let last: Vec<u16> = ticks.last().unwrap().chunks(4).map(pulse).collect();
    assert_eq!(last, neutral, "not at rest after the stop");
    assert!(ticks.len() > same, "nothing sent after the stop");

    // `mocap send --poses` stopped the same way ends with `00` and a `Stop` (SPEC.md §8's
    // example frame): the firmware parks.
    let poses = path("poses.bin");
    let o = interrupted(&["send", &clip, "--poses", "--output", &poses]);
    assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("sent Stop"), "{}", text(&o.stderr));
    let sent = std::fs::read(&poses).expect("poses");
    assert!(
        sent.ends_with(&[0x00, 0x00, 0x06, 0x04, 0x94, 0x2B, 0x6F, 0xD5, 0x00]),
        "{:02x?}",
        &sent[sent.len().saturating_sub(12)..]
    );
}

#[test]
fn show_build_info_and_play_the_demo_show() {
    let d = out_dir("show");
    let show = d.join("demo_show.mcb");
    let show = show.to_str().expect("utf-8 path");
    let o = mocap(&["show", "build", "assets/shows/demo.toml", "-o", show]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let summary = text(&o.stdout);
    assert!(summary.contains("show `demo`, 4 clips"), "{summary}");
    assert!(summary.contains("every clip's bound holds"), "{summary}");
    assert!(
        !summary.contains("LARGER"),
        "every seam within its clip's own step: {summary}"
    );
    let o = mocap(&["info", show]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let info = text(&o.stdout);
    assert!(info.starts_with("show: "), "{info}");
    assert!(
        info.contains("clip 3 `idle`") && info.contains("cue list `main`: 6 cues"),
        "{info}"
    );
    assert!(
        info.contains("trigger input 1: clip `talk` | clip `look`"),
        "{info}"
    );
    // A clip reader refuses the show by name.
    let o = mocap(&["decode", show, "-o", d.join("x.bvh").to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("is a show"), "{}", text(&o.stderr));

    let out = d.join("show.maestro");
    let o = mocap(&[
        "play",
        show,
        "--cues",
        "assets/shows/demo_cues.txt",
        "--protocol",
        "maestro",
        "--output",
        out.to_str().unwrap(),
        "--fast",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(
        err.contains("# event t_us=0 serial 7e ff 06 03 00 00 01 ef"),
        "{err}"
    );
    assert!(err.contains("# event t_us=9000000 gpio 2 1"), "{err}");
    // 14 s at 50 Hz, then the return to rest: 12 servos × 4 bytes a tick.
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(bytes.len() % 48, 0);
    assert!(bytes.len() / 48 > 700, "{} ticks", bytes.len() / 48);
}

#[test]
fn show_errors_name_the_file_and_line() {
    let d = out_dir("show-errors");
    let bad = d.join("bad.toml");
    std::fs::write(
        &bad,
        "[show]\nname = \"x\"\n\n[[clip]]\nname = \"a\"\nfile = \"../../../../assets/animatronic_demo.bvh\"\nloop = { in = \"2s\", out = \"1s\" }\n\n[[cues]]\nname = \"m\"\ncue = [ { at = \"1s\", play = \"nope\" } ]\n",
    )
    .unwrap();
    let o = mocap(&[
        "show",
        "build",
        bad.to_str().unwrap(),
        "-o",
        d.join("x.mcb").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.contains("bad.toml:11:") && err.contains("no clip named `nope`"),
        "{err}"
    );

    // Two sources with different channels: both files and the first difference.
    let other = d.join("other.bvh");
    let demo = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../assets/animatronic_demo.bvh"
    ))
    .unwrap();
    std::fs::write(&other, demo.replacen("JOINT Torso", "JOINT Spine", 1)).unwrap();
    let two = d.join("two.toml");
    std::fs::write(
        &two,
        format!(
            "[show]\nname = \"two\"\n[[clip]]\nname = \"a\"\nfile = \"{}\"\n[[clip]]\nname = \"b\"\nfile = \"other.bvh\"\n",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/animatronic_demo.bvh")
        ),
    )
    .unwrap();
    let o = mocap(&[
        "show",
        "build",
        two.to_str().unwrap(),
        "-o",
        d.join("y.mcb").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.contains("other.bvh") && err.contains("animatronic_demo.bvh"),
        "{err}"
    );
    assert!(
        err.contains("`Spine.Zrotation`, not `Torso.Zrotation`"),
        "{err}"
    );
}

/// A small ASF (CMU units, a bone without dof, a bone with an axis) and an
/// AMC of `frames` frames of a knee bending.
fn asf_amc(d: &Path, frames: usize) -> (PathBuf, PathBuf) {
    let asf = ":units\n  mass 1.0\n  length 0.45\n  angle deg\n:root\n  order TX TY TZ RX RY RZ\n  axis XYZ\n  position 0 0 0\n  orientation 0 0 0\n:bonedata\n  begin\n    id 1\n    name hip\n    direction 0 -1 0\n    length 2\n    axis 0 0 0 XYZ\n  end\n  begin\n    id 2\n    name knee\n    direction 0 -1 0\n    length 7\n    axis 0 0 20 XYZ\n    dof rx\n    limits (-10.0 170.0)\n  end\n:hierarchy\n  begin\n    root hip\n    hip knee\n  end\n";
    let mut amc = String::from(":FULLY-SPECIFIED\r\n:DEGREES\r\n");
    for f in 0..frames {
        let t = f as f64 / 120.0;
        amc += &format!(
            "{}\r\nroot {:.4} 17 {:.4} 0 {:.3} 0\r\nknee {:.4}\r\n",
            f + 1,
            t * 10.0,
            t,
            t * 30.0,
            60.0 * (1.0 - (t * 6.0).cos())
        );
    }
    let (a, m) = (d.join("leg.asf"), d.join("leg_01.amc"));
    std::fs::write(&a, asf).expect("asf");
    std::fs::write(&m, amc).expect("amc");
    (a, m)
}

/// `mocap encode x.amc --skeleton y.asf`, then `mocap eval` of the clip
/// against the AMC (its skeleton found beside it: leg_01.amc → leg.asf);
/// `--fps`; the errors name the file and line.
#[test]
fn encode_and_eval_an_amc() {
    let d = out_dir("asf");
    let (asf, amc) = asf_amc(&d, 240);
    let (asf, amc) = (asf.to_str().expect("utf-8"), amc.to_str().expect("utf-8"));
    let clip = d.join("leg.mcb");
    let clip = clip.to_str().expect("utf-8 path");
    let o = mocap(&["encode", amc, "--skeleton", asf, "-o", clip]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(
        err.contains("240 frames × 9 channels at 120.0 Hz, units cmu"),
        "{err}"
    );
    assert!(text(&o.stdout).contains("(bound 1° holds;"));

    let o = mocap(&["eval", amc, clip, "--json"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let x: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(x["frames"], 240);
    assert!(x["angle_max_deg"].as_f64().expect("angle") <= 1.0);

    let o = mocap(&["encode", amc, "--fps", "60", "-o", clip]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("at 60.0 Hz"),
        "{}",
        text(&o.stderr)
    );

    // Limits: the knee past 170° in some frames is a warning.
    let bent = std::fs::read_to_string(amc)
        .expect("amc")
        .replace("knee 0.0000\r\n", "knee 175\r\n");
    let bent_path = d.join("leg_02.amc");
    std::fs::write(&bent_path, bent).expect("amc");
    let o = mocap(&["encode", bent_path.to_str().expect("utf-8"), "-o", clip]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr)
            .contains("1 of 240 frames have dof values outside the ASF's limits (knee rx: 1)"),
        "{}",
        text(&o.stderr)
    );

    let broken = d.join("leg_03.amc");
    std::fs::write(&broken, ":DEGREES\n1\nroot 0 0 0 0 0 0\nknee 1 2\n").expect("amc");
    let o = mocap(&["encode", broken.to_str().expect("utf-8"), "-o", clip]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        text(&o.stderr),
        format!(
            "mocap: error: {}:4:8: bone 'knee' has 1 dof (rx) but the line has more values\n",
            broken.display()
        )
    );

    let alone = d.join("walk_01.amc");
    std::fs::write(&alone, ":DEGREES\n").expect("amc");
    let o = mocap(&["eval", alone.to_str().expect("utf-8"), clip]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("no skeleton:") && text(&o.stderr).contains("walk.asf not found"),
        "{}",
        text(&o.stderr)
    );
}

/// A tiny Intel C3D file (integer data, scale 0.1 mm, 100 Hz): markers
/// A test directory `name` holding [`tiny_c3d`] as `tiny.c3d`: the
/// directory, that file and the clip path `tiny.mcb` beside it.
fn tiny_c3d_in(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let d = out_dir(name);
    let c3d = d.join("tiny.c3d");
    std::fs::write(&c3d, tiny_c3d()).expect("write");
    let clip = d.join("tiny.mcb");
    (d, c3d, clip)
}

/// `LHEE` and `RHEE` over four frames, `RHEE` missing at frame 2.
fn tiny_c3d() -> Vec<u8> {
    let u16s = |b: &mut Vec<u8>, v: &[u16]| v.iter().for_each(|x| b.extend(x.to_le_bytes()));
    let mut b = vec![2u8, 0x50];
    u16s(&mut b, &[2, 0, 1, 4, 0]);
    b.extend(0.1f32.to_le_bytes());
    u16s(&mut b, &[3, 0]);
    b.extend(100f32.to_le_bytes());
    b.resize(512, 0);
    b.extend([1, 0x50, 1, 84]);
    // Group POINT (id 1), then its parameters; each record's next offset
    // counts from the offset word.
    b.extend([5, 0xff]);
    b.extend(b"POINT");
    b.extend([3, 0, 0]);
    let mut param = |name: &str, kind: i8, dims: &[u8], data: &[u8], last: bool| {
        b.extend([name.len() as u8, 1]);
        b.extend(name.as_bytes());
        let next = if last { 0 } else { 5 + dims.len() + data.len() } as u16;
        b.extend(next.to_le_bytes());
        b.extend([kind as u8, dims.len() as u8]);
        b.extend(dims);
        b.extend(data);
        b.push(0);
    };
    param("USED", 2, &[], &2u16.to_le_bytes(), false);
    param("SCALE", 4, &[], &0.1f32.to_le_bytes(), false);
    param("RATE", 4, &[], &100f32.to_le_bytes(), false);
    param("LABELS", -1, &[4, 2], b"LHEERHEE", false);
    param("UNITS", -1, &[2], b"mm", true);
    b.resize(1024, 0);
    for f in 0..4i16 {
        for p in 0..2i16 {
            let residual = if p == 1 && f == 2 { -1 } else { 0x0102 };
            for v in [1000 + 10 * f, 2000 * p, 900 - 5 * f, residual] {
                b.extend(v.to_le_bytes());
            }
        }
    }
    b
}

/// `--target` on a marker file without `--codec` tries every codec the cost
/// model knows and keeps the smallest clip that fits the chip; the clip
/// written is that candidate's and still flags its missing sample.
#[test]
fn a_c3d_marker_file_with_a_target_tries_every_codec() {
    let (_, c3d, clip) = tiny_c3d_in("c3d-target");
    let (c3d, clip) = (c3d.to_str().unwrap(), clip.to_str().unwrap());
    let o = mocap(&[
        "encode",
        c3d,
        "-o",
        clip,
        "--max-error",
        "2mm",
        "--target",
        "microbit",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    for label in ["index ", "index-fast", "pca-spline", "predictive", "rma "] {
        assert!(out.contains(&format!("  {label}")), "{label}: {out}");
    }
    let chosen = out
        .lines()
        .find(|l| l.ends_with("[chosen]"))
        .unwrap_or_else(|| panic!("a chosen clip: {out}"));
    let bytes: usize = chosen.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert_eq!(
        std::fs::metadata(clip).unwrap().len() as usize,
        bytes,
        "{out}"
    );
    let o = mocap(&["info", clip]);
    assert!(
        text(&o.stdout).contains("missing samples: 1 of 8"),
        "{}",
        text(&o.stdout)
    );
    // `--codec` keeps the one codec, checked against the chip.
    let o = mocap(&[
        "encode",
        c3d,
        "-o",
        clip,
        "--max-error",
        "2mm",
        "--target",
        "microbit",
        "--codec",
        "index",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!text(&o.stdout).contains("[chosen]"), "{}", text(&o.stdout));
}

#[test]
fn encode_info_eval_a_c3d_marker_file() {
    let (d, c3d, clip) = tiny_c3d_in("c3d");
    let (c3d, clip) = (c3d.to_str().unwrap(), clip.to_str().unwrap());
    let o = mocap(&["encode", c3d, "-o", clip, "--max-error", "2mm"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains("1 missing samples flagged"), "{out}");
    assert!(
        text(&o.stderr).contains(
            "4 frames × 2 markers at 100 Hz, units mm (POINT:UNITS 'mm'), 1 samples missing"
        ),
        "{}",
        text(&o.stderr)
    );
    let o = mocap(&["info", clip, "--channels"]);
    let out = text(&o.stdout);
    assert!(
        out.contains("missing samples: 1 of 8 (12.5 %) in 1 runs"),
        "{out}"
    );
    assert!(out.contains("  RHEE: frames 2\n"), "{out}");
    assert!(out.contains("section 0x81: 6 bytes"), "{out}");
    // The view page: both markers, the missing sample flagged (frame 2,
    // joint 1 of 2: bit 5 of the bitmap, base64 "IA=="), not drawn as data.
    let page = d.join("tiny.html");
    let o = mocap(&["view", c3d, clip, "-o", page.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let html = std::fs::read_to_string(&page).expect("page");
    assert!(
        html.contains(r#""missing":"IA==","missingCount":1"#),
        "{html}"
    );
    let o = mocap(&["eval", c3d, clip]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(out.contains("present samples     7"), "{out}");
    assert!(
        out.contains("missing samples     1 (12.5 %) in 1 runs: the clip flags exactly these"),
        "{out}"
    );
    let o = mocap(&["eval", c3d, clip, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert!(v["max_mm"].as_f64().unwrap() <= 2.0);
    assert_eq!(v["mask_matches"], true);
    // An angle bound means nothing for markers; a cut file names its offset.
    let o = mocap(&["encode", c3d, "-o", clip, "--max-error", "1deg"]);
    assert!(text(&o.stderr).contains("a marker clip has no rotation channels"));
    let cut = d.join("cut.c3d");
    std::fs::write(&cut, &tiny_c3d()[..1070]).expect("write");
    let o = mocap(&["encode", cut.to_str().unwrap(), "-o", clip]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.starts_with(&format!(
            "mocap: error: {}: byte 1056: file ends inside frame 3 of 4",
            cut.display()
        )),
        "{err}"
    );
}

/// A tiny generated BVH: a root with position and rotation channels, an
/// arm, an End Site, 40 frames of smooth motion in centimetres.
fn tiny_bvh() -> String {
    let mut s = String::from(
        "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n\tJOINT Arm\n\t{\n\t\tOFFSET 0 40 0\n\t\tCHANNELS 3 Zrotation Yrotation Xrotation\n\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 30 0\n\t\t}\n\t}\n}\nMOTION\nFrames: 40\nFrame Time: 0.0333333\n",
    );
    for f in 0..40 {
        let t = f as f64 / 30.0;
        let v = [
            20.0 * t,
            90.0 + (3.0 * t).sin(),
            0.0,
            10.0 * t.sin(),
            5.0,
            -3.0 * t,
            40.0 * (2.0 * t).sin(),
            0.0,
            25.0 * t.cos(),
        ];
        let line: Vec<String> = v.iter().map(|x| format!("{x:.4}")).collect();
        s += &line.join(" ");
        s.push('\n');
    }
    s
}

/// `mocap bench` with baselines beside a codec on a tiny BVH: the columns,
/// a row per method and bound, the summary with `--summary`, the JSON rows
/// with the header convention, and the plot.
#[test]
fn bench_prints_baselines_beside_the_codecs() {
    let d = out_dir("bench");
    let bvh = d.join("tiny.bvh");
    std::fs::write(&bvh, tiny_bvh()).expect("write");
    let bvh = bvh.to_str().unwrap();
    let json = d.join("rows.json");
    let plot = d.join("rd.svg");
    let o = mocap(&[
        "bench",
        bvh,
        "--codec",
        "index",
        "--codec",
        "raw16",
        "--codec",
        "zstd",
        "--codec",
        "xz",
        "--codec",
        "keyframe-linear",
        "--max-error",
        "1deg",
        "--max-error",
        "50mm+arms:10mm",
        "--json",
        json.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.starts_with("| folder | file | codec | bound | frames×ch | bytes | ratio f32 | ratio f32 w/o header | ratio file | bits/ch/frame | ARMS mm | max mm | d % | angle RMS ° | angle max ° | foot slide mm/s (source) | foot h mm | holds | K | repeated frames | encode s |\n"),
        "{out}"
    );
    assert!(out.contains("| folder | codec | bound | files | total f32 bytes | total bytes | ratio f32 | ratio f32 w/o header | bits/ch/frame | worst ARMS mm | worst max mm | worst angle max ° | mean d % | foot slide mm/s (source) | foot h mm | bound holds | encode s |\n"), "{out}");
    for method in [
        "index",
        "raw16",
        "quant+zstd",
        "quant+xz",
        "keyframe-linear",
    ] {
        for bound in ["1deg", "50mm+arms:10mm"] {
            let row = format!("| bench | tiny.bvh | {method} | {bound} | 40×9 | ");
            assert!(out.contains(&row), "{row}\n{out}");
            let total = format!("| bench | {method} | {bound} | 1 | 1440 | ");
            assert!(out.contains(&total), "{total}\n{out}");
        }
    }
    assert!(!out.contains("**no**"), "{out}");
    let rows: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).expect("json")).expect("json rows");
    let rows = rows.as_array().expect("rows");
    assert_eq!(rows.len(), 10);
    for r in rows {
        let (bytes, header) = (
            r["metrics"]["bytes"].as_u64().unwrap(),
            r["header_bytes"].as_u64().unwrap(),
        );
        assert!(header > 0 && bytes > header, "{r}");
        let without = 1440.0 / (bytes - header) as f64;
        assert!((r["ratio_f32_without_header"].as_f64().unwrap() - without).abs() < 1e-9);
    }
    // A baseline is charged the header our clip of the same input carries.
    let header_of = |codec: &str| {
        rows.iter()
            .find(|r| r["codec"] == codec)
            .map(|r| r["header_bytes"].as_u64().unwrap())
            .unwrap()
    };
    assert!(header_of("index").abs_diff(header_of("quant+zstd")) <= 4);
    assert!(std::fs::read_to_string(&plot)
        .expect("plot")
        .contains("keyframe-linear"));

    // --baselines --summary: the totals only, every baseline after the codec.
    let o = mocap(&[
        "bench",
        bvh,
        "--baselines",
        "--summary",
        "--max-error",
        "20mm",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    let codecs: Vec<&str> = out
        .lines()
        .skip(2)
        .take_while(|l| !l.is_empty())
        .map(|l| l.split(" | ").nth(1).unwrap_or(""))
        .collect();
    assert_eq!(
        codecs,
        [
            "index",
            "raw16",
            "quant+zstd",
            "quant+xz",
            "keyframe-linear"
        ],
        "{out}"
    );
    // Then our smallest against the smallest tuned baseline.
    let versus = out.split("\n\n").nth(1).unwrap_or_else(|| panic!("{out}"));
    assert!(
        versus.starts_with(
            "| folder | bound | ours: smallest total bytes | best baseline (not raw16) | "
        ),
        "{out}"
    );
    assert_eq!(versus.lines().count(), 3, "{out}");
    assert!(versus.contains("| bench | 20mm | "), "{out}");
    assert!(!versus.contains("raw16 |"), "{out}");
}

/// `mocap encode --codec rma --plot`: the demo played twice keeps its
/// second playing as one repeated clip, and the picture says so; `--plot`
/// with another codec is refused with what to use instead.
#[test]
fn encode_rma_plots_the_analysis_and_the_kept_clips() {
    let d = out_dir("rma_plot");
    let (twice, clip, plot) = (
        d.join("twice.bvh"),
        d.join("twice.mcb"),
        d.join("twice.svg"),
    );
    let path = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let o = mocap(&[
        "generate",
        "long",
        "--from",
        "assets/animatronic_demo.bvh",
        "--frames",
        "960",
        "-o",
        &path(&twice),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = mocap(&[
        "encode",
        &path(&twice),
        "-o",
        &path(&clip),
        "--codec",
        "rma",
        "--max-error",
        "20mm",
        "--plot",
        &path(&plot),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("the clip keeps 1 repeated clip over"),
        "{}",
        text(&o.stderr)
    );
    let svg = std::fs::read_to_string(&plot).expect("plot");
    assert!(svg.contains("kept in the clip: 1 repeated clip "), "{svg}");
    let e = failure(&[
        "encode",
        "assets/animatronic_demo.bvh",
        "-o",
        &path(&clip),
        "--codec",
        "index",
        "--plot",
        &path(&plot),
    ]);
    assert!(
        e.contains("--plot draws the repeated-motion analysis of --codec rma"),
        "{e}"
    );
}

/// `--bound` is `--max-error` by the name the docs use (users typed it and
/// were offered `--budget`).
#[test]
fn bound_is_another_name_of_max_error() {
    let d = out_dir("bound_alias");
    let (a, b) = (d.join("a.mcb"), d.join("b.mcb"));
    for (flag, out) in [("--max-error", &a), ("--bound", &b)] {
        let o = mocap(&[
            "encode",
            "assets/animatronic_demo.bvh",
            "-o",
            out.to_str().unwrap(),
            flag,
            "2deg",
        ]);
        assert!(o.status.success(), "{flag}: {}", text(&o.stderr));
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

/// `mocap bench` reads a C3D marker file: marker rows at a length bound,
/// the angle bound skipped with a note.
#[test]
fn bench_reads_a_c3d_marker_file() {
    let d = out_dir("bench-c3d");
    let c3d = d.join("tiny.c3d");
    std::fs::write(&c3d, tiny_c3d()).expect("write");
    let o = mocap(&[
        "bench",
        c3d.to_str().unwrap(),
        "--codec",
        "predictive",
        "--codec",
        "keyframe-linear",
        "--max-error",
        "1deg",
        "--max-error",
        "2mm",
        "--summary",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("| bench-c3d | predictive | 2mm | 1 | 96 | "),
        "{out}"
    );
    assert!(
        out.contains("| bench-c3d | keyframe-linear | 2mm | 1 | 96 | "),
        "{out}"
    );
    assert!(!out.contains("1deg"), "{out}");
    assert!(
        text(&o.stderr).contains("skipped at 1deg: a marker clip has no rotation channels"),
        "{}",
        text(&o.stderr)
    );
}

/// `auto` taken from the three codecs' rows (when they are asked for too)
/// is the clip `auto` alone encodes: same codec, same bytes.
#[test]
fn bench_auto_from_the_codecs_rows_is_the_encoders_auto() {
    let d = out_dir("bench-auto");
    let bvh = d.join("tiny.bvh");
    std::fs::write(&bvh, tiny_bvh()).expect("write");
    let bvh = bvh.to_str().unwrap();
    let auto_row = |args: &[&str]| {
        let mut all = vec!["bench", bvh, "--max-error", "20mm"];
        all.extend_from_slice(args);
        let o = mocap(&all);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let out = text(&o.stdout);
        let row = out
            .lines()
            .find(|l| l.starts_with("| bench-auto | tiny.bvh | auto ("))
            .unwrap_or_else(|| panic!("{out}"))
            .to_string();
        // folder, file, codec (chosen), bound, frames×ch, bytes.
        row.split(" | ").take(6).collect::<Vec<_>>().join(" | ")
    };
    let alone = auto_row(&["--codec", "auto"]);
    let derived = auto_row(&[
        "--codec",
        "index",
        "--codec",
        "pca-spline",
        "--codec",
        "predictive",
        "--codec",
        "auto",
    ]);
    assert_eq!(alone, derived);
}

/// `mocap generate -o` writes the shipped demo byte for byte; `mocap
/// generate long` walks a take on to any length (here the demo, resampled
/// to 30 Hz), and its output encodes with no progress bar in a pipe.
#[test]
fn generate_the_demo_and_a_long_input() {
    let d = out_dir("generate");
    let demo = d.join("demo.bvh");
    let o = mocap(&["generate", "-o", demo.to_str().expect("utf-8 path")]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let shipped = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../assets/animatronic_demo.bvh"
    ))
    .expect("shipped demo");
    assert_eq!(std::fs::read(&demo).expect("demo"), shipped);

    let long = d.join("long.bvh");
    let long = long.to_str().expect("utf-8 path");
    let o = mocap(&[
        "generate",
        "long",
        "--from",
        "assets/animatronic_demo.bvh",
        "--frames",
        "1500",
        "--fps",
        "30",
        "-o",
        long,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("1500 frames at 30.0 Hz"));
    let text_bvh = std::fs::read_to_string(long).expect("long");
    assert!(text_bvh.contains("Frames: 1500\nFrame Time: 0.0333333"));

    let clip = d.join("long.mcb");
    let o = mocap(&[
        "encode",
        long,
        "-o",
        clip.to_str().expect("utf-8 path"),
        "--codec",
        "pca-spline",
        "--max-error",
        "50mm+arms:10mm",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // stderr is a pipe here: no bar, no control characters.
    assert!(!text(&o.stderr).contains('\r'), "{}", text(&o.stderr));

    let o = mocap(&[
        "generate",
        "long",
        "--from",
        "assets/animatronic_demo.bvh",
        "--frames",
        "10",
        "--skip",
        "480",
        "-o",
        long,
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("mocap: error: the take has 480 frames after skipping 480"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn encode_for_a_chip_keeps_the_smallest_clip_that_fits_the_budget() {
    let d = out_dir("target");
    let clip = d.join("demo_rp2040.mcb");
    let clip = clip.to_str().expect("utf-8 path");

    // A chip without a budget: today's default codec, its predicted cost printed.
    let o = mocap(&[
        "encode",
        "assets/animatronic_demo.bvh",
        "-o",
        clip,
        "--target",
        "rp2040",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains("rp2040 (M0, 133 MHz"), "{out}");
    assert!(
        out.contains("  index ") && out.contains("[chosen]"),
        "{out}"
    );

    // A budget: every codec tried, each line judged, the smallest that fits kept.
    let o = mocap(&[
        "encode",
        "assets/animatronic_demo.bvh",
        "-o",
        clip,
        "--target",
        "microbit",
        "--budget",
        "cpu=50%,ram=16k",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    for codec in ["index", "pca-spline", "predictive"] {
        assert!(out.contains(&format!("  {codec} ")), "{out}");
    }
    let chosen: Vec<&str> = out.lines().filter(|l| l.ends_with("[chosen]")).collect();
    assert_eq!(chosen.len(), 1, "{out}");
    let size = |l: &str| -> usize {
        l.split_whitespace()
            .nth(1)
            .and_then(|b| b.parse().ok())
            .unwrap_or(usize::MAX)
    };
    let fitting = out
        .lines()
        .filter(|l| l.ends_with("[chosen]") || l.ends_with("[fits]"))
        .map(size)
        .min();
    assert_eq!(Some(size(chosen[0])), fitting, "{out}");
    assert_eq!(
        std::fs::metadata(clip).expect("clip").len() as usize,
        size(chosen[0])
    );

    // The prediction of a clip already made.
    let o = mocap(&[
        "target", "cost", clip, "--target", "microbit", "--target", "esp32c3",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("\nmicrobit ") && out.contains("\nesp32c3 "),
        "{out}"
    );

    // Nothing fits a budget no clip can meet: an error saying what went over, no file.
    let none = d.join("none.mcb");
    let o = mocap(&[
        "encode",
        "assets/animatronic_demo.bvh",
        "-o",
        none.to_str().expect("utf-8"),
        "--target",
        "microbit",
        "--budget",
        "cpu=0.001%",
    ]);
    assert!(!o.status.success());
    assert!(text(&o.stdout).contains("over: cpu"), "{}", text(&o.stdout));
    assert!(
        text(&o.stderr)
            .contains("mocap: error: no codec's clip fits the microbit under budget cpu="),
        "{}",
        text(&o.stderr)
    );
    assert!(!none.exists());
}

/// The stderr of a `mocap` run that must fail.
fn failure(args: &[&str]) -> String {
    let o = mocap(args);
    assert!(!o.status.success(), "{args:?} succeeded");
    text(&o.stderr)
}

#[test]
fn target_and_budget_errors_name_what_is_wrong() {
    let demo = ["encode", "assets/animatronic_demo.bvh", "-o", "/dev/null"];
    for (extra, message) in [
        (
            &["--budget", "cpu=2%"][..],
            "mocap: error: --budget needs a chip as --target, not mcu (one of: microbit,",
        ),
        (
            &["--target", "esp32"],
            "mocap: error: unknown chip 'esp32' (known: microbit, lm3s6965,",
        ),
        (
            &["--target", "rp2040", "--budget", "gpu=2%"],
            "unknown budget 'gpu' (cpu, ram, flash)",
        ),
    ] {
        let err = failure(&[&demo[..], extra].concat());
        assert!(err.contains(message), "{extra:?}: {err}");
    }
    let o = mocap(&["target", "list"]);
    assert!(o.status.success());
    let out = text(&o.stdout);
    for chip in [
        "microbit",
        "lm3s6965",
        "mps2-an386",
        "riscv-virt",
        "rp2040",
        "stm32f411",
        "esp32c3",
    ] {
        assert!(out.contains(&format!("\n{chip} ")), "{out}");
    }
}
