//! `mocap view` end to end: the page of the shipped demo and its clip is one
//! self-contained file, a servo clip gets its curves page (alone, or with
//! its source and rig), and inputs that do not belong together (a clip of
//! another skeleton, a clip longer than its source, a servo clip without its
//! rig, a servo clip with another rig, a file that is no clip) fail with a
//! message that names the files, writing no page.
//! The page in a browser: `tests/tests/view_browser.rs`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

fn mocap_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mocap"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run mocap")
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn view_writes_one_self_contained_page() {
    let d = out_dir("view-demo");
    let bvh = root().join("assets/animatronic_demo.bvh");
    let clip = root().join("firmware-example/clips/demo.mcb");
    let o = mocap_in(&d, &["view", s(&bvh), s(&clip)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // Default name: the input's stem + .html, in the current folder.
    let page = std::fs::read_to_string(d.join("animatronic_demo.html")).expect("page");
    let err = text(&o.stderr);
    assert!(
        err.starts_with(&format!(
            "wrote animatronic_demo.html ({} bytes; 480 frames × ",
            page.len()
        )),
        "{err}"
    );
    assert!(err.contains("the page's worst frame"), "{err}");
    assert!(page.starts_with("<!DOCTYPE html>"));
    // Self-contained: nothing fetched from elsewhere.
    for outside in [
        "<script src",
        "<link",
        "http://",
        "https://",
        "@import",
        "url(",
    ] {
        assert!(
            !page.contains(outside),
            "page refers outside itself: {outside}"
        );
    }
    assert!(page.contains(r#""clip":"demo.mcb""#));
    assert!(page.contains(r#""worstFrame":"#));

    // The BVH alone, named by -o.
    let o = mocap_in(&d, &["view", s(&bvh), "-o", "alone.html", "--units", "cm"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let alone = std::fs::read_to_string(d.join("alone.html")).expect("page");
    assert!(alone.contains(r#""clip":null"#) && alone.contains(r#""unit":"cm""#));
}

/// The demo BVH with `edit` applied to its text, written to `dir/name`.
fn edited_demo(dir: &Path, name: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let src = std::fs::read_to_string(root().join("assets/animatronic_demo.bvh")).expect("demo");
    let p = dir.join(name);
    std::fs::write(&p, edit(&src)).expect("write");
    p
}

/// `mocap encode --rig assets/rigs/animatronic_demo.toml --max-error 0.5deg`
/// of the demo, written to `dir/servo.mcb`.
fn demo_servo_clip(dir: &Path) -> PathBuf {
    let demo = root().join("assets/animatronic_demo.bvh");
    let rig = root().join("assets/rigs/animatronic_demo.toml");
    let servo = dir.join("servo.mcb");
    let args = [
        "encode",
        "--rig",
        s(&rig),
        "--max-error",
        "0.5deg",
        s(&demo),
        "-o",
        s(&servo),
    ];
    let o = mocap_in(dir, &args);
    assert!(o.status.success(), "{}", text(&o.stderr));
    servo
}

#[test]
fn view_refuses_what_does_not_belong_together() {
    let d = out_dir("view-errors");
    let clip = root().join("firmware-example/clips/demo.mcb");
    let expect_error = |args: &[&str], message: &str| {
        let o = mocap_in(&d, args);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_eq!(
            text(&o.stderr),
            format!("mocap: error: {message}\n"),
            "{args:?}"
        );
    };

    // A source cut to 100 frames: the clip is longer.
    let short = edited_demo(&d, "short.bvh", |t| {
        let (head, motion) = t.split_once("Frame Time:").unwrap();
        let mut lines = motion.lines();
        let time = lines.next().unwrap();
        let frames: Vec<&str> = lines.take(100).collect();
        format!(
            "{}Frame Time:{time}\n{}\n",
            head.replace("Frames: 480", "Frames: 100"),
            frames.join("\n")
        )
    });
    let channels: usize = std::fs::read_to_string(&short)
        .unwrap()
        .lines()
        .filter_map(|l| l.trim().strip_prefix("CHANNELS "))
        .map(|c| {
            c.split_whitespace()
                .next()
                .unwrap()
                .parse::<usize>()
                .unwrap()
        })
        .sum();
    let v = ["view", s(&short), s(&clip), "-o", "x.html"];
    expect_error(
        &v,
        &format!(
            "{} does not play against {}: it has 480 frames × {channels} channels but the source has 100 × {channels}",
            s(&clip),
            s(&short)
        ),
    );
    // `mocap eval` says the same.
    expect_error(
        &["eval", s(&short), s(&clip)],
        &format!(
            "{} does not play against {}: it has 480 frames × {channels} channels but the source has 100 × {channels}",
            s(&clip),
            s(&short)
        ),
    );

    // Another skeleton: a longer torso.
    let other = edited_demo(&d, "other.bvh", |t| {
        t.replacen("OFFSET 0 72 0", "OFFSET 0 80 0", 1)
    });
    expect_error(
        &["view", s(&other), s(&clip), "-o", "x.html"],
        &format!(
            "{} does not play against {}: its skeleton differs from the source's at joint 1 (Torso): offset",
            s(&clip),
            s(&other)
        ),
    );

    // A servo clip of the demo.
    let (demo, servo) = (
        root().join("assets/animatronic_demo.bvh"),
        demo_servo_clip(&d),
    );
    expect_error(
        &["view", s(&demo), s(&servo), "-o", "x.html"],
        &format!(
            "{} does not play against {}: it is a servo clip (servo pulses, not the source's {} channels)",
            s(&servo),
            s(&demo),
            channels
        ),
    );

    // Not a clip at all.
    let junk = d.join("junk.mcb");
    std::fs::write(&junk, b"not a clip").unwrap();
    let o = mocap_in(&d, &["view", s(&demo), s(&junk), "-o", "x.html"]);
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).starts_with(&format!("mocap: error: {}: ", s(&junk))),
        "{}",
        text(&o.stderr)
    );
    assert!(!d.join("x.html").exists(), "a page was written");
}

#[test]
fn view_a_servo_clip_alone_and_with_its_source() {
    let d = out_dir("view-servo");
    let demo = root().join("assets/animatronic_demo.bvh");
    let rig = root().join("assets/rigs/animatronic_demo.toml");
    let wide = root().join("assets/rigs/animatronic_demo_wide.toml");
    let servo = demo_servo_clip(&d);

    // Alone: the clip's own rig table; default name from the clip.
    let o = mocap_in(&d, &["view", s(&servo)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.starts_with("wrote servo.html ("), "{err}");
    assert!(err.contains("12 servos × "), "{err}");
    let page = std::fs::read_to_string(d.join("servo.html")).expect("page");
    assert!(page.contains(r#""kind":"servo""#) && page.contains(r#""sourcePulses":null"#));

    // With its source and rig: the rig's names and signals.
    let with_rig = |rig: &Path, out: &str| {
        mocap_in(
            &d,
            &["view", s(&demo), s(&servo), "--rig", s(rig), "-o", out],
        )
    };
    let o = with_rig(&rig, "with.html");
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("largest pulse difference, decoded against the source: "));
    let page = std::fs::read_to_string(d.join("with.html")).expect("page");
    assert!(page.contains(r#""name":"torso_twist""#) && page.contains(r#""sourcePulses":[["#));

    // Another rig (same servos, wider ranges): refused by the clip's rig digest.
    let o = with_rig(&wide, "x.html");
    assert!(!o.status.success());
    assert_eq!(
        text(&o.stderr),
        format!(
            "mocap: error: {} does not play against {}: the clip was encoded for another rig\n",
            s(&servo),
            s(&wide)
        )
    );
    // A motion clip viewed as a servo clip.
    let motion = root().join("firmware-example/clips/demo.mcb");
    let o = mocap_in(&d, &["view", s(&motion), "-o", "x.html"]);
    assert_eq!(
        text(&o.stderr),
        format!(
            "mocap: error: {}: not a servo clip (give its source BVH first to view a motion clip)\n",
            s(&motion)
        )
    );
    assert!(!d.join("x.html").exists(), "a page was written");
}

#[test]
fn view_a_show() {
    let d = out_dir("view-show");
    let show = root().join("firmware-example/clips/demo_show.mcb");
    let cues = root().join("assets/shows/demo_cues.txt");
    let o = mocap_in(&d, &["view", s(&show), "--cues", s(&cues)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.starts_with("wrote demo_show.html ("), "{err}");
    assert!(err.contains("12 servos × "), "{err}");
    let page = std::fs::read_to_string(d.join("demo_show.html")).expect("page");
    assert!(page.contains(r#""kind":"show""#) && page.contains(r#""name":"greet""#));
    // A show with a clip beside it.
    let clip = root().join("firmware-example/clips/demo.mcb");
    let o = mocap_in(&d, &["view", s(&show), s(&clip), "-o", "x.html"]);
    assert_eq!(
        text(&o.stderr),
        format!("mocap: error: {}: a show is viewed alone\n", s(&show))
    );
    assert!(!d.join("x.html").exists());
}
