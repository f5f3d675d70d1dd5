//! Constants shared by the encoder and the decoder (SPEC.md §2–§5b).
//! The encoder imports this module; nothing here is duplicated elsewhere.

/// File magic, SPEC.md §2.1.
pub const MAGIC: [u8; 4] = *b"MOCB";
/// Current bitstream version, SPEC.md §2.1.
pub const VERSION: u8 = 1;
/// Bitstream version of a show (many clips, SPEC.md §9).
pub const VERSION_SHOW: u8 = 2;
/// Largest number of sections a show may declare (§9.1).
pub const MAX_SHOW_SECTIONS: usize = 1024;
/// Largest number of clips in a show (§9.2).
pub const MAX_SHOW_CLIPS: usize = 255;
/// Longest clip name in a show, bytes (§9.2).
pub const MAX_CLIP_NAME: usize = 31;
/// Most shared model sections one show clip reads (§9.2).
pub const MAX_CLIP_MODELS: usize = 4;
/// Section id of a show's clip directory, §9.2.
pub const SECTION_SHOW: u8 = 0x04;
/// Section id of a show's cue lists and triggers, §9.5.
pub const SECTION_CUES: u8 = 0x05;
/// First and last section ids of shared model sections, §9.1.
pub const SECTION_MODEL_FIRST: u8 = 0x20;
/// Last id of the shared model sections, §9.1.
pub const SECTION_MODEL_LAST: u8 = 0x2F;
/// Shared model section: the `pattern` codec's database, §11.2.
pub const SECTION_MODEL_PATTERN: u8 = 0x20;
/// Bytes before the section table: magic(4) version(1) flags(1) count(2).
pub const PREAMBLE_LEN: usize = 8;
/// Bytes per section-table entry: id(1) reserved(3) offset(4) length(4).
pub const SECTION_ENTRY_LEN: usize = 12;
/// Length of the trailing CRC-32.
pub const CRC_LEN: usize = 4;
/// Largest number of sections a file may declare.
pub const MAX_SECTIONS: usize = 16;

/// Section id of the header (frame timing, skeleton, channel table), §3.
pub const SECTION_HEADER: u8 = 0x01;
/// Section id of the compact header (same content, smaller), §3.4. A clip
/// has exactly one of `0x01` and `0x02`.
pub const SECTION_HEADER_COMPACT: u8 = 0x02;
/// Section id of the rig table of a servo clip, §3.5.
pub const SECTION_RIG: u8 = 0x03;
/// Section id of the `index` codec payload, §4.
pub const SECTION_CODEC_INDEX: u8 = 0x10;
/// Rig digest (§3.6): ancillary, the digest of the rig a servo clip was encoded for.
pub const SECTION_RIG_DIGEST: u8 = 0x80;
/// Missing samples (§3.7): ancillary, which samples of a marker clip the
/// capture did not have.
pub const SECTION_MISSING: u8 = 0x81;
/// Section id of the `pca-spline` codec payload, §5.
pub const SECTION_CODEC_PCA_SPLINE: u8 = 0x11;
/// Section id of the `predictive` codec payload, §5b.
pub const SECTION_CODEC_PREDICTIVE: u8 = 0x12;
/// Section id of the `index` codec in its fast layout, §4.6.
pub const SECTION_CODEC_INDEX_FAST: u8 = 0x13;
/// Section id of the `pattern` codec payload, §11.
pub const SECTION_CODEC_PATTERN: u8 = 0x14;
/// Section id of the `rma` codec payload, §12.
pub const SECTION_CODEC_RMA: u8 = 0x15;

/// Whether `id` is a codec section's (§2.2): `index` (both layouts),
/// `pca-spline`, `predictive`, `pattern`, `rma`.
pub const fn is_codec_section(id: u8) -> bool {
    matches!(
        id,
        SECTION_CODEC_INDEX
            | SECTION_CODEC_INDEX_FAST
            | SECTION_CODEC_PCA_SPLINE
            | SECTION_CODEC_PREDICTIVE
            | SECTION_CODEC_PATTERN
            | SECTION_CODEC_RMA
    )
}

/// Channel kind codes, SPEC.md §3.2 (`kind` field).
pub mod kind {
    /// Translation along X.
    pub const X_POSITION: u8 = 0;
    /// Translation along Y.
    pub const Y_POSITION: u8 = 1;
    /// Translation along Z.
    pub const Z_POSITION: u8 = 2;
    /// Rotation about X.
    pub const X_ROTATION: u8 = 3;
    /// Rotation about Y.
    pub const Y_ROTATION: u8 = 4;
    /// Rotation about Z.
    pub const Z_ROTATION: u8 = 5;
}

/// Fixed-point units, SPEC.md §3.3 (`unit` field).
pub mod unit {
    /// 1/1000 degree.
    pub const MILLIDEGREE: u8 = 0;
    /// 1/1000 millimetre.
    pub const MICROMETRE: u8 = 1;
}

/// Index codec constants, SPEC.md §4.
pub mod index {
    /// Bytes of a group header (§4.2): width, shift+flags, count.
    pub const GROUP_HEADER_LEN: usize = 4;
    /// Bytes of one group entry (§4.2): channel, table offset, base.
    pub const ENTRY_LEN: usize = 8;
    /// Largest index width in bits.
    pub const MAX_BITS: u8 = 12;
    /// Largest table shift.
    pub const MAX_SHIFT: u8 = 24;
    /// Group flag: add the looked-up value to the previous frame's value.
    pub const FLAG_ACCUMULATE: u8 = 0x80;
    /// Mask of the shift in group header byte 1.
    pub const SHIFT_MASK: u8 = 0x1F;
    /// Bytes of a group header in the fast layout (§4.6): width, flags,
    /// count, stride.
    pub const FAST_GROUP_HEADER_LEN: usize = 6;
    /// Index widths of the fast layout (§4.6): whole bytes, or fields that
    /// never straddle a byte.
    pub const FAST_WIDTHS: [u8; 6] = [0, 1, 2, 4, 8, 16];
}

/// `pca-spline` codec constants, SPEC.md §5.
pub mod pca {
    /// Most principal components a group may keep.
    pub const MAX_COMPONENTS: u8 = 16;
    /// Largest mean shift.
    pub const MAX_MEAN_SHIFT: u8 = 16;
    /// Largest number of frames in one segment.
    pub const MAX_SEGMENT_FRAMES: u32 = 32_768;
    /// Largest bit width of a key time.
    pub const MAX_TIME_BITS: u8 = 15;
    /// Largest bit width of a key value.
    pub const MAX_VALUE_BITS: u8 = 30;
    /// Largest key value shift.
    pub const MAX_VALUE_SHIFT: u8 = 24;
    /// Basis entries are `i8` scaled by `2^-BASIS_SHIFT`.
    pub const BASIS_SHIFT: u32 = 7;
    /// Fixed-point fraction bits of positions and spline weights.
    pub const FRAC_BITS: u32 = 16;
}

/// `predictive` codec constants, SPEC.md §5b.
pub mod predictive {
    /// Probabilities are `PROB_BITS`-bit: `p / 2^PROB_BITS` is the chance of a 0.
    pub const PROB_BITS: u32 = 11;
    /// A fresh probability (one half).
    pub const PROB_INIT: u16 = 1 << (PROB_BITS - 1);
    /// Adaptation speed: after each bit, `p` moves `1 / 2^MOVE_BITS` of the way.
    pub const MOVE_BITS: u32 = 5;
    /// The range is renormalised (one byte shifted in) while below this.
    pub const TOP: u32 = 1 << 24;
    /// Contexts: the channel's previous residual magnitude, 0, 1 or ≥ 2.
    pub const CONTEXTS: usize = 3;
    /// Magnitude bits coded with a context: `|q| > 1`, …, `|q| > MAGNITUDE_STEPS`.
    pub const MAGNITUDE_STEPS: u32 = 8;
    /// Probabilities per context: zero flag, sign, magnitude steps.
    pub const PROBS_PER_CONTEXT: usize = 2 + MAGNITUDE_STEPS as usize;
    /// Longest Exp-Golomb prefix of an escaped magnitude.
    pub const MAX_ESCAPE_BITS: u32 = 30;
    /// Predictor weights `a` (of 4) by mode bits 0–1: `pred = v1 + ((a · (v1 − v2)) >> 2)`.
    pub const PREDICTOR_WEIGHTS: [i64; 4] = [0, 2, 3, 4];
    /// Mode bit 2: a constant channel.
    pub const MODE_CONSTANT: u32 = 0x04;
    /// Mode bits above this hold the step multiplier.
    pub const MODE_STEP_SHIFT: u32 = 3;
    /// Largest quantisation step, `unit × multiplier`.
    pub const MAX_STEP: u32 = 1 << 30;
    /// Player state words besides `3 · C`: probabilities (two per word) and the coder.
    pub const STATE_EXTRA_WORDS: usize = CONTEXTS * PROBS_PER_CONTEXT / 2 + 4;
}

/// Flags of a servo in the compact rig table, SPEC.md §3.5.1.
pub mod rig_flag {
    /// `output` = the previous servo's + 1 (0 for the first); else a varint.
    pub const OUTPUT_NEXT: u8 = 0x01;
    /// Angle and pulse range as the previous servo's.
    pub const SAME_RANGE: u8 = 0x02;
    /// Angles stored in whole degrees (× 1000).
    pub const ANGLE_DEG: u8 = 0x04;
    /// `neutral` = `(pulse_lo + pulse_hi) div 2`; else a varint.
    pub const MID_NEUTRAL: u8 = 0x08;
    /// `max_speed` as the previous servo's.
    pub const SAME_SPEED: u8 = 0x10;
    /// `max_speed` stored in whole degrees per second (× 1000).
    pub const SPEED_DEG: u8 = 0x20;
    /// Pulses from the previous servo's angle-to-pulse line (only the
    /// angles are stored).
    pub const SAME_MAP: u8 = 0x40;
    /// Every defined bit.
    pub const ALL: u8 = 0x7F;
}
