//! Servo mode (`MOCAP_SERVO=maestro` or `ssc32`): plays a servo clip (one with a rig table, SPEC.md §3.5)
//! the way an animatronic controller does — a fixed-rate tick at the rig's rate, `sample_at`,
//! the rig's integer angle-to-pulse mapping, `mocap_servo::Limiter` (pulse range and speed),
//! then the Pololu Maestro Set Target bytes of every servo or one SSC-32 group move — and
//! finally brings every servo back to neutral at its speed limit. Each tick is printed as one
//! line — Maestro bytes as hex (`m 84 00 70 2e …`), SSC-32 as its text without the `\r`
//! (`s #0P1500#1P1625T20`) — which the host's `mocap play … --protocol maestro|ssc32` must
//! reproduce byte for byte. Only the tick's work is timed, not the printing.

use mocap_decoder::{tick_count, tick_us, Clip, Player, RigServo};
use mocap_servo::{maestro, ssc32, Limiter, ServoLimits};

use crate::config::SERVO;
use crate::{decoder_glue, instructions, ticks, Failure, Out, MAX_CHANNELS};

/// Bytes of one tick's commands (SSC-32 text is the longer).
const TICK_BYTES: usize = ssc32::group_move_max_len(MAX_SERVOS);

/// Most servos of a rig in this firmware.
pub const MAX_SERVOS: usize = 32;
/// Bound on the ticks of the return to neutral.
const MAX_STOP_TICKS: u32 = 100_000;

/// Everything one tick needs.
struct Rig {
    servos: [RigServo; MAX_SERVOS],
    count: usize,
    limiter: Limiter<MAX_SERVOS>,
    rate_mhz: u32,
}

pub fn run(clip: &Clip<'static>, calibration_ticks: u32, text: &mut Out) -> Result<(), Failure> {
    let table = clip
        .rig()
        .ok_or(Failure::Servo("the clip has no rig table"))?;
    let rate_mhz = table.rate_mhz();
    let idle = RigServo {
        output: 0,
        angle_lo_mdeg: 0,
        angle_hi_mdeg: 1,
        pulse_lo_qus: 6000,
        pulse_hi_qus: 6000,
        neutral_qus: 6000,
        max_speed_mdeg_s: 0,
    };
    let mut servos = [idle; MAX_SERVOS];
    let mut count = 0;
    for (slot, s) in servos.iter_mut().zip(table.servos()) {
        *slot = s;
        count += 1;
    }
    if table.servo_count() > MAX_SERVOS {
        return Err(Failure::Servo("more servos than MAX_SERVOS"));
    }
    let mut limits = [ServoLimits {
        min_qus: 6000,
        max_qus: 6000,
        neutral_qus: 6000,
        max_step_qus: 0,
    }; MAX_SERVOS];
    for (l, s) in limits.iter_mut().zip(&servos).take(count) {
        let (lo, hi) = s.pulse_range_qus();
        *l = ServoLimits::new(lo, hi, s.neutral_qus, s.max_step_qus(rate_mhz))
            .map_err(|_| Failure::Servo("invalid limits"))?;
    }
    let limiter = Limiter::new(limits).map_err(|_| Failure::Servo("invalid limits"))?;
    let mut rig = Rig {
        servos,
        count,
        limiter,
        rate_mhz,
    };
    let mut player = decoder_glue::new_player(clip).map_err(|e| Failure::Decoder("player", e))?;
    let duration_us = clip.header().duration_us();
    let n_ticks = tick_count(duration_us, rate_mhz);
    text.str("# mode=servo protocol=")
        .str(if SERVO == 2 { "ssc32" } else { "maestro" })
        .kv("servos", count as u64)
        .kv("rate_mhz", u64::from(rate_mhz))
        .kv("ticks", n_ticks)
        .nl();

    let mut out = [0i32; MAX_CHANNELS];
    let mut held = [0u16; MAX_SERVOS];
    let mut bytes = [0u8; TICK_BYTES];
    let (mut total, mut worst) = (0u64, 0u32);
    for i in 0..n_ticks {
        let start = ticks::now();
        let len = tick(
            &mut rig,
            &mut player,
            tick_us(i, rate_mhz),
            &mut out,
            &mut held,
            &mut bytes,
        )?;
        let spent = ticks::since(start, ticks::now());
        total += u64::from(spent);
        worst = worst.max(spent);
        print_tick(text, bytes.get(..len).unwrap_or(&[]));
    }
    for _ in 0..MAX_STOP_TICKS {
        let done = rig
            .limiter
            .stop_step(&mut held)
            .map_err(|_| Failure::Servo("stop"))?;
        let len = encode(&rig, &held, &mut bytes)?;
        print_tick(text, bytes.get(..len).unwrap_or(&[]));
        if done {
            break;
        }
    }
    let cal = calibration_ticks;
    let per_tick = instructions(total, cal) / n_ticks.max(1);
    text.str("#")
        .kv("servo_ticks", n_ticks)
        .kv("per_tick", per_tick)
        .kv("max_tick", instructions(u64::from(worst), cal))
        // Share of a 48 MHz core at one instruction per cycle, in 1/100 %.
        .kv(
            "cpu_x10000_at_48mhz",
            per_tick * u64::from(rate_mhz) / 1000 * 10_000 / 48_000_000,
        )
        .nl();
    text.str("#")
        .kv("stack_bytes_used", crate::stack::used_bytes() as u64)
        .nl();
    Ok(())
}

/// One servo tick: pose at `t_us`, pulses, limits, command bytes; returns their length.
#[inline(never)]
fn tick(
    rig: &mut Rig,
    player: &mut Player<'static, MAX_CHANNELS>,
    t_us: u64,
    out: &mut [i32; MAX_CHANNELS],
    held: &mut [u16; MAX_SERVOS],
    bytes: &mut [u8; TICK_BYTES],
) -> Result<usize, Failure> {
    decoder_glue::sample_at(player, t_us, out).map_err(|e| Failure::Decoder("sample", e))?;
    let mut targets = [6000u16; MAX_SERVOS];
    for ((t, s), v) in targets
        .iter_mut()
        .zip(&rig.servos)
        .zip(out.iter())
        .take(rig.count)
    {
        *t = s.pulse_qus(*v);
    }
    rig.limiter
        .apply(&targets, held)
        .map_err(|_| Failure::Servo("limiter"))?;
    encode(rig, held, bytes)
}

fn encode(rig: &Rig, held: &[u16; MAX_SERVOS], bytes: &mut [u8]) -> Result<usize, Failure> {
    if SERVO == 2 {
        // One group move: the rig's outputs must be consecutive, in rig order.
        let first = rig.servos.first().map_or(0, |s| s.output);
        let in_order = rig
            .servos
            .iter()
            .take(rig.count)
            .enumerate()
            .all(|(i, s)| usize::from(s.output) == usize::from(first) + i);
        let first = u8::try_from(first).map_err(|_| Failure::Servo("output above 255"))?;
        if !in_order {
            return Err(Failure::Servo(
                "ssc32 needs consecutive outputs in rig order",
            ));
        }
        // The tick in ms, rounded (as `mocap play`).
        let mhz = u64::from(rig.rate_mhz.max(1));
        let period_ms = (1_000_000 + mhz / 2) / mhz;
        let time_ms = u16::try_from(period_ms).unwrap_or(u16::MAX).max(1);
        let pulses = held.get(..rig.count).unwrap_or(&[]);
        return ssc32::group_move(first, pulses, time_ms, bytes)
            .map_err(|_| Failure::Servo("ssc32"));
    }
    let mut at = 0;
    for (s, &p) in rig.servos.iter().zip(held.iter()).take(rig.count) {
        let ch = u8::try_from(s.output).map_err(|_| Failure::Servo("output above 255"))?;
        let dst = bytes.get_mut(at..).unwrap_or(&mut []);
        at += maestro::set_target(ch, p, dst).map_err(|_| Failure::Servo("maestro"))?;
    }
    Ok(at)
}

fn print_tick(text: &mut Out, bytes: &[u8]) {
    if SERVO == 2 {
        let line = bytes.strip_suffix(b"\r").unwrap_or(bytes);
        text.str("s ")
            .str(core::str::from_utf8(line).unwrap_or("?"))
            .nl();
        return;
    }
    const HEX: &[u8; 16] = b"0123456789abcdef";
    text.str("m");
    for b in bytes {
        let pair = [HEX[usize::from(b >> 4)], HEX[usize::from(b & 15)]];
        text.str(" ")
            .str(core::str::from_utf8(&pair).unwrap_or("??"));
    }
    text.nl();
}
