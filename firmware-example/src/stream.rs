//! Streaming mode (`MOCAP_STREAM=1`): the firmware takes its motion from the UART instead of
//! flash — a clip uploaded in `ClipChunk`s and played on `Play`, or live `Pose`s — as frames of
//! postcard + COBS + CRC-32 (SPEC.md §8, `mocap_servo::stream`), and drives the servos through
//! the same [`Driver`] as the servo mode (output `MOCAP_SERVO`, Maestro when unset).
//!
//! - **Link.** Bytes go from the UART's receive FIFO into a fixed ring ([`RING_BYTES`],
//!   `heapless::Deque`), then one by one into a `FrameReceiver<MAX_FRAME_LEN>`: corrupt frames
//!   are dropped and counted, reception resynchronises at the next `00`. (Here the ring is
//!   filled by polling between ticks and QEMU holds bytes back while the UART is full; on a
//!   board, `Link::pump` is the receive interrupt's body.)
//! - **Rig.** The servos and their limits are the figure's, compiled in at build time
//!   (`MOCAP_FIGURE`, `crate::figure`). A streamed clip must carry the figure's rig
//!   table, and live poses are held to its limits and hard limits, whatever the host sends.
//! - **Upload.** `ClipChunk`s are assembled in a fixed RAM buffer
//!   ([`crate::board::CLIP_BUFFER_BYTES`]) in any order, by `mocap_servo::stream::upload`'s
//!   rule (SPEC.md §8.1): the first chunk accepted fixes `total` (at most the buffer); each
//!   chunk must be the 64-byte-aligned chunk of that clip it claims to be; a bitmap of
//!   [`BITMAP_WORDS`] words records the chunks received. Copies of a chunk are counted and
//!   change nothing (`mocap send --passes N` sends every chunk N times); anything inconsistent
//!   is rejected and counted. `Play` parses the complete clip with `Clip::parse` (CRC-checked)
//!   and plays it from tick 0 at the rig's rate — or refuses it (corrupt, another rig: the
//!   upload is then forgotten, so a later pass can bring it again; no upload at all). A `Play`
//!   that comes while chunks are missing is remembered (state armed) and the clip starts when
//!   the last missing chunk arrives; `Hello` forgets the upload and the armed `Play`, `Pose` and
//!   `Stop` the armed `Play`. While a clip plays, chunks are only checked against the upload
//!   (copies counted as such; the buffer is not written).
//! - **Live poses.** `Pose.seq` counts the sender's ticks: each pose is one tick towards its
//!   pulses. A gap in `seq` (lost frames) becomes that many ticks holding the last pose (at most
//!   [`MAX_HOLD_TICKS`]); a `seq` that is not ahead of the last one (a duplicate or a stale
//!   frame) is ignored, a pose with the wrong servo count rejected.
//! - **Stop** (or the end of a clip played without `loop_`, or a decoder error in it) returns
//!   every servo to neutral at its speed limit; a `Pose`, `Stop` or `Hello` during playback
//!   interrupts it.
//! - **Faults end at rest.** No accepted frame for `STREAM_TIMEOUT_MS` (build option
//!   `MOCAP_STREAM_TIMEOUT_MS`, default 500 ms; 0 holds the last pose however long the gap)
//!   once the first byte has arrived — a cut cable, a host that stopped, a line so corrupt that
//!   nothing gets through — parks every servo at its speed and acceleration limits and ends the
//!   session; up to then a gap holds the last pose. A decoder error in the playing clip and the
//!   e-stop do the same. Each prints `# fault=stream_timeout|decode_error|estop park_ticks=
//!   park_ms=` after the park. (An uploaded clip plays from RAM: a cut cable while it plays
//!   does not stop it; it ends at rest.)
//! - **Status** frames (`Status { received, dropped, last_seq, state, chunks }`, state
//!   [`State`], `chunks` the distinct chunks of the upload) go back in reply to `Hello`, after
//!   every `Play` (accepted, armed or refused) and when an armed `Play` starts the clip, every
//!   [`STATUS_EVERY_TICKS`] output ticks, and once the servos are parked after `Stop` or the
//!   end of a clip. The firmware greets with `Hello` at start-up.
//!
//! QEMU's UART is also the console, so frames sent back are printed as hex lines (`f 0b 05 …`)
//! and servo commands as in the servo mode. This example ends its run when the servos are
//! parked after `Stop` or after a clip (a controller would wait for the next session), then
//! prints its link figures.

use heapless::Deque;
use mocap_decoder::Clip;
use mocap_servo::output::ServoOutput;
use mocap_servo::stream::upload::{bitmap_words, Accepted, Play, Upload};
use mocap_servo::stream::{
    encode_frame, FrameReceiver, Message, MAX_CHUNK_LEN, MAX_FRAME_LEN, MAX_POSE_SERVOS,
    PROTOCOL_VERSION,
};

use crate::board::{Rx, CLIP_BUFFER_BYTES, SYSTICK_HZ};
use crate::config::STREAM_TIMEOUT_MS;
use crate::servo::{hex, Driver, Fault, Mode, FIGURE_ID, MAX_SERVOS, PLAYER_WORDS};
use crate::{decoder_glue, ticks, Failure, Out};

/// SysTick ticks without an accepted frame that end the session at rest (`STREAM_TIMEOUT_MS`).
const TIMEOUT_TICKS: u64 = STREAM_TIMEOUT_MS as u64 * SYSTICK_HZ as u64 / 1000;

/// The receive ring between the UART and the frame receiver.
pub const RING_BYTES: usize = 64;
/// A `Status` every this many output ticks (1 s at 50 Hz).
pub const STATUS_EVERY_TICKS: u32 = 50;
/// The most ticks one gap in `Pose.seq` holds the last pose for (1 s at 50 Hz).
pub const MAX_HOLD_TICKS: u16 = 50;
/// Words of the upload's chunk bitmap: one bit per 64-byte chunk of the clip buffer (3 words on
/// the micro:bit, 16 on the LM3S6965, 32 on the MPS2).
pub const BITMAP_WORDS: usize = bitmap_words(CLIP_BUFFER_BYTES);

/// `Status.state`.
#[derive(Clone, Copy)]
#[repr(u8)]
pub enum State {
    /// Nothing playing; the servos hold their last pulses (neutral at start-up).
    Idle = 0,
    /// An upload is in progress.
    Loading = 1,
    /// A complete clip is in the buffer, waiting for `Play`.
    Ready = 2,
    /// Playing the uploaded clip.
    Playing = 3,
    /// Following live poses.
    Live = 4,
    /// The last `Play` was refused: no upload, or a clip corrupt or for another rig.
    Refused = 5,
    /// A `Play` came while chunks are missing: the clip starts when the last one arrives.
    Armed = 6,
}

/// A received message, copied out of the frame receiver.
pub(crate) enum Event {
    Hello,
    Chunk {
        offset: u32,
        total: u32,
        bytes: heapless::Vec<u8, MAX_CHUNK_LEN>,
    },
    Play {
        looped: bool,
    },
    Pose {
        seq: u16,
        pulses: heapless::Vec<u16, MAX_POSE_SERVOS>,
    },
    Stop,
    /// A message the streaming mode does not take (`Status`, a `Hello` of another version, the
    /// show mode's `Show` and `Timecode`).
    Other,
}

impl Event {
    fn from_message(message: &Message<'_>) -> Self {
        match message {
            Message::Hello { version } if *version == PROTOCOL_VERSION => Event::Hello,
            Message::ClipChunk {
                offset,
                total,
                bytes,
            } => match heapless::Vec::from_slice(bytes) {
                Ok(bytes) => Event::Chunk {
                    offset: *offset,
                    total: *total,
                    bytes,
                },
                Err(_) => Event::Other,
            },
            Message::Play { loop_ } => Event::Play { looped: *loop_ },
            Message::Pose { seq, pulses } => Event::Pose {
                seq: *seq,
                pulses: pulses.clone(),
            },
            Message::Stop => Event::Stop,
            _ => Event::Other,
        }
    }
}

/// UART → ring → frame receiver, with the resynchronisation figures.
pub(crate) struct Link {
    rx: Rx,
    ring: Deque<u8, RING_BYTES>,
    frames: FrameReceiver<MAX_FRAME_LEN>,
    /// Bytes taken from the UART.
    bytes: u32,
    /// Bytes of the frame in progress.
    frame_bytes: u32,
    /// The run of dropped frames since the last accepted one: frames and bytes.
    run_frames: u32,
    run_bytes: u32,
    /// Runs ended by an accepted frame; their bytes in all; the longest in bytes and frames.
    resyncs: u32,
    resync_bytes: u32,
    resync_bytes_max: u32,
    resync_frames_max: u32,
    /// SysTick ticks spent on the delimiters: COBS, CRC-32 and postcard of each frame.
    decode_ticks: u64,
    /// Frames ended, accepted or dropped (not the empty ones).
    frames_ended: u32,
    /// Waits that ended in the gap timeout.
    timeouts: u32,
}

impl Link {
    pub(crate) fn new(rx: Rx) -> Self {
        Link {
            rx,
            ring: Deque::new(),
            frames: FrameReceiver::new(),
            bytes: 0,
            frame_bytes: 0,
            run_frames: 0,
            run_bytes: 0,
            resyncs: 0,
            resync_bytes: 0,
            resync_bytes_max: 0,
            resync_frames_max: 0,
            decode_ticks: 0,
            frames_ended: 0,
            timeouts: 0,
        }
    }

    /// Moves waiting bytes from the UART into the ring, as far as it has room (the rest stay
    /// in the UART).
    fn pump(&mut self) {
        while !self.ring.is_full() {
            let Some(byte) = self.rx.read_byte() else {
                return;
            };
            // Cannot fail: the ring is not full.
            let _ = self.ring.push_back(byte);
        }
    }

    /// The next accepted message if its last byte has arrived; never waits.
    pub(crate) fn poll(&mut self) -> Option<Event> {
        self.poll_map(Event::from_message)
    }

    /// [`poll`](Self::poll), the message handed to `f` (the show mode reads it in place).
    pub(crate) fn poll_map<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T> {
        let mut f = Some(f);
        loop {
            self.pump();
            let byte = self.ring.pop_front()?;
            self.bytes = self.bytes.wrapping_add(1);
            self.frame_bytes = self.frame_bytes.wrapping_add(1);
            // Only a delimiter costs more than a store: time those.
            let start = if byte == 0 { Some(ticks::now()) } else { None };
            let pushed = self.frames.push(byte);
            if let (Some(start), Some(_)) = (start, &pushed) {
                self.decode_ticks += u64::from(ticks::since(start, ticks::now()));
                self.frames_ended += 1;
            }
            let event = match pushed {
                None => {
                    if byte == 0 {
                        // An empty frame: counted with the run it interrupts, if any.
                        self.end_frame(false);
                    }
                    continue;
                }
                // `f` is called once: the loop returns after it.
                Some(Ok(message)) => f.take().map(|f| f(&message))?,
                Some(Err(_)) => {
                    self.end_frame(true);
                    continue;
                }
            };
            self.end_frame(false);
            if self.run_frames > 0 {
                self.resyncs += 1;
                self.resync_bytes = self.resync_bytes.saturating_add(self.run_bytes);
                self.resync_bytes_max = self.resync_bytes_max.max(self.run_bytes);
                self.resync_frames_max = self.resync_frames_max.max(self.run_frames);
                self.run_frames = 0;
                self.run_bytes = 0;
            }
            return Some(event);
        }
    }

    /// A frame ended: a dropped one joins the current run, an empty one adds its byte to it.
    fn end_frame(&mut self, dropped: bool) {
        let len = core::mem::take(&mut self.frame_bytes);
        if dropped {
            self.run_frames += 1;
        }
        if self.run_frames > 0 && len > 0 {
            self.run_bytes = self.run_bytes.saturating_add(len);
        }
    }

    /// Waits for the next accepted message; `None` once [`TIMEOUT_TICKS`] SysTick ticks pass
    /// without one after the first byte has arrived (never with `STREAM_TIMEOUT_MS` = 0).
    /// Corrupt frames do not count: only an accepted frame is a sign of life.
    pub(crate) fn wait(&mut self) -> Option<Event> {
        self.wait_map(Event::from_message)
    }

    /// [`wait`](Self::wait), the message handed to `f`.
    pub(crate) fn wait_map<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T> {
        let mut idle = 0u64;
        let mut last = ticks::now();
        let mut f = Some(f);
        loop {
            if let Some(event) = self.poll_map(|m| f.take().map(|f| f(m))) {
                return event;
            }
            // One SysTick wrap at most between two reads: a poll is far shorter.
            let now = ticks::now();
            idle = idle.saturating_add(u64::from(ticks::since(last, now)));
            last = now;
            if TIMEOUT_TICKS != 0 && self.bytes != 0 && idle >= TIMEOUT_TICKS {
                self.timeouts += 1;
                return None;
            }
        }
    }
}

/// The upload into the clip buffer (`mocap_servo::stream::upload`'s rule).
type Clips = Upload<BITMAP_WORDS>;

/// The session's state and counters.
struct Session {
    state: State,
    /// `seq` of the last pose applied (reported in `Status`).
    last_seq: u16,
    /// While following poses: the `seq` of the last one applied.
    live: Option<u16>,
    /// The last pose's pulses (held on a gap).
    targets: [u16; MAX_SERVOS],
    since_status: u32,
    /// Chunks new to the upload, copies of one received, inconsistent ones.
    chunks_accepted: u32,
    chunks_duplicate: u32,
    chunks_rejected: u32,
    /// `Play`s remembered until the upload completes.
    plays_armed: u32,
    clips_played: u32,
    clips_refused: u32,
    /// Clips the decoder failed on while playing (then parked).
    clips_failed: u32,
    poses_applied: u32,
    poses_missing: u32,
    poses_stale: u32,
    poses_rejected: u32,
    held_ticks: u32,
    status_frames: u32,
    other_frames: u32,
}

impl Session {
    fn new() -> Self {
        Session {
            state: State::Idle,
            last_seq: 0,
            live: None,
            targets: [6000; MAX_SERVOS],
            since_status: 0,
            chunks_accepted: 0,
            chunks_duplicate: 0,
            chunks_rejected: 0,
            plays_armed: 0,
            clips_played: 0,
            clips_refused: 0,
            clips_failed: 0,
            poses_applied: 0,
            poses_missing: 0,
            poses_stale: 0,
            poses_rejected: 0,
            held_ticks: 0,
            status_frames: 0,
            other_frames: 0,
        }
    }

    /// Sends `Status` now.
    fn status(&mut self, link: &Link, upload: &Clips, text: &mut Out) -> Result<(), Failure> {
        send(
            text,
            &Message::Status {
                received: link.frames.received(),
                dropped: link.frames.dropped(),
                last_seq: self.last_seq,
                state: self.state as u8,
                chunks: upload.received(),
            },
        )?;
        self.status_frames += 1;
        self.since_status = 0;
        Ok(())
    }

    /// After an output tick: `Status` every [`STATUS_EVERY_TICKS`].
    fn ticked(&mut self, link: &Link, upload: &Clips, text: &mut Out) -> Result<(), Failure> {
        self.since_status += 1;
        if self.since_status >= STATUS_EVERY_TICKS {
            self.status(link, upload, text)?;
        }
        Ok(())
    }

    /// A chunk while the buffer is free: taken if new (the upload is then loading, ready or —
    /// with an armed `Play` — about to play). Returns the armed `Play`'s `loop_` once the
    /// upload is complete.
    fn chunk(
        &mut self,
        upload: &mut Clips,
        buffer: &mut [u8],
        offset: u32,
        total: u32,
        bytes: &[u8],
    ) -> Option<bool> {
        match upload.accept(buffer, offset, total, bytes) {
            Ok(Accepted::New) => self.chunks_accepted += 1,
            Ok(Accepted::Duplicate) => {
                self.chunks_duplicate += 1;
                return None;
            }
            Err(_) => {
                self.chunks_rejected += 1;
                return None;
            }
        }
        self.state = if upload.is_complete() {
            State::Ready
        } else if upload.armed().is_some() {
            State::Armed
        } else {
            State::Loading
        };
        upload.take_armed()
    }

    /// A live pose: ticks holding the last pose for the frames missing before it, then one
    /// tick towards it.
    fn pose<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>>(
        &mut self,
        seq: u16,
        pulses: &[u16],
        driver: &mut Driver<O, S>,
        link: &Link,
        upload: &Clips,
        text: &mut Out,
    ) -> Result<(), Failure> {
        if pulses.len() != driver.rig.count() {
            self.poses_rejected += 1;
            return Ok(());
        }
        let gap = match self.live {
            None => 1,
            Some(last) => seq.wrapping_sub(last),
        };
        if gap == 0 || gap >= 0x8000 {
            self.poses_stale += 1;
            return Ok(());
        }
        let missing = gap - 1;
        self.poses_missing += u32::from(missing);
        for _ in 0..missing.min(MAX_HOLD_TICKS) {
            driver.command(&self.targets, ticks::now(), text)?;
            self.held_ticks += 1;
            self.ticked(link, upload, text)?;
        }
        let start = ticks::now();
        for (t, &p) in self.targets.iter_mut().zip(pulses) {
            *t = p;
        }
        driver.command(&self.targets, start, text)?;
        self.poses_applied += 1;
        self.live = Some(seq);
        self.last_seq = seq;
        self.state = State::Live;
        self.ticked(link, upload, text)
    }
}

/// Writes one frame back to the host (printed as a hex line here, see the module doc).
pub(crate) fn send(text: &mut Out, message: &Message<'_>) -> Result<(), Failure> {
    let mut frame = [0u8; MAX_FRAME_LEN];
    let len = encode_frame(message, &mut frame).map_err(|e| Failure::ServoCrate("frame", e))?;
    text.str("f");
    hex(text, frame.get(..len).unwrap_or(&[]));
    text.nl();
    Ok(())
}

/// How a clip's playback ended.
enum Played {
    /// At its end (not looped).
    Ended,
    /// By a message (`Stop`, `Pose`, `Hello`), to be handled next.
    Interrupted(Event),
    /// The decoder refused the clip (a valid CRC does not make valid codec data).
    Failed,
    /// The e-stop was pressed.
    EStop,
}

/// Plays `clip` (the upload's) from tick 0 (again and again when `looped`), taking frames
/// between ticks.
fn play<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>>(
    clip: &Clip<'_>,
    looped: bool,
    driver: &mut Driver<O, S>,
    link: &mut Link,
    upload: &Clips,
    session: &mut Session,
    text: &mut Out,
) -> Result<Played, Failure> {
    let Ok(mut player) = decoder_glue::new_player::<PLAYER_WORDS>(clip) else {
        return Ok(Played::Failed);
    };
    let n_ticks = driver.rig.tick_count(clip.header().duration_us());
    let mut angles = [0i32; PLAYER_WORDS];
    loop {
        for i in 0..n_ticks {
            let t_us = driver.rig.tick_us(i);
            match driver.clip_tick(&mut player, t_us, &mut angles, text) {
                Err(Failure::Decoder(..)) => return Ok(Played::Failed),
                Err(Failure::EStop) => return Ok(Played::EStop),
                other => other?,
            }
            session.ticked(link, upload, text)?;
            while let Some(event) = link.poll() {
                match event {
                    Event::Stop | Event::Pose { .. } | Event::Hello => {
                        return Ok(Played::Interrupted(event))
                    }
                    // The buffer is the clip being played: checked, never written (the
                    // upload is complete, so a consistent chunk is a copy).
                    Event::Chunk {
                        offset,
                        total,
                        bytes,
                    } => match upload.check(CLIP_BUFFER_BYTES, offset, total, bytes.len()) {
                        Ok(_) => session.chunks_duplicate += 1,
                        Err(_) => session.chunks_rejected += 1,
                    },
                    Event::Play { .. } | Event::Other => session.other_frames += 1,
                }
            }
        }
        if !looped {
            return Ok(Played::Ended);
        }
    }
}

/// The streaming session on the firmware's rig.
pub struct Stream {
    pub calibration_ticks: u32,
}

impl Mode for Stream {
    fn run<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>>(
        self,
        driver: &mut Driver<O, S>,
        text: &mut Out,
    ) -> Result<(), Failure> {
        let mut link = Link::new(Rx::take());
        let mut buffer = [0u8; CLIP_BUFFER_BYTES];
        let mut upload = Clips::new();
        let mut s = Session::new();
        text.str("# mode=stream")
            .kv("servos", driver.rig.count() as u64)
            .kv("rate_mhz", u64::from(driver.rig.rate_mhz()))
            .kv("clip_buffer_bytes", CLIP_BUFFER_BYTES as u64)
            .kv("bitmap_words", BITMAP_WORDS as u64)
            .kv("ring_bytes", RING_BYTES as u64)
            .kv("status_every_ticks", u64::from(STATUS_EVERY_TICKS))
            .kv("timeout_ms", u64::from(STREAM_TIMEOUT_MS))
            .kv("park_ticks_max", u64::from(driver.rig.park_ticks_max()))
            .nl();
        send(
            text,
            &Message::Hello {
                version: PROTOCOL_VERSION,
            },
        )?;
        let mut pending = None;
        // What ended the session early, if anything: the servos then park after it.
        let mut fault = None;
        loop {
            let event = match pending.take() {
                Some(event) => event,
                None => match link.wait() {
                    Some(event) => event,
                    None => {
                        fault = Some(Fault::StreamTimeout);
                        break;
                    }
                },
            };
            // `Some(loop_)`: play the upload now (a `Play`, or the chunk that completes an
            // upload with an armed `Play`).
            let start = match event {
                Event::Hello => {
                    upload.reset();
                    s.live = None;
                    if !matches!(s.state, State::Playing | State::Live) {
                        s.state = State::Idle;
                    }
                    s.status(&link, &upload, text)?;
                    None
                }
                Event::Chunk {
                    offset,
                    total,
                    bytes,
                } => s.chunk(&mut upload, &mut buffer, offset, total, &bytes),
                Event::Play { looped } => match upload.play(looped) {
                    Play::Start => Some(looped),
                    Play::Armed => {
                        s.plays_armed += 1;
                        s.state = State::Armed;
                        s.status(&link, &upload, text)?;
                        None
                    }
                    Play::NoUpload => {
                        s.clips_refused += 1;
                        s.state = State::Refused;
                        s.status(&link, &upload, text)?;
                        None
                    }
                },
                Event::Pose { seq, pulses } => {
                    upload.disarm();
                    match s.pose(seq, &pulses, driver, &link, &upload, text) {
                        Err(Failure::EStop) => {
                            fault = Some(Fault::EStop);
                            break;
                        }
                        other => other?,
                    }
                    None
                }
                Event::Stop => break,
                // The show mode's frames: no show here.
                Event::Other => {
                    s.other_frames += 1;
                    None
                }
            };
            let Some(looped) = start else {
                continue;
            };
            let clip = upload
                .complete(&buffer)
                .and_then(|bytes| decoder_glue::parse(bytes).ok())
                .filter(|clip| FIGURE_ID.compare(clip).is_same());
            let Some(clip) = clip else {
                // Corrupt or another rig's: forget it, so that a later pass can refill it.
                upload.reset();
                s.clips_refused += 1;
                s.state = State::Refused;
                s.status(&link, &upload, text)?;
                continue;
            };
            s.clips_played += 1;
            s.state = State::Playing;
            s.live = None;
            s.status(&link, &upload, text)?;
            let played = play(&clip, looped, driver, &mut link, &upload, &mut s, text)?;
            s.state = State::Ready;
            match played {
                Played::Interrupted(event) => pending = Some(event),
                // The clip ended: back to neutral, end of the session.
                Played::Ended => break,
                Played::Failed => {
                    s.clips_failed += 1;
                    fault = Some(Fault::DecodeError);
                    break;
                }
                Played::EStop => {
                    fault = Some(Fault::EStop);
                    break;
                }
            }
        }
        s.live = None;
        match fault {
            Some(fault) => driver.park_after(fault, text)?,
            None => {
                driver.park(text)?;
            }
        }
        s.state = State::Idle;
        s.status(&link, &upload, text)?;
        report(&link, &s, driver, self.calibration_ticks, text);
        Ok(())
    }
}

/// The link and session figures (`#` lines).
fn report<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>>(
    link: &Link,
    s: &Session,
    driver: &Driver<O, S>,
    calibration_ticks: u32,
    text: &mut Out,
) {
    text.str("# link")
        .kv("rx_bytes", u64::from(link.bytes))
        .kv("frames_received", u64::from(link.frames.received()))
        .kv("frames_dropped", u64::from(link.frames.dropped()))
        .kv("resyncs", u64::from(link.resyncs))
        .kv("resync_bytes_total", u64::from(link.resync_bytes))
        .kv("resync_bytes_max", u64::from(link.resync_bytes_max))
        .kv("resync_frames_max", u64::from(link.resync_frames_max))
        .kv("timeouts", u64::from(link.timeouts))
        .kv(
            "decode_per_frame",
            crate::instructions(link.decode_ticks, calibration_ticks)
                / u64::from(link.frames_ended.max(1)),
        )
        .nl();
    text.str("# session")
        .kv("chunks_accepted", u64::from(s.chunks_accepted))
        .kv("chunks_duplicate", u64::from(s.chunks_duplicate))
        .kv("chunks_rejected", u64::from(s.chunks_rejected))
        .kv("plays_armed", u64::from(s.plays_armed))
        .kv("clips_played", u64::from(s.clips_played))
        .kv("clips_refused", u64::from(s.clips_refused))
        .kv("clips_failed", u64::from(s.clips_failed))
        .kv("poses_applied", u64::from(s.poses_applied))
        .kv("poses_missing", u64::from(s.poses_missing))
        .kv("poses_stale", u64::from(s.poses_stale))
        .kv("poses_rejected", u64::from(s.poses_rejected))
        .kv("held_ticks", u64::from(s.held_ticks))
        .kv("status_frames", u64::from(s.status_frames))
        .kv("other_frames", u64::from(s.other_frames))
        .nl();
    driver.print_stats("stream_ticks", calibration_ticks, text);
    text.str("#")
        .kv("stack_bytes_used", crate::stack::used_bytes() as u64)
        .nl();
}
