//! The player: sequential frames, random access and sampling at any time,
//! over a fixed-size state owned by the caller's stack or a `static`.

use crate::clip::Clip;
use crate::codec::Codec;
use crate::error::Error;
use crate::frame_time::FrameTime;
use core::num::NonZeroU32;

/// Plays a clip of at most `N` channels.
///
/// State: the codec view (a few slices), a segment cursor and `N` words —
/// the `index` codec's current frame, or the `pca-spline` codec's cache:
/// 4 words, then per group of `n` channels and `k` components `7 + 4k`
/// words (`3 + n` if `k = 0`), then one word per constant channel; with
/// less room the same values are decoded, more slowly — or the
/// `predictive` codec's two frames, contexts, probabilities and coder
/// (`3·C + 19` words; a smaller `N` is refused), or the `pattern` codec's
/// second frame while `sample_at` mixes two (`C` words), then 12 words per
/// node, its place in the database, its last segment and, for coded segment
/// lists, the list's stream state after it (with less room every node
/// searches its segment list each frame) — so `size_of::<Player<N>>()` is
/// `4·N + 248` bytes on a 32-bit MCU (measured on thumbv7m by the example
/// firmware, 1 528 B for its `N = 320`; BENCHMARKS.md).
/// Output goes into the caller's slice, in the units of the channel table.
#[derive(Clone, Debug)]
// Declaration order: the words every call reads first, within reach of the
// Cortex-M0's load offsets (at most 124 bytes from the player), the state
// array last. (Rust's own order put them past the array.)
#[repr(C)]
pub struct Player<'a, const N: usize> {
    channels: usize,
    frames: u32,
    /// Next frame [`Player::next_frame`] returns.
    cursor: u32,
    /// The frame held in `state`, if any.
    state_frame: Option<u32>,
    /// Splits `sample_at`'s times into frames and fractions (frame time
    /// validated non-zero, §3.2).
    frame_time: FrameTime,
    codec: Codec<'a>,
    /// Where the `pca-spline` codec is in its segment list.
    #[cfg(feature = "codec-pca-spline")]
    segment: crate::codec::pca_spline::Cursor<'a>,
    /// Where the `rma` codec's reference position is in the segment list.
    #[cfg(feature = "codec-rma")]
    reference: crate::codec::pca_spline::Cursor<'a>,
    /// `index`: the frame `state_frame`; `pca-spline`: its cache of key
    /// intervals (a larger `N` caches more groups).
    state: [i32; N],
}

impl<'a, const N: usize> Player<'a, N> {
    /// A player positioned before the first frame.
    pub fn new(clip: &Clip<'a>) -> Result<Self, Error> {
        let header = clip.header();
        let channels = header.channel_count();
        if channels > N {
            return Err(Error::PlayerCapacity {
                channels,
                capacity: N,
            });
        }
        let codec = clip.codec();
        #[cfg(feature = "codec-rma")]
        if let Codec::Rma(c) = &codec {
            if c.state_words() > N {
                return Err(Error::PlayerStateTooSmall {
                    needed: c.state_words(),
                    capacity: N,
                });
            }
        }
        #[cfg(feature = "codec-predictive")]
        if let Codec::Predictive(c) = &codec {
            if c.state_words() > N {
                return Err(Error::PlayerStateTooSmall {
                    needed: c.state_words(),
                    capacity: N,
                });
            }
        }
        Ok(Player {
            codec,
            channels,
            frames: header.frame_count(),
            frame_time: FrameTime::new(
                NonZeroU32::new(header.frame_time_ns())
                    .ok_or(Error::PlayerInvariant { frame: 0 })?,
            ),
            state_frame: None,
            cursor: 0,
            #[cfg(feature = "codec-pca-spline")]
            segment: crate::codec::pca_spline::Cursor::default(),
            #[cfg(feature = "codec-rma")]
            reference: crate::codec::pca_spline::Cursor::default(),
            state: [0; N],
        })
    }

    /// Channels per frame.
    pub fn channel_count(&self) -> usize {
        self.channels
    }

    /// Frames in the clip.
    pub fn frame_count(&self) -> u32 {
        self.frames
    }

    /// Moves the sequential cursor back to frame 0.
    pub fn rewind(&mut self) {
        self.cursor = 0;
    }

    /// Decodes the next frame into `out`; `Ok(None)` after the last frame.
    pub fn next_frame(&mut self, out: &mut [i32]) -> Result<Option<u32>, Error> {
        if self.cursor >= self.frames {
            return Ok(None);
        }
        let i = self.cursor;
        self.frame(i, out)?;
        self.cursor = i.wrapping_add(1);
        Ok(Some(i))
    }

    /// Decodes frame `i` into `out` (random access).
    pub fn frame(&mut self, i: u32, out: &mut [i32]) -> Result<(), Error> {
        let out = self.output(out)?;
        if i >= self.frames {
            return Err(Error::PlayerFrameOutOfRange {
                frame: i,
                frames: self.frames,
            });
        }
        if self.pose_at(u64::from(i) << 16, out)? {
            return Ok(());
        }
        self.seek(i)?;
        copy_values(out, &self.state);
        Ok(())
    }

    /// Codecs that evaluate any time directly (no frame history) decode
    /// the pose at `pos` (frames, 16.16) into `out` and return true
    /// (`pattern`: its frames directly, between two frames §6's mix).
    fn pose_at(&mut self, pos: u64, out: &mut [i32]) -> Result<bool, Error> {
        match &self.codec {
            #[cfg(feature = "codec-pattern")]
            Codec::Pattern(c) => {
                let f = u32::try_from(pos >> 16).unwrap_or(u32::MAX);
                let frac = (pos & 0xffff) as u32;
                // The second frame of `sample_at`, then each node's segment
                // (§11.4): the next frame needs no search.
                let (next, cursors) = self
                    .state
                    .split_at_mut_checked(self.channels)
                    .unwrap_or((&mut [], &mut []));
                let ok = c.decode(f, out, cursors).is_some()
                    && (frac == 0 || c.decode(f.wrapping_add(1), next, cursors).is_some());
                if !ok {
                    return Err(Error::PlayerInvariant { frame: f });
                }
                if frac != 0 {
                    for (o, &b) in out.iter_mut().zip(next.iter()) {
                        *o = mix(*o, b, frac);
                    }
                }
                Ok(true)
            }
            #[cfg(feature = "codec-pca-spline")]
            Codec::PcaSpline(c) => c
                .decode_at(pos, &mut self.segment, out, &mut self.state)
                .map(|()| true)
                .ok_or_else(|| Error::PlayerInvariant {
                    frame: u32::try_from(pos >> 16).unwrap_or(u32::MAX),
                }),
            #[cfg(feature = "codec-rma")]
            Codec::Rma(c) => c
                .decode_at(
                    pos,
                    &mut self.segment,
                    &mut self.reference,
                    out,
                    &mut self.state,
                )
                .map(|()| true)
                .ok_or_else(|| Error::PlayerInvariant {
                    frame: u32::try_from(pos >> 16).unwrap_or(u32::MAX),
                }),
            _ => {
                let _ = (pos, out);
                Ok(false)
            }
        }
    }

    /// Samples the clip at `t_us` microseconds from its start (SPEC.md §6):
    /// spline codecs evaluate their curves at that time; frame codecs
    /// interpolate linearly between the two neighbouring frames in fixed
    /// point. Times past the last frame hold the last frame.
    pub fn sample_at(&mut self, t_us: u64, out: &mut [i32]) -> Result<(), Error> {
        let out = self.output(out)?;
        let ns = t_us.saturating_mul(1000);
        let (whole, frac) = self.frame_time.split(ns);
        let last = self.frames.wrapping_sub(1);
        let pos = if whole >= u64::from(last) {
            u64::from(last) << 16
        } else {
            (whole << 16) | u64::from(frac)
        };
        if self.pose_at(pos, out)? {
            return Ok(());
        }
        if whole >= u64::from(last) {
            self.seek(last)?;
            copy_values(out, &self.state);
            return Ok(());
        }
        let i = whole as u32;
        #[cfg(feature = "codec-predictive")]
        if let Codec::Predictive(c) = self.codec {
            // The state holds two frames: frame i is `v2` once frame i + 1
            // is decoded, unless i + 1 starts a block.
            if self.state_frame != Some(i.wrapping_add(1))
                || c.key_before(i.wrapping_add(1)) == i.wrapping_add(1)
            {
                self.seek(i)?;
                copy_values(out, &self.state);
                self.seek(i.wrapping_add(1))?;
            } else {
                let v2 = self.state.get(self.channels..self.channels.wrapping_mul(2));
                copy_values(out, v2.unwrap_or(&[]));
            }
            let next = self.state.get(..self.channels).unwrap_or(&[]);
            for (o, &b) in out.iter_mut().zip(next) {
                *o = mix(*o, b, frac);
            }
            return Ok(());
        }
        self.seek(i)?;
        let now = self.state.get(..self.channels).unwrap_or(&[]);
        copy_values(out, now);
        // Decode frame i + 1 into `out` without disturbing the state.
        let next = i.wrapping_add(1);
        decode(&self.codec, next, out).ok_or(Error::PlayerInvariant { frame: next })?;
        for (o, &a) in out.iter_mut().zip(now) {
            *o = mix(a, *o, frac);
        }
        Ok(())
    }

    fn output<'o>(&self, out: &'o mut [i32]) -> Result<&'o mut [i32], Error> {
        let actual = out.len();
        out.get_mut(..self.channels)
            .ok_or(Error::PlayerOutputTooSmall {
                expected: self.channels,
                actual,
            })
    }

    /// Brings `state` to frame `i`, decoding as few frames as possible.
    fn seek(&mut self, i: u32) -> Result<(), Error> {
        if self.state_frame == Some(i) {
            return Ok(());
        }
        let key = self.key_before(i);
        let start = match self.state_frame {
            Some(s) if s < i && s >= key => s.wrapping_add(1),
            _ => key,
        };
        let codec = self.codec;
        let state = match codec {
            #[cfg(feature = "codec-predictive")]
            Codec::Predictive(_) => &mut self.state[..],
            _ => self.state.get_mut(..self.channels).unwrap_or(&mut []),
        };
        // No early exit: the loop stays as tight as before the check.
        let mut ok = true;
        for f in start..=i {
            ok &= decode(&codec, f, state).is_some();
        }
        if !ok {
            // The state holds no whole frame now.
            self.state_frame = None;
            return Err(Error::PlayerInvariant { frame: i });
        }
        self.state_frame = Some(i);
        Ok(())
    }

    fn key_before(&self, i: u32) -> u32 {
        match &self.codec {
            #[cfg(feature = "codec-index")]
            Codec::Index(c) => c.key_before(i),
            #[cfg(feature = "codec-index")]
            Codec::IndexFast(c) => c.key_before(i),
            #[cfg(feature = "codec-predictive")]
            Codec::Predictive(c) => c.key_before(i),
            _ => i,
        }
    }
}

/// `a + (b − a) · frac / 2^16` in wrapping fixed point (SPEC.md §6: the
/// product in 64 bits, `>>` arithmetic), for `frac < 2^16`, in 32-bit
/// products: with `d = b − a = hi · 2^16 + lo`, `0 ≤ lo < 2^16`,
/// `⌊d · frac / 2^16⌋ = hi · frac + ⌊lo · frac / 2^16⌋` (the first term is a
/// whole multiple of `2^16`), and `|hi · frac| < 2^31`, `lo · frac < 2^32`.
pub(crate) fn mix(a: i32, b: i32, frac: u32) -> i32 {
    let d = b.wrapping_sub(a);
    let hi = (d >> 16).wrapping_mul(frac as i32);
    let lo = ((d as u32 & 0xffff).wrapping_mul(frac) >> 16) as i32;
    a.wrapping_add(hi).wrapping_add(lo)
}

/// Decodes frame `f` into `values`, which hold frame `f - 1` if `f` is not
/// a key frame. `None` only if an invariant of the validated clip is broken.
fn decode(codec: &Codec<'_>, f: u32, values: &mut [i32]) -> Option<()> {
    match codec {
        #[cfg(feature = "codec-index")]
        Codec::Index(c) => c.decode_frame(f, values),
        #[cfg(feature = "codec-index")]
        Codec::IndexFast(c) => c.decode_frame(f, values),
        #[cfg(feature = "codec-predictive")]
        Codec::Predictive(c) => c.decode_frame(f, values),
        _ => {
            let _ = (f, values);
            Some(())
        }
    }
}

/// Copies the first `dst.len()` values of `src` into `dst` (as many as
/// both hold): a `copy_from_slice` without its length-mismatch panic.
fn copy_values(dst: &mut [i32], src: &[i32]) {
    let n = dst.len().min(src.len());
    if let (Some(d), Some(s)) = (dst.get_mut(..n), src.get(..n)) {
        // Eight words at a time: a load-multiple and a store-multiple on
        // the Cortex-M3 (`copy_from_slice` calls `memcpy`, ~5 instructions
        // a word there). RV32's `memcpy` is the faster there.
        if cfg!(not(target_arch = "arm")) {
            d.copy_from_slice(s);
            return;
        }
        let (dc, dt) = d.as_chunks_mut::<8>();
        let (sc, st) = s.as_chunks::<8>();
        for (a, b) in dc.iter_mut().zip(sc) {
            *a = *b;
        }
        for (a, b) in dt.iter_mut().zip(st) {
            *a = *b;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::mix;

    /// SPEC.md §6 as written.
    fn spec(a: i32, b: i32, frac: u32) -> i32 {
        a.wrapping_add(((i64::from(b.wrapping_sub(a)) * i64::from(frac)) >> 16) as i32)
    }

    #[test]
    fn mix_is_the_specs_64_bit_product() {
        let edges = [
            i32::MIN,
            i32::MIN + 1,
            -65_537,
            -65_536,
            -65_535,
            -1,
            0,
            1,
            65_535,
            65_536,
            i32::MAX,
        ];
        let fracs = [0u32, 1, 2, 32_767, 32_768, 65_534, 65_535];
        for &a in &edges {
            for &b in &edges {
                for &f in &fracs {
                    assert_eq!(mix(a, b, f), spec(a, b, f), "{a} {b} {f}");
                }
            }
        }
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..1_000_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let (a, b, f) = (s as i32, (s >> 32) as i32, (s >> 16) as u32 & 0xffff);
            assert_eq!(mix(a, b, f), spec(a, b, f), "{a} {b} {f}");
        }
    }
}
