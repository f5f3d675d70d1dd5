//! Any byte string: `Clip::parse` plus every way of playing must return an
//! `Err` or values, never panic or read out of bounds. Seed the corpus with
//! real clips (`bash scripts/fuzz.sh` does) so the fuzzer gets past the CRC
//! by mutating valid files; the CRC check is what a flipped bit usually
//! hits, so the target also re-seals the CRC to reach the deeper parsers.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mocap_decoder::{Clip, Player};

fn play(bytes: &[u8]) {
    let Ok(clip) = Clip::parse(bytes) else { return };
    let _ = clip.header().joints().count();
    let _ = clip.header().channels().count();
    if let Some(rig) = clip.rig() {
        for s in rig.servos() {
            let _ = (
                s.pulse_qus(i32::MIN),
                s.pulse_qus(i32::MAX),
                s.max_step_qus(rig.rate_mhz()),
            );
        }
    }
    let Ok(mut player) = Player::<512>::new(&clip) else {
        return;
    };
    let mut out = [0i32; 512];
    while let Ok(Some(_)) = player.next_frame(&mut out) {}
    let n = player.frame_count();
    let _ = player.frame(n / 2, &mut out);
    let _ = player.frame(n.wrapping_sub(1), &mut out);
    let _ = player.sample_at(clip.header().duration_us() / 3, &mut out);
    let _ = player.sample_at(u64::MAX, &mut out);
}

fuzz_target!(|data: &[u8]| {
    play(data);
    // Re-seal the CRC so mutations reach the header and codec parsers.
    if data.len() >= 4 {
        let mut v = data.to_vec();
        let n = v.len() - 4;
        let crc = crc32(&v[..n]);
        v[n..].copy_from_slice(&crc.to_le_bytes());
        play(&v);
    }
});

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}
