//! The figure's own hard limits: what the mechanism allows, whatever the
//! clip, show or stream asks for.
//!
//! A clip carries the limits of the rig it was encoded for; a figure's
//! firmware also knows its own ([`HardLimit`], one per controller output:
//! pulse range, neutral, speed and acceleration, in physical units so one
//! table serves every tick rate). [`HardStage`] applies them *after* the
//! clip's own shaping ([`crate::Limiter`]): every pulse the playback loop
//! writes passes both. Its state is the last pulse and the velocity of each
//! servo, so acceleration is limited too, and a return to rest goes to the
//! figure's neutral at the figure's speed and acceleration.
//!
//! [`HardLimits::fit`] tells whether a rig lies inside the figure's limits
//! (every output known, every pulse range and neutral inside); the caller
//! applies its policy ([`Policy`]) with it.

use mocap_decoder::{DigestServo, RigServo};

use crate::ServoLimits;

/// One output of the figure: the pulses its mechanism allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HardLimit {
    /// Controller output (the rig's `output`).
    pub output: u16,
    /// Lowest pulse, ¼ µs.
    pub min_qus: u16,
    /// Highest pulse, ¼ µs.
    pub max_qus: u16,
    /// Rest pulse, ¼ µs, in `min_qus..=max_qus`.
    pub neutral_qus: u16,
    /// Most the pulse may change per second, ¼ µs/s; 0 = no limit.
    pub max_speed_qus_s: u32,
    /// Most the pulse's speed may change per second, ¼ µs/s²; 0 = no limit.
    pub max_accel_qus_s2: u32,
}

/// What to do with a clip whose rig is not the figure's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Policy {
    /// Refuse it.
    Refuse,
    /// Play it, through the hard limits, if its every servo lies inside
    /// them ([`Fit::Inside`]); refuse it otherwise.
    ClampIfInside,
    /// Play it through the hard limits whatever its rig says (every output
    /// must still be one of the figure's).
    ClampAlways,
}

impl Policy {
    /// Every policy, by its name: the spelling of `mocap play --policy` and
    /// of the firmware's build option (`MOCAP_POLICY`).
    pub const ALL: [(Policy, &'static str); 3] = [
        (Policy::Refuse, "refuse"),
        (Policy::ClampIfInside, "clamp-if-inside"),
        (Policy::ClampAlways, "clamp"),
    ];

    /// The policy of a name ([`Policy::ALL`]).
    pub fn from_name(name: &str) -> Option<Policy> {
        Self::ALL.iter().find(|(_, n)| *n == name).map(|(p, _)| *p)
    }

    /// This policy's name ([`Policy::ALL`]).
    pub fn name(self) -> &'static str {
        match self {
            Policy::Refuse => "refuse",
            Policy::ClampIfInside => "clamp-if-inside",
            Policy::ClampAlways => "clamp",
        }
    }
}

/// How a rig lies against the figure's hard limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fit {
    /// Every servo's output is the figure's, and its pulse range and neutral
    /// lie inside that output's limits.
    Inside,
    /// A servo's pulse range or neutral leaves its output's limits.
    Outside {
        /// The servo's output.
        output: u16,
    },
    /// A servo drives an output the figure does not have.
    UnknownOutput {
        /// The servo's output.
        output: u16,
    },
}

/// A figure's hard limits: one [`HardLimit`] per output it has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HardLimits<'a> {
    limits: &'a [HardLimit],
}

impl<'a> HardLimits<'a> {
    /// The figure's outputs (any order; the first entry of an output counts).
    pub const fn new(limits: &'a [HardLimit]) -> Self {
        HardLimits { limits }
    }

    /// Every output's limits.
    pub const fn all(&self) -> &'a [HardLimit] {
        self.limits
    }

    /// The limits of `output`, if the figure has it.
    pub fn get(&self, output: u16) -> Option<&'a HardLimit> {
        self.limits.iter().find(|l| l.output == output)
    }

    /// The rig digest (SPEC.md §3.6) of `servos` at `rate_mhz` with these
    /// limits' speed and acceleration for their outputs (none for an output
    /// these limits lack): what a clip made for this figure carries.
    pub fn digest(&self, rate_mhz: u32, servos: &[RigServo]) -> u32 {
        mocap_decoder::rig_digest(
            rate_mhz,
            servos.iter().map(|&servo| {
                let hard = self.get(servo.output);
                DigestServo {
                    servo,
                    max_speed_qus_s: hard.map_or(0, |h| h.max_speed_qus_s),
                    max_accel_qus_s2: hard.map_or(0, |h| h.max_accel_qus_s2),
                }
            }),
        )
    }

    /// Whether `servos` lie inside these limits. An output the figure does not have counts before a range that
    /// leaves the limits.
    pub fn fit(&self, servos: &[RigServo]) -> Fit {
        if let Some(s) = servos.iter().find(|s| self.get(s.output).is_none()) {
            return Fit::UnknownOutput { output: s.output };
        }
        for s in servos {
            let Some(h) = self.get(s.output) else {
                continue;
            };
            let (lo, hi) = s.pulse_range_qus();
            if lo < h.min_qus || hi > h.max_qus || !(lo..=hi).contains(&s.neutral_qus) {
                return Fit::Outside { output: s.output };
            }
        }
        Fit::Inside
    }
}

/// A figure's identity: its rig table (servos at a rate) and its rig digest
/// (SPEC.md §3.6, [`HardLimits::digest`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FigureId<'a> {
    /// Tick rate, millihertz.
    pub rate_mhz: u32,
    /// The servos as the rig table of a clip made for the figure holds them.
    pub servos: &'a [RigServo],
    /// The figure's rig digest.
    pub digest: u32,
}

/// How a clip's rig compares with a figure's ([`FigureId::compare`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Identity {
    /// Made for this figure: its rig table is the figure's and so is its
    /// rig digest.
    Same,
    /// Its rig table is the figure's; it carries no rig digest (encoded
    /// before the digest existed), so the table is all there is to compare.
    SameTable,
    /// Its rig table is another (or it has none).
    OtherTable,
    /// Its rig table is the figure's but its digest is not: made for a rig
    /// with the same table and other speed or acceleration limits.
    OtherDigest,
}

impl Identity {
    /// Whether this counts as made for the figure.
    pub const fn is_same(self) -> bool {
        matches!(self, Identity::Same | Identity::SameTable)
    }

    /// Its name in status lines: `same`, `same_table`, `other_table`, `other_digest`.
    pub const fn name(self) -> &'static str {
        match self {
            Identity::Same => "same",
            Identity::SameTable => "same_table",
            Identity::OtherTable => "other_table",
            Identity::OtherDigest => "other_digest",
        }
    }
}

impl FigureId<'_> {
    /// How `clip` was made relative to this figure: its rig table against
    /// the figure's (rate and every servo), and its rig digest, when it has
    /// one, against the figure's.
    pub fn compare(&self, clip: &mocap_decoder::Clip<'_>) -> Identity {
        let same_table = clip.rig().is_some_and(|t| {
            t.rate_mhz() == self.rate_mhz
                && t.servo_count() == self.servos.len()
                && t.servos().zip(self.servos).all(|(a, b)| a == *b)
        });
        match (same_table, clip.rig_digest()) {
            (false, _) => Identity::OtherTable,
            (true, None) => Identity::SameTable,
            (true, Some(d)) if d == self.digest => Identity::Same,
            (true, Some(_)) => Identity::OtherDigest,
        }
    }
}

/// One servo's hard limits at a tick rate, in ¼ µs per tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HardStep {
    /// Lowest pulse, ¼ µs.
    pub min_qus: u16,
    /// Highest pulse, ¼ µs.
    pub max_qus: u16,
    /// Rest pulse, ¼ µs.
    pub neutral_qus: u16,
    /// Most change per tick, ¼ µs; 0 = no limit.
    pub max_step_qus: u16,
    /// Most change of the per-tick change per tick, ¼ µs; 0 = no limit.
    pub max_accel_qus: u16,
}

impl HardStep {
    /// A pass-through: the whole `u16` range, no speed or acceleration limit.
    pub const OPEN: HardStep = HardStep {
        min_qus: 0,
        max_qus: u16::MAX,
        neutral_qus: 6000,
        max_step_qus: 0,
        max_accel_qus: 0,
    };

    /// An upper bound on the ticks [`step`](Self::step) towards neutral
    /// takes to bring the servo to neutral, at rest, from any position in
    /// its range at any speed it can have there: ⌈span / v⌉ + 1 without an
    /// acceleration limit, ⌈span / v⌉ + 2·⌈v / a⌉ + 2 with one (braking from
    /// full speed, then accelerating again), with `v` the speed limit (the
    /// span when there is none) and `a` the acceleration limit, per tick.
    pub fn park_ticks_max(&self) -> u32 {
        let span = u32::from(self.max_qus.saturating_sub(self.min_qus)).max(1);
        let v = match self.max_step_qus {
            0 => span,
            v => u32::from(v),
        };
        let travel = span.div_ceil(v);
        match self.max_accel_qus {
            0 => travel.saturating_add(1),
            a => travel
                .saturating_add(v.div_ceil(u32::from(a)).saturating_mul(2))
                .saturating_add(2),
        }
    }

    /// `limit` at `rate_mhz` ticks per 1000 s: its speed as ¼ µs per tick
    /// (rounded down, at least 1 when limited) and its acceleration as ¼ µs
    /// per tick per tick (the same). A neutral outside the range is moved
    /// into it.
    pub fn at_rate(limit: &HardLimit, rate_mhz: u32) -> Self {
        let rate = u64::from(rate_mhz.max(1));
        let (min_qus, max_qus) = if limit.min_qus <= limit.max_qus {
            (limit.min_qus, limit.max_qus)
        } else {
            (limit.max_qus, limit.min_qus)
        };
        let per_tick = |v: u64, den: u64| -> u16 {
            if v == 0 {
                0
            } else {
                u16::try_from(v.checked_div(den).unwrap_or(0).max(1)).unwrap_or(u16::MAX)
            }
        };
        HardStep {
            min_qus,
            max_qus,
            neutral_qus: limit.neutral_qus.max(min_qus).min(max_qus),
            // v [qus/s] / (rate_mhz / 1000 [ticks/s]).
            max_step_qus: per_tick(u64::from(limit.max_speed_qus_s).saturating_mul(1000), rate),
            // a [qus/s²] / (rate_mhz / 1000)².
            max_accel_qus: per_tick(
                u64::from(limit.max_accel_qus_s2).saturating_mul(1_000_000),
                rate.saturating_mul(rate),
            ),
        }
    }

    /// One tick from `pos` at `vel` (¼ µs per tick, signed) towards `target`
    /// (clamped to the range first): the new position and velocity. Never
    /// leaves `[min_qus, max_qus]` (even from outside it), never changes the
    /// position by more than `max_step_qus` nor the velocity by more than
    /// `max_accel_qus` — except to come back into the range — and brakes
    /// early enough to stop on a target that holds still.
    pub fn step(&self, pos: u16, vel: i32, target: u16) -> (u16, i32) {
        // Range and speed are the clip limiter's own rules.
        let speed_limit = ServoLimits {
            min_qus: self.min_qus,
            max_qus: self.max_qus,
            neutral_qus: self.neutral_qus,
            max_step_qus: self.max_step_qus,
        };
        let target = speed_limit.clamp(target);
        if !(self.min_qus..=self.max_qus).contains(&pos) {
            // Only before the first tick of a wrongly built stage: back
            // inside at once, at rest.
            return (speed_limit.clamp(pos), 0);
        }
        if self.max_accel_qus == 0 {
            let next = speed_limit.step(pos, target);
            return (next, i32::from(next).wrapping_sub(i32::from(pos)));
        }
        let d = i32::from(target).wrapping_sub(i32::from(pos));
        let dist = d.unsigned_abs();
        let mut speed = dist;
        if self.max_step_qus > 0 {
            speed = speed.min(u32::from(self.max_step_qus));
        }
        let v = {
            // The fastest speed that still stops within `dist` braking by
            // `a` per tick ([`brake_speed`]), kept against the target and
            // against both range ends, so the servo never has to stop harder
            // than `a`, even when the target jumps behind it.
            let a = u32::from(self.max_accel_qus);
            let a64 = i64::from(a);
            let speed = brake_cap(a, i64::from(speed), dist);
            let want = if d < 0 {
                0i64.saturating_sub(speed)
            } else {
                speed
            };
            let v0 = i64::from(vel);
            let (mut lo, mut hi) = (v0.saturating_sub(a64), v0.saturating_add(a64));
            if self.max_step_qus > 0 {
                let m = i64::from(self.max_step_qus);
                (lo, hi) = (lo.max(0i64.saturating_sub(m)), hi.min(m));
            }
            // `pos` is inside the range here.
            let below = u32::from(pos.saturating_sub(self.min_qus));
            let above = u32::from(self.max_qus.saturating_sub(pos));
            // lo.max(−brake(below)) and hi.min(brake(above)).
            lo = 0i64.saturating_sub(brake_cap(a, 0i64.saturating_sub(lo), below));
            hi = brake_cap(a, hi, above);
            let v = if lo <= hi { want.max(lo).min(hi) } else { 0 };
            i32::try_from(v).unwrap_or(0)
        };
        let next = i32::from(pos)
            .saturating_add(v)
            .max(i32::from(self.min_qus))
            .min(i32::from(self.max_qus));
        let next = u16::try_from(next).unwrap_or(self.neutral_qus);
        // The velocity actually moved (a range end stops it).
        let moved = i32::from(next).wrapping_sub(i32::from(pos));
        (next, moved)
    }
}

/// `s.min(brake_speed(a, dist))`, the square root only when braking binds:
/// `brake_speed(a, dist) >= s` exactly when `stopping_distance(a, s) <= dist`
/// (`brake_speed` grows with `dist`, and [`stopping_distance`] is the least
/// `dist` reaching `s`), which takes one division instead of a square root
/// and a search — most ticks of a servo tracking its target.
fn brake_cap(a: u32, s: i64, dist: u32) -> i64 {
    if s <= 0 {
        // brake_speed is never negative.
        return s;
    }
    match u32::try_from(s) {
        Ok(v) if stopping_distance(a, v) <= dist => s,
        _ => s.min(i64::from(brake_speed(a, dist))),
    }
}

/// The largest speed `s` (¼ µs per tick) that stops within `dist` when it
/// can drop by at most `a > 0` per tick: the ticks `s, s − a, s − 2a, …`
/// (while positive) add up to at most `dist`. With `k` further ticks (`k·a
/// < s <= (k+1)·a`) they add up to `(k+1)·s − a·k(k+1)/2`. 0 for `dist = 0`.
/// 32-bit divisions and square root where the values fit (always for the
/// ranges of ¼ µs pulses but the largest): cheap on a Cortex-M.
fn brake_speed(a: u32, dist: u32) -> u32 {
    if dist == 0 || a == 0 {
        return 0;
    }
    let (a64, d64) = (u64::from(a), u64::from(dist));
    // The continuous bound s(s + a) <= 2·a·dist is never below the answer.
    let disc = a64
        .saturating_mul(8)
        .saturating_mul(d64)
        .saturating_add(a64.saturating_mul(a64));
    let root = match u32::try_from(disc) {
        Ok(small) => small.isqrt(),
        Err(_) => u32::try_from(disc.isqrt()).unwrap_or(u32::MAX),
    };
    let upper = root.saturating_sub(a) / 2;
    let mut k = u64::from(upper.checked_div(a).unwrap_or(0)).saturating_add(1);
    loop {
        let k1 = k.saturating_add(1);
        let tri = a64.saturating_mul(k).saturating_mul(k1) / 2;
        let num = d64.saturating_add(tri);
        let fit = match (u32::try_from(num), u32::try_from(k1)) {
            (Ok(n), Ok(k1)) => u64::from(n.checked_div(k1).unwrap_or(0)),
            _ => num.checked_div(k1).unwrap_or(0),
        };
        let s = k1.saturating_mul(a64).min(fit).min(d64);
        if s > k.saturating_mul(a64) || k == 0 {
            return u32::try_from(s).unwrap_or(u32::MAX);
        }
        k = k.wrapping_sub(1);
    }
}

/// Speeds up to this have `v² < 2³¹` ([`stopping_distance`] in 32 bits).
const SMALL_SPEED: u32 = 46_340;

/// The distance a servo at speed `v` needs to stop braking by `a > 0` per
/// tick: `v + (v − a) + (v − 2a) + …` while positive — the least `dist` with
/// [`brake_speed`]`(a, dist) >= v`.
fn stopping_distance(a: u32, v: u32) -> u32 {
    if a == 0 || v == 0 {
        return 0;
    }
    // k further ticks after the first: k·a < v.
    let k32 = v.saturating_sub(1).checked_div(a).unwrap_or(0);
    if v <= SMALL_SPEED {
        // (k + 1)·v <= v² and a·k·(k + 1) <= (v − 1)·(k + 1) < v² < 2³¹: 32 bits hold every
        // term, the same sum without 64-bit products (calls on a Cortex-M0).
        let k1 = k32.wrapping_add(1);
        return k1
            .wrapping_mul(v)
            .wrapping_sub(a.wrapping_mul(k32).wrapping_mul(k1) / 2);
    }
    let k = u64::from(k32);
    let (a64, v64) = (u64::from(a), u64::from(v));
    let sum = k
        .saturating_add(1)
        .saturating_mul(v64)
        .saturating_sub(a64.saturating_mul(k).saturating_mul(k.saturating_add(1)) / 2);
    u32::try_from(sum).unwrap_or(u32::MAX)
}

/// The hard-limit stage of `N` servos: the last pulse and velocity of each,
/// every pulse through [`HardStep::step`]. Starts at rest at each servo's
/// neutral. Counts, per servo, the ticks whose pulse it changed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HardStage<const N: usize> {
    steps: [HardStep; N],
    pos: [u16; N],
    vel: [i32; N],
    clamped: [u32; N],
    worst: [u16; N],
    /// Slots in use (the rest are never stepped: a playback's idle slots).
    count: usize,
}

impl<const N: usize> HardStage<N> {
    /// A stage for the first `count` of `steps` (at most `N`), at rest at
    /// their neutrals; the slots past them are left alone.
    pub fn new(steps: [HardStep; N], count: usize) -> Self {
        let mut pos = [0u16; N];
        for (p, s) in pos.iter_mut().zip(&steps) {
            *p = s.neutral_qus;
        }
        HardStage {
            steps,
            pos,
            vel: [0; N],
            clamped: [0; N],
            worst: [0; N],
            count: count.min(N),
        }
    }

    /// Each servo's limits per tick.
    pub const fn steps(&self) -> &[HardStep; N] {
        &self.steps
    }

    /// Each servo's last pulse, ¼ µs.
    pub const fn positions(&self) -> &[u16; N] {
        &self.pos
    }

    /// Moves each servo one tick towards `pulses`; writes the result back
    /// into `pulses`.
    pub fn apply(&mut self, pulses: &mut [u16; N]) {
        for (((((q, p), v), s), c), w) in pulses
            .iter_mut()
            .zip(&mut self.pos)
            .zip(&mut self.vel)
            .zip(&self.steps)
            .zip(&mut self.clamped)
            .zip(&mut self.worst)
            .take(self.count)
        {
            let (next, vel) = s.step(*p, *v, *q);
            if next != *q {
                *c = c.saturating_add(1);
                *w = (*w).max(next.abs_diff(*q));
            }
            (*p, *v, *q) = (next, vel, next);
        }
    }

    /// Moves each servo one tick towards its neutral; writes the pulses
    /// into `pulses`; `true` once every servo is at neutral and at rest.
    pub fn stop_step(&mut self, pulses: &mut [u16; N]) -> bool {
        let mut parked = true;
        for (((q, p), v), s) in pulses
            .iter_mut()
            .zip(&mut self.pos)
            .zip(&mut self.vel)
            .zip(&self.steps)
            .take(self.count)
        {
            let (next, vel) = s.step(*p, *v, s.neutral_qus);
            (*p, *v, *q) = (next, vel, next);
            parked &= next == s.neutral_qus && vel == 0;
        }
        parked
    }

    /// The most ticks [`stop_step`](Self::stop_step) needs from any state
    /// ([`HardStep::park_ticks_max`] of the slowest servo).
    pub fn park_ticks_max(&self) -> u32 {
        self.steps
            .iter()
            .take(self.count)
            .map(HardStep::park_ticks_max)
            .max()
            .unwrap_or(0)
    }

    /// Whether every servo is at its neutral, at rest.
    pub fn parked(&self) -> bool {
        self.pos
            .iter()
            .zip(&self.vel)
            .zip(&self.steps)
            .take(self.count)
            .all(|((&p, &v), s)| p == s.neutral_qus && v == 0)
    }

    /// Per servo, the ticks whose pulse this stage changed.
    pub const fn clamped(&self) -> &[u32; N] {
        &self.clamped
    }

    /// Per servo, the most this stage moved a pulse from the one it was
    /// given, ¼ µs.
    pub const fn worst(&self) -> &[u16; N] {
        &self.worst
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::TestRng;

    /// The brake speed as first written (i64 throughout): the oracle of the
    /// 32-bit one.
    fn brake_speed_reference(a: i64, dist: i64) -> i64 {
        if dist <= 0 || a <= 0 {
            return 0;
        }
        let root = (a * 8 * dist + a * a).unsigned_abs().isqrt();
        let upper = (root as i64 - a) / 2;
        let mut k = upper / a + 1;
        loop {
            let k1 = k + 1;
            let tri = a * k * k1 / 2;
            let fit = (dist + tri) / k1;
            let s = (k1 * a).min(fit).min(dist);
            if s > k * a || k == 0 {
                return s.max(0);
            }
            k -= 1;
        }
    }

    /// Behaviour kept: the 32-bit brake speed is the reference's on every
    /// `a` and `dist` of ¼ µs pulses (every `a` up to 300 with every
    /// distance, and random pairs over the whole range), and the stopping
    /// distance is the first distance whose brake speed reaches `v`.
    #[test]
    fn brake_speed_is_the_reference_one() {
        for a in 1..=300u32 {
            for dist in 0..=65_535u32 {
                assert_eq!(
                    i64::from(brake_speed(a, dist)),
                    brake_speed_reference(i64::from(a), i64::from(dist)),
                    "a={a} dist={dist}"
                );
            }
        }
        let mut rng = TestRng::new(11);
        for _ in 0..200_000 {
            let (a, dist) = (u32::from(rng.next_u16()).max(1), u32::from(rng.next_u16()));
            assert_eq!(
                i64::from(brake_speed(a, dist)),
                brake_speed_reference(i64::from(a), i64::from(dist)),
                "a={a} dist={dist}"
            );
        }
        for _ in 0..20_000 {
            let a = u32::from(rng.next_u16() % 500).max(1);
            let v = u32::from(rng.next_u16() % 2000).max(1);
            let free = stopping_distance(a, v);
            assert!(brake_speed(a, free) >= v, "a={a} v={v} free={free}");
            assert!(brake_speed(a, free - 1) < v, "a={a} v={v} free={free}");
        }
    }

    /// `brake_cap` is `s.min(brake_speed(a, dist))` for every sign and size of `s`, and
    /// `stopping_distance`'s 32-bit sums are its 64-bit ones.
    #[test]
    fn brake_cap_is_the_minimum_with_brake_speed() {
        let stopping_64 = |a: u64, v: u64| -> u64 {
            let k = (v - 1) / a;
            (k + 1) * v - a * k * (k + 1) / 2
        };
        for a in 1..=40u32 {
            for v in 1..=400u32 {
                assert_eq!(
                    u64::from(stopping_distance(a, v)),
                    stopping_64(u64::from(a), u64::from(v)),
                    "a={a} v={v}"
                );
            }
        }
        let mut rng = TestRng::new(12);
        for _ in 0..200_000 {
            let a = u32::from(rng.next_u16() % 2000).max(1);
            let v = u32::from(rng.next_u16()).max(1);
            if v <= SMALL_SPEED {
                assert_eq!(
                    u64::from(stopping_distance(a, v)),
                    stopping_64(u64::from(a), u64::from(v)),
                    "a={a} v={v}"
                );
            }
            let dist = u32::from(rng.next_u16());
            let s = i64::from(rng.next_u16()) - 2000;
            assert_eq!(
                brake_cap(a, s, dist),
                s.min(i64::from(brake_speed(a, dist))),
                "a={a} s={s} dist={dist}"
            );
        }
        for a in 1..=12u32 {
            for dist in 0..=300u32 {
                for s in -3..=300i64 {
                    assert_eq!(
                        brake_cap(a, s, dist),
                        s.min(i64::from(brake_speed(a, dist))),
                        "a={a} s={s} dist={dist}"
                    );
                }
            }
        }
        assert_eq!(brake_cap(3, i64::MAX, 10), i64::from(brake_speed(3, 10)));
    }

    #[test]
    fn every_policy_reads_back_from_its_name() {
        for (policy, name) in Policy::ALL {
            assert_eq!(policy.name(), name);
            assert_eq!(Policy::from_name(name), Some(policy));
        }
        assert_eq!(Policy::from_name("clamp_if_inside"), None);
    }

    fn limit(min: u16, max: u16, speed: u32, accel: u32) -> HardLimit {
        HardLimit {
            output: 0,
            min_qus: min,
            max_qus: max,
            neutral_qus: min + (max - min) / 2,
            max_speed_qus_s: speed,
            max_accel_qus_s2: accel,
        }
    }

    #[test]
    fn brake_speed_is_the_largest_that_stops() {
        let stops = |a: u32, s: u32, d: u32| {
            let (a, s, d) = (i64::from(a), i64::from(s), i64::from(d));
            let (mut s, mut sum) = (s, 0);
            while s > 0 {
                sum += s;
                s -= a;
            }
            sum <= d
        };
        for a in 1..40u32 {
            for d in 0..400u32 {
                let s = brake_speed(a, d);
                assert!(stops(a, s, d) && !stops(a, s + 1, d), "a={a} d={d} s={s}");
            }
        }
    }

    #[test]
    fn per_tick_conversion() {
        // 50 Hz: 40 000 ¼µs/s is 800 per tick; 100 000 ¼µs/s² is 40 per tick².
        let s = HardStep::at_rate(&limit(4000, 8000, 40_000, 100_000), 50_000);
        assert_eq!((s.max_step_qus, s.max_accel_qus), (800, 40));
        let s = HardStep::at_rate(&limit(4000, 8000, 1, 1), 50_000);
        assert_eq!((s.max_step_qus, s.max_accel_qus), (1, 1));
        let s = HardStep::at_rate(&limit(4000, 8000, 0, 0), 50_000);
        assert_eq!((s.max_step_qus, s.max_accel_qus), (0, 0));
    }

    /// Whatever the targets: inside the range, within the speed and the
    /// acceleration limits, and at a held target eventually, at rest.
    #[test]
    fn random_targets_stay_inside_every_limit() {
        let mut rng = TestRng::new(7);
        for _ in 0..2000 {
            let a = rng.next_u16();
            let b = rng.next_u16();
            let (min, max) = if a <= b { (a, b) } else { (b, a) };
            let step = HardStep {
                min_qus: min,
                max_qus: max,
                neutral_qus: min + (max - min) / 3,
                max_step_qus: rng.next_u16() % 300,
                max_accel_qus: rng.next_u16() % 40,
            };
            let (mut p, mut v) = (step.neutral_qus, 0i32);
            for _ in 0..500 {
                let (n, nv) = step.step(p, v, rng.next_u16());
                assert!((min..=max).contains(&n));
                let moved = i32::from(n) - i32::from(p);
                assert_eq!(moved, nv);
                if step.max_step_qus > 0 {
                    assert!(moved.unsigned_abs() <= u32::from(step.max_step_qus));
                }
                if step.max_accel_qus > 0 {
                    assert!(
                        (nv - v).unsigned_abs() <= u32::from(step.max_accel_qus),
                        "{step:?} p={p} v={v} -> {n} {nv}"
                    );
                }
                (p, v) = (n, nv);
            }
            // Then on its way to the end farther from neutral, at speed, for a while; from
            // there, neutral within the bound.
            let far = if step.neutral_qus - min > max - step.neutral_qus {
                min
            } else {
                max
            };
            let (mut q, mut w) = (p, v);
            for _ in 0..rng.next_u16() % 300 {
                (q, w) = step.step(q, w, far);
            }
            let (start, speed) = (q, w);
            let mut ticks = 0;
            while (q, w) != (step.neutral_qus, 0) {
                (q, w) = step.step(q, w, step.neutral_qus);
                ticks += 1;
                assert!(
                    ticks <= step.park_ticks_max(),
                    "{step:?} from {start} at {speed}"
                );
            }
            // A held target is reached and held, at rest.
            let target = rng.next_u16();
            for _ in 0..200_000 {
                (p, v) = step.step(p, v, target);
                if p == target.clamp(min, max) && v == 0 {
                    break;
                }
            }
            assert_eq!((p, v), (target.clamp(min, max), 0), "{step:?}");
        }
    }

    #[test]
    fn open_steps_pass_pulses_through() {
        let mut stage = HardStage::<3>::new([HardStep::OPEN; 3], 3);
        assert_eq!(stage.positions(), &[6000; 3]);
        let mut q = [0, 16_000, 65_535];
        stage.apply(&mut q);
        assert_eq!(q, [0, 16_000, 65_535]);
        assert_eq!(stage.clamped(), &[0, 0, 0]);
    }

    #[test]
    fn fit_names_the_first_servo_outside() {
        let servo = |output, lo, hi| RigServo {
            output,
            angle_lo_mdeg: -45_000,
            angle_hi_mdeg: 45_000,
            pulse_lo_qus: lo,
            pulse_hi_qus: hi,
            neutral_qus: 6000,
            max_speed_mdeg_s: 0,
        };
        let hard = [
            HardLimit {
                output: 3,
                ..limit(4000, 8000, 0, 0)
            },
            HardLimit {
                output: 5,
                ..limit(4400, 7600, 0, 0)
            },
        ];
        let hard = HardLimits::new(&hard);
        assert_eq!(hard.fit(&[servo(3, 4000, 8000)]), Fit::Inside);
        assert_eq!(
            hard.fit(&[servo(5, 8000, 4400)]),
            Fit::Outside { output: 5 }
        );
        assert_eq!(
            hard.fit(&[servo(3, 4000, 8000), servo(4, 5000, 7000)]),
            Fit::UnknownOutput { output: 4 }
        );
    }
}
