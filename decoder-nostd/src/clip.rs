//! The container (SPEC.md §2): magic, version, section table, CRC-32.

use crate::codec::{open_codec, Codec};
use crate::consts::{self, CRC_LEN, MAX_SECTIONS, PREAMBLE_LEN, SECTION_ENTRY_LEN};
use crate::error::Error;
use crate::header::Header;
use crate::missing::{self, Missing};
use crate::reader::Reader;
use crate::rig::Rig;
use crate::wire;

/// One section of a clip: its id and its bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Section<'a> {
    /// Section id (SPEC.md §2.2).
    pub id: u8,
    /// The section's payload.
    pub bytes: &'a [u8],
}

/// Iterator over the sections of a validated clip, in table order.
#[derive(Clone, Debug)]
pub struct Sections<'a> {
    file: &'a [u8],
    table: Reader<'a>,
    left: u16,
}

impl<'a> Iterator for Sections<'a> {
    type Item = Section<'a>;

    fn next(&mut self) -> Option<Section<'a>> {
        if self.left == 0 {
            return None;
        }
        self.left = self.left.wrapping_sub(1);
        let (id, range) = read_entry(&mut self.table)?;
        Some(Section {
            id,
            bytes: self.file.get(range)?,
        })
    }
}

pub(crate) fn read_entry(r: &mut Reader<'_>) -> Option<(u8, core::ops::Range<usize>)> {
    let id = r.u8()?;
    let reserved = r.take(3)?;
    if reserved != [0, 0, 0] {
        return None;
    }
    let offset = usize::try_from(r.u32_le()?).ok()?;
    let len = usize::try_from(r.u32_le()?).ok()?;
    Some((id, offset..offset.checked_add(len)?))
}

/// Checks the preamble (§2.1, §9.1) and the CRC (§2.3) of a file of
/// `version` with at most `max_sections` sections; returns the section
/// count, where the body starts and where the CRC starts.
pub(crate) fn open_container(
    bytes: &[u8],
    version: u8,
    max_sections: usize,
) -> Result<(u16, usize, usize), Error> {
    let mut r = Reader::new(bytes);
    let truncated = |needed: usize| Error::ContainerTruncated {
        needed,
        available: bytes.len(),
    };
    let magic = r.take(4).ok_or(truncated(PREAMBLE_LEN + CRC_LEN))?;
    if magic != consts::MAGIC {
        return Err(Error::ContainerBadMagic);
    }
    let found = r.u8().ok_or(truncated(PREAMBLE_LEN + CRC_LEN))?;
    if found != version {
        return Err(if found == consts::VERSION_SHOW {
            Error::ContainerIsShow
        } else {
            Error::ContainerUnsupportedVersion { version: found }
        });
    }
    let flags = r.u8().ok_or(truncated(PREAMBLE_LEN + CRC_LEN))?;
    if flags != 0 {
        return Err(Error::ContainerUnsupportedFlags { flags });
    }
    let count = r.u16_le().ok_or(truncated(PREAMBLE_LEN + CRC_LEN))?;
    if count == 0 || usize::from(count) > max_sections {
        return Err(Error::ContainerSectionCount { count });
    }
    let body_start = PREAMBLE_LEN.wrapping_add(usize::from(count).wrapping_mul(SECTION_ENTRY_LEN));
    let needed = body_start.wrapping_add(CRC_LEN);
    if bytes.len() < needed {
        return Err(truncated(needed));
    }
    let crc_at = bytes.len().wrapping_sub(CRC_LEN);
    let (body, crc_bytes) = bytes.split_at(crc_at);
    let stored = match crc_bytes {
        [a, b, c, d] => u32::from_le_bytes([*a, *b, *c, *d]),
        _ => return Err(truncated(needed)),
    };
    let computed = wire::crc32(body);
    if stored != computed {
        return Err(Error::ContainerCrcMismatch { stored, computed });
    }
    Ok((count, body_start, crc_at))
}

/// A parsed, validated clip borrowing its bytes (zero copy).
#[derive(Clone, Copy, Debug)]
pub struct Clip<'a> {
    bytes: &'a [u8],
    section_count: u16,
    header: Header<'a>,
    codec_id: u8,
    rig: Option<Rig<'a>>,
    /// The missing-sample mask (§3.7), validated here.
    missing: Option<Missing<'a>>,
    /// The codec section, validated once here for every player.
    codec: Codec<'a>,
}

impl<'a> Clip<'a> {
    /// Validates a whole clip: container, CRC, header and codec section
    /// (SPEC.md §2–§4). After this succeeds every frame can be decoded.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        let (count, body_start, crc_at) = open_container(bytes, consts::VERSION, MAX_SECTIONS)?;
        let mut r = Reader::new(bytes.get(PREAMBLE_LEN..).unwrap_or(&[]));
        let table_at = PREAMBLE_LEN;
        let mut seen = [false; 256];
        let mut header = None;
        let mut codec = None;
        let mut rig = None;
        let mut mask = None;
        for _ in 0..count {
            let at = table_at.wrapping_add(r.pos());
            let id = bytes.get(at).copied().unwrap_or(0);
            let (id, range) = read_entry(&mut r).ok_or(Error::ContainerSectionBounds { id })?;
            if range.start < body_start || range.end > crc_at {
                return Err(Error::ContainerSectionBounds { id });
            }
            let slot = seen
                .get_mut(usize::from(id))
                .ok_or(Error::ContainerSectionBounds { id })?;
            if *slot {
                return Err(Error::ContainerDuplicateSection { id });
            }
            *slot = true;
            let payload = bytes
                .get(range)
                .ok_or(Error::ContainerSectionBounds { id })?;
            match id {
                consts::SECTION_HEADER | consts::SECTION_HEADER_COMPACT => {
                    if header.is_some() {
                        return Err(Error::ContainerDuplicateSection { id });
                    }
                    header = Some((id, payload));
                }
                id if consts::is_codec_section(id) => {
                    if codec.is_some() {
                        return Err(Error::ContainerDuplicateSection { id });
                    }
                    codec = Some((id, payload));
                }
                consts::SECTION_RIG => rig = Some(payload),
                consts::SECTION_MISSING => mask = Some(payload),
                0x80..=0xFF => {} // ancillary: skipped by this decoder
                _ => return Err(Error::ContainerUnknownSection { id }),
            }
        }
        let (header_id, header) = header.ok_or(Error::ContainerMissingSection {
            id: consts::SECTION_HEADER,
        })?;
        let header = Header::parse(header, header_id == consts::SECTION_HEADER_COMPACT)?;
        let (codec_id, codec_bytes) = codec.ok_or(Error::ContainerNoCodec)?;
        // The servo form of the header describes nothing but a servo count:
        // only a rig table (which lists every servo) gives it meaning.
        if header.is_servo_form() && rig.is_none() {
            return Err(Error::ContainerMissingSection {
                id: consts::SECTION_RIG,
            });
        }
        let rig = rig
            .map(|r| Rig::parse(r, header.channel_count()))
            .transpose()?;
        let missing = mask
            .map(|m| missing::parse(m, header.joint_count(), header.frame_count()))
            .transpose()?;
        // Validate the codec section now so that playing never meets a
        // structural error later.
        let codec = open_codec(
            codec_id,
            codec_bytes,
            None,
            header.channel_count(),
            header.frame_count(),
        )?;
        Ok(Clip {
            bytes,
            section_count: count,
            header,
            codec_id,
            rig,
            missing,
            codec,
        })
    }

    /// A clip of a show (SPEC.md §9.2): the show's bytes, header (with the
    /// clip's frame count) and rig, and the clip's validated codec section.
    pub(crate) fn of_show(
        bytes: &'a [u8],
        section_count: u16,
        header: Header<'a>,
        rig: Option<Rig<'a>>,
        codec_id: u8,
        codec: Codec<'a>,
    ) -> Self {
        Clip {
            bytes,
            section_count,
            header,
            codec_id,
            rig,
            missing: None,
            codec,
        }
    }

    /// The header: timing, skeleton, channel table.
    pub fn header(&self) -> &Header<'a> {
        &self.header
    }

    /// The whole clip's bytes (a show's clip: the whole show's).
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// The rig table of a servo clip (SPEC.md §3.5): channel `i` is servo
    /// `i`'s angle; `None` for a motion clip.
    pub fn rig(&self) -> Option<&Rig<'a>> {
        self.rig.as_ref()
    }

    /// The digest of the rig a servo clip was encoded for (SPEC.md §3.6, the
    /// ancillary section `0x80`): `None` without one, or when that section is
    /// not 4 bytes long (an ancillary section this decoder cannot read is
    /// skipped, §1). Compare it with [`crate::rig_digest`] of the rig at hand.
    pub fn rig_digest(&self) -> Option<u32> {
        let section = self
            .sections()
            .find(|s| s.id == consts::SECTION_RIG_DIGEST)?;
        let bytes: [u8; 4] = section.bytes.try_into().ok()?;
        Some(u32::from_le_bytes(bytes))
    }

    /// The missing samples of a marker clip (SPEC.md §3.7, the ancillary
    /// section `0x81`), validated by [`Clip::parse`]: `None` when the clip
    /// has no such section (nothing missing, or encoded before §3.7). The
    /// decoded frames hold the encoder's fill at those samples.
    pub fn missing(&self) -> Option<Missing<'a>> {
        self.missing
    }

    /// Id of the codec section (SPEC.md §2.2).
    pub fn codec_id(&self) -> u8 {
        self.codec_id
    }

    /// The validated codec section.
    pub(crate) fn codec(&self) -> Codec<'a> {
        self.codec
    }

    /// All sections, in table order (ancillary ones included; a show's clip:
    /// all the show's sections).
    pub fn sections(&self) -> Sections<'a> {
        Sections {
            file: self.bytes,
            table: Reader::new(self.bytes.get(PREAMBLE_LEN..).unwrap_or(&[])),
            left: self.section_count,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// A container of `sections` (SPEC.md §2) with its CRC.
    fn container(sections: &[(u8, &[u8])]) -> Vec<u8> {
        let mut b = Vec::from(consts::MAGIC);
        b.extend([consts::VERSION, 0]);
        b.extend((sections.len() as u16).to_le_bytes());
        let mut at = PREAMBLE_LEN + sections.len() * SECTION_ENTRY_LEN;
        for (id, bytes) in sections {
            b.extend([*id, 0, 0, 0]);
            b.extend((at as u32).to_le_bytes());
            b.extend((bytes.len() as u32).to_le_bytes());
            at += bytes.len();
        }
        for (_, bytes) in sections {
            b.extend_from_slice(bytes);
        }
        let crc = wire::crc32(&b);
        b.extend(crc.to_le_bytes());
        b
    }

    /// Compact header: 1 ns, 1 frame, 1 nm, no joints (so no channels).
    const HEADER: &[u8] = &[1, 1, 1, 0];
    /// An `index` section for no channels: no key interval, no groups, no
    /// table, no payload.
    const INDEX: &[u8] = &[0, 0, 0, 0, 0, 0, 0, 0, 0, 0];

    #[test]
    fn a_second_codec_section_is_a_duplicate() {
        let one = container(&[(consts::SECTION_HEADER_COMPACT, HEADER), (0x10, INDEX)]);
        #[cfg(feature = "codec-index")]
        assert!(Clip::parse(&one).is_ok());
        let _ = one;
        // The same codec twice, or another codec beside it.
        for id in [0x10, 0x11, 0x12] {
            let two = container(&[
                (consts::SECTION_HEADER_COMPACT, HEADER),
                (0x10, INDEX),
                (id, INDEX),
            ]);
            assert_eq!(
                Clip::parse(&two).err(),
                Some(Error::ContainerDuplicateSection { id })
            );
        }
    }
}
