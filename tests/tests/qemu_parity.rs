//! The firmware example decodes clips on Cortex-M0 (microbit), M3
//! (lm3s6965evb) and M4F (mps2-an386) in QEMU; its UART output must be
//! byte-identical to the host decoder's (firmware-example/README.md gives the
//! format; `#` lines carry statistics and are not compared).
//!
//! Needs `scripts/firmware.sh` to work (the README's test command installs
//! what it needs). Without QEMU the test prints SKIPPED, unless `CI` is set,
//! where a missing emulator is a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

use mocap_decoder::Clip;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{bvh, clipfile, generate, motion::Motion, units};
use mocap_tests::{corpus_files, workspace_root};

const BOARDS: [&str; 3] = ["microbit", "lm3s6965", "mps2-an386"];

fn qemu_available() -> bool {
    let ok = Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        if std::env::var_os("CI").is_some() {
            panic!("qemu-system-arm missing in CI: run the README's test command");
        }
        mocap_tests::skipped("qemu-system-arm not found (run scripts/test.sh, which installs it)");
    }
    ok
}

fn encode_to(m: &Motion, path: &Path, key_interval: Option<u16>) -> Vec<u8> {
    let opts = EncodeOptions {
        codec: CodecChoice::Index,
        bound: Bound::from_specs(&["1deg".parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(m).metres(),
        key_interval,
    };
    let bytes = encode::encode(m, &opts).unwrap().bytes;
    std::fs::write(path, &bytes).unwrap();
    bytes
}

fn run_board(board: &str, clip: &Path) -> String {
    let out = Command::new("bash")
        .arg(workspace_root().join("scripts/firmware.sh"))
        .args(["run", "--board", board, "--clip"])
        .arg(clip)
        .output()
        .expect("scripts/firmware.sh runs");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{board} {}: firmware failed ({}):\n{}\n{}",
        clip.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr),
        stdout
            .lines()
            .filter(|l| l.starts_with('#'))
            .collect::<Vec<_>>()
            .join("\n")
    );
    stdout
}

fn check(name: &str, m: &Motion, key_interval: Option<u16>) {
    let dir = workspace_root().join("target/qemu-parity");
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join(format!("{name}.mcb"));
    let bytes = encode_to(m, &path, key_interval);
    let clip = Clip::parse(&bytes).unwrap();
    let frames = clipfile::decode_all(&clip).unwrap();
    let expected = clipfile::uart_text(&frames, clip.header().channel_count());
    for board in BOARDS {
        let uart = run_board(board, &path);
        let data: String = uart
            .lines()
            .filter(|l| !l.starts_with('#'))
            .flat_map(|l| [l, "\n"])
            .collect();
        assert!(
            data == expected,
            "{name} on {board}: UART output differs from the host decoder ({} vs {} bytes)",
            data.len(),
            expected.len()
        );
        let stats: Vec<&str> = uart.lines().filter(|l| l.starts_with("# ")).collect();
        eprintln!(
            "{name} on {board}: {} frames identical; {}",
            m.frames(),
            stats.join("; ")
        );
    }
}

#[test]
fn firmware_output_matches_host_on_three_cores() {
    if !qemu_available() {
        return;
    }
    check("demo", &generate::animatronic_demo(), None);
    if let Some(files) = corpus_files("cmu") {
        let f = files
            .iter()
            .find(|p| p.ends_with("35_01.bvh"))
            .unwrap_or(&files[0]);
        check("cmu-35_01", &bvh::read_file(f).unwrap(), None);
    }
    if let Some(files) = corpus_files("iclone-cmu") {
        let f = files
            .iter()
            .find(|p| p.ends_with("002_03.bvh"))
            .unwrap_or(&files[0]);
        check("iclone-002_03", &bvh::read_file(f).unwrap(), Some(16));
    }
}
