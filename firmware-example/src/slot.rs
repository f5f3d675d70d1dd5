//! The clip slot: in a build with `MOCAP_CLIP_SLOT=N` (build.rs) the clip is not compiled in but
//! written into this reserved flash area of the finished ELF, so one build plays any clip of up
//! to `N` bytes (`scripts/firmware.sh run` does this for the QEMU runs: building once per board
//! and mode instead of once per clip).
//!
//! Layout (little-endian), 32 bytes then the clip: [`MAGIC`] (16 bytes, how the script finds
//! the slot in the ELF file), the clip's length (`u32`), the servo output (1 byte, `MOCAP_SERVO`'s
//! number: 0 none, 1 Maestro, 2 SSC-32, 3 PWM, 4 PCA9685), 3 zero bytes, the sampling period in µs
//! (`u64`, 0 plays every frame) — the run's `--servo` and `--sample-us`, build settings otherwise —
//! then the clip's bytes. The firmware reads the slot through `core::hint::black_box`, so the
//! compiler cannot fold the placeholder's zeros into the code.

use crate::config::CLIP_SLOT;

/// What the slot starts with.
const MAGIC: [u8; 16] = *b"MOCAP-CLIP-SLOT:";
/// Bytes before the clip.
const HEAD: usize = 32;

/// The slot as built: the magic, then zeros (an empty clip).
static SLOT: [u8; HEAD + CLIP_SLOT] = placeholder();

const fn placeholder() -> [u8; HEAD + CLIP_SLOT] {
    let mut s = [0u8; HEAD + CLIP_SLOT];
    let mut i = 0;
    while i < MAGIC.len() {
        s[i] = MAGIC[i];
        i += 1;
    }
    s
}

/// The slot's bytes as written into the ELF (opaque to the optimiser).
fn slot() -> &'static [u8] {
    core::hint::black_box(&SLOT[..])
}

fn word<const N: usize>(at: usize) -> [u8; N] {
    slot()
        .get(at..at.wrapping_add(N))
        .and_then(|b| b.first_chunk::<N>())
        .copied()
        .unwrap_or([0; N])
}

/// The clip written into the slot (empty if its length does not fit the slot).
pub fn clip() -> &'static [u8] {
    let len = u32::from_le_bytes(word::<4>(16)) as usize;
    slot().get(HEAD..HEAD.saturating_add(len)).unwrap_or(&[])
}

/// The sampling period written into the slot, in µs (0: every frame).
pub fn sample_us() -> u64 {
    u64::from_le_bytes(word::<8>(24))
}

/// The servo output written into the slot (`MOCAP_SERVO`'s numbers; 0: none).
pub fn servo() -> u8 {
    word::<1>(20)[0]
}
