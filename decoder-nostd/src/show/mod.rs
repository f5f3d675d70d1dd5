//! Shows (SPEC.md §9): many clips of one skeleton or rig in one version-2
//! file — the header and rig once, one codec section per clip, the show
//! table naming them, and the cue lists ([`cues`]) — and the player that
//! runs two of them at once with blends ([`player`]).

pub mod clock;
pub mod cues;
pub mod player;
pub mod runner;

use crate::clip::{open_container, read_entry, Clip};
use crate::codec::open_codec;
use crate::consts::{self, MAX_SHOW_SECTIONS, PREAMBLE_LEN, SECTION_ENTRY_LEN};
use crate::error::Error;
use crate::header::Header;
use crate::reader::Reader;
use crate::rig::Rig;

/// The loop of a looping clip (SPEC.md §9.2): a pass plays up to frame
/// `out`, the next starts at frame `start`, the two blended over `seam`
/// frames (§9.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Loop {
    /// First frame of every pass after the first (`loop_in`).
    pub start: u32,
    /// Last frame of a pass (`loop_out`).
    pub end: u32,
    /// Frames of the seam blend.
    pub seam: u32,
}

/// One clip of a show's table (SPEC.md §9.2).
#[derive(Clone, Copy, Debug)]
pub struct ShowClip<'a> {
    /// The clip's name.
    pub name: &'a str,
    /// Its frame count.
    pub frames: u32,
    /// Its loop, if it loops.
    pub looping: Option<Loop>,
    /// Position of its codec section in the section table.
    pub codec_section: u16,
    /// Shared model sections it reads (positions; `model_count` used).
    pub models: [u16; consts::MAX_CLIP_MODELS],
    /// How many of `models` are used.
    pub model_count: u8,
}

/// A parsed, validated show borrowing its bytes (zero copy). Every clip's
/// codec section was validated by [`Show::parse`]; [`Show::clip`] opens one
/// for a [`Player`](crate::Player).
#[derive(Clone, Copy, Debug)]
pub struct Show<'a> {
    bytes: &'a [u8],
    section_count: u16,
    header: Header<'a>,
    rig: Option<Rig<'a>>,
    table: &'a [u8],
    clip_count: u16,
    cues: Option<&'a [u8]>,
}

/// A set of up to [`MAX_SHOW_SECTIONS`] section positions.
struct SectionSet([u32; MAX_SHOW_SECTIONS / 32]);

impl SectionSet {
    /// Adds `i`; false if it was there already (or is out of range).
    fn insert(&mut self, i: usize) -> bool {
        let bit = 1u32 << (i % 32);
        match self.0.get_mut(i / 32) {
            Some(w) if *w & bit == 0 => {
                *w |= bit;
                true
            }
            _ => false,
        }
    }
}

impl<'a> Show<'a> {
    /// Validates a whole show: container, CRC, header, rig, show table,
    /// cue section and every clip's codec section (SPEC.md §9).
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        let (count, body_start, crc_at) =
            open_container(bytes, consts::VERSION_SHOW, MAX_SHOW_SECTIONS)?;
        let mut r = Reader::new(bytes.get(PREAMBLE_LEN..).unwrap_or(&[]));
        let mut header = None;
        let mut rig = None;
        let mut table = None;
        let mut cues = None;
        let mut digest = false;
        let mut codecs: u32 = 0;
        for _ in 0..count {
            let at = PREAMBLE_LEN.wrapping_add(r.pos());
            let id = bytes.get(at).copied().unwrap_or(0);
            let (id, range) = read_entry(&mut r).ok_or(Error::ContainerSectionBounds { id })?;
            if range.start < body_start || range.end > crc_at {
                return Err(Error::ContainerSectionBounds { id });
            }
            let payload = bytes
                .get(range)
                .ok_or(Error::ContainerSectionBounds { id })?;
            let once = |slot: &mut Option<(u8, &'a [u8])>| {
                if slot.is_some() {
                    return Err(Error::ContainerDuplicateSection { id });
                }
                *slot = Some((id, payload));
                Ok(())
            };
            match id {
                consts::SECTION_HEADER | consts::SECTION_HEADER_COMPACT => once(&mut header)?,
                consts::SECTION_RIG => once(&mut rig)?,
                consts::SECTION_SHOW => once(&mut table)?,
                consts::SECTION_CUES => once(&mut cues)?,
                id if consts::is_codec_section(id) => codecs = codecs.wrapping_add(1),
                consts::SECTION_MODEL_FIRST..=consts::SECTION_MODEL_LAST => {}
                consts::SECTION_RIG_DIGEST => {
                    if digest {
                        return Err(Error::ContainerDuplicateSection { id });
                    }
                    digest = true;
                }
                0x81..=0xFF => {}
                _ => return Err(Error::ContainerUnknownSection { id }),
            }
        }
        let (header_id, header) = header.ok_or(Error::ContainerMissingSection {
            id: consts::SECTION_HEADER,
        })?;
        let header = Header::parse(header, header_id == consts::SECTION_HEADER_COMPACT)?;
        if header.is_servo_form() && rig.is_none() {
            return Err(Error::ContainerMissingSection {
                id: consts::SECTION_RIG,
            });
        }
        let rig = rig
            .map(|(_, r)| Rig::parse(r, header.channel_count()))
            .transpose()?;
        let (_, table) = table.ok_or(Error::ContainerMissingSection {
            id: consts::SECTION_SHOW,
        })?;
        let mut show = Show {
            bytes,
            section_count: count,
            header,
            rig,
            table,
            clip_count: 0,
            cues: cues.map(|(_, c)| c),
        };
        show.clip_count = show.check_table(codecs)?;
        if let Some(c) = show.cues {
            cues::Cues::parse(c, show.clip_count)?;
        }
        Ok(show)
    }

    /// Validates the show table (§9.2) and every clip's codec section;
    /// returns the clip count.
    fn check_table(&self, codecs: u32) -> Result<u16, Error> {
        let mut r = Reader::new(self.table);
        let n = r.varint_u32().ok_or(Error::ShowMalformed { offset: 0 })?;
        if n == 0 || n as usize > consts::MAX_SHOW_CLIPS {
            return Err(Error::ShowMalformed { offset: 0 });
        }
        let mut used = SectionSet([0; MAX_SHOW_SECTIONS / 32]);
        let mut total: u32 = 0;
        for i in 0..n as u16 {
            let clip = read_clip(&mut r, self.section_count)?;
            // Names are unique: compare with every earlier clip's.
            let mut earlier = Reader::new(self.table);
            let _ = earlier.varint_u32();
            for _ in 0..i {
                let other = read_clip(&mut earlier, self.section_count)?;
                if other.name == clip.name {
                    return Err(Error::ShowMalformed { offset: r.pos() });
                }
            }
            for &m in clip
                .models
                .get(..usize::from(clip.model_count))
                .unwrap_or(&[])
            {
                match self.section_id(m) {
                    Some(consts::SECTION_MODEL_FIRST..=consts::SECTION_MODEL_LAST) => {}
                    _ => return Err(Error::ShowMalformed { offset: r.pos() }),
                }
            }
            if !used.insert(usize::from(clip.codec_section)) {
                return Err(Error::ShowClipCodec { clip: i });
            }
            self.open(&clip, i)?;
            total = total
                .checked_add(clip.frames)
                .ok_or(Error::ShowMalformed { offset: r.pos() })?;
        }
        if !r.is_empty() {
            return Err(Error::ShowMalformed { offset: r.pos() });
        }
        if codecs != n {
            // A codec section no clip names.
            return Err(Error::ShowClipCodec { clip: n as u16 });
        }
        if total != self.header.frame_count() {
            return Err(Error::ShowMalformed { offset: 0 });
        }
        Ok(n as u16)
    }

    /// The id and bytes of the section at position `i` of the table.
    fn section(&self, i: u16) -> Option<(u8, &'a [u8])> {
        let at = PREAMBLE_LEN.checked_add(usize::from(i).checked_mul(SECTION_ENTRY_LEN)?)?;
        let mut r = Reader::new(self.bytes.get(at..)?);
        let (id, range) = read_entry(&mut r)?;
        Some((id, self.bytes.get(range)?))
    }

    fn section_id(&self, i: u16) -> Option<u8> {
        self.section(i).map(|(id, _)| id)
    }

    /// The clip `entry` (number `i`) as a [`Clip`]: the show's header with
    /// its frame count, the rig, its codec section validated.
    fn open(&self, entry: &ShowClip<'a>, i: u16) -> Result<Clip<'a>, Error> {
        let (id, codec_bytes) = self
            .section(entry.codec_section)
            .ok_or(Error::ShowClipCodec { clip: i })?;
        if !consts::is_codec_section(id) {
            return Err(Error::ShowClipCodec { clip: i });
        }
        let header = self.header.with_frame_count(entry.frames);
        // The pattern codec's shared database: the clip's first model
        // section, when it is one (§9.2, §11.2).
        let model = entry
            .models
            .get(..usize::from(entry.model_count))
            .and_then(<[u16]>::first)
            .and_then(|&m| self.section(m))
            .filter(|(id, _)| *id == consts::SECTION_MODEL_PATTERN)
            .map(|(_, b)| b);
        let codec = open_codec(id, codec_bytes, model, header.channel_count(), entry.frames)?;
        Ok(Clip::of_show(
            self.bytes,
            self.section_count,
            header,
            self.rig,
            id,
            codec,
        ))
    }

    /// The show's header: the skeleton (or servo count) every clip shares;
    /// its frame count is the sum of the clips'.
    pub fn header(&self) -> &Header<'a> {
        &self.header
    }

    /// The rig table of a servo show (SPEC.md §3.5), shared by every clip.
    pub fn rig(&self) -> Option<&Rig<'a>> {
        self.rig.as_ref()
    }

    /// The rig digest (§3.6) of a servo show, if it carries one.
    pub fn rig_digest(&self) -> Option<u32> {
        (0..self.section_count)
            .filter_map(|i| self.section(i))
            .find(|(id, _)| *id == consts::SECTION_RIG_DIGEST)
            .and_then(|(_, b)| <[u8; 4]>::try_from(b).ok())
            .map(u32::from_le_bytes)
    }

    /// Clips in the show (at least 1).
    pub fn clip_count(&self) -> u16 {
        self.clip_count
    }

    /// The whole show's bytes.
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Sections in the section table.
    pub fn section_count(&self) -> u16 {
        self.section_count
    }

    /// The id and length of every section, in table order.
    pub fn sections(&self) -> impl Iterator<Item = (u8, usize)> + '_ {
        (0..self.section_count)
            .filter_map(|i| self.section(i))
            .map(|(id, b)| (id, b.len()))
    }

    /// Entry `i` of the show table.
    pub fn entry(&self, i: u16) -> Result<ShowClip<'a>, Error> {
        if i >= self.clip_count {
            return Err(Error::ShowClipOutOfRange {
                clip: i,
                clips: self.clip_count,
            });
        }
        let mut r = Reader::new(self.table);
        let _ = r.varint_u32();
        for _ in 0..i {
            read_clip(&mut r, self.section_count)?;
        }
        read_clip(&mut r, self.section_count)
    }

    /// Clip `i` as a [`Clip`] to play with a [`Player`](crate::Player).
    pub fn clip(&self, i: u16) -> Result<Clip<'a>, Error> {
        self.entry_and_clip(i).map(|(_, clip)| clip)
    }

    /// Entry `i` of the show table and its clip, the table walked once.
    pub fn entry_and_clip(&self, i: u16) -> Result<(ShowClip<'a>, Clip<'a>), Error> {
        let entry = self.entry(i)?;
        let clip = self.open(&entry, i)?;
        Ok((entry, clip))
    }

    /// The number of the clip called `name`.
    pub fn find(&self, name: &str) -> Option<u16> {
        (0..self.clip_count).find(|&i| self.entry(i).is_ok_and(|e| e.name == name))
    }

    /// The cue lists and triggers (§9.5), if the show has them.
    pub fn cues(&self) -> Option<cues::Cues<'a>> {
        self.cues
            .and_then(|c| cues::Cues::parse(c, self.clip_count).ok())
    }
}

/// Reads one clip entry of the show table (§9.2).
fn read_clip<'a>(r: &mut Reader<'a>, sections: u16) -> Result<ShowClip<'a>, Error> {
    let bad = |r: &Reader<'_>| Error::ShowMalformed { offset: r.pos() };
    let name = r.byte_seq().ok_or_else(|| bad(r))?;
    if name.is_empty() || name.len() > consts::MAX_CLIP_NAME {
        return Err(bad(r));
    }
    let name = core::str::from_utf8(name).map_err(|_| bad(r))?;
    let position = |r: &mut Reader<'a>| -> Result<u16, Error> {
        let p = r.varint_u32().ok_or_else(|| bad(r))?;
        match u16::try_from(p) {
            Ok(p) if p < sections => Ok(p),
            _ => Err(bad(r)),
        }
    };
    let codec_section = position(r)?;
    let frames = r.varint_u32().ok_or_else(|| bad(r))?;
    if frames == 0 {
        return Err(bad(r));
    }
    let flags = r.u8().ok_or_else(|| bad(r))?;
    let looping = match flags {
        0 => None,
        1 => {
            let start = r.varint_u32().ok_or_else(|| bad(r))?;
            let end = r.varint_u32().ok_or_else(|| bad(r))?;
            let seam = r.varint_u32().ok_or_else(|| bad(r))?;
            if start >= end || end >= frames || seam >= end.wrapping_sub(start) {
                return Err(bad(r));
            }
            Some(Loop { start, end, seam })
        }
        _ => return Err(bad(r)),
    };
    let model_count = r.varint_u32().ok_or_else(|| bad(r))?;
    if model_count as usize > consts::MAX_CLIP_MODELS {
        return Err(bad(r));
    }
    let mut models = [0u16; consts::MAX_CLIP_MODELS];
    for m in models.iter_mut().take(model_count as usize) {
        *m = position(r)?;
    }
    Ok(ShowClip {
        name,
        frames,
        looping,
        codec_section,
        models,
        model_count: model_count as u8,
    })
}
