//! The Pico firmware's build: the RP2040 memory map (`memory.x`, which cortex-m-rt's `link.x`
//! INCLUDEs) and the Pico's link arguments, then the same clip staging and figure as the QEMU
//! firmware, by the same code (`../build_common.rs`):
//!
//! - the clip: `$MOCAP_CLIP` (relative paths are relative to this directory), else
//!   `../clips/demo.mcb`, as `OUT_DIR/clip.mcb`;
//! - the figure: `$MOCAP_FIGURE` (default `../../assets/rigs/animatronic_demo.toml`) and
//!   `$MOCAP_POLICY`, compiled into `OUT_DIR/figure.rs` (its rig table and hard limits);
//! - the servo output, `$MOCAP_SERVO`: `pca9685` (default; a PCA9685 on I²C0) or `pwm` (the
//!   RP2040's own PWM channels), as `OUT_DIR/config.rs` (`const OUTPUT_PWM: bool`).

use std::env;
use std::path::PathBuf;

#[path = "../build_common.rs"]
mod build_common;
use build_common::{copy_or_fail, fail, write_if_changed, DEFAULT_CLIP, DEFAULT_FIGURE};

fn main() {
    let manifest_dir =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    // firmware-example/, where the shared defaults live.
    let examples = manifest_dir.join("..");

    let target = env::var("TARGET").unwrap_or_default();
    if target != "thumbv6m-none-eabi" {
        fail(&format!(
            "mocap-firmware-pico: the RP2040 is a Cortex-M0+: build for thumbv6m-none-eabi, \
             not '{target}' (.cargo/config.toml and scripts/firmware.sh --board pico do this)"
        ));
    }
    let memory = manifest_dir.join("memory.x");
    copy_or_fail(&memory, &out_dir.join("memory.x"), "memory map");
    println!("cargo:rustc-link-search={}", out_dir.display());
    println!("cargo:rerun-if-changed={}", memory.display());
    // No page alignment of the sections (flash starts right after the 256-byte boot2), and
    // defmt's table of interned log strings, which stays in the ELF for probe-rs to decode.
    // cortex-m-rt's -Tlink.x comes from ../.cargo/config.toml's rustflags.
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");

    build_common::clip(&manifest_dir, &out_dir, &examples.join(DEFAULT_CLIP));
    build_common::figure(&manifest_dir, &out_dir, &examples.join(DEFAULT_FIGURE));

    println!("cargo:rerun-if-env-changed=MOCAP_SERVO");
    let pwm = match env::var("MOCAP_SERVO").as_deref().map(str::trim) {
        Ok("" | "pca9685") | Err(env::VarError::NotPresent) => false,
        Ok("pwm") => true,
        Ok(v) => fail(&format!(
            "mocap-firmware-pico: MOCAP_SERVO must be `pca9685` (default) or `pwm`, got '{v}'"
        )),
        Err(e) => fail(&format!("mocap-firmware-pico: MOCAP_SERVO: {e}")),
    };
    let config = format!(
        "/// The servo output (`MOCAP_SERVO`): the RP2040's PWM channels, else a PCA9685 on I²C0.\n\
         pub const OUTPUT_PWM: bool = {pwm};\n"
    );
    write_if_changed(&out_dir.join("config.rs"), config.as_bytes());
}
