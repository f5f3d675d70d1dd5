//! `no_std`, allocation-free decoder for `.mcb` motion clips (SPEC.md).
//!
//! ```text
//! let clip = Clip::parse(bytes)?;            // zero copy, validates everything
//! let mut player = Player::<96>::new(&clip)?; // fixed-size state, no allocation
//! player.next_frame(&mut out)?;              // sequential
//! player.frame(120, &mut out)?;              // random access
//! player.sample_at(20_000, &mut out)?;       // any time t (µs), interpolated
//! ```
//!
//! Every value is an `i32` in the fixed-point unit of its channel
//! ([`Unit`]): identical bits on every platform.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// The lints of Cargo.toml `[lints]` (no indexing, unwrap, expect, panic or
// implicit overflow) hold for the library; tests may do all of these.
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

#[cfg(test)]
extern crate std;

#[cfg(any(feature = "codec-index", feature = "codec-pca-spline"))]
mod bits;
mod clip;
mod codec;
pub mod consts;
/// The static rANS coder of SPEC.md §10, shared by the codecs that need
/// one; public for the encoder and the workspace tests (outside semver).
#[cfg(feature = "entropy")]
#[doc(hidden)]
pub mod entropy;
mod error;
mod frame_time;
mod header;
mod missing;
mod player;
/// Power-aware sampling (SPEC.md §6.1): a cheaper level at run time, no jump.
pub mod power;
mod reader;
mod rig;
pub mod show;
#[doc(hidden)]
pub mod wire;

pub use clip::{Clip, Section, Sections};
pub use error::Error;
pub use header::{Channel, ChannelIter, ChannelKind, Header, Joint, JointIter, Unit};
pub use missing::{Missing, MissingRuns};
pub use player::Player;
pub use rig::{rig_digest, tick_count, tick_us, DigestServo, Rig, RigServo, DIGEST_SERVO_LEN};
pub use show::clock::ShowClock;
pub use show::player::{Now, ShowPlayer, State};
pub use show::runner::{Command, Output, ShowRunner};
pub use show::{Loop, Show, ShowClip};

/// The fixed-point key-frame spline of the `pca-spline` codec (SPEC.md
/// §5.4), public so the encoder fits exactly what the decoder evaluates.
#[cfg(feature = "codec-pca-spline")]
pub mod spline {
    pub use crate::codec::spline::{apply, weights};
}

/// The words of the `pca-spline` player's cache of key intervals (the
/// player's state, SPEC.md §6): a head, then a slot per group while they fit
/// (`GROUP_HEAD + n` words for `k = 0`, `GROUP_HEAD + INTERVAL + 4k` else),
/// then the constants; groups without a slot are decoded from their record
/// on every pose. Public so the encoder can size a player for a clip.
#[cfg(feature = "codec-pca-spline")]
pub mod pca_spline_cache {
    pub use crate::codec::pca_spline::cache::{CACHE_HEAD, GROUP_HEAD, INTERVAL};
}

/// The position, curve weights and values of the `pattern` codec (SPEC.md §11.4),
/// public so the encoder checks its patterns against exactly what the
/// decoder plays.
#[cfg(feature = "codec-pattern")]
pub mod pattern {
    pub use crate::codec::pattern::{
        coded_extent, for_each_coded_segment, interpolate, position, taps, weights, window,
        FLAG_CODED, FLAG_SHARED, HEAD_WIDE_BASE, LAYOUT_COLUMNS, LAYOUT_PACKED, LAYOUT_ROWS,
        MAX_BLOCK_BITS, MAX_NODES, MAX_SEGMENT, PACKED_TAIL, WIDE_BASE_2,
    };
}

/// The constants of the `rma` codec's section (SPEC.md §12), public so the
/// encoder writes what the decoder reads.
#[cfg(feature = "codec-rma")]
pub mod rma {
    pub use crate::codec::rma::{CURSOR_WORDS, FORM, MAX_FRAMES, MAX_KNOT_GAP, REF_FRAC_BITS};
}

/// The prediction and reconstruction of the `predictive` codec (SPEC.md
/// §5b), public so the encoder quantises against exactly what the decoder
/// computes.
#[cfg(feature = "codec-predictive")]
pub mod predictive {
    pub use crate::codec::predictive::{predict, value};
}
