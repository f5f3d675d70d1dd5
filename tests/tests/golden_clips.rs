//! Golden clips: one committed clip per codec and form (`tests/golden/*.mcb`)
//! and its expected decoded output (`tests/golden/*.out`). The encoder must
//! write exactly the committed bytes today, and the decoder must decode the
//! committed bytes to exactly the committed output (every frame in order,
//! random access, `sample_at` at 50 Hz, servo pulses). A format, encoder or
//! decoder change fails here until the files are regenerated on purpose:
//!
//! ```sh
//! MOCAP_BLESS=1 cargo test --release -p mocap-tests --test golden_clips
//! ```
//!
//! The corpus cases (`tests/golden/corpus.txt`) pin digests of clips encoded
//! from the real data, which is not copied into the repository.

use mocap_decoder::{Clip, Player};
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::motion::Motion;
use mocap_encoder::rig::Rig;
use mocap_encoder::servo_clip::{self, ServoEncodeOptions, ServoNames, ServoRate};
use mocap_encoder::{bvh, units};
use mocap_tests::{corpus_file, workspace_root};
use std::fmt::Write as _;
use std::path::PathBuf;

const CRC64: crc::Crc<u64> = crc::Crc::<u64>::new(&crc::CRC_64_ECMA_182);

fn golden_dir() -> PathBuf {
    workspace_root().join("tests/golden")
}

fn bless() -> bool {
    std::env::var_os("MOCAP_BLESS").is_some_and(|v| v != "0")
}

fn bound(specs: &[&str]) -> Bound {
    let specs: Vec<BoundSpec> = specs.iter().map(|s| s.parse().unwrap()).collect();
    Bound::from_specs(&specs)
}

fn motion_clip(m: &Motion, codec: CodecChoice, specs: &[&str]) -> Vec<u8> {
    motion_clip_layout(m, codec, specs, Default::default())
}

fn motion_clip_layout(
    m: &Motion,
    codec: CodecChoice,
    specs: &[&str],
    index_layout: mocap_encoder::codec::index::IndexLayout,
) -> Vec<u8> {
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: bound(specs),
        metres_per_unit: units::detect(m).metres(),
        key_interval: None,
        index_layout,
        pattern: Default::default(),
    };
    encode::encode(m, &opts).unwrap().bytes
}

fn servo_clip_bytes(m: &Motion, rig_file: &str, codec: CodecChoice, specs: &[&str]) -> Vec<u8> {
    let rig = Rig::read_file(&workspace_root().join(rig_file)).unwrap();
    let channels = rig.resolve(&m.skeleton).unwrap();
    let tracks = rig.servo_tracks(m, &channels, units::detect(m).metres());
    let opts = ServoEncodeOptions {
        codec,
        bound: bound(specs),
        key_interval: None,
        rate: ServoRate::Rig,
        names: ServoNames::Strip,
    };
    servo_clip::encode_servo_clip(&rig, &tracks, &opts)
        .unwrap()
        .bytes
}

fn demo() -> Motion {
    bvh::read_file(&workspace_root().join("assets/animatronic_demo.bvh")).unwrap()
}

fn join(v: &[i32]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Everything the decoder makes of `bytes`, as text: a summary with digests
/// of every access path, then the first two and the last frame in full.
fn decoded_report(bytes: &[u8]) -> String {
    let clip = Clip::parse(bytes).unwrap();
    let mut player = Player::<1024>::new(&clip).unwrap();
    let n = player.channel_count();
    let frames = player.frame_count();
    let mut out = vec![0i32; n];
    let mut all: Vec<Vec<i32>> = Vec::new();
    while player.next_frame(&mut out).unwrap().is_some() {
        all.push(out.clone());
    }
    assert_eq!(all.len(), frames as usize);
    let digest = |rows: &[Vec<i32>]| {
        let mut d = CRC64.digest();
        for r in rows {
            for v in r {
                d.update(&v.to_le_bytes());
            }
        }
        d.finalize()
    };
    // Random access in a fixed scrambled order must give the same frames.
    let mut random = Vec::new();
    let mut i = 0u32;
    for _ in 0..frames.min(200) {
        i = (i.wrapping_mul(7919).wrapping_add(104_729)) % frames.max(1);
        player.frame(i, &mut out).unwrap();
        assert_eq!(&out, &all[i as usize], "frame({i}) differs from next_frame");
        random.push(out.clone());
    }
    // sample_at at 50 Hz over the whole clip and a little past it.
    let mut samples = Vec::new();
    let dur = clip.header().duration_us();
    let mut t = 0u64;
    while t <= dur + 40_000 {
        player.sample_at(t, &mut out).unwrap();
        samples.push(out.clone());
        t += 20_000;
    }
    let mut s = String::new();
    writeln!(
        s,
        "codec 0x{:02x}, {} bytes, {} frames, {} channels, duration {} us",
        clip.codec_id(),
        bytes.len(),
        frames,
        n,
        dur
    )
    .unwrap();
    writeln!(s, "bytes crc64 {:016x}", CRC64.checksum(bytes)).unwrap();
    writeln!(s, "next_frame crc64 {:016x}", digest(&all)).unwrap();
    writeln!(s, "frame(i) crc64 {:016x}", digest(&random)).unwrap();
    writeln!(
        s,
        "sample_at 50 Hz ({} samples) crc64 {:016x}",
        samples.len(),
        digest(&samples)
    )
    .unwrap();
    if let Some(rig) = clip.rig() {
        let pulses: Vec<Vec<i32>> = samples
            .iter()
            .map(|row| {
                rig.servos()
                    .zip(row)
                    .map(|(sv, &a)| i32::from(sv.pulse_qus(a)))
                    .collect()
            })
            .collect();
        writeln!(s, "pulses at 50 Hz (qus) crc64 {:016x}", digest(&pulses)).unwrap();
        if let Some(first) = pulses.first() {
            writeln!(s, "pulses t=0: {}", join(first)).unwrap();
        }
    }
    for (k, row) in all.iter().enumerate() {
        if k < 2 || k + 1 == all.len() {
            writeln!(s, "frame {k}: {}", join(row)).unwrap();
        }
    }
    s
}

/// A readable line diff of two texts.
fn diff(expected: &str, actual: &str) -> String {
    let (e, a): (Vec<_>, Vec<_>) = (expected.lines().collect(), actual.lines().collect());
    let mut d = String::new();
    for i in 0..e.len().max(a.len()) {
        match (e.get(i), a.get(i)) {
            (Some(x), Some(y)) if x == y => {}
            (x, y) => {
                if let Some(x) = x {
                    writeln!(d, "- {x}").unwrap();
                }
                if let Some(y) = y {
                    writeln!(d, "+ {y}").unwrap();
                }
            }
        }
    }
    d
}

/// Checks (or, with `MOCAP_BLESS`, writes) one golden case: the encoder's
/// bytes against `<name>.mcb`, the decoded committed bytes against
/// `<name>.out`.
fn check_case(name: &str, made: &[u8]) {
    let mcb = golden_dir().join(format!("{name}.mcb"));
    let out = golden_dir().join(format!("{name}.out"));
    if bless() {
        std::fs::create_dir_all(golden_dir()).unwrap();
        std::fs::write(&mcb, made).unwrap();
        std::fs::write(&out, decoded_report(made)).unwrap();
        return;
    }
    let committed = std::fs::read(&mcb).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; make it with MOCAP_BLESS=1 (header of this file)",
            mcb.display()
        )
    });
    let expected = std::fs::read_to_string(&out).unwrap();
    let actual = decoded_report(&committed);
    assert!(
        expected == actual,
        "{}: the decoder's output of the committed clip changed:\n{}\
         (regenerate on purpose with MOCAP_BLESS=1)",
        out.display(),
        diff(&expected, &actual)
    );
    assert!(
        made == committed.as_slice(),
        "{}: the encoder now writes other bytes ({} B, committed {} B):\n{}\
         (regenerate on purpose with MOCAP_BLESS=1)",
        mcb.display(),
        made.len(),
        committed.len(),
        diff(&expected, &decoded_report(made))
    );
}

#[test]
fn golden_index_clip() {
    check_case(
        "index_demo_1deg",
        &motion_clip(&demo(), CodecChoice::Index, &["1deg"]),
    );
}

/// `index` in its fast layout (SPEC.md §4.6, section `0x13`): the demo,
/// and the far-travelled demo whose key frames are in levels (§4.5).
#[test]
fn golden_index_fast_clips() {
    use mocap_encoder::codec::index::IndexLayout;
    let fast = |m: &Motion| motion_clip_layout(m, CodecChoice::Index, &["1deg"], IndexLayout::Fast);
    let bytes = fast(&demo());
    assert!(Clip::parse(&bytes)
        .unwrap()
        .sections()
        .any(|s| s.id == 0x13));
    check_case("index_fast_demo_1deg", &bytes);
    check_case(
        "index_fast_levels_far_demo_1deg",
        &fast(&mocap_tests::far_travelled_demo()),
    );
}

/// The demo sent 150 m and 200 turns away: `index` codes its key frames
/// in levels (SPEC.md §4.5).
#[test]
fn golden_index_levels_clip() {
    let m = mocap_tests::far_travelled_demo();
    let bytes = motion_clip(&m, CodecChoice::Index, &["1deg"]);
    let info = mocap_encoder::codec::describe_section(
        0x10,
        Clip::parse(&bytes)
            .unwrap()
            .sections()
            .find(|s| s.id == 0x10)
            .unwrap()
            .bytes,
        Clip::parse(&bytes).unwrap().header(),
        false,
    )
    .unwrap();
    assert!(info.contains("key frames in levels"), "{info}");
    check_case("index_levels_far_demo_1deg", &bytes);
}

#[test]
fn golden_pca_spline_clip() {
    let m = demo();
    check_case(
        "pca_spline_demo_20mm",
        &motion_clip(&m, CodecChoice::PcaSpline, &["20mm"]),
    );
}

#[test]
fn golden_predictive_clip() {
    check_case(
        "predictive_demo_1deg",
        &motion_clip(&demo(), CodecChoice::Predictive, &["1deg"]),
    );
}

/// `pattern` (SPEC.md §11): the demo at 20 mm, its database in the section.
#[test]
fn golden_pattern_clip() {
    check_case(
        "pattern_demo_20mm",
        &motion_clip(&demo(), CodecChoice::Pattern, &["20mm"]),
    );
}

/// `rma` (SPEC.md §12): the demo played twice at 20 mm — its second
/// playing one repeated clip referring to the first (two knots) — and the
/// demo alone, where no repetition pays (the empty plan before a body).
#[test]
fn golden_rma_clips() {
    let once = demo();
    let mut twice = once.clone();
    twice.values.extend_from_slice(&once.values);
    check_case(
        "rma_demo_twice_20mm",
        &motion_clip(&twice, CodecChoice::Rma, &["20mm"]),
    );
    check_case(
        "rma_demo_20mm",
        &motion_clip(&once, CodecChoice::Rma, &["20mm"]),
    );
}

#[test]
fn golden_servo_clips() {
    let m = demo();
    let rig = "assets/rigs/animatronic_demo.toml";
    for (name, codec) in [
        ("servo_predictive_demo_0.5deg", CodecChoice::Predictive),
        ("servo_pca_spline_demo_0.5deg", CodecChoice::PcaSpline),
        ("servo_index_demo_0.5deg", CodecChoice::Index),
    ] {
        check_case(name, &servo_clip_bytes(&m, rig, codec, &["0.5deg"]));
    }
}

/// Servo clips as the encoder wrote them before the rig digest (SPEC.md §3.6),
/// kept as committed (`tests/golden/pre-digest/`): they still decode to
/// exactly their committed output, carry no digest, and still count as made
/// for the demo figure by their rig table (`Identity::SameTable`).
#[test]
fn pre_digest_servo_clips_keep_decoding() {
    use mocap_encoder::play::{Figure, Identity, Policy};
    let dir = golden_dir().join("pre-digest");
    let figure = Figure::from_rig(
        &Rig::read_file(&workspace_root().join("assets/rigs/animatronic_demo.toml")).unwrap(),
        Policy::Refuse,
    );
    for codec in ["index", "pca_spline", "predictive"] {
        let name = format!("servo_{codec}_demo_0.5deg");
        let bytes = std::fs::read(dir.join(format!("{name}.mcb"))).unwrap();
        let expected = std::fs::read_to_string(dir.join(format!("{name}.out"))).unwrap();
        let actual = decoded_report(&bytes);
        assert!(
            expected == actual,
            "pre-digest {name}: the decoder's output changed:\n{}",
            diff(&expected, &actual)
        );
        let clip = Clip::parse(&bytes).unwrap();
        assert_eq!(clip.rig_digest(), None, "{name}");
        assert_eq!(figure.id().compare(&clip), Identity::SameTable, "{name}");
    }
}

/// `pattern` clips as the encoder wrote them before its current layout,
/// kept as committed: `tests/golden/pre-columns/` (layout 0, SPEC.md
/// §11.3: a `u16` node count, records in rows), `tests/golden/pre-packed/`
/// (layout 1, §11.3b: columns of whole-byte codes) and
/// `tests/golden/pre-coded/` (layout 2 with plain segment lists, §11.1,
/// before the coded lists of §11.1b). They still decode to exactly their
/// committed output.
#[test]
fn earlier_pattern_layouts_keep_decoding() {
    for dir in ["pre-columns", "pre-packed", "pre-coded"] {
        let dir = golden_dir().join(dir);
        let name = "pattern_demo_20mm";
        let bytes = std::fs::read(dir.join(format!("{name}.mcb"))).unwrap();
        let expected = std::fs::read_to_string(dir.join(format!("{name}.out"))).unwrap();
        let actual = decoded_report(&bytes);
        assert!(
            expected == actual,
            "{}: the decoder's output changed:\n{}",
            dir.display(),
            diff(&expected, &actual)
        );
    }
}

/// The encoder still writes layout 1 on request (`--pattern-layout
/// columns`, SPEC.md §11.3b): a clip that decodes to exactly the committed
/// layout-1 clip's output (the bytes differ since the segment lists are
/// coded, §11.1b, and the patterns numbered in order of use).
#[test]
fn pattern_columns_layout_is_the_committed_layout_1_clip() {
    let m = demo();
    let opts = EncodeOptions {
        key_bits: None,
        codec: CodecChoice::Pattern,
        bound: bound(&["20mm"]),
        metres_per_unit: units::detect(&m).metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: mocap_encoder::codec::pattern::PatternOptions {
            nodes: Vec::new(),
            layout: mocap_encoder::codec::pattern::Layout::Columns,
            ..Default::default()
        },
    };
    let made = encode::encode(&m, &opts).unwrap().bytes;
    let committed = std::fs::read(golden_dir().join("pre-packed/pattern_demo_20mm.mcb")).unwrap();
    // What the decoder makes of them, without the lines about the bytes.
    let decoded = |b: &[u8]| -> String {
        decoded_report(b)
            .lines()
            .filter(|l| !l.starts_with("codec ") && !l.starts_with("bytes "))
            .flat_map(|l| [l, "\n"])
            .collect()
    };
    let (made_out, committed_out) = (decoded(&made), decoded(&committed));
    assert!(
        made_out == committed_out,
        "{} B against {} B:\n{}",
        made.len(),
        committed.len(),
        diff(&committed_out, &made_out)
    );
    let section = |b: &[u8]| {
        let clip = mocap_decoder::Clip::parse(b).unwrap();
        let s = clip
            .sections()
            .find(|s| s.id == mocap_encoder::codec::pattern::SECTION_ID)
            .unwrap();
        mocap_encoder::codec::pattern::inspect(s.bytes).unwrap()
    };
    assert_eq!(
        section(&made).layout,
        mocap_decoder::pattern::LAYOUT_COLUMNS
    );
    assert!(section(&made).coded_lists);
}

/// Clips encoded from the corpus, pinned by digests of their bytes and of
/// everything the decoder makes of them.
#[test]
fn golden_corpus_digests() {
    let Some(walk) = corpus_file("cmu", "35_01.bvh") else {
        return;
    };
    let Some(iclone) = corpus_file("iclone-cmu", "002_01.bvh") else {
        return;
    };
    let Some(arms) = corpus_file("cmu", "05_04.bvh") else {
        return;
    };
    let walk = bvh::read_file(&walk).unwrap();
    let iclone = bvh::read_file(&iclone).unwrap();
    let arms = bvh::read_file(&arms).unwrap();
    let rig = "assets/rigs/cmu_upper_body.toml";
    let cases: Vec<(&str, Vec<u8>)> = vec![
        (
            "cmu/35_01 index 1deg",
            motion_clip(&walk, CodecChoice::Index, &["1deg"]),
        ),
        (
            "cmu/35_01 pca-spline 50mm+arms:10mm",
            motion_clip(&walk, CodecChoice::PcaSpline, &["50mm", "arms:10mm"]),
        ),
        (
            "cmu/35_01 pattern 50mm+arms:10mm",
            motion_clip(&walk, CodecChoice::Pattern, &["50mm", "arms:10mm"]),
        ),
        (
            "cmu/35_01 predictive 1deg",
            motion_clip(&walk, CodecChoice::Predictive, &["1deg"]),
        ),
        (
            "cmu/05_04 rma 50mm+arms:10mm",
            motion_clip(&arms, CodecChoice::Rma, &["50mm", "arms:10mm"]),
        ),
        (
            "iclone-cmu/002_01 pca-spline 20mm",
            motion_clip(&iclone, CodecChoice::PcaSpline, &["20mm"]),
        ),
        (
            "cmu/05_04 servo predictive 0.5deg",
            servo_clip_bytes(&arms, rig, CodecChoice::Predictive, &["0.5deg"]),
        ),
        (
            "cmu/05_04 servo pca-spline 2deg",
            servo_clip_bytes(&arms, rig, CodecChoice::PcaSpline, &["2deg"]),
        ),
    ];
    let mut actual = String::new();
    for (name, bytes) in &cases {
        writeln!(actual, "## {name}").unwrap();
        actual.push_str(
            &decoded_report(bytes)
                .lines()
                .filter(|l| !l.starts_with("frame ") && !l.starts_with("pulses t=0"))
                .flat_map(|l| [l, "\n"])
                .collect::<String>(),
        );
    }
    let path = golden_dir().join("corpus.txt");
    if bless() {
        std::fs::write(&path, &actual).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path).unwrap();
    assert!(
        expected == actual,
        "{}: clips encoded from the corpus changed:\n{}(regenerate on purpose with MOCAP_BLESS=1)",
        path.display(),
        diff(&expected, &actual)
    );
}

/// The shipped demo show (`mocap show build assets/shows/demo.toml`) pins the show format
/// (SPEC.md §9) and its builder: the committed `tests/golden/demo_show.mcb` is what the
/// builder writes today, and its clips decode to the committed output (each clip's frames,
/// then the show player's pose at every 20 ms through a scripted sequence of plays, fades,
/// a queue and a stop).
#[test]
fn the_demo_show_is_golden() {
    use mocap_decoder::Show;
    use mocap_encoder::show::{self, file::ShowSpec, HostShowPlayer};
    let spec = ShowSpec::read_file(&workspace_root().join("assets/shows/demo.toml")).unwrap();
    let built = show::build(&spec).unwrap().bytes;
    let (mcb, out) = (
        golden_dir().join("demo_show.mcb"),
        golden_dir().join("demo_show.out"),
    );
    if bless() {
        std::fs::write(&mcb, &built).unwrap();
    }
    let committed =
        std::fs::read(&mcb).expect("tests/golden/demo_show.mcb (MOCAP_BLESS=1 writes it)");
    assert!(
        built == committed,
        "the show builder no longer writes tests/golden/demo_show.mcb"
    );
    let s = Show::parse(&committed).unwrap();
    let mut text = String::new();
    for i in 0..s.clip_count() {
        let e = s.entry(i).unwrap();
        let clip = s.clip(i).unwrap();
        let mut p = Player::<128>::new(&clip).unwrap();
        let mut v = vec![0; clip.header().channel_count()];
        let _ = writeln!(
            text,
            "clip {i} {} frames={} loop={:?}",
            e.name, e.frames, e.looping
        );
        while p.next_frame(&mut v).unwrap().is_some() {
            let _ = writeln!(text, "{v:?}");
        }
    }
    let mut p = Box::new(HostShowPlayer::new(s).unwrap());
    let mut v = vec![0; s.header().channel_count()];
    for k in 0..400u64 {
        let t = k * 20_000;
        match k {
            0 => p.play(0, t).unwrap(),
            40 => p.crossfade_to(1, 400_000, t).unwrap(),
            50 => p.crossfade_to(2, 300_000, t).unwrap(),
            120 => p.queue(3, t).unwrap(),
            300 => p.stop(t).unwrap(),
            _ => {}
        }
        let now = p.sample(t, &mut v).unwrap();
        let _ = writeln!(text, "t={t} {:?} {v:?}", now.state);
    }
    if bless() {
        std::fs::write(&out, &text).unwrap();
    }
    let want = std::fs::read_to_string(&out).expect("tests/golden/demo_show.out");
    assert!(
        text == want,
        "the demo show decodes differently from tests/golden/demo_show.out"
    );
}
