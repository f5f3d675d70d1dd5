//! `mocap view` pages opened in a real browser (headless Chromium): the
//! shipped demo with its clip, a corpus clip with its encoding, the demo's
//! servo clip and the demo show. The page must draw the skeletons (or the
//! servo curves), play (its frame readout advances with the browser's virtual
//! time), and scrub to the worst-error frame the Rust side computed
//! (`mocap eval`'s). Without Chromium the tests print SKIPPED
//! (under `CI` they fail); screenshots are kept in `target/view-browser/`.

use std::path::{Path, PathBuf};

use mocap_encoder::play::Protocol;
use mocap_encoder::show::play::{show_stream, Script};
use mocap_report::view::{self, ServoSource};
use mocap_tests::{
    body_data, browse, chromium, corpus_file, encode_index_1deg, servo_demo_clip, workspace_root,
    BrowserOutput, DEMO_RIG,
};

fn out_dir() -> PathBuf {
    let d = workspace_root().join("target/view-browser");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn frame_of(dom: &str) -> usize {
    body_data(dom, "frame")
        .unwrap_or_else(|| panic!("no data-frame on <body>: {}", &dom[..dom.len().min(400)]))
        .parse()
        .unwrap()
}

/// Pixels of a screenshot inside `rect` (x, y, w, h): how many are close to
/// `colour` (the original's blue, within 40 in each channel), and how many
/// are in the heat colours (green, yellow, red: strongly coloured, max − min
/// channel ≥ 60, and blue well below red or green), which the blue's
/// anti-aliased edges are not.
fn count_pixels(png_path: &Path, rect: [u32; 4], colour: [u8; 3]) -> (usize, usize) {
    let decoder = png::Decoder::new(std::fs::File::open(png_path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert!(channels >= 3, "{:?}", info.color_type);
    let (mut near, mut other) = (0, 0);
    for y in rect[1]..(rect[1] + rect[3]).min(info.height) {
        for x in rect[0]..(rect[0] + rect[2]).min(info.width) {
            let i = (y as usize * info.width as usize + x as usize) * channels;
            let p = [buf[i], buf[i + 1], buf[i + 2]];
            let close = (0..3).all(|k| p[k].abs_diff(colour[k]) <= 40);
            let spread = p.iter().max().unwrap() - p.iter().min().unwrap();
            if close {
                near += 1;
            } else if spread >= 60 && u16::from(p[2]) + 30 < u16::from(p[0].max(p[1])) {
                other += 1;
            }
        }
    }
    (near, other)
}

/// The 3-D view's rectangle from the page (`data-view`, CSS px = screen px
/// at scale 1), less a 220 × 70 corner at the top right where the legend's
/// colour bar is.
fn view_rect(dom: &str) -> [u32; 4] {
    let v: Vec<u32> = body_data(dom, "view")
        .expect("data-view")
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    [v[0], v[1] + 70, v[2] - 220, v[3] - 70]
}

/// The frames shown after 0.4 s and 1.6 s of playing from frame 0.
fn played(browser: &Path, html: &Path) -> (usize, usize) {
    let at = |ms| frame_of(&browse(browser, html, "frame=0", ms, BrowserOutput::Dom));
    (at(400), at(1600))
}

/// The page's blue of the original skeleton (viewer.js `COLOR_ORIGINAL`).
const ORIGINAL: [u8; 3] = [0x3b, 0x6f, 0xc4];

#[test]
fn demo_page_plays_and_scrubs_in_chromium() {
    let Some(browser) = chromium() else {
        return;
    };
    let root = workspace_root();
    let bvh = root.join("assets/animatronic_demo.bvh");
    let clip = root.join("firmware-example/clips/demo.mcb");
    let page = view::load(&bvh, Some(&clip), None).unwrap();
    let worst = page.metrics.as_ref().unwrap().max_joint_err_frame;
    let html = out_dir().join("demo.html");
    std::fs::write(&html, &page.html).unwrap();

    // Paused at frame 0: ready, the demo's 480 frames, the Rust side's worst frame.
    let dom = browse(&browser, &html, "frame=0&paused=1", 500, BrowserOutput::Dom);
    assert_eq!(
        body_data(&dom, "ready").as_deref(),
        Some("1"),
        "page not ready"
    );
    assert_eq!(body_data(&dom, "frames"), Some(page.frames.to_string()));
    assert_eq!(body_data(&dom, "worst"), Some(worst.to_string()));
    assert_eq!(frame_of(&dom), 0);
    assert_eq!(body_data(&dom, "playing").as_deref(), Some("0"));
    let rect = view_rect(&dom);

    // Playing: the frame follows the clock (60 Hz demo, 8 s: no wrap).
    let (early, late) = played(&browser, &html);
    assert!(
        0 < early && early < late && late < page.frames,
        "frames {early} then {late} of {}",
        page.frames
    );

    // Scrubbing by the hash: the worst frame, and a given frame, paused.
    let dom = browse(
        &browser,
        &html,
        "frame=worst&paused=1",
        800,
        BrowserOutput::Dom,
    );
    assert_eq!(frame_of(&dom), worst);
    // The page unpacked the encoder's numbers: the last joint's positions
    // (original and decoded, to the 0.1 mm quantum) and the frame's largest
    // joint error (to the 0.01 mm error quantum) are the encoder's.
    let probe: Vec<f64> = body_data(&dom, "probe")
        .expect("data-probe")
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let m = mocap_encoder::bvh::read_file(&bvh).unwrap();
    let metres = mocap_encoder::units::detect(&m).metres();
    let bytes = std::fs::read(&clip).unwrap();
    let c = mocap_decoder::Clip::parse(&bytes).unwrap();
    let back = mocap_encoder::clipfile::decode_against(&c, &m, metres).unwrap();
    let j = page.joints;
    let at = worst * j + j - 1;
    let a = mocap_encoder::metrics::positions_mm(&m, metres)[at];
    let b = mocap_encoder::metrics::positions_mm(&back, metres)[at];
    for k in 0..3 {
        assert!(
            (probe[k] - a[k]).abs() <= 0.051,
            "original {probe:?} vs {a:?}"
        );
        assert!(
            (probe[3 + k] - b[k]).abs() <= 0.051,
            "decoded {probe:?} vs {b:?}"
        );
    }
    let max = page.metrics.as_ref().unwrap().max_joint_err_mm;
    assert!(
        (probe[6] - max).abs() <= 0.0051,
        "max error {} vs {max}",
        probe[6]
    );
    let dom = browse(
        &browser,
        &html,
        "frame=123&paused=1",
        800,
        BrowserOutput::Dom,
    );
    assert_eq!(frame_of(&dom), 123);

    // The worst frame drawn: the original in blue, the decoded skeleton in
    // its heat colours, in the 3-D view.
    let shot = out_dir().join("demo_worst.png");
    browse(
        &browser,
        &html,
        "frame=worst&paused=1",
        800,
        BrowserOutput::Screenshot(&shot),
    );
    let (blue, heat) = count_pixels(&shot, rect, ORIGINAL);
    eprintln!("demo worst frame {worst}: {blue} original pixels, {heat} decoded (heat) pixels");
    assert!(blue > 500, "original skeleton not drawn: {blue} pixels");
    assert!(heat > 200, "decoded skeleton not drawn: {heat} pixels");

    // Side by side: the original on the left half of the view, the decoded
    // skeleton on the right (the legend's corner left out of both).
    let shot = out_dir().join("demo_side.png");
    browse(
        &browser,
        &html,
        "frame=worst&paused=1&side=1",
        800,
        BrowserOutput::Screenshot(&shot),
    );
    let half = (rect[2] + 220) / 2;
    let left = [rect[0], rect[1], half, rect[3]];
    let right = [rect[0] + half, rect[1], half - 220, rect[3]];
    let (blue_l, heat_l) = count_pixels(&shot, left, ORIGINAL);
    let (blue_r, heat_r) = count_pixels(&shot, right, ORIGINAL);
    assert!(
        blue_l > 500 && heat_r > 200 && blue_r < blue_l / 10 && heat_l < heat_r / 10,
        "side by side: left {blue_l} original, {heat_l} heat; right {blue_r} original, {heat_r} heat"
    );

    // Without the clip: the original alone, no heat colours.
    let alone = view::load(&bvh, None, None).unwrap();
    let html = out_dir().join("demo_alone.html");
    std::fs::write(&html, &alone.html).unwrap();
    let shot = out_dir().join("demo_alone.png");
    browse(
        &browser,
        &html,
        "frame=100&paused=1",
        800,
        BrowserOutput::Screenshot(&shot),
    );
    let (blue, heat) = count_pixels(&shot, rect, ORIGINAL);
    assert!(blue > 500, "skeleton not drawn: {blue} pixels");
    assert!(heat < 20, "{heat} heat pixels without a clip");
}

/// The page of a corpus file with its index clip at 1°: built, its worst
/// frame shown on load (`#frame=worst`), the skeleton drawn with heat on the
/// decoded joints. Returns the page.
fn corpus_clip_page(folder: &str, name: &str) -> Option<view::Page> {
    let bvh = corpus_file(folder, name)?;
    let browser = chromium()?;
    let m = mocap_encoder::bvh::read_file(&bvh).unwrap();
    let enc = encode_index_1deg(&m);
    let stem = name.trim_end_matches(".bvh");
    let clip = out_dir().join(format!("{stem}.mcb"));
    std::fs::write(&clip, &enc).unwrap();
    let page = view::load(&bvh, Some(&clip), None).unwrap();
    let x = page.metrics.as_ref().unwrap();
    eprintln!(
        "{}: {} frames × {} joints: page {} bytes (positions to {} mm); ARMS {:.3} mm, worst frame {}",
        bvh.display(),
        page.frames,
        page.joints,
        page.html.len(),
        page.quantum_mm,
        x.arms_mm,
        x.max_joint_err_frame
    );
    let html = out_dir().join(format!("{stem}.html"));
    std::fs::write(&html, &page.html).unwrap();
    let dom = browse(
        &browser,
        &html,
        "frame=worst&paused=1",
        1000,
        BrowserOutput::Dom,
    );
    assert_eq!(frame_of(&dom), x.max_joint_err_frame);
    let shot = out_dir().join(format!("{stem}_worst.png"));
    browse(
        &browser,
        &html,
        "frame=worst&paused=1",
        1000,
        BrowserOutput::Screenshot(&shot),
    );
    let (blue, heat) = count_pixels(&shot, view_rect(&dom), ORIGINAL);
    assert!(
        blue > 300 && heat > 100,
        "{stem}: {blue} original, {heat} heat pixels"
    );
    Some(page)
}

#[test]
fn corpus_clip_page_in_chromium() {
    let Some(page) = corpus_clip_page("cmu", "05_04.bvh") else {
        return;
    };
    // 05_04 is 10 s at 120 Hz: the size target.
    assert_eq!(page.frames, 1200);
    assert!(page.html.len() < 2_000_000, "{} bytes", page.html.len());
    assert_eq!(page.quantum_mm, 0.1);
}

/// The game rig (101 joints under `RL_BoneRoot`, which stays at the
/// origin) and the long take (2 339 frames, 13.5 m of travel).
#[test]
fn other_rigs_and_lengths_in_chromium() {
    if let Some(page) = corpus_clip_page("iclone-cmu", "002_01.bvh") {
        assert_eq!(page.frames, 171);
    }
    if let Some(page) = corpus_clip_page("cmu-long", "01_14.bvh") {
        assert_eq!(page.frames, 2339);
    }
}

#[test]
fn servo_clip_page_in_chromium() {
    let Some(browser) = chromium() else {
        return;
    };
    let root = workspace_root();
    let (clip, _) = servo_demo_clip("view_servo");
    let page = view::load_servo(
        &clip,
        Some(ServoSource {
            bvh: &root.join("assets/animatronic_demo.bvh"),
            rig: &root.join(DEMO_RIG),
            unit: None,
        }),
    )
    .unwrap();
    // The demo rig's 12 servos at 50 Hz over 8 s; the playback loop starts
    // at neutral, so it changes the first ticks at least.
    assert_eq!(page.servos, 12);
    assert_eq!(page.ticks, 401);
    assert!(page.shaped_ticks > 0);
    // pca-spline at 0.5° of travel: within a few µs of the rig's signal.
    let e = page.max_error_us.unwrap();
    assert!(e > 0.0 && e < 20.0, "{e} µs");
    let html = out_dir().join("servo.html");
    std::fs::write(&html, &page.html).unwrap();

    let dom = browse(
        &browser,
        &html,
        "frame=100&paused=1",
        500,
        BrowserOutput::Dom,
    );
    assert_eq!(body_data(&dom, "ready").as_deref(), Some("1"));
    assert_eq!(body_data(&dom, "frames"), Some(page.ticks.to_string()));
    assert_eq!(
        body_data(&dom, "shaped"),
        Some(page.shaped_ticks.to_string())
    );
    assert_eq!(frame_of(&dom), 100);
    let (early, late) = played(&browser, &html);
    assert!(0 < early && early < late, "ticks {early} then {late}");

    // The curves drawn: the decoded blue and the commanded orange.
    let shot = out_dir().join("servo.png");
    browse(
        &browser,
        &html,
        "frame=100&paused=1",
        500,
        BrowserOutput::Screenshot(&shot),
    );
    let rows = [150, 60, 1000, 700];
    let (blue, _) = count_pixels(&shot, rows, ORIGINAL);
    let (orange, _) = count_pixels(&shot, rows, [0xe0, 0x7b, 0x00]);
    eprintln!("servo page: {blue} decoded pixels, {orange} commanded pixels");
    assert!(blue > 2000, "decoded curves not drawn: {blue} pixels");
    assert!(orange > 500, "commanded curves not drawn: {orange} pixels");
}

#[test]
fn show_page_in_chromium() {
    let Some(browser) = chromium() else {
        return;
    };
    let root = workspace_root();
    let show_path = root.join("firmware-example/clips/demo_show.mcb");
    let cues = root.join("assets/shows/demo_cues.txt");
    let page = view::load_show(&show_path, Some(&cues), Some(&root.join(DEMO_RIG)), 60.0).unwrap();
    // What the show player played, straight from the library.
    let bytes = std::fs::read(&show_path).unwrap();
    let show = mocap_decoder::Show::parse(&bytes).unwrap();
    let text = std::fs::read_to_string(&cues).unwrap();
    let script = Script::parse(&text, "demo_cues.txt", &show).unwrap();
    let played = show_stream(&show, &script, Protocol::Maestro, None, None, 60.0).unwrap();
    assert_eq!(page.ticks, played.timeline.len());
    assert_eq!(page.servos, 12);
    let html = out_dir().join("show.html");
    std::fs::write(&html, &page.html).unwrap();

    // At a few ticks the page names the clip the show player played.
    for tick in [10, page.ticks / 3, page.ticks - 5] {
        let expected = played.timeline[tick]
            .clip
            .map(|k| show.entry(k).unwrap().name.to_string())
            .unwrap_or_default();
        let hash = format!("frame={tick}&paused=1");
        let dom = browse(&browser, &html, &hash, 500, BrowserOutput::Dom);
        assert_eq!(frame_of(&dom), tick);
        assert_eq!(body_data(&dom, "clip"), Some(expected), "tick {tick}");
    }
    let shot = out_dir().join("show.png");
    browse(
        &browser,
        &html,
        "frame=200&paused=1",
        500,
        BrowserOutput::Screenshot(&shot),
    );
    let (blue, _) = count_pixels(&shot, [150, 150, 1000, 600], ORIGINAL);
    assert!(blue > 2000, "curves not drawn: {blue} pixels");
}
