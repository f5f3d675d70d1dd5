//! The firmware's streaming mode (`scripts/firmware.sh run --stream --input FILE`) on
//! Cortex-M0, M3 and M4F in QEMU, fed the bytes of `mocap send` through its UART receiver
//! (QEMU's `-serial stdio`, stdin from the file; the UART holds QEMU back while it is full).
//!
//! - A clean clip upload (`mocap send`) and a clean pose stream (`mocap send --poses`) must
//!   play byte-identically to `mocap play` of the same servo clip.
//! - The same streams with 1 % of their bytes corrupted (fixed seed): no command outside the
//!   rig's pulse limits or faster than its speed limits, the run ends at neutral, the
//!   firmware's last `Status` frame counts the frames the host's `FrameReceiver` counts on the
//!   same bytes; for the pose stream, the commands are exactly what SPEC.md §8's rules (hold
//!   the last pose over lost ones, ignore stale ones) give through the same `Limiter`.
//!
//! - A clip the firmware must refuse — the demo's motion clip: no rig table, and on the
//!   micro:bit more than its 6 KB buffer — plays nothing.
//!
//! A corrupted stream is followed by a clean `00 Stop`, as a host repeats `Stop` until the
//! firmware confirms it: the stream's own `Stop` may be lost, and the firmware (an example
//! run) ends its session at the first `Stop`. `cargo test -p mocap-tests --test qemu_stream
//! -- --nocapture` prints the link figures (MCU side); the inputs stay in
//! `target/qemu-stream/` for `scripts/firmware.sh run --stream --input … --icount`.

use std::path::{Path, PathBuf};

use mocap_decoder::Clip;
use mocap_encoder::play::{clip_frames, pose_frames, servo_clip_stream, Protocol, ServoStream};
use mocap_servo::output::{MaestroOutput, ServoOutput};
use mocap_servo::stream::{decode_frame, FrameReceiver, Message, MAX_FRAME_LEN};
use mocap_servo::{Limiter, ServoLimits};
use mocap_tests::{qemu_available, run_firmware, servo_demo_clip, workspace_root};

const BOARDS: [&str; 3] = ["microbit", "lm3s6965", "mps2-an386"];
/// One byte in this many is hit by a random non-zero XOR.
const CORRUPT_ONE_IN: u64 = 100;
/// The firmware's rules (firmware-example/src/stream.rs, SPEC.md §8).
const MAX_HOLD_TICKS: u16 = 50;
const MAX_SERVOS: usize = 32;

/// SplitMix64: deterministic, dependency-free.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// `bytes` with about 1 % of them XORed with a random non-zero value, and how many.
/// The first byte (the sender's flushing `00`) is left alone: what arrives before the firmware
/// has set up its UART is lost (QEMU's PL011 drops it when its FIFO is enabled), so only a
/// `00` there reads the same on both sides.
fn corrupt(bytes: &[u8], seed: u64) -> (Vec<u8>, usize) {
    let mut rng = Rng(seed);
    let mut out = bytes.to_vec();
    let mut hit = 0;
    for b in out.iter_mut().skip(1) {
        if rng.next().is_multiple_of(CORRUPT_ONE_IN) {
            *b ^= 1 + (rng.next() % 255) as u8;
            hit += 1;
        }
    }
    (out, hit)
}

/// `bytes`, then a clean `00 Stop` (the firmware ends its session at the first `Stop`).
fn then_stop(mut bytes: Vec<u8>) -> Vec<u8> {
    bytes.push(0);
    bytes.extend([0x06, 0x04, 0x94, 0x2B, 0x6F, 0xD5, 0x00]); // Stop (SPEC.md §8 example)
    bytes
}

/// What the host's receiver makes of `bytes` up to the first accepted `Stop` (where the
/// firmware ends its session): the accepted messages (owned copies), received, dropped.
fn host_receive(bytes: &[u8]) -> (Vec<Received>, u32, u32) {
    let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
    let mut got = Vec::new();
    for &b in bytes {
        if let Some(Ok(m)) = rx.push(b) {
            let r = Received::from(&m);
            let stop = matches!(r, Received::Stop);
            got.push(r);
            if stop {
                break;
            }
        }
    }
    (got, rx.received(), rx.dropped())
}

enum Received {
    Hello,
    Chunk { offset: u32, total: u32, len: usize },
    Play,
    Pose { seq: u16, pulses: Vec<u16> },
    Stop,
    Other,
}

impl From<&Message<'_>> for Received {
    fn from(m: &Message<'_>) -> Self {
        match m {
            Message::Hello { version: 1 } => Received::Hello,
            Message::ClipChunk {
                offset,
                total,
                bytes,
            } => Received::Chunk {
                offset: *offset,
                total: *total,
                len: bytes.len(),
            },
            Message::Play { .. } => Received::Play,
            Message::Pose { seq, pulses } => Received::Pose {
                seq: *seq,
                pulses: pulses.to_vec(),
            },
            Message::Stop => Received::Stop,
            _ => Received::Other,
        }
    }
}

/// The firmware's run: its servo commands (Maestro lines parsed back into pulses), its last
/// `Status`, and its `# link` / `# session` figures.
struct Run {
    ticks: Vec<Vec<u16>>,
    maestro: String,
    status: (u32, u32, u16, u8),
    statuses: usize,
    figures: String,
}

impl Run {
    fn figure(&self, key: &str) -> u64 {
        let pat = format!(" {key}=");
        let at = self
            .figures
            .find(&pat)
            .unwrap_or_else(|| panic!("no {key}"))
            + pat.len();
        let digits: String = self.figures[at..]
            .chars()
            .take_while(char::is_ascii_digit)
            .collect();
        digits.parse().unwrap()
    }
}

fn run_stream(board: &str, clip: &Path, input: &Path) -> Run {
    let uart = run_firmware(
        board,
        clip,
        &[
            "--stream",
            "--icount",
            "--timeout",
            "120",
            "--input",
            input.to_str().unwrap(),
        ],
    );
    let mut ticks = Vec::new();
    let mut maestro = String::new();
    let mut status = None;
    let mut statuses = 0;
    for line in uart.lines() {
        if let Some(hex) = line.strip_prefix("m") {
            maestro += line;
            maestro += "\n";
            let bytes = parse_hex(hex);
            ticks.push(
                bytes
                    .chunks(4)
                    .map(|c| {
                        assert_eq!(c[0], 0x84, "{board}: Set Target");
                        u16::from(c[2]) | u16::from(c[3]) << 7
                    })
                    .collect(),
            );
        } else if let Some(hex) = line.strip_prefix("f") {
            let mut frame = parse_hex(hex);
            match decode_frame(&mut frame).unwrap() {
                Message::Status {
                    received,
                    dropped,
                    last_seq,
                    state,
                } => {
                    status = Some((received, dropped, last_seq, state));
                    statuses += 1;
                }
                Message::Hello { version } => assert_eq!(version, 1),
                m => panic!("{board}: unexpected frame {m:?}"),
            }
        }
    }
    let figures = uart
        .lines()
        .filter(|l| l.starts_with("# link") || l.starts_with("# session"))
        .collect::<Vec<_>>()
        .join(" ");
    Run {
        ticks,
        maestro,
        status: status.unwrap_or_else(|| panic!("{board}: no Status")),
        statuses,
        figures,
    }
}

fn parse_hex(hex: &str) -> Vec<u8> {
    hex.split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect()
}

/// `mocap play`'s Maestro bytes as the firmware prints them.
fn maestro_lines(stream: &ServoStream) -> String {
    stream
        .ticks
        .iter()
        .map(|t| {
            let hex: String = t.iter().map(|b| format!(" {b:02x}")).collect();
            format!("m{hex}\n")
        })
        .collect()
}

/// No pulse outside its servo's limits, no step above its speed limit (from neutral, where
/// the limiter starts), the last command at neutral.
fn check_safe(name: &str, ticks: &[Vec<u16>], limits: &[ServoLimits]) {
    let mut last: Vec<u16> = limits.iter().map(|l| l.neutral_qus).collect();
    for (i, tick) in ticks.iter().enumerate() {
        assert_eq!(tick.len(), limits.len(), "{name} tick {i}");
        for (j, ((&p, l), prev)) in tick.iter().zip(limits).zip(&mut last).enumerate() {
            assert!(
                (l.min_qus..=l.max_qus).contains(&p),
                "{name} tick {i} servo {j}: {p} outside [{}, {}]",
                l.min_qus,
                l.max_qus
            );
            if l.max_step_qus > 0 {
                assert!(
                    p.abs_diff(*prev) <= l.max_step_qus,
                    "{name} tick {i} servo {j}: step {} > {}",
                    p.abs_diff(*prev),
                    l.max_step_qus
                );
            }
            *prev = p;
        }
    }
    for (j, (p, l)) in last.iter().zip(limits).enumerate() {
        assert_eq!(
            *p, l.neutral_qus,
            "{name}: servo {j} does not end at neutral"
        );
    }
}

/// SPEC.md §8's live-pose rules, through the same `Limiter` and `MaestroOutput` as the
/// firmware: a pose per `seq` step, the last pose held over missing ones (at most
/// `MAX_HOLD_TICKS`), stale or wrong-sized poses ignored, `Hello` forgets the last `seq`,
/// `Stop` parks at the speed limits. Returns the Maestro lines and (applied, missing, stale).
fn expected_pose_run(
    received: &[Received],
    limits: &[ServoLimits],
    outputs: &[u16],
) -> (String, [u64; 3]) {
    let idle = ServoLimits::new(6000, 6000, 6000, 0).unwrap();
    let mut all = [idle; MAX_SERVOS];
    all[..limits.len()].copy_from_slice(limits);
    let mut limiter = Limiter::new(all).unwrap();
    let n = limits.len();
    let mut targets = [6000u16; MAX_SERVOS];
    let mut held = [0u16; MAX_SERVOS];
    let mut text = String::new();
    let emit = |pulses: &[u16], text: &mut String| {
        let mut bytes = Vec::new();
        MaestroOutput::new(&mut bytes, outputs)
            .unwrap()
            .write(pulses)
            .unwrap();
        let hex: String = bytes.iter().map(|b| format!(" {b:02x}")).collect();
        *text += &format!("m{hex}\n");
    };
    let (mut applied, mut missing_total, mut stale) = (0, 0, 0);
    let mut live: Option<u16> = None;
    for r in received {
        match r {
            Received::Hello => live = None,
            Received::Pose { seq, pulses } => {
                if pulses.len() != n {
                    continue;
                }
                let gap = live.map_or(1, |last| seq.wrapping_sub(last));
                if gap == 0 || gap >= 0x8000 {
                    stale += 1;
                    continue;
                }
                missing_total += u64::from(gap - 1);
                for _ in 0..(gap - 1).min(MAX_HOLD_TICKS) {
                    limiter.apply(&targets, &mut held).unwrap();
                    emit(&held[..n], &mut text);
                }
                targets[..n].copy_from_slice(pulses);
                limiter.apply(&targets, &mut held).unwrap();
                emit(&held[..n], &mut text);
                applied += 1;
                live = Some(*seq);
            }
            Received::Stop => break,
            _ => {}
        }
    }
    let parked = |l: &Limiter<MAX_SERVOS>| {
        l.limits()
            .iter()
            .zip(l.last())
            .all(|(s, &p)| p == s.neutral_qus)
    };
    while !parked(&limiter) {
        limiter.stop_step(&mut held).unwrap();
        emit(&held[..n], &mut text);
    }
    (text, [applied, missing_total, stale])
}

/// The upload rules: offset 0 starts an upload (if it fits the board's buffer), every other
/// chunk must continue it exactly. Returns (accepted, rejected, complete at `Play`).
fn expected_upload(received: &[Received], capacity: usize) -> (u64, u64, bool) {
    let (mut total, mut len) = (0usize, 0usize);
    let (mut accepted, mut rejected, mut complete) = (0, 0, false);
    for r in received {
        match *r {
            Received::Chunk {
                offset,
                total: t,
                len: n,
            } => {
                let (offset, t) = (offset as usize, t as usize);
                let continues = if offset == 0 {
                    // A new upload; one that cannot fit ends the old one too.
                    (total, len) = (0, 0);
                    if t > 0 && t <= capacity {
                        total = t;
                    }
                    total > 0
                } else {
                    total != 0 && t == total && offset == len
                };
                let ok = continues && len + n <= total;
                if ok {
                    len += n;
                    accepted += 1;
                } else {
                    rejected += 1;
                }
            }
            Received::Play => complete = total > 0 && len == total,
            Received::Stop => break,
            _ => {}
        }
    }
    (accepted, rejected, complete)
}

fn clip_buffer_bytes(board: &str) -> usize {
    match board {
        "microbit" => 6 * 1024,
        "lm3s6965" => 32 * 1024,
        _ => 64 * 1024,
    }
}

fn write_input(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = workspace_root().join("target/qemu-stream");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn streamed_clips_and_poses_play_like_mocap_play_and_survive_corruption() {
    if !qemu_available() {
        return;
    }
    let (clip_path, clip_bytes) = servo_demo_clip("servo-demo-stream");
    let clip = Clip::parse(&clip_bytes).unwrap();
    let played = servo_clip_stream(&clip, Protocol::Maestro, None).unwrap();
    let expected = maestro_lines(&played);
    let limits = played.limits.clone();
    let outputs: Vec<u16> = clip.rig().unwrap().servos().map(|s| s.output).collect();

    let upload: Vec<u8> = clip_frames(&clip_bytes, false).unwrap().concat();
    let poses: Vec<u8> = pose_frames(&clip).unwrap().frames.concat();
    let motion = std::fs::read(workspace_root().join("firmware-example/clips/demo.mcb")).unwrap();
    let (upload_bad, upload_hits) = corrupt(&upload, 0x5EED_0001);
    let (poses_bad, poses_hits) = corrupt(&poses, 0x5EED_0002);
    // (name, bytes, corrupted bytes, a pose stream, the uploaded clip is this rig's)
    let inputs = [
        ("upload", upload.clone(), 0, false, true),
        ("poses", poses.clone(), 0, true, true),
        (
            "upload-1pct",
            then_stop(upload_bad),
            upload_hits,
            false,
            true,
        ),
        ("poses-1pct", then_stop(poses_bad), poses_hits, true, true),
        (
            "motion-clip",
            then_stop(clip_frames(&motion, false).unwrap().concat()),
            0,
            false,
            false,
        ),
    ];

    for board in BOARDS {
        for (name, bytes, hits, is_poses, same_rig) in &inputs {
            let path = write_input(&format!("{name}.bin"), bytes);
            let run = run_stream(board, &clip_path, &path);
            let what = format!("{name} on {board}");
            let (received, host_received, host_dropped) = host_receive(bytes);
            // Every frame the host's receiver counts, the firmware counted (its last Status).
            assert_eq!(
                (run.status.0, run.status.1),
                (host_received, host_dropped),
                "{what}: Status (received, dropped) differs from the host's FrameReceiver"
            );
            assert_eq!(run.status.3, 0, "{what}: the last Status is not idle");
            assert_eq!(
                run.figure("frames_received"),
                u64::from(host_received),
                "{what}"
            );
            check_safe(&what, &run.ticks, &limits);
            let (accepted, rejected, complete) =
                expected_upload(&received, clip_buffer_bytes(board));
            assert_eq!(run.figure("chunks_accepted"), accepted, "{what}");
            assert_eq!(run.figure("chunks_rejected"), rejected, "{what}");
            if *is_poses {
                let (text, [applied, missing, stale]) =
                    expected_pose_run(&received, &limits, &outputs);
                assert!(
                    run.maestro == text,
                    "{what}: commands differ from SPEC.md §8's pose rules ({} vs {} ticks)",
                    run.ticks.len(),
                    text.lines().count()
                );
                assert_eq!(run.figure("poses_applied"), applied, "{what}");
                assert_eq!(run.figure("poses_missing"), missing, "{what}");
                assert_eq!(run.figure("poses_stale"), stale, "{what}");
            } else {
                let plays = complete && *same_rig;
                assert_eq!(run.figure("clips_played"), u64::from(plays), "{what}");
                assert_eq!(run.figure("clips_refused"), u64::from(!plays), "{what}");
                if !plays {
                    assert!(run.ticks.is_empty(), "{what}: a refused clip moved servos");
                }
            }
            if *hits == 0 && *same_rig {
                // Clean: exactly `mocap play`, every frame accepted.
                assert!(
                    run.maestro == expected,
                    "{what}: commands differ from mocap play ({} vs {} ticks)",
                    run.ticks.len(),
                    played.ticks.len()
                );
                assert_eq!(host_dropped, 0);
            } else if *hits > 0 {
                assert!(host_dropped > 0, "{what}: the corruption dropped nothing");
            }
            eprintln!(
                "{what}: {} bytes, {hits} corrupted; {} commands within limits, ends at \
                 neutral; {} Status frames, last {:?}; {}",
                bytes.len(),
                run.ticks.len(),
                run.statuses,
                run.status,
                run.figures
            );
        }
    }
}
