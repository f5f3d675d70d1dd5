//! Reads every motion file of the given folders or files the way every
//! command does (`input::expand`, then `input::read_motion`: BVH, or AMC
//! with its ASF) and prints the readers' throughput (MB of file text per
//! second, reading from disk included) and the time for the whole set:
//!
//! ```sh
//! cargo run --release -p mocap-encoder --example read_folder -- ../shared/data/cmu ../shared/data/iclone-cmu
//! ```
//!
//! `scripts/bench.sh` (part 8) runs it on a folder of 500 files made of the
//! corpus' files (links), BENCHMARKS.md §8.

use std::path::PathBuf;
use std::time::Instant;

use mocap_encoder::input;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if paths.is_empty() {
        return Err("usage: read_folder FOLDER_OR_FILE...".into());
    }
    let files = input::expand(&paths)?;
    let (mut bvh, mut amc) = ((0usize, 0usize, 0.0f64), (0usize, 0usize, 0.0f64));
    let mut frames = 0usize;
    let start = Instant::now();
    for f in &files {
        let bytes = std::fs::metadata(f)?.len() as usize;
        let t = Instant::now();
        let read = input::read_motion(f, None)?;
        let s = t.elapsed().as_secs_f64();
        frames += read.motion.frames();
        let slot = if read.asf.is_some() {
            &mut amc
        } else {
            &mut bvh
        };
        slot.0 += 1;
        slot.1 += bytes;
        slot.2 += s;
    }
    let total = start.elapsed().as_secs_f64();
    for (what, (n, bytes, s)) in [("BVH", bvh), ("AMC", amc)] {
        if n > 0 {
            println!(
                "{what}: {n} files, {:.1} MB in {s:.2} s: {:.0} MB/s",
                bytes as f64 / 1e6,
                bytes as f64 / 1e6 / s
            );
        }
    }
    println!(
        "{} files, {frames} frames, read in {total:.2} s ({:.1} ms per file)",
        files.len(),
        1e3 * total / files.len().max(1) as f64
    );
    Ok(())
}
