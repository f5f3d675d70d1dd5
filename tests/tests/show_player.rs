//! The show player (SPEC.md §9.4) on shows built by `mocap_encoder::show`
//! from synthetic motion: a clip alone plays as its `Player` does, blends
//! start and end on the clips' own poses and never jump, a transition that
//! interrupts another keeps the pose, loops run forever across their seams,
//! `hold` freezes time, queued clips end their fade at the current clip's
//! end, angles blend the short way round, and every value is independent
//! of how often the player is sampled.

use std::path::PathBuf;

use mocap_decoder::{Player, Show, State};
use mocap_encoder::motion::{ChannelKind, Joint, Motion, Skeleton};
use mocap_encoder::show::{self, file::ShowSpec, HostShowPlayer};

/// A temporary folder of this test process.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mocap-show-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// One root joint with `Zrotation` and `Xrotation`, 100 Hz, `frames`
/// frames of `f(frame)` degrees.
fn motion(frames: usize, f: impl Fn(usize) -> [f64; 2]) -> Motion {
    Motion {
        skeleton: Skeleton {
            joints: vec![Joint {
                name: "J".into(),
                parent: None,
                offset: [0.0; 3],
                channels: vec![ChannelKind::Zrotation, ChannelKind::Xrotation],
                end_site: false,
            }],
        },
        frame_time: 0.01,
        values: (0..frames).flat_map(f).collect(),
    }
}

/// A show of `clips` (name, motion, `loop` value or "") with `extra` TOML.
fn build(name: &str, clips: &[(&str, Motion, &str)], extra: &str) -> Vec<u8> {
    let d = dir(name);
    let mut toml =
        format!("[show]\nname = \"{name}\"\nmax_error = \"0.1deg\"\nfade_ms = 200\n{extra}\n");
    for (clip, m, looping) in clips {
        let path = d.join(format!("{clip}.bvh"));
        mocap_encoder::bvh::write_file(m, &path).unwrap();
        toml += &format!("[[clip]]\nname = \"{clip}\"\nfile = \"{clip}.bvh\"\nunits = \"cm\"\n");
        if !looping.is_empty() {
            toml += &format!("loop = {looping}\n");
        }
    }
    let spec = ShowSpec::parse(&toml, "test.toml", &d).unwrap();
    show::build(&spec).unwrap().bytes
}

fn wave(frames: usize, amp: f64, period: f64, phase: f64) -> Motion {
    motion(frames, |i| {
        let x = i as f64 / period * std::f64::consts::TAU + phase;
        [amp * x.sin(), amp * 0.5 * x.cos()]
    })
}

fn sample(p: &mut HostShowPlayer<'_>, t: u64) -> Vec<i32> {
    let mut out = vec![0; 2];
    p.sample(t, &mut out).unwrap();
    out
}

fn player(bytes: &[u8]) -> Box<HostShowPlayer<'_>> {
    Box::new(HostShowPlayer::new(Show::parse(bytes).unwrap()).unwrap())
}

#[test]
fn a_clip_alone_plays_as_its_player() {
    let bytes = build(
        "alone",
        &[
            ("a", wave(150, 30.0, 80.0, 0.0), ""),
            ("b", wave(90, 10.0, 40.0, 1.0), ""),
        ],
        "",
    );
    let show = Show::parse(&bytes).unwrap();
    let mut p = player(&bytes);
    p.play(1, 5_000).unwrap();
    let clip = show.clip(1).unwrap();
    let mut single = Player::<64>::new(&clip).unwrap();
    let mut want = vec![0; 2];
    for t in (5_000..1_200_000).step_by(3_331) {
        single.sample_at(t - 5_000, &mut want).unwrap();
        assert_eq!(sample(&mut p, t), want, "t = {t}");
    }
    assert_eq!(p.state(), State::Ended);
}

#[test]
fn a_crossfade_starts_and_ends_on_the_clips_and_never_jumps() {
    let bytes = build(
        "fade",
        &[
            ("a", wave(300, 40.0, 100.0, 0.0), ""),
            ("b", wave(300, 60.0, 70.0, 2.0), ""),
        ],
        "",
    );
    let show = Show::parse(&bytes).unwrap();
    let (mut a, mut b) = (
        Player::<64>::new(&show.clip(0).unwrap()).unwrap(),
        Player::<64>::new(&show.clip(1).unwrap()).unwrap(),
    );
    let mut p = player(&bytes);
    p.play(0, 0).unwrap();
    let (start, dur) = (500_000, 400_000);
    p.crossfade_to(1, dur, start).unwrap();
    let mut w = vec![0; 2];
    a.sample_at(start, &mut w).unwrap();
    assert_eq!(
        sample(&mut p, start),
        w,
        "the blend starts on the outgoing clip"
    );
    b.sample_at(dur, &mut w).unwrap();
    assert_eq!(
        sample(&mut p, start + dur),
        w,
        "and ends on the incoming one"
    );
    assert_eq!(p.state(), State::Playing);
    // Steps at 1 ms: never more than either clip's step plus the blend's
    // own share, 1.5·|b − a|/T per ms (smoothstep's slope is at most 1.5).
    let mut prev = sample(&mut p, start - 1_000);
    let mut worst = 0i64;
    for t in (start..start + dur + 10_000).step_by(1_000) {
        let now = sample(&mut p, t);
        for (x, y) in prev.iter().zip(&now) {
            worst = worst.max(i64::from(y - x).abs());
        }
        prev = now;
    }
    // 60° at 2π/70 per frame of 10 ms: ≈ 0.54° per ms; the blend adds at
    // most 1.5 · 100° / 400 ms ≈ 0.38° per ms.
    assert!(worst < 1_000, "largest step per ms {worst} mdeg");
}

#[test]
fn an_interrupted_transition_keeps_the_pose() {
    let bytes = build(
        "interrupt",
        &[
            ("a", wave(300, 40.0, 100.0, 0.0), ""),
            ("b", wave(300, 60.0, 70.0, 2.0), ""),
            ("c", wave(300, 20.0, 50.0, 4.0), ""),
        ],
        "",
    );
    let mut p = player(&bytes);
    p.play(0, 0).unwrap();
    p.crossfade_to(1, 400_000, 300_000).unwrap();
    let t = 450_000;
    let earlier = sample(&mut p, t - 1_000);
    let before = sample(&mut p, t);
    p.crossfade_to(2, 300_000, t).unwrap();
    let after = sample(&mut p, t);
    assert_eq!(
        after, before,
        "the new transition starts on the pose of its moment"
    );
    // And with its velocity: the step in the ms after the interrupt is the
    // step in the ms before it, within the 10 ms secant's difference.
    let next = sample(&mut p, t + 1_000);
    for c in 0..2 {
        let (v0, v1) = (before[c] - earlier[c], next[c] - after[c]);
        assert!(
            (v1 - v0).abs() <= v0.abs() / 5 + 30,
            "channel {c}: {v0} then {v1} mdeg/ms"
        );
    }
    assert_eq!(p.state(), State::Blending);
    sample(&mut p, t + 400_000);
    assert_eq!(p.state(), State::Playing);
}

#[test]
fn a_loop_runs_on_across_its_seams() {
    // Not cyclic: the end pose differs from the start by 30°.
    let m = motion(200, |i| {
        [30.0 * i as f64 / 199.0, 5.0 * (i as f64 / 20.0).sin()]
    });
    let bytes = build("loop", &[("a", m, "true")], "");
    let show = Show::parse(&bytes).unwrap();
    let l = show.entry(0).unwrap().looping.unwrap();
    assert_eq!((l.start, l.end), (0, 199));
    assert!(l.seam > 0 && l.seam < 199);
    // The clip's own largest frame-to-frame step, any channel.
    let mut single = Player::<64>::new(&show.clip(0).unwrap()).unwrap();
    let (mut a, mut b) = (vec![0; 2], vec![0; 2]);
    let mut own = 0;
    single.frame(0, &mut a).unwrap();
    for f in 1..200 {
        single.frame(f, &mut b).unwrap();
        own = own.max((b[0] - a[0]).abs()).max((b[1] - a[1]).abs());
        std::mem::swap(&mut a, &mut b);
    }
    let mut p = player(&bytes);
    p.play(0, 0).unwrap();
    let mut prev = sample(&mut p, 0);
    let mut worst = 0;
    for t in (10_000..10_000_000u64).step_by(10_000) {
        let now = sample(&mut p, t);
        worst = worst
            .max((now[0] - prev[0]).abs())
            .max((now[1] - prev[1]).abs());
        prev = now;
        assert!(
            matches!(p.state(), State::Playing | State::Blending),
            "t = {t}"
        );
    }
    // The end pose is 30° from the start, yet the encoder lengthened the
    // seam until no step across it exceeds the clip's own.
    assert!(
        worst <= own,
        "largest step {worst} mdeg, the clip's own {own}"
    );
}

#[test]
fn hold_freezes_time_and_resume_goes_on() {
    let bytes = build("hold", &[("a", wave(300, 40.0, 100.0, 0.0), "")], "");
    let mut p = player(&bytes);
    let mut q = player(&bytes);
    p.play(0, 0).unwrap();
    q.play(0, 0).unwrap();
    let at = sample(&mut p, 700_000);
    p.hold(700_000).unwrap();
    assert_eq!(sample(&mut p, 900_000), at);
    assert_eq!(p.state(), State::Held);
    p.resume(1_000_000).unwrap();
    // 300 ms later on the show clock, the clip is where it was.
    assert_eq!(sample(&mut p, 1_000_000), at);
    assert_eq!(sample(&mut p, 1_500_000), sample(&mut q, 1_200_000));
}

#[test]
fn a_queued_clip_ends_its_fade_at_the_current_clips_end() {
    let bytes = build(
        "queue",
        &[
            ("a", wave(100, 40.0, 100.0, 0.0), ""),
            ("b", wave(300, 60.0, 70.0, 2.0), ""),
        ],
        "",
    );
    let show = Show::parse(&bytes).unwrap();
    let mut b = Player::<64>::new(&show.clip(1).unwrap()).unwrap();
    let mut p = player(&bytes);
    p.play(0, 0).unwrap();
    p.queue(1, 100_000).unwrap();
    // `a` ends at 990 ms; the fade (200 ms) starts at 790 ms.
    sample(&mut p, 789_000);
    assert_eq!(p.state(), State::Playing);
    sample(&mut p, 800_000);
    assert_eq!(p.state(), State::Blending);
    let mut w = vec![0; 2];
    b.sample_at(1_000_000 - 790_000, &mut w).unwrap();
    assert_eq!(sample(&mut p, 1_000_000), w);
}

#[test]
fn angles_blend_the_short_way_round() {
    let bytes = build(
        "wrap",
        &[
            ("a", motion(50, |_| [170.0, 0.0]), ""),
            ("b", motion(50, |_| [-170.0, 0.0]), ""),
        ],
        "",
    );
    let mut p = player(&bytes);
    p.play(0, 0).unwrap();
    p.crossfade_to(1, 200_000, 100_000).unwrap();
    let mid = sample(&mut p, 200_000)[0];
    assert!(
        mid.rem_euclid(360_000) > 170_000 && mid.rem_euclid(360_000) < 190_000,
        "{mid}"
    );
}

#[test]
fn values_do_not_depend_on_the_sampling_rate() {
    let bytes = build(
        "rate",
        &[
            ("a", wave(300, 40.0, 100.0, 0.0), ""),
            ("b", wave(300, 60.0, 70.0, 2.0), "true"),
            ("c", wave(200, 20.0, 50.0, 4.0), ""),
        ],
        "",
    );
    let script = |p: &mut HostShowPlayer<'_>, t: u64| match t {
        0 => p.play(0, 0).unwrap(),
        400_000 => p.crossfade_to(1, 300_000, t).unwrap(),
        600_000 => p.crossfade_to(2, 300_000, t).unwrap(),
        1_500_000 => p.queue(1, t).unwrap(),
        _ => {}
    };
    let (mut fast, mut slow) = (player(&bytes), player(&bytes));
    let mut at_fast = std::collections::BTreeMap::new();
    for t in (0..6_000_000u64).step_by(1_000) {
        script(&mut fast, t);
        at_fast.insert(t, sample(&mut fast, t));
    }
    for t in (0..6_000_000u64).step_by(1_000) {
        script(&mut slow, t);
        // 50 Hz: sample only every 20 ms.
        if t % 20_000 == 0 {
            assert_eq!(sample(&mut slow, t), at_fast[&t], "t = {t}");
        }
    }
}

/// `pattern` clips of one bound share one database (SPEC.md §11.2): one
/// model section that every such clip reads, stored once, so a show of a
/// repeated movement costs less than its clips as single files.
#[test]
fn pattern_clips_share_one_database() {
    let d = dir("pattern");
    let mut toml =
        String::from("[show]\nname = \"p\"\nmax_error = \"0.1deg\"\ncodec = \"pattern\"\n");
    for (clip, m) in [
        ("a", wave(400, 30.0, 80.0, 0.0)),
        ("b", wave(400, 30.0, 80.0, 0.0)),
        ("c", wave(300, 20.0, 50.0, 1.0)),
    ] {
        mocap_encoder::bvh::write_file(&m, &d.join(format!("{clip}.bvh"))).unwrap();
        toml += &format!("[[clip]]\nname = \"{clip}\"\nfile = \"{clip}.bvh\"\nunits = \"cm\"\n");
    }
    let spec = ShowSpec::parse(&toml, "test.toml", &d).unwrap();
    let built = show::build(&spec).unwrap();
    let s = Show::parse(&built.bytes).unwrap();
    let models: Vec<u16> = (0..s.section_count())
        .filter(|&i| s.sections().nth(usize::from(i)).unwrap().0 == 0x20)
        .collect();
    assert_eq!(models.len(), 1, "one database");
    for i in 0..s.clip_count() {
        let e = s.entry(i).unwrap();
        assert_eq!(e.model_count, 1);
        assert_eq!(e.models[0], models[0]);
        // Every clip plays (the build checked each against its single clip).
        let clip = s.clip(i).unwrap();
        let mut p = Player::<8>::new(&clip).unwrap();
        let mut out = [0i32; 2];
        while p.next_frame(&mut out).unwrap().is_some() {}
    }
    assert!(
        built.bytes.len() * 10 < built.singles_bytes() * 7,
        "{} bytes against {} as single files",
        built.bytes.len(),
        built.singles_bytes()
    );
}

/// A show file's `pattern_nodes` sets the pattern codec's body-part nodes
/// (issue: the hierarchy is overridable in the show file): the given nodes
/// come first in the shared database, the joints in none keep their limbs;
/// a joint the skeleton lacks is an error that names it.
#[test]
fn pattern_nodes_in_the_show_file_set_the_database_nodes() {
    let d = dir("pattern-nodes");
    let demo = mocap_tests::workspace_root().join("assets/animatronic_demo.bvh");
    let show = |nodes: &str| {
        format!(
            "[show]\nname = \"p\"\nmax_error = \"1deg\"\ncodec = \"pattern\"\npattern_nodes = {nodes}\n\
             [[clip]]\nname = \"a\"\nfile = \"{f}\"\nto = \"2s\"\n\
             [[clip]]\nname = \"b\"\nfile = \"{f}\"\nfrom = \"4s\"\nto = \"6s\"\n",
            f = demo.display()
        )
    };
    let nodes_of = |toml: &str| {
        let spec = ShowSpec::parse(toml, "test.toml", &d).unwrap();
        let built = show::build(&spec).unwrap();
        let b = &built.bytes;
        // The container's section table (SPEC.md §2.2): the model section.
        let count = usize::from(u16::from_le_bytes([b[6], b[7]]));
        let word = |at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
        let e = (0..count)
            .map(|i| 8 + 12 * i)
            .find(|&e| word(e) == 0x20)
            .unwrap();
        let db = b[word(e + 4)..word(e + 4) + word(e + 8)].to_vec();
        mocap_encoder::codec::pattern::inspect_database(&db)
            .unwrap()
            .nodes
            .iter()
            .map(|n| n[0])
            .collect::<Vec<usize>>()
    };
    let default = nodes_of(&show("[]").replace("pattern_nodes = []\n", ""));
    // Both arms in one node, the head and jaw in another.
    let given = nodes_of(&show(
        r#"[["LeftShoulder", "LeftUpperArm", "LeftForeArm", "LeftHand", "RightShoulder", "RightUpperArm", "RightForeArm", "RightHand"], ["Head", "Jaw"]]"#,
    ));
    assert_ne!(given, default);
    assert_eq!(given.iter().sum::<usize>(), default.iter().sum::<usize>());
    let demo_m = mocap_encoder::bvh::read_file(&demo).unwrap();
    let chans = |names: &[&str]| {
        let joint_of = demo_m.skeleton.channel_joints();
        joint_of
            .iter()
            .filter(|&&j| names.contains(&demo_m.skeleton.joints[j].name.as_str()))
            .count()
    };
    assert_eq!(
        given[0],
        chans(&[
            "LeftShoulder",
            "LeftUpperArm",
            "LeftForeArm",
            "LeftHand",
            "RightShoulder",
            "RightUpperArm",
            "RightForeArm",
            "RightHand"
        ])
    );
    assert_eq!(given[1], chans(&["Head", "Jaw"]));
    let spec = ShowSpec::parse(&show(r#"[["Head", "Tail"]]"#), "test.toml", &d).unwrap();
    let err = show::build(&spec).unwrap_err().to_string();
    assert!(err.contains("'Tail'"), "{err}");
    let empty = ShowSpec::parse(&show(r#"[["Head"], []]"#), "test.toml", &d).unwrap_err();
    assert!(empty.to_string().contains("pattern_nodes"), "{empty}");
}
