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
//! - The upload as a carousel (`mocap send --passes N`) with the same corruption (same seed,
//!   so its first pass is hit exactly as the one-pass upload): the firmware collects every chunk
//!   from whichever pass brings it and plays the clip byte-identically to `mocap play`; with one
//!   pass the `Play` is only armed and nothing moves. A clean upload in a scrambled order with
//!   copies, inconsistent chunks and an early `Play` plays byte-identically too.
//! - A clip the firmware must refuse — the demo's motion clip: no rig table, and on the
//!   micro:bit more than its 6 KB buffer — plays nothing.
//! - Every run's session figures and last `Status` are those of [`session_model`]: the host's
//!   `FrameReceiver` and the firmware's own upload rule (`mocap_servo::stream::upload`) on the
//!   same bytes, up to where the firmware stopped reading.
//! - Every run's servo commands match the committed snapshot `tests/snapshots/stream-<input>.out`
//!   (`tests/snapshots/README.md`; `MOCAP_BLESS=1` overwrites it).
//!
//! A corrupted stream that will not play is followed by a clean `00 Stop`, as a host repeats
//! `Stop` until the firmware confirms it: the stream's own `Stop` may be lost, and the firmware
//! (an example run) ends its session at the first `Stop` (or at the end of a clip).
//! `cargo test -p mocap-tests --test qemu_stream -- --nocapture` prints the link figures (MCU
//! side) and the carousel's completion rates over 200 seeds
//! ([`carousel_completion_rates`], host only); the inputs stay in `target/qemu-stream/` for
//! `scripts/firmware.sh run --stream --input … --icount`.

use std::path::{Path, PathBuf};

use mocap_decoder::Clip;
use mocap_encoder::play::{
    clip_frames, pose_frames, servo_clip_stream_on, Figure, Policy, Protocol, ServoStream,
};
use mocap_servo::output::MaestroOutput;
use mocap_servo::record::SerialRecorder;
use mocap_servo::stream::upload::{bitmap_words, Accepted, Play, Upload};
use mocap_servo::stream::{
    decode_frame, encode_frame, FrameReceiver, Message, MAX_CHUNK_LEN, MAX_FRAME_LEN,
    PROTOCOL_VERSION,
};
use mocap_servo::{HardLimits, HardStep, Playback, ServoLimits};
use mocap_tests::snapshot::check_snapshot;
use mocap_tests::{demo_figure, qemu_available, run_firmware, servo_demo_clip, workspace_root};

/// One byte in this many is hit by a random non-zero XOR.
const CORRUPT_ONE_IN: u64 = 100;
/// The seed of the corrupted upload (one pass and the carousel).
const UPLOAD_SEED: u64 = 0x5EED_0001;
/// Passes of the corrupted carousel run in QEMU: enough for [`UPLOAD_SEED`] (see
/// [`carousel_completion_rates`] for how often a number of passes is enough).
const CAROUSEL_PASSES: u32 = 8;
/// The firmware's rules (firmware-example/src/stream.rs, SPEC.md §8).
const MAX_HOLD_TICKS: u16 = 50;
const MAX_SERVOS: usize = 32;
/// A bitmap for the largest board buffer (64 KB); the buffer bounds the clip as on the board.
type Clips = Upload<{ bitmap_words(64 * 1024) }>;

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

/// `bytes` with one byte in `one_in` (on average) XORed with a random non-zero value, and how
/// many. The first byte (the sender's flushing `00`) is left alone: what arrives before the
/// firmware has set up its UART is lost (QEMU's PL011 drops it when its FIFO is enabled), so
/// only a `00` there reads the same on both sides.
fn corrupt_one_in(bytes: &[u8], seed: u64, one_in: u64) -> (Vec<u8>, usize) {
    let mut rng = Rng(seed);
    let mut out = bytes.to_vec();
    let mut hit = 0;
    for b in out.iter_mut().skip(1) {
        if rng.next().is_multiple_of(one_in) {
            *b ^= 1 + (rng.next() % 255) as u8;
            hit += 1;
        }
    }
    (out, hit)
}

/// 1 % of the bytes corrupted.
fn corrupt(bytes: &[u8], seed: u64) -> (Vec<u8>, usize) {
    corrupt_one_in(bytes, seed, CORRUPT_ONE_IN)
}

/// `bytes`, then a clean `00 Stop` (the firmware ends its session at the first `Stop`).
fn then_stop(mut bytes: Vec<u8>) -> Vec<u8> {
    bytes.push(0);
    bytes.extend([0x06, 0x04, 0x94, 0x2B, 0x6F, 0xD5, 0x00]); // Stop (SPEC.md §8 example)
    bytes
}

/// What the host's receiver makes of `bytes` up to the first accepted `Stop` (where the
/// firmware ends its session): the accepted messages (owned copies).
fn host_receive(bytes: &[u8]) -> Vec<Received> {
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
    got
}

enum Received {
    Hello,
    Chunk {
        offset: u32,
        total: u32,
        bytes: Vec<u8>,
    },
    Play {
        looped: bool,
    },
    Pose {
        seq: u16,
        pulses: Vec<u16>,
    },
    Stop,
    /// `Status`, a `Hello` of another version: counted, nothing else.
    Other,
}

impl From<&Message<'_>> for Received {
    fn from(m: &Message<'_>) -> Self {
        match m {
            Message::Hello { version } if *version == PROTOCOL_VERSION => Received::Hello,
            Message::ClipChunk {
                offset,
                total,
                bytes,
            } => Received::Chunk {
                offset: *offset,
                total: *total,
                bytes: bytes.to_vec(),
            },
            Message::Play { loop_ } => Received::Play { looped: *loop_ },
            Message::Pose { seq, pulses } => Received::Pose {
                seq: *seq,
                pulses: pulses.to_vec(),
            },
            Message::Stop => Received::Stop,
            _ => Received::Other,
        }
    }
}

/// The firmware's session figures (`# session`, the last `Status`) at one point of a stream.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Figures {
    /// The receiver's frame counts.
    received: u32,
    dropped: u32,
    /// `Status.chunks`: distinct chunks of the upload.
    chunks: u32,
    chunks_accepted: u64,
    chunks_duplicate: u64,
    chunks_rejected: u64,
    plays_armed: u64,
    clips_played: u64,
    clips_refused: u64,
    other_frames: u64,
}

/// SPEC.md §8.1's upload and `Play` rules as the firmware runs them — the host's
/// `FrameReceiver`, then the same `Upload` (`mocap_servo::stream::upload`) into a buffer of
/// `capacity` bytes — on `bytes` up to the first `Stop`: the figures after every frame end,
/// and the index of the one at which a clip started (`valid` says whether a complete upload is
/// a clip the firmware plays: `Clip::parse` and its rig). A `Play` while a clip plays is
/// counted in `other_frames`; chunks then are only checked; `Hello`, `Pose` and `Stop` end the
/// clip (a `Pose` also forgets an armed `Play`, `Hello` the upload).
fn session_model(
    bytes: &[u8],
    capacity: usize,
    valid: impl Fn(&[u8]) -> bool,
) -> (Vec<Figures>, Option<usize>) {
    let mut rx = FrameReceiver::<MAX_FRAME_LEN>::new();
    let mut upload = Clips::new();
    let mut buffer = vec![0u8; capacity];
    let mut f = Figures::default();
    let (mut snapshots, mut started, mut playing) = (Vec::new(), None, false);
    for &b in bytes {
        let Some(frame) = rx.push(b) else { continue };
        let message = frame.ok().map(|m| Received::from(&m));
        let mut start = false;
        let mut stop = false;
        match message {
            None => {}
            Some(Received::Hello) => {
                upload.reset();
                playing = false;
            }
            Some(Received::Chunk {
                offset,
                total,
                bytes,
            }) if playing => match upload.check(capacity, offset, total, bytes.len()) {
                Ok(_) => f.chunks_duplicate += 1,
                Err(_) => f.chunks_rejected += 1,
            },
            Some(Received::Chunk {
                offset,
                total,
                bytes,
            }) => match upload.accept(&mut buffer, offset, total, &bytes) {
                Ok(Accepted::New) => {
                    f.chunks_accepted += 1;
                    start = upload.take_armed().is_some();
                }
                Ok(Accepted::Duplicate) => f.chunks_duplicate += 1,
                Err(_) => f.chunks_rejected += 1,
            },
            Some(Received::Play { .. }) if playing => f.other_frames += 1,
            Some(Received::Play { looped }) => match upload.play(looped) {
                Play::Start => start = true,
                Play::Armed => f.plays_armed += 1,
                Play::NoUpload => f.clips_refused += 1,
            },
            Some(Received::Pose { .. }) => {
                upload.disarm();
                playing = false;
            }
            Some(Received::Stop) => stop = true,
            Some(Received::Other) => f.other_frames += 1,
        }
        if start {
            if upload.complete(&buffer).is_some_and(&valid) {
                f.clips_played += 1;
                playing = true;
                started.get_or_insert(snapshots.len());
            } else {
                upload.reset();
                f.clips_refused += 1;
            }
        }
        (f.received, f.dropped, f.chunks) = (rx.received(), rx.dropped(), upload.received());
        snapshots.push(f);
        if stop {
            break;
        }
    }
    (snapshots, started)
}

/// The firmware's run: its servo commands (Maestro lines parsed back into pulses), its last
/// `Status`, and its `# link` / `# session` figures.
struct Run {
    ticks: Vec<Vec<u16>>,
    maestro: String,
    status: (u32, u32, u16, u8, u32),
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

    /// The figures [`session_model`] predicts, as the firmware reports them.
    fn session(&self) -> Figures {
        Figures {
            received: self.status.0,
            dropped: self.status.1,
            chunks: self.status.4,
            chunks_accepted: self.figure("chunks_accepted"),
            chunks_duplicate: self.figure("chunks_duplicate"),
            chunks_rejected: self.figure("chunks_rejected"),
            plays_armed: self.figure("plays_armed"),
            clips_played: self.figure("clips_played"),
            clips_refused: self.figure("clips_refused"),
            other_frames: self.figure("other_frames"),
        }
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
                    chunks,
                } => {
                    status = Some((received, dropped, last_seq, state, chunks));
                    statuses += 1;
                }
                Message::Hello { version } => assert_eq!(version, PROTOCOL_VERSION),
                m => panic!("{board}: unexpected frame {m:?}"),
            }
        }
    }
    let figures = uart
        .lines()
        .filter(|l| {
            l.starts_with("# link")
                || l.starts_with("# session")
                || l.starts_with("# mode=stream")
                || l.starts_with("# fault=")
        })
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

/// SPEC.md §8's live-pose rules, through the same `Playback` as the firmware (the figure's
/// servos at its rate, its limits, then its hard limits) and `MaestroOutput`: a pose per `seq`
/// step, the last pose held over missing ones (at most `MAX_HOLD_TICKS`), stale or wrong-sized
/// poses ignored, `Hello` forgets the last `seq`, `Stop` parks at the speed limits. Returns the
/// Maestro lines and (applied, missing, stale).
fn expected_pose_run(received: &[Received], figure: &Figure) -> (String, [u64; 3]) {
    let (mut playback, _) =
        Playback::<MAX_SERVOS>::new(figure.servos.iter().copied(), figure.rate_mhz)
            .unwrap()
            .with_hard_limits(&HardLimits::new(&figure.limits), true, figure.policy)
            .unwrap();
    let outputs: Vec<u16> = figure.servos.iter().map(|s| s.output).collect();
    let n = outputs.len();
    let port = SerialRecorder::<{ 4 * MAX_SERVOS }>::new();
    let mut output = MaestroOutput::new(&port, &outputs).unwrap();
    let mut targets = [6000u16; MAX_SERVOS];
    let mut text = String::new();
    let emit = |_: &mut MaestroOutput<&SerialRecorder<{ 4 * MAX_SERVOS }>>, text: &mut String| {
        port.with_bytes(|bytes| {
            let hex: String = bytes.iter().map(|b| format!(" {b:02x}")).collect();
            *text += &format!("m{hex}\n");
        })
        .unwrap();
        port.clear();
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
                    playback.tick(&targets, &mut output).unwrap();
                    emit(&mut output, &mut text);
                }
                targets[..n].copy_from_slice(pulses);
                playback.tick(&targets, &mut output).unwrap();
                emit(&mut output, &mut text);
                applied += 1;
                live = Some(*seq);
            }
            Received::Stop => break,
            _ => {}
        }
    }
    while !playback.parked() {
        playback.stop_tick(&mut output).unwrap();
        emit(&mut output, &mut text);
    }
    (text, [applied, missing_total, stale])
}

fn clip_buffer_bytes(board: &str) -> usize {
    match board {
        "microbit" => 6 * 1024,
        "lm3s6965" | "riscv-virt" => 32 * 1024,
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

/// One frame of `message`.
fn frame(message: &Message<'_>) -> Vec<u8> {
    let mut wire = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(message, &mut wire).unwrap();
    wire[..n].to_vec()
}

/// A clean upload out of order: `00 Hello`, the odd chunks from the last, an early `Play`
/// (armed), two inconsistent chunks (misaligned; another clip's `total`), the even chunks but
/// chunk 0 with a copy of chunk 2, then chunk 0 (which starts the clip), a copy of chunk 5 and
/// a `Play` (while the clip plays).
fn scrambled_upload(clip: &[u8]) -> Vec<u8> {
    let total = clip.len() as u32;
    let chunk = |i: usize| {
        let start = i * MAX_CHUNK_LEN;
        frame(&Message::ClipChunk {
            offset: start as u32,
            total,
            bytes: &clip[start..clip.len().min(start + MAX_CHUNK_LEN)],
        })
    };
    let n = clip.len().div_ceil(MAX_CHUNK_LEN);
    let mut bytes = vec![0];
    bytes.extend(frame(&Message::Hello {
        version: PROTOCOL_VERSION,
    }));
    for i in (1..n).step_by(2).rev() {
        bytes.extend(chunk(i));
    }
    bytes.extend(frame(&Message::Play { loop_: false }));
    bytes.extend(frame(&Message::ClipChunk {
        offset: 32,
        total,
        bytes: &clip[32..96],
    }));
    bytes.extend(frame(&Message::ClipChunk {
        offset: 64,
        total: total + 1,
        bytes: &clip[64..128],
    }));
    for i in (2..n).step_by(2) {
        bytes.extend(chunk(i));
        if i == 2 {
            bytes.extend(chunk(2));
        }
    }
    bytes.extend(chunk(0));
    bytes.extend(chunk(5));
    bytes.extend(frame(&Message::Play { loop_: false }));
    bytes
}

/// One input of the QEMU runs.
struct Input {
    name: &'static str,
    bytes: Vec<u8>,
    /// Bytes corrupted.
    hits: usize,
    /// A pose stream (else an upload).
    poses: bool,
    /// The uploaded clip is this firmware's rig's.
    same_rig: bool,
}

#[test]
fn streamed_clips_and_poses_play_like_mocap_play_and_survive_corruption() {
    if !qemu_available() {
        return;
    }
    let (clip_path, clip_bytes) = servo_demo_clip("servo-demo-stream");
    let clip = Clip::parse(&clip_bytes).unwrap();
    // The firmware plays on its figure (the default MOCAP_FIGURE, the demo rig).
    let figure = demo_figure(Policy::ClampIfInside);
    let played = servo_clip_stream_on(&clip, &figure, Protocol::Maestro, None).unwrap();
    let expected = maestro_lines(&played);
    let limits = played.limits.clone();
    // The figure's hard limits at its rate, as a limiter's: every command inside them too.
    let hard: Vec<ServoLimits> = figure
        .limits
        .iter()
        .map(|l| {
            let h = HardStep::at_rate(l, figure.rate_mhz);
            ServoLimits::new(h.min_qus, h.max_qus, h.neutral_qus, h.max_step_qus).unwrap()
        })
        .collect();

    let upload: Vec<u8> = clip_frames(&clip_bytes, false, 1).unwrap().concat();
    let carousel: Vec<u8> = clip_frames(&clip_bytes, false, CAROUSEL_PASSES)
        .unwrap()
        .concat();
    let poses: Vec<u8> = pose_frames(&clip).unwrap().frames.concat();
    let motion = std::fs::read(workspace_root().join("firmware-example/clips/demo.mcb")).unwrap();
    let (upload_bad, upload_hits) = corrupt(&upload, UPLOAD_SEED);
    let (carousel_bad, carousel_hits) = corrupt(&carousel, UPLOAD_SEED);
    assert_eq!(
        carousel_bad[..upload.len()],
        upload_bad[..],
        "the carousel's first pass is hit as the one-pass upload"
    );
    let (poses_bad, poses_hits) = corrupt(&poses, 0x5EED_0002);
    // Heavier corruption, and cut cables: the stream stops mid-frame (no `Stop`), and the
    // firmware's gap timeout parks the servos.
    let (poses_10, poses_10_hits) = corrupt_one_in(&poses, 0x5EED_0010, 10);
    let (poses_50, poses_50_hits) = corrupt_one_in(&poses, 0x5EED_0050, 2);
    let (upload_10, upload_10_hits) = corrupt_one_in(&upload, 0x5EED_0011, 10);
    let (upload_50, upload_50_hits) = corrupt_one_in(&upload, 0x5EED_0051, 2);
    let cut = |bytes: &[u8], fraction: f64| {
        // Past a delimiter, into the next frame: mid-frame.
        let at = (bytes.len() as f64 * fraction) as usize;
        let next = at + bytes[at..].iter().position(|&b| b == 0).unwrap();
        bytes[..next + 3].to_vec()
    };
    let poses_cut = cut(&poses, 0.4);
    let upload_cut = cut(&upload, 0.5);
    let input = |name, bytes, hits, poses, same_rig| Input {
        name,
        bytes,
        hits,
        poses,
        same_rig,
    };
    let inputs = [
        input("upload", upload.clone(), 0, false, true),
        input("poses", poses.clone(), 0, true, true),
        input(
            "upload-scrambled",
            scrambled_upload(&clip_bytes),
            0,
            false,
            true,
        ),
        input(
            "upload-1pct",
            then_stop(upload_bad),
            upload_hits,
            false,
            true,
        ),
        // No `Stop` after it: the clip plays (checked on the host first), and the firmware
        // reads the rest of the carousel while it plays; a `Stop` would cut it short.
        input(
            "upload-1pct-carousel",
            carousel_bad,
            carousel_hits,
            false,
            true,
        ),
        input("poses-1pct", then_stop(poses_bad), poses_hits, true, true),
        input(
            "poses-10pct",
            then_stop(poses_10),
            poses_10_hits,
            true,
            true,
        ),
        input(
            "poses-50pct",
            then_stop(poses_50),
            poses_50_hits,
            true,
            true,
        ),
        input(
            "upload-10pct",
            then_stop(upload_10),
            upload_10_hits,
            false,
            true,
        ),
        input(
            "upload-50pct",
            then_stop(upload_50),
            upload_50_hits,
            false,
            true,
        ),
        input("poses-cut", poses_cut, 0, true, true),
        input("upload-cut", upload_cut, 0, false, true),
        input(
            "motion-clip",
            then_stop(clip_frames(&motion, false, 1).unwrap().concat()),
            0,
            false,
            false,
        ),
    ];

    for board in &mocap_tests::boards() {
        for input in &inputs {
            let Input {
                name,
                bytes,
                hits,
                poses: is_poses,
                same_rig,
            } = input;
            let capacity = clip_buffer_bytes(board);
            let valid = |c: &[u8]| *same_rig && Clip::parse(c).is_ok();
            let (snapshots, started) = session_model(bytes, capacity, valid);
            let last = *snapshots.last().unwrap();
            let plays = started.is_some();
            let what = format!("{name} on {board}");
            match *name {
                "upload" | "upload-scrambled" | "upload-1pct-carousel" => {
                    assert!(
                        plays,
                        "{what}: the host's model of the firmware does not play it"
                    )
                }
                "upload-1pct" | "motion-clip" => {
                    assert!(!plays, "{what}: the host's model plays it")
                }
                _ => {}
            }
            let path = write_input(&format!("{name}.bin"), bytes);
            let run = run_stream(board, &clip_path, &path);
            // The firmware's figures are the model's where the firmware stopped reading: the
            // first `Stop`, or (for a clip that plays) anywhere after the clip started, where it
            // ended.
            let session = run.session();
            let at = snapshots
                .iter()
                .position(|f| (f.received, f.dropped) == (session.received, session.dropped))
                .unwrap_or_else(|| {
                    panic!(
                        "{what}: Status {:?} is nowhere in the host's model",
                        run.status
                    )
                });
            assert_eq!(session, snapshots[at], "{what}: session figures differ");
            match started {
                Some(start) => assert!(at >= start, "{what}: stopped before the clip started"),
                None => assert_eq!(at, snapshots.len() - 1, "{what}: stopped early"),
            }
            assert_eq!(run.status.3, 0, "{what}: the last Status is not idle");
            assert_eq!(
                run.figure("frames_received"),
                u64::from(session.received),
                "{what}"
            );
            check_safe(&what, &run.ticks, &limits);
            check_safe(&format!("{what} (hard limits)"), &run.ticks, &hard);
            if name.ends_with("-cut") {
                // A cut cable: the gap timeout, then neutral at the speed limits within the
                // documented time (STREAM_TIMEOUT_MS + park_ticks_max ticks).
                let timeout_ms = run.figure("timeout_ms");
                let park_ticks = run.figure("park_ticks");
                let park_max = run.figure("park_ticks_max");
                assert_eq!(run.figure("timeouts"), 1, "{what}: no gap timeout");
                assert!(
                    park_ticks <= park_max,
                    "{what}: parked in {park_ticks} ticks, documented at most {park_max}"
                );
                eprintln!(
                    "{what}: cable cut; {timeout_ms} ms timeout, neutral after {park_ticks} ticks \
                     ({} ms; documented at most {park_max} ticks = {} ms)",
                    run.figure("park_ms"),
                    park_max * 1_000_000 / u64::from(figure.rate_mhz)
                );
            }
            if *is_poses {
                let received = host_receive(bytes);
                let (text, [applied, missing, stale]) = expected_pose_run(&received, &figure);
                assert!(
                    run.maestro == text,
                    "{what}: commands differ from SPEC.md §8's pose rules ({} vs {} ticks)",
                    run.ticks.len(),
                    text.lines().count()
                );
                assert_eq!(run.figure("poses_applied"), applied, "{what}");
                assert_eq!(run.figure("poses_missing"), missing, "{what}");
                assert_eq!(run.figure("poses_stale"), stale, "{what}");
            } else if plays {
                // Exactly `mocap play`, whatever was lost or came out of order.
                assert!(
                    run.maestro == expected,
                    "{what}: commands differ from mocap play ({} vs {} ticks)",
                    run.ticks.len(),
                    played.ticks.len()
                );
            } else {
                assert!(run.ticks.is_empty(), "{what}: a refused clip moved servos");
            }
            // The servo commands (not the Status frames, whose counts depend on how far the
            // firmware had read) against their committed snapshot.
            check_snapshot(&format!("stream-{name}"), &run.maestro);
            if *hits == 0 && *same_rig {
                assert_eq!(last.dropped, 0, "{what}");
            } else if *hits > 0 {
                assert!(last.dropped > 0, "{what}: the corruption dropped nothing");
            }
            eprintln!(
                "{what}: {} bytes, {hits} corrupted; {} commands within limits, ends at \
                 neutral; {} Status frames, last {:?}; read up to frame {} of {}; {}",
                bytes.len(),
                run.ticks.len(),
                run.statuses,
                run.status,
                at + 1,
                snapshots.len(),
                run.figures
            );
        }
    }
}

/// How often a carousel of `passes` uploads the demo's servo clip whole through a line that
/// corrupts one byte in `one_in`, over `seeds` seeds: the session model (the host's
/// `FrameReceiver` and the firmware's upload rule) on `mocap send --passes N`'s bytes.
struct Rate {
    passes: u32,
    wire_bytes: usize,
    played: usize,
    /// Chunk frames received intact, of those sent.
    chunk_frames: f64,
    /// Of the uploads that played: where the clip started, as a fraction of the stream.
    start_at: f64,
}

fn carousel_rate(clip: &[u8], passes: u32, one_in: u64, seeds: u64) -> Rate {
    let wire = clip_frames(clip, false, passes).unwrap().concat();
    let n_chunks = clip.len().div_ceil(MAX_CHUNK_LEN) as f64;
    let (mut played, mut chunk_frames, mut start_at) = (0, 0.0, 0.0);
    for seed in 0..seeds {
        let (bad, _) = corrupt_one_in(&wire, 0xC0DE_0000 + seed, one_in);
        let (snapshots, started) = session_model(&bad, 6 * 1024, |c| Clip::parse(c).is_ok());
        let last = snapshots.last().unwrap();
        chunk_frames +=
            (last.chunks_accepted + last.chunks_duplicate) as f64 / (n_chunks * f64::from(passes));
        if let Some(at) = started {
            played += 1;
            start_at += (at + 1) as f64 / snapshots.len() as f64;
        }
    }
    Rate {
        passes,
        wire_bytes: wire.len(),
        played,
        chunk_frames: chunk_frames / seeds as f64,
        start_at: if played > 0 {
            start_at / played as f64
        } else {
            f64::NAN
        },
    }
}

/// BENCHMARKS.md §5's carousel figures (host only, no QEMU): the fraction of 200 uploads of the
/// demo's servo clip that complete and play, by passes, at 1 % and 0.1 % corrupted bytes.
#[test]
fn carousel_completion_rates() {
    const SEEDS: u64 = 200;
    let (_, clip) = servo_demo_clip("servo-demo-carousel");
    let n = clip.len().div_ceil(MAX_CHUNK_LEN);
    for (one_in, passes) in [
        (CORRUPT_ONE_IN, &[1, 2, 3, 4, 6, 8, 10, 12, 14, 16][..]),
        (1000, &[1, 2, 3, 4][..]),
    ] {
        let mut last = 0;
        for &p in passes {
            let r = carousel_rate(&clip, p, one_in, SEEDS);
            let chunk_p = r.chunk_frames;
            let predicted = (1.0 - (1.0 - chunk_p).powi(p as i32)).powi(n as i32);
            eprintln!(
                "1/{one_in} bytes corrupted, {} passes: {} B on the wire; {} of {SEEDS} uploads \
                 play ({:.1} %; (1-(1-p)^N)^{n} = {:.1} % with p = {:.3} chunk frames intact); \
                 the clip starts after {:.0} % of the stream",
                r.passes,
                r.wire_bytes,
                r.played,
                100.0 * r.played as f64 / SEEDS as f64,
                100.0 * predicted,
                chunk_p,
                100.0 * r.start_at
            );
            assert!(
                r.played + SEEDS as usize / 20 >= last,
                "more passes, fewer uploads"
            );
            last = r.played;
            if p == 1 && one_in == CORRUPT_ONE_IN {
                assert_eq!(r.played, 0, "one pass at 1 %: practically never whole");
            }
        }
    }
    // The seed the QEMU test runs: enough passes.
    let wire = clip_frames(&clip, false, CAROUSEL_PASSES).unwrap().concat();
    let (bad, _) = corrupt(&wire, UPLOAD_SEED);
    let (_, started) = session_model(&bad, 6 * 1024, |c| Clip::parse(c).is_ok());
    assert!(
        started.is_some(),
        "{CAROUSEL_PASSES} passes do not upload seed {UPLOAD_SEED:#x}"
    );
}
