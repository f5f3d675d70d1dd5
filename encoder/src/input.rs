//! The one entry point of every command that reads motion: a BVH file, or
//! an ASF + AMC pair ([`crate::asf`]), by extension, into the same
//! [`Motion`] model, with the length unit the file declares when it does.
//!
//! * `.bvh`: [`crate::bvh::read_file`]; no declared unit.
//! * `.amc`: with the skeleton given, else the `.asf` beside it named as
//!   the AMC (`walk.amc` → `walk.asf`) or, CMU's naming, as the AMC's name
//!   up to its first `_` (`16_15.amc` → `16.asf`); the unit is the ASF's
//!   (`:units length 0.45`: [`LengthUnit::Cmu`]); the frame time
//!   [`InputOptions::frame_time`], default 1/120 s (CMU's rate: AMC files
//!   state none).
//! * `.asf` with an `.amc` as the skeleton argument: the same pair, given
//!   the other way round.

use std::path::{Path, PathBuf};

use crate::asf::{self, Amc, AmcOptions, Asf, AsfError, BakeReport};
use crate::bvh::{self, BvhError};
use crate::motion::Motion;
use crate::units::LengthUnit;

/// How motion is read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InputOptions {
    /// The ASF of an `.amc` input (default: found beside it).
    pub skeleton: Option<PathBuf>,
    /// Seconds per frame of an `.amc` input (default
    /// [`asf::DEFAULT_FRAME_TIME`], 120 Hz); BVH files keep their own.
    pub frame_time: Option<f64>,
}

/// What was read from an ASF + AMC pair besides the motion.
#[derive(Clone, Debug)]
pub struct AsfSource {
    /// The skeleton file used.
    pub skeleton_path: PathBuf,
    /// The skeleton as read (limits included).
    pub asf: Asf,
    /// The frames as read.
    pub amc: Amc,
    /// What the conversion did.
    pub report: BakeReport,
}

/// Motion read from a file, with what the file says about it.
#[derive(Clone, Debug)]
pub struct Input {
    /// The motion.
    pub motion: Motion,
    /// The length unit the file declares (ASF `:units length`); `None` for
    /// BVH, which declares none.
    pub unit: Option<LengthUnit>,
    /// For an ASF + AMC input: the skeleton, frames and conversion.
    pub asf: Option<AsfSource>,
}

impl Input {
    /// Frames with a dof value outside its ASF `limits` (0 for BVH).
    pub fn frames_outside_limits(&self) -> usize {
        self.asf
            .as_ref()
            .map_or(0, |a| a.amc.frames_outside_limits(&a.asf))
    }

    /// The declared unit, else [`crate::units::detect`]'s guess.
    pub fn unit_or_detect(&self) -> LengthUnit {
        self.unit
            .unwrap_or_else(|| crate::units::detect(&self.motion))
    }
}

/// Error of [`read_motion`].
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// A BVH file did not read.
    #[error(transparent)]
    Bvh(#[from] BvhError),
    /// An ASF or AMC file did not read.
    #[error(transparent)]
    Asf(#[from] AsfError),
    /// An `.amc` without a skeleton given and none beside it.
    #[error("{}: no skeleton: {tried} not found (give it with --skeleton x.asf)", amc.display())]
    NoSkeleton {
        /// The AMC file.
        amc: PathBuf,
        /// The `.asf` files looked for.
        tried: String,
    },
    /// An `.asf` alone: it holds no motion.
    #[error("{}: an ASF file holds a skeleton, not motion: give its .amc (e.g. mocap encode 16_15.amc --skeleton 16.asf)", path.display())]
    SkeletonOnly {
        /// The ASF file.
        path: PathBuf,
    },
    /// A skeleton given for a BVH file.
    #[error("{}: a BVH file has its own skeleton (--skeleton is for .amc files)", path.display())]
    SkeletonForBvh {
        /// The BVH file.
        path: PathBuf,
    },
    /// Not a motion file.
    #[error("{}: not a motion file (expected .bvh, or .amc with its .asf)", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
    },
}

fn has_ext(p: &Path, ext: &str) -> bool {
    p.extension().is_some_and(|x| x.eq_ignore_ascii_case(ext))
}

/// Whether `path` is read by [`read_motion`] as motion (`.bvh`, `.amc`).
pub fn is_motion_file(path: &Path) -> bool {
    has_ext(path, "bvh") || has_ext(path, "amc")
}

/// Reads motion with the default options and, for an `.amc`, the skeleton
/// `skeleton` (else the one beside it).
pub fn read_motion(path: &Path, skeleton: Option<&Path>) -> Result<Input, InputError> {
    read_motion_with(
        path,
        &InputOptions {
            skeleton: skeleton.map(Path::to_path_buf),
            frame_time: None,
        },
    )
}

/// The `.asf` beside `amc`: `<stem>.asf`, else (CMU naming) the stem up to
/// its first `_` + `.asf`.
pub fn find_skeleton(amc: &Path) -> Result<PathBuf, InputError> {
    let dir = amc.parent().unwrap_or(Path::new(""));
    let stem = amc
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut names = vec![stem.clone()];
    if let Some((subject, _)) = stem.split_once('_') {
        names.push(subject.to_string());
    }
    let mut tried = Vec::new();
    for name in names {
        for ext in ["asf", "ASF"] {
            let p = dir.join(format!("{name}.{ext}"));
            if p.is_file() {
                return Ok(p);
            }
        }
        tried.push(dir.join(format!("{name}.asf")).display().to_string());
    }
    Err(InputError::NoSkeleton {
        amc: amc.to_path_buf(),
        tried: tried.join(" or "),
    })
}

/// Reads motion: see the module documentation.
pub fn read_motion_with(path: &Path, opts: &InputOptions) -> Result<Input, InputError> {
    if has_ext(path, "bvh") {
        if opts.skeleton.is_some() {
            return Err(InputError::SkeletonForBvh {
                path: path.to_path_buf(),
            });
        }
        return Ok(Input {
            motion: bvh::read_file(path)?,
            unit: None,
            asf: None,
        });
    }
    let (amc, skeleton) = if has_ext(path, "amc") {
        let s = match &opts.skeleton {
            Some(s) => s.clone(),
            None => find_skeleton(path)?,
        };
        (path.to_path_buf(), s)
    } else if has_ext(path, "asf") {
        match &opts.skeleton {
            Some(m) if has_ext(m, "amc") => (m.clone(), path.to_path_buf()),
            _ => {
                return Err(InputError::SkeletonOnly {
                    path: path.to_path_buf(),
                })
            }
        }
    } else {
        return Err(InputError::Unsupported {
            path: path.to_path_buf(),
        });
    };
    let amc_opts = AmcOptions {
        frame_time: opts.frame_time.unwrap_or(asf::DEFAULT_FRAME_TIME),
    };
    let read = asf::read_files(&skeleton, &amc, &amc_opts)?;
    Ok(Input {
        unit: read.declared_unit(),
        motion: read.motion,
        asf: Some(AsfSource {
            skeleton_path: skeleton,
            asf: read.asf,
            amc: read.amc,
            report: read.report,
        }),
    })
}

/// Expands folders into their motion files (`.bvh` and `.amc`, sorted);
/// files pass through.
pub fn expand(paths: &[PathBuf]) -> std::io::Result<Vec<PathBuf>> {
    expand_where(paths, is_motion_file)
}

/// Expands folders into their files that `keep` accepts (sorted); files
/// pass through.
pub fn expand_where(
    paths: &[PathBuf],
    keep: impl Fn(&Path) -> bool,
) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", p.display())))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| keep(f))
                .collect();
            files.sort();
            out.extend(files);
        } else {
            out.push(p.clone());
        }
    }
    Ok(out)
}
