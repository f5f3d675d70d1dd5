//! The static rANS coder of SPEC.md §10, encoder (`mocap_encoder::entropy`)
//! against decoder (`mocap_decoder::entropy`): random streams round-trip
//! (alphabets 1 … 256, flat and skewed, 0 … 10 000 symbols), the size stays
//! within 1 % of the Shannon entropy on a long skewed stream (tables and
//! state included), malformed tables and streams give typed errors, and the
//! binary-search path (`Table::index`, `Decoder::symbol_in`) decodes every
//! stream to the same symbols and states as the scan.

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

/// Decodes `count` symbols with the scan and, beside it, through the
/// table's index: the same symbol and state at every step.
fn decode(bytes: &[u8], count: usize) -> Vec<u32> {
    let (t, used) = Table::parse(bytes).unwrap();
    let mut d = Decoder::new(t, &bytes[used..]).unwrap();
    let mut buf = vec![0u16; t.alphabet() as usize + 1];
    let index = t.index(&mut buf).unwrap();
    let mut di = Decoder::new(t, &bytes[used..]).unwrap();
    let out = (0..count)
        .map(|i| {
            let s = d.symbol();
            assert_eq!(di.symbol_in(&index), s, "symbol {i}");
            assert_eq!(di.state(), d.state(), "state after symbol {i}");
            s
        })
        .collect();
    assert!(d.is_finished() && di.is_finished());
    out
}

#[test]
fn the_index_decodes_escaped_values_and_zero_counts_as_the_scan() {
    // Counts with zeros between (symbols never coded), the escape last.
    let mut rng = Rng(0x1234_5678);
    for a in [2u32, 3, 17, 64, 200, 1000] {
        let n = 12;
        let mut counts = vec![0u32; a as usize];
        let mut left = 1u32 << n;
        for (s, c) in counts.iter_mut().enumerate().take(a as usize - 1) {
            if s % 3 != 1 {
                *c = (rng.next() % (left / 4 + 1)).min(left);
                left -= *c;
            }
        }
        counts[a as usize - 1] = left;
        let model = Model::from_counts(n, counts.clone()).unwrap();
        let values: Vec<u32> = (0..5000)
            .map(|_| loop {
                let v = rng.next() % (a + 40);
                let s = v.min(a - 1) as usize;
                if counts[s] > 0 {
                    break v;
                }
            })
            .collect();
        let mut bytes = model.table_bytes();
        bytes.extend(model.encode_values(&values).unwrap());
        let (t, used) = Table::parse(&bytes).unwrap();
        let mut buf = vec![0u16; a as usize + 1];
        let index = t.index(&mut buf).unwrap();
        let (mut d, mut di) = (
            Decoder::new(t, &bytes[used..]).unwrap(),
            Decoder::new(t, &bytes[used..]).unwrap(),
        );
        for (i, &v) in values.iter().enumerate() {
            assert_eq!(d.value(), v, "a={a} value {i}");
            assert_eq!(di.value_in(&index), v, "a={a} value {i} through the index");
            assert_eq!(di.state(), d.state());
        }
        assert!(d.is_finished() && di.is_finished());
        // Too short a buffer is an error; an index of another table falls
        // back to the scan.
        let mut short = vec![0u16; a as usize];
        assert!(matches!(
            t.index(&mut short),
            Err(Error::EntropyTable { .. })
        ));
        let other = Model::from_counts(n, vec![1 << (n - 1), 1 << (n - 1)]).unwrap();
        let other_bytes = other.table_bytes();
        let (ot, _) = Table::parse(&other_bytes).unwrap();
        let mut obuf = [0u16; 3];
        let oindex = ot.index(&mut obuf).unwrap();
        if a != 2 {
            let mut dj = Decoder::new(t, &bytes[used..]).unwrap();
            for &v in &values {
                assert_eq!(dj.value_in(&oindex), v);
            }
        }
    }
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
