//! Writes a [`Model`] as the `pca-spline` section (SPEC.md §5) and reads
//! the figures `mocap info` prints back out of a section.

use mocap_decoder::consts::pca::MAX_TIME_BITS;

use super::{GroupModel, Model};
use crate::codec::bits::BitWriter;
use crate::container::{varint, zigzag, ByteCursor};

fn index(out: &mut Vec<u8>, c: usize, wide: bool) {
    out.push(c as u8);
    if wide {
        out.push((c >> 8) as u8);
    }
}

impl Model {
    /// The section bytes (SPEC.md §5.2–§5.3).
    pub fn to_section(&self, channels: usize) -> Vec<u8> {
        let wide = channels > 256;
        let mut out = vec![if wide { 2 } else { 1 }];
        varint(&mut out, self.groups.len() as u32);
        for g in &self.groups {
            varint(&mut out, g.len() as u32);
            for &c in g {
                index(&mut out, c, wide);
            }
        }
        varint(&mut out, self.consts.len() as u32);
        for &(c, _) in &self.consts {
            index(&mut out, c, wide);
        }
        for &(_, v) in &self.consts {
            zigzag(&mut out, v);
        }
        varint(&mut out, self.segments.len() as u32);
        for s in &self.segments {
            varint(&mut out, s.start);
            varint(&mut out, s.end);
            let mut body = Vec::new();
            for g in &s.groups {
                write_group(&mut body, g, s.end - s.start + 1);
            }
            varint(&mut out, body.len() as u32);
            out.extend_from_slice(&body);
            let mut patches = Vec::new();
            let mut at = 0;
            for &(f, c, v) in &s.patches {
                varint(&mut patches, f - at);
                index(&mut patches, c, wide);
                zigzag(&mut patches, v);
                at = f;
            }
            varint(&mut out, patches.len() as u32);
            out.extend_from_slice(&patches);
        }
        out
    }
}

fn write_group(out: &mut Vec<u8>, g: &GroupModel, len: u32) {
    out.push(g.k as u8);
    out.push(g.mean_shift);
    if g.k == 0 {
        for &m in &g.mean {
            zigzag(out, i32::from(m));
        }
        return;
    }
    for m in &g.mean {
        out.extend_from_slice(&m.to_le_bytes());
    }
    out.extend(g.basis.iter().map(|&b| b as u8));
    varint(out, g.times.len() as u32);
    let time_bits = (32 - (len - 1).leading_zeros()).clamp(1, u32::from(MAX_TIME_BITS)) as u8;
    out.push(time_bits);
    for &(w, s, o) in &g.comps {
        out.push(w);
        out.push(s);
        zigzag(out, o);
    }
    let mut bits = BitWriter::default();
    for &t in &g.times {
        bits.write(t, time_bits);
    }
    for row in g.codes.chunks(g.k) {
        for (&c, &(w, _, _)) in row.iter().zip(&g.comps) {
            bits.write(c, w);
        }
    }
    out.extend(bits.finish());
}

/// A segment's start and end frames and, per group, (k, keys).
pub type SegmentInfo = (u32, u32, Vec<(usize, usize)>);

/// Figures of a `pca-spline` section for `mocap info`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SectionInfo {
    /// Channel groups (separate curves plus the PCA body).
    pub groups: usize,
    /// Channels of each group.
    pub group_channels: Vec<usize>,
    /// Constant channels.
    pub consts: usize,
    /// Per segment: start, end, and per group (k, keys).
    pub segments: Vec<SegmentInfo>,
    /// Bytes of means, bases and key bits over all segments.
    pub mean_bytes: usize,
    /// Bytes of bases.
    pub basis_bytes: usize,
    /// Bytes of key times and values (and their parameters).
    pub key_bytes: usize,
    /// Bytes of patches.
    pub patch_bytes: usize,
}

impl SectionInfo {
    /// The lines `mocap info` prints for the section.
    pub fn describe(&self) -> String {
        let keys: usize = self
            .segments
            .iter()
            .flat_map(|(_, _, g)| g.iter().map(|&(_, m)| m))
            .sum();
        let mut s = format!(
            "  pca-spline codec: {} groups, {} constant channels, {} segments, {keys} keys\n  bytes: means {}, bases {}, keys {}, patches {}\n",
            self.groups,
            self.consts,
            self.segments.len(),
            self.mean_bytes,
            self.basis_bytes,
            self.key_bytes,
            self.patch_bytes
        );
        for (start, end, groups) in &self.segments {
            let g: Vec<String> = groups.iter().map(|(k, m)| format!("k{k}/{m}")).collect();
            s += &format!("  segment {start}..={end}: {}\n", g.join(" "));
        }
        s
    }
}

/// Reads the figures back from a section (already validated by the
/// decoder); `None` if it does not parse.
pub fn inspect(section: &[u8]) -> Option<SectionInfo> {
    let mut r = ByteCursor::new(section);
    let wide = r.u8()? == 2;
    let w = if wide { 2 } else { 1 };
    let groups = r.varint()? as usize;
    let mut sizes = Vec::new();
    for _ in 0..groups {
        let n = r.varint()? as usize;
        r.skip(n * w)?;
        sizes.push(n);
    }
    let consts = r.varint()? as usize;
    r.skip(consts * w)?;
    for _ in 0..consts {
        r.varint()?;
    }
    let mut info = SectionInfo {
        groups,
        group_channels: sizes.clone(),
        consts,
        ..SectionInfo::default()
    };
    let count = r.varint()?;
    for _ in 0..count {
        let start = r.varint()?;
        let end = r.varint()?;
        let len = r.varint()? as usize;
        let stop = r.pos() + len;
        let mut per = Vec::new();
        for &n in &sizes {
            let k = r.u8()? as usize;
            r.u8()?;
            if k == 0 {
                let from = r.pos();
                for _ in 0..n {
                    r.varint()?;
                }
                info.mean_bytes += r.pos() - from + 2;
                per.push((0, 0));
                continue;
            }
            r.skip(2 * n)?;
            info.mean_bytes += 2 * n + 2;
            r.skip(n * k)?;
            info.basis_bytes += n * k;
            let from = r.pos();
            let m = r.varint()? as usize;
            let tb = r.u8()? as u64;
            let mut row = 0u64;
            for _ in 0..k {
                row += u64::from(r.u8()?);
                r.u8()?;
                r.varint()?;
            }
            r.skip((m as u64 * (tb + row)).div_ceil(8) as usize)?;
            info.key_bytes += r.pos() - from;
            per.push((k, m));
        }
        if r.pos() != stop {
            return None;
        }
        let patches = r.varint()? as usize;
        r.skip(patches)?;
        info.patch_bytes += patches;
        info.segments.push((start, end, per));
    }
    Some(info)
}
