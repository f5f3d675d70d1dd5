//! The show runner (SPEC.md §9.5): a [`ShowPlayer`] driven by the show's
//! cue lists, triggers and idle clips, emitting the cues' output events.
//! The firmware's show mode and `mocap play` of a show run this code.

use super::cues::{Action, Cues, TriggerKind, MAX_TRIGGERS};
use super::player::{Now, ShowPlayer, State};
use super::Show;
use crate::error::Error;

/// An output event of a cue, at its show time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output<'a> {
    /// Set GPIO `pin` to `level`.
    Gpio {
        /// The pin.
        pin: u8,
        /// High.
        level: bool,
    },
    /// Send these bytes (an MP3 module's command, say).
    Serial(&'a [u8]),
}

/// A command to a running show (`mocap play --cues`, the firmware's UART),
/// applied at a show time by [`ShowRunner::command`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Start cue list `0`.
    List(u16),
    /// Input `0` fired.
    Trigger(u8),
    /// `play(clip)`.
    Play(u16),
    /// `crossfade_to(clip, ms)`.
    Fade {
        /// The clip.
        clip: u16,
        /// Transition, ms.
        ms: u32,
    },
    /// `queue(clip)`.
    Queue(u16),
    /// `set_loop(on)`.
    Loop(bool),
    /// `hold()`.
    Hold,
    /// `resume()`.
    Resume,
    /// `stop()`, and the running cue list stops too.
    Stop,
}

/// The running cue list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Running {
    list: u16,
    start_us: u64,
    next: u16,
}

/// A show with its cues: a [`ShowPlayer`], the running cue list, the
/// triggers' last starts and the random state. `N` and `C` as the player's.
#[derive(Clone, Debug)]
pub struct ShowRunner<'a, const N: usize, const C: usize> {
    player: ShowPlayer<'a, N, C>,
    cues: Option<Cues<'a>>,
    running: Option<Running>,
    fired: [Option<u64>; MAX_TRIGGERS],
    rng: u32,
}

impl<'a, const N: usize, const C: usize> ShowRunner<'a, N, C> {
    /// A runner of `show`, idle.
    pub fn new(show: Show<'a>) -> Result<Self, Error> {
        let cues = show.cues();
        Ok(ShowRunner {
            player: ShowPlayer::new(show)?,
            rng: cues.map_or(1, |c| c.seed),
            cues,
            running: None,
            fired: [None; MAX_TRIGGERS],
        })
    }

    /// The player (to give it commands directly).
    pub fn player(&mut self) -> &mut ShowPlayer<'a, N, C> {
        &mut self.player
    }

    /// The cue section, if the show has one.
    pub fn cues(&self) -> Option<&Cues<'a>> {
        self.cues.as_ref()
    }

    /// The running cue list and its next cue.
    pub fn running(&self) -> Option<(u16, u16)> {
        self.running.map(|r| (r.list, r.next))
    }

    /// Starts cue list `list` at `t_us` (replacing the running one); its
    /// cues at `at_ms = 0` fire at the next [`ShowRunner::tick`].
    pub fn start_list(&mut self, list: u16, t_us: u64) -> Result<(), Error> {
        let count = self.cues.map_or(0, |c| c.list_count());
        if list >= count {
            return Err(Error::ShowClipOutOfRange {
                clip: list,
                clips: count,
            });
        }
        self.running = Some(Running {
            list,
            start_us: t_us,
            next: 0,
        });
        Ok(())
    }

    /// Stops the running cue list (the player plays on).
    pub fn stop_list(&mut self) {
        self.running = None;
    }

    /// Input `input` fired at `t_us`: its trigger starts one of its
    /// targets, chosen at random, unless its cooldown has not passed since
    /// its last start. True if it started one.
    pub fn trigger(&mut self, input: u8, t_us: u64) -> Result<bool, Error> {
        let Some(t) = self.cues.and_then(|c| c.trigger_of(input)) else {
            return Ok(false);
        };
        let slot = usize::from(input);
        if let Some(Some(last)) = self.fired.get(slot) {
            if t_us.saturating_sub(*last) < u64::from(t.cooldown_ms).saturating_mul(1000) {
                return Ok(false);
            }
        }
        let k = self.random(u32::from(t.target_count()));
        let Some(target) = t.target(k as u8) else {
            return Ok(false);
        };
        match t.kind {
            TriggerKind::List => self.start_list(target, t_us)?,
            TriggerKind::Clip => self.player.play(target, t_us)?,
        }
        if let Some(f) = self.fired.get_mut(slot) {
            *f = Some(t_us);
        }
        Ok(true)
    }

    /// Applies `cmd` at show time `at_us`, after the cues due before it.
    /// Clip, list and input numbers out of range are an error (nothing
    /// changes); a trigger in its cooldown does nothing.
    pub fn command(
        &mut self,
        cmd: Command,
        at_us: u64,
        emit: impl FnMut(u64, Output<'a>),
    ) -> Result<(), Error> {
        self.run_cues(at_us, emit)?;
        match cmd {
            Command::List(l) => self.start_list(l, at_us),
            Command::Trigger(i) => self.trigger(i, at_us).map(|_| ()),
            Command::Play(c) => self.player.play(c, at_us),
            Command::Fade { clip, ms } => {
                self.player
                    .crossfade_to(clip, u64::from(ms).saturating_mul(1000), at_us)
            }
            Command::Queue(c) => self.player.queue(c, at_us),
            Command::Loop(on) => self.player.set_loop(on, at_us),
            Command::Hold => self.player.hold(at_us),
            Command::Resume => self.player.resume(at_us),
            Command::Stop => {
                self.running = None;
                self.player.stop(at_us)
            }
        }
    }

    /// True when nothing will move any more on its own: no cue list runs,
    /// nothing is queued and the player is idle, stopped or at the end of a
    /// clip that does not loop.
    pub fn is_done(&self) -> bool {
        self.running.is_none()
            && self.player.queued().is_none()
            && matches!(
                self.player.state(),
                State::Idle | State::Stopped | State::Ended
            )
    }

    /// Fires every cue due by `t_us` (each at its own time; output events go
    /// to `emit` with their time), keeps an idle clip queued behind a clip
    /// that ends, and samples the pose at `t_us` into `out`.
    pub fn tick(
        &mut self,
        t_us: u64,
        out: &mut [i32],
        emit: impl FnMut(u64, Output<'a>),
    ) -> Result<Now, Error> {
        self.run_cues(t_us, emit)?;
        self.keep_idle_queued(t_us)?;
        self.player.sample(t_us, out)
    }

    /// Fires the cues of the running list due by `t_us`.
    fn run_cues(&mut self, t_us: u64, mut emit: impl FnMut(u64, Output<'a>)) -> Result<(), Error> {
        while let Some(r) = self.running {
            let Some(list) = self.cues.and_then(|c| c.list(r.list)) else {
                self.running = None;
                break;
            };
            let Some(cue) = list.cue(r.next) else {
                self.running = None;
                break;
            };
            let at = r
                .start_us
                .saturating_add(u64::from(cue.at_ms).saturating_mul(1000));
            if at > t_us {
                break;
            }
            self.running = Some(Running {
                next: r.next.wrapping_add(1),
                ..r
            });
            match cue.action {
                Action::Play(c) => self.player.play(c, at)?,
                Action::Fade { clip, ms } => {
                    self.player
                        .crossfade_to(clip, u64::from(ms).saturating_mul(1000), at)?
                }
                Action::Queue(c) => self.player.queue(c, at)?,
                Action::Stop => self.player.stop(at)?,
                Action::Hold => self.player.hold(at)?,
                Action::Resume => self.player.resume(at)?,
                Action::Loop(on) => self.player.set_loop(on, at)?,
                Action::Gpio { pin, level } => emit(at, Output::Gpio { pin, level }),
                Action::Serial(bytes) => emit(at, Output::Serial(bytes)),
            }
        }
        Ok(())
    }

    /// A clip that will end with nothing after it gets a random idle clip
    /// queued behind it (§9.5).
    fn keep_idle_queued(&mut self, t_us: u64) -> Result<(), Error> {
        let Some(c) = self.cues else { return Ok(()) };
        let idle = c.idle_count();
        if idle == 0
            || self.player.queued().is_some()
            || !matches!(
                self.player.state(),
                State::Playing | State::Blending | State::Ended
            )
            || self.player.loops()
        {
            return Ok(());
        }
        let k = self.random(u32::from(idle));
        match c.idle(k as u16) {
            Some(clip) => self.player.queue(clip, t_us),
            None => Ok(()),
        }
    }

    /// xorshift32, then `mod n` (n ≥ 1).
    fn random(&mut self, n: u32) -> u32 {
        let mut x = self.rng.max(1);
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        x.checked_rem(n).unwrap_or(0)
    }
}
