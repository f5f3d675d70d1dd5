//! mocap-firmware-esp32c3: the ESP32-C3 (RISC-V RV32IMC, esp-hal) firmware. It plays the `.mcb`
//! clip embedded in flash on the figure compiled in, paced by the system timer's µs
//! (`esp_hal::time::Instant`), and logs with defmt over RTT, which probe-rs reads through the
//! chip's built-in USB-Serial-JTAG. The playback is the one every real board shares
//! (`../hw/play.rs`, with the QEMU firmware's `../src/figure.rs`); this file sets up the board.
//!
//! A show (`mocap show build`) runs the show mode every board shares (`../hw/show.rs`, with the
//! QEMU firmware's loop `../src/show_core.rs`): commands as `Show` frames on UART0 (TX GPIO21,
//! RX GPIO20, 115 200 baud 8N1; SPEC.md §8.2, `mocap send show.mcb --cues cues.txt --port …`).
//! The e-stop is GPIO9 (pulled up; the BOOT button of most boards, or a button to GND, parks
//! every servo and ends the run).
//!
//! The output (`MOCAP_SERVO`): a PCA9685 on I2C0 (SDA GPIO4, SCL GPIO5, address 0x40, 400 kHz;
//! default) or 6 PWM servos at 50 Hz on the LEDC's six channels (14-bit duty, 1.22 µs steps):
//! outputs 0–5 on GPIO0, GPIO1, GPIO3, GPIO4, GPIO5, GPIO6 (GPIO2, a strapping pin, is left
//! out). The LED (GPIO8, active low, as on the ESP32-C3 SuperMini) is on while the clip plays and
//! blinks fast after an error. See README.md for wiring and flashing.
#![no_std]
#![no_main]

// The figure and how a clip's rig is held to it: the QEMU firmware's own file.
#[path = "../../src/figure.rs"]
mod figure;
// The playback every real board shares: clip, figure, pacing, logs.
#[path = "../../hw/play.rs"]
mod play;
// The show mode every real board shares, and its loop, the QEMU firmware's own.
#[path = "../../hw/show.rs"]
mod show;
#[path = "../../src/show_core.rs"]
mod show_core;

use core::cell::RefCell;

use critical_section::Mutex;
use defmt::{error, info};
use defmt_rtt as _;
use esp_hal::clock::CpuClock;
use esp_hal::gpio::{DriveMode, Input, InputConfig, Level, Output, OutputConfig, Pull};
use esp_hal::i2c::master::{Config as I2cConfig, I2c};
use esp_hal::ledc::channel::{self, ChannelIFace};
use esp_hal::ledc::timer::{self, TimerIFace};
use esp_hal::ledc::{LSGlobalClkSource, Ledc, LowSpeed};
use esp_hal::time::{Instant, Rate};
use esp_hal::uart::{Config as UartConfig, RxConfig, Uart, UartInterrupt};
use esp_hal::{handler, main, Blocking};
use mocap_servo::output::PwmOutput;
use mocap_servo::ServoBank;

use play::{idle, Io};

// The application descriptor the ESP-IDF second-stage bootloader checks before it starts the
// app (esp-bootloader-esp-idf): espflash and probe-rs flash that bootloader with the ELF.
esp_bootloader_esp_idf::esp_app_desc!();

/// The PCA9685's I²C bus clock.
const I2C_KHZ: u32 = 400;
/// PWM: the LEDC's six low-speed channels, one timer at 50 Hz with 14-bit duty (80 MHz APB
/// clock / 97.66: a 20 ms period in 16 384 steps of 1.22 µs).
const PWM_CHANNELS: usize = 6;
const PWM_HZ: u32 = 50;
/// The receive FIFO's interrupt level (bytes); a receive timeout (10 bit times of silence)
/// takes the rest.
const RX_FIFO_LEVEL: u16 = 16;
/// Bytes the receive interrupt reads from the FIFO at a time.
const RX_CHUNK: usize = 32;

/// UART0, shared by the main code (replies) and its receive interrupt ([`uart0_received`]).
static UART0: Mutex<RefCell<Option<Uart<'static, Blocking>>>> = Mutex::new(RefCell::new(None));

/// The system timer's µs since boot (64 bits: it never wraps in practice).
struct Micros;

impl play::Clock for Micros {
    fn now_us(&self) -> u64 {
        Instant::now().duration_since_epoch().as_micros()
    }
}

#[main]
fn main() -> ! {
    info!(
        "mocap-firmware-esp32c3: clip {=usize} bytes, figure {=str}",
        play::CLIP.len(),
        figure::FIGURE_NAME
    );
    let p = esp_hal::init(esp_hal::Config::default().with_cpu_clock(CpuClock::max()));
    let clock = Micros;
    // Off (active low).
    let mut led = Output::new(p.GPIO8, Level::High, OutputConfig::default());

    let Ok(embedded) = play::parse_clip() else {
        play::blink(&clock, |on| light(&mut led, on));
    };
    let estop_pin = Input::new(p.GPIO9, InputConfig::default().with_pull(Pull::Up));
    let estop = move || estop_pin.is_low();

    let config = UartConfig::default()
        .with_baudrate(show::BAUD)
        .with_rx(RxConfig::default().with_fifo_full_threshold(RX_FIFO_LEVEL));
    let Ok(uart) = Uart::new(p.UART0, config) else {
        error!("UART0 set-up failed");
        play::blink(&clock, |on| light(&mut led, on));
    };
    let mut uart = uart.with_tx(p.GPIO21).with_rx(p.GPIO20);
    uart.set_interrupt_handler(uart0_received);
    critical_section::with(|cs| {
        uart.listen(UartInterrupt::RxFifoFull | UartInterrupt::RxTimeout);
        UART0.borrow_ref_mut(cs).replace(uart);
    });
    info!("UART0: TX GPIO21, RX GPIO20, {=u32} baud", show::BAUD);
    let io = Io { estop, send };

    light(&mut led, true);
    let played = if play::config::OUTPUT_PWM {
        let mut ledc = Ledc::new(p.LEDC);
        ledc.set_global_slow_clock(LSGlobalClkSource::APBClk);
        let mut timer0 = ledc.timer::<LowSpeed>(timer::Number::Timer0);
        let timer_config = timer::config::Config {
            duty: timer::config::Duty::Duty14Bit,
            clock_source: timer::LSClockSource::APBClk,
            frequency: Rate::from_hz(PWM_HZ),
        };
        if timer0.configure(timer_config).is_err() {
            error!("LEDC timer 0 did not take 50 Hz with 14-bit duty");
            play::blink(&clock, |on| light(&mut led, on));
        }
        // Output n on the LEDC's channel n.
        let mut channels = [
            ledc.channel(channel::Number::Channel0, p.GPIO0),
            ledc.channel(channel::Number::Channel1, p.GPIO1),
            ledc.channel(channel::Number::Channel2, p.GPIO3),
            ledc.channel(channel::Number::Channel3, p.GPIO4),
            ledc.channel(channel::Number::Channel4, p.GPIO5),
            ledc.channel(channel::Number::Channel5, p.GPIO6),
        ];
        for channel in &mut channels {
            let config = channel::config::Config {
                timer: &timer0,
                duty_pct: 0,
                drive_mode: DriveMode::PushPull,
            };
            if channel.configure(config).is_err() {
                error!("LEDC channel set-up failed");
                play::blink(&clock, |on| light(&mut led, on));
            }
        }
        let bank: ServoBank<_, PWM_CHANNELS> = ServoBank::new(channels);
        info!(
            "output: PWM on the LEDC, 6 channels at 50 Hz (GPIO0 GPIO1 GPIO3 GPIO4 GPIO5 GPIO6), {=u32} steps of 1.22 us per period",
            1u32 << 14
        );
        play::play(&embedded, &clock, io, |outputs| {
            PwmOutput::new(bank, outputs)
        })
    } else {
        let i2c_config = I2cConfig::default().with_frequency(Rate::from_khz(I2C_KHZ));
        let Ok(i2c) = I2c::new(p.I2C0, i2c_config) else {
            error!("I2C0 set-up failed");
            play::blink(&clock, |on| light(&mut led, on));
        };
        let i2c = i2c.with_sda(p.GPIO4).with_scl(p.GPIO5);
        info!(
            "output: PCA9685 at {=u8:#x} on I2C0 (SDA GPIO4, SCL GPIO5, 400 kHz), 50 Hz",
            play::PCA9685_ADDRESS
        );
        play::play_pca9685(
            &embedded,
            &clock,
            io,
            i2c,
            "SDA GPIO4, SCL GPIO5 (with pull-ups)",
        )
    };
    light(&mut led, false);
    play::finish(played, &clock, |on| light(&mut led, on))
}

/// Writes a reply on UART0 (blocking), a FIFO's worth at a time; a failed write is logged,
/// the show goes on.
fn send(mut bytes: &[u8]) {
    while !bytes.is_empty() {
        let written = critical_section::with(|cs| {
            UART0
                .borrow_ref_mut(cs)
                .as_mut()
                .map(|uart| uart.write(bytes))
        });
        match written {
            Some(Ok(n)) if n > 0 => bytes = bytes.get(n..).unwrap_or(&[]),
            _ => {
                error!("UART0: reply not sent");
                return;
            }
        }
    }
}

/// UART0's receive interrupt (FIFO level or receive timeout): every waiting byte to the show's
/// ring.
#[handler]
fn uart0_received() {
    critical_section::with(|cs| {
        let mut uart = UART0.borrow_ref_mut(cs);
        let Some(uart) = uart.as_mut() else {
            return;
        };
        let mut chunk = [0u8; RX_CHUNK];
        // The 128-byte FIFO in chunks; a reported receive error (overrun, framing) is cleared
        // by the read that reports it, and the next read goes on (the frame receiver drops
        // the damaged frame).
        for _ in 0..8 {
            match uart.read_buffered(&mut chunk) {
                Ok(0) => break,
                Ok(n) => chunk.iter().take(n).for_each(|&b| show::received(b)),
                Err(_) => continue,
            }
        }
        uart.clear_interrupts(UartInterrupt::RxFifoFull | UartInterrupt::RxTimeout);
    });
}

/// The LED (GPIO8, active low).
fn light(led: &mut Output<'_>, on: bool) {
    led.set_level(if on { Level::Low } else { Level::High });
}

/// A panic (the firmware has none it expects) is logged, then the core spins; probe-rs shows
/// the message.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    error!("panic: {}", defmt::Display2Format(info));
    idle()
}
