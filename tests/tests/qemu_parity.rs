//! The firmware example decodes clips on Cortex-M0 (microbit), M3
//! (lm3s6965evb) and M4F (mps2-an386) in QEMU; its UART output must be
//! byte-identical to the host decoder's (firmware-example/README.md gives the
//! format; `#` lines carry statistics and are not compared). Index clips are
//! played frame by frame; pca-spline clips frame by frame and also in the
//! firmware's sample mode (`--sample-us`, `Player::sample_at`), compared with
//! `clipfile::uart_text_sampled`.
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

/// Sample mode period: a 50 Hz servo rate, which falls between the frames of
/// a 120 Hz clip.
const SERVO_PERIOD_US: u64 = 20_000;

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

fn encode_to(
    m: &Motion,
    path: &Path,
    codec: CodecChoice,
    bound: &str,
    key_interval: Option<u16>,
) -> Vec<u8> {
    let opts = EncodeOptions {
        codec,
        bound: Bound::from_specs(&[bound.parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(m).metres(),
        key_interval,
    };
    let bytes = encode::encode(m, &opts).unwrap().bytes;
    std::fs::write(path, &bytes).unwrap();
    bytes
}

fn run_board(board: &str, clip: &Path, sample_us: Option<u64>) -> String {
    run_board_with(board, clip, sample_us, None)
}

fn run_board_with(board: &str, clip: &Path, sample_us: Option<u64>, servo: Option<&str>) -> String {
    let mut cmd = Command::new("bash");
    cmd.arg(workspace_root().join("scripts/firmware.sh"))
        .args(["run", "--board", board, "--clip"])
        .arg(clip);
    if let Some(p) = sample_us {
        cmd.args(["--sample-us", &p.to_string()]);
    }
    if let Some(p) = servo {
        cmd.args(["--servo", p]);
    }
    let out = cmd.output().expect("scripts/firmware.sh runs");
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

/// The UART output without its `#` statistics lines.
fn data_lines(uart: &str) -> String {
    uart.lines()
        .filter(|l| !l.starts_with('#'))
        .flat_map(|l| [l, "\n"])
        .collect()
}

fn check(name: &str, m: &Motion, key_interval: Option<u16>) {
    check_codec(name, m, CodecChoice::Index, "1deg", key_interval, None);
}

/// Encodes `m`, runs the firmware on every board and compares its frame lines
/// with the host decoder: every frame (`next_frame`), or with `sample_us` the
/// firmware's sample mode against `clipfile::uart_text_sampled`.
fn check_codec(
    name: &str,
    m: &Motion,
    codec: CodecChoice,
    bound: &str,
    key_interval: Option<u16>,
    sample_us: Option<u64>,
) {
    let dir = workspace_root().join("target/qemu-parity");
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join(format!("{name}.mcb"));
    let bytes = encode_to(m, &path, codec, bound, key_interval);
    let clip = Clip::parse(&bytes).unwrap();
    let (expected, what) = match sample_us {
        None => {
            let frames = clipfile::decode_all(&clip).unwrap();
            let text = clipfile::uart_text(&frames, clip.header().channel_count());
            (text, format!("{} frames", m.frames()))
        }
        Some(p) => {
            let text = clipfile::uart_text_sampled(&clip, p).unwrap();
            let n = text.lines().count();
            (text, format!("{n} samples every {p} us"))
        }
    };
    for board in BOARDS {
        let uart = run_board(board, &path, sample_us);
        let data = data_lines(&uart);
        assert!(
            data == expected,
            "{name} on {board}: UART output differs from the host decoder ({} vs {} bytes)",
            data.len(),
            expected.len()
        );
        let stats: Vec<&str> = uart.lines().filter(|l| l.starts_with("# ")).collect();
        eprintln!("{name} on {board}: {what} identical; {}", stats.join("; "));
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

/// pca-spline clips: every frame, and `sample_at` at a 50 Hz servo rate.
fn check_pca_spline(name: &str, m: &Motion, bound: &str) {
    let codec = CodecChoice::PcaSpline;
    check_codec(name, m, codec, bound, None, None);
    check_codec(
        &format!("{name}-sampled"),
        m,
        codec,
        bound,
        None,
        Some(SERVO_PERIOD_US),
    );
}

#[test]
fn pca_spline_firmware_output_matches_host_on_three_cores() {
    if !qemu_available() {
        return;
    }
    check_pca_spline("pca-demo", &generate::animatronic_demo(), "1deg");
    if let Some(files) = corpus_files("cmu") {
        let f = files
            .iter()
            .find(|p| p.ends_with("35_01.bvh"))
            .unwrap_or(&files[0]);
        check_pca_spline("pca-cmu-35_01", &bvh::read_file(f).unwrap(), "50mm");
    }
}

/// Servo mode: the demo's servo clip (`mocap encode --rig`) played by the
/// firmware at 50 Hz through the rig mapping and the limiter must send the
/// same Pololu Maestro bytes and SSC-32 text as `mocap play`.
#[test]
fn servo_clip_commands_match_host_on_three_cores() {
    use mocap_encoder::play::Protocol;
    use mocap_encoder::rig::Rig;
    use mocap_encoder::servo_clip;
    if !qemu_available() {
        return;
    }
    let root = workspace_root();
    let rig = Rig::read_file(&root.join("assets/rigs/animatronic_demo.toml")).unwrap();
    let m = generate::animatronic_demo();
    let channels = rig.resolve(&m.skeleton).unwrap();
    let tracks = rig.servo_tracks(&m, &channels, units::detect(&m).metres());
    let sm = servo_clip::servo_motion(&rig, &tracks);
    let opts = EncodeOptions {
        codec: CodecChoice::PcaSpline,
        bound: Bound::from_specs(&["0.5deg".parse::<BoundSpec>().unwrap()]),
        metres_per_unit: 1e-3,
        key_interval: None,
    };
    let enc = encode::encode(&sm, &opts).unwrap();
    let bytes = servo_clip::attach_rig(&enc.bytes, &rig).unwrap();
    let dir = root.join("target/qemu-parity");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("servo-demo.mcb");
    std::fs::write(&path, &bytes).unwrap();
    let clip = Clip::parse(&bytes).unwrap();
    for (protocol, name) in [(Protocol::Maestro, "maestro"), (Protocol::Ssc32, "ssc32")] {
        check_servo_mode(&clip, &path, protocol, name);
    }
}

fn check_servo_mode(
    clip: &Clip<'_>,
    path: &Path,
    protocol: mocap_encoder::play::Protocol,
    name: &str,
) {
    use mocap_encoder::play::{servo_clip_stream, Protocol};
    let stream = servo_clip_stream(clip, protocol, None).unwrap();
    let expected: String = stream
        .ticks
        .iter()
        .map(|t| match protocol {
            Protocol::Maestro => {
                let mut line = String::from("m");
                for b in t {
                    line += &format!(" {b:02x}");
                }
                line + "\n"
            }
            Protocol::Ssc32 => {
                let text = std::str::from_utf8(t).unwrap();
                format!("s {}\n", text.strip_suffix('\r').unwrap())
            }
        })
        .collect();
    for board in BOARDS {
        let uart = run_board_with(board, path, None, Some(name));
        let data = data_lines(&uart);
        assert!(
            data == expected,
            "servo clip on {board}: {name} commands differ from mocap play ({} vs {} ticks)",
            data.lines().count(),
            expected.lines().count()
        );
        let stats: Vec<&str> = uart.lines().filter(|l| l.starts_with("# ")).collect();
        eprintln!(
            "servo clip on {board}: {} ticks of {name} commands identical; {}",
            stream.ticks.len(),
            stats.join("; ")
        );
    }
}
