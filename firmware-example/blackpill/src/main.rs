//! mocap-firmware-blackpill: the STM32F411 "Black Pill" (WeAct, STM32F411CEU6) firmware. It plays
//! the `.mcb` clip embedded in flash on the figure compiled in, paced by TIM5 counting µs, and
//! logs with defmt over RTT. The playback is the one every real board shares
//! (`../hw/play.rs`, with the QEMU firmware's `../src/figure.rs`); this file sets up the board.
//!
//! A show (`mocap show build`) runs the show mode every board shares (`../hw/show.rs`, with the
//! QEMU firmware's loop `../src/show_core.rs`): commands as `Show` frames on USART2 (TX PA2,
//! RX PA3, 115 200 baud 8N1; SPEC.md §8.2, `mocap send show.mcb --cues cues.txt --port …`).
//! USART2, not USART1: USART1's PA9/PA10 are PWM outputs 1 and 2 (TIM1); PA2/PA3 are free with
//! either output. The e-stop is PB12 (pulled up; a button to GND parks every servo and ends the
//! run).
//!
//! The output (`MOCAP_SERVO`): a PCA9685 on I²C1 (SCL PB6, SDA PB7, address 0x40, 400 kHz;
//! default) or 12 PWM servos at 50 Hz: outputs 0–3 on TIM1 (PA8, PA9, PA10, PA11), 4–7 on TIM3
//! (PA6, PA7, PB0, PB1), 8–11 on TIM4 (PB6, PB7, PB8, PB9). The LED (PC13, active low) is on while
//! the clip plays and blinks fast after an error. See README.md for flashing.
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

use core::cell::Cell;
use core::convert::Infallible;

use cortex_m_rt::entry;
use defmt::{error, info};
use defmt_rtt as _;
use embedded_hal::pwm::SetDutyCycle;
use embedded_io::Write as _;
use mocap_servo::output::PwmOutput;
use mocap_servo::ServoBank;
use panic_probe as _;
use stm32f4xx_hal::gpio::{Output, Pin, PushPull};
use stm32f4xx_hal::i2c::I2c;
use stm32f4xx_hal::pac::interrupt;
use stm32f4xx_hal::serial::{self, Serial};
use stm32f4xx_hal::timer::CounterUs;
use stm32f4xx_hal::{pac, prelude::*, rcc::Config};

use play::{idle, Io};

/// The Black Pill's crystal, and the core clock it runs at.
const HSE_MHZ: u32 = 25;
const SYSCLK_MHZ: u32 = 100;
/// The PCA9685's I²C bus clock.
const I2C_KHZ: u32 = 400;
/// PWM: 12 channels (TIM1, TIM3, TIM4, four each) at 50 Hz.
const PWM_CHANNELS: usize = 12;

type Led = Pin<'C', 13, Output<PushPull>>;
type PwmChannel<'a> = &'a mut dyn SetDutyCycle<Error = Infallible>;

/// TIM5, a 32-bit timer counting µs, extended to 64 bits on each read (reads come far more often
/// than its 71-minute wrap).
struct Micros {
    counter: CounterUs<pac::TIM5>,
    last: Cell<u32>,
    high: Cell<u64>,
}

/// TIM5 counts 0 ..= u32::MAX - 1 (its auto-reload is the period's ticks minus one).
const TIM5_WRAP: u64 = u32::MAX as u64;

impl play::Clock for Micros {
    fn now_us(&self) -> u64 {
        let now = self.counter.now().ticks();
        if now < self.last.get() {
            self.high.set(self.high.get().saturating_add(TIM5_WRAP));
        }
        self.last.set(now);
        self.high.get().saturating_add(u64::from(now))
    }
}

#[entry]
fn main() -> ! {
    info!(
        "mocap-firmware-blackpill: clip {=usize} bytes, figure {=str}",
        play::CLIP.len(),
        figure::FIGURE_NAME
    );
    let Some(dp) = pac::Peripherals::take() else {
        error!("peripherals already taken");
        idle();
    };
    let mut rcc = dp
        .RCC
        .freeze(Config::hse(HSE_MHZ.MHz()).sysclk(SYSCLK_MHZ.MHz()));
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let gpioc = dp.GPIOC.split(&mut rcc);
    let mut led: Led = gpioc.pc13.into_push_pull_output();
    led.set_high(); // off (active low)

    let mut counter = dp.TIM5.counter_us(&mut rcc);
    if counter.start(u32::MAX.micros()).is_err() {
        error!("TIM5 did not start");
        idle();
    }
    let clock = Micros {
        counter,
        last: Cell::new(0),
        high: Cell::new(0),
    };

    let Ok(embedded) = play::parse_clip() else {
        play::blink(&clock, |on| light(&mut led, on));
    };
    let estop_pin = gpiob.pb12.into_pull_up_input();
    let estop = move || estop_pin.is_low();
    let config = serial::config::Config::default().baudrate(show::BAUD.bps());
    let Ok(mut uart) = dp
        .USART2
        .serial::<u8>((gpioa.pa2, gpioa.pa3), config, &mut rcc)
    else {
        error!("USART2 set-up failed");
        play::blink(&clock, |on| light(&mut led, on));
    };
    uart.listen(serial::Event::RxNotEmpty);
    // SAFETY: the handler (USART2) only drains USART2's receive register into the show's ring,
    // which it shares through a critical section; unmasking breaks no critical section.
    unsafe { pac::NVIC::unmask(pac::Interrupt::USART2) };
    info!("USART2: TX PA2, RX PA3, {=u32} baud", show::BAUD);
    let io = Io {
        estop,
        send: |bytes: &[u8]| send(&mut uart, bytes),
    };

    led.set_low(); // on
    let played = if play::config::OUTPUT_PWM {
        let (_, (t1c1, t1c2, t1c3, t1c4)) = dp.TIM1.pwm_hz(50.Hz(), &mut rcc);
        let (_, (t3c1, t3c2, t3c3, t3c4)) = dp.TIM3.pwm_hz(50.Hz(), &mut rcc);
        let (_, (t4c1, t4c2, t4c3, t4c4)) = dp.TIM4.pwm_hz(50.Hz(), &mut rcc);
        let mut t1c1 = t1c1.with(gpioa.pa8);
        let mut t1c2 = t1c2.with(gpioa.pa9);
        let mut t1c3 = t1c3.with(gpioa.pa10);
        let mut t1c4 = t1c4.with(gpioa.pa11);
        let mut t3c1 = t3c1.with(gpioa.pa6);
        let mut t3c2 = t3c2.with(gpioa.pa7);
        let mut t3c3 = t3c3.with(gpiob.pb0);
        let mut t3c4 = t3c4.with(gpiob.pb1);
        let mut t4c1 = t4c1.with(gpiob.pb6);
        let mut t4c2 = t4c2.with(gpiob.pb7);
        let mut t4c3 = t4c3.with(gpiob.pb8);
        let mut t4c4 = t4c4.with(gpiob.pb9);
        t1c1.enable();
        t1c2.enable();
        t1c3.enable();
        t1c4.enable();
        t3c1.enable();
        t3c2.enable();
        t3c3.enable();
        t3c4.enable();
        t4c1.enable();
        t4c2.enable();
        t4c3.enable();
        t4c4.enable();
        let channels: [PwmChannel; PWM_CHANNELS] = [
            &mut t1c1, &mut t1c2, &mut t1c3, &mut t1c4, &mut t3c1, &mut t3c2, &mut t3c3, &mut t3c4,
            &mut t4c1, &mut t4c2, &mut t4c3, &mut t4c4,
        ];
        let bank = ServoBank::new(channels);
        info!(
            "output: PWM, 12 channels at 50 Hz (TIM1 PA8-PA11, TIM3 PA6 PA7 PB0 PB1, TIM4 PB6-PB9)"
        );
        play::play(&embedded, &clock, io, |outputs| {
            PwmOutput::new(bank, outputs)
        })
    } else {
        let i2c = I2c::new(dp.I2C1, (gpiob.pb6, gpiob.pb7), I2C_KHZ.kHz(), &mut rcc);
        info!(
            "output: PCA9685 at {=u8:#x} on I2C1 (SCL PB6, SDA PB7, 400 kHz), 50 Hz",
            play::PCA9685_ADDRESS
        );
        play::play_pca9685(
            &embedded,
            &clock,
            io,
            i2c,
            "SCL PB6, SDA PB7 (with pull-ups)",
        )
    };
    led.set_high(); // off
    play::finish(played, &clock, |on| light(&mut led, on))
}

/// Writes a reply on USART2 (blocking; a failed write is logged, the show goes on).
fn send(uart: &mut Serial<pac::USART2>, bytes: &[u8]) {
    if uart.write_all(bytes).is_err() {
        error!("USART2: reply not sent");
    }
}

/// USART2's receive interrupt: the received byte to the show's ring.
#[interrupt]
fn USART2() {
    // SAFETY: reads only USART2's status and data registers (reading both clears the receive
    // flag and an overrun); the main code owns the peripheral but only transmits.
    let usart = unsafe { &*pac::USART2::ptr() };
    while usart.sr().read().rxne().bit_is_set() {
        show::received(usart.dr().read().dr().bits() as u8);
    }
}

/// The LED (PC13, active low).
fn light(led: &mut Led, on: bool) {
    if on {
        led.set_low();
    } else {
        led.set_high();
    }
}
