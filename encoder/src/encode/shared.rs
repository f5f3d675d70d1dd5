//! One `pattern` database for several motions: the pattern clips of a show
//! (SPEC.md §9.2, §11.2). The tolerance search is the one every coder
//! driven by tolerances uses, over all the motions at once: each try codes
//! them together and proves every one by decoding it; a try holds when the
//! bound holds for each motion, and its size is the database plus every
//! clip's segment lists.

use mocap_decoder::consts;

use super::proof::{prove, Attempt};
use super::reference::Reference;
use super::search::{search_tolerances_with, Trial};
use super::{CodecChoice, EncodeError, EncodeOptions, Encoded, Progress};
use crate::codec::pattern;
use crate::fixed::FixedChannels;
use crate::metrics::Metrics;
use crate::motion::Motion;

/// Motions coded with one database.
#[derive(Clone, Debug)]
pub struct SharedPatterns {
    /// The database: the payload of the show's shared model section.
    pub database: Vec<u8>,
    /// Per motion, its codec section reading the shared database (flag
    /// `SHARED`, §11.1).
    pub sections: Vec<Vec<u8>>,
    /// Per motion, the same clip as a single `.mcb` file (the database in
    /// its codec section) and its measured quality.
    pub clips: Vec<Encoded>,
}

/// One try: every motion's proof and the shared sections.
struct Joint {
    database: Vec<u8>,
    sections: Vec<Vec<u8>>,
    attempts: Vec<Attempt>,
    /// The worst of every motion's metrics (the bound holds for each iff
    /// it holds for these).
    worst: Metrics,
    size: usize,
}

impl Trial for Joint {
    fn size(&self) -> usize {
        self.size
    }

    fn metrics(&self) -> &Metrics {
        &self.worst
    }
}

fn worst(all: &[&Metrics]) -> Metrics {
    let mut w = all[0].clone();
    for m in &all[1..] {
        w.arms_mm = w.arms_mm.max(m.arms_mm);
        w.max_joint_err_mm = w.max_joint_err_mm.max(m.max_joint_err_mm);
        w.angle_max_deg = w.angle_max_deg.max(m.angle_max_deg);
        w.angle_rms_deg = w.angle_rms_deg.max(m.angle_rms_deg);
        w.position_max_mm = w.position_max_mm.max(m.position_max_mm);
        w.distortion_pct = w.distortion_pct.max(m.distortion_pct);
        w.foot_slide_mm_s = w.foot_slide_mm_s.max(m.foot_slide_mm_s);
        w.foot_slide_source_mm_s = w.foot_slide_source_mm_s.max(m.foot_slide_source_mm_s);
        w.foot_height_err_mm = w.foot_height_err_mm.max(m.foot_height_err_mm);
    }
    w
}

/// Codes `motions` (the same channels, the same frame rate) with the
/// `pattern` codec and one database, each within `opts.bound`, motion `k`
/// in `metres_per_unit[k]` metres per length unit.
pub fn encode_pattern_shared(
    motions: &[&Motion],
    metres_per_unit: &[f64],
    opts: &EncodeOptions,
    progress: &dyn Progress,
) -> Result<SharedPatterns, EncodeError> {
    let first = *motions.first().ok_or(EncodeError::Empty)?;
    if motions.iter().any(|m| m.frames() == 0 || m.channels() == 0) {
        return Err(EncodeError::Empty);
    }
    let refs: Vec<Reference> = motions
        .iter()
        .zip(metres_per_unit)
        .map(|(m, &u)| Reference::new(m, u))
        .collect();
    let nodes = pattern::nodes_with(first, &opts.pattern.nodes)?;
    let fps = 1.0 / first.frame_time;
    let accept = pattern::accept_for(&opts.bound);
    let run = |tol: &[i64]| -> Result<Joint, EncodeError> {
        let takes: Vec<&[Vec<i32>]> = refs.iter().map(|r| r.fixed.values.as_slice()).collect();
        let pattern::Shared {
            database,
            sections,
            decoded,
        } = pattern::encode_shared(&takes, tol, accept, &nodes, fps, &opts.pattern)?;
        let mut attempts = Vec::new();
        for (k, (((m, r), segments), values)) in motions
            .iter()
            .zip(&refs)
            .zip(&sections)
            .zip(decoded)
            .enumerate()
        {
            let expected = FixedChannels {
                kinds: r.fixed.kinds.clone(),
                values,
            };
            let one = EncodeOptions {
                codec: CodecChoice::Pattern,
                metres_per_unit: metres_per_unit[k],
                ..opts.clone()
            };
            let section = pattern::with_database(&database, segments);
            let mut a = prove(
                m,
                r,
                (consts::SECTION_CODEC_PATTERN, section),
                Some(&expected),
                &one,
            )?;
            a.decoded = Vec::new();
            attempts.push(a);
        }
        let size = database.len() + sections.iter().map(Vec::len).sum::<usize>();
        let worst = worst(&attempts.iter().map(|a| &a.metrics).collect::<Vec<_>>());
        Ok(Joint {
            database,
            sections,
            attempts,
            worst,
            size,
        })
    };
    let (best, attempts) = search_tolerances_with(&refs[0], &opts.bound, run, |n, rounds| {
        progress.round(CodecChoice::Pattern, n, rounds)
    })?;
    Ok(SharedPatterns {
        database: best.database,
        sections: best.sections,
        clips: best
            .attempts
            .into_iter()
            .map(|a| Encoded {
                bytes: a.bytes,
                metrics: a.metrics,
                codec: CodecChoice::Pattern,
                key_interval: 0,
                attempts,
            })
            .collect(),
    })
}
