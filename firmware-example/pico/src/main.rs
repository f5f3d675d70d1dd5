//! mocap-firmware-pico: the Raspberry Pi Pico (RP2040) firmware. It plays the `.mcb` clip
//! embedded in flash (build.rs: `MOCAP_CLIP`) on the figure compiled in (`MOCAP_FIGURE`), paced
//! by the RP2040's 1 MHz hardware timer, and logs with defmt over RTT.
//!
//! - A servo clip (`mocap encode --rig`, SPEC.md §3.5) is held to the figure exactly as the QEMU
//!   firmware and `mocap play --rig` hold it (`../src/figure.rs`, shared: the policy for a clip
//!   made for another rig, then the figure's hard limits), and played through
//!   `mocap_servo::Playback` at the rig's tick rate: `Player::sample_at` per tick, the rig's
//!   pulse mapping, the limiter, the hard limits, the output; after the clip every servo
//!   returns to its neutral at its speed and acceleration limits.
//! - Any other clip (the default `clips/demo.mcb` is a skeleton clip) is played frame by frame
//!   at its own frame rate with `Player::next_frame`, its frames logged once a second; the
//!   servos are held at the figure's neutral.
//!
//! The output (`MOCAP_SERVO`): a PCA9685 on I²C0 (SDA GP16, SCL GP17, address 0x40, 400 kHz;
//! default) or the RP2040's own PWM on GP0–GP15 (output n on GPn, 50 Hz). The LED (GP25) is on
//! while the clip plays and blinks fast after an error. See README.md for wiring and flashing.
#![no_std]
#![no_main]

// The figure and how a clip's rig is held to it: the QEMU firmware's own file.
#[path = "../../src/figure.rs"]
mod figure;

use core::convert::Infallible;

use defmt::{error, info, warn};
use defmt_rtt as _;
use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;
use mocap_decoder::{Clip, Player};
use mocap_servo::output::{Pca9685Output, PwmOutput, ServoOutput};
use mocap_servo::pca9685::{Address, Pca9685Servos};
use mocap_servo::{OutputError, ServoBank};
use panic_probe as _;
use rp2040_hal as hal;

use hal::clocks::init_clocks_and_plls;
use hal::fugit::RateExtU32;
use hal::gpio::{bank0::Gpio25, FunctionI2C, FunctionSioOutput, Pin, PullDown, PullUp};
use hal::{pac, pwm, Clock};

use figure::{Refusal, Rig};

/// The second-stage bootloader for the Pico's W25Q080 flash: the boot ROM runs these first 256
/// bytes of flash (`.boot2`, memory.x), which set up execute-in-place for the rest.
#[link_section = ".boot2"]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// The clip, chosen at build time (build.rs: `MOCAP_CLIP`, default `../clips/demo.mcb`).
static CLIP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/clip.mcb"));

/// The servo output, chosen at build time (build.rs: `MOCAP_SERVO`).
mod config {
    include!(concat!(env!("OUT_DIR"), "/config.rs"));
}

/// The Pico's crystal.
const XOSC_HZ: u32 = 12_000_000;
/// Words of the servo player's state, as in the QEMU firmware (`servo::PLAYER_WORDS`): one per
/// servo and `pca-spline`'s key-interval cache.
const PLAYER_WORDS: usize = 128;
/// Channel capacity of the frame player, as in the QEMU firmware: a full BVH skeleton.
const MAX_CHANNELS: usize = 320;
/// The PCA9685's I²C address (all address pins low) and the bus clock.
const PCA9685_ADDRESS: u8 = 0x40;
const I2C_HZ: u32 = 400_000;
/// PWM: 16 channels (8 slices × A/B) on GP0–GP15; 125 MHz / 100 = 1.25 MHz counts, TOP 24 999:
/// a 20 ms period (50 Hz) in steps of 0.8 µs.
const PWM_CHANNELS: usize = 16;
const PWM_DIV: u8 = 100;
const PWM_TOP: u16 = 24_999;

type Led = Pin<Gpio25, FunctionSioOutput, PullDown>;
type PwmChannel<'a> = &'a mut dyn SetDutyCycle<Error = Infallible>;

/// Why the run stopped early (each is logged where it happens).
struct Stop;

#[hal::entry]
fn main() -> ! {
    info!(
        "mocap-firmware-pico: clip {=usize} bytes, figure {=str}",
        CLIP.len(),
        figure::FIGURE_NAME
    );
    let Some(mut pac) = pac::Peripherals::take() else {
        error!("peripherals already taken");
        idle();
    };
    let mut watchdog = hal::Watchdog::new(pac.WATCHDOG);
    let Ok(clocks) = init_clocks_and_plls(
        XOSC_HZ,
        pac.XOSC,
        pac.CLOCKS,
        pac.PLL_SYS,
        pac.PLL_USB,
        &mut pac.RESETS,
        &mut watchdog,
    ) else {
        error!("clock set-up failed (crystal or PLL)");
        idle();
    };
    let sio = hal::Sio::new(pac.SIO);
    let pins = hal::gpio::Pins::new(
        pac.IO_BANK0,
        pac.PADS_BANK0,
        sio.gpio_bank0,
        &mut pac.RESETS,
    );
    let timer = hal::Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);
    let mut led: Led = pins.gpio25.reconfigure();

    let clip = match Clip::parse(CLIP) {
        Ok(clip) => clip,
        Err(e) => {
            error!("clip: {}", e);
            blink(&mut led, &timer);
        }
    };
    let header = clip.header();
    info!(
        "clip: {=u32} frames of {=usize} channels, {=u64} ms",
        header.frame_count(),
        header.channel_count(),
        header.duration_us() / 1000
    );

    let _ = led.set_high();
    let played = if config::OUTPUT_PWM {
        let mut slices = pwm::Slices::new(pac.PWM, &mut pac.RESETS);
        servo_slice(&mut slices.pwm0);
        servo_slice(&mut slices.pwm1);
        servo_slice(&mut slices.pwm2);
        servo_slice(&mut slices.pwm3);
        servo_slice(&mut slices.pwm4);
        servo_slice(&mut slices.pwm5);
        servo_slice(&mut slices.pwm6);
        servo_slice(&mut slices.pwm7);
        // Output n on GPn: GP2k is slice k's channel A, GP2k+1 its channel B.
        let _gp0 = slices.pwm0.channel_a.output_to(pins.gpio0);
        let _gp1 = slices.pwm0.channel_b.output_to(pins.gpio1);
        let _gp2 = slices.pwm1.channel_a.output_to(pins.gpio2);
        let _gp3 = slices.pwm1.channel_b.output_to(pins.gpio3);
        let _gp4 = slices.pwm2.channel_a.output_to(pins.gpio4);
        let _gp5 = slices.pwm2.channel_b.output_to(pins.gpio5);
        let _gp6 = slices.pwm3.channel_a.output_to(pins.gpio6);
        let _gp7 = slices.pwm3.channel_b.output_to(pins.gpio7);
        let _gp8 = slices.pwm4.channel_a.output_to(pins.gpio8);
        let _gp9 = slices.pwm4.channel_b.output_to(pins.gpio9);
        let _gp10 = slices.pwm5.channel_a.output_to(pins.gpio10);
        let _gp11 = slices.pwm5.channel_b.output_to(pins.gpio11);
        let _gp12 = slices.pwm6.channel_a.output_to(pins.gpio12);
        let _gp13 = slices.pwm6.channel_b.output_to(pins.gpio13);
        let _gp14 = slices.pwm7.channel_a.output_to(pins.gpio14);
        let _gp15 = slices.pwm7.channel_b.output_to(pins.gpio15);
        let channels: [PwmChannel; PWM_CHANNELS] = [
            &mut slices.pwm0.channel_a,
            &mut slices.pwm0.channel_b,
            &mut slices.pwm1.channel_a,
            &mut slices.pwm1.channel_b,
            &mut slices.pwm2.channel_a,
            &mut slices.pwm2.channel_b,
            &mut slices.pwm3.channel_a,
            &mut slices.pwm3.channel_b,
            &mut slices.pwm4.channel_a,
            &mut slices.pwm4.channel_b,
            &mut slices.pwm5.channel_a,
            &mut slices.pwm5.channel_b,
            &mut slices.pwm6.channel_a,
            &mut slices.pwm6.channel_b,
            &mut slices.pwm7.channel_a,
            &mut slices.pwm7.channel_b,
        ];
        let bank = ServoBank::new(channels);
        info!(
            "output: PWM on GP0-GP15, 50 Hz, {=u32} steps of 0.8 us per period",
            u32::from(PWM_TOP) + 1
        );
        play(&clip, &timer, |outputs| PwmOutput::new(bank, outputs))
    } else {
        let sda: Pin<_, FunctionI2C, PullUp> = pins.gpio16.reconfigure();
        let scl: Pin<_, FunctionI2C, PullUp> = pins.gpio17.reconfigure();
        let i2c = hal::I2C::i2c0(
            pac.I2C0,
            sda,
            scl,
            I2C_HZ.Hz(),
            &mut pac.RESETS,
            clocks.system_clock.freq(),
        );
        info!(
            "output: PCA9685 at {=u8:#x} on I2C0 (SDA GP16, SCL GP17, 400 kHz), 50 Hz",
            PCA9685_ADDRESS
        );
        match Pca9685Servos::new(i2c, Address::from(PCA9685_ADDRESS)) {
            Ok(device) => play(&clip, &timer, |outputs| Pca9685Output::new(device, outputs)),
            Err(_) => {
                error!("the PCA9685 did not answer: check SDA GP16, SCL GP17, VCC 3V3, GND and its address pins");
                Err(Stop)
            }
        }
    };
    let _ = led.set_low();
    match played {
        Ok(()) => {
            info!("done: every servo at rest; reset the board to play again");
            idle()
        }
        Err(Stop) => blink(&mut led, &timer),
    }
}

/// A PWM slice at 50 Hz for servos ([`PWM_DIV`], [`PWM_TOP`]).
fn servo_slice<I: pwm::SliceId>(slice: &mut pwm::Slice<I, pwm::FreeRunning>) {
    slice.set_div_int(PWM_DIV);
    slice.set_div_frac(0);
    slice.set_top(PWM_TOP);
    slice.enable();
}

/// Builds the output for the servos of the rig that plays `clip` (`make(outputs)`), then plays:
/// a servo clip on its rig held to the figure, any other clip's frames with the servos at the
/// figure's neutral.
fn play<O: ServoOutput>(
    clip: &Clip<'static>,
    timer: &hal::Timer,
    make: impl FnOnce(&[u16]) -> Result<O, mocap_servo::Error>,
) -> Result<(), Stop> {
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
    if servo_clip {
        servo_ticks(clip, &mut rig, &mut output, timer)
    } else {
        // The rig starts at neutral: one write puts every servo there.
        rig.write(&mut output).map_err(output_failed)?;
        frames(clip, timer)
    }
}

/// Logs a failed output write.
fn output_failed<E>(e: OutputError<E>) -> Stop {
    match e {
        OutputError::Invalid(e) => error!("servo output: {}", e),
        _ => error!("servo output device failed (PCA9685: I2C error, check the wiring)"),
    }
    Stop
}

/// The hardware timer's µs counter, from the start of playback.
struct Pace<'t> {
    timer: &'t hal::Timer,
    start_us: u64,
    /// Deadlines already past when waited for (a tick that overran its period).
    late: u32,
}

impl<'t> Pace<'t> {
    fn start(timer: &'t hal::Timer) -> Self {
        Pace {
            timer,
            start_us: timer.get_counter().ticks(),
            late: 0,
        }
    }

    fn now_us(&self) -> u64 {
        self.timer.get_counter().ticks()
    }

    /// Waits until `t_us` after the start.
    fn wait_until(&mut self, t_us: u64) {
        let deadline = self.start_us.saturating_add(t_us);
        if self.now_us() > deadline {
            self.late = self.late.saturating_add(1);
        }
        while self.now_us() < deadline {}
    }
}

/// Time of each tick's work (decode, limits, output), µs.
#[derive(Default)]
struct Busy {
    count: u64,
    total_us: u64,
    max_us: u64,
}

impl Busy {
    fn add(&mut self, us: u64) {
        self.count = self.count.saturating_add(1);
        self.total_us = self.total_us.saturating_add(us);
        self.max_us = self.max_us.max(us);
    }

    /// `what`: count, mean and worst µs, and the share of a `period_us` period (1/100 %).
    fn log(&self, what: &str, period_us: u64, late: u32) {
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
    timer: &hal::Timer,
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
    let mut pace = Pace::start(timer);
    let mut result = Ok(());
    for i in 0..n_ticks {
        let t_us = rig.tick_us(i);
        pace.wait_until(t_us);
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
    // Back to neutral, one tick per period after the last.
    let mut k = n_ticks;
    rig.park(output, |_| {
        k = k.saturating_add(1);
        pace.wait_until(rig_tick_us(period_us, k));
        Ok::<(), OutputError<O::Error>>(())
    })
    .map_err(output_failed)?;
    busy.log("ticks", period_us, pace.late);
    info!("at rest after {=u64} park ticks", k.saturating_sub(n_ticks));
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
    result
}

/// Tick `k`'s time at a period of `period_us` (the park's ticks continue the clip's).
fn rig_tick_us(period_us: u64, k: u64) -> u64 {
    period_us.saturating_mul(k)
}

/// Any clip's frames at its frame rate; one logged a second.
fn frames(clip: &Clip<'static>, timer: &hal::Timer) -> Result<(), Stop> {
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
    let mut pace = Pace::start(timer);
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

/// Sleeps for good (the servos hold their last pulses).
fn idle() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

/// Blinks the LED at 5 Hz for good: the run stopped on an error (the log says which).
fn blink(led: &mut Led, timer: &hal::Timer) -> ! {
    let mut pace = Pace::start(timer);
    let mut t = 0u64;
    loop {
        let _ = led.set_high();
        t = t.saturating_add(100_000);
        pace.wait_until(t);
        let _ = led.set_low();
        t = t.saturating_add(100_000);
        pace.wait_until(t);
    }
}
