//! The show mode on a real board (`hw/play.rs` calls [`run`] when the embedded `.mcb` is a show):
//! the QEMU firmware's own show loop (`../src/show_core.rs`: the command queue, lockstep with
//! the sender, `ShowRunner`'s cues, triggers and blends, `ShowStatus` replies), given the
//! board's UART and its servos.
//!
//! - **Link.** The board's UART receive interrupt hands every byte to [`received`], which keeps
//!   it in a ring of [`RX_BYTES`]; the loop takes the bytes into a `FrameReceiver` (postcard +
//!   COBS + CRC-32 frames, SPEC.md §8.2, as `mocap send show.mcb --cues cues.txt --port …`
//!   writes them) between ticks. Corrupt frames are dropped; a full ring drops bytes (counted).
//!   Replies (`ShowStatus`) go out on the same UART.
//! - **Ticks.** Tick `i` waits for its time on the board's µs timer (`Pace`), counted from the
//!   first `Show` frame (show time 0), then the runner's pose goes through the figure (the
//!   rig's limits, the figure's hard limits) to the output, as a servo clip's ticks do.
//! - **Faults end at rest.** The e-stop, a host's `Stop`, an `End` and, once bytes have come,
//!   [`GAP_TIMEOUT_US`] without an intact frame while the show waits for its sender (lockstep)
//!   park every servo at its speed and acceleration limits.
//! - **Output events** of the cues (`gpio`, `serial`) are logged with their show time; wire
//!   them to pins or a second UART in [`Board::event`].

use core::cell::RefCell;

use critical_section::Mutex;
use defmt::{info, warn};
use heapless::Deque;
use mocap_decoder::{Output, Show, State};
use mocap_servo::output::ServoOutput;
use mocap_servo::stream::{encode_frame, FrameReceiver, Message, MAX_FRAME_LEN};

use crate::figure::Rig;
use crate::play::{self, Busy, Clock, Io, Pace, Stop, PLAYER_WORDS};
use crate::show_core::{self, Ended, Fail, Frames, Stage, QUEUE};

/// The UART's line rate (8N1), `mocap send`'s default.
pub const BAUD: u32 = 115_200;
/// The receive ring between the interrupt and the frame receiver: 22 ms of bytes at
/// [`BAUD`], more than a tick.
pub const RX_BYTES: usize = 256;
/// While the show waits for its sender: this long without an intact frame, once bytes have
/// come, parks the servos (the QEMU firmware's default `MOCAP_STREAM_TIMEOUT_MS`).
pub const GAP_TIMEOUT_US: u64 = 500_000;

/// The show runner: two clip players of [`PLAYER_WORDS`] words.
type Runner = show_core::Runner<PLAYER_WORDS>;

/// Bytes from the UART, and those a full ring dropped.
struct Ring {
    bytes: Deque<u8, RX_BYTES>,
    dropped: u32,
}

static RX: Mutex<RefCell<Ring>> = Mutex::new(RefCell::new(Ring {
    bytes: Deque::new(),
    dropped: 0,
}));

/// The UART receive interrupt's body: one received byte into the ring.
pub fn received(byte: u8) {
    critical_section::with(|cs| {
        let mut ring = RX.borrow_ref_mut(cs);
        if ring.bytes.push_back(byte).is_err() {
            ring.dropped = ring.dropped.saturating_add(1);
        }
    });
}

fn next_byte() -> Option<u8> {
    critical_section::with(|cs| RX.borrow_ref_mut(cs).bytes.pop_front())
}

/// The ring → the frame receiver.
struct Link<'c, C: Clock> {
    frames: FrameReceiver<MAX_FRAME_LEN>,
    clock: &'c C,
    /// Bytes taken from the ring.
    bytes: u32,
}

impl<C: Clock> Frames for Link<'_, C> {
    fn poll_with<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T> {
        while let Some(byte) = next_byte() {
            self.bytes = self.bytes.wrapping_add(1);
            if let Some(Ok(message)) = self.frames.push(byte) {
                return Some(f(&message));
            }
        }
        None
    }

    fn wait_with<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T> {
        let since = self.clock.now_us();
        let mut f = Some(f);
        loop {
            if let Some(taken) = self.poll_with(|m| f.take().map(|f| f(m))) {
                return taken;
            }
            let idle = self.clock.now_us().saturating_sub(since);
            if self.bytes != 0 && idle >= GAP_TIMEOUT_US {
                return None;
            }
        }
    }
}

/// The show loop's stage on a board: the pace, the figure and the output, the e-stop, the
/// replies, and the tick's time.
struct Board<'a, O, C: Clock, E, S> {
    rig: &'a mut Rig,
    output: &'a mut O,
    clock: &'a C,
    io: &'a mut Io<E, S>,
    /// Started at the first tick (the first `Show` frame's arrival).
    pace: Option<Pace<'a, C>>,
    /// The last tick's index, and when its work started (µs).
    tick: u64,
    t0: u64,
    blend: Busy,
    plain: Busy,
}

impl<O: ServoOutput, C: Clock, E: FnMut() -> bool, S: FnMut(&[u8])> Board<'_, O, C, E, S> {
    /// Every servo back to rest, one tick per period after the last.
    fn park(&mut self) -> Result<(), Stop> {
        let clock = self.clock;
        let pace = self.pace.get_or_insert_with(|| Pace::start(clock));
        play::park(self.rig, self.output, pace, self.tick)
    }
}

impl<O: ServoOutput, C: Clock, E: FnMut() -> bool, S: FnMut(&[u8])> Stage
    for Board<'_, O, C, E, S>
{
    type Error = Stop;

    fn tick_us(&self, i: u64) -> u64 {
        self.rig.tick_us(i)
    }

    fn pace(&mut self, local_us: u64) {
        let clock = self.clock;
        self.pace
            .get_or_insert_with(|| Pace::start(clock))
            .wait_until(local_us);
    }

    fn start(&mut self) {
        self.t0 = self.clock.now_us();
    }

    fn pose(&mut self, angles: &[i32], state: State) -> Result<bool, Stop> {
        if (self.io.estop)() {
            warn!("e-stop: every servo to rest");
            self.park()?;
            return Ok(false);
        }
        let targets = self.rig.targets(angles);
        self.rig
            .tick(&targets, self.output)
            .map_err(play::output_failed)?;
        let spent = self.clock.now_us().saturating_sub(self.t0);
        if state == State::Blending {
            self.blend.add(spent);
        } else {
            self.plain.add(spent);
        }
        // One line a second.
        let per_second = 1_000_000u64
            .checked_div(self.rig.tick_us(1))
            .unwrap_or(1)
            .max(1);
        if self.tick.is_multiple_of(per_second) {
            info!(
                "t={=u64} ms {} pulses_qus={}",
                self.rig.tick_us(self.tick) / 1000,
                state,
                self.rig.held()
            );
        }
        self.tick = self.tick.saturating_add(1);
        Ok(true)
    }

    fn event(&mut self, at_us: u64, output: &Output<'_>) {
        match *output {
            Output::Gpio { pin, level } => {
                info!(
                    "event t={=u64} ms: gpio {=u8} {=bool}",
                    at_us / 1000,
                    pin,
                    level
                )
            }
            Output::Serial(bytes) => {
                info!("event t={=u64} ms: serial {=[u8]:x}", at_us / 1000, bytes)
            }
        }
    }

    fn send(&mut self, message: &Message<'_>) -> Result<(), Stop> {
        let mut frame = [0u8; MAX_FRAME_LEN];
        match encode_frame(message, &mut frame) {
            Ok(len) => (self.io.send)(frame.get(..len).unwrap_or(&[])),
            Err(e) => warn!("reply not sent: {}", e),
        }
        Ok(())
    }

    fn timed_out(&mut self) -> Result<(), Stop> {
        warn!(
            "no intact frame for {=u64} ms: every servo to rest",
            GAP_TIMEOUT_US / 1000
        );
        self.park()
    }
}

/// Runs `show` on `rig` (the figure's playback of its clips' rig) through `output`, its commands
/// from the UART (module doc), until it ends; then every servo back to rest.
pub fn run<O: ServoOutput, C: Clock>(
    show: Show<'static>,
    rig: &mut Rig,
    output: &mut O,
    clock: &C,
    io: &mut Io<impl FnMut() -> bool, impl FnMut(&[u8])>,
) -> Result<(), Stop> {
    let mut runner = Runner::new(show).map_err(|e| {
        defmt::error!("show: {}", e);
        Stop
    })?;
    info!(
        "show mode: {=u16} clips, {=usize} servos at {=u32} mHz; waiting for commands on the UART ({=u32} baud, queue {=usize}, runner {=usize} B)",
        show.clip_count(),
        rig.count(),
        rig.rate_mhz(),
        BAUD,
        QUEUE,
        core::mem::size_of::<Runner>()
    );
    let mut link = Link {
        frames: FrameReceiver::new(),
        clock,
        bytes: 0,
    };
    let period_us = rig.tick_us(1);
    let mut board = Board {
        rig,
        output,
        clock,
        io,
        pace: None,
        tick: 0,
        t0: 0,
        blend: Busy::default(),
        plain: Busy::default(),
    };
    let summary = match show_core::run(&mut runner, &mut link, &mut board) {
        Ok(Ended::Ran(summary)) => summary,
        Ok(Ended::TimedOut) => return Ok(()),
        Err(Fail::Show(e)) => {
            defmt::error!("show: {}", e);
            board.park()?;
            return Err(Stop);
        }
        Err(Fail::Stage(stop)) => return Err(stop),
    };
    board.park()?;
    let late = board.pace.as_ref().map_or(0, |p| p.late);
    board.blend.log("ticks in a transition", period_us, late);
    board.plain.log("ticks outside one", period_us, late);
    play::log_hard_clamps(board.rig);
    let (frames, dropped) = (link.frames.received(), link.frames.dropped());
    let ring_dropped = critical_section::with(|cs| RX.borrow_ref(cs).dropped);
    info!(
        "link: {=u32} bytes, {=u32} frames, {=u32} dropped, {=u32} bytes lost to a full ring; {=u32} commands rejected, {=u32} events dropped, {=u32} timecodes, {=u32} relocations",
        link.bytes,
        frames,
        dropped,
        ring_dropped,
        summary.rejected,
        summary.events_dropped,
        summary.timecodes,
        summary.relocations
    );
    Ok(())
}
