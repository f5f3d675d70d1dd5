//! The parameter section: groups and parameters, their types and
//! dimensions, and typed access to the few the reader needs.
//!
//! A record is `i8 name length` (negative: locked; 0 ends the section),
//! `i8 group id` (negative: a group, positive: a parameter of group `|id|`),
//! the name, `i16` offset from that word to the next record (0: the last
//! record), then for a group a description, for a parameter `i8 type` (−1
//! char, 1 byte, 2 int16, 4 float), `u8` dimension count, the dimensions,
//! the data (row-major, first dimension fastest) and a description.

use super::bytes::Bytes;
use super::C3dError;

/// One parameter: where its data is and how it is laid out.
#[derive(Clone, Debug)]
pub(super) struct Param {
    /// Group id (positive).
    pub group: u8,
    /// Name, upper case.
    pub name: String,
    /// −1 char, 1 byte, 2 int16, 4 float.
    pub kind: i8,
    /// Dimensions (empty: a scalar).
    pub dims: Vec<usize>,
    /// Elements: the product of the dimensions (1 for a scalar), checked.
    elements: usize,
    /// Offset of the first data byte.
    pub data_at: usize,
    /// Offset of the record (for errors).
    pub record_at: usize,
}

impl Param {
    /// Elements (product of the dimensions; 1 for a scalar).
    pub fn elements(&self) -> usize {
        self.elements
    }

    /// Bytes per element.
    fn width(&self) -> usize {
        usize::from(self.kind.unsigned_abs())
    }
}

/// The parsed parameter section.
pub(super) struct Params {
    /// `(id, name)` of every group (id positive).
    groups: Vec<(u8, String)>,
    params: Vec<Param>,
}

impl Params {
    /// Parses the section at `start` (its 4-byte header already read),
    /// `blocks` 512-byte blocks long.
    pub fn parse(b: &Bytes<'_>, start: usize, blocks: usize) -> Result<Params, C3dError> {
        let end = start.saturating_add(blocks.saturating_mul(512));
        let mut groups = Vec::new();
        let mut params = Vec::new();
        let mut at = start + 4;
        loop {
            if at >= end {
                break;
            }
            let len = b.i8(at, "a parameter record's name length")?;
            if len == 0 {
                break;
            }
            let id = b.i8(at + 1, "a parameter record's group id")?;
            let n = usize::from(len.unsigned_abs());
            let name_bytes = b.take(at + 2, n, "a parameter record's name")?;
            let name = String::from_utf8_lossy(name_bytes)
                .trim()
                .to_ascii_uppercase();
            let next_word = at + 2 + n;
            let next = b.i16(next_word, "a parameter record's next-record offset")?;
            if id == 0 {
                return Err(b.err(at + 1, format!("parameter record '{name}' has group id 0")));
            }
            if id < 0 {
                groups.push((id.unsigned_abs(), name));
            } else {
                let kind_at = next_word + 2;
                let kind = b.i8(kind_at, "a parameter's type")?;
                if !matches!(kind, -1 | 1 | 2 | 4) {
                    return Err(b.err(
                        kind_at,
                        format!("parameter '{name}' has type {kind} (expected -1, 1, 2 or 4)"),
                    ));
                }
                let ndims = usize::from(b.u8(kind_at + 1, "a parameter's dimension count")?);
                let dims: Vec<usize> = b
                    .take(kind_at + 2, ndims, "a parameter's dimensions")?
                    .iter()
                    .map(|&d| usize::from(d))
                    .collect();
                let elements = dims
                    .iter()
                    .try_fold(1usize, |a, &d| a.checked_mul(d))
                    .filter(|&n| n <= b.data.len())
                    .ok_or_else(|| {
                        b.err(
                            kind_at + 1,
                            format!("parameter '{name}' has dimensions {dims:?}: more elements than the file has bytes"),
                        )
                    })?;
                let p = Param {
                    group: id.unsigned_abs(),
                    name,
                    kind,
                    dims,
                    elements,
                    data_at: kind_at + 2 + ndims,
                    record_at: at,
                };
                // The data must be in the file (read lazily, checked now).
                b.take(
                    p.data_at,
                    p.elements() * p.width(),
                    &format!("the data of parameter '{}'", p.name),
                )?;
                params.push(p);
            }
            if next == 0 {
                break;
            }
            if next < 0 {
                return Err(b.err(
                    next_word,
                    format!("parameter record points backwards (offset {next})"),
                ));
            }
            at = next_word + next as usize;
            if at > end {
                return Err(b.err(
                    next_word,
                    format!(
                        "parameter record points to byte {at}, past the parameter section's end at byte {end}"
                    ),
                ));
            }
        }
        Ok(Params { groups, params })
    }

    /// The parameter `GROUP:NAME` (case-insensitive).
    pub fn get(&self, group: &str, name: &str) -> Option<&Param> {
        let id = self
            .groups
            .iter()
            .find(|(_, g)| g.eq_ignore_ascii_case(group))?
            .0;
        self.params
            .iter()
            .find(|p| p.group == id && p.name.eq_ignore_ascii_case(name))
    }

    /// A number parameter's first element as `f64` (byte: unsigned, int16:
    /// signed, float: as is); `None` when absent; an error for a char
    /// parameter, no element, or not a number.
    pub fn number(&self, b: &Bytes<'_>, group: &str, name: &str) -> Result<Option<f64>, C3dError> {
        let Some(p) = self.get(group, name) else {
            return Ok(None);
        };
        let what = format!("{group}:{name}");
        if p.elements() == 0 || p.kind == -1 {
            return Err(b.err(
                p.record_at,
                format!(
                    "{what} is not a number (type {}, {} elements)",
                    p.kind,
                    p.elements()
                ),
            ));
        }
        Ok(Some(match p.kind {
            1 => f64::from(b.u8(p.data_at, &what)?),
            2 => f64::from(b.i16(p.data_at, &what)?),
            _ => b.f32(p.data_at, &what)?,
        }))
    }

    /// A count parameter (`POINT:USED`, `POINT:FRAMES`, `POINT:DATA_START`):
    /// int16 words are read unsigned (C3D stores counts up to 65 535 in
    /// them), floats must be whole and non-negative.
    pub fn count(&self, b: &Bytes<'_>, group: &str, name: &str) -> Result<Option<usize>, C3dError> {
        let Some(p) = self.get(group, name) else {
            return Ok(None);
        };
        let what = format!("{group}:{name}");
        if p.kind == 2 && p.elements() > 0 {
            return Ok(Some(usize::from(b.u16(p.data_at, &what)?)));
        }
        let v = self.number(b, group, name)?.unwrap_or(0.0);
        if !(v >= 0.0 && v.fract() == 0.0 && v <= 1e9) {
            return Err(b.err(p.data_at, format!("{what} is {v}, not a count")));
        }
        Ok(Some(v as usize))
    }

    /// A char parameter as strings: dimensions `[len, count…]` give
    /// `count…` strings of `len` bytes (`[len]` or no dimension: one),
    /// trimmed of spaces and NULs. Each comes with the offset of its bytes.
    pub fn strings(
        &self,
        b: &Bytes<'_>,
        group: &str,
        name: &str,
    ) -> Result<Option<Vec<(String, usize)>>, C3dError> {
        let Some(p) = self.get(group, name) else {
            return Ok(None);
        };
        if p.kind != -1 {
            return Err(b.err(
                p.record_at,
                format!("{group}:{name} has type {}, not characters", p.kind),
            ));
        }
        let (len, count) = match p.dims.split_first() {
            None => (1, 1),
            // Strings of no characters: none (their count could be anything).
            Some((0, _)) => (0, 0),
            // `len · count` elements are in the file (checked when parsed).
            Some((&len, _)) => (len, p.elements() / len),
        };
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let at = p.data_at + i * len;
            let raw = b.take(at, len, &format!("{group}:{name}"))?;
            let text = String::from_utf8_lossy(raw);
            out.push((
                text.trim_matches(|c: char| c == ' ' || c == '\0')
                    .to_string(),
                at,
            ));
        }
        Ok(Some(out))
    }

    /// Offset of the record of `GROUP:NAME` (for errors about its value).
    pub fn record_at(&self, group: &str, name: &str) -> Option<usize> {
        self.get(group, name).map(|p| p.record_at)
    }
}
