//! The `pattern` codec's claim (Gu, Peng & Deng 2008, Fig. 10/11; issue 13):
//! the ratio grows with the size of the database. Shows of the first 1, 2,
//! 4, 8, 16 and all clips of each corpus are built with every codec at the
//! same bounds (`mocap show build`'s pipeline: each clip proven by decoding;
//! the `pattern` clips of a show share one database), and the paper's
//! repeated single-type experiment: one walk as a show of 1, 10 and 50
//! copies, and as one take concatenated 10 and 50 times. Prints the tables
//! and draws the ratio against the show size.
//!
//! ```sh
//! cargo run --release -p mocap-report --example pattern_db -- target/pattern_db.png \
//!     cmu=../shared/data/cmu,../shared/data/cmu-long iclone=../shared/data/iclone-cmu \
//!     --walk ../shared/data/cmu/35_01.bvh
//! ```

use std::path::{Path, PathBuf};
use std::time::Instant;

use mocap_encoder::input;
use mocap_encoder::motion::Motion;
use mocap_encoder::show::{self, file::ShowSpec};
use mocap_report::plot::database::{database_plot, Series};

const CODECS: [&str; 4] = ["index", "pca-spline", "predictive", "pattern"];
const BOUNDS: [&str; 2] = ["arms:5mm", "50mm+arms:10mm"];

/// Builds a show of `files` with `codec` at `bound` in `dir`; its bytes.
fn show_bytes(dir: &Path, files: &[PathBuf], codec: &str, bound: &str) -> Result<usize, String> {
    let mut toml = format!("[show]\nname = \"db\"\nmax_error = \"{bound}\"\ncodec = \"{codec}\"\n");
    for (i, f) in files.iter().enumerate() {
        toml += &format!("[[clip]]\nname = \"c{i}\"\nfile = \"{}\"\n", f.display());
    }
    let spec = ShowSpec::parse(&toml, "db.toml", dir).map_err(|e| e.to_string())?;
    let built = show::build(&spec).map_err(|e| e.to_string())?;
    Ok(built.bytes.len())
}

/// Bytes of `files` as 32-bit floats.
fn raw_bytes(files: &[PathBuf]) -> Result<usize, String> {
    let mut n = 0;
    for f in files {
        let m = input::read_motion(f, None)
            .map_err(|e| e.to_string())?
            .motion;
        n += m.frames() * m.channels() * 4;
    }
    Ok(n)
}

/// The motion files of `folders` (comma-separated), by name; of those
/// whose channels differ (two rigs in a folder), the largest set with the
/// same channels (a show has one skeleton).
fn motion_files(folders: &str) -> Result<Vec<PathBuf>, String> {
    let mut files: Vec<PathBuf> = folders
        .split(',')
        .flat_map(|d| std::fs::read_dir(d).into_iter().flatten().flatten())
        .filter_map(|e| e.path().canonicalize().ok())
        .filter(|p| p.extension().is_some_and(|x| x == "bvh"))
        .collect();
    files.sort_by_key(|p| p.file_name().map(|n| n.to_os_string()));
    let mut rigs: Vec<(Vec<String>, Vec<PathBuf>)> = Vec::new();
    for f in files {
        let m = input::read_motion(&f, None)
            .map_err(|e| e.to_string())?
            .motion;
        let names = m.skeleton.channel_names();
        match rigs.iter_mut().find(|r| r.0 == names) {
            Some(r) => r.1.push(f),
            None => rigs.push((names, vec![f])),
        }
    }
    rigs.sort_by_key(|r| std::cmp::Reverse(r.1.len()));
    Ok(rigs.into_iter().next().map(|r| r.1).unwrap_or_default())
}

/// `m` played `k` times end to end.
fn repeated(m: &Motion, k: usize) -> Motion {
    Motion {
        skeleton: m.skeleton.clone(),
        frame_time: m.frame_time,
        values: m.values.repeat(k),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((out, rest)) = args.split_first() else {
        return Err("usage: pattern_db OUT.png NAME=DIR[,DIR]... [--walk WALK.bvh]".into());
    };
    let tmp = std::env::temp_dir().join(format!("mocap-pattern-db-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    let mut series = Vec::new();
    let mut walk = None;
    let mut it = rest.iter();
    while let Some(a) = it.next() {
        if a == "--walk" {
            walk = it.next().map(PathBuf::from);
            continue;
        }
        let (name, folders) = a.split_once('=').ok_or("corpus as NAME=DIR[,DIR]")?;
        let files = motion_files(folders)?;
        let mut sizes: Vec<usize> = [1, 2, 4, 8, 16]
            .into_iter()
            .filter(|&n| n < files.len())
            .collect();
        sizes.push(files.len());
        println!("\n{name}: {} files of one skeleton", files.len());
        println!(
            "| bound | clips | f32 values | {} |",
            CODECS.map(|c| format!("{c} B (ratio)")).join(" | ")
        );
        println!("|---|---|---|{}", "---|".repeat(CODECS.len()));
        for bound in BOUNDS {
            let mut per_codec: Vec<Vec<(usize, f64)>> = vec![Vec::new(); CODECS.len()];
            for &n in &sizes {
                let chosen = &files[..n];
                let raw = raw_bytes(chosen)?;
                let frames = raw / 4;
                let mut cells = Vec::new();
                for (k, codec) in CODECS.iter().enumerate() {
                    let t = Instant::now();
                    let bytes = show_bytes(&tmp, chosen, codec, bound)?;
                    let ratio = raw as f64 / bytes as f64;
                    per_codec[k].push((n, ratio));
                    cells.push(format!(
                        "{bytes} ({ratio:.1}:1, {:.0} s)",
                        t.elapsed().as_secs_f64()
                    ));
                }
                println!("| {bound} | {n} | {frames} | {} |", cells.join(" | "));
            }
            for (k, points) in per_codec.into_iter().enumerate() {
                series.push(Series {
                    panel: format!("{name}, {bound}"),
                    codec: CODECS[k].to_string(),
                    points,
                });
            }
        }
    }
    if let Some(w) = walk {
        let w = w.canonicalize()?;
        let m = input::read_motion(&w, None)?.motion;
        println!("\nrepeated walk {}: {} frames", w.display(), m.frames());
        println!(
            "| bound | form | copies | {} |",
            CODECS.map(|c| format!("{c} ratio")).join(" | ")
        );
        println!("|---|---|---|{}", "---|".repeat(CODECS.len()));
        for bound in BOUNDS {
            let mut per_codec: Vec<Vec<(usize, f64)>> = vec![Vec::new(); CODECS.len()];
            for k in [1usize, 10, 50] {
                let copies = vec![w.clone(); k];
                let raw = m.frames() * m.channels() * 4 * k;
                let mut cells = Vec::new();
                for (c, codec) in CODECS.iter().enumerate() {
                    let bytes = show_bytes(&tmp, &copies, codec, bound)?;
                    let ratio = raw as f64 / bytes as f64;
                    per_codec[c].push((k, ratio));
                    cells.push(format!("{ratio:.1}"));
                }
                println!("| {bound} | show of copies | {k} | {} |", cells.join(" | "));
                if k == 1 {
                    continue;
                }
                let long = tmp.join(format!("walk_x{k}.bvh"));
                mocap_encoder::bvh::write_file(&repeated(&m, k), &long)?;
                let mut cells = Vec::new();
                for codec in CODECS {
                    let bytes = show_bytes(&tmp, std::slice::from_ref(&long), codec, bound)?;
                    cells.push(format!("{:.1}", raw as f64 / bytes as f64));
                }
                println!("| {bound} | one take | {k} | {} |", cells.join(" | "));
            }
            for (c, points) in per_codec.into_iter().enumerate() {
                series.push(Series {
                    panel: format!("one walk, copies in a show, {bound}"),
                    codec: CODECS[c].to_string(),
                    points,
                });
            }
        }
    }
    database_plot(Path::new(out), &series)?;
    println!("\nwrote {out}");
    let _ = std::fs::remove_dir_all(&tmp);
    Ok(())
}
