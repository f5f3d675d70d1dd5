//! The decoder's one error type. Every rule of SPEC.md that a byte string
//! can break has its own variant, named after the phase that checks it.

use core::fmt;

/// Everything that can go wrong while parsing or playing a clip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// The input ends before a structure it declares (SPEC.md §2).
    ContainerTruncated {
        /// Bytes the structure needs.
        needed: usize,
        /// Bytes that are there.
        available: usize,
    },
    /// The first four bytes are not `MOCB` (§2.1).
    ContainerBadMagic,
    /// The file is a show (version 2, §9): read it with
    /// [`Show::parse`](crate::Show::parse), not as one clip.
    ContainerIsShow,
    /// A version this decoder does not know (§2.1).
    ContainerUnsupportedVersion {
        /// The version byte found.
        version: u8,
    },
    /// Reserved flag bits are set (§2.1).
    ContainerUnsupportedFlags {
        /// The flags byte found.
        flags: u8,
    },
    /// Section count is 0 or above the limit (§2.2).
    ContainerSectionCount {
        /// The count found.
        count: u16,
    },
    /// A section entry is malformed or points outside the payload area (§2.2).
    ContainerSectionBounds {
        /// The section's id.
        id: u8,
    },
    /// The same section id appears twice (§2.2).
    ContainerDuplicateSection {
        /// The repeated id.
        id: u8,
    },
    /// A critical section (id < 0x80) this decoder does not know (§2.2).
    ContainerUnknownSection {
        /// The unknown id.
        id: u8,
    },
    /// A required section is absent (§2.2).
    ContainerMissingSection {
        /// The missing id.
        id: u8,
    },
    /// The file has no codec section this build can decode (§2.2).
    ContainerNoCodec,
    /// The CRC-32 over the file does not match (§2.3).
    ContainerCrcMismatch {
        /// CRC stored in the file.
        stored: u32,
        /// CRC computed over the bytes.
        computed: u32,
    },
    /// A varint, string or value of the header is malformed (§3.1).
    HeaderMalformed {
        /// Byte offset inside the header section.
        offset: usize,
    },
    /// A header name is not UTF-8 (§3.1).
    HeaderUtf8 {
        /// Byte offset inside the header section.
        offset: usize,
    },
    /// The frame time is zero or the clip has no frames (§3.2).
    HeaderTiming,
    /// `source_unit_nm` is zero (§3.2).
    HeaderSourceUnit,
    /// An End Site joint declares channels (§3.2, §3.4).
    HeaderEndSiteChannels {
        /// The joint index.
        joint: u32,
    },
    /// A joint's parent is not an earlier joint (§3.2).
    HeaderParent {
        /// The joint index.
        joint: u32,
    },
    /// A channel kind code is unknown (§3.2).
    HeaderChannelKind {
        /// The code found.
        code: u8,
    },
    /// A channel unit code is unknown (§3.3).
    HeaderUnit {
        /// The code found.
        code: u8,
    },
    /// The channel table disagrees with the joints' channel lists (§3.3).
    HeaderChannelCount {
        /// Channels the joints declare.
        joints: u32,
        /// Entries in the channel table.
        table: u32,
    },
    /// A channel's range has min > max (§3.3).
    HeaderRange {
        /// The channel index.
        channel: u32,
    },
    /// Bytes remain after the header's last field (§3.1).
    HeaderTrailingBytes,
    /// The rig section is malformed (§3.5).
    RigMalformed {
        /// Which rule of §3.5 is broken.
        rule: &'static str,
    },
    /// The missing-sample section ends early or holds a malformed varint
    /// (§3.7).
    MissingMalformed {
        /// Byte offset inside the section.
        offset: usize,
    },
    /// The missing-sample section's marker count is not the header's joint
    /// count (§3.7).
    MissingMarkerCount {
        /// Markers in the section.
        markers: u32,
        /// Joints in the header.
        joints: u32,
    },
    /// A marker's runs do not add up to the frame count (§3.7).
    MissingRunTotal {
        /// The marker (joint index).
        marker: u32,
        /// The header's frame count.
        frames: u32,
    },
    /// A run other than a marker's first has length 0 (§3.7).
    MissingEmptyRun {
        /// The marker (joint index).
        marker: u32,
        /// The run's index among the marker's runs.
        run: u32,
    },
    /// Bytes remain after the last marker's runs (§3.7).
    MissingTrailingBytes {
        /// Byte offset inside the section.
        offset: usize,
    },
    /// The index codec section is malformed (§4).
    IndexMalformed {
        /// Which rule of §4 is broken.
        rule: &'static str,
    },
    /// A channel descriptor of the index codec is invalid (§4.2).
    IndexDescriptor {
        /// The channel index.
        channel: u32,
    },
    /// The index payload holds fewer bits than the frames need (§4.4).
    IndexPayloadTruncated {
        /// Bits the frames need.
        needed_bits: u64,
        /// Bits present.
        available_bits: u64,
    },
    /// The `pca-spline` codec section is malformed (§5).
    PcaMalformed {
        /// Which rule of §5 is broken.
        rule: &'static str,
    },
    /// The `predictive` codec section is malformed (§5b).
    PredictiveMalformed {
        /// Which rule of §5b is broken.
        rule: &'static str,
    },
    /// The `pattern` codec section is malformed (§11).
    PatternMalformed {
        /// Which rule of §11 is broken.
        rule: &'static str,
    },
    /// The `rma` codec section is malformed (§12).
    RmaMalformed {
        /// Which rule of §12 is broken.
        rule: &'static str,
    },
    /// An entropy-coder frequency table breaks a rule of §10.2.
    EntropyTable {
        /// Which rule of §10.2 is broken.
        rule: &'static str,
    },
    /// An entropy-coded stream does not start with a state in
    /// `2^23 … 2^31 − 1`, or has fewer than four bytes (§10.3).
    EntropyState,
    /// The show table breaks a rule of §9.2.
    ShowMalformed {
        /// Byte offset inside the show table.
        offset: usize,
    },
    /// A clip's codec reference is not a codec section, or a codec section
    /// is no clip's or two clips' (§9.2).
    ShowClipCodec {
        /// The clip (position in the show table); its count for a codec
        /// section no clip names.
        clip: u16,
    },
    /// A clip number past the show's clips.
    ShowClipOutOfRange {
        /// The number asked for.
        clip: u16,
        /// Clips in the show.
        clips: u16,
    },
    /// The cue section breaks a rule of §9.5.
    ShowCuesMalformed {
        /// Byte offset inside the cue section.
        offset: usize,
    },
    /// The player's state is too small for the codec's state (the
    /// `predictive` codec needs `3·C + 19` words).
    PlayerStateTooSmall {
        /// Words the codec needs.
        needed: usize,
        /// The player's `N`.
        capacity: usize,
    },
    /// The clip has more channels than the player's capacity.
    PlayerCapacity {
        /// Channels in the clip.
        channels: usize,
        /// The player's `N`.
        capacity: usize,
    },
    /// The caller's output slice is shorter than the channel count.
    PlayerOutputTooSmall {
        /// Slots needed.
        expected: usize,
        /// Slots given.
        actual: usize,
    },
    /// A structure the validation of [`Clip::parse`](crate::Clip::parse)
    /// proved could not be read while decoding (a decoder bug, never a bad
    /// clip); the output slice may be partly written.
    PlayerInvariant {
        /// The frame being decoded.
        frame: u32,
    },
    /// A frame index past the end of the clip.
    PlayerFrameOutOfRange {
        /// The index asked for.
        frame: u32,
        /// Frames in the clip.
        frames: u32,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::ContainerTruncated { needed, available } => write!(
                f,
                "clip truncated: needs {needed} bytes, {available} available"
            ),
            Error::ContainerBadMagic => f.write_str("not a .mcb clip (bad magic)"),
            Error::ContainerIsShow => {
                f.write_str("this file is a show (version 2): read it as a show, not as one clip")
            }
            Error::ContainerUnsupportedVersion { version } => {
                write!(f, "unsupported bitstream version {version}")
            }
            Error::ContainerUnsupportedFlags { flags } => {
                write!(f, "unsupported container flags {flags:#04x}")
            }
            Error::ContainerSectionCount { count } => write!(f, "bad section count {count}"),
            Error::ContainerSectionBounds { id } => {
                write!(f, "section {id:#04x} lies outside the file")
            }
            Error::ContainerDuplicateSection { id } => write!(f, "section {id:#04x} appears twice"),
            Error::ContainerUnknownSection { id } => {
                write!(f, "unknown critical section {id:#04x}")
            }
            Error::ContainerMissingSection { id } => {
                write!(f, "required section {id:#04x} missing")
            }
            Error::ContainerNoCodec => f.write_str("no codec section this decoder supports"),
            Error::ContainerCrcMismatch { stored, computed } => write!(
                f,
                "CRC mismatch: stored {stored:#010x}, computed {computed:#010x}"
            ),
            Error::HeaderMalformed { offset } => write!(f, "malformed header at byte {offset}"),
            Error::HeaderUtf8 { offset } => write!(f, "header name at byte {offset} is not UTF-8"),
            Error::HeaderTiming => f.write_str("frame time is zero or the clip has no frames"),
            Error::HeaderSourceUnit => f.write_str("source unit is 0 nm"),
            Error::HeaderEndSiteChannels { joint } => {
                write!(f, "End Site joint {joint} has channels")
            }
            Error::HeaderParent { joint } => write!(f, "joint {joint} has an invalid parent"),
            Error::HeaderChannelKind { code } => write!(f, "unknown channel kind {code}"),
            Error::HeaderUnit { code } => write!(f, "unknown channel unit {code}"),
            Error::HeaderChannelCount { joints, table } => write!(
                f,
                "joints declare {joints} channels but the channel table has {table}"
            ),
            Error::HeaderRange { channel } => write!(f, "channel {channel} has min > max"),
            Error::HeaderTrailingBytes => f.write_str("bytes after the end of the header"),
            Error::RigMalformed { rule } => write!(f, "rig table: {rule}"),
            Error::MissingMalformed { offset } => {
                write!(f, "missing samples: malformed at byte {offset}")
            }
            Error::MissingMarkerCount { markers, joints } => write!(
                f,
                "missing samples: {markers} markers, the header has {joints} joints"
            ),
            Error::MissingRunTotal { marker, frames } => write!(
                f,
                "missing samples: the runs of marker {marker} do not add up to {frames} frames"
            ),
            Error::MissingEmptyRun { marker, run } => {
                write!(f, "missing samples: run {run} of marker {marker} is empty")
            }
            Error::MissingTrailingBytes { offset } => {
                write!(
                    f,
                    "missing samples: bytes after the last marker at byte {offset}"
                )
            }
            Error::IndexMalformed { rule } => write!(f, "index codec: {rule}"),
            Error::IndexDescriptor { channel } => {
                write!(f, "index codec: invalid descriptor for channel {channel}")
            }
            Error::IndexPayloadTruncated {
                needed_bits,
                available_bits,
            } => write!(
                f,
                "index codec: payload has {available_bits} bits, frames need {needed_bits}"
            ),
            Error::PcaMalformed { rule } => write!(f, "pca-spline codec: {rule}"),
            Error::PredictiveMalformed { rule } => write!(f, "predictive codec: {rule}"),
            Error::PatternMalformed { rule } => write!(f, "pattern codec: {rule}"),
            Error::RmaMalformed { rule } => write!(f, "rma codec: {rule}"),
            Error::EntropyTable { rule } => write!(f, "entropy table: {rule}"),
            Error::EntropyState => {
                f.write_str("entropy-coded stream: initial state missing or out of range")
            }
            Error::ShowMalformed { offset } => write!(f, "malformed show table at byte {offset}"),
            Error::ShowClipCodec { clip } => {
                write!(f, "show clip {clip}: no codec section of its own")
            }
            Error::ShowClipOutOfRange { clip, clips } => {
                write!(f, "show clip {clip} out of range (the show has {clips})")
            }
            Error::ShowCuesMalformed { offset } => {
                write!(f, "malformed cue section at byte {offset}")
            }
            Error::PlayerStateTooSmall { needed, capacity } => write!(
                f,
                "the codec needs {needed} words of player state, player capacity is {capacity}"
            ),
            Error::PlayerCapacity { channels, capacity } => write!(
                f,
                "clip has {channels} channels, player capacity is {capacity}"
            ),
            Error::PlayerOutputTooSmall { expected, actual } => {
                write!(f, "output slice holds {actual} values, {expected} needed")
            }
            Error::PlayerInvariant { frame } => write!(
                f,
                "decoder invariant broken at frame {frame} (a decoder bug: the clip was validated)"
            ),
            Error::PlayerFrameOutOfRange { frame, frames } => {
                write!(f, "frame {frame} out of range (clip has {frames})")
            }
        }
    }
}

/// `core::error::Error`, so no `std` is needed for `?` into a boxed error.
impl core::error::Error for Error {}
