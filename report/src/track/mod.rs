//! Motion Track (Hu et al., PacificVis 2010; METHODS.md §5): a 2-D picture
//! in which each clip is a curve.
//!
//! 1. Frames become vectors of joint quaternions, root translation and
//!    heading removed ([`features`]).
//! 2. A self-organising map (16×16, seeded) is trained on all frames of the
//!    reference set; each node is snapped to its nearest real frame: the key
//!    frames ([`som`]).
//! 3. Locally Linear Embedding lays the key frames out in 2-D ([`lle`]).
//! 4. Every frame of a clip is placed at the inverse-distance-weighted mean
//!    of the key frames' 2-D positions ([`idw`], eq. 2–4); consecutive frames
//!    form the clip's track, whose brightness shows joint angular speed
//!    ([`render`]).

pub mod features;
pub mod idw;
pub mod lle;
pub mod render;
pub mod som;

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use crate::plot::PlotError;
use features::QuatFrames;
use idw::Scheme;
use mocap_encoder::bvh::BvhError;
use mocap_encoder::motion::Motion;
use som::SomConfig;

/// Why a Motion Track picture could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrackError {
    /// A clip cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A folder cannot be listed (the error names it).
    #[error(transparent)]
    Folder(std::io::Error),
    /// A `.mcb` clip does not parse or decode.
    #[error("{}: {source}", path.display())]
    Clip {
        /// The clip.
        path: PathBuf,
        /// Why.
        source: mocap_decoder::Error,
    },
    /// A BVH file does not parse (the error names the file).
    #[error(transparent)]
    Bvh(#[from] BvhError),
    /// An AMC/ASF source does not read (the error names the file).
    #[error(transparent)]
    Input(#[from] mocap_encoder::input::InputError),
    /// No clips to draw.
    #[error("no clips")]
    NoClips,
    /// The clips have no rotating joint in common.
    #[error("the clips share no rotating joint")]
    NoSharedJoint,
    /// A clip lacks a joint of the reference set.
    #[error("joint {0} is missing")]
    MissingJoint(String),
    /// No frames to train the SOM on.
    #[error("no reference frames")]
    NoReferenceFrames,
    /// The reference clips' frames have different lengths.
    #[error("reference clips differ in joints")]
    ReferenceJointsDiffer,
    /// Fewer than four reference frames.
    #[error("{0} reference frames are too few")]
    TooFewReferenceFrames(usize),
    /// Too few key frames for the embedding.
    #[error("LLE needs at least {needed} points, got {got}")]
    TooFewKeyFrames {
        /// Points needed.
        needed: usize,
        /// Points given.
        got: usize,
    },
    /// A local Gram matrix of the LLE is singular.
    #[error("LLE: singular local Gram matrix")]
    SingularGram,
    /// The picture cannot be drawn or written.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// The paper's k for its mixed-type database (§4.1); its walking-only
/// database used 22.
pub const DEFAULT_K: usize = 27;

/// Key frames that place a frame by default: its 27 nearest (Shepard's
/// local form of eq. 3/4, `R` = distance to the farthest of them).
pub const DEFAULT_NEIGHBOURS: usize = 27;

/// Settings of the reference space and of the placement.
#[derive(Clone, Debug)]
pub struct TrackOptions {
    /// SOM settings.
    pub som: SomConfig,
    /// LLE neighbours.
    pub k: usize,
    /// Replace each SOM node by its nearest real frame.
    pub snap: bool,
    /// IDW scheme.
    pub scheme: Scheme,
    /// IDW power p.
    pub p: f64,
    /// Key frames that place a frame (its nearest); `None`: all.
    pub neighbours: Option<usize>,
}

impl Default for TrackOptions {
    fn default() -> Self {
        TrackOptions {
            som: SomConfig::default(),
            k: DEFAULT_K,
            snap: true,
            scheme: Scheme::Eq4,
            p: Scheme::Eq4.default_p(),
            neighbours: Some(DEFAULT_NEIGHBOURS),
        }
    }
}

/// The 2-D reference space: key frames and their LLE positions.
#[derive(Clone, Debug)]
pub struct ReferenceSpace {
    /// Quaternion-vector length.
    pub dim: usize,
    /// Key frames, row-major `keys × dim`.
    pub keys: Vec<f32>,
    /// 2-D position of each key frame.
    pub key_xy: Vec<[f64; 2]>,
    /// Frames the SOM was trained on.
    pub train_frames: usize,
    /// SOM quantisation error (mean distance of a frame to its node).
    pub quantisation_error: f64,
    /// Seconds spent in the SOM (training and snapping).
    pub som_seconds: f64,
    /// Seconds spent in the LLE.
    pub lle_seconds: f64,
}

impl ReferenceSpace {
    /// Number of key frames.
    pub fn key_count(&self) -> usize {
        self.key_xy.len()
    }

    /// Places every frame of `q` (same joints as the reference set) using
    /// its `neighbours` nearest key frames (all when `None`); `R` of eq. 3/4
    /// is then the distance to the farthest of them (Shepard's local form).
    pub fn place(
        &self,
        q: &QuatFrames,
        scheme: Scheme,
        p: f64,
        neighbours: Option<usize>,
    ) -> Vec<[f64; 2]> {
        assert_eq!(q.dim, self.dim, "clip and reference set differ in joints");
        let n = neighbours
            .unwrap_or(usize::MAX)
            .clamp(1, self.key_count().max(1));
        q.data
            .par_chunks_exact(self.dim)
            .map(|x| {
                let mut h: Vec<(f64, usize)> = self
                    .keys
                    .chunks_exact(self.dim)
                    .map(|k| f64::from(som::dist2(k, x)).sqrt())
                    .zip(0..)
                    .collect();
                if n < h.len() {
                    h.select_nth_unstable_by(n - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    h.truncate(n);
                }
                let d: Vec<f64> = h.iter().map(|x| x.0).collect();
                let xy: Vec<[f64; 2]> = h.iter().map(|x| self.key_xy[x.1]).collect();
                idw::place(&d, &xy, scheme, p)
            })
            .collect()
    }
}

/// Builds the reference space from the frames of `train`.
pub fn build_reference(
    train: &[&QuatFrames],
    opts: &TrackOptions,
) -> Result<ReferenceSpace, TrackError> {
    let dim = train
        .first()
        .map(|q| q.dim)
        .ok_or(TrackError::NoReferenceFrames)?;
    let mut data = Vec::new();
    for q in train {
        if q.dim != dim {
            return Err(TrackError::ReferenceJointsDiffer);
        }
        data.extend_from_slice(&q.data);
    }
    let frames = data.len() / dim.max(1);
    if frames < 4 {
        return Err(TrackError::TooFewReferenceFrames(frames));
    }
    let t = Instant::now();
    let map = som::train(&data, dim, &opts.som);
    let quantisation_error = map.quantisation_error(&data);
    let keys: Vec<f32> = if opts.snap {
        let mut idx = map.snap(&data);
        // Keep the first node of each real frame: LLE needs distinct points.
        let mut seen = std::collections::HashSet::new();
        idx.retain(|i| seen.insert(*i));
        idx.iter()
            .flat_map(|&i| data[i * dim..(i + 1) * dim].iter().copied())
            .collect()
    } else {
        map.nodes.clone()
    };
    let som_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let keys64: Vec<f64> = keys.iter().map(|&v| f64::from(v)).collect();
    let flat = lle::embed(&keys64, dim, opts.k, 2)?;
    let key_xy = flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    Ok(ReferenceSpace {
        dim,
        keys,
        key_xy,
        train_frames: frames,
        quantisation_error,
        som_seconds,
        lle_seconds: t.elapsed().as_secs_f64(),
    })
}

/// One clip's track.
#[derive(Clone, Debug)]
pub struct Track {
    /// Legend name.
    pub name: String,
    /// 2-D position per frame.
    pub xy: Vec<[f64; 2]>,
    /// Joint angular speed per frame, degrees per second.
    pub speed: Vec<f64>,
}

/// Separation of two tracks.
#[derive(Clone, Debug)]
pub struct PairStats {
    /// Index of the first track.
    pub a: usize,
    /// Index of the second track.
    pub b: usize,
    /// Mean distance between a frame of `a` and a frame of `b`.
    pub between: f64,
    /// Mean over both tracks' frames of the distance to the other track's
    /// nearest frame.
    pub nearest: f64,
}

/// Mean distance between two frames of the same track (its spread).
pub fn spread(t: &Track) -> f64 {
    mean_cross(&t.xy, &t.xy, true)
}

fn d2(p: [f64; 2], q: [f64; 2]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
}

fn mean_cross(a: &[[f64; 2]], b: &[[f64; 2]], same: bool) -> f64 {
    let sum: f64 = a
        .par_iter()
        .map(|&p| b.iter().map(|&q| d2(p, q)).sum::<f64>())
        .sum();
    let pairs = if same {
        a.len() * a.len().saturating_sub(1)
    } else {
        a.len() * b.len()
    };
    sum / pairs.max(1) as f64
}

fn mean_nearest(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let sum: f64 = a
        .par_iter()
        .map(|&p| b.iter().map(|&q| d2(p, q)).fold(f64::INFINITY, f64::min))
        .sum();
    sum / a.len().max(1) as f64
}

/// Statistics of every pair of tracks.
pub fn pair_stats(tracks: &[Track]) -> Vec<PairStats> {
    let mut out = Vec::new();
    for a in 0..tracks.len() {
        for b in a + 1..tracks.len() {
            let (x, y) = (&tracks[a].xy, &tracks[b].xy);
            out.push(PairStats {
                a,
                b,
                between: mean_cross(x, y, false),
                nearest: 0.5 * (mean_nearest(x, y) + mean_nearest(y, x)),
            });
        }
    }
    out
}

/// The separation table as Markdown: per clip its spread, per pair the mean
/// distance between tracks, its ratio to the mean of the two spreads, and the
/// mean distance to the nearest frame of the other track.
pub fn separation_markdown(tracks: &[Track]) -> String {
    let spreads: Vec<f64> = tracks.iter().map(spread).collect();
    let mut s = String::from("| clip | frames | spread (mean within-clip distance) | mean speed °/s |\n|---|---|---|---|\n");
    for (t, sp) in tracks.iter().zip(&spreads) {
        let v = t.speed.iter().sum::<f64>() / t.speed.len().max(1) as f64;
        s += &format!("| {} | {} | {sp:.3} | {v:.0} |\n", t.name, t.xy.len());
    }
    s += "\n| pair | mean distance between tracks | mean of the two spreads | ratio | mean nearest-frame distance |\n|---|---|---|---|---|\n";
    for p in pair_stats(tracks) {
        let within = 0.5 * (spreads[p.a] + spreads[p.b]);
        s += &format!(
            "| {} – {} | {:.3} | {within:.3} | {:.2} | {:.3} |\n",
            tracks[p.a].name,
            tracks[p.b].name,
            p.between,
            p.between / within.max(1e-12),
            p.nearest
        );
    }
    s
}

/// Reads a BVH file or an AMC (with the `.asf` beside it), or decodes a
/// `.mcb` clip with the `no_std` decoder.
pub fn load(path: &Path) -> Result<Motion, TrackError> {
    let is_mcb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcb"));
    if !is_mcb {
        return Ok(mocap_encoder::input::read_motion(path, None)?.motion);
    }
    let bytes = std::fs::read(path).map_err(|source| TrackError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let clip_error = |source| TrackError::Clip {
        path: path.to_path_buf(),
        source,
    };
    let clip = mocap_decoder::Clip::parse(&bytes).map_err(clip_error)?;
    mocap_encoder::clipfile::to_motion(&clip).map_err(clip_error)
}

/// Legend name of a file: its stem, with "(decoded)" for a `.mcb`.
pub fn clip_name(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcb"))
    {
        format!("{stem} (decoded)")
    } else {
        stem
    }
}

/// What `mocap track` draws: clips (BVH files, folders of them, `.mcb`
/// clips drawn decoded), the optional reference set, the settings and the
/// picture.
#[derive(Clone, Debug)]
pub struct TrackJob {
    /// Clips to draw.
    pub clips: Vec<PathBuf>,
    /// Train the SOM on these BVH files or folders instead of the clips.
    pub reference: Vec<PathBuf>,
    /// Reference space and placement settings.
    pub opts: TrackOptions,
    /// Output picture: `.svg` or `.png`.
    pub output: PathBuf,
    /// Picture title (default: the settings).
    pub title: Option<String>,
    /// Fit the view to the tracks rather than to all key frames.
    pub zoom: bool,
}

/// What [`draw`] made and measured.
#[derive(Clone, Debug)]
pub struct TrackReport {
    /// The reference space.
    pub space: ReferenceSpace,
    /// One track per clip.
    pub tracks: Vec<Track>,
    /// Joints compared.
    pub joints: usize,
    /// Clips the SOM was trained on.
    pub train_clips: usize,
    /// Seconds reading the clips and computing their features.
    pub load_seconds: f64,
    /// Seconds placing the frames.
    pub place_seconds: f64,
    /// Seconds drawing the picture.
    pub render_seconds: f64,
    /// Threads the SOM, the LLE and the placement ran on.
    pub threads: usize,
}

fn expand(paths: &[PathBuf]) -> Result<Vec<PathBuf>, TrackError> {
    mocap_encoder::input::expand(paths).map_err(TrackError::Folder)
}

/// `mocap track`: reads the clips, builds the reference space, places every
/// clip's frames and writes the picture.
pub fn draw(job: &TrackJob) -> Result<TrackReport, TrackError> {
    let t0 = Instant::now();
    let files = expand(&job.clips)?;
    let motions: Vec<Motion> = files
        .par_iter()
        .map(|f| load(f))
        .collect::<Result<_, _>>()?;
    let ref_files = expand(&job.reference)?;
    let ref_motions: Vec<Motion> = ref_files
        .par_iter()
        .map(|f| load(f))
        .collect::<Result<_, _>>()?;
    // Joints: the first clip's rotating joints present in every clip.
    let all: Vec<&Motion> = motions.iter().chain(&ref_motions).collect();
    let first = all.first().ok_or(TrackError::NoClips)?;
    let joints: Vec<String> = features::rotating_joints(first)
        .into_iter()
        .filter(|n| {
            all.iter()
                .all(|m| m.skeleton.joints.iter().any(|j| &j.name == n))
        })
        .collect();
    if joints.is_empty() {
        return Err(TrackError::NoSharedJoint);
    }
    let q: Vec<QuatFrames> = motions
        .par_iter()
        .map(|m| features::quat_frames(m, &joints))
        .collect::<Result<_, _>>()?;
    let qr: Vec<QuatFrames> = ref_motions
        .par_iter()
        .map(|m| features::quat_frames(m, &joints))
        .collect::<Result<_, _>>()?;
    let load_seconds = t0.elapsed().as_secs_f64();
    let opts = &job.opts;
    let train: Vec<&QuatFrames> = if qr.is_empty() {
        q.iter().collect()
    } else {
        qr.iter().collect()
    };
    let space = build_reference(&train, opts)?;
    let t = Instant::now();
    let tracks: Vec<Track> = files
        .iter()
        .zip(&q)
        .map(|(f, qf)| Track {
            name: clip_name(f),
            xy: space.place(qf, opts.scheme, opts.p, opts.neighbours),
            speed: qf.speed.clone(),
        })
        .collect();
    let place_seconds = t.elapsed().as_secs_f64();
    let title = job.title.clone().unwrap_or_else(|| {
        format!(
            "Motion Track: SOM {0}×{0}, {1} key frames, LLE k={2}, IDW {3} p={4}, {5} nearest",
            opts.som.width,
            space.key_count(),
            opts.k,
            opts.scheme,
            opts.p,
            opts.neighbours.map_or("all".to_string(), |n| n.to_string())
        )
    });
    let t = Instant::now();
    render::render_view(&job.output, &title, &tracks, &space.key_xy, job.zoom)?;
    let render_seconds = t.elapsed().as_secs_f64();
    Ok(TrackReport {
        space,
        tracks,
        joints: joints.len(),
        train_clips: train.len(),
        load_seconds,
        place_seconds,
        render_seconds,
        threads: rayon::current_num_threads(),
    })
}
