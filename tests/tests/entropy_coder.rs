//! The static rANS coder of SPEC.md §10, encoder (`mocap_encoder::entropy`)
//! against decoder (`mocap_decoder::entropy`): random streams round-trip
//! (alphabets 1 … 256, flat and skewed, 0 … 10 000 symbols), the size stays
//! within 1 % of the Shannon entropy on a long skewed stream (tables and
//! state included), and malformed tables and streams give typed errors.

use mocap_decoder::entropy::{Decoder, Table};
use mocap_decoder::Error;
use mocap_encoder::entropy::{encode_all, histogram, shannon_bits, Model};

/// xorshift32: the same streams on every run.
struct Rng(u32);

impl Rng {
    fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }

    fn unit(&mut self) -> f64 {
        f64::from(self.next()) / 4_294_967_296.0
    }

    /// A symbol of `0 … a − 1`, geometric with ratio `r` (`r = 1`: flat).
    fn symbol(&mut self, a: u32, r: f64) -> u32 {
        if r >= 1.0 {
            return self.next() % a;
        }
        let s = (self.unit().max(1e-300).ln() / r.ln()).floor();
        (s as u32).min(a - 1)
    }
}

fn decode(bytes: &[u8], count: usize) -> Vec<u32> {
    let (t, used) = Table::parse(bytes).unwrap();
    let mut d = Decoder::new(t, &bytes[used..]).unwrap();
    let out = (0..count).map(|_| d.symbol()).collect();
    assert!(d.is_finished());
    out
}

#[test]
fn random_streams_roundtrip() {
    let mut rng = Rng(0x9e37_79b9);
    let mut cases = 0;
    for a in (1..=256u32).step_by(5).chain([1, 2, 3, 255, 256]) {
        for r in [1.0, 0.9, 0.6, 0.2] {
            let len = match cases % 4 {
                0 => (rng.next() % 10) as usize,
                1 => (rng.next() % 300) as usize,
                2 => (rng.next() % 3000) as usize,
                _ => 10_000,
            };
            let s: Vec<u32> = (0..len).map(|_| rng.symbol(a, r)).collect();
            let bytes = encode_all(&s).unwrap();
            assert_eq!(decode(&bytes, s.len()), s, "a={a} r={r} len={len}");
            cases += 1;
        }
    }
    // One symbol over and over: a 2-byte table and the 4-byte state.
    let s = vec![0u32; 10_000];
    let bytes = encode_all(&s).unwrap();
    assert_eq!(bytes.len(), 6);
    assert_eq!(decode(&bytes, s.len()), s);
    let s = vec![41u32; 10_000];
    assert_eq!(decode(&encode_all(&s).unwrap(), s.len()), s);
    assert!(cases > 200);
}

/// Zigzag residuals of a two-sided geometric (Laplacian-like) source, the
/// shape of quantised motion differences.
fn laplacian(rng: &mut Rng, len: usize, r: f64) -> Vec<u32> {
    (0..len)
        .map(|_| {
            let m = rng.symbol(u32::MAX, r);
            if m == 0 {
                0
            } else if rng.next() & 1 == 0 {
                2 * m - 1
            } else {
                2 * m
            }
        })
        .collect()
}

#[test]
fn size_within_one_percent_of_entropy() {
    let mut rng = Rng(0x1234_5678);
    for (len, r) in [(10_000, 0.5), (10_000, 0.7), (20_000, 0.8), (50_000, 0.9)] {
        let s = laplacian(&mut rng, len, r);
        let hist = histogram(&s);
        let h = shannon_bits(&hist);
        let bytes = encode_all(&s).unwrap();
        let bits = bytes.len() as f64 * 8.0;
        let model = Model::fit(&s).unwrap();
        println!(
            "{len} symbols, ratio {r}: alphabet {}, n = {}, entropy {:.1} bytes, coded {} bytes \
             (table {}), +{:.2} %",
            hist.len(),
            model.precision(),
            h / 8.0,
            bytes.len(),
            model.table_bytes().len(),
            (bits / h - 1.0) * 100.0
        );
        assert!(
            bits <= h * 1.01,
            "{len} symbols, r {r}: {bits} bits, entropy {h}"
        );
        assert_eq!(decode(&bytes, s.len()), s);
    }
}

#[test]
fn malformed_tables_and_streams_are_errors() {
    let s: Vec<u32> = (0..500u32).map(|i| (i * i) % 7).collect();
    let bytes = encode_all(&s).unwrap();
    let (_, used) = Table::parse(&bytes).unwrap();
    // Every truncation of the table: a typed error.
    for cut in 0..used {
        assert!(
            matches!(Table::parse(&bytes[..cut]), Err(Error::EntropyTable { .. })),
            "cut at {cut}"
        );
    }
    // Zero alphabet.
    assert!(matches!(
        Table::parse(&[bytes[0], 0x00]),
        Err(Error::EntropyTable { .. })
    ));
    // Counts that add up to more than M: every stored count at its maximum.
    let mut bad = bytes[..used].to_vec();
    for b in &mut bad[2..] {
        *b = 0xff;
    }
    assert!(matches!(
        Table::parse(&bad),
        Err(Error::EntropyTable { .. })
    ));
    // A truncated stream: the state missing is an error; a stream cut after
    // the state decodes (zeros past the end) to garbage, never panics.
    let (t, _) = Table::parse(&bytes).unwrap();
    for cut in used..bytes.len() {
        match Decoder::new(t, &bytes[used..cut]) {
            Err(e) => {
                assert_eq!(e, Error::EntropyState);
                assert!(cut - used < 4);
            }
            Ok(mut d) => {
                let got: Vec<u32> = (0..s.len()).map(|_| d.symbol()).collect();
                assert!(got.iter().all(|&g| g < t.alphabet()));
                assert!(d.state() < 1 << 31);
                // No integrity check in the coder (the container's CRC is
                // that): a cut stream may even end at x = 2^23.
                assert!(cut < bytes.len() || d.is_finished());
            }
        }
    }
    // Every single flipped bit of the stream: no panic, symbols in range.
    for i in used..bytes.len() {
        for bit in 0..8 {
            let mut b = bytes.clone();
            b[i] ^= 1 << bit;
            if let Ok(mut d) = Decoder::new(t, &b[used..]) {
                for _ in 0..s.len() {
                    assert!(d.symbol() < t.alphabet());
                }
            }
        }
    }
}
