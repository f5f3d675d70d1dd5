//! `mocap track`: the Motion Track picture (Hu et al. 2010) of clips, with
//! `--stats` the timings and the separation table.

use std::path::PathBuf;

use mocap_report::track::idw::Scheme;
use mocap_report::track::som::SomConfig;
use mocap_report::track::{self, TrackJob, TrackOptions, DEFAULT_K, DEFAULT_NEIGHBOURS};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Clips to draw: BVH or AMC files (an AMC with the `.asf` beside it,
    /// 16_15.amc → 16.asf), folders of them, and `.mcb` clips (drawn
    /// decoded, e.g. beside their source).
    #[arg(required = true)]
    clips: Vec<PathBuf>,
    /// Output picture: `.svg` or `.png`.
    #[arg(short, long)]
    output: PathBuf,
    /// Train the SOM on these BVH files or folders instead of the clips.
    #[arg(long)]
    reference: Vec<PathBuf>,
    /// SOM grid side (nodes = side²).
    #[arg(long, default_value_t = 16)]
    som: usize,
    /// SOM batch epochs.
    #[arg(long, default_value_t = 30)]
    epochs: usize,
    /// Seed of the SOM initialisation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// LLE neighbours (the paper uses 22–27).
    #[arg(long, default_value_t = DEFAULT_K)]
    k: usize,
    /// Inverse-distance weighting: eq2, eq3 or eq4 (Gaussian).
    #[arg(long, default_value = "eq4")]
    weights: Scheme,
    /// Power p of the weighting (default: 8 for eq2, 2 for eq3/eq4).
    #[arg(long)]
    p: Option<f64>,
    /// Place each frame by its N nearest key frames (0 = all, as the paper
    /// writes it; over all key frames eq. 4 pulls every frame to the
    /// key frames' centroid, see docs/TRACK.md).
    #[arg(long, default_value_t = DEFAULT_NEIGHBOURS)]
    neighbours: usize,
    /// Keep the SOM nodes as key frames instead of snapping them to real frames.
    #[arg(long)]
    no_snap: bool,
    /// Print timings, frame counts and the separation table.
    #[arg(long)]
    stats: bool,
    /// Fit the view to the tracks rather than to all key frames.
    #[arg(long)]
    zoom: bool,
    /// Picture title.
    #[arg(long)]
    title: Option<String>,
}

pub fn run(a: Args) -> super::Result {
    let job = TrackJob {
        clips: a.clips,
        reference: a.reference,
        opts: TrackOptions {
            som: SomConfig {
                width: a.som,
                height: a.som,
                epochs: a.epochs,
                seed: a.seed,
                ..SomConfig::default()
            },
            k: a.k,
            snap: !a.no_snap,
            scheme: a.weights,
            p: a.p.unwrap_or(a.weights.default_p()),
            neighbours: if a.neighbours == 0 {
                None
            } else {
                Some(a.neighbours)
            },
        },
        output: a.output,
        title: a.title,
        zoom: a.zoom,
    };
    let r = track::draw(&job)?;
    eprintln!("wrote {}", job.output.display());
    if a.stats {
        let (space, opts) = (&r.space, &job.opts);
        println!(
            "reference: {} frames × {} values ({} joints) from {} clips; SOM {}×{} {} epochs: {:.2} s (quantisation error {:.4}); {} key frames; LLE k={}: {:.2} s; SOM+LLE {:.2} s on {} threads",
            space.train_frames,
            space.dim,
            r.joints,
            r.train_clips,
            a.som,
            a.som,
            opts.som.epochs,
            space.som_seconds,
            space.quantisation_error,
            space.key_count(),
            opts.k,
            space.lle_seconds,
            space.som_seconds + space.lle_seconds,
            r.threads
        );
        println!(
            "read+features {:.2} s, placement ({} frames, {}) {:.2} s, render {:.2} s\n",
            r.load_seconds,
            r.tracks.iter().map(|t| t.xy.len()).sum::<usize>(),
            opts.scheme,
            r.place_seconds,
            r.render_seconds
        );
        print!("{}", track::separation_markdown(&r.tracks));
    }
    Ok(())
}
