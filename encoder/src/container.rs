//! Writes the `.mcb` container (SPEC.md §2) and its header section (§3).
//! The header is postcard-encoded from the structs below; the decoder reads
//! the same bytes with its own zero-copy reader.

use mocap_decoder::consts::{self, CRC_LEN, PREAMBLE_LEN, SECTION_ENTRY_LEN};
use serde::Serialize;

use crate::fixed::FixedChannels;
use crate::motion::Motion;

/// CRC-32/ISO-HDLC with the decoder's parameters (SPEC.md §2.3).
pub const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(mocap_decoder::wire::CRC_ALGORITHM);

/// Header section, field for field in SPEC.md §3.1 order.
#[derive(Serialize, Debug, Clone, PartialEq)]
pub struct HeaderWire {
    /// Nanoseconds per frame.
    pub frame_time_ns: u32,
    /// Number of frames.
    pub frame_count: u32,
    /// One source length unit in nanometres.
    pub source_unit_nm: u32,
    /// Joints in file order.
    pub joints: Vec<JointWire>,
    /// Channel table.
    pub channels: Vec<ChannelWire>,
}

/// One joint (SPEC.md §3.2).
#[derive(Serialize, Debug, Clone, PartialEq)]
pub struct JointWire {
    /// Joint name.
    pub name: String,
    /// Parent index, `None` for a root.
    pub parent: Option<u32>,
    /// Offset in micrometres.
    pub offset_um: [i32; 3],
    /// BVH End Site.
    pub end_site: bool,
    /// Channel kind codes.
    pub kinds: Vec<u8>,
}

/// One channel-table entry (SPEC.md §3.3).
#[derive(Serialize, Debug, Clone, PartialEq)]
pub struct ChannelWire {
    /// Unit code.
    pub unit: u8,
    /// Smallest decoded value.
    pub min: i32,
    /// Largest decoded value.
    pub max: i32,
}

impl HeaderWire {
    /// The header a decoded clip describes (its skeleton, timing and channel
    /// table), to write again — a show's shared header (SPEC.md §9.1).
    pub fn from_decoded(h: &mocap_decoder::Header<'_>) -> HeaderWire {
        HeaderWire {
            frame_time_ns: h.frame_time_ns(),
            frame_count: h.frame_count(),
            source_unit_nm: h.source_unit_nm(),
            joints: h
                .joints()
                .map(|j| JointWire {
                    name: j.name.to_string(),
                    parent: j.parent,
                    offset_um: j.offset_um,
                    end_site: j.end_site,
                    kinds: j.channel_kinds().map(|k| k.code()).collect(),
                })
                .collect(),
            channels: h
                .channels()
                .map(|c| ChannelWire {
                    unit: match c.unit {
                        mocap_decoder::Unit::Millidegree => consts::unit::MILLIDEGREE,
                        mocap_decoder::Unit::Micrometre => consts::unit::MICROMETRE,
                    },
                    min: c.min,
                    max: c.max,
                })
                .collect(),
        }
    }

    /// The header of `m`, with channel ranges taken from the decoded values
    /// (`decoded[channel][frame]`).
    pub fn new(m: &Motion, metres_per_unit: f64, decoded: &FixedChannels) -> HeaderWire {
        let um = metres_per_unit * 1e6;
        HeaderWire {
            frame_time_ns: frame_time_ns(m.frame_time),
            frame_count: m.frames() as u32,
            source_unit_nm: (metres_per_unit * 1e9).round().clamp(1.0, u32::MAX as f64) as u32,
            joints: m
                .skeleton
                .joints
                .iter()
                .map(|j| JointWire {
                    name: j.name.clone(),
                    parent: j.parent.map(|p| p as u32),
                    offset_um: j.offset.map(|o| (o * um).round() as i32),
                    end_site: j.end_site,
                    kinds: j.channels.iter().map(|k| k.code()).collect(),
                })
                .collect(),
            channels: decoded
                .kinds
                .iter()
                .zip(&decoded.values)
                .map(|(k, v)| ChannelWire {
                    unit: if k.is_rotation() {
                        consts::unit::MILLIDEGREE
                    } else {
                        consts::unit::MICROMETRE
                    },
                    min: v.iter().copied().min().unwrap_or(0),
                    max: v.iter().copied().max().unwrap_or(0),
                })
                .collect(),
        }
    }

    /// The postcard bytes of the header section `0x01` (SPEC.md §3.1).
    pub fn to_bytes(&self) -> Vec<u8> {
        postcard::to_stdvec(self).expect("postcard serialisation of plain data cannot fail")
    }

    /// The compact header section `0x02` (SPEC.md §3.4): parents as
    /// back-references, End Sites unnamed, units implied by kinds, ranges
    /// as outward-rounded bounds in units of 2^10.
    pub fn to_compact(&self) -> Vec<u8> {
        let mut out = Vec::new();
        varint(&mut out, self.frame_time_ns);
        varint(&mut out, self.frame_count);
        varint(&mut out, self.source_unit_nm);
        varint(&mut out, self.joints.len() as u32);
        for (i, j) in self.joints.iter().enumerate() {
            let mut flags = j.kinds.len() as u8;
            if j.end_site {
                flags |= 0x08;
            }
            if j.parent.is_some() {
                flags |= 0x10;
            }
            out.push(flags);
            if let Some(p) = j.parent {
                varint(&mut out, i as u32 - p);
            }
            let name: &str = if j.end_site { "" } else { &j.name };
            varint(&mut out, name.len() as u32);
            out.extend_from_slice(name.as_bytes());
            for &o in &j.offset_um {
                zigzag(&mut out, o);
            }
            out.extend_from_slice(&j.kinds);
        }
        for c in &self.channels {
            let lo = c.min.div_euclid(1024);
            let hi = (i64::from(c.max) + 1023).div_euclid(1024);
            zigzag(&mut out, lo);
            varint(&mut out, (hi - i64::from(lo)) as u32);
        }
        out
    }
}

/// A frame time in seconds as the header stores it: whole nanoseconds
/// (SPEC.md §3.2).
pub fn frame_time_ns(seconds: f64) -> u32 {
    (seconds * 1e9).round().clamp(1.0, f64::from(u32::MAX)) as u32
}

/// A reading position in a section's bytes, for inspecting what the
/// encoder wrote (`mocap info`); the decoder has its own, crate-private.
pub struct ByteCursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> ByteCursor<'a> {
    /// A cursor at the start of `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        ByteCursor { bytes, at: 0 }
    }

    /// Bytes read so far.
    pub fn pos(&self) -> usize {
        self.at
    }

    /// One byte.
    pub fn u8(&mut self) -> Option<u8> {
        let v = *self.bytes.get(self.at)?;
        self.at += 1;
        Some(v)
    }

    /// Skips `n` bytes (`None` past the end).
    pub fn skip(&mut self, n: usize) -> Option<()> {
        (self.at + n <= self.bytes.len()).then(|| self.at += n)
    }

    /// A varint as [`varint`] writes it.
    pub fn varint(&mut self) -> Option<u32> {
        let (v, next) = mocap_decoder::wire::varint_u32(self.bytes, self.at)?;
        self.at = next;
        Some(v)
    }
}

/// Appends `v` as a postcard varint (LEB128, SPEC.md §3.1).
pub fn varint(out: &mut Vec<u8>, mut v: u32) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// Appends `v` zigzag-encoded as a postcard varint (SPEC.md §3.1).
pub fn zigzag(out: &mut Vec<u8>, v: i32) {
    varint(out, mocap_decoder::wire::zigzag_encode(v));
}

/// Assembles sections into a clip container (version 1): preamble, section
/// table, payloads in table order, CRC-32.
pub fn assemble(sections: &[(u8, Vec<u8>)]) -> Vec<u8> {
    assemble_version(consts::VERSION, sections)
}

/// Assembles sections into a container of `version` (1: a clip, SPEC.md
/// §2; 2: a show, §9.1).
pub fn assemble_version(version: u8, sections: &[(u8, Vec<u8>)]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&consts::MAGIC);
    out.push(version);
    out.push(0); // flags
    out.extend_from_slice(&(sections.len() as u16).to_le_bytes());
    let mut offset = PREAMBLE_LEN + sections.len() * SECTION_ENTRY_LEN;
    for (id, bytes) in sections {
        out.push(*id);
        out.extend_from_slice(&[0, 0, 0]);
        out.extend_from_slice(&(offset as u32).to_le_bytes());
        out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        offset += bytes.len();
    }
    for (_, bytes) in sections {
        out.extend_from_slice(bytes);
    }
    let crc = CRC32.checksum(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    debug_assert_eq!(out.len(), offset + CRC_LEN);
    out
}
