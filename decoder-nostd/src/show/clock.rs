//! The show clock (SPEC.md §8.2): the MCU's own tick time, following an
//! external show clock (timecode from a sound player or a show controller)
//! by slewing — never by jumping — so several figures and the sound stay in
//! step and the motion never jerks.

/// How fast the clock may run ahead or behind its own ticks while it
/// follows, parts per million (0.5 %: a 10 ms error is gone in 2 s).
pub const DEFAULT_SLEW_PPM: u32 = 5_000;
/// A timecode further than this from the clock, µs, is a relocation (the
/// show was restarted or skipped): the clock jumps to it.
pub const RELOCATE_US: u64 = 2_000_000;

/// Show time from local time: `show = local + offset`, the offset moving
/// towards the last timecode's by at most `slew_ppm` of the local time that
/// passes. Monotonic while `slew_ppm < 10⁶`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShowClock {
    offset_us: i64,
    target_us: i64,
    last_local_us: u64,
    slew_ppm: u32,
    /// Timecodes taken, relocations among them.
    timecodes: u32,
    relocations: u32,
}

impl ShowClock {
    /// A clock at local time 0 = show time 0, slewing at most `slew_ppm`.
    pub const fn new(slew_ppm: u32) -> Self {
        ShowClock {
            offset_us: 0,
            target_us: 0,
            last_local_us: 0,
            slew_ppm,
            timecodes: 0,
            relocations: 0,
        }
    }

    /// A timecode: at local time `local_us` the show clock reads `show_us`.
    pub fn timecode(&mut self, local_us: u64, show_us: u64) {
        let now = self.now(local_us);
        self.timecodes = self.timecodes.wrapping_add(1);
        let target = (show_us as i64).wrapping_sub(local_us as i64);
        if now.abs_diff(show_us) > RELOCATE_US {
            self.offset_us = target;
            self.relocations = self.relocations.wrapping_add(1);
        }
        self.target_us = target;
    }

    /// Show time at local time `local_us` (not before the last call's).
    pub fn now(&mut self, local_us: u64) -> u64 {
        let local = local_us.max(self.last_local_us);
        let passed = local.wrapping_sub(self.last_local_us);
        self.last_local_us = local;
        let step = passed
            .saturating_mul(u64::from(self.slew_ppm))
            .checked_div(1_000_000)
            .unwrap_or(0)
            .min(i64::MAX as u64) as i64;
        let gap = self.target_us.wrapping_sub(self.offset_us);
        self.offset_us = self
            .offset_us
            .wrapping_add(gap.clamp(step.wrapping_neg(), step));
        (local as i64).wrapping_add(self.offset_us).max(0) as u64
    }

    /// Timecodes taken, and how many of them relocated the clock.
    pub fn timecodes(&self) -> (u32, u32) {
        (self.timecodes, self.relocations)
    }

    /// The offset still to slew, µs (positive: the clock is behind).
    pub fn error_us(&self) -> i64 {
        self.target_us.wrapping_sub(self.offset_us)
    }
}
