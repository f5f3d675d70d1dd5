//! The static rANS coder (SPEC.md §10) on real motion: every channel of a
//! BVH quantised at a step, frame-to-frame differences (first order) or
//! differences of differences (second order) of the quantised values,
//! zigzag-mapped to symbols, all channels in one stream with one table
//! (each channel's first frame, a codec's start values, left out).
//! Prints, per stream: symbols, alphabet, the Shannon entropy and the coded
//! size in bits per symbol (table and 4-byte state included), and the
//! overhead; then the same stream cut into blocks (one state per block, one
//! table) and with an escape (§10.4) cutting the alphabet short.
//!
//!   cargo run --release -p mocap-encoder --example entropy_report [-- FILE.bvh ...]
//!
//! Default file: `$MOCAP_CORPUS/cmu/35_01.bvh` (`MOCAP_CORPUS` default
//! `../shared/data` from the repository root).

use std::path::PathBuf;

use mocap_decoder::entropy::{Decoder, Table};
use mocap_encoder::entropy::{encode_all, histogram, shannon_bits, Model};

fn zigzag(v: i64) -> u32 {
    ((v << 1) ^ (v >> 63)) as u32
}

/// Channel-major symbol stream: `order` 1 = differences, 2 = second
/// differences of the values quantised at `step`.
fn symbols(values: &[f64], channels: usize, step: f64, order: u32) -> Vec<u32> {
    let frames = values.len() / channels;
    let mut out = Vec::with_capacity(values.len());
    for c in 0..channels {
        let q: Vec<i64> = (0..frames)
            .map(|f| (values[f * channels + c] / step).round() as i64)
            .collect();
        // Frame 0 (and, second order, frame 1's difference) is the
        // channel's start, which a codec keeps apart: not in the stream.
        for f in order as usize..frames {
            let d = q[f] - q[f - 1];
            let r = if order == 1 {
                d
            } else {
                d - (q[f - 1] - q[f - 2])
            };
            out.push(zigzag(r));
        }
    }
    out
}

fn check(bytes: &[u8], s: &[u32]) {
    let (t, used) = Table::parse(bytes).expect("table");
    let mut d = Decoder::new(t, &bytes[used..]).expect("state");
    for &x in s {
        assert_eq!(d.symbol(), x, "round trip");
    }
    assert!(d.is_finished());
}

fn main() {
    let mut files: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if files.is_empty() {
        let corpus = std::env::var("MOCAP_CORPUS").unwrap_or_else(|_| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data").to_string()
        });
        files.push(PathBuf::from(corpus).join("cmu/35_01.bvh"));
    }
    for path in files {
        let input = mocap_encoder::input::read_motion(&path, None)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let m = input.motion;
        let channels = m.channels();
        println!(
            "{}: {} frames x {} channels (values in the file's units: degrees, and its length unit)",
            path.display(),
            m.frames(),
            channels
        );
        println!(
            "{:<24} {:>8} {:>5} {:>3} {:>8} {:>8} {:>6} {:>8} {:>8}",
            "stream", "symbols", "A", "n", "H b/sym", "coded", "table", "bytes", "over %"
        );
        for order in [1, 2] {
            for step in [0.05, 0.1, 0.25, 0.5, 1.0] {
                let s = symbols(&m.values, channels, step, order);
                let hist = histogram(&s);
                let h = shannon_bits(&hist);
                let bytes = encode_all(&s).expect("encodes");
                check(&bytes, &s);
                let model = Model::fit(&s).expect("fits");
                let n = s.len() as f64;
                println!(
                    "{:<24} {:>8} {:>5} {:>3} {:>8.4} {:>8.4} {:>6} {:>8} {:>8.3}",
                    format!("d{order} step {step}"),
                    s.len(),
                    hist.len(),
                    model.precision(),
                    h / n,
                    bytes.len() as f64 * 8.0 / n,
                    model.table_bytes().len(),
                    bytes.len(),
                    (bytes.len() as f64 * 8.0 / h - 1.0) * 100.0
                );
                // Blocks of 1 000 and 10 000 symbols: one table, one state each.
                for block in [1_000usize, 10_000] {
                    let mut total = model.table_bytes().len();
                    for b in s.chunks(block) {
                        total += model.encode_symbols(b).expect("encodes").len();
                    }
                    println!(
                        "{:<24} {:>8} {:>5} {:>3} {:>8.4} {:>8.4} {:>6} {:>8} {:>8.3}",
                        format!("  blocks of {block}"),
                        s.len(),
                        hist.len(),
                        model.precision(),
                        h / n,
                        total as f64 * 8.0 / n,
                        model.table_bytes().len(),
                        total,
                        (total as f64 * 8.0 / h - 1.0) * 100.0
                    );
                }
                // The escape of §10.4 at the best cut-off.
                let best = Model::fit_values_best(&s).ok().map(|(model, e)| {
                    let mut b = model.table_bytes();
                    b.extend(model.encode_values(&s).expect("encodes"));
                    (b.len(), e, model)
                });
                if let Some((len, e, model)) = best {
                    println!(
                        "{:<24} {:>8} {:>5} {:>3} {:>8.4} {:>8.4} {:>6} {:>8} {:>8.3}",
                        format!("  escape at {e}"),
                        s.len(),
                        e + 1,
                        model.precision(),
                        h / n,
                        len as f64 * 8.0 / n,
                        model.table_bytes().len(),
                        len,
                        (len as f64 * 8.0 / h - 1.0) * 100.0
                    );
                }
            }
        }
        // Short streams: the first 2 000 and 5 000 symbols of one setting.
        let s = symbols(&m.values, channels, 0.1, 1);
        for len in [2_000usize, 5_000, 20_000] {
            let s = &s[..len.min(s.len())];
            let h = shannon_bits(&histogram(s));
            let bytes = encode_all(s).expect("encodes");
            check(&bytes, s);
            println!(
                "first {len} symbols of d1 step 0.1: entropy {:.1} bytes, coded {} bytes, +{:.2} %",
                h / 8.0,
                bytes.len(),
                (bytes.len() as f64 * 8.0 / h - 1.0) * 100.0
            );
        }
    }
}
