//! Any bytes into the encoder's input readers — BVH, ASF, ASF + AMC (baked into the motion
//! model), C3D (then its marker clip) — must give a motion or a located error, never a panic,
//! an overflow or an allocation the file does not justify. The first byte picks the reader;
//! for AMC the rest splits at the first NUL into the ASF and the AMC text. Seeds
//! (`scripts/fuzz.sh`): the shipped demo BVH and, when present, the corpus' ASF/AMC and C3D
//! files, each behind its selector byte.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mocap_encoder::asf::{self, AmcOptions};
use mocap_encoder::{bvh, c3d};

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    match which % 4 {
        0 => {
            let _ = bvh::parse_str(&String::from_utf8_lossy(rest), "fuzz.bvh");
        }
        1 => {
            let _ = asf::parse_asf(&String::from_utf8_lossy(rest), "fuzz.asf");
        }
        2 => {
            let (a, b) = match rest.iter().position(|&x| x == 0) {
                Some(i) => (&rest[..i], &rest[i + 1..]),
                None => (rest, &[][..]),
            };
            let _ = asf::parse_strs(
                &String::from_utf8_lossy(a),
                "fuzz.asf",
                &String::from_utf8_lossy(b),
                "fuzz.amc",
                &AmcOptions::default(),
            );
        }
        _ => {
            if let Ok(c) = c3d::parse(rest, "fuzz.c3d") {
                let _ = c.summary();
                let _ = c.to_markers();
            }
        }
    }
});
