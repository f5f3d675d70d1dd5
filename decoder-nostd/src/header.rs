//! The header section (SPEC.md §3): frame timing, the skeleton and the
//! channel table. [`Header::parse`] validates every field once; the
//! iterators then walk the same bytes again without allocating.

use crate::consts;
use crate::error::Error;
use crate::reader::Reader;

/// What a channel moves (SPEC.md §3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChannelKind {
    /// Translation along X.
    Xposition,
    /// Translation along Y.
    Yposition,
    /// Translation along Z.
    Zposition,
    /// Rotation about X.
    Xrotation,
    /// Rotation about Y.
    Yrotation,
    /// Rotation about Z.
    Zrotation,
}

impl ChannelKind {
    /// All kinds, in the order of their codes (SPEC.md §3.2).
    pub const ALL: [ChannelKind; 6] = [
        ChannelKind::Xposition,
        ChannelKind::Yposition,
        ChannelKind::Zposition,
        ChannelKind::Xrotation,
        ChannelKind::Yrotation,
        ChannelKind::Zrotation,
    ];

    /// The kind's code (SPEC.md §3.2).
    pub fn code(self) -> u8 {
        match self {
            ChannelKind::Xposition => consts::kind::X_POSITION,
            ChannelKind::Yposition => consts::kind::Y_POSITION,
            ChannelKind::Zposition => consts::kind::Z_POSITION,
            ChannelKind::Xrotation => consts::kind::X_ROTATION,
            ChannelKind::Yrotation => consts::kind::Y_ROTATION,
            ChannelKind::Zrotation => consts::kind::Z_ROTATION,
        }
    }

    /// Parses a BVH channel name, ASCII case-insensitively (exporters vary).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(name))
    }

    /// True for the three rotation kinds.
    pub fn is_rotation(self) -> bool {
        matches!(
            self,
            ChannelKind::Xrotation | ChannelKind::Yrotation | ChannelKind::Zrotation
        )
    }

    /// Axis index: 0 = X, 1 = Y, 2 = Z.
    pub fn axis(self) -> usize {
        match self {
            ChannelKind::Xposition | ChannelKind::Xrotation => 0,
            ChannelKind::Yposition | ChannelKind::Yrotation => 1,
            ChannelKind::Zposition | ChannelKind::Zrotation => 2,
        }
    }

    /// Decodes a kind code of §3.2.
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            consts::kind::X_POSITION => Some(ChannelKind::Xposition),
            consts::kind::Y_POSITION => Some(ChannelKind::Yposition),
            consts::kind::Z_POSITION => Some(ChannelKind::Zposition),
            consts::kind::X_ROTATION => Some(ChannelKind::Xrotation),
            consts::kind::Y_ROTATION => Some(ChannelKind::Yrotation),
            consts::kind::Z_ROTATION => Some(ChannelKind::Zrotation),
            _ => None,
        }
    }

    /// The BVH name of the kind, e.g. `Zrotation`.
    pub fn name(self) -> &'static str {
        match self {
            ChannelKind::Xposition => "Xposition",
            ChannelKind::Yposition => "Yposition",
            ChannelKind::Zposition => "Zposition",
            ChannelKind::Xrotation => "Xrotation",
            ChannelKind::Yrotation => "Yrotation",
            ChannelKind::Zrotation => "Zrotation",
        }
    }
}

impl core::fmt::Display for ChannelKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Fixed-point unit of a channel's decoded integers (SPEC.md §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unit {
    /// 1/1000 degree. Angles are unwrapped (continuous), so they may leave
    /// ±180°.
    Millidegree,
    /// 1/1000 millimetre.
    Micrometre,
}

impl Unit {
    /// Decodes a unit code of §3.3.
    pub fn from_code(code: u8) -> Option<Self> {
        match code {
            consts::unit::MILLIDEGREE => Some(Unit::Millidegree),
            consts::unit::MICROMETRE => Some(Unit::Micrometre),
            _ => None,
        }
    }
}

/// One joint of the skeleton (SPEC.md §3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Joint<'a> {
    /// Joint name.
    pub name: &'a str,
    /// Parent joint index; `None` for a root.
    pub parent: Option<u32>,
    /// Offset from the parent in micrometres.
    pub offset_um: [i32; 3],
    /// True for a BVH End Site.
    pub end_site: bool,
    /// Kind codes of the joint's channels, in order (validated).
    kinds: &'a [u8],
}

impl<'a> Joint<'a> {
    /// Number of channels of the joint.
    pub fn channel_count(&self) -> usize {
        self.kinds.len()
    }

    /// The joint's channel kinds in order.
    pub fn channel_kinds(&self) -> impl Iterator<Item = ChannelKind> + 'a {
        self.kinds.iter().filter_map(|&c| ChannelKind::from_code(c))
    }
}

/// One entry of the channel table (SPEC.md §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Channel<'a> {
    /// Index of the joint the channel belongs to.
    pub joint: u32,
    /// Name of that joint.
    pub joint_name: &'a str,
    /// What the channel moves.
    pub kind: ChannelKind,
    /// Unit of its decoded integers.
    pub unit: Unit,
    /// Smallest decoded value over the clip.
    pub min: i32,
    /// Largest decoded value over the clip.
    pub max: i32,
}

/// The parsed header: borrowed bytes plus the fields every player needs.
#[derive(Clone, Copy, Debug)]
pub struct Header<'a> {
    bytes: &'a [u8],
    frame_time_ns: u32,
    frame_count: u32,
    source_unit_nm: u32,
    joint_count: u32,
    joints_at: usize,
    channel_count: u32,
    channels_at: usize,
    /// Which layout the bytes follow.
    form: Form,
}

/// The layout of a header section.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Form {
    /// Section `0x01`, postcard (§3.1).
    Full,
    /// Section `0x02`, compact (§3.4).
    Compact,
    /// Section `0x02` starting with a `0` varint: a servo clip's skeleton,
    /// one unnamed root joint with one `Zrotation` channel per servo and
    /// no channel ranges (§3.4.1). Nothing of it is stored but the count.
    Servo,
}

/// Kind codes of a servo-form joint: one `Zrotation`.
const SERVO_KINDS: &[u8] = &[consts::kind::Z_ROTATION];
/// `source_unit_nm` of a servo-form header (millimetres; a servo clip has
/// no lengths).
pub const SERVO_SOURCE_UNIT_NM: u32 = 1_000_000;

impl<'a> Header<'a> {
    /// Parses and validates a header section (SPEC.md §3).
    pub(crate) fn parse(bytes: &'a [u8], compact: bool) -> Result<Self, Error> {
        let mut r = Reader::new(bytes);
        let malformed = |r: &Reader<'_>| Error::HeaderMalformed { offset: r.pos() };
        let frame_time_ns = r.varint_u32().ok_or_else(|| malformed(&r))?;
        // A frame time is never 0: in section 0x02 a 0 marks the servo form.
        if compact && frame_time_ns == 0 {
            return Self::parse_servo(bytes, r);
        }
        let form = if compact { Form::Compact } else { Form::Full };
        let frame_count = r.varint_u32().ok_or_else(|| malformed(&r))?;
        let source_unit_nm = r.varint_u32().ok_or_else(|| malformed(&r))?;
        if frame_time_ns == 0 || frame_count == 0 {
            return Err(Error::HeaderTiming);
        }
        if source_unit_nm == 0 {
            return Err(Error::HeaderSourceUnit);
        }
        let joint_count = r.varint_u32().ok_or_else(|| malformed(&r))?;
        let joints_at = r.pos();
        let mut declared: u32 = 0;
        for index in 0..joint_count {
            let joint = read_joint(&mut r, form, index)?;
            if let Some(p) = joint.parent {
                if p >= index {
                    return Err(Error::HeaderParent { joint: index });
                }
            }
            if joint.end_site && !joint.kinds.is_empty() {
                return Err(Error::HeaderEndSiteChannels { joint: index });
            }
            for &code in joint.kinds {
                ChannelKind::from_code(code).ok_or(Error::HeaderChannelKind { code })?;
            }
            let n = u32::try_from(joint.kinds.len()).map_err(|_| malformed(&r))?;
            declared = declared.checked_add(n).ok_or_else(|| malformed(&r))?;
        }
        let channel_count = if compact {
            declared
        } else {
            r.varint_u32().ok_or_else(|| malformed(&r))?
        };
        if channel_count != declared {
            return Err(Error::HeaderChannelCount {
                joints: declared,
                table: channel_count,
            });
        }
        let channels_at = r.pos();
        for channel in 0..channel_count {
            let (unit, min, max) = read_channel(&mut r, form)?;
            Unit::from_code(unit).ok_or(Error::HeaderUnit { code: unit })?;
            if min > max {
                return Err(Error::HeaderRange { channel });
            }
        }
        if !r.is_empty() {
            return Err(Error::HeaderTrailingBytes);
        }
        Ok(Header {
            bytes,
            frame_time_ns,
            frame_count,
            source_unit_nm,
            joint_count,
            joints_at,
            channel_count,
            channels_at,
            form,
        })
    }

    /// The servo form of section `0x02` (§3.4.1) after its `varint 0`:
    /// frame time, frame count, servo count.
    fn parse_servo(bytes: &'a [u8], mut r: Reader<'a>) -> Result<Self, Error> {
        let malformed = |r: &Reader<'_>| Error::HeaderMalformed { offset: r.pos() };
        let frame_time_ns = r.varint_u32().ok_or_else(|| malformed(&r))?;
        let frame_count = r.varint_u32().ok_or_else(|| malformed(&r))?;
        if frame_time_ns == 0 || frame_count == 0 {
            return Err(Error::HeaderTiming);
        }
        let servos = r.varint_u32().ok_or_else(|| malformed(&r))?;
        if !r.is_empty() {
            return Err(Error::HeaderTrailingBytes);
        }
        Ok(Header {
            bytes,
            frame_time_ns,
            frame_count,
            source_unit_nm: SERVO_SOURCE_UNIT_NM,
            joint_count: servos,
            joints_at: r.pos(),
            channel_count: servos,
            channels_at: r.pos(),
            form: Form::Servo,
        })
    }

    /// The same header with another frame count: a show's clip (SPEC.md
    /// §9.2) shares the show's header but has its own length.
    pub(crate) fn with_frame_count(mut self, frames: u32) -> Self {
        self.frame_count = frames;
        self
    }

    /// Nanoseconds per frame.
    pub fn frame_time_ns(&self) -> u32 {
        self.frame_time_ns
    }

    /// Number of frames (at least 1).
    pub fn frame_count(&self) -> u32 {
        self.frame_count
    }

    /// Length of one length unit of the source file in nanometres (used
    /// to write BVH back in the source's units).
    pub fn source_unit_nm(&self) -> u32 {
        self.source_unit_nm
    }

    /// Clip duration in microseconds: `frame_count × frame_time`.
    pub fn duration_us(&self) -> u64 {
        u64::from(self.frame_count).wrapping_mul(u64::from(self.frame_time_ns)) / 1000
    }

    /// True for a servo clip's header form (SPEC.md §3.4.1): one unnamed
    /// root joint with one `Zrotation` channel per servo, no ranges.
    pub fn is_servo_form(&self) -> bool {
        self.form == Form::Servo
    }

    /// Number of joints, End Sites included.
    pub fn joint_count(&self) -> usize {
        self.joint_count as usize
    }

    /// Number of channels per frame.
    pub fn channel_count(&self) -> usize {
        self.channel_count as usize
    }

    /// The joints in file order.
    pub fn joints(&self) -> JointIter<'a> {
        JointIter {
            reader: Reader::new(self.bytes.get(self.joints_at..).unwrap_or(&[])),
            left: self.joint_count,
            index: 0,
            form: self.form,
        }
    }

    /// The channel table, in frame order.
    pub fn channels(&self) -> ChannelIter<'a> {
        ChannelIter {
            joints: self.joints(),
            joint_index: 0,
            current: None,
            kind_pos: 0,
            table: Reader::new(self.bytes.get(self.channels_at..).unwrap_or(&[])),
            left: self.channel_count,
            form: self.form,
        }
    }
}

/// Flags byte of a compact joint (§3.4): channel count in bits 0–2.
const COMPACT_COUNT_MASK: u8 = 0x07;
/// Largest channel count of a compact joint (§3.4: `n` is `0..=6`).
const COMPACT_MAX_CHANNELS: u8 = 6;
/// Compact joint flag: an End Site.
const COMPACT_END_SITE: u8 = 0x08;
/// Compact joint flag: a parent follows.
const COMPACT_HAS_PARENT: u8 = 0x10;
/// Compact ranges are in units of 2^10.
const COMPACT_RANGE_SHIFT: u32 = 10;
/// Marker returned by [`read_channel`] for compact channels, whose unit
/// follows from the kind.
const COMPACT_UNIT_FROM_KIND: u8 = consts::unit::MILLIDEGREE;

fn read_joint<'a>(r: &mut Reader<'a>, form: Form, index: u32) -> Result<Joint<'a>, Error> {
    match form {
        Form::Full => {}
        Form::Compact => return read_compact_joint(r, index),
        Form::Servo => {
            return Ok(Joint {
                name: "",
                parent: None,
                offset_um: [0; 3],
                end_site: false,
                kinds: SERVO_KINDS,
            })
        }
    }
    let at = r.pos();
    let name_bytes = r.byte_seq().ok_or(Error::HeaderMalformed { offset: at })?;
    let name = core::str::from_utf8(name_bytes).map_err(|_| Error::HeaderUtf8 { offset: at })?;
    let bad = |r: &Reader<'_>| Error::HeaderMalformed { offset: r.pos() };
    let parent = match r.u8().ok_or_else(|| bad(r))? {
        0 => None,
        1 => Some(r.varint_u32().ok_or_else(|| bad(r))?),
        _ => return Err(bad(r)),
    };
    let mut offset_um = [0i32; 3];
    for v in offset_um.iter_mut() {
        *v = r.zigzag_i32().ok_or_else(|| bad(r))?;
    }
    let end_site = r.bool().ok_or_else(|| bad(r))?;
    let kinds = r.byte_seq().ok_or_else(|| bad(r))?;
    Ok(Joint {
        name,
        parent,
        offset_um,
        end_site,
        kinds,
    })
}

fn read_compact_joint<'a>(r: &mut Reader<'a>, index: u32) -> Result<Joint<'a>, Error> {
    let bad = |r: &Reader<'_>| Error::HeaderMalformed { offset: r.pos() };
    let flags = r.u8().ok_or_else(|| bad(r))?;
    if flags & !(COMPACT_COUNT_MASK | COMPACT_END_SITE | COMPACT_HAS_PARENT) != 0
        || flags & COMPACT_COUNT_MASK > COMPACT_MAX_CHANNELS
    {
        return Err(bad(r));
    }
    let parent = if flags & COMPACT_HAS_PARENT != 0 {
        let back = r.varint_u32().ok_or_else(|| bad(r))?;
        // index − back must be an earlier joint: 1 ≤ back ≤ index.
        Some(
            index
                .checked_sub(back)
                .filter(|_| back >= 1)
                .ok_or(Error::HeaderParent { joint: index })?,
        )
    } else {
        None
    };
    let at = r.pos();
    let name_bytes = r.byte_seq().ok_or(Error::HeaderMalformed { offset: at })?;
    let name = core::str::from_utf8(name_bytes).map_err(|_| Error::HeaderUtf8 { offset: at })?;
    let mut offset_um = [0i32; 3];
    for v in offset_um.iter_mut() {
        *v = r.zigzag_i32().ok_or_else(|| bad(r))?;
    }
    let count = usize::from(flags & COMPACT_COUNT_MASK);
    let kinds = r.take(count).ok_or_else(|| bad(r))?;
    Ok(Joint {
        name,
        parent,
        offset_um,
        end_site: flags & COMPACT_END_SITE != 0,
        kinds,
    })
}

fn read_channel(r: &mut Reader<'_>, form: Form) -> Result<(u8, i32, i32), Error> {
    let bad = |r: &Reader<'_>| Error::HeaderMalformed { offset: r.pos() };
    if form == Form::Servo {
        // No ranges stored: the rig table bounds what a servo plays.
        return Ok((consts::unit::MILLIDEGREE, i32::MIN, i32::MAX));
    }
    if form == Form::Compact {
        // Unit from the kind (the caller knows it); bounds in 2^10 units.
        let lo = r.zigzag_i32().ok_or_else(|| bad(r))?;
        let span = r.varint_u32().ok_or_else(|| bad(r))?;
        let scale =
            |v: i64| (v << COMPACT_RANGE_SHIFT).clamp(i32::MIN.into(), i32::MAX.into()) as i32;
        let min = scale(i64::from(lo));
        let max = scale(i64::from(lo).wrapping_add(i64::from(span)));
        return Ok((COMPACT_UNIT_FROM_KIND, min, max));
    }
    let unit = r.u8().ok_or_else(|| bad(r))?;
    let min = r.zigzag_i32().ok_or_else(|| bad(r))?;
    let max = r.zigzag_i32().ok_or_else(|| bad(r))?;
    Ok((unit, min, max))
}

/// Iterator over the joints of a validated header.
#[derive(Clone, Debug)]
pub struct JointIter<'a> {
    reader: Reader<'a>,
    left: u32,
    index: u32,
    form: Form,
}

impl<'a> Iterator for JointIter<'a> {
    type Item = Joint<'a>;

    fn next(&mut self) -> Option<Joint<'a>> {
        if self.left == 0 {
            return None;
        }
        self.left = self.left.wrapping_sub(1);
        let j = read_joint(&mut self.reader, self.form, self.index).ok();
        self.index = self.index.wrapping_add(1);
        j
    }
}

/// Iterator over the channel table of a validated header.
#[derive(Clone, Debug)]
pub struct ChannelIter<'a> {
    joints: JointIter<'a>,
    joint_index: u32,
    current: Option<Joint<'a>>,
    kind_pos: usize,
    table: Reader<'a>,
    left: u32,
    form: Form,
}

impl<'a> Iterator for ChannelIter<'a> {
    type Item = Channel<'a>;

    fn next(&mut self) -> Option<Channel<'a>> {
        if self.left == 0 {
            return None;
        }
        // Advance to the next joint that still has channels to hand out.
        loop {
            match self.current {
                Some(j) if self.kind_pos < j.kinds.len() => break,
                Some(_) => {
                    self.current = self.joints.next();
                    self.joint_index = self.joint_index.wrapping_add(1);
                    self.kind_pos = 0;
                }
                None => {
                    self.current = self.joints.next();
                    self.kind_pos = 0;
                    self.current?;
                }
            }
        }
        let joint = self.current?;
        let code = *joint.kinds.get(self.kind_pos)?;
        self.kind_pos = self.kind_pos.wrapping_add(1);
        let (unit, min, max) = read_channel(&mut self.table, self.form).ok()?;
        self.left = self.left.wrapping_sub(1);
        let kind = ChannelKind::from_code(code)?;
        let unit = match (self.form, kind.is_rotation()) {
            (Form::Full, _) => Unit::from_code(unit)?,
            (_, true) => Unit::Millidegree,
            (_, false) => Unit::Micrometre,
        };
        Some(Channel {
            joint: self.joint_index,
            joint_name: joint.name,
            kind,
            unit,
            min,
            max,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Full form (§3.1): 1 ns, 1 frame, `unit` nm, then `joints`.
    fn full(unit: u8, joints: &[u8]) -> std::vec::Vec<u8> {
        let mut b = std::vec![1, 1, unit];
        b.extend_from_slice(joints);
        b
    }

    #[test]
    fn source_unit_zero_is_named() {
        assert_eq!(
            Header::parse(&full(0, &[0, 0]), false).err(),
            Some(Error::HeaderSourceUnit)
        );
        assert_eq!(
            Header::parse(&full(0, &[0]), true).err(),
            Some(Error::HeaderSourceUnit)
        );
    }

    #[test]
    fn end_site_with_channels_is_named() {
        // One joint: name "", no parent, offset 0 0 0, End Site, kinds [3];
        // then one channel: unit 0, min 0, max 0.
        let bytes = full(1, &[1, 0, 0, 0, 0, 0, 1, 1, 3, 1, 0, 0, 0]);
        assert_eq!(
            Header::parse(&bytes, false).err(),
            Some(Error::HeaderEndSiteChannels { joint: 0 })
        );
        // Compact: flags n = 1 | End Site, name "", offset 0 0 0, kind 3,
        // range lo 0 span 0.
        let bytes = full(1, &[1, 0x09, 0, 0, 0, 0, 3, 0, 0]);
        assert_eq!(
            Header::parse(&bytes, true).err(),
            Some(Error::HeaderEndSiteChannels { joint: 0 })
        );
        // The same joint without the End Site flag is valid.
        assert!(Header::parse(&full(1, &[1, 0x01, 0, 0, 0, 0, 3, 0, 0]), true).is_ok());
    }

    #[test]
    fn compact_channel_count_is_at_most_six() {
        let joint = |n: u8| {
            let mut j = std::vec![1, n, 0, 0, 0, 0];
            j.extend(core::iter::repeat_n(3, usize::from(n)));
            j.extend(core::iter::repeat_n(0, 2 * usize::from(n)));
            full(1, &j)
        };
        let six = joint(6);
        let six = Header::parse(&six, true).map(|h| h.channel_count());
        assert_eq!(six.ok(), Some(6));
        assert!(matches!(
            Header::parse(&joint(7), true),
            Err(Error::HeaderMalformed { .. })
        ));
    }
}
