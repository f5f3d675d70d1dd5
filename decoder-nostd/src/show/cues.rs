//! The cue section of a show (SPEC.md §9.5): the default transition, cue
//! lists (timed actions), idle clips and triggers, read in place.

use crate::error::Error;
use crate::reader::Reader;

/// Most cue lists, triggers, idle clips of a show.
pub const MAX_LISTS: usize = 255;
/// Most triggers of a show (inputs `0..32`).
pub const MAX_TRIGGERS: usize = 32;
/// Most targets of one trigger.
pub const MAX_TARGETS: usize = 16;
/// Longest serial output of an event, bytes.
pub const MAX_SERIAL: usize = 32;

/// What a cue does (SPEC.md §9.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action<'a> {
    /// `play(clip)`: the clip, after the default transition.
    Play(u16),
    /// `crossfade_to(clip, ms)`.
    Fade {
        /// The clip.
        clip: u16,
        /// Transition length, ms.
        ms: u32,
    },
    /// `queue(clip)`: the clip when the current one ends.
    Queue(u16),
    /// `stop()`.
    Stop,
    /// `hold()`: time stops, the pose stays.
    Hold,
    /// `resume()` after a hold.
    Resume,
    /// `set_loop(on)` on the current clip.
    Loop(bool),
    /// An output event: set GPIO `pin` to `level`.
    Gpio {
        /// Pin number (the board maps it).
        pin: u8,
        /// `true` = high.
        level: bool,
    },
    /// An output event: these bytes on the serial output (an MP3 module's
    /// command, say).
    Serial(&'a [u8]),
}

/// One timed action of a cue list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cue<'a> {
    /// Time from the list's start, ms.
    pub at_ms: u32,
    /// What it does.
    pub action: Action<'a>,
}

/// What a trigger starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriggerKind {
    /// One of its targets is a cue list.
    List,
    /// One of its targets is a clip, played with the default transition.
    Clip,
}

/// A trigger: input `input` starts one of its targets, chosen at random,
/// unless the last start was less than `cooldown_ms` ago.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Trigger<'a> {
    /// Input number, `0..32`.
    pub input: u8,
    /// What the targets are.
    pub kind: TriggerKind,
    /// Least time between two starts, ms.
    pub cooldown_ms: u32,
    targets: &'a [u8],
    count: u8,
}

impl Trigger<'_> {
    /// Number of targets (1..=16).
    pub fn target_count(&self) -> u8 {
        self.count
    }

    /// Target `k` (a cue list or a clip number).
    pub fn target(&self, k: u8) -> Option<u16> {
        let mut r = Reader::new(self.targets);
        for _ in 0..k {
            r.varint_u32()?;
        }
        r.varint_u32().and_then(|v| u16::try_from(v).ok())
    }
}

/// A cue list: a name and its cues in time order.
#[derive(Clone, Copy, Debug)]
pub struct CueList<'a> {
    /// The list's name.
    pub name: &'a str,
    cues: &'a [u8],
    count: u16,
    clips: u16,
}

impl<'a> CueList<'a> {
    /// Number of cues.
    pub fn len(&self) -> u16 {
        self.count
    }

    /// True without cues.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The cues, in order.
    pub fn cues(&self) -> CueIter<'a> {
        CueIter {
            r: Reader::new(self.cues),
            left: self.count,
            clips: self.clips,
        }
    }

    /// Cue `k`.
    pub fn cue(&self, k: u16) -> Option<Cue<'a>> {
        self.cues().nth(usize::from(k))
    }
}

/// Iterator over the cues of a list.
#[derive(Clone, Debug)]
pub struct CueIter<'a> {
    r: Reader<'a>,
    left: u16,
    clips: u16,
}

impl<'a> Iterator for CueIter<'a> {
    type Item = Cue<'a>;

    fn next(&mut self) -> Option<Cue<'a>> {
        if self.left == 0 {
            return None;
        }
        self.left = self.left.wrapping_sub(1);
        read_cue(&mut self.r, self.clips).ok()
    }
}

/// The cue section, validated.
#[derive(Clone, Copy, Debug)]
pub struct Cues<'a> {
    /// Length of `play`'s transition and of a queued clip's, ms.
    pub default_fade_ms: u32,
    /// Seed of the random choices (never 0).
    pub seed: u32,
    lists: &'a [u8],
    list_count: u16,
    idle: &'a [u8],
    idle_count: u16,
    triggers: &'a [u8],
    trigger_count: u8,
    clips: u16,
}

impl<'a> Cues<'a> {
    /// Validates a cue section for a show of `clips` clips (SPEC.md §9.5).
    pub fn parse(bytes: &'a [u8], clips: u16) -> Result<Self, Error> {
        let mut r = Reader::new(bytes);
        let bad = |r: &Reader<'_>| Error::ShowCuesMalformed { offset: r.pos() };
        let default_fade_ms = r.varint_u32().ok_or_else(|| bad(&r))?;
        let seed = r.varint_u32().ok_or_else(|| bad(&r))?;
        if seed == 0 {
            return Err(bad(&r));
        }
        let list_count = count(&mut r, MAX_LISTS)?;
        let lists_at = r.pos();
        for i in 0..list_count {
            let (name, _) = read_list(&mut r, clips)?;
            // Names are unique.
            let mut earlier = Reader::new(bytes.get(lists_at..).unwrap_or(&[]));
            for _ in 0..i {
                let (other, _) = read_list(&mut earlier, clips)?;
                if other == name {
                    return Err(bad(&r));
                }
            }
        }
        let lists = bytes.get(lists_at..r.pos()).unwrap_or(&[]);
        let idle_count = count(&mut r, MAX_LISTS)?;
        let idle_at = r.pos();
        for _ in 0..idle_count {
            clip_number(&mut r, clips)?;
        }
        let idle = bytes.get(idle_at..r.pos()).unwrap_or(&[]);
        let trigger_count = count(&mut r, MAX_TRIGGERS)?;
        let triggers_at = r.pos();
        let mut inputs: u32 = 0;
        for _ in 0..trigger_count {
            let t = read_trigger(&mut r, clips, list_count)?;
            let bit = 1u32 << (t.input & 31);
            if inputs & bit != 0 {
                return Err(bad(&r)); // one trigger per input
            }
            inputs |= bit;
        }
        let triggers = bytes.get(triggers_at..r.pos()).unwrap_or(&[]);
        if !r.is_empty() {
            return Err(bad(&r));
        }
        Ok(Cues {
            default_fade_ms,
            seed,
            lists,
            list_count,
            idle,
            idle_count,
            triggers,
            trigger_count: trigger_count as u8,
            clips,
        })
    }

    /// Number of cue lists.
    pub fn list_count(&self) -> u16 {
        self.list_count
    }

    /// Cue list `i`.
    pub fn list(&self, i: u16) -> Option<CueList<'a>> {
        let mut r = Reader::new(self.lists);
        for _ in 0..i {
            read_list(&mut r, self.clips).ok()?;
        }
        let (name, (cues, count)) = read_list(&mut r, self.clips).ok()?;
        Some(CueList {
            name,
            cues,
            count,
            clips: self.clips,
        })
    }

    /// The number of the cue list called `name`.
    pub fn find_list(&self, name: &str) -> Option<u16> {
        (0..self.list_count).find(|&i| self.list(i).is_some_and(|l| l.name == name))
    }

    /// Number of idle clips.
    pub fn idle_count(&self) -> u16 {
        self.idle_count
    }

    /// Idle clip `k`.
    pub fn idle(&self, k: u16) -> Option<u16> {
        let mut r = Reader::new(self.idle);
        for _ in 0..k {
            r.varint_u32()?;
        }
        r.varint_u32().and_then(|v| u16::try_from(v).ok())
    }

    /// Number of triggers.
    pub fn trigger_count(&self) -> u8 {
        self.trigger_count
    }

    /// Trigger `k`.
    pub fn trigger(&self, k: u8) -> Option<Trigger<'a>> {
        let mut r = Reader::new(self.triggers);
        for _ in 0..k {
            read_trigger(&mut r, self.clips, self.list_count).ok()?;
        }
        read_trigger(&mut r, self.clips, self.list_count).ok()
    }

    /// The trigger of input `input`.
    pub fn trigger_of(&self, input: u8) -> Option<Trigger<'a>> {
        (0..self.trigger_count)
            .filter_map(|k| self.trigger(k))
            .find(|t| t.input == input)
    }
}

fn count(r: &mut Reader<'_>, max: usize) -> Result<u16, Error> {
    let n = r
        .varint_u32()
        .ok_or(Error::ShowCuesMalformed { offset: r.pos() })?;
    if n as usize > max {
        return Err(Error::ShowCuesMalformed { offset: r.pos() });
    }
    Ok(n as u16)
}

fn clip_number(r: &mut Reader<'_>, clips: u16) -> Result<u16, Error> {
    let v = r
        .varint_u32()
        .ok_or(Error::ShowCuesMalformed { offset: r.pos() })?;
    match u16::try_from(v) {
        Ok(c) if c < clips => Ok(c),
        _ => Err(Error::ShowCuesMalformed { offset: r.pos() }),
    }
}

/// A list's name and its cues' bytes and count.
type ListBytes<'a> = (&'a str, (&'a [u8], u16));

fn read_list<'a>(r: &mut Reader<'a>, clips: u16) -> Result<ListBytes<'a>, Error> {
    let bad = |r: &Reader<'_>| Error::ShowCuesMalformed { offset: r.pos() };
    let name = r.byte_seq().ok_or_else(|| bad(r))?;
    if name.is_empty() || name.len() > crate::consts::MAX_CLIP_NAME {
        return Err(bad(r));
    }
    let name = core::str::from_utf8(name).map_err(|_| bad(r))?;
    let n = count(r, usize::from(u16::MAX))?;
    let at = r.clone();
    let start = r.pos();
    let mut last: u32 = 0;
    for _ in 0..n {
        let cue = read_cue(r, clips)?;
        if cue.at_ms < last {
            return Err(bad(r));
        }
        last = cue.at_ms;
    }
    let mut whole = at;
    let cues = whole
        .take(r.pos().wrapping_sub(start))
        .ok_or_else(|| bad(r))?;
    Ok((name, (cues, n)))
}

fn read_cue<'a>(r: &mut Reader<'a>, clips: u16) -> Result<Cue<'a>, Error> {
    let bad = |r: &Reader<'_>| Error::ShowCuesMalformed { offset: r.pos() };
    let at_ms = r.varint_u32().ok_or_else(|| bad(r))?;
    let op = r.u8().ok_or_else(|| bad(r))?;
    let action = match op {
        0 => Action::Play(clip_number(r, clips)?),
        1 => Action::Fade {
            clip: clip_number(r, clips)?,
            ms: r.varint_u32().ok_or_else(|| bad(r))?,
        },
        2 => Action::Queue(clip_number(r, clips)?),
        3 => Action::Stop,
        4 => Action::Hold,
        5 => Action::Resume,
        6 => Action::Loop(r.bool().ok_or_else(|| bad(r))?),
        7 => Action::Gpio {
            pin: r.u8().ok_or_else(|| bad(r))?,
            level: r.bool().ok_or_else(|| bad(r))?,
        },
        8 => {
            let bytes = r.byte_seq().ok_or_else(|| bad(r))?;
            if bytes.is_empty() || bytes.len() > MAX_SERIAL {
                return Err(bad(r));
            }
            Action::Serial(bytes)
        }
        _ => return Err(bad(r)),
    };
    Ok(Cue { at_ms, action })
}

fn read_trigger<'a>(r: &mut Reader<'a>, clips: u16, lists: u16) -> Result<Trigger<'a>, Error> {
    let bad = |r: &Reader<'_>| Error::ShowCuesMalformed { offset: r.pos() };
    let input = r.u8().ok_or_else(|| bad(r))?;
    if usize::from(input) >= MAX_TRIGGERS {
        return Err(bad(r));
    }
    let kind = match r.u8().ok_or_else(|| bad(r))? {
        0 => TriggerKind::List,
        1 => TriggerKind::Clip,
        _ => return Err(bad(r)),
    };
    let cooldown_ms = r.varint_u32().ok_or_else(|| bad(r))?;
    let n = count(r, MAX_TARGETS)?;
    if n == 0 {
        return Err(bad(r));
    }
    let start = r.pos();
    let at = r.clone();
    for _ in 0..n {
        match kind {
            TriggerKind::Clip => {
                clip_number(r, clips)?;
            }
            TriggerKind::List => {
                clip_number(r, lists)?;
            }
        }
    }
    let mut whole = at;
    let targets = whole
        .take(r.pos().wrapping_sub(start))
        .ok_or_else(|| bad(r))?;
    Ok(Trigger {
        input,
        kind,
        cooldown_ms,
        targets,
        count: n as u8,
    })
}
