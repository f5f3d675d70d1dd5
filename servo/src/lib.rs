//! Servo outputs and serial streaming for mocap clips, shared by the firmware
//! and the host CLI (`mocap play`, `mocap send`). `no_std`, no allocation,
//! no panics.
//!
//! # Units
//!
//! Every pulse width is a `u16` in **quarter microseconds** (0.25 µs), the
//! Pololu Maestro's native unit: 1500 µs is `6000`, and `u16` reaches
//! 16 383.75 µs, far beyond any servo. Each output converts from it:
//! PWM duty cycles ([`bank`]), PCA9685 counts of 4.88 µs (`pca9685`),
//! Maestro targets as they are ([`maestro`]), SSC-32 whole µs ([`ssc32`]).
//!
//! # Flow
//!
//! ```text
//! decoded frame / streamed Pose ──► Playback::tick ──► ServoOutput::write
//!                              (Limiter::apply: clamp, speed;
//!                               then HardStage::apply: the figure's
//!                               own range, speed, acceleration)
//!                                                      ├► PwmOutput     → ServoBank::write     (PWM)
//!                                                      ├► Pca9685Output → Pca9685Servos::write (I²C)
//!                                                      ├► MaestroOutput → maestro::set_target  (UART)
//!                                                      └► Ssc32Output   → ssc32::group_move    (UART)
//! ```
//!
//! Every output should take its pulses from a [`Limiter`]: it is what
//! guarantees that no pulse outside a servo's limits is ever commanded.
//! [`output`] puts the four outputs behind one trait, so one playback loop,
//! [`playback`] (rig servos, limits, tick clock, return to neutral), drives
//! any of them for `mocap play` and the firmware alike; [`record`] has devices that record instead of
//! driving hardware (QEMU, host checks).
//!
//! # Features
//!
//! - `std`: `std::error::Error` for the errors.
//! - `defmt`: `defmt::Format` for the errors and limits.
//! - `pca9685`: the PCA9685 output (`pwm-pca9685` driver).
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// The panic-free lints are denied in Cargo.toml; tests may unwrap, index and
// do plain arithmetic.
#![cfg_attr(
    test,
    allow(
        clippy::indexing_slicing,
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::arithmetic_side_effects
    )
)]

#[cfg(feature = "std")]
extern crate std;

pub mod bank;
mod error;
pub mod hard;
pub mod limits;
pub mod maestro;
pub mod output;
#[cfg(feature = "pca9685")]
pub mod pca9685;
pub mod playback;
pub mod record;
pub mod ssc32;
pub mod stream;
#[cfg(test)]
mod test_rng;

pub use bank::ServoBank;
pub use error::{Error, OutputError};
pub use hard::{FigureId, Fit, HardLimit, HardLimits, HardStage, HardStep, Identity, Policy};
pub use limits::{Limiter, ServoLimits};
pub use output::ServoOutput;
#[cfg(feature = "pca9685")]
pub use pca9685::Pca9685Servos;
pub use playback::{Playback, PlaybackError};
pub use stream::{decode_frame, encode_frame, FrameReceiver, Message};
