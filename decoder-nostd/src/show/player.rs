//! The show player (SPEC.md §9.4): two clip players and a frozen pose,
//! blended in integer arithmetic, driven by show time so that the servo
//! rate is free.
//!
//! ```text
//! play(c) / crossfade_to(c, d) / queue(c) / set_loop / hold / resume / stop
//!                 │
//!   slot 0 ─┐     ▼
//!           ├─ blend (smoothstep, angle-wrap aware) ─► sample(t, out)
//!   slot 1 ─┘  or the from-pose: the pose and velocity at the moment a
//!              transition interrupted another, eased to rest
//! ```
//!
//! Every value it returns is a function of the commands and their times
//! only — not of when or how often it was sampled — so the host and the
//! MCU give the same bits whatever their tick rates.

use super::{Loop, Show};
use crate::error::Error;
use crate::player::Player;

/// `play`'s transition when the show has no cue section, ms.
pub const DEFAULT_FADE_MS: u32 = 500;
/// Longest transition, µs (10 minutes): keeps the fixed-point products in
/// 64 bits.
pub const MAX_FADE_US: u64 = 600_000_000;
/// The time step over which the from-pose's velocity is measured, µs.
pub const VELOCITY_STEP_US: u64 = 10_000;
/// [`VELOCITY_STEP_US`] as the divisor of the from-pose's displacement.
const STEP_I64: i64 = VELOCITY_STEP_US as i64;
/// Most transitions one [`ShowPlayer::sample`] call carries out (a later
/// one waits for the next call).
pub const MAX_EVENTS_PER_SAMPLE: usize = 16;

/// Where the player is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// Nothing played yet.
    Idle,
    /// A clip plays.
    Playing,
    /// A transition runs.
    Blending,
    /// Time stands still (`hold`).
    Held,
    /// `stop`: the pose of that moment, held.
    Stopped,
    /// A clip that does not loop is past its last frame, nothing queued.
    Ended,
}

/// What [`ShowPlayer::sample`] played.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Now {
    /// The player's state.
    pub state: State,
    /// The clip that plays (the incoming one of a transition).
    pub clip: Option<u16>,
    /// Its local time, µs.
    pub local_us: u64,
    /// The transition's weight of the incoming clip, 0..=65536 (65536
    /// outside a transition).
    pub weight: u32,
}

/// One running clip.
#[derive(Clone, Debug)]
struct Slot<'a, const N: usize> {
    player: Player<'a, N>,
    clip: u16,
    /// Show time of the clip's local time 0, µs.
    origin_us: u64,
    looping: Option<Loop>,
    frames: u32,
}

/// Where a transition comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum From {
    /// A clip that keeps playing.
    Slot(usize),
    /// The frozen pose `snap` and velocity `snap_d` (per
    /// [`VELOCITY_STEP_US`]) at `start_us`, eased to rest.
    Pose,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Blend {
    from: From,
    to: usize,
    start_us: u64,
    dur_us: u64,
}

/// Plays a show: at most two clips at once, each with `N` words of player
/// state ([`Player`]), over at most `C` channels. State: two `Player<N>`,
/// three `C`-word pose buffers and a few words (`size_of` is printed by
/// the firmware's show mode; BENCHMARKS.md).
#[derive(Clone, Debug)]
pub struct ShowPlayer<'a, const N: usize, const C: usize> {
    show: Show<'a>,
    channels: usize,
    frame_ns: u32,
    /// Rotation channels of a motion show blend the short way round.
    wrap: [bool; C],
    slots: [Option<Slot<'a, N>>; 2],
    /// The playing slot outside a transition.
    current: usize,
    blend: Option<Blend>,
    queued: Option<u16>,
    state: State,
    /// Show time at which `hold` froze time.
    held_at: u64,
    default_fade_us: u64,
    snap: [i32; C],
    snap_d: [i32; C],
    scratch: [i32; C],
}

impl<'a, const N: usize, const C: usize> ShowPlayer<'a, N, C> {
    /// A player of `show`, idle. Fails if a clip does not fit `N` words of
    /// player state or the show has more than `C` channels.
    pub fn new(show: Show<'a>) -> Result<Self, Error> {
        let header = show.header();
        let channels = header.channel_count();
        if channels > C {
            return Err(Error::PlayerCapacity {
                channels,
                capacity: C,
            });
        }
        for i in 0..show.clip_count() {
            Player::<N>::new(&show.clip(i)?)?;
        }
        let mut wrap = [false; C];
        if show.rig().is_none() {
            for (w, ch) in wrap.iter_mut().zip(header.channels()) {
                *w = ch.kind.is_rotation();
            }
        }
        let fade_ms = show.cues().map_or(DEFAULT_FADE_MS, |c| c.default_fade_ms);
        Ok(ShowPlayer {
            show,
            channels,
            frame_ns: header.frame_time_ns(),
            wrap,
            slots: [None, None],
            current: 0,
            blend: None,
            queued: None,
            state: State::Idle,
            held_at: 0,
            default_fade_us: fade_us(fade_ms),
            snap: [0; C],
            snap_d: [0; C],
            scratch: [0; C],
        })
    }

    /// The show.
    pub fn show(&self) -> &Show<'a> {
        &self.show
    }

    /// Channels of every pose.
    pub fn channel_count(&self) -> usize {
        self.channels
    }

    /// The transition of [`ShowPlayer::play`] and of queued clips, µs.
    pub fn default_fade_us(&self) -> u64 {
        self.default_fade_us
    }

    /// The state after the last call.
    pub fn state(&self) -> State {
        self.state
    }

    /// The clip waiting in the queue.
    pub fn queued(&self) -> Option<u16> {
        self.queued
    }

    /// True when the playing clip loops.
    pub fn loops(&self) -> bool {
        let playing = self.blend.map_or(self.current, |b| b.to);
        self.slot(playing).is_some_and(|s| s.looping.is_some())
    }

    /// `clip` after the default transition, from whatever pose the player is
    /// in; the first clip starts at once.
    pub fn play(&mut self, clip: u16, t_us: u64) -> Result<(), Error> {
        self.crossfade_to(clip, self.default_fade_us, t_us)
    }

    /// `clip` from its start at `t_us`, blended in over `dur_us` from
    /// whatever the player is doing: a playing clip keeps playing under the
    /// blend; a transition in progress (or a held or stopped pose) is frozen
    /// with its velocity, which eases to rest under the blend (§9.4).
    pub fn crossfade_to(&mut self, clip: u16, dur_us: u64, t_us: u64) -> Result<(), Error> {
        let t = self.prepare(t_us)?;
        self.transition(clip, 0, dur_us.min(MAX_FADE_US), t)
    }

    /// Plays `clip` when the current one ends: its transition (the default
    /// one) ends at the current clip's last frame, or at the end of the
    /// current pass of a looping clip, instead of the seam. One clip waits
    /// at most; a second `queue` replaces it. With nothing playing it plays
    /// at once.
    pub fn queue(&mut self, clip: u16, t_us: u64) -> Result<(), Error> {
        self.show.entry(clip)?;
        if matches!(self.state, State::Idle | State::Stopped | State::Ended) {
            return self.play(clip, t_us);
        }
        self.queued = Some(clip);
        Ok(())
    }

    /// Turns looping of the playing clip on (at its loop points, or over the
    /// whole clip with a seam of the default transition, at most a third of
    /// the clip) or off (it plays to its end).
    pub fn set_loop(&mut self, on: bool, t_us: u64) -> Result<(), Error> {
        self.prepare(t_us)?;
        let at = self.blend.map_or(self.current, |b| b.to);
        let fade_frames = self.frames_in(self.default_fade_us);
        let Some(slot) = self.slots.get_mut(at).and_then(Option::as_mut) else {
            return Ok(());
        };
        slot.looping = if !on {
            None
        } else if let Some(l) = self.show.entry(slot.clip)?.looping {
            Some(l)
        } else if slot.frames >= 2 {
            let end = slot.frames.wrapping_sub(1);
            Some(Loop {
                start: 0,
                end,
                seam: fade_frames.min(end / 3),
            })
        } else {
            None
        };
        Ok(())
    }

    /// Stops time at `t_us`: the pose stays until [`ShowPlayer::resume`]
    /// (or a new clip).
    pub fn hold(&mut self, t_us: u64) -> Result<(), Error> {
        if matches!(self.state, State::Playing | State::Blending | State::Ended) {
            self.advance(t_us)?;
            self.held_at = t_us;
            self.state = State::Held;
        }
        Ok(())
    }

    /// Lets time run again after [`ShowPlayer::hold`].
    pub fn resume(&mut self, t_us: u64) -> Result<(), Error> {
        if self.state == State::Held {
            let shift = t_us.saturating_sub(self.held_at);
            for slot in self.slots.iter_mut().flatten() {
                slot.origin_us = slot.origin_us.saturating_add(shift);
            }
            if let Some(b) = self.blend.as_mut() {
                b.start_us = b.start_us.saturating_add(shift);
            }
            self.state = State::Playing;
            self.refresh_state(t_us);
        }
        Ok(())
    }

    /// Stops: the pose at `t_us` is held from then on; clips and the queue
    /// are dropped (a servo player then returns the servos to rest).
    pub fn stop(&mut self, t_us: u64) -> Result<(), Error> {
        if matches!(self.state, State::Idle | State::Stopped) {
            return Ok(());
        }
        let t = self.prepare(t_us)?;
        let mut pose = self.snap;
        self.pose_at(t, &mut pose)?;
        self.snap = pose;
        self.snap_d = [0; C];
        self.slots = [None, None];
        self.blend = None;
        self.queued = None;
        self.state = State::Stopped;
        Ok(())
    }

    /// The pose at show time `t_us` into `out` (at least the channel count;
    /// the channel table's units), after every transition due by then.
    /// Times must not go backwards between calls (an earlier time is taken
    /// as the last one).
    pub fn sample(&mut self, t_us: u64, out: &mut [i32]) -> Result<Now, Error> {
        let actual = out.len();
        let out = out
            .get_mut(..self.channels)
            .ok_or(Error::PlayerOutputTooSmall {
                expected: self.channels,
                actual,
            })?;
        let t = match self.state {
            State::Held => self.held_at,
            _ => t_us,
        };
        match self.state {
            State::Idle => {
                out.fill(0);
                return Ok(self.now(t));
            }
            State::Stopped => {
                copy(out, &self.snap);
                return Ok(self.now(t));
            }
            _ => {}
        }
        if self.state != State::Held {
            self.advance(t)?;
        }
        self.pose_at(t, out)?;
        Ok(self.now(t))
    }

    /// Resumes a held player and brings the transitions up to `t_us`; the
    /// time commands act at.
    fn prepare(&mut self, t_us: u64) -> Result<u64, Error> {
        if self.state == State::Held {
            self.resume(t_us)?;
        }
        if !matches!(self.state, State::Idle | State::Stopped) {
            self.advance(t_us)?;
        }
        Ok(t_us)
    }

    /// Starts `clip` at local time `local_us` at show time `t`, blended over
    /// `dur` µs from what plays.
    fn transition(&mut self, clip: u16, local_us: u64, dur: u64, t: u64) -> Result<(), Error> {
        let (entry, c) = self.show.entry_and_clip(clip)?;
        let player = Player::<N>::new(&c)?;
        let slot = Slot {
            player,
            clip,
            origin_us: t.saturating_sub(local_us),
            looping: entry.looping,
            frames: entry.frames,
        };
        self.queued = None;
        let from = match (self.state, self.blend) {
            (State::Idle, _) => None,
            (State::Stopped, _) => Some(From::Pose),
            (_, None) if dur > 0 => Some(From::Slot(self.current)),
            _ => {
                // Freeze the pose (and its velocity) of this moment.
                self.freeze(t)?;
                Some(From::Pose)
            }
        };
        let to = match from {
            Some(From::Slot(i)) => i ^ 1,
            _ => {
                self.slots = [None, None];
                0
            }
        };
        if let Some(s) = self.slots.get_mut(to) {
            *s = Some(slot);
        }
        self.current = to;
        self.blend = match from {
            Some(from) if dur > 0 => Some(Blend {
                from,
                to,
                start_us: t,
                dur_us: dur,
            }),
            _ => None,
        };
        self.state = if self.blend.is_some() {
            State::Blending
        } else {
            State::Playing
        };
        Ok(())
    }

    /// `snap` = the pose at `t`, `snap_d` = its change over the
    /// [`VELOCITY_STEP_US`] before `t` (short way round on wrapped
    /// channels), from the current state.
    fn freeze(&mut self, t: u64) -> Result<(), Error> {
        let mut now = [0i32; C];
        let mut before = [0i32; C];
        // Earlier time first: frame codecs then decode forward from the frames they hold.
        self.pose_at(t.saturating_sub(VELOCITY_STEP_US), &mut before)?;
        self.pose_at(t, &mut now)?;
        for (i, d) in self.snap_d.iter_mut().enumerate() {
            let (a, b) = (at(&before, i), at(&now, i));
            *d = diff(b, a, flag(&self.wrap, i));
        }
        self.snap = now;
        Ok(())
    }

    /// Carries out every transition due by `t`, each at its own time.
    fn advance(&mut self, t: u64) -> Result<(), Error> {
        for _ in 0..MAX_EVENTS_PER_SAMPLE {
            match self.next_event() {
                Some((due, ev)) if due <= t => self.fire(due, ev)?,
                _ => break,
            }
        }
        self.refresh_state(t);
        Ok(())
    }

    fn refresh_state(&mut self, t: u64) {
        if matches!(self.state, State::Idle | State::Stopped | State::Held) {
            return;
        }
        self.state = if self.blend.is_some() {
            State::Blending
        } else {
            match self.slot(self.current) {
                Some(s) if s.looping.is_none() && self.local(s, t) >= self.time(last(s.frames)) => {
                    State::Ended
                }
                Some(_) => State::Playing,
                None => State::Idle,
            }
        };
    }

    /// The earliest due transition: a blend's end, the playing clip's seam,
    /// or the queued clip's start.
    fn next_event(&self) -> Option<(u64, Event)> {
        let mut best: Option<(u64, Event)> = None;
        let mut consider = |due: u64, ev: Event| {
            if best.is_none_or(|(b, _)| due < b) {
                best = Some((due, ev));
            }
        };
        if let Some(b) = self.blend {
            consider(b.start_us.saturating_add(b.dur_us), Event::BlendEnd);
        }
        let playing = self.blend.map_or(self.current, |b| b.to);
        if let Some(s) = self.slot(playing) {
            let end = match s.looping {
                Some(l) => self.time(l.end),
                None => self.time(last(s.frames)),
            };
            if let Some(q) = self.queued {
                let at = end.saturating_sub(self.default_fade_us);
                consider(s.origin_us.saturating_add(at), Event::Queued(q));
            } else if let Some(l) = s.looping {
                let at = self.time(l.end.wrapping_sub(l.seam));
                consider(s.origin_us.saturating_add(at), Event::Seam(l));
            }
        }
        best
    }

    fn fire(&mut self, due: u64, ev: Event) -> Result<(), Error> {
        match ev {
            Event::BlendEnd => {
                if let Some(b) = self.blend.take() {
                    if let From::Slot(i) = b.from {
                        if let Some(s) = self.slots.get_mut(i) {
                            *s = None;
                        }
                    }
                    self.current = b.to;
                }
                Ok(())
            }
            Event::Seam(l) => {
                let playing = self.blend.map_or(self.current, |b| b.to);
                let Some(clip) = self.slot(playing).map(|s| s.clip) else {
                    return Ok(());
                };
                let dur = self
                    .time(l.end)
                    .saturating_sub(self.time(l.end.wrapping_sub(l.seam)));
                let start = self.time(l.start);
                self.transition(clip, start, dur, due)?;
                // The new pass keeps the loop the old one had (a loop set by
                // `set_loop` on a clip without loop points too).
                if let Some(s) = self.slots.get_mut(self.current).and_then(Option::as_mut) {
                    s.looping = Some(l);
                }
                Ok(())
            }
            Event::Queued(q) => {
                let playing = self.blend.map_or(self.current, |b| b.to);
                let fade = match self.slot(playing) {
                    Some(s) => {
                        let end = match s.looping {
                            Some(l) => self.time(l.end),
                            None => self.time(last(s.frames)),
                        };
                        self.default_fade_us
                            .min(s.origin_us.saturating_add(end).saturating_sub(due))
                    }
                    None => 0,
                };
                self.transition(q, 0, fade.max(1), due)
            }
        }
    }

    /// The pose at `t` of the current state (no transition carried out).
    fn pose_at(&mut self, t: u64, out: &mut [i32]) -> Result<(), Error> {
        let Some(b) = self.blend else {
            return self.sample_slot(self.current, t, out);
        };
        // The incoming clip into the scratch buffer, the outgoing into `out`.
        let mut scratch = self.scratch;
        self.sample_slot(b.to, t, &mut scratch)?;
        let tau = t.saturating_sub(b.start_us).min(b.dur_us);
        match b.from {
            From::Slot(i) => self.sample_slot(i, t, out)?,
            From::Pose => {
                // Velocity easing to rest: displacement D·g/h with
                // g = τ − τ²/(2T) µs.
                let two_t = b.dur_us.saturating_mul(2).max(1);
                let g = two_t
                    .wrapping_mul(tau)
                    .wrapping_sub(tau.wrapping_mul(tau))
                    .checked_div(two_t)
                    .unwrap_or(0) as i64;
                for (i, o) in out.iter_mut().enumerate() {
                    let d = i64::from(at(&self.snap_d, i));
                    let shift = d.wrapping_mul(g) / STEP_I64;
                    *o = at(&self.snap, i).wrapping_add(shift as i32);
                }
            }
        }
        let e = ease(tau, b.dur_us);
        for (i, (o, &s)) in out.iter_mut().zip(scratch.iter()).enumerate() {
            *o = mix(*o, s, e, flag(&self.wrap, i));
        }
        self.scratch = scratch;
        Ok(())
    }

    fn sample_slot(&mut self, i: usize, t: u64, out: &mut [i32]) -> Result<(), Error> {
        let Some(Some(slot)) = self.slots.get_mut(i) else {
            copy(out, &self.snap);
            return Ok(());
        };
        let local = t.saturating_sub(slot.origin_us);
        slot.player.sample_at(local, out)
    }

    fn slot(&self, i: usize) -> Option<&Slot<'a, N>> {
        self.slots.get(i).and_then(Option::as_ref)
    }

    fn local(&self, s: &Slot<'a, N>, t: u64) -> u64 {
        t.saturating_sub(s.origin_us)
    }

    /// Local time of frame `f`, µs (floor).
    fn time(&self, f: u32) -> u64 {
        u64::from(f).wrapping_mul(u64::from(self.frame_ns)) / 1000
    }

    /// Whole frames in `us` microseconds.
    fn frames_in(&self, us: u64) -> u32 {
        let ns = us.saturating_mul(1000);
        let frames = ns.checked_div(u64::from(self.frame_ns)).unwrap_or(0);
        u32::try_from(frames).unwrap_or(u32::MAX)
    }

    fn now(&self, t: u64) -> Now {
        let playing = self.blend.map_or(self.current, |b| b.to);
        let slot = self.slot(playing);
        let weight = match self.blend {
            Some(b) => ease(t.saturating_sub(b.start_us).min(b.dur_us), b.dur_us),
            None => 65536,
        };
        Now {
            state: self.state,
            clip: slot.map(|s| s.clip),
            local_us: slot.map_or(0, |s| self.local(s, t)),
            weight: weight as u32,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Event {
    BlendEnd,
    Seam(Loop),
    Queued(u16),
}

fn fade_us(ms: u32) -> u64 {
    u64::from(ms).wrapping_mul(1000).min(MAX_FADE_US)
}

fn last(frames: u32) -> u32 {
    frames.saturating_sub(1)
}

/// The C1 smoothstep `3u² − 2u³` of `u = τ/T` in 16.16 fixed point
/// (0..=65536).
pub fn ease(tau: u64, dur: u64) -> i64 {
    if dur == 0 || tau >= dur {
        return 65536;
    }
    let u = tau
        .wrapping_mul(65536)
        .checked_div(dur)
        .unwrap_or(0)
        .min(65536);
    (u.wrapping_mul(u)
        .wrapping_mul((3 * 65536u64).wrapping_sub(u.wrapping_mul(2)))
        >> 32) as i64
}

/// `b − a`, the short way round (into (−180°, 180°]) on a wrapped channel.
pub fn diff(b: i32, a: i32, wrap: bool) -> i32 {
    let d = b.wrapping_sub(a);
    if !wrap {
        return d;
    }
    let m = i64::from(d).rem_euclid(360_000);
    (if m > 180_000 {
        m.wrapping_sub(360_000)
    } else {
        m
    }) as i32
}

/// `a + (b − a)·e / 2^16`, wrapping, the difference the short way round on
/// a wrapped channel (SPEC.md §9.4).
pub fn mix(a: i32, b: i32, e: i64, wrap: bool) -> i32 {
    let d = i64::from(diff(b, a, wrap));
    a.wrapping_add((d.wrapping_mul(e) >> 16) as i32)
}

fn at(v: &[i32], i: usize) -> i32 {
    v.get(i).copied().unwrap_or(0)
}

fn flag(v: &[bool], i: usize) -> bool {
    v.get(i).copied().unwrap_or(false)
}

fn copy(dst: &mut [i32], src: &[i32]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}
