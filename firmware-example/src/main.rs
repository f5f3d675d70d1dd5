//! mocap-firmware: plays the `.mcb` clip embedded in flash and prints every decoded frame on
//! the board's UART, then decode statistics, then exits through semihosting (QEMU's exit code).
//! Built with `MOCAP_SAMPLE_US=P`, it prints `Player::sample_at` at t = 0, P, 2P, … instead
//! (up to and including the first t past the clip's duration). Built with `MOCAP_SERVO`, it
//! plays a servo clip through a servo output (`servo.rs`); with `MOCAP_STREAM=1`, it takes
//! clips and live poses from its UART (`stream.rs`); with `MOCAP_ENTROPY_BENCH=1`, it times
//! the entropy coder instead (`entropy_bench.rs`).
//!
//! Output format: see README.md. Lines starting with `#` are metadata; every other line is
//! one frame (or sample) and must be byte-identical to the host decoder's output for the clip.
#![no_std]
#![no_main]

// The core: Cortex-M or RISC-V.
#[cfg_attr(target_arch = "arm", path = "arch/cortex_m.rs")]
#[cfg_attr(target_arch = "riscv32", path = "arch/riscv.rs")]
mod arch;
mod board;
mod entropy_bench;
mod figure;
mod servo;
mod show;
mod show_core;
mod slot;
mod stream;
mod text;

use core::mem::size_of;

use mocap_decoder::{Clip, Error, Player};

use arch::{exit, ticks};
use board::Uart;
use text::Text;

/// Channel capacity of the player, its state in words (build.rs: `MOCAP_PLAYER_WORDS`, default
/// 320: enough for a full BVH skeleton).
const MAX_CHANNELS: usize = config::PLAYER_WORDS;

/// The clip, chosen at build time (build.rs: `MOCAP_CLIP`, default `clips/demo.mcb`).
static CLIP: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/clip.mcb"));

/// A run setting: the build's, or in a clip-slot build (`MOCAP_CLIP_SLOT`) the one written into
/// the slot (`slot.rs`). `CLIP_SLOT` is a constant, so the embedding build keeps its constants.
fn built_or_slot<T>(built: T, slot: impl FnOnce() -> T) -> T {
    if CLIP_SLOT == 0 {
        built
    } else {
        slot()
    }
}

/// The clip this run plays.
fn clip_bytes() -> &'static [u8] {
    built_or_slot(CLIP, slot::clip)
}

/// Playback mode, chosen at build time (build.rs: `MOCAP_SAMPLE_US`).
mod config {
    include!(concat!(env!("OUT_DIR"), "/config.rs"));
}
use config::{CLIP_SLOT, ENTROPY_BENCH, SAMPLE_US, SERVO, STREAM};

/// The sampling period in µs (`MOCAP_SAMPLE_US` or the slot's); 0 plays every frame.
fn sample_us() -> u64 {
    built_or_slot(SAMPLE_US, slot::sample_us)
}

/// The servo output (`MOCAP_SERVO`'s number or the slot's); 0 none.
fn servo_output() -> u8 {
    built_or_slot(SERVO, slot::servo)
}

/// Whether this run samples with `sample_at` (else it plays every frame with `next_frame`).
fn sampling() -> bool {
    sample_us() != 0
}

type Out = Text<Uart>;

/// Calls into the decoder, kept out of line so that `scripts/firmware.sh size` can attribute
/// code to the decoder by symbol name even after LTO has inlined the decoder's internals here.
mod decoder_glue {
    use super::{Clip, Error, Player, MAX_CHANNELS};

    #[inline(never)]
    pub fn parse(bytes: &[u8]) -> Result<Clip<'_>, Error> {
        Clip::parse(bytes)
    }

    #[inline(never)]
    pub fn parse_show(bytes: &[u8]) -> Result<mocap_decoder::Show<'_>, Error> {
        mocap_decoder::Show::parse(bytes)
    }

    #[inline(never)]
    pub fn new_player<'c, const N: usize>(clip: &Clip<'c>) -> Result<Player<'c, N>, Error> {
        Player::new(clip)
    }

    #[inline(never)]
    pub fn next_frame(
        player: &mut Player<'static, MAX_CHANNELS>,
        out: &mut [i32; MAX_CHANNELS],
    ) -> Result<Option<u32>, Error> {
        player.next_frame(out)
    }

    #[inline(never)]
    pub fn sample_at<const N: usize>(
        player: &mut Player<'_, N>,
        t_us: u64,
        out: &mut [i32; N],
    ) -> Result<(), Error> {
        player.sample_at(t_us, out)
    }

    #[inline(never)]
    pub fn sample_level<const C: usize, const N: usize>(
        levels: &mut mocap_decoder::power::LevelSampler<C>,
        player: &mut Player<'_, N>,
        tick: u64,
        out: &mut [i32; N],
    ) -> Result<(), Error> {
        levels.sample(player, tick, out)
    }
}

/// Instructions executed by [`arch::spin`] in the calibration (2 per iteration).
const CALIBRATION_INSTRUCTIONS: u32 = 2 * CALIBRATION_ITERATIONS;
const CALIBRATION_ITERATIONS: u32 = 1_000_000;

/// Ticks that [`CALIBRATION_INSTRUCTIONS`] instructions take.
fn calibrate() -> u32 {
    let t0 = ticks::now();
    arch::spin(CALIBRATION_ITERATIONS);
    ticks::since(t0, ticks::now())
}

/// Converts ticks into instructions with the calibration (0 if SysTick did not run).
fn instructions(ticks: u64, calibration_ticks: u32) -> u64 {
    if calibration_ticks == 0 {
        return 0;
    }
    let cal = u64::from(calibration_ticks);
    (ticks * u64::from(CALIBRATION_INSTRUCTIONS) + cal / 2) / cal
}

/// Stack high-water mark: paint the free RAM between the end of .bss and the stack pointer,
/// later count how much of the paint was overwritten.
mod stack {
    use core::ptr::{addr_of, read_volatile, write_volatile};

    const PAINT: u32 = 0xA5C3_5A3C;

    extern "C" {
        // cortex-m-rt and riscv-rt alike:
        static __sheap: u32; // first free word after .bss/.uninit
        static _stack_start: u32; // initial stack pointer (top of RAM)
    }

    #[allow(unused_unsafe)] // taking the address of an extern static became safe in Rust 1.82
    fn bottom() -> usize {
        // SAFETY: only the address of the linker symbol is taken.
        unsafe { addr_of!(__sheap) as usize }
    }

    #[allow(unused_unsafe)]
    fn top() -> usize {
        // SAFETY: as above.
        unsafe { addr_of!(_stack_start) as usize }
    }

    #[inline(never)]
    pub fn paint() {
        let sp = crate::arch::stack_pointer();
        // Leave a margin below this function's frame.
        let end = sp.saturating_sub(64) & !3;
        let mut p = bottom();
        while p < end {
            // SAFETY: free RAM between the statics and the live stack, owned by nothing.
            unsafe { write_volatile(p as *mut u32, PAINT) };
            p += 4;
        }
    }

    /// The lowest stack address written since the last [`paint`].
    #[inline(never)]
    fn lowest_written() -> usize {
        let mut p = bottom();
        // SAFETY: reads RAM between the statics and the stack top.
        while p < top() && unsafe { read_volatile(p as *const u32) } == PAINT {
            p += 4;
        }
        p
    }

    #[inline(never)]
    pub fn used_bytes() -> usize {
        top() - lowest_written()
    }

    /// Stack below `sp` (a caller's stack pointer) written since the last [`paint`]: what the
    /// calls made from that frame used. An upper bound: the few words between `paint`'s own
    /// frame and `sp` are counted whether written or not.
    #[inline(never)]
    pub fn used_below(sp: usize) -> usize {
        sp.saturating_sub(lowest_written())
    }
}

/// Why the run failed.
enum Failure {
    Decoder(&'static str, Error),
    Servo(&'static str),
    ServoCrate(&'static str, mocap_servo::Error),
    /// The e-stop was pressed (the caller parks the servos).
    EStop,
    /// The figure refuses the clip (made for another rig, by the policy; or an output it lacks).
    Figure(mocap_servo::PlaybackError),
    FrameIndex {
        expected: u32,
        got: u32,
    },
    FrameCount {
        header: u32,
        decoded: u32,
    },
    SampleCount {
        expected: u32,
        got: u32,
    },
}

/// Number of samples in sample mode: t = 0, P, 2P, … up to and including the first t past
/// `duration_us`, that is ⌊duration / P⌋ + 2.
fn sample_count(duration_us: u64) -> u64 {
    // `checked_div`: this also compiles (unused) in frame mode, where the period is 0.
    duration_us.checked_div(sample_us()).unwrap_or(0) + 2
}

/// The output lines of one run: every frame in order (`next_frame`), or in sample mode
/// `sample_at(t)` for t = 0, P, 2P, … up to and including the first t past the duration.
struct Playback {
    player: Player<'static, MAX_CHANNELS>,
    /// Lines produced so far.
    produced: u32,
    /// Sample mode: the next sample's time, and whether the last one has been produced.
    t_us: u64,
    duration_us: u64,
    done: bool,
}

impl Playback {
    fn new(clip: &Clip<'static>) -> Result<Self, Failure> {
        Ok(Playback {
            player: decoder_glue::new_player(clip).map_err(|e| Failure::Decoder("player", e))?,
            produced: 0,
            t_us: 0,
            duration_us: clip.header().duration_us(),
            done: false,
        })
    }

    /// Produces the next line into `out`; `Ok(false)` once there is none left.
    #[inline(always)]
    fn step(&mut self, out: &mut [i32; MAX_CHANNELS]) -> Result<bool, Failure> {
        if sampling() {
            if self.done {
                return Ok(false);
            }
            let t = self.t_us;
            decoder_glue::sample_at(&mut self.player, t, out)
                .map_err(|e| Failure::Decoder("sample", e))?;
            self.produced += 1;
            if t > self.duration_us {
                self.done = true;
            } else {
                self.t_us = t + sample_us();
            }
            return Ok(true);
        }
        match decoder_glue::next_frame(&mut self.player, out) {
            Ok(Some(index)) => {
                if index != self.produced {
                    return Err(Failure::FrameIndex {
                        expected: self.produced,
                        got: index,
                    });
                }
                self.produced += 1;
                Ok(true)
            }
            Ok(None) => Ok(false),
            Err(e) => Err(Failure::Decoder("frame", e)),
        }
    }
}

/// Figures of the timed pass.
struct Timing {
    /// Frames, or samples in sample mode.
    lines: u32,
    total_ticks: u64,
    max_line_ticks: u32,
    /// Peak stack of the playback path: the decoder's calls below the frame that holds the
    /// player and the pose (those two are counted apart, `state_bytes` and the pose's 4 bytes per
    /// channel).
    playback_stack_bytes: usize,
}

/// Pass 1: decode every frame (or sample), timing only the decoder (no output in the measured
/// spans). Telescoping reads: each read ends one span and starts the next, so the sum is exact.
#[inline(never)]
fn timed_pass(clip: &Clip<'static>) -> Result<Timing, Failure> {
    let mut playback = Playback::new(clip)?;
    let mut out = [0i32; MAX_CHANNELS];
    let mut timing = Timing {
        lines: 0,
        total_ticks: 0,
        max_line_ticks: 0,
        playback_stack_bytes: 0,
    };
    // Paint again below this frame: what the decoder's calls write is then the playback path's
    // own stack, whatever ran deeper before.
    let sp = arch::stack_pointer();
    stack::paint();
    let mut prev = ticks::now();
    loop {
        let more = playback.step(&mut out)?;
        let now = ticks::now();
        let spent = ticks::since(prev, now);
        prev = now;
        if !more {
            timing.playback_stack_bytes = stack::used_below(sp);
            return Ok(timing);
        }
        timing.lines += 1;
        timing.total_ticks += u64::from(spent);
        timing.max_line_ticks = timing.max_line_ticks.max(spent);
    }
}

/// Pass 2: decode again and print every frame (or sample).
#[inline(never)]
fn print_pass(clip: &Clip<'static>, text: &mut Out) -> Result<u32, Failure> {
    let mut playback = Playback::new(clip)?;
    let channels = playback.player.channel_count();
    let mut out = [0i32; MAX_CHANNELS];
    while playback.step(&mut out)? {
        for (i, value) in out.iter().take(channels).enumerate() {
            if i > 0 {
                text.str(" ");
            }
            text.i32(*value);
        }
        text.nl();
    }
    Ok(playback.produced)
}

fn run(text: &mut Out) -> Result<(), Failure> {
    let calibration_ticks = calibrate();

    let bytes = clip_bytes();
    if bytes.get(4) == Some(&mocap_decoder::consts::VERSION_SHOW) {
        // A show (SPEC.md §9): its clips share the figure's rig table.
        let show = decoder_glue::parse_show(bytes).map_err(|e| Failure::Decoder("parse", e))?;
        let first = show.clip(0).map_err(|e| Failure::Decoder("parse", e))?;
        let rig = servo::playback_of(&first, text)?;
        return servo::drive(
            rig,
            show::ShowMode {
                show,
                calibration_ticks,
            },
            text,
        );
    }
    let t0 = ticks::now();
    let clip = decoder_glue::parse(bytes).map_err(|e| Failure::Decoder("parse", e))?;
    let parse_ticks = ticks::since(t0, ticks::now());

    if STREAM {
        // The figure compiled in gives the rig (servos, limits, rate, hard limits); the motion
        // comes over the UART.
        let rig = servo::figure_playback(text)?;
        return servo::drive(rig, stream::Stream { calibration_ticks }, text);
    }
    if servo_output() != 0 {
        return servo::run(&clip, calibration_ticks, text);
    }
    let header_frames = clip.header().frame_count();
    let channels = clip.header().channel_count();
    text.str("# mocap-firmware clip")
        .kv("frames", u64::from(header_frames))
        .kv("channels", channels as u64)
        .nl();
    let duration_us = clip.header().duration_us();
    if sampling() {
        text.str("# mode=sample")
            .kv("sample_us", sample_us())
            .kv("samples", sample_count(duration_us))
            .kv("duration_us", duration_us)
            .nl();
    } else {
        text.str("# mode=frames").nl();
    }

    // Player::new alone, timed; the player is not kept.
    let new_ticks = {
        let t0 = ticks::now();
        let _player = decoder_glue::new_player::<MAX_CHANNELS>(&clip)
            .map_err(|e| Failure::Decoder("player", e))?;
        ticks::since(t0, ticks::now())
    };

    // The peak so far (parse, the header's lines): the timed pass paints the stack again.
    let boot_stack_bytes = stack::used_bytes();
    let timing = timed_pass(&clip)?;
    let printed = print_pass(&clip, text)?;
    if sampling() {
        let expected = sample_count(duration_us);
        if u64::from(timing.lines) != expected || u64::from(printed) != expected {
            return Err(Failure::SampleCount {
                expected: expected.min(u64::from(u32::MAX)) as u32,
                got: timing.lines.min(printed),
            });
        }
    } else if timing.lines != header_frames || printed != header_frames {
        return Err(Failure::FrameCount {
            header: header_frames,
            decoded: timing.lines.min(printed),
        });
    }

    // ---- statistics (all `# ` lines; excluded from host comparisons)
    let cal = calibration_ticks;
    // Per output line: per frame, or per sample in sample mode.
    let (count_key, per_key, max_key) = if sampling() {
        ("samples", "per_sample", "max_sample")
    } else {
        ("frames", "per_frame", "max_frame")
    };
    let lines = u64::from(timing.lines.max(1));
    let values = lines * (channels.max(1) as u64);
    let decode = instructions(timing.total_ticks, cal);
    let parse = instructions(u64::from(parse_ticks), cal);
    let new = instructions(u64::from(new_ticks), cal);
    let total = parse + new + decode;
    text.str("# board=")
        .str(board::NAME)
        .kv("max_channels", MAX_CHANNELS as u64)
        .nl();
    text.str("#")
        .kv("instructions_total", total)
        .kv(count_key, u64::from(timing.lines))
        .kv(per_key, total / lines)
        .kv("per_channel_x100", total * 100 / values)
        .nl();
    text.str("#")
        .kv("decode_instructions_total", decode)
        .kv(count_key, u64::from(timing.lines))
        .kv(per_key, decode / lines)
        .kv("per_channel_x100", decode * 100 / values)
        .kv(max_key, instructions(u64::from(timing.max_line_ticks), cal))
        .nl();
    text.str("#")
        .kv("parse_instructions", parse)
        .kv("player_new_instructions", new)
        .nl();
    text.str("#")
        .kv(
            "calibration_instructions",
            u64::from(CALIBRATION_INSTRUCTIONS),
        )
        .kv("calibration_ticks", u64::from(cal))
        .kv("instructions_per_tick", instructions(1, cal))
        .kv("decode_ticks", timing.total_ticks)
        .nl();
    text.str("#")
        .kv(
            "state_bytes",
            size_of::<Player<'static, MAX_CHANNELS>>() as u64,
        )
        .nl();
    text.str("#")
        .kv("flash_clip_bytes", bytes.len() as u64)
        .nl();
    text.str("#")
        .kv(
            "stack_bytes_used",
            stack::used_bytes().max(boot_stack_bytes) as u64,
        )
        .kv("playback_stack_bytes", timing.playback_stack_bytes as u64)
        .nl();
    Ok(())
}

fn report(text: &mut Out, failure: &Failure) {
    match failure {
        Failure::Decoder(phase, error) => {
            text.str("# error ").str(phase).str(": ");
            // core::fmt only on this path; the error's Display says which SPEC.md rule broke.
            let _ = core::fmt::write(&mut FmtAdapter(text), format_args!("{error}"));
            text.nl();
        }
        Failure::Servo(what) => {
            text.str("# error servo: ").str(what).nl();
        }
        Failure::ServoCrate(what, error) => {
            text.str("# error servo ").str(what).str(": ");
            let _ = core::fmt::write(&mut FmtAdapter(text), format_args!("{error}"));
            text.nl();
        }
        Failure::EStop => {
            text.str("# error estop").nl();
        }
        Failure::Figure(error) => {
            text.str("# error figure: ");
            let _ = core::fmt::write(&mut FmtAdapter(text), format_args!("{error}"));
            text.nl();
        }
        Failure::FrameIndex { expected, got } => {
            text.str("# error frame_index")
                .kv("expected", u64::from(*expected))
                .kv("got", u64::from(*got))
                .nl();
        }
        Failure::FrameCount { header, decoded } => {
            text.str("# error frame_count")
                .kv("header", u64::from(*header))
                .kv("decoded", u64::from(*decoded))
                .nl();
        }
        Failure::SampleCount { expected, got } => {
            text.str("# error sample_count")
                .kv("expected", u64::from(*expected))
                .kv("got", u64::from(*got))
                .nl();
        }
    }
}

struct FmtAdapter<'t>(&'t mut Out);

impl core::fmt::Write for FmtAdapter<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.str(s);
        Ok(())
    }
}

#[arch::entry]
fn main() -> ! {
    stack::paint();
    let mut text = Text(Uart::init());
    if !ticks::start() {
        text.str("# error peripherals already taken\n");
        exit(false);
    }

    if ENTROPY_BENCH {
        let ok = entropy_bench::run(&mut text);
        text.str("# end\n");
        exit(ok)
    }
    let ok = match run(&mut text) {
        Ok(()) => true,
        Err(failure) => {
            report(&mut text, &failure);
            false
        }
    };
    text.str("# end\n");
    exit(ok)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    let mut text = Text(Uart::steal());
    text.str("\n# error panic\n# end\n");
    exit(false)
}
