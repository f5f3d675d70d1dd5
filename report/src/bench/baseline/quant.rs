//! `quant+zstd`, `quant+xz`: uniform quantisation at the bound, then a
//! general-purpose compressor — what a user reaches for first.
//!
//! Each channel `c` is quantised with the step `2·tol_c + 1` (its tolerance
//! from the encode pipeline, fixed-point units): `q = round(v / step)`,
//! decoded `q · step`, so every value is within `tol_c`. The stream before
//! compression: `varint frames, varint channels`; per channel `varint step`;
//! then channel after channel its first code and its frame-to-frame code
//! differences (wrapping in 32 bits), each a `zigzag varint` — constant and
//! slow channels become runs of zero bytes, which both compressors take to
//! almost nothing. The bytes counted are the whole stream compressed by
//! zstd at level 19 or by xz at preset 9 extreme (one `.zst` / `.xz` frame
//! each, with the compressor's own header and checksum).

use super::{round_div, saturate, write_shape, BaselineError, Decoded, Reader};
use mocap_encoder::container::{varint, zigzag};

const NAME: &str = "quant";

/// zstd's level: the highest of its normal range.
pub const ZSTD_LEVEL: i32 = 19;
/// xz's preset: 9 with the extreme flag (`xz -9e`).
pub const XZ_PRESET: u32 = 9 | liblzma::stream::PRESET_EXTREME;

/// The general-purpose compressor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compressor {
    /// zstd, level [`ZSTD_LEVEL`].
    Zstd,
    /// xz (LZMA2), preset [`XZ_PRESET`].
    Xz,
}

impl Compressor {
    fn name(self) -> &'static str {
        match self {
            Compressor::Zstd => "zstd",
            Compressor::Xz => "xz",
        }
    }

    fn error(self) -> impl FnOnce(std::io::Error) -> BaselineError {
        move |source| BaselineError::Compressor {
            compressor: self.name(),
            source,
        }
    }

    /// Compresses `plain`.
    pub fn compress(self, plain: &[u8]) -> Result<Vec<u8>, BaselineError> {
        match self {
            Compressor::Zstd => zstd::bulk::compress(plain, ZSTD_LEVEL),
            Compressor::Xz => liblzma::encode_all(plain, XZ_PRESET),
        }
        .map_err(self.error())
    }

    /// Decompresses what [`Compressor::compress`] wrote.
    pub fn decompress(self, bytes: &[u8]) -> Result<Vec<u8>, BaselineError> {
        match self {
            Compressor::Zstd => zstd::stream::decode_all(bytes),
            Compressor::Xz => liblzma::decode_all(bytes),
        }
        .map_err(self.error())
    }
}

/// The step of a channel of tolerance `tol`: `2·tol + 1`, at least 1.
pub fn step(tol: i64) -> u32 {
    (2 * tol.clamp(0, i64::from(i32::MAX)) + 1) as u32
}

/// The stream before compression (see the module documentation).
pub fn plain(values: &[Vec<i32>], tol: &[i64]) -> Result<Vec<u8>, BaselineError> {
    if tol.len() != values.len() {
        return Err(BaselineError::OutOfRange {
            baseline: NAME,
            what: format!("{} tolerances for {} channels", tol.len(), values.len()),
        });
    }
    let mut out = Vec::new();
    write_shape(&mut out, values);
    let steps: Vec<u32> = tol.iter().map(|&t| step(t)).collect();
    for &s in &steps {
        varint(&mut out, s);
    }
    for (ch, &s) in values.iter().zip(&steps) {
        let mut prev = 0i32;
        for &v in ch {
            // |round(v / s)| ≤ |v| for s ≥ 1: the code fits i32.
            let q = round_div(i64::from(v), i64::from(s)) as i32;
            zigzag(&mut out, q.wrapping_sub(prev));
            prev = q;
        }
    }
    Ok(out)
}

/// Quantises `values` (`[channel][frame]`) at the tolerances `tol` and
/// compresses the stream.
pub fn encode(
    values: &[Vec<i32>],
    tol: &[i64],
    compressor: Compressor,
) -> Result<Vec<u8>, BaselineError> {
    compressor.compress(&plain(values, tol)?)
}

/// Decodes the stream before compression.
pub fn decode_plain(bytes: &[u8]) -> Result<Decoded, BaselineError> {
    let mut r = Reader::new(bytes, NAME);
    let (frames, channels) = r.shape(1)?;
    let mut steps = Vec::with_capacity(channels);
    for _ in 0..channels {
        let s = r.varint("channel step")?;
        if s == 0 {
            return Err(r.malformed("a step of 0"));
        }
        steps.push(i64::from(s));
    }
    let mut values = vec![0i32; frames * channels];
    for (c, &s) in steps.iter().enumerate() {
        let mut q = 0i32;
        for f in 0..frames {
            q = q.wrapping_add(r.zigzag("a code difference")?);
            values[f * channels + c] = saturate(i64::from(q) * s);
        }
    }
    r.finish()?;
    Ok(Decoded {
        frames,
        channels,
        values,
    })
}

/// Decompresses and decodes what [`encode`] wrote.
pub fn decode(bytes: &[u8], compressor: Compressor) -> Result<Decoded, BaselineError> {
    decode_plain(&compressor.decompress(bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channels() -> Vec<Vec<i32>> {
        vec![
            (0..200).map(|f| (f * f) % 7919 - 4000).collect(),
            vec![123_456; 200],
            (0..200).map(|f| i32::MAX - f).collect(),
            (0..200)
                .map(|f| if f % 2 == 0 { i32::MIN } else { 0 })
                .collect(),
        ]
    }

    /// Every decoded value within its channel's tolerance, extreme values
    /// included; a tolerance of 0 is lossless.
    #[test]
    fn quantisation_stays_within_each_tolerance() {
        let values = channels();
        for tol in [
            [0i64, 0, 0, 0],
            [3, 1000, 7, 0],
            [250, 0, 1 << 20, i64::from(i32::MAX)],
        ] {
            for compressor in [Compressor::Zstd, Compressor::Xz] {
                let d = decode(&encode(&values, &tol, compressor).unwrap(), compressor).unwrap();
                assert_eq!((d.frames, d.channels), (200, 4));
                for (c, ch) in values.iter().enumerate() {
                    let got = d.channel(c);
                    for (a, b) in got.iter().zip(ch) {
                        assert!(
                            (i64::from(*a) - i64::from(*b)).abs() <= tol[c],
                            "{compressor:?} channel {c} tol {}: {a} vs {b}",
                            tol[c]
                        );
                    }
                    if tol[c] == 0 {
                        assert_eq!(&got, ch);
                    }
                }
            }
        }
    }

    /// The bytes counted are the compressed stream, and they decompress to
    /// exactly the plain stream.
    #[test]
    fn bytes_are_the_compressed_stream() {
        let values = channels();
        let tol = [10, 10, 10, 10];
        let plain = plain(&values, &tol).unwrap();
        for compressor in [Compressor::Zstd, Compressor::Xz] {
            let bytes = encode(&values, &tol, compressor).unwrap();
            assert_eq!(bytes, compressor.compress(&plain).unwrap());
            assert_eq!(compressor.decompress(&bytes).unwrap(), plain);
            assert!(bytes.len() < plain.len(), "{compressor:?}");
        }
        // zstd's and xz's own magic numbers: real frames of each.
        assert_eq!(
            &encode(&values, &tol, Compressor::Zstd).unwrap()[..4],
            &[0x28, 0xb5, 0x2f, 0xfd]
        );
        assert_eq!(
            &encode(&values, &tol, Compressor::Xz).unwrap()[..6],
            b"\xfd7zXZ\0"
        );
    }

    #[test]
    fn corrupt_streams_are_refused() {
        let values = channels();
        let bytes = encode(&values, &[1, 1, 1, 1], Compressor::Zstd).unwrap();
        assert!(decode(&bytes[..bytes.len() / 2], Compressor::Zstd).is_err());
        assert!(decode(&bytes, Compressor::Xz).is_err());
        let plain = plain(&values, &[1, 1, 1, 1]).unwrap();
        assert!(decode_plain(&plain[..plain.len() - 1]).is_err());
    }
}
