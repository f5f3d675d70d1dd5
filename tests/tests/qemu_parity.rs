//! The firmware example decodes clips on Cortex-M0 (microbit), M3
//! (lm3s6965evb), M4F (mps2-an386) and RISC-V RV32IMC (virt) in QEMU; its UART output must be
//! byte-identical to the host decoder's (firmware-example/README.md gives the
//! format; `#` lines carry statistics and are not compared). Index clips are
//! played frame by frame; pca-spline clips frame by frame and also in the
//! firmware's sample mode (`--sample-us`, `Player::sample_at`), compared with
//! `clipfile::uart_text_sampled`.
//!
//! Every run's data lines are also compared with a committed snapshot,
//! `tests/snapshots/<case>.out` (the same on every board; format and the
//! overwrite switch `MOCAP_BLESS=1` in `tests/snapshots/README.md`), so a
//! change that moves host and firmware together still shows.
//!
//! Needs `scripts/firmware.sh` to work (the README's test command installs
//! what it needs). Without QEMU the test prints SKIPPED, unless `CI` is set,
//! where a missing emulator is a failure.

use std::path::{Path, PathBuf};

use mocap_decoder::Clip;
use mocap_encoder::codec::index::IndexLayout;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{bvh, clipfile, generate, motion::Motion, units};
use mocap_tests::snapshot::{check_snapshot, first_difference};
use mocap_tests::{
    corpus_file, data_lines, demo_figure, qemu_available, run_firmware, servo_demo_clip,
    servo_demo_clip_with, workspace_root,
};

/// Sample mode period: a 50 Hz servo rate, which falls between the frames of
/// a 120 Hz clip.
const SERVO_PERIOD_US: u64 = 20_000;

fn encode_to(
    m: &Motion,
    path: &Path,
    codec: CodecChoice,
    bound: &str,
    key_interval: Option<u16>,
    index_layout: IndexLayout,
) -> Vec<u8> {
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound::from_specs(&[bound.parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(m).metres(),
        key_interval,
        index_layout,
        pattern: Default::default(),
    };
    let bytes = encode::encode(m, &opts).unwrap().bytes;
    std::fs::write(path, &bytes).unwrap();
    bytes
}

fn run_board(board: &str, clip: &Path, sample_us: Option<u64>) -> String {
    run_board_with(board, clip, sample_us, None)
}

fn run_board_with(board: &str, clip: &Path, sample_us: Option<u64>, servo: Option<&str>) -> String {
    let sample = sample_us.map(|p| p.to_string());
    let mut args = Vec::new();
    if let Some(p) = &sample {
        args.extend(["--sample-us", p.as_str()]);
    }
    if let Some(p) = servo {
        args.extend(["--servo", p]);
    }
    run_firmware(board, clip, &args)
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
    check_codec_layout(
        name,
        m,
        (codec, IndexLayout::Compact),
        bound,
        key_interval,
        sample_us,
    );
}

/// [`check_codec`] with the `index` codec's section layout.
fn check_codec_layout(
    name: &str,
    m: &Motion,
    (codec, layout): (CodecChoice, IndexLayout),
    bound: &str,
    key_interval: Option<u16>,
    sample_us: Option<u64>,
) {
    let dir = workspace_root().join("target/qemu-parity");
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join(format!("{name}.mcb"));
    let bytes = encode_to(m, &path, codec, bound, key_interval, layout);
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
    for board in &mocap_tests::boards() {
        let uart = run_board(board, &path, sample_us);
        let data = data_lines(&uart);
        assert!(
            data == expected,
            "{name} on {board}: UART output differs from the host decoder: {}",
            first_difference(&expected, &data)
        );
        check_snapshot(name, &data);
        let stats: Vec<&str> = uart.lines().filter(|l| l.starts_with("# ")).collect();
        eprintln!("{name} on {board}: {what} identical; {}", stats.join("; "));
    }
}

#[test]
fn firmware_output_matches_host_on_every_core() {
    if !qemu_available() {
        return;
    }
    check("demo", &generate::animatronic_demo(), None);
    // Key frames in levels (SPEC.md §4.5).
    check("index-levels", &mocap_tests::far_travelled_demo(), None);
    if let Some(f) = corpus_file("cmu", "35_01.bvh") {
        check("cmu-35_01", &bvh::read_file(&f).unwrap(), None);
    }
    if let Some(f) = corpus_file("iclone-cmu", "002_03.bvh") {
        check("iclone-002_03", &bvh::read_file(&f).unwrap(), Some(16));
    }
}

/// `index` in its fast layout (SPEC.md §4.6): every frame and 50 Hz samples,
/// at the default key interval and with every frame a key frame.
#[test]
fn index_fast_firmware_output_matches_host_on_every_core() {
    if !qemu_available() {
        return;
    }
    let fast = (CodecChoice::Index, IndexLayout::Fast);
    let demo = generate::animatronic_demo();
    check_codec_layout("fast-demo", &demo, fast, "1deg", None, None);
    check_codec_layout("fast-demo-k0", &demo, fast, "1deg", Some(0), None);
    if let Some(f) = corpus_file("cmu", "35_01.bvh") {
        let m = bvh::read_file(&f).unwrap();
        check_codec_layout("fast-cmu-35_01", &m, fast, "1deg", None, None);
        let p = Some(SERVO_PERIOD_US);
        check_codec_layout("fast-cmu-35_01-sampled", &m, fast, "1deg", None, p);
    }
}

/// Every frame, and `sample_at` at a 50 Hz servo rate.
fn check_frames_and_samples(name: &str, m: &Motion, codec: CodecChoice, bound: &str) {
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
fn pca_spline_firmware_output_matches_host_on_every_core() {
    if !qemu_available() {
        return;
    }
    let codec = CodecChoice::PcaSpline;
    check_frames_and_samples("pca-demo", &generate::animatronic_demo(), codec, "1deg");
    if let Some(f) = corpus_file("cmu", "35_01.bvh") {
        check_frames_and_samples("pca-cmu-35_01", &bvh::read_file(&f).unwrap(), codec, "50mm");
    }
}

/// pattern clips: every frame and 50 Hz samples.
#[test]
fn pattern_firmware_output_matches_host_on_every_core() {
    if !qemu_available() {
        return;
    }
    let codec = CodecChoice::Pattern;
    check_frames_and_samples(
        "pattern-demo",
        &generate::animatronic_demo(),
        codec,
        "0.5deg",
    );
    if let Some(f) = corpus_file("cmu", "35_01.bvh") {
        let m = bvh::read_file(&f).unwrap();
        check_frames_and_samples("pattern-cmu-35_01", &m, codec, "50mm");
    }
}

/// rma clips: every frame and 50 Hz samples (the clips fade in and out
/// between frames, SPEC.md §12.4): the demo played twice (its second
/// playing a repeated clip) and 05_04, whose rma clip at 50 mm keeps one.
#[test]
fn rma_firmware_output_matches_host_on_every_core() {
    if !qemu_available() {
        return;
    }
    let codec = CodecChoice::Rma;
    let twice = mocap_tests::demo_played_twice();
    check_frames_and_samples("rma-demo-twice", &twice, codec, "20mm");
    if let Some(f) = corpus_file("cmu", "05_04.bvh") {
        let m = bvh::read_file(&f).unwrap();
        check_frames_and_samples("rma-cmu-05_04", &m, codec, "50mm");
    }
}

/// predictive clips: every frame and 50 Hz samples (the range decoder's
/// state carried from frame to frame), and a predictive servo clip played
/// in servo mode against `mocap play`.
#[test]
fn predictive_firmware_output_matches_host_on_every_core() {
    use mocap_encoder::play::Protocol;
    if !qemu_available() {
        return;
    }
    let codec = CodecChoice::Predictive;
    check_frames_and_samples("pred-demo", &generate::animatronic_demo(), codec, "0.5deg");
    if let Some(f) = corpus_file("cmu", "35_01.bvh") {
        check_frames_and_samples(
            "pred-cmu-35_01",
            &bvh::read_file(&f).unwrap(),
            codec,
            "1deg",
        );
    }
    let (path, bytes) = servo_demo_clip_with("servo-demo-pred", codec);
    let clip = Clip::parse(&bytes).unwrap();
    let expected = serial_lines(&clip, Protocol::Maestro);
    check_servo_output("servo-demo-pred-maestro", &path, "maestro", &expected, None);
}

/// Servo mode: the demo's servo clip (`mocap encode --rig`) played by the
/// firmware at 50 Hz through the rig mapping and the limiter must send the
/// same Pololu Maestro bytes and SSC-32 text as `mocap play`.
#[test]
fn servo_clip_commands_match_host_on_every_core() {
    use mocap_encoder::play::Protocol;
    if !qemu_available() {
        return;
    }
    let (path, bytes) = servo_demo_clip("servo-demo");
    let clip = Clip::parse(&bytes).unwrap();
    for (protocol, name) in [(Protocol::Maestro, "maestro"), (Protocol::Ssc32, "ssc32")] {
        let expected = serial_lines(&clip, protocol);
        check_servo_output(&format!("servo-demo-{name}"), &path, name, &expected, None);
    }
}

/// Power levels (SPEC.md §6.1): the demo's servo clip played with a schedule that visits
/// every level, up and down, mid-stretch too, must send `mocap play --power`'s bytes.
#[test]
fn servo_clip_power_levels_match_host_on_every_core() {
    use mocap_encoder::play::{parse_power, Protocol};
    if !qemu_available() {
        return;
    }
    const SCHEDULE: &str = "0,3@1s,1@2.03s,4@3s,2@5.1s,0@6.05s,4@7s";
    let (path, bytes) = servo_demo_clip("servo-demo-power");
    let clip = Clip::parse(&bytes).unwrap();
    let power = parse_power(SCHEDULE).unwrap();
    let expected = serial_lines_at(&clip, Protocol::Maestro, &power);
    // The levels change the bytes: the test would pass on a firmware that ignored them otherwise.
    assert_ne!(expected, serial_lines(&clip, Protocol::Maestro));
    for board in &mocap_tests::boards() {
        let uart = run_firmware(
            board,
            &path,
            &["--servo", "maestro", "--power", SCHEDULE, "--icount"],
        );
        let data = data_lines(&uart);
        assert!(
            data == expected,
            "power levels on {board}: lines differ from the host: {}",
            first_difference(&expected, &data)
        );
        eprintln!(
            "power levels on {board}: {} ticks identical; {}",
            expected.lines().count(),
            uart.lines()
                .filter(|l| l.starts_with("# servo_ticks"))
                .collect::<String>()
        );
    }
}

/// `mocap play`'s Maestro bytes as hex lines, its SSC-32 text without the `\r`.
/// On the demo figure, as the firmware holds the clip to it (its default `MOCAP_FIGURE`).
fn serial_lines(clip: &Clip<'_>, protocol: mocap_encoder::play::Protocol) -> String {
    serial_lines_at(clip, protocol, &[])
}

/// [`serial_lines`] at the power levels of a schedule.
fn serial_lines_at(
    clip: &Clip<'_>,
    protocol: mocap_encoder::play::Protocol,
    power: &[(u64, u8)],
) -> String {
    use mocap_encoder::play::{servo_clip_stream_at, Policy, Protocol};
    let figure = demo_figure(Policy::ClampIfInside);
    let stream = servo_clip_stream_at(clip, Some(&figure), protocol, None, power).unwrap();
    stream
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
        .collect()
}

/// Runs the firmware's servo mode with `output` on every board and compares
/// its tick lines with `expected` (and its `# output=` line with `header`),
/// and with the snapshot `case`.
fn check_servo_output(case: &str, path: &Path, output: &str, expected: &str, header: Option<&str>) {
    for board in &mocap_tests::boards() {
        let uart = run_board_with(board, path, None, Some(output));
        if let Some(header) = header {
            // The peripheral the host simulated is the firmware's.
            assert!(uart.lines().any(|l| l == header), "{board}: no `{header}`");
        }
        let data = data_lines(&uart);
        assert!(
            data == expected,
            "servo clip on {board}: {output} lines differ from the host: {}",
            first_difference(expected, &data)
        );
        check_snapshot(case, &data);
        let stats: Vec<&str> = uart.lines().filter(|l| l.starts_with("# ")).collect();
        eprintln!(
            "servo clip on {board}: {} lines of {output} output identical; {}",
            expected.lines().count(),
            stats.join("; ")
        );
    }
}

/// The firmware's simulated PWM peripheral and PCA9685 (firmware-example/src/servo.rs), as
/// its `# output=` line states them.
const PWM_CHANNELS: usize = 16;
const PWM_MAX_DUTY: u16 = u16::MAX;
const PCA9685_ADDRESS: u8 = 0x40;

/// `mocap play`'s pulses (clip ticks, then the return to neutral) through the same
/// `mocap_servo::output::PwmOutput` on 16 recording `SetDutyCycle` channels: a line per tick
/// of every channel's duty.
fn pwm_lines(pulses: &[Vec<u16>], outputs: &[u16]) -> String {
    use mocap_servo::output::{PwmOutput, ServoOutput};
    use mocap_servo::record::DutyRecorder;
    use mocap_servo::ServoBank;
    let channels: [DutyRecorder; PWM_CHANNELS] =
        std::array::from_fn(|_| DutyRecorder::new(PWM_MAX_DUTY));
    let mut output = PwmOutput::new(ServoBank::new(channels.each_ref()), outputs).unwrap();
    let mut text = String::new();
    for tick in pulses {
        output.write(tick).unwrap();
        text += "p";
        for c in &channels {
            text += &format!(" {}", c.duty());
        }
        text += "\n";
    }
    text
}

/// The same pulses through `Pca9685Output` (pwm-pca9685 at 50 Hz) on a recording I²C bus: the
/// set-up writes, then a line per tick of every write (`@address` and its bytes).
fn pca9685_lines(pulses: &[Vec<u16>], outputs: &[u16]) -> String {
    use mocap_servo::output::{Pca9685Output, ServoOutput};
    use mocap_servo::pca9685::{Address, Pca9685Servos};
    use mocap_servo::record::I2cRecorder;
    let bus = I2cRecorder::<1024>::new();
    let line = |bus: &I2cRecorder<1024>| {
        let mut line = String::from("i");
        bus.for_each_write(|address, bytes| {
            line += &format!(" @{address:02x}");
            for b in bytes {
                line += &format!(" {b:02x}");
            }
        })
        .unwrap();
        bus.clear();
        line + "\n"
    };
    let device = Pca9685Servos::new(&bus, Address::from(PCA9685_ADDRESS)).unwrap();
    let mut text = line(&bus);
    let mut output = Pca9685Output::new(device, outputs).unwrap();
    for tick in pulses {
        output.write(tick).unwrap();
        text += &line(&bus);
    }
    text
}

/// The playback loop's two other outputs: PWM channels through `ServoBank`
/// (embedded-hal `SetDutyCycle`) and a PCA9685 over I²C. QEMU's boards have
/// neither, so the firmware drives recording devices and prints a line per
/// tick; the host drives the same outputs with `mocap play`'s pulses.
#[test]
fn servo_clip_pwm_and_pca9685_match_host_on_every_core() {
    use mocap_encoder::play::{servo_clip_stream_on, Policy, Protocol};
    if !qemu_available() {
        return;
    }
    let (path, bytes) = servo_demo_clip("servo-demo-pwm");
    let clip = Clip::parse(&bytes).unwrap();
    let figure = demo_figure(Policy::ClampIfInside);
    let pulses = servo_clip_stream_on(&clip, &figure, Protocol::Maestro, None)
        .unwrap()
        .pulses;
    let outputs: Vec<u16> = clip.rig().unwrap().servos().map(|s| s.output).collect();
    let pwm = pwm_lines(&pulses, &outputs);
    let pca = pca9685_lines(&pulses, &outputs);
    // Sanity of the expectations themselves: a line per tick (and the PCA9685's set-up),
    // and the servos move.
    assert_eq!(pwm.lines().count(), pulses.len());
    assert_eq!(pca.lines().count(), pulses.len() + 1);
    assert!(pwm.lines().collect::<std::collections::HashSet<_>>().len() > pulses.len() / 2);
    for (output, expected, header) in [
        (
            "pwm",
            &pwm,
            format!("# output=pwm channels={PWM_CHANNELS} max_duty={PWM_MAX_DUTY} period_us=20000"),
        ),
        (
            "pca9685",
            &pca,
            format!("# output=pca9685 address={PCA9685_ADDRESS} prescale=121"),
        ),
    ] {
        check_servo_output(
            &format!("servo-demo-{output}"),
            &path,
            output,
            expected,
            Some(&header),
        );
    }
}
