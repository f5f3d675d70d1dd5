//! The cost model of `mocap encode --target` (encoder/src/target/) against
//! the instructions QEMU counts (`-icount shift=0`), on clips the fit never
//! saw (`scripts/cost.sh` keeps 35_01 in its held-out set): on every board,
//! every codec's predicted instructions per pose (`index` in both layouts)
//! within ±15 % of the measured, the playback path's stack within the
//! model's, and the player's state as the model computes it.
//!
//! Needs QEMU (as the parity tests) and the CMU corpus; prints SKIPPED
//! without them (under `CI` a missing emulator fails).

use mocap_encoder::codec::index::IndexLayout;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::target::{self, cost};
use mocap_encoder::{bvh, units};
use mocap_tests::{boards, corpus_file, qemu_available, run_firmware, skipped};

/// The value of `key=` on the first `#` line that has it (and starts with
/// `line`: `# decode_instructions_total=` for the decode figures).
fn stat_on(uart: &str, line: &str, key: &str) -> u64 {
    let pat = format!("{key}=");
    uart.lines()
        .filter(|l| l.starts_with(line))
        .flat_map(str::split_whitespace)
        .find_map(|w| w.strip_prefix(&pat))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {key}= in the firmware's output:\n{uart}"))
}

fn stat(uart: &str, key: &str) -> u64 {
    stat_on(uart, "#", key)
}

/// `m` encoded with `codec` (`index` in `index_layout`) under `bound`
/// (bounds joined by `+`, as on the command line).
fn encode_with(
    m: &mocap_encoder::motion::Motion,
    codec: CodecChoice,
    index_layout: IndexLayout,
    bound: &str,
) -> Vec<u8> {
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound::from_specs(
            &bound
                .split('+')
                .map(|b| b.parse::<BoundSpec>().unwrap())
                .collect::<Vec<_>>(),
        ),
        metres_per_unit: units::detect(m).metres(),
        key_interval: None,
        index_layout,
        pattern: Default::default(),
    };
    encode::encode(m, &opts).unwrap().bytes
}

#[test]
fn predicted_cost_is_within_15_percent_of_qemu_on_every_board() {
    if !qemu_available() {
        return;
    }
    let Some(path) = corpus_file("cmu", "35_01.bvh") else {
        skipped("corpus not found (set MOCAP_CORPUS)");
        return;
    };
    let m = bvh::read_file(&path).unwrap();
    let dir = std::env::temp_dir().join(format!("mocap-qemu-cost-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut worst = 0.0f64;
    for (codec, layout, bound) in [
        (CodecChoice::Index, IndexLayout::Compact, "1deg"),
        (
            CodecChoice::PcaSpline,
            IndexLayout::Compact,
            "50mm+arms:10mm",
        ),
        (CodecChoice::Predictive, IndexLayout::Compact, "1deg"),
        (CodecChoice::Index, IndexLayout::Fast, "1deg"),
    ] {
        let bytes = encode_with(&m, codec, layout, bound);
        let name = target::candidate_label(codec, layout);
        let clip = dir.join(format!("35_01_{name}.mcb"));
        std::fs::write(&clip, &bytes).unwrap();
        let features = target::Features::of(&bytes).unwrap();
        eprintln!("35_01 {name} at {bound}: {} bytes", bytes.len());
        for board in boards() {
            let chip = target::chip(&board)
                .unwrap_or_else(|| panic!("board {board} has no chip profile of the same name"));
            let predicted = target::predict(&bytes, chip).unwrap();
            let uart = run_firmware(&board, &clip, &["--icount"]);
            let measured = stat_on(&uart, "# decode_instructions_total=", "per_frame") as f64;
            let err = (predicted.instructions_per_pose - measured) / measured;
            eprintln!(
                "{board} {}: measured {measured:.0}, predicted {:.0} ({:+.1} %), stack {} (model {})",
                name,
                predicted.instructions_per_pose,
                err * 100.0,
                stat(&uart, "playback_stack_bytes"),
                predicted.playback_stack_bytes
            );
            assert!(
                err.abs() <= 0.15,
                "{board} {}: predicted {:.0} instructions per pose, measured {measured:.0} ({:+.1} %)",
                name,
                predicted.instructions_per_pose,
                err * 100.0
            );
            worst = worst.max(err.abs());
            let stack = stat(&uart, "playback_stack_bytes") as usize;
            assert!(
                stack <= predicted.playback_stack_bytes,
                "{board} {}: the playback path took {stack} B of stack, the model says {}",
                name,
                predicted.playback_stack_bytes
            );
            // The firmware's player holds `max_channels` words.
            let capacity = stat(&uart, "max_channels") as usize;
            assert_eq!(
                stat(&uart, "state_bytes") as usize,
                cost::state_bytes(capacity),
                "{board}: the player's state"
            );
            assert!(features.state_words <= capacity);
        }
    }
    eprintln!("worst error {:.1} %", worst * 100.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `pca-spline` with a player too small to cache every group, and one that
/// caches them all: the model's figure for each `Player<N>` (the capacities
/// `mocap encode --target --budget` chooses between) within ±15 % of the
/// firmware built with `--player-words N`, on the M3.
#[test]
fn predicted_cost_follows_the_players_capacity() {
    if !qemu_available() {
        return;
    }
    let Some(path) = corpus_file("cmu", "35_01.bvh") else {
        skipped("corpus not found (set MOCAP_CORPUS)");
        return;
    };
    let m = bvh::read_file(&path).unwrap();
    let bytes = encode_with(&m, CodecChoice::PcaSpline, IndexLayout::Compact, "5mm");
    let dir = std::env::temp_dir().join(format!("mocap-qemu-capacity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let clip = dir.join("35_01_pca-spline_5mm.mcb");
    std::fs::write(&clip, &bytes).unwrap();
    let full = target::Features::of(&bytes).unwrap();
    let capacities = [full.capacities[0], *full.capacities.last().unwrap()];
    assert!(
        capacities[0] < capacities[1],
        "the clip should have groups worth caching: capacities {:?}",
        full.capacities
    );
    let chip = target::chip("lm3s6965").unwrap();
    let mut measured_at = Vec::new();
    for n in capacities {
        let f = target::Features::with_capacity(&bytes, Some(n)).unwrap();
        let predicted = cost::predict_features(&f, chip).unwrap();
        let words = n.to_string();
        let uart = run_firmware("lm3s6965", &clip, &["--icount", "--player-words", &words]);
        assert_eq!(stat(&uart, "max_channels") as usize, n);
        assert_eq!(stat(&uart, "state_bytes") as usize, cost::state_bytes(n));
        let measured = stat_on(&uart, "# decode_instructions_total=", "per_frame") as f64;
        let err = (predicted.instructions_per_pose - measured) / measured;
        eprintln!(
            "Player<{n}>: measured {measured:.0}, predicted {:.0} ({:+.1} %)",
            predicted.instructions_per_pose,
            err * 100.0
        );
        assert!(
            err.abs() <= 0.15,
            "Player<{n}>: predicted {:.0} instructions per pose, measured {measured:.0} ({:+.1} %)",
            predicted.instructions_per_pose,
            err * 100.0
        );
        measured_at.push(measured);
    }
    assert!(
        measured_at[1] < measured_at[0],
        "caching every group should cost fewer instructions: {measured_at:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `rma` (calibrated on other takes played on, `scripts/cost.sh`): 35_01 played on to 1 000
/// frames at 20 mm, a third of its poses in repeated clips, on the M0 and the M3 with the
/// firmware's player, and on the M3 with one that caches every group at `t` and at `Ref(t)`:
/// predicted within ±15 % of the measured. (Without repeated clips `rma` is its `pca-spline`
/// body, whose model the test above holds.)
#[test]
fn predicted_rma_cost_is_within_15_percent_with_repeated_clips() {
    if !qemu_available() {
        return;
    }
    let Some(path) = corpus_file("cmu", "35_01.bvh") else {
        skipped("corpus not found (set MOCAP_CORPUS)");
        return;
    };
    let take = bvh::read_file(&path).unwrap();
    let m = mocap_encoder::generate::long_take(
        &take,
        &mocap_encoder::generate::LongOptions {
            skip: 1,
            ..mocap_encoder::generate::LongOptions::new(1000)
        },
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("mocap-qemu-rma-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for bound in ["20mm"] {
        let bytes = encode_with(&m, CodecChoice::Rma, IndexLayout::Compact, bound);
        let clip = dir.join(format!("35_01x_rma_{}.mcb", bound.replace([':', '+'], "_")));
        std::fs::write(&clip, &bytes).unwrap();
        let full = target::Features::of(&bytes).unwrap();
        assert!(full.x[10] > 0.2, "{bound}: repeated poses {:?}", full.x);
        for board in ["microbit", "lm3s6965"] {
            let chip = target::chip(board).unwrap();
            // The firmware's player, and one with every group cached where the board holds it.
            let mut players = vec![None];
            if board == "lm3s6965" {
                players.push(Some(full.state_words));
            }
            for n in players {
                let f = target::Features::with_capacity(&bytes, n.or(Some(320))).unwrap();
                let predicted = cost::predict_features(&f, chip).unwrap();
                let words = n.map(|n| n.to_string());
                let mut args = vec!["--icount"];
                if let Some(w) = &words {
                    args.extend(["--player-words", w]);
                }
                let uart = run_firmware(board, &clip, &args);
                let measured = stat_on(&uart, "# decode_instructions_total=", "per_frame") as f64;
                let err = (predicted.instructions_per_pose - measured) / measured;
                eprintln!(
                    "{board} rma {bound} Player<{}>: {} B, repeated poses {:.0} %, measured {measured:.0}, predicted {:.0} ({:+.1} %)",
                    f.state_words,
                    bytes.len(),
                    f.x[10] * 100.0,
                    predicted.instructions_per_pose,
                    err * 100.0
                );
                assert!(
                    err.abs() <= 0.15,
                    "{board} rma {bound} Player<{}>: predicted {:.0}, measured {measured:.0} ({:+.1} %)",
                    f.state_words,
                    predicted.instructions_per_pose,
                    err * 100.0
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
