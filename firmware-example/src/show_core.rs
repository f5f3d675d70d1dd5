//! The show mode's loop, the one every firmware runs: the QEMU firmware (`src/show.rs`) and the
//! real boards (`hw/show.rs`, included there with `#[path]`, as `src/figure.rs` is). The show
//! (SPEC.md §9) is run by `mocap_decoder::ShowRunner` at the figure's tick rate; commands come
//! as `Show` frames (SPEC.md §8.2: postcard + COBS + CRC) and act at their show time;
//! `Timecode` frames make the show clock (`ShowClock`) slew towards an external clock.
//!
//! What differs between firmwares stays with them, behind two traits: where the frames come
//! from ([`Frames`]: QEMU's polled UART, a board's UART receive interrupt) and what a tick's
//! pose goes through ([`Stage`]: the figure's limits and the servo output, the e-stop, the
//! timing figures, how output events and `ShowStatus` replies leave).
//!
//! The show clock starts with the first `Show` frame (show time 0 is its arrival); a command
//! whose time has passed when it arrives acts at once. After a first `Sync` the clock runs in
//! lockstep with the sender (it waits at the show time the sender has vouched for). The run
//! ends after the tick at an `End` command's time, or once the show is done (no cue list,
//! nothing queued, the last clip ended) with no command waiting; a host's `Stop` stops the
//! show and ends it.

use heapless::Deque;
use mocap_decoder::show::clock::DEFAULT_SLEW_PPM;
use mocap_decoder::{Command, Error, Output, ShowClock, ShowRunner, State};
use mocap_servo::stream::{show_request, Message, ShowRequest, PROTOCOL_VERSION};

use crate::figure::MAX_SERVOS;

/// The show runner: two clip players of `W` words, poses of [`MAX_SERVOS`].
pub type Runner<const W: usize> = ShowRunner<'static, W, MAX_SERVOS>;
/// Commands waiting for their time.
pub const QUEUE: usize = 32;
/// Output events of one tick kept until the tick's pose is out.
const EVENTS: usize = 8;

/// A request at a show time, µs.
type Pending = (u64, ShowRequest);

/// Where the frames come from.
pub trait Frames {
    /// Hands the next frame that has arrived intact to `f`; `None` if none has (never waits).
    fn poll_with<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T>;
    /// Waits for the next intact frame; `None` once the link's gap timeout has passed.
    fn wait_with<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T>;
}

/// What a tick's pose goes through, and where the show's outputs go.
pub trait Stage {
    type Error;
    /// Tick `i`'s time on the local clock, µs from the show's start (the rig's tick clock).
    fn tick_us(&self, i: u64) -> u64;
    /// Before tick `i` takes its frames: a board waits here until the tick's time comes.
    fn pace(&mut self, local_us: u64);
    /// The tick's work starts: its commands, the runner's tick, then [`pose`](Self::pose).
    fn start(&mut self);
    /// The tick's pose (the rig's angles, mdeg) through the figure to the servos; `state` is
    /// the player's. `Ok(false)`: the e-stop is pressed, the servos are parked, the show ends.
    fn pose(&mut self, angles: &[i32], state: State) -> Result<bool, Self::Error>;
    /// A cue's output event (a GPIO edge, serial bytes) at show time `at_us`.
    fn event(&mut self, at_us: u64, output: &Output<'_>);
    /// A reply to the sender (`ShowStatus`).
    fn send(&mut self, message: &Message<'_>) -> Result<(), Self::Error>;
    /// The link fell silent past its gap timeout: park the servos.
    fn timed_out(&mut self) -> Result<(), Self::Error>;
}

/// Why the run stopped early.
pub enum Fail<E> {
    /// The show runner refused the show or failed on it.
    Show(Error),
    /// The stage failed (its output, its reply).
    Stage(E),
}

/// How the run ended.
pub enum Ended {
    /// The link fell silent (the stage parked the servos).
    TimedOut,
    /// At an `End`, a `Stop`, the e-stop, or the end of the show; the caller parks.
    Ran(Summary),
}

/// The link's figures of a run.
pub struct Summary {
    /// Frames the show could not take: unknown ops, clips or lists the show does not have,
    /// a full queue, other messages.
    pub rejected: u32,
    /// Output events past [`EVENTS`] in one tick.
    pub events_dropped: u32,
    /// Timecodes taken, and the clock's relocations (jumps, past 2 s of error).
    pub timecodes: u32,
    pub relocations: u32,
}

/// `ShowStatus.state` (SPEC.md §8.2).
pub fn state_code(s: State) -> u8 {
    match s {
        State::Idle => 0,
        State::Playing => 1,
        State::Blending => 2,
        State::Held => 3,
        State::Stopped => 4,
        State::Ended => 5,
    }
}

/// What came over the link: the commands waiting for their time, and how far the sender has
/// vouched for the show (lockstep).
struct Inbox {
    queue: Deque<Pending, QUEUE>,
    /// After a first `Sync`: every command up to this show time (µs) has arrived; the show
    /// clock waits here. `None`: free-running (commands act when they arrive).
    horizon: Option<u64>,
    /// A first `Show` frame arrived: the show clock runs.
    started: bool,
    rejected: u32,
}

impl Inbox {
    fn new() -> Self {
        Inbox {
            queue: Deque::new(),
            horizon: None,
            started: false,
            rejected: 0,
        }
    }

    /// One frame: a command into the queue, a `Sync` moves the horizon (an `End` makes it
    /// endless), a timecode into the clock.
    fn accept(&mut self, message: &Message<'_>, clock: &mut ShowClock, local_us: u64) {
        match *message {
            Message::Show { at_ms, op, arg, ms } => {
                self.started = true;
                let at = u64::from(at_ms) * 1000;
                match show_request(op, arg, ms) {
                    Some(ShowRequest::Sync) => {
                        let h = if at_ms == u32::MAX { u64::MAX } else { at };
                        self.horizon = Some(self.horizon.unwrap_or(0).max(h));
                    }
                    Some(r) if self.queue.push_back((at, r)).is_ok() => {
                        if r == ShowRequest::End {
                            self.horizon = self.horizon.map(|_| u64::MAX);
                        }
                    }
                    _ => self.rejected += 1,
                }
            }
            Message::Timecode { show_ms } => clock.timecode(local_us, u64::from(show_ms) * 1000),
            // A session's greeting: nothing to do.
            Message::Hello { version } if version == PROTOCOL_VERSION => {}
            // A host that stops (`mocap send`, Ctrl-C): stop now and end, at rest.
            Message::Stop => {
                let now = clock.now(local_us);
                self.horizon = self.horizon.map(|_| u64::MAX);
                if self
                    .queue
                    .push_back((now, ShowRequest::Run(Command::Stop)))
                    .is_err()
                    || self.queue.push_back((now, ShowRequest::End)).is_err()
                {
                    self.rejected += 1;
                }
            }
            _ => self.rejected += 1,
        }
    }

    /// Takes the frames that have arrived, while the queue has room (the rest wait in the
    /// link).
    fn take(&mut self, link: &mut impl Frames, clock: &mut ShowClock, local_us: u64) {
        while !self.queue.is_full() {
            if link
                .poll_with(|m| self.accept(m, clock, local_us))
                .is_none()
            {
                return;
            }
        }
    }

    /// Whether the show clock must wait for the sender before show time `t`.
    fn behind(&self, t: u64) -> bool {
        self.horizon.is_some_and(|h| h < t) && !self.queue.is_full()
    }
}

/// Runs `show` on `runner` (the caller's, for its size) with commands from `link`, every tick's
/// pose through `stage`, until the show ends (module doc).
pub fn run<const W: usize, S: Stage>(
    runner: &mut Runner<W>,
    link: &mut impl Frames,
    stage: &mut S,
) -> Result<Ended, Fail<S::Error>> {
    let mut inbox = Inbox::new();
    let mut clock = ShowClock::new(DEFAULT_SLEW_PPM);
    // The show starts with the first `Show` frame.
    while !inbox.started {
        if link.wait_with(|m| inbox.accept(m, &mut clock, 0)).is_none() {
            stage.timed_out().map_err(Fail::Stage)?;
            return Ok(Ended::TimedOut);
        }
    }
    let mut angles = [0i32; W];
    let mut end: Option<u64> = None;
    let mut events: heapless::Vec<(u64, Output<'static>), EVENTS> = heapless::Vec::new();
    let mut events_dropped = 0u32;
    let mut i = 0u64;
    // The last tick's show time: a command that arrives late acts now, not in the past.
    let mut last_t = 0u64;
    loop {
        let local = stage.tick_us(i);
        stage.pace(local);
        inbox.take(link, &mut clock, local);
        let t = clock.now(local);
        // Lockstep: wait until the sender has vouched for this tick's time.
        while inbox.behind(t) {
            if link
                .wait_with(|m| inbox.accept(m, &mut clock, local))
                .is_none()
            {
                stage.timed_out().map_err(Fail::Stage)?;
                return Ok(Ended::TimedOut);
            }
        }
        if end.is_some_and(|e| t > e) {
            break;
        }
        stage.start();
        let mut emit = |at: u64, o: Output<'static>| {
            if events.push((at, o)).is_err() {
                events_dropped += 1;
            }
        };
        let mut status = None;
        while let Some(&(at, request)) = inbox.queue.front().filter(|(at, _)| *at <= t) {
            inbox.queue.pop_front();
            match request {
                ShowRequest::Run(c) => match runner.command(c, at.max(last_t), &mut emit) {
                    Ok(()) => {}
                    // A clip or list the show does not have: nothing changes.
                    Err(_) => inbox.rejected += 1,
                },
                ShowRequest::End => end = Some(at),
                ShowRequest::Status => status = Some(at.max(last_t)),
                ShowRequest::Sync => {}
            }
        }
        let now = runner.tick(t, &mut angles, &mut emit).map_err(Fail::Show)?;
        if !stage.pose(&angles, now.state).map_err(Fail::Stage)? {
            break;
        }
        for (at, o) in events.iter() {
            stage.event(*at, o);
        }
        events.clear();
        if let Some(at) = status {
            let message = Message::ShowStatus {
                show_ms: u32::try_from(at / 1000).unwrap_or(u32::MAX),
                clip: now.clip.unwrap_or(u16::MAX),
                state: state_code(now.state),
                list: runner.running().map_or(u16::MAX, |(l, _)| l),
            };
            stage.send(&message).map_err(Fail::Stage)?;
        }
        last_t = t;
        i += 1;
        if end.is_none()
            && inbox.queue.is_empty()
            && inbox.horizon.is_none_or(|h| h == u64::MAX)
            && runner.is_done()
        {
            break;
        }
    }
    let (timecodes, relocations) = clock.timecodes();
    Ok(Ended::Ran(Summary {
        rejected: inbox.rejected,
        events_dropped,
        timecodes,
        relocations,
    }))
}
