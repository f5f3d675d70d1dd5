//! How much the rANS coder (SPEC §10) would save on `pca-spline`'s key
//! payload (SPEC §5.3: per group and segment, `m` key times of `tb` bits and
//! `m` rows of fixed-width component codes), measured on real encodes: the
//! payload as stored against the same keys as entropy-coded streams — time
//! gaps, and each component's code minus the previous key's (zigzag), every
//! stream with its table. Issue 13 offers the coder to the codecs "where it
//! measurably helps"; issue 14 codes spline keys too.
//!
//! ```sh
//! cargo run --release -p mocap-encoder --example pca_keys_entropy -- 50mm+arms:10mm ../shared/data/cmu ../shared/data/cmu-long
//! ```

use std::path::PathBuf;

use mocap_decoder::{consts, Clip};
use mocap_encoder::container::ByteCursor;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::entropy::Model;
use mocap_encoder::input;

/// LSB-first bits (SPEC §4.4).
struct Bits<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Bits<'_> {
    fn read(&mut self, n: u8) -> u32 {
        let mut v = 0u32;
        for k in 0..n {
            let byte = self.bytes.get(self.at / 8).copied().unwrap_or(0);
            v |= u32::from((byte >> (self.at % 8)) & 1) << k;
            self.at += 1;
        }
        v
    }
}

/// Key streams of one section: (stored key payload bytes, time gaps, code
/// deltas, second differences).
#[derive(Default)]
struct Keys {
    stored: usize,
    gaps: Vec<u32>,
    deltas: Vec<u32>,
    second: Vec<u32>,
}

fn zz(v: i64) -> u32 {
    ((v << 1) ^ (v >> 63)) as u32
}

fn keys(section: &[u8], keys: &mut Keys) -> Option<()> {
    let mut r = ByteCursor::new(section);
    let w = if r.u8()? == 2 { 2 } else { 1 };
    let groups = r.varint()? as usize;
    let mut sizes = Vec::new();
    for _ in 0..groups {
        let n = r.varint()? as usize;
        r.skip(n * w)?;
        sizes.push(n);
    }
    let consts = r.varint()? as usize;
    r.skip(consts * w)?;
    for _ in 0..consts {
        r.varint()?;
    }
    for _ in 0..r.varint()? {
        r.varint()?;
        r.varint()?;
        let len = r.varint()? as usize;
        let stop = r.pos() + len;
        for &n in &sizes {
            let k = r.u8()? as usize;
            r.u8()?;
            if k == 0 {
                for _ in 0..n {
                    r.varint()?;
                }
                continue;
            }
            r.skip(2 * n + n * k)?;
            let m = r.varint()? as usize;
            let tb = r.u8()?;
            let mut widths = Vec::new();
            for _ in 0..k {
                widths.push(r.u8()?);
                r.u8()?;
                r.varint()?;
            }
            let row: usize = widths.iter().map(|&x| usize::from(x)).sum();
            let bytes = (m * (usize::from(tb) + row)).div_ceil(8);
            let from = r.pos();
            r.skip(bytes)?;
            keys.stored += bytes;
            let mut b = Bits {
                bytes: &section[from..from + bytes],
                at: 0,
            };
            let times: Vec<u32> = (0..m).map(|_| b.read(tb)).collect();
            keys.gaps.extend(times.windows(2).map(|t| t[1] - t[0]));
            let codes: Vec<Vec<i64>> = (0..m)
                .map(|_| widths.iter().map(|&x| i64::from(b.read(x))).collect())
                .collect();
            for j in 0..k {
                let column: Vec<i64> = codes.iter().map(|row| row[j]).collect();
                for (r, &c) in column.iter().enumerate() {
                    let p1 = if r > 0 { column[r - 1] } else { 0 };
                    let p2 = if r > 1 { column[r - 2] } else { p1 };
                    keys.deltas.push(zz(c - p1));
                    keys.second.push(zz(c - (2 * p1 - p2)));
                }
            }
        }
        if r.pos() != stop {
            return None;
        }
        let patches = r.varint()? as usize;
        r.skip(patches)?;
    }
    Some(())
}

fn coded(values: &[u32]) -> usize {
    if values.is_empty() {
        return 0;
    }
    let (model, _) = Model::fit_values_best(values).expect("model");
    model.table_bytes().len() + model.encode_values(values).expect("encode").len()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let bound_arg = args
        .next()
        .ok_or("usage: pca_keys_entropy BOUND FOLDER_OR_FILE...")?;
    let specs: Vec<BoundSpec> = bound_arg
        .split('+')
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let paths: Vec<PathBuf> = args.map(PathBuf::from).collect();
    println!("| file | clip bytes | key payload stored | gaps coded | code deltas coded | 2nd differences coded | best keys coded | saving on the clip |");
    println!("|---|---|---|---|---|---|---|---|");
    let (mut all_clip, mut all_saving) = (0usize, 0isize);
    for f in input::expand(&paths)? {
        let read = input::read_motion(&f, None)?;
        let opts = EncodeOptions {
            key_bits: None,
            codec: CodecChoice::PcaSpline,
            bound: Bound::from_specs(&specs),
            metres_per_unit: read.unit_or_detect().metres(),
            key_interval: None,
            index_layout: Default::default(),
            pattern: Default::default(),
        };
        let enc = encode::encode(&read.motion, &opts)?;
        let clip = Clip::parse(&enc.bytes).map_err(|e| format!("{e:?}"))?;
        let section = clip
            .sections()
            .find(|s| s.id == consts::SECTION_CODEC_PCA_SPLINE)
            .ok_or("no pca-spline section")?;
        let mut k = Keys::default();
        keys(section.bytes, &mut k).ok_or("section does not parse")?;
        let gaps = coded(&k.gaps);
        let (d1, d2) = (coded(&k.deltas), coded(&k.second));
        let best = gaps + d1.min(d2);
        let saving = k.stored as isize - best as isize;
        all_clip += enc.bytes.len();
        all_saving += saving;
        println!(
            "| {} | {} | {} | {gaps} | {d1} | {d2} | {best} | {:.1} % |",
            f.file_name().unwrap_or_default().to_string_lossy(),
            enc.bytes.len(),
            k.stored,
            100.0 * saving as f64 / enc.bytes.len() as f64
        );
    }
    println!(
        "| all | {all_clip} | | | | | | {:.1} % |",
        100.0 * all_saving as f64 / all_clip.max(1) as f64
    );
    Ok(())
}
