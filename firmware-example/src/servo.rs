//! Servo playback: the rig of a servo clip (SPEC.md §3.5) in `mocap_servo::Playback`, the one
//! playback loop of `mocap play` and this firmware (limits, speed, tick clock, return to
//! neutral), which writes every tick's limited pulses through `mocap_servo::output::ServoOutput`,
//! whichever output the build selects (`MOCAP_SERVO`):
//!
//! | `MOCAP_SERVO` | output | device in this build (QEMU) | line per tick |
//! |---|---|---|---|
//! | `maestro` | `MaestroOutput` (Set Target per servo) | UART bytes, recorded | `m 84 00 70 2e …` (hex) |
//! | `ssc32` | `Ssc32Output` (one group move) | UART bytes, recorded | `s #0P1500#1P1625…T20` (no `\r`) |
//! | `pwm` | `PwmOutput` over a `ServoBank` of 16 `SetDutyCycle` channels | `DutyRecorder`s | `p <duty ch0> … <duty ch15>` |
//! | `pca9685` | `Pca9685Output` (pwm-pca9685, 50 Hz) | I²C bus, recorded | `i @40 06 00 00 33 01 @40 …` |
//!
//! QEMU's boards have no observable PWM or PCA9685 and one UART (the console), so the build
//! hands each output a recorder from `mocap_servo::record` and prints what it recorded after
//! each tick; on hardware the same output takes the board's UART, timer channels or I²C bus.
//! The host (`tests/tests/qemu_parity.rs`) drives the same outputs with the same recorders
//! from `mocap play`'s pulses and must read the same lines. Only a tick's work is timed
//! (pose, pulses, limiter, output write), not the printing.
//!
//! Modes: [`FlashClip`] plays the clip embedded in flash (`MOCAP_SERVO` alone); the streaming
//! mode (`MOCAP_STREAM`, `src/stream.rs`) drives the same [`Driver`] from UART frames.

use mocap_decoder::power::{level_at, LevelSampler};
use mocap_decoder::{Clip, Player};
use mocap_servo::output::{MaestroOutput, Pca9685Output, PwmOutput, ServoOutput, Ssc32Output};
use mocap_servo::pca9685::{self, Address, Pca9685Servos};
use mocap_servo::record::{DutyRecorder, I2cRecorder, SerialRecorder};
use mocap_servo::{ssc32, Fit, Identity, OutputError, PlaybackError, ServoBank};

use crate::config::{ESTOP_AT_TICK, POWER};
use crate::{decoder_glue, instructions, ticks, Failure, Out};

use crate::figure::{
    self, Refusal, FIGURE_DIGEST, FIGURE_NAME, FIGURE_SERVOS, HARD_LIMITS, POLICY,
};
pub use crate::figure::{Rig, FIGURE_ID, MAX_SERVOS};

/// Words of the servo player's state: at least one per servo; more let `pca-spline` keep its
/// key-interval cache (SPEC.md §6), which a tick would otherwise recompute.
pub const PLAYER_WORDS: usize = 128;
/// The player of servo clips.
pub type ServoPlayer<'c> = Player<'c, PLAYER_WORDS>;
/// The power levels' sampler (SPEC.md §6.1): two poses of the rig's servos.
pub type Levels = LevelSampler<MAX_SERVOS>;

/// Outputs (`MOCAP_SERVO`, build.rs); 1 (and 0 in the streaming mode) is the Maestro.
const SSC32: u8 = 2;
const PWM: u8 = 3;
const PCA9685: u8 = 4;

/// The simulated PWM peripheral: 16 channels of a 16-bit timer whose period is the 20 ms
/// servo frame (`ServoBank::new`, 50 Hz), so duty = round(pulse · 65535 / 20 000 µs).
const PWM_CHANNELS: usize = 16;
const PWM_MAX_DUTY: u16 = u16::MAX;
/// The PCA9685's I²C address (all address pins low).
const PCA9685_ADDRESS: u8 = 0x40;
/// Serial bytes of one tick (SSC-32 text is the longer).
const TICK_BYTES: usize = ssc32::group_move_max_len(MAX_SERVOS);
/// I²C record of one tick: 2 + 5 bytes per servo and the driver's MODE1 write.
const I2C_RECORD_BYTES: usize = 7 * MAX_SERVOS + 8;
fn playback_failure(e: PlaybackError) -> Failure {
    match e {
        PlaybackError::Limits { error, .. } => Failure::ServoCrate("limits", error),
        PlaybackError::TooManyServos { .. } => Failure::Servo("more servos than MAX_SERVOS"),
        refused => Failure::Figure(refused),
    }
}

/// The playback of a servo clip on this figure: the clip's rig table with its own limits, then
/// the figure's hard limits (`crate::figure`). A clip made for another rig plays only as
/// [`POLICY`] allows (else [`Failure::Figure`]); `# figure …` says which case this is.
pub fn playback_of(clip: &Clip<'_>, text: &mut Out) -> Result<Rig, Failure> {
    let candidate = figure::candidate(clip).map_err(|e| match e {
        Refusal::NoRigTable => Failure::Servo("the clip has no rig table"),
        Refusal::Playback(e) => playback_failure(e),
    })?;
    print_figure(candidate.identity, candidate.fit, text);
    candidate.harden().map_err(playback_failure)
}

/// The figure's own playback (the streaming mode's rig): its servos at its rate, through its
/// hard limits.
pub fn figure_playback(text: &mut Out) -> Result<Rig, Failure> {
    let (rig, fit) = figure::figure_rig().map_err(playback_failure)?;
    print_figure(Identity::Same, fit, text);
    Ok(rig)
}

/// `# figure name=… servos=… digest=… policy=… identity=same|same_table|other_table|other_digest
/// same_rig=0|1 fit=inside|outside|unknown_output [output=N]` (the digest in decimal).
fn print_figure(identity: Identity, fit: Fit, text: &mut Out) {
    text.str("# figure name=")
        .str(FIGURE_NAME)
        .kv("servos", FIGURE_SERVOS.len() as u64)
        .kv("digest", u64::from(FIGURE_DIGEST))
        .str(" policy=")
        .str(POLICY.name())
        .str(" identity=")
        .str(identity.name())
        .kv("same_rig", u64::from(identity.is_same()));
    match fit {
        Fit::Inside => text.str(" fit=inside"),
        Fit::Outside { output } => text.str(" fit=outside").kv("output", u64::from(output)),
        Fit::UnknownOutput { output } => text
            .str(" fit=unknown_output")
            .kv("output", u64::from(output)),
    };
    text.nl();
}

/// Instruction figures of the timed ticks.
#[derive(Default)]
pub struct TickStats {
    pub ticks: u64,
    pub total_ticks: u64,
    pub worst_ticks: u32,
    /// The part spent in `ServoOutput::write`.
    pub output_ticks: u64,
    /// The parts spent sampling the clip (`sample_at` or the power levels' sampler), mapping
    /// angles to pulses (`Playback::targets`) and limiting them (`Playback::limit`: the clip's
    /// limits, then the figure's hard limits).
    pub sample_ticks: u64,
    pub map_ticks: u64,
    pub limit_ticks: u64,
}

/// One playback loop's state: the rig's playback, the output, and what prints a tick's line.
pub struct Driver<O, S> {
    pub rig: Rig,
    output: O,
    show: S,
    pub stats: TickStats,
}

impl<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>> Driver<O, S> {
    fn new(rig: Rig, output: O, show: S) -> Self {
        Driver {
            rig,
            output,
            show,
            stats: TickStats::default(),
        }
    }

    /// One tick towards `targets` (¼ µs, rig order): the limiter, then the output. The tick's
    /// time counts from `start` (SysTick read by the caller before its own work), the
    /// printing of its line does not.
    ///
    /// [`Failure::EStop`] once the e-stop is pressed ([`estop_pressed`]): nothing is commanded;
    /// the caller parks ([`park_after`](Self::park_after)).
    pub fn command(
        &mut self,
        targets: &[u16; MAX_SERVOS],
        start: u32,
        text: &mut Out,
    ) -> Result<(), Failure> {
        if estop_pressed(self.stats.ticks) {
            return Err(Failure::EStop);
        }
        let before_limit = ticks::now();
        self.rig
            .limit(targets)
            .map_err(|e| Failure::ServoCrate("limiter", e))?;
        let before_output = ticks::now();
        self.stats.limit_ticks += u64::from(ticks::since(before_limit, before_output));
        self.rig.write(&mut self.output)?;
        let end = ticks::now();
        let spent = ticks::since(start, end);
        self.stats.output_ticks += u64::from(ticks::since(before_output, end));
        self.stats.ticks += 1;
        self.stats.total_ticks += u64::from(spent);
        self.stats.worst_ticks = self.stats.worst_ticks.max(spent);
        (self.show)(text)
    }

    /// One tick of the clip at `t_us`: `sample_at` (into `angles`, the caller's scratch),
    /// the rig's pulse mapping, [`command`].
    pub fn clip_tick(
        &mut self,
        player: &mut ServoPlayer<'_>,
        t_us: u64,
        angles: &mut [i32; PLAYER_WORDS],
        text: &mut Out,
    ) -> Result<(), Failure> {
        let start = ticks::now();
        decoder_glue::sample_at(player, t_us, angles).map_err(|e| Failure::Decoder("sample", e))?;
        let targets = self.map(angles, start);
        self.command(&targets, start, text)
    }

    /// [`clip_tick`](Self::clip_tick) at tick `tick`'s power level (`config::POWER`, SPEC.md
    /// §6.1): the pose from `levels`, sampled or interpolated.
    pub fn level_tick(
        &mut self,
        levels: &mut Levels,
        player: &mut ServoPlayer<'_>,
        tick: u64,
        angles: &mut [i32; PLAYER_WORDS],
        text: &mut Out,
    ) -> Result<(), Failure> {
        let start = ticks::now();
        levels.set_level(level_at(POWER, self.rig.tick_us(tick)));
        decoder_glue::sample_level(levels, player, tick, angles)
            .map_err(|e| Failure::Decoder("sample", e))?;
        let targets = self.map(angles, start);
        self.command(&targets, start, text)
    }

    /// The pulses of `angles` (`Playback::targets`), the sampling since `start` and the mapping
    /// counted apart.
    fn map(&mut self, angles: &[i32; PLAYER_WORDS], start: u32) -> [u16; MAX_SERVOS] {
        let sampled = ticks::now();
        let targets = self.rig.targets(angles);
        self.stats.sample_ticks += u64::from(ticks::since(start, sampled));
        self.stats.map_ticks += u64::from(ticks::since(sampled, ticks::now()));
        targets
    }

    /// Returns every servo to neutral at its speed limit (nothing when already there); the
    /// ticks it took.
    pub fn park(&mut self, text: &mut Out) -> Result<u32, Failure> {
        let show = &mut self.show;
        let mut n = 0u32;
        self.rig.park(&mut self.output, |_| {
            n = n.saturating_add(1);
            show(text)
        })?;
        Ok(n)
    }

    /// After `fault`: every servo to neutral at its speed (and, with the figure's hard limits,
    /// acceleration) limit, then `# fault=<name> park_ticks=<n> park_ms=<n>`.
    pub fn park_after(&mut self, fault: Fault, text: &mut Out) -> Result<(), Failure> {
        let n = self.park(text)?;
        let mhz = u64::from(self.rig.rate_mhz().max(1));
        text.str("# fault=")
            .str(fault.name())
            .kv("park_ticks", u64::from(n))
            .kv("park_ms", u64::from(n) * 1_000_000 / mhz)
            .nl();
        Ok(())
    }

    /// What the figure's hard limits changed: `# hard_clamp output= ticks= worst_qus=` per
    /// servo they changed, then `# hard_clamps servos= ticks=` (servos changed, ticks in all).
    pub fn print_hard_clamps(&self, text: &mut Out) {
        let mut servos = 0u64;
        let mut all = 0u64;
        for ((servo, &ticks), &worst) in self
            .rig
            .servos()
            .iter()
            .zip(self.rig.hard_clamps())
            .zip(self.rig.hard_worst())
        {
            if ticks == 0 {
                continue;
            }
            servos += 1;
            all += u64::from(ticks);
            text.str("# hard_clamp")
                .kv("output", u64::from(servo.output))
                .kv("ticks", u64::from(ticks))
                .kv("worst_qus", u64::from(worst))
                .nl();
        }
        text.str("# hard_clamps")
            .kv("servos", servos)
            .kv("ticks", all)
            .nl();
    }

    /// Per-tick figures: `# <key>= per_tick= max_tick= output_per_tick= cpu_x10000_at_48mhz=
    /// sample_per_tick= map_per_tick= limit_per_tick=` (the parts of `per_tick`: the clip's
    /// pose, its pulses, the limiter and hard limits; the output's is `output_per_tick`).
    pub fn print_stats(&self, key: &str, calibration_ticks: u32, text: &mut Out) {
        let cal = calibration_ticks;
        let n = self.stats.ticks;
        let per_tick = instructions(self.stats.total_ticks, cal) / n.max(1);
        text.str("#")
            .kv(key, n)
            .kv("per_tick", per_tick)
            .kv(
                "max_tick",
                instructions(u64::from(self.stats.worst_ticks), cal),
            )
            .kv(
                "output_per_tick",
                instructions(self.stats.output_ticks, cal) / n.max(1),
            )
            // Share of a 48 MHz core at one instruction per cycle, in 1/100 %.
            .kv(
                "cpu_x10000_at_48mhz",
                per_tick * u64::from(self.rig.rate_mhz()) / 1000 * 10_000 / 48_000_000,
            )
            .kv(
                "sample_per_tick",
                instructions(self.stats.sample_ticks, cal) / n.max(1),
            )
            .kv(
                "map_per_tick",
                instructions(self.stats.map_ticks, cal) / n.max(1),
            )
            .kv(
                "limit_per_tick",
                instructions(self.stats.limit_ticks, cal) / n.max(1),
            )
            .nl();
    }
}

/// What brings the servos to rest before the motion ends.
#[derive(Clone, Copy)]
pub enum Fault {
    /// No accepted frame for `STREAM_TIMEOUT_MS` (a cut cable, a host that stopped).
    StreamTimeout,
    /// The decoder refused the clip while it played.
    DecodeError,
    /// The e-stop input.
    EStop,
}

impl Fault {
    pub fn name(self) -> &'static str {
        match self {
            Fault::StreamTimeout => "stream_timeout",
            Fault::DecodeError => "decode_error",
            Fault::EStop => "estop",
        }
    }
}

/// Whether the e-stop input is pressed before output tick `tick` (0-based). On a board this
/// reads the e-stop pin; QEMU's boards have no input a test can press, so the build simulates
/// a press at output tick `MOCAP_ESTOP_AT_TICK` (1-based; 0 = never). Once pressed it stays
/// pressed: the firmware parks and ends its run.
fn estop_pressed(tick: u64) -> bool {
    ESTOP_AT_TICK != 0 && tick >= u64::from(ESTOP_AT_TICK).saturating_sub(1)
}

impl<E> From<OutputError<E>> for Failure {
    fn from(e: OutputError<E>) -> Self {
        match e {
            OutputError::Invalid(e) => Failure::ServoCrate("output", e),
            _ => Failure::Servo("output device failed"),
        }
    }
}

/// What runs on a [`Driver`]: the flash clip's playback, or the streaming session.
pub trait Mode {
    fn run<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>>(
        self,
        driver: &mut Driver<O, S>,
        text: &mut Out,
    ) -> Result<(), Failure>;
}

/// Builds the output this firmware was built for (`MOCAP_SERVO`, or the clip slot's) on its
/// recorder, prints its `# output=…` line, and runs `mode` on it.
pub fn drive<M: Mode>(rig: Rig, mode: M, text: &mut Out) -> Result<(), Failure> {
    let all = rig.outputs();
    let outputs = all.get(..rig.count()).unwrap_or(&[]);
    let invalid = |e| Failure::ServoCrate("output", e);
    match crate::servo_output() {
        PWM => {
            let channels: [DutyRecorder; PWM_CHANNELS] =
                core::array::from_fn(|_| DutyRecorder::new(PWM_MAX_DUTY));
            let bank = ServoBank::new(channels.each_ref());
            let period_us = bank.period_us().get();
            let output = PwmOutput::new(bank, outputs).map_err(invalid)?;
            text.str("# output=pwm")
                .kv("channels", PWM_CHANNELS as u64)
                .kv("max_duty", u64::from(PWM_MAX_DUTY))
                .kv("period_us", u64::from(period_us))
                .nl();
            let show = |text: &mut Out| {
                text.str("p");
                for channel in &channels {
                    text.str(" ").u32(u32::from(channel.duty()));
                }
                text.nl();
                Ok(())
            };
            mode.run(&mut Driver::new(rig, output, show), text)
        }
        PCA9685 => {
            let bus = I2cRecorder::<I2C_RECORD_BYTES>::new();
            text.str("# output=pca9685")
                .kv("address", u64::from(PCA9685_ADDRESS))
                .kv("prescale", u64::from(pca9685::PRESCALE_50HZ))
                .nl();
            let device = Pca9685Servos::new(&bus, Address::from(PCA9685_ADDRESS))?;
            // The set-up writes (prescale, wake) on a line of their own.
            print_i2c(&bus, text)?;
            let output = Pca9685Output::new(device, outputs).map_err(invalid)?;
            let show = |text: &mut Out| print_i2c(&bus, text);
            mode.run(&mut Driver::new(rig, output, show), text)
        }
        SSC32 => {
            let port = SerialRecorder::<TICK_BYTES>::new();
            // The tick in ms, rounded (as `mocap play`).
            let mhz = u64::from(rig.rate_mhz().max(1));
            let period_ms = u16::try_from((1_000_000 + mhz / 2) / mhz)
                .unwrap_or(u16::MAX)
                .max(1);
            let output = Ssc32Output::new(&port, outputs, period_ms).map_err(invalid)?;
            text.str("# output=ssc32")
                .kv("time_ms", u64::from(period_ms))
                .nl();
            let show = |text: &mut Out| {
                let printed = port.with_bytes(|bytes| {
                    let line = bytes.strip_suffix(b"\r").unwrap_or(bytes);
                    text.str("s ")
                        .str(core::str::from_utf8(line).unwrap_or("?"))
                        .nl();
                });
                port.clear();
                printed.map_err(|_| Failure::Servo("recorder"))
            };
            mode.run(&mut Driver::new(rig, output, show), text)
        }
        _ => {
            // MOCAP_SERVO=maestro, and the streaming mode's default.
            let port = SerialRecorder::<TICK_BYTES>::new();
            let output = MaestroOutput::new(&port, outputs).map_err(invalid)?;
            text.str("# output=maestro").nl();
            let show = |text: &mut Out| {
                let printed = port.with_bytes(|bytes| {
                    text.str("m");
                    hex(text, bytes);
                    text.nl();
                });
                port.clear();
                printed.map_err(|_| Failure::Servo("recorder"))
            };
            mode.run(&mut Driver::new(rig, output, show), text)
        }
    }
}

/// ` xx` for every byte.
pub fn hex(text: &mut Out, bytes: &[u8]) {
    for &b in bytes {
        text.str(" ");
        hex_byte(text, b);
    }
}

fn hex_byte(text: &mut Out, b: u8) {
    const HEX: &[u8; 16] = b"0123456789abcdef";
    let pair = [HEX[usize::from(b >> 4)], HEX[usize::from(b & 15)]];
    text.str(core::str::from_utf8(&pair).unwrap_or("??"));
}

/// `i @aa xx xx … @aa …`: every I²C write since the last line, then forgets them.
fn print_i2c<const CAP: usize>(bus: &I2cRecorder<CAP>, text: &mut Out) -> Result<(), Failure> {
    text.str("i");
    let printed = bus.for_each_write(|address, bytes| {
        text.str(" @");
        hex_byte(text, address);
        hex(text, bytes);
    });
    text.nl();
    bus.clear();
    printed.map_err(|_| Failure::Servo("recorder"))
}

/// The flash clip at its rig's rate: ticks `0 … tick_count`, then back to neutral.
pub struct FlashClip<'a> {
    pub clip: &'a Clip<'static>,
    pub calibration_ticks: u32,
}

impl Mode for FlashClip<'_> {
    fn run<O: ServoOutput, S: FnMut(&mut Out) -> Result<(), Failure>>(
        self,
        driver: &mut Driver<O, S>,
        text: &mut Out,
    ) -> Result<(), Failure> {
        let mut player =
            decoder_glue::new_player(self.clip).map_err(|e| Failure::Decoder("player", e))?;
        let n_ticks = driver.rig.tick_count(self.clip.header().duration_us());
        text.str("# mode=servo")
            .kv("servos", driver.rig.count() as u64)
            .kv("rate_mhz", u64::from(driver.rig.rate_mhz()))
            .kv("ticks", n_ticks)
            .nl();
        let mut angles = [0i32; PLAYER_WORDS];
        // Power levels (`MOCAP_POWER`) only when a schedule is built in: without one, no
        // sampler's state and the loop as before.
        let mut levels = (!POWER.is_empty()).then(|| Levels::new(driver.rig.rate_mhz()));
        for i in 0..n_ticks {
            let tick = match &mut levels {
                Some(levels) => driver.level_tick(levels, &mut player, i, &mut angles, text),
                None => driver.clip_tick(&mut player, driver.rig.tick_us(i), &mut angles, text),
            };
            match tick {
                Ok(()) => {}
                // Faults end at rest: park first, then report (the park below is then a no-op).
                Err(Failure::EStop) => {
                    driver.park_after(Fault::EStop, text)?;
                    break;
                }
                Err(e @ Failure::Decoder(..)) => {
                    driver.park_after(Fault::DecodeError, text)?;
                    return Err(e);
                }
                Err(e) => return Err(e),
            }
        }
        driver.park(text)?;
        driver.print_hard_clamps(text);
        driver.print_stats("servo_ticks", self.calibration_ticks, text);
        // What the figure's hard limits cost: the table in flash, the stage in the playback.
        text.str("#")
            .kv(
                "hard_table_bytes",
                core::mem::size_of_val(&HARD_LIMITS) as u64,
            )
            .kv(
                "figure_table_bytes",
                core::mem::size_of_val(&FIGURE_SERVOS) as u64,
            )
            .kv(
                "hard_stage_bytes",
                core::mem::size_of::<mocap_servo::HardStage<MAX_SERVOS>>() as u64,
            )
            .kv("playback_bytes", core::mem::size_of::<Rig>() as u64)
            .nl();
        text.str("#")
            .kv("stack_bytes_used", crate::stack::used_bytes() as u64)
            .nl();
        Ok(())
    }
}

/// Servo mode: the flash clip through the selected output.
pub fn run(clip: &Clip<'static>, calibration_ticks: u32, text: &mut Out) -> Result<(), Failure> {
    let rig = playback_of(clip, text)?;
    drive(
        rig,
        FlashClip {
            clip,
            calibration_ticks,
        },
        text,
    )
}
