//! The figure's hard limits in the firmware (issue: "no clip, show or stream can drive a servo
//! past what the mechanism allows"): a clip encoded for a wider rig
//! (`assets/rigs/animatronic_demo_wide.toml`, every range ×1.8, no speed limits) played by the
//! firmware built for the demo figure (`assets/rigs/animatronic_demo.toml`, the default
//! `MOCAP_FIGURE`) on every board, under each policy (`MOCAP_POLICY`, `firmware.sh --policy`):
//!
//! - `refuse` and `clamp-if-inside` (the default): the firmware refuses it — a `# figure …
//!   same_rig=0 fit=outside` status line, `# error figure: …`, exit 1, not one command sent;
//! - `clamp`: it plays, every Maestro command inside the figure's pulse range for its channel,
//!   and the bytes are `mocap play --rig animatronic_demo.toml --policy clamp`'s, clamp report
//!   included (`# hard_clamp output= ticks= worst_qus=` against the host's `FigureReport`).

use mocap_decoder::Clip;
use mocap_encoder::encode::CodecChoice;
use mocap_encoder::play::{servo_clip_stream_on, Policy, Protocol};
use mocap_tests::snapshot::first_difference;
use mocap_tests::{
    data_lines, demo_figure, qemu_available, run_firmware_outcome, servo_demo_clip_for, WIDE_RIG,
};

/// `m 84 ch lo hi …` lines: every (channel, target ¼ µs).
fn maestro_commands(lines: &str) -> Vec<(u8, u16)> {
    let mut commands = Vec::new();
    for line in lines.lines() {
        let bytes: Vec<u8> = line
            .strip_prefix("m")
            .unwrap_or_else(|| panic!("not a Maestro line: {line}"))
            .split_whitespace()
            .map(|h| u8::from_str_radix(h, 16).unwrap())
            .collect();
        assert_eq!(bytes.len() % 4, 0, "{line}");
        for c in bytes.chunks(4) {
            assert_eq!(c[0], 0x84, "Set Target: {line}");
            commands.push((c[1], u16::from(c[2]) | u16::from(c[3]) << 7));
        }
    }
    commands
}

fn host_lines(clip: &Clip<'_>, policy: Policy) -> (String, mocap_encoder::play::FigureReport) {
    let s = servo_clip_stream_on(clip, &demo_figure(policy), Protocol::Maestro, None).unwrap();
    let lines = s
        .ticks
        .iter()
        .map(|t| {
            let mut line = String::from("m");
            for b in t {
                line += &format!(" {b:02x}");
            }
            line + "\n"
        })
        .collect();
    (lines, s.figure.unwrap())
}

#[test]
fn a_clip_for_a_wider_rig_is_refused_or_clamped_by_the_figure_on_every_core() {
    if !qemu_available() {
        return;
    }
    let (path, bytes) = servo_demo_clip_for("servo-demo-wide", WIDE_RIG, CodecChoice::Index);
    let clip = Clip::parse(&bytes).unwrap();
    let figure = demo_figure(Policy::ClampAlways);
    let (expected, report) = host_lines(&clip, Policy::ClampAlways);
    assert_eq!(report.identity, mocap_encoder::play::Identity::OtherTable);
    assert!(
        report.clamps.iter().any(|c| c.ticks > 0),
        "nothing to clamp"
    );
    let hard_lines: String = report
        .clamps
        .iter()
        .filter(|c| c.ticks > 0)
        .map(|c| {
            format!(
                "# hard_clamp output={} ticks={} worst_qus={}\n",
                c.output, c.ticks, c.worst_qus
            )
        })
        .collect();

    for board in &mocap_tests::boards() {
        for policy in ["refuse", "clamp-if-inside"] {
            let (ok, uart) =
                run_firmware_outcome(board, &path, &["--servo", "maestro", "--policy", policy]);
            assert!(!ok, "{board} {policy}: the wide clip played:\n{uart}");
            let status = format!("policy={policy} identity=other_table same_rig=0 fit=outside");
            assert!(
                uart.lines()
                    .any(|l| l.starts_with("# figure ") && l.contains(&status)),
                "{board} {policy}: no `{status}` status line:\n{uart}"
            );
            assert!(
                uart.lines().any(|l| l.starts_with("# error figure: ")
                    && l.contains("leaves the figure's hard limits")),
                "{board} {policy}: no typed refusal:\n{uart}"
            );
            assert_eq!(data_lines(&uart), "", "{board} {policy}: commands sent");
            eprintln!("wide clip on {board}, policy {policy}: refused");
        }

        let (ok, uart) =
            run_firmware_outcome(board, &path, &["--servo", "maestro", "--policy", "clamp"]);
        assert!(ok, "{board} clamp: the wide clip did not play:\n{uart}");
        assert!(
            uart.contains(" policy=clamp identity=other_table same_rig=0 fit=outside"),
            "{board}: {uart}"
        );
        let data = data_lines(&uart);
        let mut outside = 0usize;
        let commands = maestro_commands(&data);
        for &(channel, target) in &commands {
            let limit = figure
                .limits
                .iter()
                .find(|l| l.output == u16::from(channel))
                .unwrap_or_else(|| panic!("{board}: channel {channel} is not the figure's"));
            outside += usize::from(!(limit.min_qus..=limit.max_qus).contains(&target));
        }
        assert_eq!(
            outside, 0,
            "{board}: commands outside the figure's hard limits"
        );
        assert!(
            data == expected,
            "{board}: clamped wide clip differs from mocap play --policy clamp: {}",
            first_difference(&expected, &data)
        );
        let firmware_hard: String = uart
            .lines()
            .filter(|l| l.starts_with("# hard_clamp "))
            .flat_map(|l| [l, "\n"])
            .collect();
        assert_eq!(firmware_hard, hard_lines, "{board}: clamp report");
        eprintln!(
            "wide clip on {board}, policy clamp: {} commands, 0 outside the figure's limits; {}",
            commands.len(),
            hard_lines.trim_end().replace('\n', "; ")
        );
    }
}

/// The rig digest (SPEC.md §3.6) on the firmware: a clip for the demo rig with neck_pan's
/// acceleration limit halved has the figure's rig table but another digest. `refuse` refuses
/// it (`identity=other_digest`); `clamp-if-inside` plays it, every servo being inside the
/// figure's limits, byte-identical to `mocap play --rig` (which compares the same way).
#[test]
fn a_clip_with_the_figures_table_but_another_digest_follows_the_policy_on_every_core() {
    if !qemu_available() {
        return;
    }
    let root = mocap_tests::workspace_root();
    let toml = std::fs::read_to_string(root.join(mocap_tests::DEMO_RIG)).unwrap();
    let slow = toml.replacen("max_accel = 5000.0", "max_accel = 2500.0", 1);
    assert_ne!(slow, toml);
    let dir = root.join("target/qemu-parity");
    std::fs::create_dir_all(&dir).unwrap();
    let rig = dir.join("demo_slow_neck.toml");
    std::fs::write(&rig, slow).unwrap();
    let (path, bytes) = servo_demo_clip_for(
        "servo-demo-slow-neck",
        rig.to_str().unwrap(),
        CodecChoice::Index,
    );
    let clip = Clip::parse(&bytes).unwrap();
    let (expected, report) = host_lines(&clip, Policy::ClampIfInside);
    assert_eq!(report.identity, mocap_encoder::play::Identity::OtherDigest);
    for board in &mocap_tests::boards() {
        let (ok, uart) =
            run_firmware_outcome(board, &path, &["--servo", "maestro", "--policy", "refuse"]);
        assert!(!ok, "{board}: refused under refuse:\n{uart}");
        assert!(
            uart.contains(" policy=refuse identity=other_digest same_rig=0 fit=inside"),
            "{board}: {uart}"
        );
        assert_eq!(data_lines(&uart), "", "{board}: commands sent");
        let (ok, uart) = run_firmware_outcome(board, &path, &["--servo", "maestro"]);
        assert!(ok, "{board}: clamp-if-inside did not play it:\n{uart}");
        assert!(
            uart.contains(" policy=clamp-if-inside identity=other_digest same_rig=0 fit=inside"),
            "{board}: {uart}"
        );
        let data = data_lines(&uart);
        assert!(
            data == expected,
            "{board}: differs from mocap play --rig: {}",
            first_difference(&expected, &data)
        );
        eprintln!(
            "other-digest clip on {board}: refused under refuse, {} ticks under clamp-if-inside",
            expected.lines().count()
        );
    }
}

/// The e-stop (simulated: QEMU's boards have no button, `firmware.sh --estop-at N`): the demo
/// figure's own clip, e-stop pressed at output tick 100. The firmware sends the 99 ticks
/// `mocap play --rig` sends, then nothing but the return to rest: every step inside the
/// figure's pulse ranges and speed limits, ending at its neutrals, in at most the documented
/// number of ticks (`Playback::park_ticks_max`), and says `# fault=estop park_ticks=N`.
#[test]
fn the_estop_brings_every_servo_to_rest_on_every_core() {
    use mocap_servo::{HardLimits, HardStep, Playback};
    if !qemu_available() {
        return;
    }
    const AT: usize = 100;
    let (path, bytes) = servo_demo_clip_for(
        "servo-demo-estop",
        mocap_tests::DEMO_RIG,
        CodecChoice::Index,
    );
    let clip = Clip::parse(&bytes).unwrap();
    let figure = demo_figure(Policy::ClampIfInside);
    let (expected, _) = host_lines(&clip, Policy::ClampIfInside);
    let (playback, _) = Playback::<32>::new(figure.servos.iter().copied(), figure.rate_mhz)
        .unwrap()
        .with_hard_limits(&HardLimits::new(&figure.limits), true, figure.policy)
        .unwrap();
    let park_max = playback.park_ticks_max() as usize;
    let steps: Vec<HardStep> = figure
        .limits
        .iter()
        .map(|l| HardStep::at_rate(l, figure.rate_mhz))
        .collect();
    let before: String = expected
        .lines()
        .take(AT - 1)
        .flat_map(|l| [l, "\n"])
        .collect();
    for board in &mocap_tests::boards() {
        let at = AT.to_string();
        let (ok, uart) =
            run_firmware_outcome(board, &path, &["--servo", "maestro", "--estop-at", &at]);
        assert!(ok, "{board}: {uart}");
        let data = data_lines(&uart);
        assert!(
            data.starts_with(&before),
            "{board}: before the e-stop: {}",
            first_difference(&before, &data)
        );
        let park = &data[before.len()..];
        let n = park.lines().count();
        assert!(
            uart.contains(&format!("# fault=estop park_ticks={n} ")),
            "{board}: {uart}"
        );
        assert!(
            n <= park_max,
            "{board}: {n} ticks to rest, documented {park_max}"
        );
        let commands = maestro_commands(&data);
        let per_tick = steps.len();
        let mut prev: Vec<u16> = commands[(AT - 2) * per_tick..(AT - 1) * per_tick]
            .iter()
            .map(|c| c.1)
            .collect();
        for tick in commands[(AT - 1) * per_tick..].chunks(per_tick) {
            for ((&(_, p), h), last) in tick.iter().zip(&steps).zip(&mut prev) {
                assert!((h.min_qus..=h.max_qus).contains(&p), "{board}");
                if h.max_step_qus > 0 {
                    assert!(p.abs_diff(*last) <= h.max_step_qus, "{board}: too fast");
                }
                *last = p;
            }
        }
        let neutral: Vec<u16> = steps.iter().map(|h| h.neutral_qus).collect();
        assert_eq!(prev, neutral, "{board}: not at rest");
        eprintln!(
            "e-stop at tick {AT} on {board}: at rest after {n} ticks ({} ms; documented at most {park_max})",
            n as u64 * 1_000_000 / u64::from(figure.rate_mhz)
        );
    }
}
