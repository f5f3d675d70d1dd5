//! Playback on a real board, shared by the board firmwares (`pico/src/main.rs`,
//! `blackpill/src/main.rs`, `esp32c3/src/main.rs`, included there with `#[path]`): the board
//! sets up its clocks, its timer (a [`Clock`]), its UART (a receive interrupt that hands bytes
//! to `show::received`, and a way to send), its e-stop input and its servo output, then calls
//! [`play`]. The figure is `../src/figure.rs`, the QEMU firmware's own.
//!
//! - A servo clip is held to the figure (the policy, then its hard limits) and played through
//!   `mocap_servo::Playback` at the rig's tick rate, then parked at the figure's limits.
//! - A show (`mocap show build`, SPEC.md §9) runs its show mode (`hw/show.rs`, with the QEMU
//!   firmware's own loop `../src/show_core.rs`): commands over the UART, every tick through the
//!   same figure and output.
//! - Any other clip plays its frames at its frame rate, one logged a second, with the servos
//!   at the figure's neutral.
//!
//! The e-stop (pressed: `estop()` true) parks every servo at its speed and acceleration limits
//! and ends the run, in a servo clip and in a show. Everything is logged with defmt.

use defmt::{error, info, warn};
use mocap_decoder::{Clip, Player, Show};
use mocap_servo::output::{Pca9685Output, ServoOutput};
use mocap_servo::pca9685::{Address, Pca9685Servos};
use mocap_servo::OutputError;

use crate::figure::{self, Refusal, Rig};
use crate::show;

/// Words of the servo player's state, as in the QEMU firmware (`servo::PLAYER_WORDS`): one per
/// servo and `pca-spline`'s key-interval cache.
pub const PLAYER_WORDS: usize = 128;
/// Channel capacity of the frame player, as in the QEMU firmware: a full BVH skeleton.
pub const MAX_CHANNELS: usize = 320;

/// The clip, chosen at build time (`hw/build_board.rs`: `MOCAP_CLIP`, default
/// `../clips/demo.mcb`).
pub static CLIP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/clip.mcb"));

/// The servo output, chosen at build time (`hw/build_board.rs`: `MOCAP_SERVO`).
pub mod config {
    include!(concat!(env!("OUT_DIR"), "/config.rs"));
}

/// The PCA9685's I²C address (all address pins low).
pub const PCA9685_ADDRESS: u8 = 0x40;

/// Why the run stopped early (each is logged where it happens).
pub struct Stop;

/// What [`CLIP`] holds.
pub enum Embedded {
    /// A clip.
    Clip(Clip<'static>),
    /// A show, and its first clip (whose rig table every clip of the show shares).
    Show(Show<'static>, Clip<'static>),
}

/// [`CLIP`] parsed, its header logged.
#[inline(always)]
pub fn parse_clip() -> Result<Embedded, Stop> {
    // `config::SHOW` (build time) says the same: the other branch is left out of the build.
    if config::SHOW && CLIP.get(4) == Some(&mocap_decoder::consts::VERSION_SHOW) {
        let parsed = Show::parse(CLIP).and_then(|show| Ok((show, show.clip(0)?)));
        let (show, first) = parsed.map_err(|e| {
            error!("show: {}", e);
            Stop
        })?;
        info!("show: {=u16} clips", show.clip_count());
        return Ok(Embedded::Show(show, first));
    }
    let clip = Clip::parse(CLIP).map_err(|e| {
        error!("clip: {}", e);
        Stop
    })?;
    let header = clip.header();
    info!(
        "clip: {=u32} frames of {=usize} channels, {=u64} ms",
        header.frame_count(),
        header.channel_count(),
        header.duration_us() / 1000
    );
    Ok(Embedded::Clip(clip))
}

/// After the run: sleeps for good when it played (the servos hold their rest pulses), else
/// blinks the LED at 5 Hz for good (the log says which error); `light(true)` lights it.
#[inline(always)]
pub fn finish(played: Result<(), Stop>, clock: &impl Clock, light: impl FnMut(bool)) -> ! {
    match played {
        Ok(()) => {
            info!("done: every servo at rest; reset the board to play again");
            idle()
        }
        Err(Stop) => blink(clock, light),
    }
}

/// Sleeps for good (the servos hold their last pulses).
pub fn idle() -> ! {
    loop {
        #[cfg(target_arch = "arm")]
        cortex_m::asm::wfi();
        // RISC-V (the ESP32-C3): spins. After esp-hal's set-up its WFI gates the core's clock
        // (SYSTEM_CPU_WAIT_MODE_FORCE_ON cleared); spinning keeps the core, and probe-rs's
        // reading of the defmt log through its JTAG debug module, undisturbed.
        #[cfg(not(target_arch = "arm"))]
        core::hint::spin_loop();
    }
}

/// Blinks the LED at 5 Hz for good: the run stopped on an error (the log says which).
#[inline(always)]
pub fn blink(clock: &impl Clock, mut light: impl FnMut(bool)) -> ! {
    let mut pace = Pace::start(clock);
    let mut t = 0u64;
    loop {
        light(true);
        t = t.saturating_add(100_000);
        pace.wait_until(t);
        light(false);
        t = t.saturating_add(100_000);
        pace.wait_until(t);
    }
}

/// The board's inputs and outputs besides the servos: the e-stop input (`estop()`: pressed) and
/// the UART's transmit side (`send(bytes)`, blocking; its receive side feeds `show::received`).
pub struct Io<E, S> {
    pub estop: E,
    pub send: S,
}

/// Builds the output for the servos of the rig that plays `embedded` (`make(outputs)`), then
/// plays: a servo clip on its rig held to the figure, a show on its clips' rig held to the
/// figure, any other clip's frames with the servos at the figure's neutral.
pub fn play<O: ServoOutput>(
    embedded: &Embedded,
    clock: &impl Clock,
    mut io: Io<impl FnMut() -> bool, impl FnMut(&[u8])>,
    make: impl FnOnce(&[u16]) -> Result<O, mocap_servo::Error>,
) -> Result<(), Stop> {
    let (clip, show) = match embedded {
        Embedded::Clip(clip) => (clip, None),
        Embedded::Show(show, first) => (first, Some(*show)),
    };
    let (mut rig, servo_clip) = match figure::candidate(clip) {
        Ok(candidate) => {
            info!(
                "figure {=str}: {=usize} servos, digest {=u32:#010x}, policy {=str}; the clip: {}, {}",
                figure::FIGURE_NAME,
                figure::FIGURE_SERVOS.len(),
                figure::FIGURE_DIGEST,
                figure::POLICY.name(),
                candidate.identity,
                candidate.fit
            );
            match candidate.harden() {
                Ok(rig) => (rig, true),
                Err(e) => {
                    error!("figure: {}", e);
                    return Err(Stop);
                }
            }
        }
        Err(Refusal::NoRigTable) if show.is_some() => {
            error!(
                "the show has no rig table (made without a rig): this firmware plays servo shows"
            );
            return Err(Stop);
        }
        Err(Refusal::NoRigTable) => {
            warn!("the clip has no rig table (made without `mocap encode --rig`): its frames play, the servos stay at the figure's neutral");
            match figure::figure_rig() {
                Ok((rig, _)) => (rig, false),
                Err(e) => {
                    error!("figure: {}", e);
                    return Err(Stop);
                }
            }
        }
        Err(Refusal::Playback(e)) => {
            error!("the clip's rig: {}", e);
            return Err(Stop);
        }
    };
    let all = rig.outputs();
    let outputs = all.get(..rig.count()).unwrap_or(&[]);
    let mut output = make(outputs).map_err(|e| {
        error!("servo output: {}", e);
        Stop
    })?;
    // The build links one of the two: the show mode for a show, the clip playback for a clip.
    if config::SHOW {
        match show {
            Some(show) => show::run(show, &mut rig, &mut output, clock, &mut io),
            None => Err(Stop),
        }
    } else if servo_clip {
        servo_ticks(clip, &mut rig, &mut output, clock, &mut io.estop)
    } else {
        // The rig starts at neutral: one write puts every servo there.
        rig.write(&mut output).map_err(output_failed)?;
        frames(clip, clock)
    }
}

/// [`play`] on a PCA9685 at [`PCA9685_ADDRESS`] on `i2c`; `pins` names the board's I²C pins
/// for the message when it does not answer.
pub fn play_pca9685<I: embedded_hal::i2c::I2c>(
    embedded: &Embedded,
    clock: &impl Clock,
    io: Io<impl FnMut() -> bool, impl FnMut(&[u8])>,
    i2c: I,
    pins: &str,
) -> Result<(), Stop> {
    match Pca9685Servos::new(i2c, Address::from(PCA9685_ADDRESS)) {
        Ok(device) => play(embedded, clock, io, |outputs| {
            Pca9685Output::new(device, outputs)
        }),
        Err(_) => {
            error!(
                "the PCA9685 did not answer: check {=str}, VCC 3V3, GND and its address pins",
                pins
            );
            Err(Stop)
        }
    }
}

/// Logs a failed output write.
pub fn output_failed<E>(e: OutputError<E>) -> Stop {
    match e {
        OutputError::Invalid(e) => error!("servo output: {}", e),
        _ => error!("servo output device failed (PCA9685: I2C error, check the wiring)"),
    }
    Stop
}

/// A board's free-running µs counter (a hardware timer), never wrapping in practice.
pub trait Clock {
    fn now_us(&self) -> u64;
}

/// Deadlines on the board's [`Clock`], from the start of playback.
pub struct Pace<'t, C: Clock> {
    clock: &'t C,
    start_us: u64,
    /// Deadlines already past when waited for (a tick that overran its period).
    pub late: u32,
}

impl<'t, C: Clock> Pace<'t, C> {
    pub fn start(clock: &'t C) -> Self {
        Pace {
            clock,
            start_us: clock.now_us(),
            late: 0,
        }
    }

    pub fn now_us(&self) -> u64 {
        self.clock.now_us()
    }

    /// Waits until `t_us` after the start.
    pub fn wait_until(&mut self, t_us: u64) {
        let deadline = self.start_us.saturating_add(t_us);
        if self.now_us() > deadline {
            self.late = self.late.saturating_add(1);
        }
        while self.now_us() < deadline {}
    }
}

/// Time of each tick's work (decode, limits, output), µs.
#[derive(Default)]
pub struct Busy {
    count: u64,
    total_us: u64,
    max_us: u64,
}

impl Busy {
    pub fn add(&mut self, us: u64) {
        self.count = self.count.saturating_add(1);
        self.total_us = self.total_us.saturating_add(us);
        self.max_us = self.max_us.max(us);
    }

    /// `what`: count, mean and worst µs, and the share of a `period_us` period (1/100 %).
    pub fn log(&self, what: &str, period_us: u64, late: u32) {
        let mean = self.total_us.checked_div(self.count).unwrap_or(0);
        info!(
            "{=str}: {=u64}, {=u64} us each on average, worst {=u64} us, {=u64}/10000 of the period; {=u32} late",
            what,
            self.count,
            mean,
            self.max_us,
            (mean * 10_000).checked_div(period_us).unwrap_or(0),
            late
        );
    }
}

/// A servo clip at its rig's rate through `output`, then back to rest.
fn servo_ticks<O: ServoOutput>(
    clip: &Clip<'static>,
    rig: &mut Rig,
    output: &mut O,
    clock: &impl Clock,
    estop: &mut impl FnMut() -> bool,
) -> Result<(), Stop> {
    let mut player = Player::<PLAYER_WORDS>::new(clip).map_err(|e| {
        error!("player: {}", e);
        Stop
    })?;
    let n_ticks = rig.tick_count(clip.header().duration_us());
    let period_us = rig.tick_us(1);
    // One progress line a second.
    let per_second = (1_000_000u64.checked_div(period_us).unwrap_or(1)).max(1);
    info!(
        "servo clip: {=usize} servos, {=u32} mHz, {=u64} ticks",
        rig.count(),
        rig.rate_mhz(),
        n_ticks
    );
    let mut angles = [0i32; PLAYER_WORDS];
    let mut busy = Busy::default();
    let mut pace = Pace::start(clock);
    let mut result = Ok(());
    let mut last = n_ticks;
    for i in 0..n_ticks {
        let t_us = rig.tick_us(i);
        pace.wait_until(t_us);
        if estop() {
            warn!("e-stop at {=u64} ms: every servo to rest", t_us / 1000);
            last = i;
            break;
        }
        let t0 = pace.now_us();
        if let Err(e) = player.sample_at(t_us, &mut angles) {
            // Faults end at rest: park below, then stop.
            error!("decode error at {=u64} ms: {}", t_us / 1000, e);
            result = Err(Stop);
            break;
        }
        let targets = rig.targets(&angles);
        rig.tick(&targets, output).map_err(output_failed)?;
        busy.add(pace.now_us().saturating_sub(t0));
        if i % per_second == 0 {
            info!("t={=u64} ms pulses_qus={}", t_us / 1000, rig.held());
        }
    }
    park(rig, output, &mut pace, last)?;
    busy.log("ticks", period_us, pace.late);
    log_hard_clamps(rig);
    result
}

/// Back to neutral at the speed and acceleration limits, one tick per period after tick `last`.
pub fn park<O: ServoOutput, C: Clock>(
    rig: &mut Rig,
    output: &mut O,
    pace: &mut Pace<'_, C>,
    last: u64,
) -> Result<(), Stop> {
    let period_us = rig.tick_us(1);
    let mut k = last;
    rig.park(output, |_| {
        k = k.saturating_add(1);
        pace.wait_until(period_us.saturating_mul(k));
        Ok::<(), OutputError<O::Error>>(())
    })
    .map_err(output_failed)?;
    info!("at rest after {=u64} park ticks", k.saturating_sub(last));
    Ok(())
}

/// What the figure's hard limits changed, per servo.
pub fn log_hard_clamps(rig: &Rig) {
    for ((servo, &ticks), &worst) in rig
        .servos()
        .iter()
        .zip(rig.hard_clamps())
        .zip(rig.hard_worst())
    {
        if ticks != 0 {
            info!(
                "hard limits changed output {=u16} on {=u32} ticks, at most {=u16} qus",
                servo.output, ticks, worst
            );
        }
    }
}

/// Any clip's frames at its frame rate; one logged a second.
fn frames(clip: &Clip<'static>, clock: &impl Clock) -> Result<(), Stop> {
    let header = clip.header();
    let mut player = Player::<MAX_CHANNELS>::new(clip).map_err(|e| {
        error!("player: {}", e);
        Stop
    })?;
    let channels = player.channel_count();
    let frame_ns = u64::from(header.frame_time_ns());
    let per_second = 1_000_000_000u64.checked_div(frame_ns).unwrap_or(1).max(1);
    info!(
        "frames: {=u32} at {=u64} ns each",
        header.frame_count(),
        frame_ns
    );
    let mut out = [0i32; MAX_CHANNELS];
    let mut busy = Busy::default();
    let mut pace = Pace::start(clock);
    let mut next = 0u64;
    loop {
        pace.wait_until(next.saturating_mul(frame_ns) / 1000);
        let t0 = pace.now_us();
        match player.next_frame(&mut out) {
            Ok(Some(index)) => {
                busy.add(pace.now_us().saturating_sub(t0));
                if u64::from(index) % per_second == 0 {
                    let shown = out.get(..channels.min(6)).unwrap_or(&[]);
                    info!(
                        "frame {=u32} t={=u64} ms: {} ...",
                        index,
                        next.saturating_mul(frame_ns) / 1_000_000,
                        shown
                    );
                }
                next = next.saturating_add(1);
            }
            Ok(None) => break,
            Err(e) => {
                error!("decode error at frame {=u64}: {}", next, e);
                return Err(Stop);
            }
        }
    }
    busy.log("frames", frame_ns / 1000, pace.late);
    Ok(())
}
