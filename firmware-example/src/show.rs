//! Show mode: the embedded `.mcb` is a show (SPEC.md §9: `mocap show build`), run by
//! `mocap_decoder::ShowRunner` — its cue lists, triggers, idle clips, blends — at the figure's
//! tick rate, every tick through the same [`Driver`] (rig limits, speed, the figure's hard
//! limits, then the output) as the servo mode. Commands come over the UART as `Show` frames
//! (SPEC.md §8.2: the same postcard + COBS + CRC link as the streaming mode) and act at their
//! show time; `Timecode` frames make the show clock (`ShowClock`) slew towards an external
//! clock. Output events of the cues (`gpio`, `serial`) print as `# event t_us=… …` lines, the
//! lines `mocap play` prints for the same show and commands.
//!
//! The loop itself — the command queue, lockstep, the runner's tick, replies — is
//! `crate::show_core`, shared with the real boards (`hw/show.rs`); this file gives it the UART
//! link ([`Link`]) and a stage: the [`Driver`], the instruction figures, the printed lines. The
//! show clock starts with the first command (show time 0 is its arrival); a command whose time
//! has passed when it arrives acts at once. The run ends after the tick at an `End` command's
//! time, or once the show is done (no cue list, nothing queued, the last clip ended) with no
//! command waiting; then every servo returns to rest.

use mocap_decoder::{Output, Show, State};
use mocap_servo::output::ServoOutput;
use mocap_servo::stream::Message;

use crate::board::Rx;
use crate::servo::{hex, Driver, Fault, Mode, TickStats, MAX_SERVOS, PLAYER_WORDS};
use crate::show_core::{self, Ended, Fail, Frames, Stage, QUEUE};
use crate::stream::Link;
use crate::{instructions, ticks, Failure, Out};

/// The show runner: two clip players of [`PLAYER_WORDS`] words.
pub type Runner = show_core::Runner<PLAYER_WORDS>;

/// The show in flash.
pub struct ShowMode {
    pub show: Show<'static>,
    pub calibration_ticks: u32,
}

/// The UART link's frames, as the show loop takes them.
impl Frames for Link {
    fn poll_with<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T> {
        self.poll_map(f)
    }

    fn wait_with<T>(&mut self, f: impl FnOnce(&Message<'_>) -> T) -> Option<T> {
        self.wait_map(f)
    }
}

/// The show loop's stage here: the [`Driver`] (limits, hard limits, the recorded output and its
/// line), the instruction figures in and outside blends, `# event` lines and replies printed.
struct Qemu<'d, 't, O, S> {
    driver: &'d mut Driver<O, S>,
    text: &'t mut Out,
    /// SysTick at the start of the tick's work.
    start: u32,
    blend: TickStats,
    plain: TickStats,
}

impl<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>> Stage for Qemu<'_, '_, O, S> {
    type Error = Failure;

    fn tick_us(&self, i: u64) -> u64 {
        self.driver.rig.tick_us(i)
    }

    /// QEMU runs as fast as it can: the tick's time is virtual.
    fn pace(&mut self, _local_us: u64) {}

    fn start(&mut self) {
        self.start = ticks::now();
    }

    fn pose(&mut self, angles: &[i32], state: State) -> Result<bool, Failure> {
        let targets = self.driver.rig.targets(angles);
        let before = self.driver.stats.total_ticks;
        match self.driver.command(&targets, self.start, self.text) {
            Ok(()) => {}
            Err(Failure::EStop) => {
                self.driver.park_after(Fault::EStop, self.text)?;
                return Ok(false);
            }
            Err(e) => return Err(e),
        }
        let spent = self.driver.stats.total_ticks - before;
        let stats = if state == State::Blending {
            &mut self.blend
        } else {
            &mut self.plain
        };
        stats.ticks += 1;
        stats.total_ticks += spent;
        stats.worst_ticks = stats.worst_ticks.max(spent as u32);
        Ok(true)
    }

    fn event(&mut self, at_us: u64, output: &Output<'_>) {
        print_event(at_us, output, self.text);
    }

    fn send(&mut self, message: &Message<'_>) -> Result<(), Failure> {
        crate::stream::send(self.text, message)
    }

    fn timed_out(&mut self) -> Result<(), Failure> {
        self.driver.park_after(Fault::StreamTimeout, self.text)
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
        let mut stage = Qemu {
            driver,
            text,
            start: 0,
            blend: TickStats::default(),
            plain: TickStats::default(),
        };
        let summary = match show_core::run(&mut runner, &mut link, &mut stage) {
            Ok(Ended::Ran(summary)) => summary,
            Ok(Ended::TimedOut) => return Ok(()),
            Err(Fail::Show(e)) => return Err(Failure::Decoder("show", e)),
            Err(Fail::Stage(e)) => return Err(e),
        };
        let Qemu {
            driver,
            text,
            blend,
            plain,
            ..
        } = stage;
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
        text.str("#")
            .kv("commands_rejected", u64::from(summary.rejected))
            .kv("events_dropped", u64::from(summary.events_dropped))
            .kv("timecodes", u64::from(summary.timecodes))
            .kv("relocations", u64::from(summary.relocations))
            .nl();
        text.str("#")
            .kv("stack_bytes_used", crate::stack::used_bytes() as u64)
            .nl();
        Ok(())
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
