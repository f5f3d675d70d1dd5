//! Power-aware sampling: a player that drops to a cheaper mode at run time
//! and back, without a jump (SPEC.md §6.1).
//!
//! At level `L` the clip is sampled ([`Player::sample_at`]) at every
//! `2^L`-th tick only; the ticks between are the fixed-point interpolation
//! of §6 between the last pose sampled and the next one. Level 0 samples
//! every tick, exactly as `sample_at` does. A level change (or a tick that
//! does not follow the last one) starts a new stretch from the pose being
//! output at that tick, so the output never leaves the path it was on: the
//! only difference a level makes is the interpolation error between two
//! sampled poses.
//!
//! What a level saves depends on the codec: `pca-spline` evaluates its
//! curves at any time, so level `L` costs about `1/2^L` of level 0; the
//! frame codecs (`index`, `predictive`) decode every frame up to the sampled
//! one whatever the level, and save only what a key frame lets them skip
//! (BENCHMARKS.md §2, "Power-aware levels").

use crate::error::Error;
use crate::player::{mix, Player};
use crate::rig::tick_us;

/// The cheapest level: one pose sampled every `2^MAX_LEVEL` = 16 ticks.
pub const MAX_LEVEL: u8 = 4;

/// Samples a clip at a servo rate, at a power level set at run time:
/// `2·C` words of state for the two poses it interpolates between.
#[derive(Clone, Debug)]
pub struct LevelSampler<const C: usize> {
    rate_mhz: u32,
    /// The level of the current stretch.
    level: u8,
    /// The level [`set_level`](Self::set_level) asked for.
    wanted: u8,
    /// Tick of `from`; the stretch ends at `start + 2^level` with `to`.
    start: u64,
    /// A stretch is under way (never at level 0).
    live: bool,
    from: [i32; C],
    to: [i32; C],
}

impl<const C: usize> LevelSampler<C> {
    /// A sampler at level 0 for ticks at `rate_mhz` (the rig's rate; tick
    /// `i` is at [`tick_us`]`(i, rate_mhz)`).
    pub fn new(rate_mhz: u32) -> Self {
        LevelSampler {
            rate_mhz,
            level: 0,
            wanted: 0,
            start: 0,
            live: false,
            from: [0; C],
            to: [0; C],
        }
    }

    /// The level from the next [`sample`](Self::sample) on: 0 (every tick)
    /// to [`MAX_LEVEL`]; higher values are taken as `MAX_LEVEL`.
    pub fn set_level(&mut self, level: u8) {
        self.wanted = level.min(MAX_LEVEL);
    }

    /// The level of the pose last output.
    pub fn level(&self) -> u8 {
        self.level
    }

    /// The pose at tick `tick` into `out` (at least the clip's channels):
    /// sampled, or interpolated within the current stretch.
    /// [`Error::PlayerCapacity`] if the clip has more than `C` channels.
    pub fn sample<const N: usize>(
        &mut self,
        player: &mut Player<'_, N>,
        tick: u64,
        out: &mut [i32],
    ) -> Result<(), Error> {
        let channels = player.channel_count();
        if channels > C {
            return Err(Error::PlayerCapacity {
                channels,
                capacity: C,
            });
        }
        let actual = out.len();
        let out = out.get_mut(..channels).ok_or(Error::PlayerOutputTooSmall {
            expected: channels,
            actual,
        })?;
        let step = 1u64 << self.level;
        let k = tick.wrapping_sub(self.start);
        let inside = self.live && tick >= self.start && k <= step;
        if inside {
            if k == step {
                copy(out, &self.to);
            } else {
                // k < step ≤ 2^MAX_LEVEL: the §6 fraction k / 2^level.
                let frac = (k as u32) << (16u8.wrapping_sub(self.level) & 31);
                for ((o, &a), &b) in out.iter_mut().zip(&self.from).zip(&self.to) {
                    *o = mix(a, b, frac);
                }
            }
            if k < step && self.wanted == self.level {
                return Ok(());
            }
        } else {
            // The first tick, a jump, or level 0: the clip's own pose.
            player.sample_at(tick_us(tick, self.rate_mhz), out)?;
        }
        self.level = self.wanted;
        self.live = self.level != 0;
        if self.live {
            // A new stretch from the pose output now.
            self.start = tick;
            copy(&mut self.from, out);
            let end = tick.saturating_add(1u64 << self.level);
            let to = self.to.get_mut(..channels).unwrap_or(&mut []);
            player.sample_at(tick_us(end, self.rate_mhz), to)?;
        }
        Ok(())
    }
}

fn copy(dst: &mut [i32], src: &[i32]) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = s;
    }
}

/// The level a schedule gives at `t_us`: `schedule` is `(from_us, level)`
/// pairs in time order, and a time takes the level of the last pair at or
/// before it (0 before the first). How `mocap play --power` and the
/// firmware's `MOCAP_POWER` drive [`LevelSampler::set_level`].
pub fn level_at(schedule: &[(u64, u8)], t_us: u64) -> u8 {
    schedule
        .iter()
        .take_while(|&&(from, _)| from <= t_us)
        .last()
        .map_or(0, |&(_, level)| level)
}
