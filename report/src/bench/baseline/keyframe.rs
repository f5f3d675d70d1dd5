//! `keyframe-linear`: what game engines default to — per channel, a few key
//! frames and linear interpolation between them.
//!
//! Key values are quantised with the step `max(1, ⌊tol_c / 2⌋)` (a key is
//! within `tol_c / 4` of its frame's value, the rest of the tolerance is
//! left to the interpolation; measured on cmu and iclone-cmu at 1°, 20 mm
//! and 50 mm + ARMS 10 mm this step gives 1–4 % fewer bytes than `tol_c`
//! and 8–13 % fewer than `2·tol_c + 1`). Reduction is greedy from the first frame: from each key
//! the next one is the furthest frame such that the line between the two
//! (quantised) keys, rounded as the decoder rounds it, is within `tol_c` of
//! every frame between them — a slope cone over the frames rules out what
//! cannot work, and each candidate is then checked exactly. A channel whose
//! first key is within `tol_c` of every frame keeps that one key.
//!
//! Bytes: `varint frames, varint channels`; per channel `varint step`,
//! `varint keys`, then per key its frame as the `varint` gap from the
//! previous key (none for the first key, at frame 0) and its quantised
//! value as the `zigzag varint` difference from the previous key's (from 0
//! for the first; wrapping in 32 bits). Decoded: `a + round((b − a)·(f −
//! fa)/(fb − fa))` between keys `(fa, a)` and `(fb, b)` (values `q · step`),
//! the last key held to the end.

use super::{round_div, saturate, write_shape, BaselineError, Decoded, Reader};
use mocap_encoder::container::{varint, zigzag};

const NAME: &str = "keyframe-linear";

/// The quantisation step of a channel's key values for its tolerance.
pub fn key_step(tol: i64) -> i64 {
    (tol / 2).clamp(1, i64::from(i32::MAX))
}

/// A key: its frame and its quantised value (`q · step` decoded).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Key {
    /// Frame.
    pub frame: usize,
    /// Quantised value.
    pub q: i32,
}

/// The decoded value of a key.
fn value(q: i32, step: i64) -> i64 {
    i64::from(saturate(i64::from(q) * step))
}

/// The decoded value at frame `f` between keys `(fa, a)` and `(fb, b)`.
fn between(fa: usize, a: i64, fb: usize, b: i64, f: usize) -> i64 {
    i64::from(saturate(
        a + round_div((b - a) * (f - fa) as i64, (fb - fa) as i64),
    ))
}

/// The keys of one channel at tolerance `tol` (fixed-point units).
pub fn reduce(ch: &[i32], tol: i64) -> Vec<Key> {
    let n = ch.len();
    let step = key_step(tol);
    let tol = tol.max(0);
    let key = |f: usize| Key {
        frame: f,
        q: round_div(i64::from(ch[f]), step) as i32,
    };
    if n == 0 {
        return Vec::new();
    }
    let first = key(0);
    let v0 = value(first.q, step);
    if ch.iter().all(|&v| (v0 - i64::from(v)).abs() <= tol) {
        return vec![first];
    }
    let within = |a: Key, b: Key| {
        let (va, vb) = (value(a.q, step), value(b.q, step));
        (a.frame + 1..b.frame)
            .all(|f| (between(a.frame, va, b.frame, vb, f) - i64::from(ch[f])).abs() <= tol)
    };
    let mut keys = vec![first];
    let mut at = first;
    // Rounding to the nearest integer moves a value by at most ½.
    let slack = tol as f64 + 0.5;
    while at.frame + 1 < n {
        let va = value(at.q, step) as f64;
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        let mut candidates = Vec::new();
        for (f, &v) in ch.iter().enumerate().skip(at.frame + 1) {
            let d = (f - at.frame) as f64;
            let k = key(f);
            let slope = (value(k.q, step) as f64 - va) / d;
            // The frames strictly between the keys bound the slope.
            if lo <= slope && slope <= hi {
                candidates.push(k);
            }
            let v = f64::from(v);
            lo = lo.max((v - slack - va) / d);
            hi = hi.min((v + slack - va) / d);
            if lo > hi {
                break;
            }
        }
        // The next frame always works (nothing lies between): the list is
        // never empty and its first entry is that frame.
        let next = candidates
            .iter()
            .rev()
            .copied()
            .find(|&k| within(at, k))
            .unwrap_or_else(|| key(at.frame + 1));
        keys.push(next);
        at = next;
    }
    keys
}

/// Decodes one channel's keys over `frames` frames.
pub fn expand(keys: &[Key], step: i64, frames: usize) -> Vec<i32> {
    let mut out = Vec::with_capacity(frames);
    for (i, k) in keys.iter().enumerate() {
        let v = value(k.q, step);
        match keys.get(i + 1) {
            Some(next) => {
                let w = value(next.q, step);
                out.extend(
                    (k.frame..next.frame).map(|f| between(k.frame, v, next.frame, w, f) as i32),
                );
            }
            None => out.extend((k.frame..frames).map(|_| v as i32)),
        }
    }
    out
}

/// Serialises `values` (`[channel][frame]`) at the tolerances `tol`.
pub fn encode(values: &[Vec<i32>], tol: &[i64]) -> Vec<u8> {
    let mut out = Vec::new();
    write_shape(&mut out, values);
    for (c, ch) in values.iter().enumerate() {
        let t = tol.get(c).copied().unwrap_or(0);
        let keys = reduce(ch, t);
        varint(&mut out, key_step(t) as u32);
        varint(&mut out, keys.len() as u32);
        let (mut frame, mut q) = (0usize, 0i32);
        for (i, k) in keys.iter().enumerate() {
            if i > 0 {
                varint(&mut out, (k.frame - frame) as u32);
            }
            zigzag(&mut out, k.q.wrapping_sub(q));
            (frame, q) = (k.frame, k.q);
        }
    }
    out
}

/// Decodes what [`encode`] wrote.
pub fn decode(bytes: &[u8]) -> Result<Decoded, BaselineError> {
    let mut r = Reader::new(bytes, NAME);
    let (frames, channels) = r.shape(0)?;
    let mut values = vec![0i32; frames * channels];
    for c in 0..channels {
        let step = r.varint("key step")?;
        if step == 0 {
            return Err(r.malformed("a step of 0"));
        }
        let count = r.varint("key count")? as usize;
        if count == 0 && frames > 0 || count > frames {
            return Err(r.malformed("a key count of 0 or more keys than frames"));
        }
        let mut keys = Vec::with_capacity(count);
        let (mut frame, mut q) = (0usize, 0i32);
        for i in 0..count {
            if i > 0 {
                let gap = r.varint("key frame gap")? as usize;
                frame += gap;
                if gap == 0 || frame >= frames {
                    return Err(r.malformed("key frames not increasing inside the clip"));
                }
            }
            q = q.wrapping_add(r.zigzag("key value difference")?);
            keys.push(Key { frame, q });
        }
        for (f, v) in expand(&keys, i64::from(step), frames)
            .into_iter()
            .enumerate()
        {
            values[f * channels + c] = v;
        }
    }
    r.finish()?;
    Ok(Decoded {
        frames,
        channels,
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A piecewise-linear curve (breaks at 0, 30, 45, 100, 140, 199, values
    /// on the key grid): exactly its breaks are kept, and it decodes
    /// exactly.
    #[test]
    fn keeps_exactly_the_keys_of_a_piecewise_linear_curve() {
        let tol = 4;
        let step = key_step(tol);
        let breaks = [
            (0usize, 0i64),
            (30, 3000),
            (45, -1500),
            (100, -1500),
            (140, 6000),
            (199, 6004),
        ];
        let mut ch = Vec::new();
        for w in breaks.windows(2) {
            let ((fa, a), (fb, b)) = (w[0], w[1]);
            for f in fa..fb {
                ch.push(between(fa, a, fb, b, f) as i32);
            }
        }
        ch.push(6004);
        let keys = reduce(&ch, tol);
        let frames: Vec<usize> = keys.iter().map(|k| k.frame).collect();
        assert_eq!(frames, [0, 30, 45, 100, 140, 199]);
        assert!(keys
            .iter()
            .zip(&breaks)
            .all(|(k, &(_, v))| i64::from(k.q) * step == v));
        assert_eq!(expand(&keys, step, ch.len()), ch);
    }

    /// Every decoded value within the tolerance, on smooth, noisy and
    /// jumping channels; far fewer keys than frames on the smooth one.
    #[test]
    fn interpolation_stays_within_the_tolerance() {
        let smooth: Vec<i32> = (0..300)
            .map(|f| (20_000.0 * (f as f64 / 40.0).sin()) as i32)
            .collect();
        let noisy: Vec<i32> = (0..300).map(|f| (f * 7919) % 101 * 10).collect();
        let jump: Vec<i32> = (0..300)
            .map(|f| if f < 150 { -90_000 } else { 90_000 })
            .collect();
        for tol in [0, 1, 50, 500] {
            for ch in [&smooth, &noisy, &jump] {
                let keys = reduce(ch, tol);
                let back = expand(&keys, key_step(tol), ch.len());
                assert_eq!(back.len(), ch.len());
                assert!(
                    back.iter()
                        .zip(ch.iter())
                        .all(|(a, b)| (i64::from(*a) - i64::from(*b)).abs() <= tol),
                    "tol {tol}"
                );
            }
        }
        assert!(reduce(&smooth, 500).len() < 40);
        assert_eq!(reduce(&jump, 500).len(), 4);
        assert_eq!(reduce(&[5; 50], 0).len(), 1);
    }

    /// The bytes are exactly the serialisation: shape, then per channel
    /// step, key count, gaps and value differences.
    #[test]
    fn bytes_are_the_keys() {
        let values = vec![vec![0, 10, 20, 30, 20, 10], vec![7; 6]];
        let bytes = encode(&values, &[0, 0]);
        // 6 frames, 2 channels | step 1, 3 keys: q 0; gap 3, +30; gap 2, −20 | step 1, 1 key: 7.
        assert_eq!(bytes, [6, 2, 1, 3, 0, 3, 60, 2, 39, 1, 1, 14]);
        let d = decode(&bytes).unwrap();
        assert_eq!(d.channel(0), [0, 10, 20, 30, 20, 10]);
        assert_eq!(d.channel(1), [7; 6]);
        for n in 0..bytes.len() {
            assert!(decode(&bytes[..n]).is_err(), "{n}");
        }
    }
}
