//! The `rma` codec (SPEC.md §12), after Lin et al. (2011): repeated
//! motion. A `pca-spline` body (§5) codes a signal `R` over every frame;
//! the **repeated clips** listed before it say that, for their frames, the
//! listed channels add the body's value at a reference position `Ref(t)`
//! (a piecewise-linear map into an earlier, primary stretch of the clip).
//! There `R` holds only the residual against the primary's reconstruction.
//!
//! `value(t) = R(t) + R(Ref(t))` on the added channels of a repeated clip,
//! `R(t)` everywhere else. `R(Ref(t))` is the body alone (never another
//! repeated clip's sum), so nothing recurses and no frame is buffered: a
//! pose costs two body evaluations inside a repeated clip, one outside.

use crate::codec::pca_spline::{Cursor, PcaSplineCodec};
use crate::consts::pca::FRAC_BITS;
use crate::error::Error;
use crate::reader::Reader;

/// The only form of the section (its first byte).
pub const FORM: u8 = 0;
/// Reference positions are stored in `1 / 2^REF_FRAC_BITS` frames.
pub const REF_FRAC_BITS: u32 = 8;
/// Most frames an `rma` clip may have: reference positions are `i32` in
/// `1/256` frames.
pub const MAX_FRAMES: u32 = 1 << 23;
/// Knots lie less than this many frames apart.
pub const MAX_KNOT_GAP: u32 = 1 << 15;
/// Words of the player's state the codec keeps for itself (the clip
/// cursor) before its scratch pose.
pub const CURSOR_WORDS: usize = 2;

fn malformed(rule: &'static str) -> Error {
    Error::RmaMalformed { rule }
}

/// A validated view of an `rma` section.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RmaCodec<'a> {
    channels: usize,
    frames: u32,
    /// The added channels' runs (§12.1: varint gap, varint length).
    runs: &'a [u8],
    /// The repeated clip records (§12.2).
    clips: &'a [u8],
    body: PcaSplineCodec<'a>,
    /// Words of the body's cache that hold every group of its largest
    /// segment: what the body at `t` gets first of the player's words.
    t_cache: usize,
    /// At most a quarter of the frames are in repeated clips: a player
    /// without room for the scratch pose beside `t`'s whole cache lays the
    /// scratch over that cache (refilled after each repeated pose) rather
    /// than shrink it for every pose.
    few_repeats: bool,
}

/// One repeated clip: its first and last frame and its knots, still coded.
#[derive(Clone, Copy, Debug)]
struct RepeatedClip<'a> {
    start: u32,
    last: u32,
    knot_count: u32,
    knots: &'a [u8],
    /// Byte offset of the next record.
    next: usize,
}

/// Reads the clip record at byte `at` of `clips`, `base` the frame after
/// the previous clip (0 for the first): `None` if it does not parse.
fn record_at(clips: &[u8], at: usize, base: u32) -> Option<RepeatedClip<'_>> {
    let mut r = Reader::new(clips.get(at..)?);
    let start = base.checked_add(r.varint_u32()?)?;
    let last = start.checked_add(r.varint_u32()?)?;
    let knot_count = r.varint_u32()?;
    let knots_at = r.pos();
    for _ in 0..knot_count {
        r.varint_u32()?;
        r.zigzag_i32()?;
    }
    let knots = clips.get(at.checked_add(knots_at)?..at.checked_add(r.pos())?)?;
    Some(RepeatedClip {
        start,
        last,
        knot_count,
        knots,
        next: at.checked_add(r.pos())?,
    })
}

impl<'a> RmaCodec<'a> {
    /// Validates the section against the header's channel and frame counts.
    pub(crate) fn parse(bytes: &'a [u8], channels: usize, frames: u32) -> Result<Self, Error> {
        let truncated = malformed("section truncated");
        if frames > MAX_FRAMES {
            return Err(malformed("more than 2^23 frames"));
        }
        let mut r = Reader::new(bytes);
        if r.u8().ok_or(truncated)? != FORM {
            return Err(malformed("unknown form"));
        }
        let run_count = r.varint_u32().ok_or(truncated)?;
        let runs_at = r.pos();
        let mut next = 0u64;
        for _ in 0..run_count {
            let gap = r.varint_u32().ok_or(truncated)?;
            let len = r.varint_u32().ok_or(truncated)?;
            if len == 0 {
                return Err(malformed("empty channel run"));
            }
            next = next
                .wrapping_add(u64::from(gap))
                .wrapping_add(u64::from(len));
            if next > channels as u64 {
                return Err(malformed("channel run past the last channel"));
            }
        }
        let runs = bytes.get(runs_at..r.pos()).ok_or(truncated)?;
        let clip_count = r.varint_u32().ok_or(truncated)?;
        let clips_at = r.pos();
        let rest = bytes.get(clips_at..).unwrap_or(&[]);
        let (mut at, mut base) = (0usize, 0u32);
        let mut repeated = 0u64;
        for _ in 0..clip_count {
            let c = record_at(rest, at, base).ok_or(truncated)?;
            if c.last >= frames {
                return Err(malformed("repeated clip past the last frame"));
            }
            check_knots(&c)?;
            repeated =
                repeated.wrapping_add(u64::from(c.last.wrapping_sub(c.start)).wrapping_add(1));
            at = c.next;
            base = c.last.wrapping_add(1);
        }
        let clips = rest.get(..at).ok_or(truncated)?;
        let body_bytes = rest.get(at..).unwrap_or(&[]);
        let body = PcaSplineCodec::parse(body_bytes, channels, frames)?;
        let t_cache = body.full_cache_words();
        Ok(RmaCodec {
            channels,
            frames,
            runs,
            clips,
            body,
            t_cache,
            few_repeats: repeated.wrapping_mul(4) <= u64::from(frames),
        })
    }

    /// Player state words the codec needs: its cursor and a scratch pose.
    pub(crate) fn state_words(&self) -> usize {
        CURSOR_WORDS.wrapping_add(self.channels)
    }

    /// The repeated clip holding `frame`, and the clip after it: the one
    /// that starts after `frame` when no clip holds it, the next record
    /// when `frame` is the holding clip's last frame (else `None`).
    /// `cursor` (two words of the player's state: a record's byte offset
    /// and the frame after the clip before it) remembers where the last
    /// search ended, so playing in order reads one record per pose; any
    /// other content only costs a search from the first record.
    fn clips_near(&self, frame: u32, cursor: &mut [i32]) -> Option<Near<'a>> {
        let (mut at, mut base) = match cursor {
            [a, b, ..] if (*b as u32) <= frame => (*a as u32 as usize, *b as u32),
            _ => (0, 0),
        };
        if at > self.clips.len() {
            (at, base) = (0, 0);
        }
        let mut restarted = at == 0;
        loop {
            if at >= self.clips.len() {
                save(cursor, at, base);
                return Some(Near::default());
            }
            let Some(c) = record_at(self.clips, at, base) else {
                if restarted {
                    return None;
                }
                (at, base, restarted) = (0, 0, true);
                continue;
            };
            save(cursor, at, base);
            if frame < c.start {
                return Some(Near {
                    here: None,
                    after: Some(c),
                });
            }
            if frame <= c.last {
                let after = if frame == c.last {
                    record_at(self.clips, c.next, c.last.wrapping_add(1))
                } else {
                    None
                };
                return Some(Near {
                    here: Some(c),
                    after,
                });
            }
            at = c.next;
            base = c.last.wrapping_add(1);
        }
    }

    /// Decodes the pose at `pos` (frames, 16.16; at most the last frame)
    /// into `out`. `state` holds the clip cursor, then the words of a
    /// scratch pose of `C` words and of the body's key-interval caches:
    /// with room for both, the scratch first, then for `t` as many words as
    /// cache its largest segment whole, the rest for `Ref(t)`; without, in
    /// a section with few repeated frames, `t`'s cache first with the
    /// scratch laid over its start (the cache is marked stale after a pose
    /// that wrote the scratch), then `Ref(t)`'s; in a section without
    /// repeated clips, every word for `t`. `segment` and `reference` are
    /// the body's segment cursors for `t` and `Ref(t)`. `None` only if an
    /// invariant of the validated section is broken or `state` is shorter
    /// than [`RmaCodec::state_words`]. The words' use never changes a
    /// decoded value.
    ///
    /// A clip weighs 1 on its frames and fades linearly over the frame
    /// before its start and the frame after its last (§12.3), so between
    /// frames `sample_at` moves from one frame's pose to the next however
    /// the body changes there. At a frame only the clip holding it counts.
    pub(crate) fn decode_at(
        &self,
        pos: u64,
        segment: &mut Cursor<'a>,
        reference: &mut Cursor<'a>,
        out: &mut [i32],
        state: &mut [i32],
    ) -> Option<()> {
        let frame = u32::try_from(pos >> FRAC_BITS).ok()?;
        let frac = (pos & ((1 << FRAC_BITS) - 1)) as i64;
        let (cursor, words) = state.split_at_mut_checked(CURSOR_WORDS)?;
        if self.clips.is_empty() {
            return self.body.decode_at(pos, segment, out, words);
        }
        let near = self.clips_near(frame, cursor)?;
        let one = 1i64 << FRAC_BITS;
        let here = near.here.map(|c| {
            let w = if frame < c.last {
                one
            } else {
                one.wrapping_sub(frac)
            };
            (c, w)
        });
        let after = near
            .after
            .filter(|c| frac > 0 && c.start == frame.wrapping_add(1))
            .map(|c| (c, frac));
        // Where `t`'s cache lies, and where `Ref(t)`'s starts: after the
        // scratch pose and `t`'s cache, or with too few words (and few
        // repeated poses) `t`'s cache from the start, under the scratch.
        let (c, len) = (self.channels, words.len());
        let overlay = self.few_repeats && len < c.wrapping_add(self.t_cache);
        let (cache_t, ref_at) = if overlay {
            let t = self.t_cache.min(len);
            (0..t, t.max(c))
        } else {
            let t = self.t_cache.min(len.saturating_sub(c));
            (c..c.wrapping_add(t), c.wrapping_add(t))
        };
        self.body
            .decode_at(pos, segment, out, words.get_mut(cache_t)?)?;
        if here.is_none() && after.is_none() {
            return Some(());
        }
        let (scratch, tail) = words.split_at_mut_checked(c)?;
        let cache_ref = tail.get_mut(ref_at.wrapping_sub(c)..).unwrap_or(&mut []);
        for (clip, weight) in here.into_iter().chain(after) {
            let at = ref_position(&clip, pos, self.frames)?;
            self.body.decode_at(at, reference, scratch, cache_ref)?;
            self.add_runs(scratch, weight, out)?;
        }
        if overlay {
            // The scratch pose was written over `t`'s cache.
            PcaSplineCodec::forget(words);
        }
        Some(())
    }

    /// `out += (scratch · weight) >> 16` on the added channels (exactly
    /// `scratch` at weight `2^16`).
    fn add_runs(&self, scratch: &[i32], weight: i64, out: &mut [i32]) -> Option<()> {
        let mut r = Reader::new(self.runs);
        let mut c = 0usize;
        while !r.is_empty() {
            c = c.wrapping_add(r.varint_u32()? as usize);
            let len = r.varint_u32()? as usize;
            let end = c.wrapping_add(len);
            let o = out.get_mut(c..end)?;
            let s = scratch.get(c..end)?;
            for (o, &s) in o.iter_mut().zip(s) {
                *o = o.wrapping_add((i64::from(s).wrapping_mul(weight) >> FRAC_BITS) as i32);
            }
            c = end;
        }
        Some(())
    }
}

/// The clips around a frame ([`RmaCodec::clips_near`]).
#[derive(Default)]
struct Near<'a> {
    here: Option<RepeatedClip<'a>>,
    after: Option<RepeatedClip<'a>>,
}

fn save(cursor: &mut [i32], at: usize, base: u32) {
    if let [a, b, ..] = cursor {
        *a = at as i32;
        *b = base as i32;
    }
}

/// Knot rules (§12.2): the first knot at time 0, times strictly increasing
/// and inside the clip, reference values that fit `i32`.
fn check_knots(c: &RepeatedClip<'_>) -> Result<(), Error> {
    if c.knot_count == 0 {
        return Err(malformed("repeated clip without knots"));
    }
    let mut r = Reader::new(c.knots);
    let mut t = 0u32;
    let mut v = i64::from(c.start) << REF_FRAC_BITS;
    for i in 0..c.knot_count {
        let dt = r.varint_u32().ok_or(malformed("section truncated"))?;
        let dv = r.zigzag_i32().ok_or(malformed("section truncated"))?;
        if i == 0 && dt != 0 {
            return Err(malformed("first knot not at the clip's start"));
        }
        if i > 0 && dt == 0 {
            return Err(malformed("knot times not increasing"));
        }
        if dt >= MAX_KNOT_GAP {
            return Err(malformed("knots 2^15 frames or more apart"));
        }
        t = t.checked_add(dt).ok_or(malformed("knot past the clip"))?;
        if u64::from(t) > u64::from(c.last.wrapping_sub(c.start)) {
            return Err(malformed("knot past the clip"));
        }
        v = v.wrapping_add(i64::from(dv));
        if i32::try_from(v).is_err() {
            return Err(malformed("reference out of range"));
        }
    }
    Ok(())
}

/// `Ref(pos)` (§12.3), 16.16 frames, clamped into the clip's frames:
/// linear between the knots around `pos`, the last knot's value after it.
/// Knots lie less than 2^15 frames apart, so the product fits `i64`.
fn ref_position(c: &RepeatedClip<'_>, pos: u64, frames: u32) -> Option<u64> {
    let rel = pos.saturating_sub(u64::from(c.start) << FRAC_BITS) as i64;
    let mut r = Reader::new(c.knots);
    let (mut t0, mut v0) = (0i64, i64::from(c.start) << REF_FRAC_BITS);
    let mut value = v0;
    for i in 0..c.knot_count {
        let t = t0.wrapping_add(i64::from(r.varint_u32()?) << FRAC_BITS);
        let v = v0.wrapping_add(i64::from(r.zigzag_i32()?));
        if i > 0 && t > rel {
            let num = v.wrapping_sub(v0).wrapping_mul(rel.wrapping_sub(t0));
            value = v0.wrapping_add(num.checked_div_euclid(t.wrapping_sub(t0))?);
            break;
        }
        (t0, v0, value) = (t, v, v);
    }
    let last = i64::from(frames.saturating_sub(1)) << FRAC_BITS;
    let at = value
        .wrapping_shl(FRAC_BITS - REF_FRAC_BITS)
        .clamp(0, last.max(0));
    Some(at as u64)
}
