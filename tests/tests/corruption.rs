//! Thousands of truncated and bit-flipped clips go through the decoder; each
//! must give an `Err` or valid output, never a panic. Half of the mutants
//! get their CRC re-sealed so the mutation reaches the header and codec
//! parsers instead of stopping at the checksum.

use mocap_encoder::container::CRC32;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{bvh, generate, units};
use mocap_tests::{corpus_file, exercise_decoder};

/// A small deterministic PRNG (xorshift64*), so failures reproduce.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

fn reseal(mut v: Vec<u8>) -> Vec<u8> {
    if v.len() >= 4 {
        let n = v.len() - 4;
        let crc = CRC32.checksum(&v[..n]);
        v[n..].copy_from_slice(&crc.to_le_bytes());
    }
    v
}

fn encode_at(m: &mocap_encoder::motion::Motion, bound: &str, key_interval: Option<u16>) -> Vec<u8> {
    encode_with(m, CodecChoice::Index, bound, key_interval)
}

fn encode_with(
    m: &mocap_encoder::motion::Motion,
    codec: CodecChoice,
    bound: &str,
    key_interval: Option<u16>,
) -> Vec<u8> {
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound: Bound::from_specs(&[bound.parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(m).metres(),
        key_interval,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    encode::encode(m, &opts).unwrap().bytes
}

fn hammer(name: &str, clip: &[u8], rounds: usize, seed: u64) -> (usize, usize) {
    assert!(
        exercise_decoder(clip).is_ok(),
        "{name}: the valid clip must decode"
    );
    let mut rng = Rng(seed);
    let (mut ok, mut err) = (0, 0);
    let mut tally = |r: Result<u64, mocap_decoder::Error>| match r {
        Ok(_) => ok += 1,
        Err(_) => err += 1,
    };
    // Every truncation point near the start, sampled ones further on.
    for len in (0..clip.len().min(400)).chain((0..200).map(|_| rng.below(clip.len()))) {
        tally(exercise_decoder(&clip[..len]));
        tally(exercise_decoder(&reseal(clip[..len].to_vec())));
    }
    for _ in 0..rounds {
        let mut v = clip.to_vec();
        let flips = 1 + rng.below(4);
        for _ in 0..flips {
            // Bias towards the structural front of the file.
            let at = if rng.below(2) == 0 {
                rng.below(v.len().min(512))
            } else {
                rng.below(v.len())
            };
            v[at] ^= 1 << rng.below(8);
        }
        if rng.below(8) == 0 {
            let at = rng.below(v.len());
            v[at] = [0x00, 0xFF, 0x80, 0x7F][rng.below(4)];
        }
        tally(exercise_decoder(&v));
        tally(exercise_decoder(&reseal(v)));
    }
    (ok, err)
}

#[test]
fn demo_clip_mutants_never_panic() {
    let m = generate::animatronic_demo();
    for k in [None, Some(0), Some(8)] {
        let clip = encode_at(&m, "1deg", k);
        let (ok, err) = hammer("demo", &clip, 3000, 0x5EED ^ u64::from(k.unwrap_or(99)));
        eprintln!("demo K={k:?}: {ok} decoded, {err} rejected");
        assert!(err > 0);
    }
}

#[test]
fn corpus_clip_mutants_never_panic() {
    let Some(file) = corpus_file("cmu", "35_17.bvh") else {
        return;
    };
    let m = bvh::read_file(&file).unwrap();
    let clip = encode_at(&m, "1deg", Some(16));
    let (ok, err) = hammer("35_17", &clip, 3000, 0xC0FFEE);
    eprintln!("35_17: {ok} decoded, {err} rejected");
}

#[test]
fn pca_spline_mutants_never_panic() {
    let m = generate::animatronic_demo();
    let clip = encode_with(&m, CodecChoice::PcaSpline, "1deg", None);
    let (ok, err) = hammer("demo pca-spline", &clip, 3000, 0xB1E5);
    eprintln!("demo pca-spline: {ok} decoded, {err} rejected");
    assert!(err > 0);
    let Some(file) = corpus_file("cmu", "16_07.bvh") else {
        return;
    };
    let m = bvh::read_file(&file).unwrap();
    // Segments, blends and patches all occur in this clip.
    let clip = encode_with(&m, CodecChoice::PcaSpline, "50mm", None);
    let (ok, err) = hammer("16_07 pca-spline", &clip, 3000, 0xFACE);
    eprintln!("16_07 pca-spline: {ok} decoded, {err} rejected");
}

#[test]
fn predictive_mutants_never_panic() {
    let m = generate::animatronic_demo();
    // Short blocks: many block starts, block table entries and coder restarts.
    for k in [None, Some(7)] {
        let clip = encode_with(&m, CodecChoice::Predictive, "0.5deg", k);
        let (ok, err) = hammer(
            "demo predictive",
            &clip,
            3000,
            0x9E3D ^ u64::from(k.unwrap_or(1)),
        );
        eprintln!("demo predictive K={k:?}: {ok} decoded, {err} rejected");
        assert!(err > 0);
    }
    let Some(file) = corpus_file("cmu", "35_17.bvh") else {
        return;
    };
    let m = bvh::read_file(&file).unwrap();
    let clip = encode_with(&m, CodecChoice::Predictive, "20mm", Some(64));
    let (ok, err) = hammer("35_17 predictive", &clip, 3000, 0xD1CE);
    eprintln!("35_17 predictive: {ok} decoded, {err} rejected");
}

#[test]
fn pattern_mutants_never_panic() {
    let m = generate::animatronic_demo();
    for bound in ["0.5deg", "50mm"] {
        let clip = encode_with(&m, CodecChoice::Pattern, bound, None);
        let (ok, err) = hammer("demo pattern", &clip, 3000, 0x7A77 ^ bound.len() as u64);
        eprintln!("demo pattern {bound}: {ok} decoded, {err} rejected");
        assert!(err > 0);
    }
    let Some(file) = corpus_file("cmu", "35_17.bvh") else {
        return;
    };
    let m = bvh::read_file(&file).unwrap();
    let clip = encode_with(&m, CodecChoice::Pattern, "50mm", None);
    let (ok, err) = hammer("35_17 pattern", &clip, 3000, 0x5A77);
    eprintln!("35_17 pattern: {ok} decoded, {err} rejected");
}

#[test]
fn rma_mutants_never_panic() {
    // The demo played twice: a repeated clip with its map and residual.
    let twice = mocap_tests::demo_played_twice();
    let clip = encode_with(&twice, CodecChoice::Rma, "20mm", None);
    let (ok, err) = hammer("demo twice rma", &clip, 3000, 0x12AA);
    eprintln!("demo twice rma: {ok} decoded, {err} rejected");
    assert!(err > 0);
    let Some(file) = corpus_file("cmu", "05_04.bvh") else {
        return;
    };
    let m = bvh::read_file(&file).unwrap();
    let clip = encode_with(&m, CodecChoice::Rma, "50mm", None);
    let (ok, err) = hammer("05_04 rma", &clip, 3000, 0x05A4);
    eprintln!("05_04 rma: {ok} decoded, {err} rejected");
}
