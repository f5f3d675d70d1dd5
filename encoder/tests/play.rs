//! `mocap play` / `mocap send` byte streams: every command parses back,
//! stays inside the rig's pulse limits and speed, the stream ends at
//! neutral; corrupt clips are refused or still produce only in-limit
//! commands; `send` frames reassemble the clip exactly, in any order and
//! from any pass of a carousel (`--passes`).

use std::path::Path;

use mocap_decoder::Clip;
use mocap_encoder::encode::{Bound, CodecChoice};
use mocap_encoder::play::{
    clip_frames, servo_clip_stream, servo_stream, PlayError, Protocol, ServoStream,
};
use mocap_encoder::rig::Rig;
use mocap_encoder::servo_clip::{ServoEncodeOptions, ServoNames, ServoRate};
use mocap_encoder::{bvh, servo_clip};
use mocap_servo::stream::upload::{bitmap_words, Accepted, Play, Upload};
use mocap_servo::stream::{MAX_CHUNK_LEN, PROTOCOL_VERSION};
use mocap_servo::{FrameReceiver, Message};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap()
}

fn demo() -> (Vec<u8>, Rig) {
    let clip = std::fs::read(root().join("firmware-example/clips/demo.mcb")).unwrap();
    let rig = Rig::read_file(&root().join("assets/rigs/animatronic_demo.toml")).unwrap();
    (clip, rig)
}

/// Parses a Maestro stream back into (channel, target) commands.
fn maestro_commands(bytes: &[u8]) -> Vec<(u8, u16)> {
    assert_eq!(bytes.len() % 4, 0);
    bytes
        .chunks(4)
        .map(|c| {
            assert_eq!(c[0], 0x84, "Set Target");
            assert!(c[1] < 0x80 && c[2] < 0x80 && c[3] < 0x80);
            (c[1], u16::from(c[2]) | u16::from(c[3]) << 7)
        })
        .collect()
}

fn check_limits(s: &ServoStream, rig: &Rig) {
    assert!(s.ticks.len() > s.clip_ticks, "no return to neutral");
    for (i, pulses) in s.pulses.iter().enumerate() {
        for (j, (&p, l)) in pulses.iter().zip(&s.limits).enumerate() {
            assert!(
                l.min_qus <= p && p <= l.max_qus,
                "tick {i} servo {}: {p} outside [{}, {}]",
                rig.servos[j].name,
                l.min_qus,
                l.max_qus
            );
            if i > 0 && l.max_step_qus > 0 {
                let d = p.abs_diff(s.pulses[i - 1][j]);
                assert!(d <= l.max_step_qus, "tick {i} servo {j}: step {d}");
            }
        }
    }
    let last = s.pulses.last().unwrap();
    for (p, l) in last.iter().zip(&s.limits) {
        assert_eq!(*p, l.neutral_qus, "ends at neutral");
    }
}

#[test]
fn maestro_stream_parses_back_within_limits() {
    let (bytes, rig) = demo();
    let clip = Clip::parse(&bytes).unwrap();
    let s = servo_stream(&clip, &rig, Protocol::Maestro, Some(50.0)).unwrap();
    check_limits(&s, &rig);
    // 50 Hz over the 8 s clip: 401 ticks, then the way back to neutral.
    assert_eq!(s.clip_ticks, 401);
    let commands = maestro_commands(&s.bytes());
    assert_eq!(commands.len(), s.ticks.len() * rig.servos.len());
    for (k, &(ch, target)) in commands.iter().enumerate() {
        let (tick, servo) = (k / rig.servos.len(), k % rig.servos.len());
        assert_eq!(u16::from(ch), rig.servos[servo].output);
        assert_eq!(target, s.pulses[tick][servo]);
    }
}

#[test]
fn ssc32_stream_parses_back_within_limits() {
    let (bytes, rig) = demo();
    let clip = Clip::parse(&bytes).unwrap();
    let s = servo_stream(&clip, &rig, Protocol::Ssc32, Some(50.0)).unwrap();
    check_limits(&s, &rig);
    let text = String::from_utf8(s.bytes()).unwrap();
    let lines: Vec<&str> = text.split_terminator('\r').collect();
    assert_eq!(lines.len(), s.ticks.len());
    for (tick, line) in lines.iter().enumerate() {
        let (moves, time) = line.split_once('T').unwrap();
        assert_eq!(time, "20");
        for (servo, m) in moves.split('#').skip(1).enumerate() {
            let (ch, us) = m.split_once('P').unwrap();
            assert_eq!(ch.parse::<u16>().unwrap(), rig.servos[servo].output);
            let us: u32 = us.parse().unwrap();
            // Rounded to the nearest µs.
            let want = (u32::from(s.pulses[tick][servo]) + 2) / 4;
            assert_eq!(us, want, "tick {tick} servo {servo}");
        }
    }
}

/// The demo's servo clip (`mocap encode --rig`) at `bound_deg`, coded at
/// the capture's frame rate with the servo names kept; and the rig's
/// pulses at the capture's frames.
fn servo_clip_bytes(codec: CodecChoice, bound_deg: f64) -> (Vec<u8>, Rig, Vec<Vec<u16>>) {
    let (rig, tracks) = demo_tracks();
    let sc = servo_clip::encode_servo_clip(
        &rig,
        &tracks,
        &servo_options(codec, bound_deg, ServoRate::Capture, ServoNames::Keep),
    )
    .unwrap();
    let pulses = tracks.servos.iter().map(|t| t.pulses.clone()).collect();
    (sc.bytes, rig, pulses)
}

fn demo_tracks() -> (Rig, mocap_encoder::rig::ServoTracks) {
    let (_, rig) = demo();
    let m = bvh::read_file(&root().join("assets/animatronic_demo.bvh")).unwrap();
    let channels = rig.resolve(&m.skeleton).unwrap();
    let tracks = rig.servo_tracks(&m, &channels, 0.01);
    (rig, tracks)
}

fn servo_options(
    codec: CodecChoice,
    bound_deg: f64,
    rate: ServoRate,
    names: ServoNames,
) -> ServoEncodeOptions {
    ServoEncodeOptions {
        codec,
        bound: Bound {
            angle_deg: Some(bound_deg),
            position_mm: None,
            arms_mm: None,
            foot_slide_mm_s: None,
        },
        key_interval: None,
        rate,
        names,
    }
}

/// The default servo clip (`mocap encode --rig`: coded at the rig's ticks,
/// servo names left out, servo-form header and compact rig table) holds
/// its bound at every tick where it is played, and is smaller than the
/// capture-rate clip with names.
#[test]
fn rig_rate_servo_clips_hold_the_bound_at_the_ticks() {
    let (rig, tracks) = demo_tracks();
    let ticks = servo_clip::tick_tracks(&rig, &tracks);
    for codec in [CodecChoice::Index, CodecChoice::PcaSpline] {
        let sc = servo_clip::encode_servo_clip(
            &rig,
            &tracks,
            &servo_options(codec, 0.5, ServoRate::Rig, ServoNames::Strip),
        )
        .unwrap();
        let clip = Clip::parse(&sc.bytes).unwrap();
        assert!(clip.header().is_servo_form());
        assert!(clip.rig().unwrap().is_compact());
        assert_eq!(clip.header().frame_time_ns(), 20_000_000);
        let e = servo_clip::tick_error(&clip, &ticks).unwrap();
        assert_eq!(e.ticks, ticks.ticks());
        assert!(e.max_deg <= 0.5, "{codec:?}: {}°", e.max_deg);
        // Every servo's table entry is the rig's.
        let want: Vec<_> = rig.servos.iter().map(servo_clip::table_entry).collect();
        assert_eq!(clip.rig().unwrap().servos().collect::<Vec<_>>(), want);
        let capture = servo_clip::encode_servo_clip(
            &rig,
            &tracks,
            &servo_options(codec, 0.5, ServoRate::Capture, ServoNames::Keep),
        )
        .unwrap();
        assert!(
            sc.bytes.len() < capture.bytes.len(),
            "{codec:?}: {} B at the rig's rate, {} B at the capture's",
            sc.bytes.len(),
            capture.bytes.len()
        );
        let s = servo_clip_stream(&clip, Protocol::Maestro, None).unwrap();
        check_limits(&s, &rig);
    }
}

#[test]
fn servo_clips_decode_within_the_bound_and_play_within_limits() {
    for codec in [CodecChoice::Index, CodecChoice::PcaSpline] {
        let (bytes, rig, want) = servo_clip_bytes(codec, 0.5);
        let clip = Clip::parse(&bytes).unwrap();
        let table = clip.rig().expect("rig table");
        assert_eq!(table.servo_count(), rig.servos.len());
        assert_eq!(table.rate_mhz(), 50_000);
        let got = servo_clip::decoded_pulses(&clip).unwrap();
        for ((s, w), g) in rig.servos.iter().zip(&want).zip(&got) {
            let e = mocap_encoder::rig::servo_error(w, g);
            // 0.5° of travel plus the ¼ µs rounding of each side.
            let limit = 0.5 / s.degrees_per_us() + 0.5;
            assert!(
                e.max_us <= limit,
                "{codec:?} {}: {} µs > {limit}",
                s.name,
                e.max_us
            );
        }
        let s = servo_clip_stream(&clip, Protocol::Maestro, None).unwrap();
        assert!(s.tracks.is_none());
        check_limits(&s, &rig);
        // The clip's own limits are the rig's.
        for (l, servo) in s.limits.iter().zip(&rig.servos) {
            assert_eq!((l.min_qus, l.max_qus), servo.quarter_us_range());
            assert_eq!(l.neutral_qus, servo.neutral_quarter_us());
        }
    }
}

#[test]
fn corrupt_servo_clips_never_command_outside_limits() {
    let (bytes, _, _) = servo_clip_bytes(CodecChoice::PcaSpline, 1.0);
    let (played, refused) = mutate_and_play(&bytes, 0x1234_5678_9ABC, |clip| {
        let s = servo_clip_stream(clip, Protocol::Maestro, Some(50.0))?;
        // The table itself may have been mutated: hold to what the clip says
        // and to the physical 400–2600 µs window.
        for p in s.pulses.iter().flatten() {
            assert!((1600..=10_400).contains(p), "{p}");
        }
        check_limits(&s, &rig_like(&s));
        Ok(())
    });
    eprintln!("corrupt servo clips: {played} played within limits, {refused} refused");
    assert!(played > 0);
}

/// A rig view of a stream's own limits, for `check_limits`' messages.
fn rig_like(s: &ServoStream) -> Rig {
    let mut text = String::from("[rig]\nname = \"clip\"\n");
    for (i, _) in s.limits.iter().enumerate() {
        text += &format!(
            "[[servo]]\nname = \"s{i}\"\noutput = {i}\nchannel = \"J.Zrotation\"\nangle = [-1.0, 1.0]\npulse = [1000, 2000]\n"
        );
    }
    Rig::parse(&text, "clip").unwrap()
}

/// 300 mutants of `bytes` (1–4 flipped bits, CRC re-sealed so the
/// mutation reaches the decoder) through `play`: (played, refused).
fn mutate_and_play(
    bytes: &[u8],
    mut seed: u64,
    play: impl Fn(&Clip<'_>) -> Result<(), PlayError>,
) -> (usize, usize) {
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
    let mut next = |n: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % n as u64) as usize
    };
    let (mut played, mut refused) = (0, 0);
    for _ in 0..300 {
        let mut v = bytes.to_vec();
        for _ in 0..1 + next(4) {
            let at = 8 + next(v.len() - 12);
            v[at] ^= 1 << next(8);
        }
        let body = v.len() - 4;
        let sum = crc.checksum(&v[..body]);
        v[body..].copy_from_slice(&sum.to_le_bytes());
        match Clip::parse(&v) {
            Ok(clip) => match play(&clip) {
                Ok(()) => played += 1,
                Err(_) => refused += 1,
            },
            Err(_) => refused += 1,
        }
    }
    (played, refused)
}

#[test]
fn corrupt_clips_never_command_outside_limits() {
    let (bytes, rig) = demo();
    let (played, refused) = mutate_and_play(&bytes, 0x9E37_79B9, |clip| {
        let s = servo_stream(clip, &rig, Protocol::Maestro, Some(50.0))?;
        check_limits(&s, &rig);
        Ok(())
    });
    eprintln!("corrupt demo clips: {played} played within limits, {refused} refused");
    assert!(played > 0);
}

#[test]
fn send_frames_reassemble_the_clip() {
    let (bytes, _) = demo();
    let frames = clip_frames(&bytes, true, 1).unwrap();
    let mut rx = FrameReceiver::<{ mocap_servo::stream::MAX_FRAME_LEN }>::new();
    let mut clip = vec![0u8; bytes.len()];
    let (mut chunks, mut hello, mut play) = (0, false, false);
    let stream: Vec<u8> = frames.concat();
    let mut rest: &[u8] = &stream;
    while !rest.is_empty() {
        let (msg, after) = rx.feed(rest);
        rest = after;
        match msg {
            Some(Ok(Message::Hello { version })) => hello = version == PROTOCOL_VERSION,
            Some(Ok(Message::ClipChunk {
                offset,
                total,
                bytes: b,
            })) => {
                assert_eq!(total as usize, bytes.len());
                clip[offset as usize..offset as usize + b.len()].copy_from_slice(b);
                chunks += 1;
            }
            Some(Ok(Message::Play { loop_ })) => play = loop_,
            Some(Ok(m)) => panic!("unexpected {m:?}"),
            Some(Err(e)) => panic!("{e}"),
            None => {}
        }
    }
    assert!(hello && play);
    assert_eq!(chunks, bytes.len().div_ceil(64));
    assert_eq!(clip, bytes);
}

#[test]
fn send_passes_repeat_the_chunks_and_play() {
    let (bytes, _) = demo();
    let n = bytes.len().div_ceil(MAX_CHUNK_LEN);
    let one = clip_frames(&bytes, false, 1).unwrap();
    let three = clip_frames(&bytes, false, 3).unwrap();
    assert_eq!(one.len(), 1 + n + 1);
    assert_eq!(three.len(), 1 + 3 * (n + 1));
    // `00 Hello` once, then the one-pass upload three times, `Play` after each pass.
    assert_eq!(three[0], one[0]);
    for pass in three[1..].chunks(n + 1) {
        assert_eq!(pass, &one[1..]);
    }
    let play: Vec<u8> = {
        let mut rx = FrameReceiver::<{ mocap_servo::stream::MAX_FRAME_LEN }>::new();
        let last = one.last().unwrap();
        let mut m = None;
        for &b in last {
            if let Some(Ok(msg)) = rx.push(b) {
                m = Some(format!("{msg:?}"));
            }
        }
        assert_eq!(m.as_deref(), Some("Play { loop_: false }"));
        last.clone()
    };
    assert_eq!(three[n + 1], play);
    assert!(clip_frames(&bytes, false, 0).is_err());
}

/// The chunk frames of `frames` as (offset, total, bytes).
fn chunks_of(frames: &[Vec<u8>]) -> Vec<(u32, u32, Vec<u8>)> {
    let mut rx = FrameReceiver::<{ mocap_servo::stream::MAX_FRAME_LEN }>::new();
    let mut out = Vec::new();
    for &b in frames.concat().iter() {
        if let Some(Ok(Message::ClipChunk {
            offset,
            total,
            bytes,
        })) = rx.push(b)
        {
            out.push((offset, total, bytes.to_vec()));
        }
    }
    out
}

#[test]
fn carousel_chunks_reassemble_in_any_order_with_losses_and_copies() {
    const BUFFER: usize = 64 * 1024;
    let (bytes, _) = demo();
    let chunks = chunks_of(&clip_frames(&bytes, true, 3).unwrap());
    let n = bytes.len().div_ceil(MAX_CHUNK_LEN);
    assert_eq!(chunks.len(), 3 * n);
    let mut state = 0x1234_5678_9ABC_DEF0u64;
    let mut next = move || {
        // xorshift64*
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        state.wrapping_mul(0x2545_F491_4F6C_DD1D)
    };
    for round in 0..20 {
        // Lose about a third of the frames, shuffle the rest; every chunk once at least.
        let mut order: Vec<usize> = (0..chunks.len())
            .filter(|&i| i < n && round % 2 == 0 || next() % 3 != 0)
            .collect();
        for k in (1..order.len()).rev() {
            order.swap(k, (next() % (k as u64 + 1)) as usize);
        }
        let mut buffer = vec![0u8; BUFFER];
        let mut upload = Upload::<{ bitmap_words(BUFFER) }>::new();
        let mut seen = vec![false; n];
        let mut started = None;
        for (k, &i) in order.iter().enumerate() {
            let (offset, total, b) = &chunks[i];
            let index = *offset as usize / MAX_CHUNK_LEN;
            let got = upload.accept(&mut buffer, *offset, *total, b).unwrap();
            assert_eq!(got == Accepted::Duplicate, seen[index], "round {round}");
            seen[index] = true;
            if k == order.len() / 2 && !upload.is_complete() {
                assert_eq!(upload.play(true), Play::Armed);
            }
            if let Some(looped) = upload.take_armed() {
                assert!(looped);
                started = Some(k);
            }
        }
        if seen.iter().all(|&s| s) {
            assert_eq!(upload.complete(&buffer), Some(&bytes[..]), "round {round}");
            Clip::parse(upload.complete(&buffer).unwrap()).unwrap();
            if started.is_none() {
                assert_eq!(upload.play(false), Play::Start, "round {round}");
            }
        } else {
            assert!(upload.complete(&buffer).is_none());
            assert_eq!(
                upload.received() as usize,
                seen.iter().filter(|&&s| s).count()
            );
        }
    }
}

#[test]
fn send_starts_with_a_flushing_delimiter() {
    let (bytes, _) = demo();
    let frames = clip_frames(&bytes, false, 1).unwrap();
    assert_eq!(
        frames[0][0], 0x00,
        "a lone 00 ends whatever the receiver holds"
    );
    // Whatever noise came before, the Hello after it is received.
    let mut rx = FrameReceiver::<{ mocap_servo::stream::MAX_FRAME_LEN }>::new();
    let noise = [0x13u8, 0x37, 0xFF];
    let mut first = None;
    for &b in noise.iter().chain(frames[0].iter()) {
        if let Some(Ok(m)) = rx.push(b) {
            first.get_or_insert(format!("{m:?}"));
        }
    }
    assert_eq!(first.as_deref(), Some("Hello { version: 3 }"));
}

#[test]
fn send_poses_sends_every_tick_of_the_servo_clip_then_stop() {
    use mocap_encoder::play::{pose_frames, servo_clip_targets};
    let (bytes, _, _) = servo_clip_bytes(CodecChoice::PcaSpline, 1.0);
    let clip = Clip::parse(&bytes).unwrap();
    let p = pose_frames(&clip).unwrap();
    let t = servo_clip_targets(&clip, None).unwrap();
    assert_eq!(p.rate_mhz, 50_000);
    assert_eq!(p.frames.len(), t.targets.len() + 2);
    let mut rx = FrameReceiver::<{ mocap_servo::stream::MAX_FRAME_LEN }>::new();
    let mut messages = Vec::new();
    for &b in p.frames.concat().iter() {
        match rx.push(b) {
            Some(Ok(m)) => messages.push(format!("{m:?}")),
            Some(Err(e)) => panic!("{e}"),
            None => {}
        }
    }
    assert_eq!(
        messages.first().map(String::as_str),
        Some("Hello { version: 3 }")
    );
    assert_eq!(messages.last().map(String::as_str), Some("Stop"));
    for (i, (m, pulses)) in messages[1..messages.len() - 1]
        .iter()
        .zip(&t.targets)
        .enumerate()
    {
        assert_eq!(m, &format!("Pose {{ seq: {i}, pulses: {pulses:?} }}"));
    }
    // Paced at the rig's rate: pose k at tick k, Stop one tick after the last.
    assert_eq!(p.due_us(0), 0);
    assert_eq!(p.due_us(1), 0);
    assert_eq!(p.due_us(2), 20_000);
    assert_eq!(
        p.due_us(p.frames.len() - 1),
        t.targets.len() as u64 * 20_000
    );
    // A motion clip has no rig table to take pulses from.
    let (motion, _) = demo();
    assert!(pose_frames(&Clip::parse(&motion).unwrap()).is_err());
}

/// The messages `mocap play`, `mocap send` and `mocap encode --rig` print
/// for these errors (the CLI prints the library's error as it is).
#[test]
fn error_messages_name_what_is_wrong() {
    use mocap_encoder::play::{pose_frames, servo_clip_targets};
    fn message(e: &impl std::error::Error) -> String {
        e.to_string()
    }
    let (motion, rig) = demo();
    let motion = Clip::parse(&motion).unwrap();
    assert_eq!(
        message(&clip_frames(b"clip", false, 0).unwrap_err()),
        "--passes must be at least 1"
    );
    assert_eq!(
        message(&pose_frames(&motion).unwrap_err()),
        "--poses needs a servo clip (mocap encode --rig)"
    );
    assert_eq!(
        message(&servo_clip_stream(&motion, Protocol::Maestro, None).unwrap_err()),
        "not a servo clip: give --rig"
    );
    let (bytes, _, _) = servo_clip_bytes(CodecChoice::Index, 1.0);
    let servo = Clip::parse(&bytes).unwrap();
    for rate in [0.0, -2.5, f64::NAN] {
        assert_eq!(
            message(&servo_clip_targets(&servo, Some(rate)).unwrap_err()),
            format!("servo rate {rate} Hz must be positive")
        );
        assert_eq!(
            message(&servo_stream(&motion, &rig, Protocol::Ssc32, Some(rate)).unwrap_err()),
            format!("servo rate {rate} Hz must be positive")
        );
    }
    for e in [
        servo_clip::decoded_pulses(&motion).unwrap_err(),
        servo_clip::tick_error(&motion, &servo_clip::tick_tracks(&rig, &demo_tracks().1))
            .unwrap_err(),
    ] {
        assert_eq!(message(&e), "not a servo clip (no rig table)");
    }
    let (rig, tracks) = demo_tracks();
    let mut ticks = servo_clip::tick_tracks(&rig, &tracks);
    ticks.angles.pop();
    assert_eq!(
        message(&servo_clip::tick_error(&servo, &ticks).unwrap_err()),
        "servo count differs from the reference"
    );
    let mut opts = servo_options(CodecChoice::Index, 1.0, ServoRate::Rig, ServoNames::Strip);
    opts.bound = Bound {
        angle_deg: None,
        ..opts.bound
    };
    assert_eq!(
        message(&servo_clip::encode_servo_clip(&rig, &tracks, &opts).unwrap_err()),
        "a servo clip needs a bound in degrees of servo travel (e.g. 0.5deg)"
    );
    let mut flat = rig.clone();
    flat.servos[1].angle = [10.0, 10.0];
    assert_eq!(
        message(&servo_clip::rig_section(&flat).unwrap_err()),
        format!(
            "servo {}: angle range must be increasing",
            flat.servos[1].name
        )
    );
    let garbage =
        message(&servo_clip::attach_rig(b"not a clip", &rig, ServoNames::Strip).unwrap_err());
    assert!(garbage.starts_with("internal error: "), "{garbage}");
}

/// A clip for a wider rig played on the demo figure (`mocap play --rig`):
/// refused under `refuse` and `clamp-if-inside`; under `clamp`, every pulse
/// inside the figure's pulse ranges, within its speed and acceleration at
/// the tick rate, back at its neutrals at the end. The figure's own clip
/// plays whatever the policy.
#[test]
fn a_clip_for_a_wider_rig_stays_inside_the_figures_hard_limits() {
    use mocap_encoder::play::{servo_clip_stream_on, Figure, Fit, Policy};
    use mocap_servo::HardStep;
    let (figure_rig, tracks) = demo_tracks();
    // A clip made for a bigger sibling figure: every range ×1.8, no speed or acceleration limit.
    let wide = Rig::read_file(&root().join("assets/rigs/animatronic_demo_wide.toml")).unwrap();
    let wide_tracks = {
        let m = bvh::read_file(&root().join("assets/animatronic_demo.bvh")).unwrap();
        let channels = wide.resolve(&m.skeleton).unwrap();
        wide.servo_tracks(&m, &channels, 0.01)
    };
    let options = servo_options(CodecChoice::Index, 0.5, ServoRate::Rig, ServoNames::Keep);
    let wide_clip = servo_clip::encode_servo_clip(&wide, &wide_tracks, &options).unwrap();
    let own_clip = servo_clip::encode_servo_clip(&figure_rig, &tracks, &options).unwrap();
    let wide_clip = Clip::parse(&wide_clip.bytes).unwrap();
    let own_clip = Clip::parse(&own_clip.bytes).unwrap();

    for policy in [Policy::Refuse, Policy::ClampIfInside] {
        let figure = Figure::from_rig(&figure_rig, policy);
        let e = servo_clip_stream_on(&wide_clip, &figure, Protocol::Maestro, None).unwrap_err();
        assert!(
            e.to_string().contains("leaves the figure's hard limits"),
            "{e}"
        );
        let own = servo_clip_stream_on(&own_clip, &figure, Protocol::Maestro, None).unwrap();
        assert!(own.figure.as_ref().unwrap().identity == mocap_encoder::play::Identity::Same);
    }

    let figure = Figure::from_rig(&figure_rig, Policy::ClampAlways);
    let s = servo_clip_stream_on(&wide_clip, &figure, Protocol::Maestro, None).unwrap();
    let report = s.figure.as_ref().unwrap();
    assert!(report.identity == mocap_encoder::play::Identity::OtherTable);
    assert!(matches!(report.fit, Fit::Outside { .. }));
    assert!(report.clamps.iter().any(|c| c.ticks > 0));
    let steps: Vec<HardStep> = figure
        .limits
        .iter()
        .map(|l| HardStep::at_rate(l, figure.rate_mhz))
        .collect();
    // The bytes say the same as the pulses.
    let commands = maestro_commands(&s.bytes());
    assert_eq!(commands.len(), s.pulses.len() * steps.len());
    let mut outside = 0;
    let mut prev: Vec<(i32, i32)> = steps
        .iter()
        .map(|h| (i32::from(h.neutral_qus), 0))
        .collect();
    for (i, pulses) in s.pulses.iter().enumerate() {
        for (j, (&p, h)) in pulses.iter().zip(&steps).enumerate() {
            assert_eq!(commands[i * steps.len() + j].1, p);
            outside += usize::from(!(h.min_qus..=h.max_qus).contains(&p));
            let (last, v) = prev[j];
            let nv = i32::from(p) - last;
            if h.max_step_qus > 0 {
                assert!(
                    nv.unsigned_abs() <= u32::from(h.max_step_qus),
                    "tick {i} servo {j}"
                );
            }
            if h.max_accel_qus > 0 {
                let dv = (nv - v).unsigned_abs();
                assert!(
                    dv <= u32::from(h.max_accel_qus),
                    "tick {i} servo {j}: Δv {dv}"
                );
            }
            prev[j] = (i32::from(p), nv);
        }
    }
    assert_eq!(outside, 0, "commands outside the figure's hard limits");
    let last = s.pulses.last().unwrap();
    for (&p, h) in last.iter().zip(&steps) {
        assert_eq!(p, h.neutral_qus);
    }
}

/// A stop at any tick (`mocap play` interrupted): the ticks before it are the stream's own,
/// and `rest_after` brings every servo from there to its neutral within the speed limits.
#[test]
fn a_stop_at_any_tick_returns_every_servo_to_rest() {
    use mocap_encoder::play::{servo_clip_stream_on, Figure, Policy};
    let (rig, tracks) = demo_tracks();
    let options = servo_options(CodecChoice::Index, 0.5, ServoRate::Rig, ServoNames::Keep);
    let clip = servo_clip::encode_servo_clip(&rig, &tracks, &options).unwrap();
    let clip = Clip::parse(&clip.bytes).unwrap();
    let figure = Figure::from_rig(&rig, Policy::ClampIfInside);
    let s = servo_clip_stream_on(&clip, &figure, Protocol::Maestro, None).unwrap();
    assert_eq!(s.rest_after(s.clip_ticks).unwrap(), s.ticks[s.clip_ticks..]);
    assert_eq!(
        s.rest_after(0).unwrap(),
        Vec::<Vec<u8>>::new(),
        "at rest already"
    );
    let neutral: Vec<u16> = s.limits.iter().map(|l| l.neutral_qus).collect();
    for stop in [1, 7, 100, 250, s.clip_ticks - 1] {
        let rest = s.rest_after(stop).unwrap();
        assert!(!rest.is_empty(), "stop at {stop}: already at rest?");
        let mut prev: Vec<u16> = s.pulses[stop - 1].clone();
        for tick in &rest {
            let pulses: Vec<u16> = maestro_commands(tick).iter().map(|c| c.1).collect();
            for ((&p, l), last) in pulses.iter().zip(&s.limits).zip(&mut prev) {
                assert!((l.min_qus..=l.max_qus).contains(&p), "stop at {stop}");
                if l.max_step_qus > 0 {
                    assert!(
                        p.abs_diff(*last) <= l.max_step_qus,
                        "stop at {stop}: too fast"
                    );
                }
                *last = p;
            }
        }
        assert_eq!(prev, neutral, "stop at {stop}: not at rest");
    }
}
