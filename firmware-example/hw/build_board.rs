//! The build script of every real board's firmware (`pico/build.rs`, …, which include this file
//! and `../build_common.rs` as modules): the board's memory map and link arguments, then the
//! clip and the figure exactly as the QEMU firmware stages them (`build_common`), and the servo
//! output (`$MOCAP_SERVO`: `pca9685`, the default, or `pwm`) as `OUT_DIR/config.rs`
//! (`const OUTPUT_PWM: bool`), with whether the clip is a show (`const SHOW: bool`: a show build
//! links the show mode and not the clip playback, a clip build the other way round).

use std::env;
use std::path::{Path, PathBuf};

use crate::build_common::{
    self, copy_or_fail, fail, write_if_changed, DEFAULT_CLIP, DEFAULT_FIGURE,
};

/// Builds the board crate `name` for `target`: its `memory.x` (which cortex-m-rt's `link.x`
/// INCLUDEs; `-Tlink.x` itself comes from firmware-example/.cargo/config.toml), `link_args` for
/// its binary, then the clip (default `firmware-example/clips/demo.mcb`), the figure (default
/// `assets/rigs/animatronic_demo.toml`) and the output.
#[allow(dead_code)] // each board's build.rs uses this or [`build_with_hal_link_script`]
pub fn build(name: &str, target: &str, link_args: &[&str]) {
    let (manifest_dir, out_dir) = dirs(name, target);
    let memory = manifest_dir.join("memory.x");
    copy_or_fail(&memory, &out_dir.join("memory.x"), "memory map");
    println!("cargo:rustc-link-search={}", out_dir.display());
    println!("cargo:rerun-if-changed={}", memory.display());
    stage(name, &manifest_dir, &out_dir, link_args);
}

/// [`build`] for a board whose HAL brings the memory map and the link script (esp-hal's build
/// script puts the chip's `memory.x` and `linkall.x` on the search path; `link_args` names the
/// script): no `memory.x` of the crate's own.
#[allow(dead_code)]
pub fn build_with_hal_link_script(name: &str, target: &str, link_args: &[&str]) {
    let (manifest_dir, out_dir) = dirs(name, target);
    stage(name, &manifest_dir, &out_dir, link_args);
}

/// The crate's directory and OUT_DIR, once the build is checked to be for `target`.
fn dirs(name: &str, target: &str) -> (PathBuf, PathBuf) {
    let manifest_dir =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let built_for = env::var("TARGET").unwrap_or_default();
    if built_for != target {
        fail(&format!(
            "{name}: build for {target}, not '{built_for}' (.cargo/config.toml and \
             scripts/firmware.sh build --board … do this)"
        ));
    }
    (manifest_dir, out_dir)
}

/// The link arguments, the clip, the figure and the output (`OUT_DIR/config.rs`).
fn stage(name: &str, manifest_dir: &Path, out_dir: &Path, link_args: &[&str]) {
    // firmware-example/, where the shared defaults live.
    let examples = manifest_dir.join("..");
    // Link arguments of the binary only (not rustflags): the artifacts of the target directory
    // shared with the QEMU firmware stay valid for both.
    for arg in link_args {
        println!("cargo:rustc-link-arg-bins={arg}");
    }

    build_common::clip(manifest_dir, out_dir, &examples.join(DEFAULT_CLIP));
    build_common::figure(manifest_dir, out_dir, &examples.join(DEFAULT_FIGURE));

    println!("cargo:rerun-if-env-changed=MOCAP_SERVO");
    let pwm = match env::var("MOCAP_SERVO").as_deref().map(str::trim) {
        Ok("" | "pca9685") | Err(env::VarError::NotPresent) => false,
        Ok("pwm") => true,
        Ok(v) => fail(&format!(
            "{name}: MOCAP_SERVO must be `pca9685` (default) or `pwm`, got '{v}'"
        )),
        Err(e) => fail(&format!("{name}: MOCAP_SERVO: {e}")),
    };
    // SPEC.md §2/§9: the container's version byte (offset 4) is 2 in a show.
    let clip = std::fs::read(out_dir.join("clip.mcb")).unwrap_or_default();
    let show = clip.get(4) == Some(&2);
    let config = format!(
        "/// The servo output (`MOCAP_SERVO`): the MCU's PWM channels, else a PCA9685 on I²C.\n\
         pub const OUTPUT_PWM: bool = {pwm};\n\
         /// The embedded `.mcb` is a show (SPEC.md §9): the show mode is built, not the clip playback.\n\
         pub const SHOW: bool = {show};\n"
    );
    write_if_changed(&out_dir.join("config.rs"), config.as_bytes());
}
