//! Clock following (SPEC.md §8.2, `mocap_decoder::ShowClock`): a figure whose own tick clock
//! runs ±100 ppm off, told the show's time by a timecode every second, plays a simulated
//! 10-minute show within one servo tick of the reference clock, and no step of its servo
//! angles is larger than the clip's own (played on the reference clock) by more than the
//! clock's largest slew (0.5 %). `-- --nocapture` prints the figures (BENCHMARKS.md §6).

use mocap_decoder::show::clock::DEFAULT_SLEW_PPM;
use mocap_decoder::{tick_us, Show, ShowClock};
use mocap_encoder::show::{self, file::ShowSpec, HostShowPlayer};
use mocap_tests::workspace_root;

/// 50 Hz: the demo figure's rate.
const RATE_MHZ: u32 = 50_000;
const TICK_US: f64 = 20_000.0;
/// Ten minutes of ticks.
const TICKS: u64 = 10 * 60 * 50;

fn demo_show() -> Vec<u8> {
    let spec = ShowSpec::read_file(&workspace_root().join("assets/shows/demo.toml")).unwrap();
    show::build(&spec).unwrap().bytes
}

/// How a timecode reaches the clock.
#[derive(Clone, Copy, PartialEq)]
enum Stamp {
    /// No timecode.
    None,
    /// Stamped with the local time it arrives at (a board's receive interrupt).
    Arrival,
    /// Taken at the next tick, stamped with that tick's time (this example firmware polls its
    /// UART once a tick): up to a tick late.
    NextTick,
}

/// Plays the looping clip `look` (clip 1) for ten minutes with the local clock `ppm` off:
/// the largest |show − reference| time (µs) and the largest angle step per tick (mdeg).
fn follow(bytes: &[u8], ppm: f64, stamp: Stamp) -> (f64, i32) {
    let show = Show::parse(bytes).unwrap();
    let mut p = Box::new(HostShowPlayer::new(show).unwrap());
    p.play(1, 0).unwrap();
    let mut clock = ShowClock::new(DEFAULT_SLEW_PPM);
    let n = show.header().channel_count();
    let (mut prev, mut pose) = (vec![0; n], vec![0; n]);
    let mut worst_err = 0f64;
    let mut worst_step = 0;
    let mut next_tc = 1u64;
    for i in 0..TICKS {
        // The figure's tick i happens at true time local / (1 + ppm).
        let local = tick_us(i, RATE_MHZ);
        let truth = local as f64 / (1.0 + ppm * 1e-6);
        // A timecode each true second.
        while stamp != Stamp::None && (next_tc * 1_000_000) as f64 <= truth {
            let arrival = ((next_tc * 1_000_000) as f64 * (1.0 + ppm * 1e-6)) as u64;
            let at = if stamp == Stamp::Arrival {
                arrival
            } else {
                local
            };
            clock.timecode(at, next_tc * 1_000_000);
            next_tc += 1;
        }
        let t = clock.now(local);
        worst_err = worst_err.max((t as f64 - truth).abs());
        p.sample(t, &mut pose).unwrap();
        if i > 0 {
            for (a, b) in prev.iter().zip(&pose) {
                worst_step = worst_step.max((b - a).abs());
            }
        }
        std::mem::swap(&mut prev, &mut pose);
    }
    (worst_err, worst_step)
}

#[test]
fn a_ten_minute_show_follows_timecode_within_one_tick() {
    let bytes = demo_show();
    // The clip's own largest step, on the reference clock.
    let (_, own) = follow(&bytes, 0.0, Stamp::None);
    let slack = (f64::from(own) * f64::from(DEFAULT_SLEW_PPM) * 1e-6).ceil() as i32 + 1;
    for ppm in [100.0, -100.0] {
        let (drift, _) = follow(&bytes, ppm, Stamp::None);
        let (err, step) = follow(&bytes, ppm, Stamp::Arrival);
        let (polled, polled_step) = follow(&bytes, ppm, Stamp::NextTick);
        eprintln!(
            "clock {ppm:+} ppm, 10 min: without timecode {:.1} ms off; timecode every second \
             stamped on arrival: at most {:.3} ms off, largest step {step} mdeg; taken at the next \
             tick: at most {:.3} ms off, largest step {polled_step} mdeg (a tick is {:.0} ms, the \
             clip's own largest step {own} mdeg)",
            drift / 1000.0,
            err / 1000.0,
            polled / 1000.0,
            TICK_US / 1000.0
        );
        assert!(
            drift > TICK_US,
            "without timecode the drift exceeds a tick ({drift} µs)"
        );
        assert!(err <= 1_000.0, "{ppm} ppm: {err} µs off");
        assert!(polled <= TICK_US, "{ppm} ppm, polled: {polled} µs off");
        for s in [step, polled_step] {
            assert!(s <= own + slack, "{ppm} ppm: step {s} > {own} + {slack}");
        }
    }
}

#[test]
fn the_clock_slews_without_jumping_and_relocates_past_two_seconds() {
    let mut c = ShowClock::new(DEFAULT_SLEW_PPM);
    assert_eq!(c.now(1_000_000), 1_000_000);
    // The show is 1.5 s ahead: the clock catches up at 0.5 %, never jumping.
    c.timecode(1_000_000, 2_500_000);
    let mut last = c.now(1_000_000);
    for i in 1..=40_000u64 {
        let t = c.now(1_000_000 + i * 20_000);
        let step = t - last;
        assert!(
            (20_000..=20_100).contains(&step),
            "tick {i}: step {step} µs"
        );
        last = t;
    }
    assert_eq!(c.error_us(), 0, "caught up within 800 s of ticks");
    // 3 s behind: a relocation.
    let now = c.now(900_000_000);
    c.timecode(900_000_000, now + 3_000_000);
    assert_eq!(c.now(900_000_000), now + 3_000_000);
    assert_eq!(c.timecodes(), (2, 1));
}
