//! Repeated motion analysis (issue 14's first step, `codec::rma`) on motion
//! files: per file the PCA components kept, the similar-posture paths, and
//! how many frames end up in primary, repeated and unique clips.
//!
//! ```sh
//! cargo run --release -p mocap-encoder --example rma_analysis -- ../shared/data/cmu ../shared/data/cmu-long
//! ```

use std::path::PathBuf;
use std::time::Instant;

use mocap_encoder::codec::rma::{self, ClipKind, Params};
use mocap_encoder::input;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if paths.is_empty() {
        return Err("usage: rma_analysis FOLDER_OR_FILE...".into());
    }
    let p = Params::default();
    println!("| file | frames | k | paths | clips P/R/U | primary frames | repeated frames | unique frames | repeated % | s |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut total = [0usize; 3];
    for f in input::expand(&paths)? {
        let m = input::read_motion(&f, None)?.motion;
        let t = Instant::now();
        let a = rma::analyse(&m, &p);
        let secs = t.elapsed().as_secs_f64();
        let n = a.frames_by_kind();
        let count = |want: fn(&ClipKind) -> bool| a.clips.iter().filter(|c| want(&c.kind)).count();
        let clips = (
            count(|k| *k == ClipKind::Primary),
            count(|k| matches!(k, ClipKind::Repeated { .. })),
            count(|k| *k == ClipKind::Unique),
        );
        for (t, v) in total.iter_mut().zip(n) {
            *t += v;
        }
        println!(
            "| {} | {} | {} | {} | {}/{}/{} | {} | {} | {} | {:.1} | {secs:.2} |",
            f.file_name().unwrap_or_default().to_string_lossy(),
            m.frames(),
            a.features.k,
            a.paths.len(),
            clips.0,
            clips.1,
            clips.2,
            n[0],
            n[1],
            n[2],
            100.0 * n[1] as f64 / m.frames().max(1) as f64
        );
    }
    let all: usize = total.iter().sum();
    println!(
        "| all | {all} | | | | {} | {} | {} | {:.1} | |",
        total[0],
        total[1],
        total[2],
        100.0 * total[1] as f64 / all.max(1) as f64
    );
    Ok(())
}
