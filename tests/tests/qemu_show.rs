//! The firmware's show mode on Cortex-M0, M3 and M4F in QEMU: the shipped demo show
//! (`assets/shows/demo.toml`) in flash, its command scripts sent as `mocap send show.mcb --cues`
//! writes them (SPEC.md §8.2) through the UART receiver. Every board must give the servo
//! commands — byte for byte — and the output events (`# event …`) of `mocap play show.mcb
//! --cues … --rig <figure>` on the host, and the committed snapshot
//! `tests/snapshots/show-<script>.out` (`MOCAP_BLESS=1` rewrites it).
//!
//! Scripts: the shipped `assets/shows/demo_cues.txt` (a cue list with sound and GPIO events,
//! triggers in and out of their cooldown, a fade from mid-blend, hold and resume, loop off,
//! `end`), and an interrupting one (fades that cut into fades, a cut, `stop` mid-blend).

use std::path::{Path, PathBuf};

use mocap_decoder::Show;
use mocap_encoder::play::{Policy, Protocol};
use mocap_encoder::show::play::{command_frames, show_stream, Script};
use mocap_encoder::show::{self, file::ShowSpec};
use mocap_servo::stream::{decode_frame, Message};
use mocap_tests::snapshot::check_snapshot;
use mocap_tests::{boards, data_lines, demo_figure, qemu_available, run_firmware, workspace_root};

const INTERRUPTS: &str = "\
0    play greet
0.6  fade look 400
0.8  fade talk 300    # into a fade: from the frozen pose
0.9  fade idle 0      # a cut
1.0  status           # the MCU answers: 1 000 ms, clip 3 (idle), playing, no cue list
1.5  queue greet
2.2  fade look 500
2.4  stop             # mid-blend
2.5  play talk
4    end
";

fn dir() -> PathBuf {
    let d = workspace_root().join("target/qemu-show");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The demo show, built as `mocap show build assets/shows/demo.toml` builds it.
fn demo_show() -> (PathBuf, Vec<u8>) {
    let spec = ShowSpec::read_file(&workspace_root().join("assets/shows/demo.toml")).unwrap();
    let bytes = show::build(&spec).unwrap().bytes;
    let path = dir().join("demo_show.mcb");
    std::fs::write(&path, &bytes).unwrap();
    (path, bytes)
}

/// The Maestro lines `m xx …` of the host's play, and its event lines.
fn host(bytes: &[u8], script: &Script) -> (String, Vec<String>) {
    let show = Show::parse(bytes).unwrap();
    let figure = demo_figure(Policy::ClampIfInside);
    let played = show_stream(&show, script, Protocol::Maestro, None, Some(&figure), 600.0).unwrap();
    let lines: String = played
        .stream
        .ticks
        .iter()
        .map(|t| {
            let hex: String = t.iter().map(|b| format!(" {b:02x}")).collect();
            format!("m{hex}\n")
        })
        .collect();
    (lines, played.events.into_iter().map(|(_, l)| l).collect())
}

fn run(name: &str, text: &str, show: &Path, bytes: &[u8], want_status: Vec<Message<'static>>) {
    let parsed = Show::parse(bytes).unwrap();
    let script = Script::parse(text, name, &parsed).unwrap();
    let (want, want_events) = host(bytes, &script);
    let input = dir().join(format!("{name}.bin"));
    let frames: Vec<u8> = command_frames(&script)
        .unwrap()
        .into_iter()
        .flat_map(|(_, f)| f)
        .collect();
    std::fs::write(&input, frames).unwrap();
    for board in boards() {
        let uart = run_firmware(
            &board,
            show,
            &[
                "--servo",
                "maestro",
                "--input",
                input.to_str().unwrap(),
                "--icount",
                // No gap timeout: in lockstep the firmware waits for QEMU's bytes, which come at
                // the host's pace; a loaded host must not turn a slow byte into a park.
                "--stream-timeout",
                "0",
            ],
        );
        let data = data_lines(&uart);
        let (frames, commands): (Vec<&str>, Vec<&str>) =
            data.lines().partition(|l| l.starts_with("f "));
        let commands: String = commands.iter().flat_map(|l| [*l, "\n"]).collect();
        // Not assert_eq: the two texts are long.
        assert!(
            commands == want,
            "{board} {name}: the MCU's servo commands differ from the host's"
        );
        let replies: Vec<String> = frames
            .iter()
            .map(|l| {
                let mut bytes: Vec<u8> = l[2..]
                    .split(' ')
                    .map(|b| u8::from_str_radix(b, 16).unwrap())
                    .collect();
                format!("{:?}", decode_frame(&mut bytes).unwrap())
            })
            .collect();
        let want_replies: Vec<String> = want_status.iter().map(|m| format!("{m:?}")).collect();
        assert_eq!(replies, want_replies, "{board} {name}: ShowStatus replies");
        let events: Vec<String> = uart
            .lines()
            .filter(|l| l.starts_with("# event"))
            .map(String::from)
            .collect();
        assert_eq!(events, want_events, "{board} {name}: output events");
        for l in uart.lines().filter(|l| {
            l.starts_with("# show_ticks")
                || l.starts_with("# blend_ticks")
                || l.starts_with("# plain_ticks")
                || l.starts_with("# mode=show")
                || l.starts_with("# stack")
        }) {
            eprintln!("{board} {name}: {l}");
        }
        assert!(
            uart.contains("commands_rejected=0"),
            "{board} {name}: {uart}"
        );
    }
    check_snapshot(&format!("show-{name}"), &want);
}

#[test]
fn the_demo_show_plays_on_every_core_as_on_the_host() {
    if !qemu_available() {
        return;
    }
    let (show, bytes) = demo_show();
    let cues =
        std::fs::read_to_string(workspace_root().join("assets/shows/demo_cues.txt")).unwrap();
    run("demo", &cues, &show, &bytes, vec![]);
    let status = Message::ShowStatus {
        show_ms: 1000,
        clip: 3,
        state: 1,
        list: u16::MAX,
    };
    run("interrupts", INTERRUPTS, &show, &bytes, vec![status]);
}
