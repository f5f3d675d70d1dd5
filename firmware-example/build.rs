//! Puts the board's memory map on the linker search path (as `memory.x`, which cortex-m-rt's
//! `link.x` INCLUDEs) and copies the clip to embed into OUT_DIR (`clip.mcb`, read by
//! `include_bytes!` in src/main.rs).
//!
//! The clip is `$MOCAP_CLIP` when set (relative paths are relative to this directory), else
//! `clips/demo.mcb`.
//!
//! The playback mode is `$MOCAP_SAMPLE_US`: unset or empty plays every frame with
//! `Player::next_frame`; a period P in µs (a whole number > 0) samples the clip with
//! `Player::sample_at` at t = 0, P, 2P, … up to and including the first t past its duration.
//! It reaches src/main.rs as `OUT_DIR/config.rs` (`const SAMPLE_US: u64`, 0 = every frame),
//! with the servo output (`$MOCAP_SERVO`, `const SERVO`) and the streaming mode
//! (`$MOCAP_STREAM=1`, `const STREAM`), the streaming mode's gap timeout
//! (`$MOCAP_STREAM_TIMEOUT_MS`, default 500, `const STREAM_TIMEOUT_MS`) and the simulated e-stop
//! (`$MOCAP_ESTOP_AT_TICK`, `const ESTOP_AT_TICK`), and the servo mode's power levels (`$MOCAP_POWER`,
//! `mocap play --power`'s schedule, `const POWER`). `$MOCAP_CLIP_SLOT=N` (`const CLIP_SLOT`)
//! reserves N bytes of flash for a clip written into the ELF after the build (src/slot.rs).
//!
//! The figure — the rig file of the mechanism this firmware drives (`$MOCAP_FIGURE`, default
//! `../assets/rigs/animatronic_demo.toml`) — becomes `OUT_DIR/figure.rs`: its rig table, its
//! hard limits and the policy for clips made for another rig (`$MOCAP_POLICY`), see
//! [`build_common::figure`] (build_common.rs, shared with pico/build.rs).

use std::env;
use std::path::{Path, PathBuf};

// The clip, the figure and the file helpers, shared with the board firmwares (pico/build.rs).
mod build_common;
use build_common::{copy_or_fail, fail, write_if_changed, DEFAULT_CLIP, DEFAULT_FIGURE};

/// (cargo feature, memory map relative to this directory, Rust targets that suit the core)
const BOARDS: &[(&str, &str, &[&str])] = &[
    (
        "board-lm3s6965",
        "../memory.x",
        &["thumbv7m-none-eabi", "thumbv6m-none-eabi"],
    ),
    (
        "board-microbit",
        "memory/microbit.x",
        &["thumbv6m-none-eabi"],
    ),
    (
        "board-mps2-an386",
        "memory/mps2-an386.x",
        &[
            "thumbv7em-none-eabihf",
            "thumbv7em-none-eabi",
            "thumbv7m-none-eabi",
            "thumbv6m-none-eabi",
        ],
    ),
    (
        "board-riscv-virt",
        "memory/riscv-virt.x",
        &[
            "riscv32imc-unknown-none-elf",
            "riscv32imac-unknown-none-elf",
            "riscv32i-unknown-none-elf",
        ],
    ),
];

fn feature_env(feature: &str) -> String {
    format!("CARGO_FEATURE_{}", feature.to_uppercase().replace('-', "_"))
}

fn main() {
    let manifest_dir =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let target = env::var("TARGET").unwrap_or_default();

    // ---- board and memory map
    let selected: Vec<_> = BOARDS
        .iter()
        .filter(|(feature, _, _)| env::var_os(feature_env(feature)).is_some())
        .collect();
    let (feature, memory, targets) = match selected.as_slice() {
        [one] => **one,
        [] => fail(
            "mocap-firmware: no board selected. Enable exactly one of the features \
             board-lm3s6965 (default), board-microbit, board-mps2-an386, board-riscv-virt.",
        ),
        many => fail(&format!(
            "mocap-firmware: several boards selected ({}). Use --no-default-features \
             --features board-<name> to pick exactly one.",
            many.iter().map(|b| b.0).collect::<Vec<_>>().join(", ")
        )),
    };
    if !targets.contains(&target.as_str()) {
        fail(&format!(
            "mocap-firmware: feature {feature} needs one of the targets {targets:?}, \
             but this build is for '{target}'. Pass --target {} (scripts/firmware.sh does this).",
            targets[0]
        ));
    }
    let memory_src = manifest_dir.join(memory);
    copy_or_fail(&memory_src, &out_dir.join("memory.x"), "memory map");
    println!("cargo:rustc-link-search={}", out_dir.display());
    println!("cargo:rerun-if-changed={}", memory_src.display());
    // riscv-rt's link.x, unlike cortex-m-rt's, does not INCLUDE memory.x (the map with its
    // REGION_* aliases): it goes first. Link arguments of the binary, not rustflags in
    // .cargo/config.toml: those would apply to esp32c3/ too (a directory below), whose HAL
    // brings its own memory map and link script for the same target.
    if target.starts_with("riscv32") {
        println!("cargo:rustc-link-arg-bins=-Tmemory.x");
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
    }

    // ---- clip
    build_common::clip(&manifest_dir, &out_dir, &manifest_dir.join(DEFAULT_CLIP));

    // ---- playback mode
    println!("cargo:rerun-if-env-changed=MOCAP_SAMPLE_US");
    let sample_us: u64 = match env::var("MOCAP_SAMPLE_US") {
        Ok(v) if v.trim().is_empty() => 0,
        Ok(v) => match v.trim().parse::<u64>() {
            Ok(n) if n > 0 => n,
            _ => fail(&format!(
                "mocap-firmware: MOCAP_SAMPLE_US must be a sampling period in microseconds \
                 (a whole number > 0), got '{v}'. Unset it to play every frame."
            )),
        },
        Err(env::VarError::NotPresent) => 0,
        Err(e) => fail(&format!("mocap-firmware: MOCAP_SAMPLE_US: {e}")),
    };
    // Servo mode: `MOCAP_SERVO=maestro|ssc32|pwm|pca9685` plays a servo clip (one with a rig
    // table) at its rig's rate through that output and prints what every tick sent (Maestro
    // bytes as hex, SSC-32 text, the 16 PWM duties, the PCA9685's I²C writes).
    println!("cargo:rerun-if-env-changed=MOCAP_SERVO");
    let servo: u8 = match env::var("MOCAP_SERVO").as_deref().map(str::trim) {
        Ok("") | Err(env::VarError::NotPresent) => 0,
        Ok("maestro") => 1,
        Ok("ssc32") => 2,
        Ok("pwm") => 3,
        Ok("pca9685") => 4,
        Ok(v) => fail(&format!(
            "mocap-firmware: MOCAP_SERVO must be `maestro`, `ssc32`, `pwm` or `pca9685` \
             (or unset), got '{v}'"
        )),
        Err(e) => fail(&format!("mocap-firmware: MOCAP_SERVO: {e}")),
    };
    // Streaming mode: `MOCAP_STREAM=1` receives clips and live poses over the UART (SPEC.md
    // §8) and plays them on the rig of the embedded servo clip, through the MOCAP_SERVO
    // output (Maestro when unset).
    println!("cargo:rerun-if-env-changed=MOCAP_STREAM");
    let stream = match env::var("MOCAP_STREAM").as_deref().map(str::trim) {
        Ok("" | "0") | Err(env::VarError::NotPresent) => false,
        Ok("1") => true,
        Ok(v) => fail(&format!(
            "mocap-firmware: MOCAP_STREAM must be 1 (or 0 / unset), got '{v}'"
        )),
        Err(e) => fail(&format!("mocap-firmware: MOCAP_STREAM: {e}")),
    };
    if stream && sample_us != 0 {
        fail("mocap-firmware: MOCAP_STREAM and MOCAP_SAMPLE_US exclude each other");
    }
    // Faults end at rest (src/stream.rs, src/servo.rs): in the streaming mode, this long without
    // an accepted frame after the first byte parks every servo (0: hold the last pose however
    // long the gap); and an e-stop, which QEMU's boards cannot press, simulated at an output
    // tick (0: never).
    let timeout_ms = whole_number("MOCAP_STREAM_TIMEOUT_MS", 500);
    let estop_at_tick = whole_number("MOCAP_ESTOP_AT_TICK", 0);
    // The entropy coder's measurement (`MOCAP_ENTROPY_BENCH=1`, src/entropy_bench.rs): rANS
    // streams encoded here; none otherwise.
    let entropy_bench = whole_number("MOCAP_ENTROPY_BENCH", 0) != 0;
    entropy_streams(entropy_bench, &out_dir);
    // The player's capacity in words (`Player<N>`; `pca-spline` caches what fits, `mocap encode
    // --target` picks it under a RAM budget): 320 unless `MOCAP_PLAYER_WORDS`.
    let player_words = whole_number("MOCAP_PLAYER_WORDS", 320);
    if player_words == 0 {
        fail("mocap-firmware: MOCAP_PLAYER_WORDS must be at least 1");
    }
    // The clip slot (`MOCAP_CLIP_SLOT=N`, src/slot.rs): N bytes of flash that scripts/firmware.sh
    // writes a clip into after the build, which then plays that clip instead of the embedded one;
    // 0 (unset): the clip is embedded.
    let clip_slot = whole_number("MOCAP_CLIP_SLOT", 0);

    // Power levels of the servo mode (`MOCAP_POWER`, `mocap play --power`'s schedule, SPEC.md
    // §6.1): none unless set.
    println!("cargo:rerun-if-env-changed=MOCAP_POWER");
    let power = match env::var("MOCAP_POWER").as_deref().map(str::trim) {
        Ok("") | Err(env::VarError::NotPresent) => Vec::new(),
        Ok(v) => mocap_encoder::play::parse_power(v)
            .unwrap_or_else(|e| fail(&format!("mocap-firmware: MOCAP_POWER: {e}"))),
        Err(e) => fail(&format!("mocap-firmware: MOCAP_POWER: {e}")),
    };
    if !power.is_empty() && servo == 0 {
        fail("mocap-firmware: MOCAP_POWER sets the servo mode's levels: it needs MOCAP_SERVO");
    }
    let power: String = power
        .iter()
        .map(|(from_us, level)| format!("({from_us}, {level}), "))
        .collect();

    // ---- the figure: its rig file, compiled into hard limits (src/servo.rs)
    build_common::figure(&manifest_dir, &out_dir, &manifest_dir.join(DEFAULT_FIGURE));

    let config = format!(
        "/// Sampling period in µs (`MOCAP_SAMPLE_US`); 0 plays every frame.\n\
         pub const SAMPLE_US: u64 = {sample_us};\n\
         /// Servo mode (`MOCAP_SERVO`): 0 off, 1 Pololu Maestro, 2 SSC-32, 3 PWM, 4 PCA9685.\n\
         pub const SERVO: u8 = {servo};\n\
         /// Streaming mode (`MOCAP_STREAM=1`).\n\
         pub const STREAM: bool = {stream};\n\
         /// Streaming mode: ms without an accepted frame that park the servos; 0 holds the last pose.\n\
         pub const STREAM_TIMEOUT_MS: u32 = {timeout_ms};\n\
         /// The output tick at which the simulated e-stop is pressed (`MOCAP_ESTOP_AT_TICK`); 0 never.\n\
         pub const ESTOP_AT_TICK: u32 = {estop_at_tick};\n\
         /// The entropy coder's measurement instead of playback (`MOCAP_ENTROPY_BENCH=1`).\n\
         pub const ENTROPY_BENCH: bool = {entropy_bench};\n\
         /// Words of the player's state, `Player<N>` (`MOCAP_PLAYER_WORDS`, default 320).\n\
         pub const PLAYER_WORDS: usize = {player_words};\n\
         /// The servo mode's power levels (`MOCAP_POWER`): `(from_us, level)`; empty: level 0.\n\
         pub const POWER: &[(u64, u8)] = &[{power}];\n\
         /// Bytes of the clip slot (`MOCAP_CLIP_SLOT`, src/slot.rs); 0 embeds the clip.\n\
         pub const CLIP_SLOT: usize = {clip_slot};\n"
    );
    write_if_changed(&out_dir.join("config.rs"), config.as_bytes());
}

/// `$name` as a whole number (unset or empty: `default`).
fn whole_number(name: &str, default: u32) -> u32 {
    println!("cargo:rerun-if-env-changed={name}");
    match env::var(name).as_deref().map(str::trim) {
        Ok("") | Err(env::VarError::NotPresent) => default,
        Ok(v) => v.parse().unwrap_or_else(|_| {
            fail(&format!(
                "mocap-firmware: {name} must be a whole number (or unset: {default}), got '{v}'"
            ))
        }),
        Err(e) => fail(&format!("mocap-firmware: {name}: {e}")),
    }
}

/// `OUT_DIR/entropy_bench.rs`: `STREAMS`, the rANS streams (SPEC.md §10) that
/// src/entropy_bench.rs decodes and times — table and one block each, with the symbol count and
/// the checksum (`sum = sum · 31 + symbol`, wrapping) of the symbols — or none without the bench.
fn entropy_streams(bench: bool, out_dir: &Path) {
    use mocap_encoder::entropy::encode_all;
    let mut src = String::from("pub static STREAMS: &[Stream] = &[\n");
    if bench {
        // xorshift32, fixed seeds: the same bytes on every build.
        let mut seed = 0x2545_f491u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        let mut unit = move || (f64::from(next()) + 0.5) / 4_294_967_296.0;
        // Zigzag residuals of a two-sided geometric source (ratio r): quantised motion differences.
        let mut laplace = |len: usize, r: f64| -> Vec<u32> {
            (0..len)
                .map(|_| {
                    let m = (unit().ln() / r.ln()).floor() as u32;
                    if m == 0 {
                        0
                    } else if unit() < 0.5 {
                        2 * m - 1
                    } else {
                        2 * m
                    }
                })
                .collect()
        };
        let flat = |len: usize, a: u32| -> Vec<u32> {
            (0..len)
                .map(|i| ((i as u32).wrapping_mul(2_654_435_761) >> 8) % a)
                .collect()
        };
        let streams: Vec<(&str, Vec<u32>)> = vec![
            ("laplace-0.5", laplace(10_000, 0.5)),
            ("laplace-0.8", laplace(10_000, 0.8)),
            ("flat-16", flat(10_000, 16)),
            ("flat-256", flat(4_000, 256)),
            ("one-symbol", vec![0; 10_000]),
        ];
        for (name, symbols) in streams {
            let bytes = encode_all(&symbols).expect("the bench streams encode");
            let checksum = symbols
                .iter()
                .fold(0u32, |s, &x| s.wrapping_mul(31).wrapping_add(x));
            src.push_str(&format!(
                "    Stream {{ name: {name:?}, symbols: {}, checksum: {checksum}, bytes: &{bytes:?} }},\n",
                symbols.len()
            ));
        }
    }
    src.push_str("];\n");
    write_if_changed(&out_dir.join("entropy_bench.rs"), src.as_bytes());
}
