//! Reads C3D files with the encoder's reader and prints what it found and
//! the reader's throughput (the file already in memory):
//! `cargo run --release -p mocap-encoder --example c3d_read -- ../shared/data/c3d/*.c3d`

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for path in std::env::args().skip(1) {
        let bytes = std::fs::read(&path)?;
        let c = mocap_encoder::c3d::parse(&bytes, &path)?;
        println!("{path}: {}", c.summary());
        println!("  markers: {}", c.marker_names().join(" "));
        let runs = 200;
        let t = Instant::now();
        for _ in 0..runs {
            std::hint::black_box(mocap_encoder::c3d::parse(
                std::hint::black_box(&bytes),
                &path,
            )?);
        }
        let s = t.elapsed().as_secs_f64();
        println!(
            "  read {} bytes × {runs} in {:.3} s: {:.0} MB/s",
            bytes.len(),
            s,
            (bytes.len() * runs) as f64 / s / 1e6
        );
    }
    Ok(())
}
