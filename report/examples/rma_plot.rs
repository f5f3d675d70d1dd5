//! The repeated motion analysis of one take as a picture: the
//! self-distance plot with its similar-posture paths and the clips, without
//! encoding (`mocap encode --codec rma --plot` draws it with what the
//! encoder kept).
//!
//! ```sh
//! cargo run --release -p mocap-report --example rma_plot -- ../shared/data/cmu-long/01_14.bvh target/rma_01_14.png
//! ```

use std::path::PathBuf;

use mocap_encoder::codec::rma::{self, Params};
use mocap_encoder::input;
use mocap_report::plot::rma::self_distance_plot;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let [take, out] = args.as_slice() else {
        return Err("usage: rma_plot TAKE OUT.png".into());
    };
    let m = input::read_motion(take, None)?.motion;
    let a = rma::analyse(&m, &Params::default());
    let name = take.file_name().unwrap_or_default().to_string_lossy();
    self_distance_plot(out, &a, None, &name)?;
    let [p, r, u] = a.frames_by_kind();
    println!(
        "{}: primary {p}, repeated {r}, unique {u} frames; wrote {}",
        name,
        out.display()
    );
    Ok(())
}
