//! `raw16`: what servo and animatronics exporters store — every channel of
//! every frame as a 16-bit integer at a fixed-point step that fits the
//! channel's range.
//!
//! Bytes: `varint frames, varint channels`; per channel `zigzag varint
//! base` (its smallest value) and `varint step` (fixed-point units per code,
//! `max(1, ⌈(max − min) / 65535⌉)`); then frame after frame, channel after
//! channel, the code `round((v − base) / step)` as a little-endian `u16`.
//! Decoded value `base + code · step`; the error is at most `step / 2`.

use super::{round_div, saturate, write_shape, BaselineError, Decoded, Reader};
use mocap_encoder::container::{varint, zigzag};

const NAME: &str = "raw16";

/// The step of a channel: the smallest integer that fits its range in 16 bits.
pub fn step(channel: &[i32]) -> u32 {
    let (lo, hi) = range(channel);
    let span = i64::from(hi) - i64::from(lo);
    (span + 65534).div_euclid(65535).max(1) as u32
}

fn range(channel: &[i32]) -> (i32, i32) {
    let lo = channel.iter().copied().min().unwrap_or(0);
    let hi = channel.iter().copied().max().unwrap_or(0);
    (lo, hi)
}

/// Serialises `values` (`[channel][frame]`).
pub fn encode(values: &[Vec<i32>]) -> Vec<u8> {
    let mut out = Vec::new();
    write_shape(&mut out, values);
    let params: Vec<(i32, i64)> = values
        .iter()
        .map(|ch| (range(ch).0, i64::from(step(ch))))
        .collect();
    for &(base, s) in &params {
        zigzag(&mut out, base);
        varint(&mut out, s as u32);
    }
    let frames = values.first().map_or(0, Vec::len);
    for f in 0..frames {
        for (ch, &(base, s)) in values.iter().zip(&params) {
            // (max − min) / step ≤ 65535: every code fits.
            let code = round_div(i64::from(ch[f]) - i64::from(base), s).clamp(0, 65535);
            out.extend_from_slice(&(code as u16).to_le_bytes());
        }
    }
    out
}

/// Decodes what [`encode`] wrote.
pub fn decode(bytes: &[u8]) -> Result<Decoded, BaselineError> {
    let mut r = Reader::new(bytes, NAME);
    let (frames, channels) = r.shape(2)?;
    let mut params = Vec::with_capacity(channels);
    for _ in 0..channels {
        let base = r.zigzag("channel base")?;
        let step = r.varint("channel step")?;
        if step == 0 {
            return Err(r.malformed("a step of 0"));
        }
        params.push((i64::from(base), i64::from(step)));
    }
    let mut values = Vec::with_capacity(frames * channels);
    for _ in 0..frames {
        for &(base, step) in &params {
            let code = r.u16_le("a value")?;
            values.push(saturate(base + i64::from(code) * step));
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

    /// Two bytes per value plus the parameters; the error of each channel
    /// at most half its step; a channel whose range fits 16 bits is exact.
    #[test]
    fn sixteen_bits_per_value_within_half_a_step() {
        let narrow: Vec<i32> = (0..50).map(|f| (f * 37) % 1000 - 500).collect();
        let wide: Vec<i32> = (0..50).map(|f| f * 123_457 - 3_000_000).collect();
        let values = vec![narrow.clone(), wide.clone(), vec![7; 50]];
        let bytes = encode(&values);
        let mut params = Vec::new();
        for ch in &values {
            zigzag(&mut params, range(ch).0);
            varint(&mut params, step(ch));
        }
        assert_eq!(bytes.len(), 2 + params.len() + 50 * 3 * 2);
        let d = decode(&bytes).unwrap();
        assert_eq!((d.frames, d.channels), (50, 3));
        assert_eq!(d.channel(0), narrow);
        assert_eq!(d.channel(2), vec![7; 50]);
        let s = i64::from(step(&wide));
        assert!(s > 1);
        assert!(d
            .channel(1)
            .iter()
            .zip(&wide)
            .all(|(a, b)| 2 * (i64::from(*a) - i64::from(*b)).abs() <= s));
        // The largest value is reached within half a step, not clamped away.
        assert!(i64::from(*d.channel(1).last().unwrap()) - i64::from(*wide.last().unwrap()) <= s);
    }

    #[test]
    fn truncated_bytes_are_refused() {
        let bytes = encode(&[vec![1, 2, 3]]);
        for n in 0..bytes.len() {
            assert!(decode(&bytes[..n]).is_err(), "{n}");
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(decode(&long).is_err());
    }
}
