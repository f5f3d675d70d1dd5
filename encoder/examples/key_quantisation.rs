//! The paper's Table 4 on our data (Lin et al. 2011, issue 14): the
//! range-aware adaptive key quantisation against uniform 9-bit keys for
//! primary (own) stretches and 7-bit keys for repeated clips' residuals,
//! each clip proven within the same bound. Per take and codec
//! (`pca-spline`, `rma`): bytes, the key payload's bytes, ARMS and max
//! joint error; a row that cannot meet the bound says why.
//!
//! ```sh
//! cargo run --release -p mocap-encoder --example key_quantisation -- 50mm+arms:10mm ../shared/data/cmu ../shared/data/cmu-long
//! ```

use std::path::PathBuf;

use mocap_encoder::codec::CodecChoice;
use mocap_encoder::encode::{self, Bound, BoundSpec, EncodeOptions};
use mocap_encoder::{input, units};

/// Key payload bytes of a `pca-spline` or `rma` clip.
fn key_bytes(clip: &[u8]) -> Option<usize> {
    let clip = mocap_decoder::Clip::parse(clip).ok()?;
    clip.sections().find_map(|s| match s.id {
        mocap_decoder::consts::SECTION_CODEC_PCA_SPLINE => {
            Some(mocap_encoder::codec::pca_spline::inspect(s.bytes)?.key_bytes)
        }
        mocap_decoder::consts::SECTION_CODEC_RMA => Some(
            mocap_encoder::codec::rma::section::inspect(s.bytes)?
                .body
                .key_bytes,
        ),
        _ => None,
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let bound = args.next().ok_or("usage: key_quantisation BOUND PATH…")?;
    let specs: Vec<BoundSpec> = bound.split('+').map(str::parse).collect::<Result<_, _>>()?;
    let paths: Vec<PathBuf> = args.map(PathBuf::from).collect();
    println!("| take | codec | quantisation | bytes | key bytes | ARMS mm | max mm |");
    println!("|---|---|---|---|---|---|---|");
    let mut totals = std::collections::BTreeMap::<(String, String), (usize, usize)>::new();
    for f in input::expand(&paths)? {
        let m = input::read_motion(&f, None)?.motion;
        let name = f
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        for codec in [CodecChoice::PcaSpline, CodecChoice::Rma] {
            for (label, key_bits) in [("adaptive", None), ("uniform 9/7 bits", Some((9, 7)))] {
                let opts = EncodeOptions {
                    codec,
                    bound: Bound::from_specs(&specs),
                    metres_per_unit: units::detect(&m).metres(),
                    key_interval: None,
                    index_layout: Default::default(),
                    pattern: Default::default(),
                    key_bits,
                };
                match encode::encode(&m, &opts) {
                    Ok(e) => {
                        let keys = key_bytes(&e.bytes).unwrap_or(0);
                        println!(
                            "| {name} | {} | {label} | {} | {keys} | {:.2} | {:.1} |",
                            codec.name(),
                            e.bytes.len(),
                            e.metrics.arms_mm,
                            e.metrics.max_joint_err_mm
                        );
                        let t = totals
                            .entry((codec.name().into(), label.into()))
                            .or_default();
                        t.0 += e.bytes.len();
                        t.1 += keys;
                    }
                    Err(e) => println!("| {name} | {} | {label} | — ({e}) | | | |", codec.name()),
                }
            }
        }
    }
    println!();
    println!("| codec | quantisation | total bytes | total key bytes |");
    println!("|---|---|---|---|");
    for ((codec, label), (bytes, keys)) in &totals {
        println!("| {codec} | {label} | {bytes} | {keys} |");
    }
    Ok(())
}
