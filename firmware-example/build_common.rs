//! The build steps every firmware of firmware-example/ shares: the QEMU firmware's build.rs and
//! the board firmwares' (pico/build.rs) include this file as a module (`#[path]`), so the clip
//! is staged and the figure's rig file compiled into hard limits by the same code for all.
//!
//! - [`clip`]: `$MOCAP_CLIP` (relative paths are relative to the crate's directory), else the
//!   default clip ([`DEFAULT_CLIP`]), copied to `OUT_DIR/clip.mcb` for `include_bytes!`.
//! - [`figure`]: `$MOCAP_FIGURE` (default [`DEFAULT_FIGURE`]) and `$MOCAP_POLICY` compiled into
//!   `OUT_DIR/figure.rs`, which the firmware includes (`src/figure.rs`).
//!
//! Paths of the defaults are relative to firmware-example/ (the directory of this file).

use std::env;
use std::fs;
use std::path::Path;
use std::process::exit;

/// The default clip, relative to firmware-example/.
pub const DEFAULT_CLIP: &str = "clips/demo.mcb";
/// The default figure, relative to firmware-example/.
pub const DEFAULT_FIGURE: &str = "../assets/rigs/animatronic_demo.toml";

pub fn fail(msg: &str) -> ! {
    // `cargo:warning` is shown even when the build script's output is not; the exit fails the build.
    for line in msg.lines() {
        println!("cargo:warning={line}");
    }
    eprintln!("error: {msg}");
    exit(1);
}

/// Stages the clip to embed: `$MOCAP_CLIP` (relative to `manifest_dir`) or `default`, copied to
/// `OUT_DIR/clip.mcb`; a missing clip fails the build with what to do.
pub fn clip(manifest_dir: &Path, out_dir: &Path, default: &Path) {
    println!("cargo:rerun-if-env-changed=MOCAP_CLIP");
    let clip = match env::var_os("MOCAP_CLIP") {
        Some(path) if !path.is_empty() => manifest_dir.join(path),
        _ => default.to_path_buf(),
    };
    // Watch the file even when it is missing, so creating it triggers a new build.
    println!("cargo:rerun-if-changed={}", clip.display());
    if !clip.is_file() {
        fail(&format!(
            "mocap-firmware: clip to embed not found: {}\n\
             Set MOCAP_CLIP=/path/to/clip.mcb (made with `mocap encode --target mcu IN -o OUT.mcb`), \
             or create {}. scripts/firmware.sh takes --clip PATH.",
            clip.display(),
            default.display()
        ));
    }
    copy_or_fail(&clip, &out_dir.join("clip.mcb"), "clip");
}

/// `OUT_DIR/figure.rs`, from the figure's rig file (`$MOCAP_FIGURE`, default
/// `default` (firmware-example's [`DEFAULT_FIGURE`]); the TOML `mocap encode --rig` reads) and the policy for clips made for
/// another rig (`$MOCAP_POLICY`: `refuse`, `clamp-if-inside` (default) or `clamp`, the names of
/// `mocap play --policy`). The conversion is the encoder's own (`Figure::from_rig`, the one
/// `mocap play --rig` applies), so host and firmware hold a clip to the same table:
/// `FIGURE_SERVOS` (the rig table a clip made for this figure carries), `FIGURE_RATE_MHZ`,
/// `FIGURE_DIGEST` (its rig digest, SPEC.md §3.6), `HARD_LIMITS` (one per output), `POLICY`.
pub fn figure(manifest_dir: &Path, out_dir: &Path, default: &Path) {
    use mocap_encoder::play::{Figure, Policy};
    use mocap_encoder::rig::Rig;

    println!("cargo:rerun-if-env-changed=MOCAP_FIGURE");
    println!("cargo:rerun-if-env-changed=MOCAP_POLICY");
    let path = match env::var_os("MOCAP_FIGURE") {
        Some(path) if !path.is_empty() => manifest_dir.join(path),
        _ => default.to_path_buf(),
    };
    println!("cargo:rerun-if-changed={}", path.display());
    // Messages name the file as the user gave it (`MOCAP_FIGURE_NAME`, set by
    // scripts/firmware.sh, which builds from a copy named by its content).
    println!("cargo:rerun-if-env-changed=MOCAP_FIGURE_NAME");
    let name = match env::var("MOCAP_FIGURE_NAME") {
        Ok(name) if !name.is_empty() => name,
        _ => path.display().to_string(),
    };
    let text = fs::read_to_string(&path).unwrap_or_else(|e| {
        fail(&format!(
            "mocap-firmware: cannot read the figure's rig file (MOCAP_FIGURE) {name}: {e}"
        ))
    });
    let rig = Rig::parse(&text, &name).unwrap_or_else(|e| {
        fail(&format!(
            "mocap-firmware: the figure's rig file (MOCAP_FIGURE): {e}"
        ))
    });
    let policy = match env::var("MOCAP_POLICY").as_deref().map(str::trim) {
        Ok("") | Err(env::VarError::NotPresent) => Policy::ClampIfInside,
        Ok(name) => Policy::from_name(name).unwrap_or_else(|| {
            fail(&format!(
                "mocap-firmware: MOCAP_POLICY must be one of {} (or unset: clamp-if-inside), got '{name}'",
                Policy::ALL.map(|(_, n)| n).join(", ")
            ))
        }),
        Err(e) => fail(&format!("mocap-firmware: MOCAP_POLICY: {e}")),
    };
    let figure = Figure::from_rig(&rig, policy);
    let n = figure.servos.len();
    // `Debug` of these plain structs is their struct expression.
    let servos: String = figure
        .servos
        .iter()
        .map(|s| format!("    {s:?},\n"))
        .collect();
    let limits: String = figure
        .limits
        .iter()
        .map(|l| format!("    {l:?},\n"))
        .collect();
    let code = format!(
        "// The figure's rig file: {path}\n\
         /// The figure's name (`[rig] name`).\n\
         pub const FIGURE_NAME: &str = {name:?};\n\
         /// The figure's tick rate, millihertz.\n\
         pub const FIGURE_RATE_MHZ: u32 = {rate};\n\
         /// The figure's servos as the rig table of a clip made for it holds them.\n\
         pub static FIGURE_SERVOS: [RigServo; {n}] = [\n{servos}];\n\
         /// The figure's hard limits, one per output.\n\
         pub static HARD_LIMITS: [HardLimit; {n}] = [\n{limits}];\n\
         /// The figure's rig digest (SPEC.md §3.6).\n\
         pub const FIGURE_DIGEST: u32 = {digest:#010x};\n\
         /// What to do with a clip made for another rig (`MOCAP_POLICY`).\n\
         pub const POLICY: Policy = Policy::{policy:?};\n",
        path = path.display(),
        name = rig.name,
        rate = figure.rate_mhz,
        digest = figure.digest,
    );
    write_if_changed(&out_dir.join("figure.rs"), code.as_bytes());
}

pub fn write_if_changed(to: &Path, bytes: &[u8]) {
    // Rewrite only on change: an unchanged copy keeps the firmware from recompiling.
    if fs::read(to).ok().as_deref() != Some(bytes) {
        fs::write(to, bytes).unwrap_or_else(|e| {
            fail(&format!(
                "mocap-firmware: cannot write {}: {e}",
                to.display()
            ))
        });
    }
}

pub fn copy_or_fail(from: &Path, to: &Path, what: &str) {
    let bytes = fs::read(from).unwrap_or_else(|e| {
        fail(&format!(
            "mocap-firmware: cannot read {what} {}: {e}",
            from.display()
        ))
    });
    write_if_changed(to, &bytes);
}
