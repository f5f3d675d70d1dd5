//! Missing samples (SPEC.md §3.7, ancillary section `0x81`): which samples of
//! a marker clip were missing in the capture (the encoder filled them in so
//! the clip plays smoothly; a player that cares can hide them). Validated
//! once by [`Clip::parse`](crate::Clip::parse), queried without allocation.

use crate::error::Error;
use crate::reader::Reader;

/// The missing-sample mask of a clip: per marker (joint of the header),
/// runs of present and missing frames.
#[derive(Clone, Copy, Debug)]
pub struct Missing<'a> {
    /// The section after its marker count.
    runs: &'a [u8],
    markers: u32,
    frames: u32,
    count: u32,
    run_count: u32,
}

/// Checks the section (SPEC.md §3.7) against the header's `joints` and
/// `frames`.
pub(crate) fn parse(bytes: &[u8], joints: usize, frames: u32) -> Result<Missing<'_>, Error> {
    let mut r = Reader::new(bytes);
    let malformed = |r: &Reader<'_>| Error::MissingMalformed { offset: r.pos() };
    let markers = r.varint_u32().ok_or_else(|| malformed(&r))?;
    if usize::try_from(markers).ok() != Some(joints) {
        return Err(Error::MissingMarkerCount {
            markers,
            joints: u32::try_from(joints).unwrap_or(u32::MAX),
        });
    }
    let runs = bytes.get(r.pos()..).unwrap_or(&[]);
    let mut count = 0u32;
    let mut run_count = 0u32;
    for marker in 0..markers {
        let n = r.varint_u32().ok_or_else(|| malformed(&r))?;
        let mut total = 0u32;
        for i in 0..n {
            let len = r.varint_u32().ok_or_else(|| malformed(&r))?;
            if len == 0 && i > 0 {
                return Err(Error::MissingEmptyRun { marker, run: i });
            }
            total = total
                .checked_add(len)
                .filter(|&t| t <= frames)
                .ok_or(Error::MissingRunTotal { marker, frames })?;
            if i & 1 == 1 {
                count = count.saturating_add(len);
                run_count = run_count.saturating_add(1);
            }
        }
        if n > 0 && total != frames {
            return Err(Error::MissingRunTotal { marker, frames });
        }
    }
    if !r.is_empty() {
        return Err(Error::MissingTrailingBytes { offset: r.pos() });
    }
    Ok(Missing {
        runs,
        markers,
        frames,
        count,
        run_count,
    })
}

impl<'a> Missing<'a> {
    /// Markers (the header's joints).
    pub fn markers(&self) -> u32 {
        self.markers
    }

    /// Frames (the header's).
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Missing samples over all markers.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Runs of missing samples over all markers.
    pub fn run_count(&self) -> u32 {
        self.run_count
    }

    /// The missing runs of `marker` as `(first frame, length)`, in frame
    /// order (none for a marker past the mask or never missing).
    pub fn runs(&self, marker: u32) -> MissingRuns<'a> {
        let mut r = Reader::new(self.runs);
        // Skip the markers before it (validated: every read succeeds).
        let mut left = 0;
        for k in 0..=marker.min(self.markers) {
            let n = r.varint_u32().unwrap_or(0);
            if k == marker {
                left = n;
                break;
            }
            for _ in 0..n {
                let _ = r.varint_u32();
            }
        }
        MissingRuns {
            r,
            left,
            index: 0,
            frame: 0,
        }
    }

    /// Whether `marker` is missing at `frame` (false past the mask).
    pub fn is_missing(&self, frame: u32, marker: u32) -> bool {
        self.runs(marker)
            .take_while(|&(start, _)| start <= frame)
            .any(|(start, len)| frame.wrapping_sub(start) < len)
    }
}

/// Iterator over one marker's missing runs: `(first frame, length)`.
#[derive(Clone, Debug)]
pub struct MissingRuns<'a> {
    r: Reader<'a>,
    left: u32,
    index: u32,
    frame: u32,
}

impl Iterator for MissingRuns<'_> {
    type Item = (u32, u32);

    fn next(&mut self) -> Option<(u32, u32)> {
        while self.left > 0 {
            self.left = self.left.wrapping_sub(1);
            let len = self.r.varint_u32()?;
            let start = self.frame;
            self.frame = self.frame.saturating_add(len);
            let missing = self.index & 1 == 1;
            self.index = self.index.wrapping_add(1);
            if missing {
                return Some((start, len));
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    #[test]
    fn runs_and_queries() {
        // 3 markers, 6 frames: never; missing 0–1 and 4; missing 5.
        let bytes = [3, 0, 5, 0, 2, 2, 1, 1, 2, 5, 1];
        let m = parse(&bytes, 3, 6).unwrap();
        assert_eq!(
            (m.markers(), m.frames(), m.count(), m.run_count()),
            (3, 6, 4, 3)
        );
        assert_eq!(m.runs(0).count(), 0);
        assert_eq!(m.runs(1).collect::<Vec<_>>(), [(0, 2), (4, 1)]);
        assert_eq!(m.runs(2).collect::<Vec<_>>(), [(5, 1)]);
        assert_eq!(m.runs(3).count(), 0);
        let grid: Vec<bool> = (0..6)
            .flat_map(|f| (0..3).map(move |k| (f, k)))
            .map(|(f, k)| m.is_missing(f, k))
            .collect();
        let want: Vec<bool> = (0..6)
            .flat_map(|f| (0..3).map(move |k| (f, k)))
            .map(|(f, k)| (k == 1 && [0, 1, 4].contains(&f)) || (k == 2 && f == 5))
            .collect();
        assert_eq!(grid, want);
        assert!(!m.is_missing(9, 1));
    }

    #[test]
    fn every_rule_has_its_error() {
        assert_eq!(
            parse(&[2, 0, 0], 3, 6).unwrap_err(),
            Error::MissingMarkerCount {
                markers: 2,
                joints: 3
            }
        );
        assert_eq!(
            parse(&[1, 2, 3, 2], 1, 6).unwrap_err(),
            Error::MissingRunTotal {
                marker: 0,
                frames: 6
            }
        );
        assert_eq!(
            parse(&[1, 3, 3, 4], 1, 6).unwrap_err(),
            Error::MissingRunTotal {
                marker: 0,
                frames: 6
            }
        );
        assert_eq!(
            parse(&[1, 3, 3, 0, 3], 1, 6).unwrap_err(),
            Error::MissingEmptyRun { marker: 0, run: 1 }
        );
        assert_eq!(
            parse(&[1, 2, 3], 1, 6).unwrap_err(),
            Error::MissingMalformed { offset: 3 }
        );
        assert_eq!(
            parse(&[1, 0, 0], 1, 6).unwrap_err(),
            Error::MissingTrailingBytes { offset: 2 }
        );
        assert_eq!(
            parse(&[1, 2, 0x80], 1, 6).unwrap_err(),
            Error::MissingMalformed { offset: 2 }
        );
        // Every truncation is an error, never a panic.
        let bytes = [3, 0, 5, 0, 2, 2, 1, 1, 2, 5, 1];
        for n in 0..bytes.len() {
            assert!(parse(&bytes[..n], 3, 6).is_err());
        }
    }
}
