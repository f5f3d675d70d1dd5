//! Show mode: the embedded `.mcb` is a show (SPEC.md §9: `mocap show build`), run by
//! `mocap_decoder::ShowRunner` — its cue lists, triggers, idle clips, blends — at the figure's
//! tick rate, every tick through the same [`Driver`] (rig limits, speed, the figure's hard
//! limits, then the output) as the servo mode. Commands come over the UART as `Show` frames
//! (SPEC.md §8.2: the same postcard + COBS + CRC link as the streaming mode) and act at their
//! show time; `Timecode` frames make the show clock (`ShowClock`) slew towards an external
//! clock. Output events of the cues (`gpio`, `serial`) print as `# event t_us=… …` lines, the
//! lines `mocap play` prints for the same show and commands.
//!
//! The show clock starts with the first command (show time 0 is its arrival); a command whose
//! time has passed when it arrives acts at once. The run ends after the tick at an `End`
//! command's time, or once the show is done (no cue list, nothing queued, the last clip ended)
//! with no command waiting; then every servo returns to rest.

use heapless::Deque;
use mocap_decoder::show::clock::DEFAULT_SLEW_PPM;
use mocap_decoder::{Command, Output, Show, ShowClock, ShowRunner, State};
use mocap_servo::output::ServoOutput;
use mocap_servo::stream::{show_request, Message, ShowRequest};

use crate::board::Rx;
use crate::servo::{hex, Driver, Fault, Mode, TickStats, MAX_SERVOS, PLAYER_WORDS};
use crate::stream::{Event, Link};
use crate::{instructions, ticks, Failure, Out};

/// The show runner: two clip players of [`PLAYER_WORDS`] words, poses of [`MAX_SERVOS`].
pub type Runner = ShowRunner<'static, PLAYER_WORDS, MAX_SERVOS>;
/// Commands waiting for their time.
pub const QUEUE: usize = 32;
/// Output events of one tick kept for printing.
const EVENTS: usize = 8;

/// A request at a show time, µs.
type Pending = (u64, ShowRequest);

/// The show in flash.
pub struct ShowMode {
    pub show: Show<'static>,
    pub calibration_ticks: u32,
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
    fn accept(&mut self, event: Event, clock: &mut ShowClock, local_us: u64) {
        match event {
            Event::Show { at_ms, op, arg, ms } => {
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
            Event::Timecode { show_ms } => clock.timecode(local_us, u64::from(show_ms) * 1000),
            // A session's greeting: nothing to do.
            Event::Hello => {}
            // A host that stops (`mocap send`, Ctrl-C): stop now and end, at rest.
            Event::Stop => {
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

    /// Takes the frames that have arrived, while the queue has room (the rest wait in the link
    /// and the UART).
    fn take(&mut self, link: &mut Link, clock: &mut ShowClock, local_us: u64) {
        while !self.queue.is_full() {
            let Some(event) = link.poll() else { return };
            self.accept(event, clock, local_us);
        }
    }

    /// Whether the show clock must wait for the sender before show time `t`.
    fn behind(&self, t: u64) -> bool {
        self.horizon.is_some_and(|h| h < t) && !self.queue.is_full()
    }
}

impl Mode for ShowMode {
    fn run<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>>(
        self,
        driver: &mut Driver<O, S>,
        text: &mut Out,
    ) -> Result<(), Failure> {
        let mut runner = Runner::new(self.show).map_err(|e| Failure::Decoder("show", e))?;
        text.str("# mode=show")
            .kv("clips", u64::from(self.show.clip_count()))
            .kv("servos", driver.rig.count() as u64)
            .kv("rate_mhz", u64::from(driver.rig.rate_mhz()))
            .kv("queue", QUEUE as u64)
            .kv("runner_bytes", core::mem::size_of::<Runner>() as u64)
            .kv(
                "player_bytes",
                core::mem::size_of::<mocap_decoder::ShowPlayer<'static, PLAYER_WORDS, MAX_SERVOS>>()
                    as u64,
            )
            .nl();
        let mut link = Link::new(Rx::take());
        let mut inbox = Inbox::new();
        let mut clock = ShowClock::new(DEFAULT_SLEW_PPM);
        // The show starts with the first `Show` frame.
        while !inbox.started {
            match link.wait() {
                Some(event) => inbox.accept(event, &mut clock, 0),
                None => {
                    driver.park_after(Fault::StreamTimeout, text)?;
                    return Ok(());
                }
            }
        }
        let mut angles = [0i32; PLAYER_WORDS];
        let mut end: Option<u64> = None;
        let mut blend = TickStats::default();
        let mut plain = TickStats::default();
        let mut events: heapless::Vec<(u64, Output<'static>), EVENTS> = heapless::Vec::new();
        let mut dropped_events = 0u32;
        let mut i = 0u64;
        // The last tick's show time: a command that arrives late acts now, not in the past.
        let mut last_t = 0u64;
        loop {
            let local = driver.rig.tick_us(i);
            inbox.take(&mut link, &mut clock, local);
            let t = clock.now(local);
            // Lockstep: wait until the sender has vouched for this tick's time.
            while inbox.behind(t) {
                match link.wait() {
                    Some(event) => inbox.accept(event, &mut clock, local),
                    None => {
                        driver.park_after(Fault::StreamTimeout, text)?;
                        return Ok(());
                    }
                }
            }
            if end.is_some_and(|e| t > e) {
                break;
            }
            let start = ticks::now();
            let mut emit = |at: u64, o: Output<'static>| {
                if events.push((at, o)).is_err() {
                    dropped_events += 1;
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
            let now = runner
                .tick(t, &mut angles, &mut emit)
                .map_err(|e| Failure::Decoder("show", e))?;
            let targets = driver.rig.targets(&angles);
            let before = driver.stats.total_ticks;
            match driver.command(&targets, start, text) {
                Ok(()) => {}
                Err(Failure::EStop) => {
                    driver.park_after(Fault::EStop, text)?;
                    break;
                }
                Err(e) => return Err(e),
            }
            let spent = driver.stats.total_ticks - before;
            let stats = if now.state == State::Blending {
                &mut blend
            } else {
                &mut plain
            };
            stats.ticks += 1;
            stats.total_ticks += spent;
            stats.worst_ticks = stats.worst_ticks.max(spent as u32);
            for (at, o) in events.iter() {
                print_event(*at, o, text);
            }
            events.clear();
            if let Some(at) = status {
                let (state, clip) = (now.state, now.clip);
                let message = Message::ShowStatus {
                    show_ms: u32::try_from(at / 1000).unwrap_or(u32::MAX),
                    clip: clip.unwrap_or(u16::MAX),
                    state: state_code(state),
                    list: runner.running().map_or(u16::MAX, |(l, _)| l),
                };
                crate::stream::send(text, &message)?;
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
        driver.park(text)?;
        driver.print_hard_clamps(text);
        driver.print_stats("show_ticks", self.calibration_ticks, text);
        let cal = self.calibration_ticks;
        for (key, s) in [("blend_ticks", &blend), ("plain_ticks", &plain)] {
            text.str("#")
                .kv(key, s.ticks)
                .kv(
                    "per_tick",
                    instructions(s.total_ticks, cal) / s.ticks.max(1),
                )
                .kv("max_tick", instructions(u64::from(s.worst_ticks), cal))
                .nl();
        }
        let (timecodes, relocations) = clock.timecodes();
        text.str("#")
            .kv("commands_rejected", u64::from(inbox.rejected))
            .kv("events_dropped", u64::from(dropped_events))
            .kv("timecodes", u64::from(timecodes))
            .kv("relocations", u64::from(relocations))
            .nl();
        text.str("#")
            .kv("stack_bytes_used", crate::stack::used_bytes() as u64)
            .nl();
        Ok(())
    }
}

/// `ShowStatus.state` (SPEC.md §8.2).
fn state_code(s: State) -> u8 {
    match s {
        State::Idle => 0,
        State::Playing => 1,
        State::Blending => 2,
        State::Held => 3,
        State::Stopped => 4,
        State::Ended => 5,
    }
}

/// `# event t_us=<t> gpio <pin> <0|1>` or `# event t_us=<t> serial <hex bytes>`, as
/// `mocap_encoder::show::play::event_text` prints them.
fn print_event(at: u64, o: &Output<'_>, text: &mut Out) {
    text.str("# event").kv("t_us", at);
    match o {
        Output::Gpio { pin, level } => {
            text.str(" gpio ")
                .u32(u32::from(*pin))
                .str(if *level { " 1" } else { " 0" });
        }
        Output::Serial(bytes) => {
            text.str(" serial");
            hex(text, bytes);
        }
    }
    text.nl();
}
