//! The figure this firmware drives, compiled in from its rig file by build.rs
//! (`build_common::figure`: `MOCAP_FIGURE`, `MOCAP_POLICY`), and how a clip's rig is held to it.
//!
//! Shared source: the QEMU firmware (`src/servo.rs` prints and drives with it) and the board
//! firmwares (`pico/src/main.rs`, through `#[path]`) include this one file, so every firmware
//! applies the figure's hard limits the same way — the way `mocap play --rig` does.

use mocap_decoder::Clip;
use mocap_servo::{FigureId, Fit, HardLimits, Identity, Playback, PlaybackError};

/// `FIGURE_NAME`, `FIGURE_RATE_MHZ`, `FIGURE_SERVOS` (the rig table of a clip made for the
/// figure), `HARD_LIMITS` (per output: pulse range, neutral, speed, acceleration),
/// `FIGURE_DIGEST` and `POLICY` (what to do with a clip made for another rig).
pub mod table {
    use mocap_decoder::RigServo;
    use mocap_servo::{HardLimit, Policy};
    include!(concat!(env!("OUT_DIR"), "/figure.rs"));
}
pub use table::{FIGURE_DIGEST, FIGURE_NAME, FIGURE_RATE_MHZ, FIGURE_SERVOS, HARD_LIMITS, POLICY};

/// Most servos of a rig in this firmware (as many as a streamed `Pose` carries).
pub const MAX_SERVOS: usize = mocap_servo::stream::MAX_POSE_SERVOS;
/// The servos of a rig (its `RigServo`s, rate and limits) and the limiter that holds every
/// pulse to their limits.
pub type Rig = Playback<MAX_SERVOS>;

const _: () = assert!(
    FIGURE_SERVOS.len() <= MAX_SERVOS,
    "the figure (MOCAP_FIGURE) has more servos than the firmware holds (MAX_SERVOS)"
);

/// The figure's hard limits: every command of every mode passes them, after the clip's own
/// limits (`Playback::with_hard_limits`).
pub const FIGURE: HardLimits<'static> = HardLimits::new(&HARD_LIMITS);

/// The figure's identity: a clip made for it carries its rig table and its rig digest.
pub const FIGURE_ID: FigureId<'static> = FigureId {
    rate_mhz: FIGURE_RATE_MHZ,
    servos: &FIGURE_SERVOS,
    digest: FIGURE_DIGEST,
};

/// Why a clip's rig cannot even be compared with the figure.
pub enum Refusal {
    /// The clip has no rig table (not a servo clip).
    NoRigTable,
    /// Its rig table does not make a playback (limits, too many servos).
    Playback(PlaybackError),
}

/// A servo clip's rig with its own limits, compared with the figure, before the figure's hard
/// limits: [`harden`](Self::harden) applies them as [`POLICY`] says.
pub struct Candidate {
    pub rig: Rig,
    /// Whether the clip was made for the figure (`identity=` of the status line).
    pub identity: Identity,
    /// Whether the clip's servos lie inside the figure's limits (`fit=`).
    pub fit: Fit,
}

/// The first step of playing `clip` on this figure: its rig table, compared.
pub fn candidate(clip: &Clip<'_>) -> Result<Candidate, Refusal> {
    let table = clip.rig().ok_or(Refusal::NoRigTable)?;
    let identity = FIGURE_ID.compare(clip);
    let rig = Rig::from_rig(table).map_err(Refusal::Playback)?;
    let fit = FIGURE.fit(rig.servos());
    Ok(Candidate { rig, identity, fit })
}

impl Candidate {
    /// The playback of the clip on this figure: its own limits, then the figure's hard limits.
    /// A clip made for another rig plays only as [`POLICY`] allows (else the error says why).
    pub fn harden(self) -> Result<Rig, PlaybackError> {
        self.rig
            .with_hard_limits(&FIGURE, self.identity.is_same(), POLICY)
            .map(|(rig, _)| rig)
    }
}

/// The figure's own playback (its servos at its rate, through its hard limits) and how its
/// servos fit its hard limits.
pub fn figure_rig() -> Result<(Rig, Fit), PlaybackError> {
    Rig::new(FIGURE_SERVOS.iter().copied(), FIGURE_RATE_MHZ)?
        .with_hard_limits(&FIGURE, true, POLICY)
}
