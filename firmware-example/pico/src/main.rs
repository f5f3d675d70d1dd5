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
//! - A show (`mocap show build`, SPEC.md §9) runs the QEMU firmware's show mode (`../hw/show.rs`
//!   with `../src/show_core.rs`): commands as `Show` frames on UART0 (`mocap send show.mcb
//!   --cues cues.txt --port …`, SPEC.md §8.2, 115 200 baud 8N1), every tick through the figure.
//! - Any other clip (the default `clips/demo.mcb` is a skeleton clip) is played frame by frame
//!   at its own frame rate with `Player::next_frame`, its frames logged once a second; the
//!   servos are held at the figure's neutral.
//!
//! The output (`MOCAP_SERVO`): a PCA9685 on I²C0 (SDA GP16, SCL GP17, address 0x40, 400 kHz;
//! default) or the RP2040's own PWM on GP0–GP15 (output n on GPn, 50 Hz). UART0 is on GP0 (TX)
//! and GP1 (RX) with the PCA9685, on GP16 (TX) and GP17 (RX) with PWM (GP0–GP15 are servos
//! then, and I²C0 is unused). The e-stop is GP22 (pulled up; a button to GND parks every servo
//! and ends the run). The LED (GP25) is on while the clip plays and blinks fast after an error.
//! See README.md for wiring and flashing.
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

use core::convert::Infallible;

use defmt::{error, info};
use defmt_rtt as _;
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use mocap_servo::output::PwmOutput;
use mocap_servo::ServoBank;
use panic_probe as _;
use rp2040_hal as hal;

use hal::clocks::init_clocks_and_plls;
use hal::fugit::{HertzU32, RateExtU32};
use hal::gpio::{bank0::Gpio25, FunctionI2C, FunctionSioOutput, FunctionUart, Pin, PullDown};
use hal::gpio::{PullNone, PullUp};
use hal::pac::interrupt;
use hal::uart::{DataBits, StopBits, UartConfig, UartPeripheral, ValidUartPinout};
use hal::{pac, pwm, Clock as _};

use play::{idle, Io};

/// The second-stage bootloader for the Pico's W25Q080 flash: the boot ROM runs these first 256
/// bytes of flash (`.boot2`, memory.x), which set up execute-in-place for the rest.
#[link_section = ".boot2"]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// The Pico's crystal.
const XOSC_HZ: u32 = 12_000_000;
/// The PCA9685's I²C bus clock.
const I2C_HZ: u32 = 400_000;
/// PWM: 16 channels (8 slices × A/B) on GP0–GP15; 125 MHz / 100 = 1.25 MHz counts, TOP 24 999:
/// a 20 ms period (50 Hz) in steps of 0.8 µs.
const PWM_CHANNELS: usize = 16;
const PWM_DIV: u8 = 100;
const PWM_TOP: u16 = 24_999;

type Led = Pin<Gpio25, FunctionSioOutput, PullDown>;
type PwmChannel<'a> = &'a mut dyn SetDutyCycle<Error = Infallible>;
type Uart<P> = UartPeripheral<hal::uart::Enabled, pac::UART0, P>;

#[hal::entry]
fn main() -> ! {
    info!(
        "mocap-firmware-pico: clip {=usize} bytes, figure {=str}",
        play::CLIP.len(),
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

    let Ok(embedded) = play::parse_clip() else {
        play::blink(&timer, |on| light(&mut led, on));
    };
    let mut estop_pin = pins.gpio22.into_pull_up_input();
    let estop = move || estop_pin.is_low().unwrap_or(false);
    let uart_hz = clocks.peripheral_clock.freq();

    let _ = led.set_high();
    let played = if play::config::OUTPUT_PWM {
        let uart_pins: (
            Pin<_, FunctionUart, PullNone>,
            Pin<_, FunctionUart, PullNone>,
        ) = (pins.gpio16.reconfigure(), pins.gpio17.reconfigure());
        let Some(uart) = serial(pac.UART0, uart_pins, &mut pac.RESETS, uart_hz) else {
            play::blink(&timer, |on| light(&mut led, on));
        };
        info!("UART0: TX GP16, RX GP17, {=u32} baud", show::BAUD);
        let send = |bytes: &[u8]| uart.write_full_blocking(bytes);
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
        let io = Io { estop, send };
        play::play(&embedded, &timer, io, |outputs| {
            PwmOutput::new(bank, outputs)
        })
    } else {
        let uart_pins: (
            Pin<_, FunctionUart, PullNone>,
            Pin<_, FunctionUart, PullNone>,
        ) = (pins.gpio0.reconfigure(), pins.gpio1.reconfigure());
        let Some(uart) = serial(pac.UART0, uart_pins, &mut pac.RESETS, uart_hz) else {
            play::blink(&timer, |on| light(&mut led, on));
        };
        info!("UART0: TX GP0, RX GP1, {=u32} baud", show::BAUD);
        let io = Io {
            estop,
            send: |bytes: &[u8]| uart.write_full_blocking(bytes),
        };
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
            play::PCA9685_ADDRESS
        );
        play::play_pca9685(&embedded, &timer, io, i2c, "SDA GP16, SCL GP17")
    };
    let _ = led.set_low();
    play::finish(played, &timer, |on| light(&mut led, on))
}

/// UART0 on `pins` at [`show::BAUD`] 8N1, its receive interrupt on (each byte to
/// `show::received`, [`UART0_IRQ`]).
fn serial<P: ValidUartPinout<pac::UART0>>(
    uart0: pac::UART0,
    pins: P,
    resets: &mut pac::RESETS,
    peripheral_hz: HertzU32,
) -> Option<Uart<P>> {
    let config = UartConfig::new(show::BAUD.Hz(), DataBits::Eight, None, StopBits::One);
    let Ok(mut uart) = UartPeripheral::new(uart0, pins, resets).enable(config, peripheral_hz)
    else {
        error!("UART0 set-up failed");
        return None;
    };
    uart.enable_rx_interrupt();
    // SAFETY: the handler (UART0_IRQ) only drains UART0's receive FIFO into the show's ring,
    // which it shares through a critical section; unmasking breaks no critical section.
    unsafe { pac::NVIC::unmask(pac::Interrupt::UART0_IRQ) };
    Some(uart)
}

/// UART0's receive interrupt (FIFO level or receive timeout): every waiting byte to the show's
/// ring.
#[interrupt]
fn UART0_IRQ() {
    // SAFETY: reads only UART0's flag and data registers; the main code owns the peripheral
    // but only writes the data register (transmit) and never reads it.
    let uart = unsafe { &*pac::UART0::ptr() };
    while uart.uartfr().read().rxfe().bit_is_clear() {
        show::received(uart.uartdr().read().data().bits());
    }
}

/// A PWM slice at 50 Hz for servos ([`PWM_DIV`], [`PWM_TOP`]).
fn servo_slice<I: pwm::SliceId>(slice: &mut pwm::Slice<I, pwm::FreeRunning>) {
    slice.set_div_int(PWM_DIV);
    slice.set_div_frac(0);
    slice.set_top(PWM_TOP);
    slice.enable();
}

/// The RP2040's timer: a 64-bit µs counter.
impl play::Clock for hal::Timer {
    fn now_us(&self) -> u64 {
        self.get_counter().ticks()
    }
}

/// The LED (GP25, active high).
fn light(led: &mut Led, on: bool) {
    let _ = if on { led.set_high() } else { led.set_low() };
}
