//! The bytes of a show's own sections: the show table (SPEC.md §9.2) and
//! the cue section (§9.5).

use mocap_decoder::Loop;

use super::file::{ActionSpec, ShowSpec};
use crate::container::varint;

/// One row of the show table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TableRow {
    /// Clip name.
    pub name: String,
    /// Position of its codec section.
    pub codec_section: u32,
    /// Frames.
    pub frames: u32,
    /// Its loop.
    pub looping: Option<Loop>,
    /// Positions of the shared model sections its codec reads (§9.2).
    pub models: Vec<u32>,
}

/// The show table section (§9.2).
pub fn show_table(rows: &[TableRow]) -> Vec<u8> {
    let mut out = Vec::new();
    varint(&mut out, rows.len() as u32);
    for r in rows {
        varint(&mut out, r.name.len() as u32);
        out.extend_from_slice(r.name.as_bytes());
        varint(&mut out, r.codec_section);
        varint(&mut out, r.frames);
        match r.looping {
            None => out.push(0),
            Some(l) => {
                out.push(1);
                varint(&mut out, l.start);
                varint(&mut out, l.end);
                varint(&mut out, l.seam);
            }
        }
        varint(&mut out, r.models.len() as u32);
        for &m in &r.models {
            varint(&mut out, m);
        }
    }
    out
}

/// The cue section (§9.5) of `spec`, clips and lists by their number.
pub fn cue_section(spec: &ShowSpec) -> Vec<u8> {
    let clip = |n: &str| spec.clips.iter().position(|c| c.name == n).unwrap_or(0) as u32;
    let list = |n: &str| spec.cues.iter().position(|l| l.name == n).unwrap_or(0) as u32;
    let mut out = Vec::new();
    varint(&mut out, spec.fade_ms);
    varint(&mut out, spec.seed.max(1));
    varint(&mut out, spec.cues.len() as u32);
    for l in &spec.cues {
        varint(&mut out, l.name.len() as u32);
        out.extend_from_slice(l.name.as_bytes());
        varint(&mut out, l.cues.len() as u32);
        for c in &l.cues {
            varint(&mut out, c.at_ms);
            match &c.action {
                ActionSpec::Play(n) => {
                    out.push(0);
                    varint(&mut out, clip(n));
                }
                ActionSpec::Fade(n, ms) => {
                    out.push(1);
                    varint(&mut out, clip(n));
                    varint(&mut out, *ms);
                }
                ActionSpec::Queue(n) => {
                    out.push(2);
                    varint(&mut out, clip(n));
                }
                ActionSpec::Stop => out.push(3),
                ActionSpec::Hold => out.push(4),
                ActionSpec::Resume => out.push(5),
                ActionSpec::Loop(on) => out.extend([6, u8::from(*on)]),
                ActionSpec::Gpio(pin, level) => out.extend([7, *pin, u8::from(*level)]),
                ActionSpec::Serial(bytes) => {
                    out.push(8);
                    varint(&mut out, bytes.len() as u32);
                    out.extend_from_slice(bytes);
                }
            }
        }
    }
    varint(&mut out, spec.idle.len() as u32);
    for n in &spec.idle {
        varint(&mut out, clip(n));
    }
    varint(&mut out, spec.triggers.len() as u32);
    for t in &spec.triggers {
        out.push(t.input);
        out.push(if t.lists { 0 } else { 1 });
        varint(&mut out, t.cooldown_ms);
        varint(&mut out, t.targets.len() as u32);
        for n in &t.targets {
            varint(&mut out, if t.lists { list(n) } else { clip(n) });
        }
    }
    out
}
