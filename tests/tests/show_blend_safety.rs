//! Blend safety of servo shows on their figure: every transition between
//! two clips, wherever it starts in the clip it leaves, played through the
//! one servo playback loop with the figure's hard limits
//! (`mocap_encoder::show::play::show_stream`, as `mocap play` and the
//! firmware's show mode do), keeps every pulse of every tick inside its
//! servo's pulse range, every per-tick step within its speed step and every
//! change of the per-tick step within the figure's acceleration bound.
//!
//! Over the CMU servo show (`assets/shows/cmu_servo.toml`, every ordered
//! pair of its 7 clips, the pair of a clip with itself included) and the
//! shipped demo show (`assets/shows/demo.toml`, every pair; no corpus
//! needed). Prints, per transition position, the largest step per tick and
//! how often the hard limits clamped (`-- --nocapture`).

use std::path::Path;

use mocap_decoder::{tick_count, tick_us, Command, RigServo, Show};
use mocap_encoder::play::{Figure, Protocol, MAX_SERVOS};
use mocap_encoder::rig::Rig;
use mocap_encoder::show;
use mocap_encoder::show::file::ShowSpec;
use mocap_encoder::show::play::ShowRequest;
use mocap_encoder::show::play::{show_stream, HostShowRunner, Script};
use mocap_servo::{HardLimits, HardStep, Identity, Playback, Policy, ServoLimits};
use mocap_tests::{corpus_dir, corpus_files, workspace_root};

/// What was wrong in a stream of pulses, and its largest moves.
#[derive(Clone, Debug, Default)]
struct Check {
    ticks: usize,
    out_of_range: usize,
    over_step: usize,
    over_accel: usize,
    /// The first violation, for the failure message.
    first: Option<String>,
    /// Largest |step| per tick, ¼ µs, over the stream and inside `window`.
    max_step: u32,
    max_step_window: u32,
    /// Largest |change of the step| per tick of a servo with an
    /// acceleration bound, ¼ µs, and the largest share of its bound, %.
    max_dv: u32,
    max_dv_share: f64,
}

impl Check {
    fn violations(&self) -> usize {
        self.out_of_range + self.over_step + self.over_accel
    }

    fn note(&mut self, what: String) {
        self.first.get_or_insert(what);
    }
}

/// Checks every tick of `pulses` (rig order, ¼ µs), which start from the
/// figure's neutrals at rest (where `Playback::with_hard_limits` starts),
/// against each servo's clip limits (`Playback::limits`: range, speed step)
/// and its hard step at the rig's rate (`HardStep::at_rate`, the bound the
/// hard stage itself applies: range, speed, acceleration). `window` is the
/// range of tick numbers whose steps count as the transition's.
fn check(
    pulses: &[Vec<u16>],
    limits: &[ServoLimits],
    hard: &[HardStep],
    window: std::ops::Range<usize>,
) -> Check {
    let mut c = Check::default();
    let n = limits.len();
    assert_eq!(hard.len(), n);
    let mut prev: Vec<i32> = hard.iter().map(|h| i32::from(h.neutral_qus)).collect();
    let mut vel = vec![0i32; n];
    for (tick, p) in pulses.iter().enumerate() {
        assert_eq!(p.len(), n, "tick {tick}: {} pulses for {n} servos", p.len());
        c.ticks += 1;
        for (s, &q) in p.iter().enumerate() {
            let (l, h) = (&limits[s], &hard[s]);
            if !(l.min_qus..=l.max_qus).contains(&q) || !(h.min_qus..=h.max_qus).contains(&q) {
                c.out_of_range += 1;
                c.note(format!(
                    "tick {tick} servo {s}: pulse {q} qus outside {}..={} (hard {}..={})",
                    l.min_qus, l.max_qus, h.min_qus, h.max_qus
                ));
            }
            let v = i32::from(q) - prev[s];
            let step = v.unsigned_abs();
            c.max_step = c.max_step.max(step);
            if window.contains(&tick) {
                c.max_step_window = c.max_step_window.max(step);
            }
            let over = |limit: u16| limit > 0 && step > u32::from(limit);
            if over(l.max_step_qus) || over(h.max_step_qus) {
                c.over_step += 1;
                c.note(format!(
                    "tick {tick} servo {s}: step {step} qus, speed step {} (hard {})",
                    l.max_step_qus, h.max_step_qus
                ));
            }
            let dv = (v - vel[s]).unsigned_abs();
            if h.max_accel_qus > 0 {
                c.max_dv = c.max_dv.max(dv);
                let share = f64::from(dv) * 100.0 / f64::from(h.max_accel_qus);
                c.max_dv_share = c.max_dv_share.max(share);
            }
            if h.max_accel_qus > 0 && dv > u32::from(h.max_accel_qus) {
                c.over_accel += 1;
                c.note(format!(
                    "tick {tick} servo {s}: step {} -> {v} qus, a change of {dv} (hard bound {})",
                    vel[s], h.max_accel_qus
                ));
            }
            prev[s] = i32::from(q);
            vel[s] = v;
        }
    }
    c
}

/// Where in the clip it leaves a transition starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Position {
    /// One tick after the clip started.
    Start,
    /// Half-way through it.
    Middle,
    /// One tick before its last frame.
    End,
    /// Half a second past its last frame (it holds its last pose).
    AfterEnd,
}

const POSITIONS: [Position; 4] = [
    Position::Start,
    Position::Middle,
    Position::End,
    Position::AfterEnd,
];

impl Position {
    /// The tick at which the transition starts in a clip whose last frame
    /// is at tick `last`, at `rate_mhz`.
    fn tick(self, last: u64, rate_mhz: u32) -> u64 {
        match self {
            Position::Start => 1,
            Position::Middle => (last / 2).max(1),
            Position::End => last.saturating_sub(1).max(1),
            Position::AfterEnd => last + tick_count(500_000, rate_mhz) - 1,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Position::Start => "start (+1 tick)",
            Position::Middle => "middle",
            Position::End => "end (last frame - 1 tick)",
            Position::AfterEnd => "after end (+0.5 s)",
        }
    }
}

/// The figures of one position, over every transition played there.
#[derive(Clone, Debug, Default)]
struct Summary {
    transitions: usize,
    ticks: usize,
    violations: usize,
    /// Largest step per tick inside the fade, and anywhere (¼ µs).
    max_step_window: u32,
    max_step: u32,
    max_dv: u32,
    max_dv_share: f64,
    /// Ticks of the show (before the return to rest) inside the fades and
    /// outside them, and of those the ticks with at least one servo changed
    /// by the hard limits; servo-ticks changed over the whole streams (the
    /// stream's `FigureReport`).
    window_ticks: usize,
    other_ticks: usize,
    clamped_ticks_window: usize,
    clamped_ticks_other: usize,
    transitions_clamped_in_window: usize,
    clamped_servo_ticks: u64,
    worst_clamp_qus: u16,
}

/// Plays `script` on `show` as `show_stream` does, tick by tick on a
/// `Playback` of its own, to tell which ticks the hard limits changed:
/// returns the pulses of the show's ticks (before the return to rest) and,
/// per tick, whether any servo's pulse was changed by the hard stage.
fn clamps_per_tick(
    show: &Show<'_>,
    script: &Script,
    figure: &Figure,
) -> (Vec<Vec<u16>>, Vec<bool>) {
    let rig = show.rig().expect("a servo show");
    let servos: Vec<RigServo> = rig.servos().collect();
    let rate_mhz = rig.rate_mhz();
    let playback = Playback::<MAX_SERVOS>::new(servos.iter().copied(), rate_mhz).unwrap();
    let identity = figure.id().compare(&show.clip(0).unwrap());
    let hard = HardLimits::new(&figure.limits);
    let (mut playback, _) = playback
        .with_hard_limits(&hard, identity.is_same(), figure.policy)
        .unwrap();
    let mut runner = Box::new(HostShowRunner::new(*show).unwrap());
    let mut pose = vec![0i32; show.header().channel_count()];
    let n = servos.len();
    let (mut pulses, mut clamped) = (Vec::new(), Vec::new());
    let mut next = 0;
    let end = script.end_us.expect("scripts here have an end");
    let mut want = [0u16; MAX_SERVOS];
    for i in 0.. {
        let t = tick_us(i, rate_mhz);
        if t > end {
            break;
        }
        while let Some((at, cmd)) = script.commands.get(next).filter(|(at, _)| *at <= t) {
            if let ShowRequest::Run(cmd) = cmd {
                runner.command(*cmd, *at, |_, _| {}).unwrap();
            }
            next += 1;
        }
        runner.tick(t, &mut pose, |_, _| {}).unwrap();
        for ((w, s), &v) in want.iter_mut().zip(&servos).zip(&pose) {
            *w = s.pulse_qus(v);
        }
        let before: u32 = playback.hard_clamps().iter().sum();
        playback.limit(&want).unwrap();
        let after: u32 = playback.hard_clamps().iter().sum();
        pulses.push(playback.held()[..n].to_vec());
        clamped.push(after > before);
    }
    (pulses, clamped)
}

/// Every transition `a → b` (`pairs`) at every position, played on
/// `figure`; asserts that no tick of any stream breaks a limit and prints
/// the figures per position.
fn blend_safety(label: &str, bytes: &[u8], figure: &Figure, pairs: &[(u16, u16)]) {
    let show = Show::parse(bytes).unwrap();
    let rig = show.rig().expect("a servo show");
    let rate_mhz = rig.rate_mhz();
    assert_eq!(
        rate_mhz, figure.rate_mhz,
        "{label}: the figure is the show's rig"
    );
    let fade_us = HostShowRunner::new(show)
        .unwrap()
        .player()
        .default_fade_us();
    let hard: Vec<HardStep> = rig
        .servos()
        .map(|s| {
            let limit = figure
                .limits
                .iter()
                .find(|l| l.output == s.output)
                .expect("the figure has every output of the show");
            HardStep::at_rate(limit, rate_mhz)
        })
        .collect();
    let names: Vec<String> = (0..show.clip_count())
        .map(|i| show.entry(i).unwrap().name.to_string())
        .collect();
    let mut failures = Vec::new();
    let mut speed_step = 0;
    for pos in POSITIONS {
        let mut sum = Summary::default();
        for &(a, b) in pairs {
            let frames = u64::from(show.entry(a).unwrap().frames);
            let ns = u64::from(show.header().frame_time_ns());
            // The tick of `a`'s last frame (local time time(frames − 1)).
            let last = tick_count((frames - 1) * ns / 1000, rate_mhz) - 1;
            let at_tick = pos.tick(last, rate_mhz);
            let at = tick_us(at_tick, rate_mhz);
            let end = at + fade_us + 1_000_000;
            let script = Script {
                commands: vec![
                    (0, ShowRequest::Run(Command::Play(a))),
                    (at, ShowRequest::Run(Command::Play(b))),
                ],
                end_us: Some(end),
            };
            let played = show_stream(&show, &script, Protocol::Maestro, None, Some(figure), 600.0)
                .unwrap_or_else(|e| panic!("{label} {a}->{b} at {pos:?}: {e}"));
            let s = &played.stream;
            let report = s.figure.as_ref().expect("played on the figure");
            assert_eq!(
                report.identity,
                Identity::Same,
                "{label}: made for the figure"
            );
            // The same loop tick by tick, for where the hard limits clamped.
            let (pulses, clamped) = clamps_per_tick(&show, &script, figure);
            assert_eq!(
                pulses,
                s.pulses[..s.clip_ticks],
                "{label} {a}->{b} at {pos:?}: the tick-by-tick replay is show_stream's"
            );
            let window = at_tick as usize..(at_tick + tick_count(fade_us, rate_mhz)) as usize;
            let c = check(&s.pulses, &s.limits, &hard, window.clone());
            speed_step = s.limits.iter().map(|l| l.max_step_qus).max().unwrap_or(0);
            assert!(
                s.pulses.len() > s.clip_ticks,
                "{label}: the stream returns to rest"
            );
            if c.violations() > 0 {
                failures.push(format!(
                    "{label} {} -> {} at {} (tick {at_tick}): {} outside the range, {} over the speed step, {} over the acceleration bound; first: {}",
                    names[usize::from(a)],
                    names[usize::from(b)],
                    pos.name(),
                    c.out_of_range,
                    c.over_step,
                    c.over_accel,
                    c.first.as_deref().unwrap_or("")
                ));
            }
            let in_window = |i: &usize| window.contains(i);
            let count = |inside: bool| {
                clamped
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| in_window(i) == inside)
                    .fold((0, 0), |(n, k), (_, &x)| (n + 1, k + usize::from(x)))
            };
            let ((wn, wk), (on, ok)) = (count(true), count(false));
            sum.window_ticks += wn;
            sum.other_ticks += on;
            sum.clamped_ticks_window += wk;
            sum.clamped_ticks_other += ok;
            sum.transitions_clamped_in_window += usize::from(wk > 0);
            sum.transitions += 1;
            sum.ticks += c.ticks;
            sum.violations += c.violations();
            sum.max_step_window = sum.max_step_window.max(c.max_step_window);
            sum.max_step = sum.max_step.max(c.max_step);
            sum.max_dv = sum.max_dv.max(c.max_dv);
            sum.max_dv_share = sum.max_dv_share.max(c.max_dv_share);
            sum.clamped_servo_ticks += report
                .clamps
                .iter()
                .map(|k| u64::from(k.ticks))
                .sum::<u64>();
            sum.worst_clamp_qus = sum
                .worst_clamp_qus
                .max(report.clamps.iter().map(|k| k.worst_qus).max().unwrap_or(0));
        }
        let us = |q: u32| f64::from(q) / 4.0;
        let pct = |k: usize, n: usize| k as f64 * 100.0 / n.max(1) as f64;
        eprintln!(
            "{label}: {:<26} {} transitions, {} ticks checked, {} violations; largest step {:.2} µs in the fades ({:.2} µs anywhere; speed steps ≤ {:.2} µs); largest step change {:.2} µs ({:.0} % of its servo's bound); hard limits clamped {} of {} fade ticks ({:.1} %, in {} fades) and {} of {} other ticks ({:.1} %); {} servo-ticks in all, worst {:.2} µs",
            pos.name(),
            sum.transitions,
            sum.ticks,
            sum.violations,
            us(sum.max_step_window),
            us(sum.max_step),
            us(u32::from(speed_step)),
            us(sum.max_dv),
            sum.max_dv_share,
            sum.clamped_ticks_window,
            sum.window_ticks,
            pct(sum.clamped_ticks_window, sum.window_ticks),
            sum.transitions_clamped_in_window,
            sum.clamped_ticks_other,
            sum.other_ticks,
            pct(sum.clamped_ticks_other, sum.other_ticks),
            sum.clamped_servo_ticks,
            f64::from(sum.worst_clamp_qus) / 4.0,
        );
    }
    assert!(
        failures.is_empty(),
        "{} of the transitions broke a limit:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Every ordered pair of `n` clips, a clip with itself included.
fn all_pairs(n: u16) -> Vec<(u16, u16)> {
    (0..n).flat_map(|a| (0..n).map(move |b| (a, b))).collect()
}

/// Builds the show file `toml` (relative to the workspace) and its figure:
/// the show's own rig file, `clamp-if-inside`.
fn build(toml: &str) -> (Vec<u8>, Figure) {
    let spec = ShowSpec::read_file(&workspace_root().join(toml)).unwrap();
    let rig_path = spec.rig.clone().expect("a servo show");
    let built = show::build(&spec).unwrap_or_else(|e| panic!("{toml}: {e}"));
    let figure = Figure::from_rig(
        &Rig::read_file(Path::new(&rig_path)).unwrap(),
        Policy::ClampIfInside,
    );
    (built.bytes, figure)
}

#[test]
fn cmu_servo_show_blends_stay_inside_the_figure() {
    if corpus_files("cmu").is_none() || corpus_files("cmu-long").is_none() {
        return;
    }
    // The show file reads `${MOCAP_CORPUS:-…}` relative to its own folder;
    // the corpus helper's folder is absolute (a relative MOCAP_CORPUS is
    // taken from the workspace root there).
    std::env::set_var("MOCAP_CORPUS", corpus_dir());
    let (bytes, figure) = build("assets/shows/cmu_servo.toml");
    let show = Show::parse(&bytes).unwrap();
    assert_eq!(show.clip_count(), 7, "cmu_servo.toml has 7 clips");
    blend_safety("cmu_servo", &bytes, &figure, &all_pairs(show.clip_count()));
}

#[test]
fn demo_show_blends_stay_inside_the_figure() {
    let (bytes, figure) = build("assets/shows/demo.toml");
    let show = Show::parse(&bytes).unwrap();
    blend_safety("demo", &bytes, &figure, &all_pairs(show.clip_count()));
}

/// The checker counts what it must: a pulse out of range, a step over the
/// speed step, a change of step over the acceleration bound — each alone.
#[test]
fn the_checker_catches_each_violation() {
    let limits = [ServoLimits::new(4000, 8000, 6000, 100).unwrap()];
    let hard = [HardStep {
        min_qus: 4000,
        max_qus: 8000,
        neutral_qus: 6000,
        max_step_qus: 100,
        max_accel_qus: 20,
    }];
    let run = |pulses: &[u16]| {
        let p: Vec<Vec<u16>> = pulses.iter().map(|&q| vec![q]).collect();
        check(&p, &limits, &hard, 0..pulses.len())
    };
    // Accelerating by 20 per tick to 100, holding, braking: clean.
    let clean = run(&[
        6020, 6060, 6120, 6200, 6300, 6400, 6480, 6540, 6580, 6600, 6600,
    ]);
    assert_eq!(clean.violations(), 0, "{:?}", clean.first);
    assert_eq!((clean.max_step, clean.max_dv), (100, 20));
    let still = run(&[6000, 6000, 6000]);
    assert_eq!(still.violations(), 0);
    let mut range = hard;
    range[0].max_qus = 6010;
    let p: Vec<Vec<u16>> = [6010u16, 6020].iter().map(|&q| vec![q]).collect();
    let c = check(&p, &limits, &range, 0..2);
    assert_eq!((c.out_of_range, c.over_step, c.over_accel), (1, 0, 0));
    // Up by 20 per tick to 120: one step over the speed step, none too sudden.
    let c = run(&[6020, 6060, 6120, 6200, 6300, 6420]);
    assert_eq!((c.out_of_range, c.over_step, c.over_accel), (0, 1, 0));
    let c = run(&[6020, 6061]);
    assert_eq!((c.out_of_range, c.over_step, c.over_accel), (0, 0, 1));
    // The first move from neutral at rest counts as a change of step too.
    let c = run(&[6021]);
    assert_eq!(c.over_accel, 1);
}
