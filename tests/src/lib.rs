//! Shared helpers for the workspace tests: where the corpus is, and a
//! visible skip when it is not there; running the firmware in QEMU
//! (`scripts/firmware.sh`) and comparing its output with committed
//! snapshots ([`snapshot`]); the demo's servo clip.

use std::path::PathBuf;

pub mod snapshot;

/// The corpus folder: `$MOCAP_CORPUS` (a relative path is taken from the
/// workspace root), else `../shared/data` beside the workspace root.
pub fn corpus_dir() -> PathBuf {
    match std::env::var_os("MOCAP_CORPUS") {
        Some(p) if std::path::Path::new(&p).is_absolute() => PathBuf::from(p),
        Some(p) => workspace_root().join(p),
        None => workspace_root().join("../shared/data"),
    }
}

/// The corpus folder `folder`, or `None` after printing a visible SKIPPED
/// line when the corpus is absent (under `CI` a missing corpus fails).
fn corpus_folder(folder: &str) -> Option<(PathBuf, std::fs::ReadDir)> {
    let dir = corpus_dir().join(folder);
    let Ok(rd) = std::fs::read_dir(&dir) else {
        // CI has the corpus: there a missing corpus is a failure, not a skip.
        if std::env::var_os("CI").is_some() {
            panic!(
                "CI: corpus not found at {} (set MOCAP_CORPUS)",
                dir.display()
            );
        }
        skipped(&format!(
            "corpus not found at {} (set MOCAP_CORPUS)",
            dir.display()
        ));
        return None;
    };
    Some((dir, rd))
}

/// The `.bvh` files of one corpus folder (`cmu`, `iclone-cmu`), sorted, or
/// `None` after printing a visible SKIPPED line when the corpus is absent.
pub fn corpus_files(folder: &str) -> Option<Vec<PathBuf>> {
    corpus_files_ext(folder, "bvh")
}

/// The files of one corpus folder with extension `ext` (`c3d/`: `c3d`),
/// sorted, or `None` with the visible skip of [`corpus_files`].
pub fn corpus_files_ext(folder: &str, ext: &str) -> Option<Vec<PathBuf>> {
    let (_, rd) = corpus_folder(folder)?;
    let mut files: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == ext))
        .collect();
    files.sort();
    Some(files)
}

/// Every file under the corpus (all folders, recursively; README files and
/// other non-data files included: the caller picks by extension), sorted,
/// or `None` with the visible skip of [`corpus_files`].
pub fn corpus_tree() -> Option<Vec<PathBuf>> {
    let dir = corpus_dir();
    if !dir.is_dir() {
        // The same skip (or CI failure) as a missing folder.
        corpus_folder(".")?;
    }
    let mut files = Vec::new();
    let mut todo = vec![dir];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else {
                files.push(p);
            }
        }
    }
    files.sort();
    Some(files)
}

/// The corpus file `folder/name`: for a `.bvh` name, the folder's first
/// `.bvh` file if it is not there; any other file (`asf-amc/16.asf`) must be
/// there by its name. `None`, with the visible skip of [`corpus_files`],
/// without the corpus (or, for a non-BVH file, without that file: a corpus
/// older than the file).
pub fn corpus_file(folder: &str, name: &str) -> Option<PathBuf> {
    if !name.ends_with(".bvh") {
        let (dir, _) = corpus_folder(folder)?;
        let path = dir.join(name);
        if !path.is_file() {
            if std::env::var_os("CI").is_some() {
                panic!("CI: corpus file {} not found", path.display());
            }
            skipped(&format!("corpus file {} not found", path.display()));
            return None;
        }
        return Some(path);
    }
    let files = corpus_files(folder)?;
    assert!(
        !files.is_empty(),
        "no .bvh files in the corpus folder {folder}"
    );
    let first = files.first().cloned();
    files.into_iter().find(|p| p.ends_with(name)).or(first)
}

/// Prints `SKIPPED: <test>: <why>` on the real stderr, past the test
/// harness's output capture, so a skip is always visible; `<test>` is the
/// name of the test's thread, which the harness names after the test.
/// scripts/test.sh counts every test that printed this line as skipped, not
/// passed (once, however often it prints it).
pub fn skipped(why: &str) {
    use std::io::Write;
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("unnamed-thread");
    let _ = writeln!(std::io::stderr().lock(), "SKIPPED: {test}: {why}");
}

/// The firmware's boards, in the order of the one board table
/// (`scripts/boards.sh`, which the scripts read too).
pub fn boards() -> Vec<String> {
    let path = workspace_root().join("scripts/boards.sh");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let table = text
        .split("MOCAP_BOARD_TABLE='")
        .nth(1)
        .and_then(|rest| rest.split('\'').next())
        .unwrap_or_else(|| panic!("{}: no MOCAP_BOARD_TABLE", path.display()));
    let boards: Vec<String> = table
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect();
    assert!(!boards.is_empty(), "{}: empty board table", path.display());
    boards
}

/// The workspace root.
pub fn workspace_root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// Decodes `bytes` in every way the player offers, returning an error or
/// nothing; used by the corruption test and the fuzz target's logic. Any
/// panic inside is a bug.
pub fn exercise_decoder(bytes: &[u8]) -> Result<u64, mocap_decoder::Error> {
    use mocap_decoder::{Clip, Player};
    let clip = Clip::parse(bytes)?;
    let mut player = Player::<512>::new(&clip)?;
    let mut out = [0i32; 512];
    let mut sum = 0u64;
    // Walk headers too: names, channels.
    sum += clip.header().joints().count() as u64 + clip.header().channels().count() as u64;
    if let Some(rig) = clip.rig() {
        for s in rig.servos() {
            sum = sum.wrapping_add(u64::from(s.pulse_qus(i32::MIN)) + u64::from(s.pulse_qus(0)));
        }
    }
    while player.next_frame(&mut out)?.is_some() {
        sum = sum.wrapping_add(out[0] as u64);
    }
    let frames = player.frame_count();
    player.frame(frames / 2, &mut out)?;
    player.frame(0, &mut out)?;
    player.sample_at(clip.header().duration_us() / 3, &mut out)?;
    player.sample_at(u64::MAX, &mut out)?;
    Ok(sum)
}

/// Whether the emulators of the boards (`qemu-system-arm`, and
/// `qemu-system-riscv32` for the RISC-V board) run; without them a test
/// prints SKIPPED and returns, except under `CI`, where a missing emulator
/// fails it.
pub fn qemu_available() -> bool {
    for qemu in ["qemu-system-arm", "qemu-system-riscv32"] {
        let ok = std::process::Command::new(qemu)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success());
        if !ok {
            if std::env::var_os("CI").is_some() {
                panic!("{qemu} missing in CI: run the README's test command");
            }
            skipped(&format!(
                "{qemu} not found (run scripts/test.sh, which installs it)"
            ));
            return false;
        }
    }
    true
}

/// `scripts/firmware.sh run --board <board> --clip <clip> <args…>`: whether
/// the firmware reported success (exit 0; 1 is its reported failure, anything
/// else panics: a build, usage or QEMU failure), and its UART output.
pub fn run_firmware_outcome(board: &str, clip: &std::path::Path, args: &[&str]) -> (bool, String) {
    let out = firmware_sh(board, clip, args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{board} {} {args:?}: firmware.sh failed ({}):\n{}",
        clip.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr),
    );
    (out.status.success(), stdout)
}

fn firmware_sh(board: &str, clip: &std::path::Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new("bash")
        .arg(workspace_root().join("scripts/firmware.sh"))
        .args(["run", "--board", board, "--clip"])
        .arg(clip)
        .args(args)
        .output()
        .expect("scripts/firmware.sh runs")
}

/// `scripts/firmware.sh run --board <board> --clip <clip> <args…>`: the
/// firmware's UART output; panics (with its `#` lines) unless it succeeds.
pub fn run_firmware(board: &str, clip: &std::path::Path, args: &[&str]) -> String {
    let out = firmware_sh(board, clip, args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{board} {} {args:?}: firmware failed ({}):\n{}\n{}",
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
pub fn data_lines(uart: &str) -> String {
    uart.lines()
        .filter(|l| !l.starts_with('#'))
        .flat_map(|l| [l, "\n"])
        .collect()
}

/// The demo's servo clip (`mocap encode assets/animatronic_demo.bvh --rig
/// assets/rigs/animatronic_demo.toml --codec pca-spline --max-error 0.5deg`),
/// written to `target/qemu-parity/<name>.mcb`.
pub fn servo_demo_clip(name: &str) -> (PathBuf, Vec<u8>) {
    servo_demo_clip_with(name, mocap_encoder::encode::CodecChoice::PcaSpline)
}

/// [`servo_demo_clip`] with another codec.
pub fn servo_demo_clip_with(
    name: &str,
    codec: mocap_encoder::encode::CodecChoice,
) -> (PathBuf, Vec<u8>) {
    servo_demo_clip_for(name, DEMO_RIG, codec)
}

/// The demo figure's rig file: the default figure the firmware is built for.
pub const DEMO_RIG: &str = "assets/rigs/animatronic_demo.toml";
/// The demo rig widened for a bigger sibling figure (every range ×1.8, no speed limits).
pub const WIDE_RIG: &str = "assets/rigs/animatronic_demo_wide.toml";

/// The demo figure as `mocap play --rig assets/rigs/animatronic_demo.toml --policy …` and the
/// firmware built for it (the default `MOCAP_FIGURE`) hold a servo clip to it.
pub fn demo_figure(policy: mocap_servo::Policy) -> mocap_encoder::play::Figure {
    let rig = mocap_encoder::rig::Rig::read_file(&workspace_root().join(DEMO_RIG)).unwrap();
    mocap_encoder::play::Figure::from_rig(&rig, policy)
}

/// The demo motion as a servo clip of the rig file `rig` (relative to the workspace).
pub fn servo_demo_clip_for(
    name: &str,
    rig: &str,
    codec: mocap_encoder::encode::CodecChoice,
) -> (PathBuf, Vec<u8>) {
    use mocap_encoder::encode::{Bound, BoundSpec};
    use mocap_encoder::servo_clip::{ServoEncodeOptions, ServoNames, ServoRate};
    use mocap_encoder::{generate, rig::Rig, servo_clip, units};
    let root = workspace_root();
    let rig = Rig::read_file(&root.join(rig)).unwrap();
    let m = generate::animatronic_demo();
    let channels = rig.resolve(&m.skeleton).unwrap();
    let tracks = rig.servo_tracks(&m, &channels, units::detect(&m).metres());
    let opts = ServoEncodeOptions {
        codec,
        bound: Bound::from_specs(&["0.5deg".parse::<BoundSpec>().unwrap()]),
        key_interval: None,
        rate: ServoRate::Rig,
        names: ServoNames::Strip,
    };
    let bytes = servo_clip::encode_servo_clip(&rig, &tracks, &opts)
        .unwrap()
        .bytes;
    let dir = root.join("target/qemu-parity");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.mcb"));
    std::fs::write(&path, &bytes).unwrap();
    (path, bytes)
}

/// `m` encoded with the `index` codec at 1° (the encoder's default), its
/// unit detected: the clip's bytes.
pub fn encode_index_1deg(m: &mocap_encoder::motion::Motion) -> Vec<u8> {
    use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
    let opts = EncodeOptions {
        key_bits: None,
        codec: CodecChoice::Index,
        bound: Bound::from_specs(&["1deg".parse::<BoundSpec>().unwrap()]),
        metres_per_unit: mocap_encoder::units::detect(m).metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    encode::encode(m, &opts).unwrap().bytes
}

/// The shipped demo played twice in a row: the `rma` codec's case of a
/// take whose second half repeats its first exactly (random access,
/// corruption and QEMU parity; the golden clip doubles the shipped BVH).
pub fn demo_played_twice() -> mocap_encoder::motion::Motion {
    let mut twice = mocap_encoder::generate::animatronic_demo();
    let frames = twice.values.clone();
    twice.values.extend_from_slice(&frames);
    twice
}

/// The shipped demo clip (480 frames, 60 Hz, cm) sent far: its root
/// travels 150 m along X and its heading winds 200 turns (150° a frame).
/// No `index` key table holds that to 1 mm / 1°, so its `index` clip
/// codes key frames in levels (SPEC.md §4.5): the golden and QEMU case of
/// that path.
pub fn far_travelled_demo() -> mocap_encoder::motion::Motion {
    let mut m = mocap_encoder::generate::animatronic_demo();
    let n = m.skeleton.channel_count();
    let frames = m.frames();
    for f in 0..frames {
        let s = f as f64 / frames as f64;
        // Root channels: Xposition Yposition Zposition Zrotation Xrotation Yrotation.
        m.values[f * n] += 15_000.0 * s;
        m.values[f * n + 5] += 360.0 * 200.0 * s;
    }
    m
}

/// The headless browser of the page tests (`mocap view`): Debian's
/// `chromium`, or `$MOCAP_CHROMIUM`. Without it a test prints SKIPPED and
/// returns (`None`), except under `CI`, where a missing browser fails it.
pub fn chromium() -> Option<PathBuf> {
    let exe = std::env::var_os("MOCAP_CHROMIUM").map_or_else(|| "chromium".into(), PathBuf::from);
    let ok = std::process::Command::new(&exe)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        if std::env::var_os("CI").is_some() {
            panic!(
                "{} missing in CI: run the README's test command",
                exe.display()
            );
        }
        skipped(&format!(
            "{} not found (run scripts/test.sh, which installs Debian's chromium)",
            exe.display()
        ));
        return None;
    }
    Some(exe)
}

/// What a headless run of [`browse`] returns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrowserOutput<'a> {
    /// The DOM after the run, serialised (`--dump-dom`).
    Dom,
    /// A PNG screenshot of the window, written to this path.
    Screenshot(&'a std::path::Path),
}

/// Opens `page#hash` in headless `browser` (from [`chromium`]) in a
/// 1200×800 window, lets `virtual_ms` of virtual time pass (timers and the
/// page's clock follow it, not the wall clock), then dumps the DOM (the
/// returned string) or takes a screenshot (empty string). No network: the
/// page is a local file and the browser's background services are off.
pub fn browse(
    browser: &std::path::Path,
    page: &std::path::Path,
    hash: &str,
    virtual_ms: u32,
    output: BrowserOutput<'_>,
) -> String {
    let profile = std::env::temp_dir().join(format!(
        "mocap-chromium-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    let page = page.canonicalize().expect("page exists");
    // A file URL: the characters a path may hold that a URL reads otherwise,
    // percent-encoded.
    let mut path = String::new();
    for c in page.display().to_string().chars() {
        match c {
            '%' | ' ' | '#' | '?' | '"' | '<' | '>' => path += &format!("%{:02X}", c as u32),
            c => path.push(c),
        }
    }
    let url = format!("file://{path}#{hash}");
    let mut cmd = std::process::Command::new(browser);
    cmd.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-extensions",
        "--hide-scrollbars",
        "--force-device-scale-factor=1",
        "--window-size=1200,800",
    ])
    .arg(format!("--user-data-dir={}", profile.display()))
    .arg(format!("--virtual-time-budget={virtual_ms}"));
    match output {
        BrowserOutput::Dom => cmd.arg("--dump-dom"),
        BrowserOutput::Screenshot(p) => cmd.arg(format!("--screenshot={}", p.display())),
    };
    // Output to files and a deadline: a browser that hangs fails the test
    // instead of stalling the run.
    std::fs::create_dir_all(&profile).expect("browser profile dir");
    let (so, se) = (profile.join("stdout"), profile.join("stderr"));
    let mut child = cmd
        .arg(&url)
        .stdout(std::fs::File::create(&so).expect("stdout file"))
        .stderr(std::fs::File::create(&se).expect("stderr file"))
        .spawn()
        .expect("run the browser");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(180);
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait for the browser") {
            break Some(s);
        }
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let stdout = std::fs::read_to_string(&so).unwrap_or_default();
    let stderr = std::fs::read_to_string(&se).unwrap_or_default();
    let _ = std::fs::remove_dir_all(&profile);
    match status {
        Some(s) if s.success() => stdout,
        Some(s) => panic!("{} {url}: {s}\n{stderr}", browser.display()),
        None => panic!("{} {url}: no answer in 180 s\n{stderr}", browser.display()),
    }
}

/// The value of `data-<name>` on the `<body>` of a dumped DOM.
pub fn body_data(dom: &str, name: &str) -> Option<String> {
    let start = dom.find("<body")?;
    let tag = &dom[start..start + dom[start..].find('>')?];
    let key = format!("data-{name}=\"");
    let from = tag.find(&key)? + key.len();
    Some(tag[from..from + tag[from..].find('"')?].to_string())
}
