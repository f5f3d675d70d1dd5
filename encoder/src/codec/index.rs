//! Encoder of the `index` codec (SPEC.md §4): per channel, a codebook of
//! 2^b values sized from the channel's tolerance (b = 0 for constant
//! channels), and — where it is smaller — a delta codebook with absolute key
//! frames every K frames. The encoder simulates the decoder exactly (closed
//! loop), so delta errors never accumulate past the tolerance.
//!
//! A channel whose key-frame values no 12-bit table covers at its
//! tolerance (the root of a long walk, a heading that winds many times) is
//! coded in levels (SPEC.md §4.5): a coarse table, then tables of the
//! remainders, summed by accumulating key-set entries — the decoder's loop
//! as it is. At `K = 0` that codes any valid clip.

use mocap_decoder::consts::index::{
    ENTRY_LEN, FAST_GROUP_HEADER_LEN, FAST_WIDTHS, FLAG_ACCUMULATE, GROUP_HEADER_LEN, MAX_BITS,
};

use super::bits::BitWriter;
use super::quantizer::{self, Codebook};
use super::CodecError;

/// How an `index` section is laid out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IndexLayout {
    /// SPEC.md §4.1–§4.5 (section `0x10`): the smallest clip — `i16` tables
    /// under a shift and a base, indices of any width up to 12 bits packed
    /// back to back. The default.
    #[default]
    Compact,
    /// SPEC.md §4.6 (section `0x13`): the fewest decode instructions —
    /// tables of final `i32` values, index widths rounded up to 1, 2, 4, 8
    /// or 16 bits, each group's fields on whole bytes.
    Fast,
}

impl IndexLayout {
    /// Every layout, in command-line order.
    pub const ALL: [IndexLayout; 2] = [IndexLayout::Compact, IndexLayout::Fast];

    /// The command-line name (`compact`, `fast`).
    pub fn name(self) -> &'static str {
        match self {
            IndexLayout::Compact => "compact",
            IndexLayout::Fast => "fast",
        }
    }

    /// The section id of this layout.
    pub fn section_id(self) -> u8 {
        match self {
            IndexLayout::Compact => mocap_decoder::consts::SECTION_CODEC_INDEX,
            IndexLayout::Fast => mocap_decoder::consts::SECTION_CODEC_INDEX_FAST,
        }
    }

    /// Bits of `n` indices into `cb`, its table and its set entry.
    fn coded_bits(self, cb: &Codebook, n: u64) -> u64 {
        match self {
            IndexLayout::Compact => coded_bits(cb, n),
            // Rounded width; `i32` entries and a `u16` destination.
            IndexLayout::Fast => {
                let width = fast_width(cb.bits);
                let entries = fast_stride(width, [cb.entries.len()]);
                n * u64::from(width) + 32 * entries as u64 + 16
            }
        }
    }
}

impl std::str::FromStr for IndexLayout {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        IndexLayout::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| format!("unknown index layout '{s}' (compact, fast)"))
    }
}

/// The field width of the fast layout (SPEC.md §4.6) for a codebook of
/// `bits`: the smallest of 0, 1, 2, 4, 8, 16 that holds it.
pub fn fast_width(bits: u8) -> u8 {
    FAST_WIDTHS.into_iter().find(|&w| w >= bits).unwrap_or(16)
}

/// Entries per channel of a fast-layout group of `width` whose channels'
/// codebooks have `lens` entries (SPEC.md §4.6): `2^width` for widths 1, 2
/// and 4, else the largest codebook (1 for width 0).
fn fast_stride(width: u8, lens: impl IntoIterator<Item = usize>) -> usize {
    match width {
        1 | 2 | 4 => 1 << width,
        _ => lens.into_iter().max().unwrap_or(1).max(1),
    }
}

/// Key-frame intervals the encoder tries when none is forced
/// (0 = absolute codes only).
pub const KEY_INTERVALS: [u16; 6] = [0, 8, 16, 32, 64, 128];

/// How one channel is coded.
#[derive(Clone, Debug)]
pub struct ChannelCode {
    /// Codebook used in key frames (and in every frame for absolute
    /// channels).
    pub key: Codebook,
    /// Delta codebook for delta frames; `None` for absolute channels.
    pub delta: Option<Codebook>,
    /// Key frames in levels (SPEC.md §4.5): the levels after `key` (the
    /// coarse one), each with its index per frame (read at key frames).
    /// Empty for a channel `key` covers alone.
    pub levels: Vec<(Codebook, Vec<u16>)>,
    /// Index per frame.
    pub indices: Vec<u16>,
    /// The values the decoder will produce.
    pub decoded: Vec<i32>,
}

/// A channel coded for one key interval, with its cost.
#[derive(Clone)]
struct Candidate {
    code: ChannelCode,
    bits: u64,
}

fn is_key(frame: usize, k: usize) -> bool {
    k == 0 || frame.is_multiple_of(k)
}

/// Absolute coding of every frame.
fn absolute(x: &[i64], tol: i64, layout: IndexLayout) -> Option<Candidate> {
    let cb = quantizer::fit(x, tol, MAX_BITS)?;
    let indices: Vec<u16> = x.iter().map(|&v| cb.nearest(v) as u16).collect();
    let decoded = indices
        .iter()
        .map(|&i| cb.value(usize::from(i)) as i32)
        .collect();
    let bits = layout.coded_bits(&cb, x.len() as u64);
    Some(Candidate {
        code: ChannelCode {
            key: cb,
            delta: None,
            levels: Vec::new(),
            indices,
            decoded,
        },
        bits,
    })
}

/// Most levels a key value is split into: three 12-bit levels reach any
/// `i32` exactly.
const MAX_LEVELS: usize = 3;

/// Codebooks whose sum codes every point within `tol` (SPEC.md §4.5): one
/// if a table covers the points, else a coarse table (tolerance `tol·2^k`,
/// the `k` of the fewest bits) and the levels of the remainders. `None`
/// if [`MAX_LEVELS`] do not reach.
fn fit_levels(
    points: &[i64],
    tol: i64,
    depth: usize,
    layout: IndexLayout,
) -> Option<Vec<Codebook>> {
    if let Some(cb) = quantizer::fit(points, tol, MAX_BITS) {
        return Some(vec![cb]);
    }
    if depth <= 1 {
        return None;
    }
    let mut best: Option<(u64, Vec<Codebook>)> = None;
    for k in 2..=MAX_BITS {
        let coarse_tol = tol.max(1) << k;
        let Some(coarse) = quantizer::fit(points, coarse_tol, MAX_BITS) else {
            continue;
        };
        let rest: Vec<i64> = points
            .iter()
            .map(|&p| p - coarse.value(coarse.nearest(p)))
            .collect();
        let Some(finer) = fit_levels(&rest, tol, depth - 1, layout) else {
            continue;
        };
        let mut levels = vec![coarse];
        levels.extend(finer);
        let bits = levels_bits(&levels, points.len() as u64, layout);
        if best.as_ref().is_none_or(|(b, _)| bits < *b) {
            best = Some((bits, levels));
        }
    }
    best.map(|(_, l)| l)
}

/// The indices of `v` in each level (coarse first, each level coding what
/// the ones before left) and the value the decoder sums (wrapping).
fn code_levels(levels: &[Codebook], v: i64) -> (Vec<u16>, i32) {
    let mut out: i32 = 0;
    let mut indices = Vec::with_capacity(levels.len());
    for cb in levels {
        let i = cb.nearest(v - i64::from(out));
        indices.push(i as u16);
        out = out.wrapping_add(cb.value(i) as i32);
    }
    (indices, out)
}

/// Every frame coded in levels at `K = 0` (SPEC.md §4.5): for channels no
/// single table covers.
fn absolute_levels(x: &[i64], tol: i64, layout: IndexLayout) -> Option<Candidate> {
    let levels = fit_levels(x, tol, MAX_LEVELS, layout)?;
    let mut per_level: Vec<Vec<u16>> = vec![Vec::with_capacity(x.len()); levels.len()];
    let mut decoded = Vec::with_capacity(x.len());
    for &v in x {
        let (idx, out) = code_levels(&levels, v);
        if (i64::from(out) - v).abs() > tol {
            return None;
        }
        for (l, i) in per_level.iter_mut().zip(idx) {
            l.push(i);
        }
        decoded.push(out);
    }
    let bits = levels_bits(&levels, x.len() as u64, layout);
    let mut levels = levels.into_iter().zip(per_level);
    let (key, indices) = levels.next()?;
    Some(Candidate {
        code: ChannelCode {
            key,
            delta: None,
            levels: levels.collect(),
            indices,
            decoded,
        },
        bits,
    })
}

/// How key frames of a delta-coded channel are coded.
enum KeyCode {
    /// By one table.
    Table(Codebook),
    /// In levels (SPEC.md §4.5), coarse first.
    Levels(Vec<Codebook>),
}

fn table_bits(cb: &Codebook) -> u64 {
    16 * cb.entries.len() as u64 + 8 * ENTRY_LEN as u64
}

/// Bits of `n` indices into `cb`, its table and its set entry.
fn coded_bits(cb: &Codebook, n: u64) -> u64 {
    n * u64::from(cb.bits) + table_bits(cb)
}

/// [`coded_bits`] of `n` values coded in `levels` (SPEC.md §4.5).
fn levels_bits(levels: &[Codebook], n: u64, layout: IndexLayout) -> u64 {
    levels.iter().map(|cb| layout.coded_bits(cb, n)).sum()
}

/// Delta coding with key frames every `k`; tries delta codebooks of
/// growing size and keeps the first whose closed loop meets `tol`. Key
/// frames no table covers are coded in levels if `levels` allows.
fn delta(
    x: &[i64],
    tol: i64,
    k: usize,
    max_bits: u8,
    levels: bool,
    layout: IndexLayout,
) -> Option<Candidate> {
    let keys: Vec<i64> = x
        .iter()
        .enumerate()
        .filter(|(f, _)| is_key(*f, k))
        .map(|(_, &v)| v)
        .collect();
    let steps: Vec<i64> = (1..x.len())
        .filter(|&f| !is_key(f, k))
        .map(|f| x[f] - x[f - 1])
        .collect();
    if steps.is_empty() {
        return None;
    }
    if let Some(key_cb) = quantizer::fit(&keys, tol, MAX_BITS) {
        return delta_tables(x, tol, k, max_bits, &KeyCode::Table(key_cb), &steps, layout);
    }
    if !levels {
        return None;
    }
    // Levels a little finer than the tolerance, then exact: the delta frames
    // after a key frame start closer to the motion (a key error near `tol`
    // can leave the delta table, whose outer codes sit inside its steps'
    // range, no room to come back).
    for key_tol in [tol / 8, 0] {
        let Some(levels) = fit_levels(&keys, key_tol, MAX_LEVELS, layout) else {
            continue;
        };
        let c = delta_tables(
            x,
            tol,
            k,
            max_bits,
            &KeyCode::Levels(levels),
            &steps,
            layout,
        );
        if c.is_some() {
            return c;
        }
    }
    None
}

/// The closed loop of [`delta`] for its key coding, with delta codebooks of
/// growing size: the first that meets `tol`.
fn delta_tables(
    x: &[i64],
    tol: i64,
    k: usize,
    max_bits: u8,
    key_code: &KeyCode,
    steps: &[i64],
    layout: IndexLayout,
) -> Option<Candidate> {
    // Delta codebooks with a tolerance below `tol` leave the closed loop room
    // to absorb the error carried from the previous frame.
    for frac in [2i64, 3, 4, 6, 8] {
        let step_tol = tol / frac;
        let Some(cb) = quantizer::fit(steps, step_tol, max_bits) else {
            continue;
        };
        if let Some(c) = closed_loop(x, tol, k, key_code, &cb, layout) {
            return Some(c);
        }
    }
    None
}

fn closed_loop(
    x: &[i64],
    tol: i64,
    k: usize,
    key_code: &KeyCode,
    cb: &Codebook,
    layout: IndexLayout,
) -> Option<Candidate> {
    let mut indices = Vec::with_capacity(x.len());
    let mut decoded = Vec::with_capacity(x.len());
    let finer = match key_code {
        KeyCode::Levels(l) => l.len() - 1,
        KeyCode::Table(_) => 0,
    };
    let mut level_indices: Vec<Vec<u16>> = vec![Vec::with_capacity(x.len()); finer];
    let mut prev: i32 = 0;
    for (f, &v) in x.iter().enumerate() {
        let (i, out) = if is_key(f, k) {
            match key_code {
                KeyCode::Table(key_cb) => {
                    let i = key_cb.nearest(v);
                    (i, key_cb.value(i) as i32)
                }
                KeyCode::Levels(levels) => {
                    let (idx, out) = code_levels(levels, v);
                    for (l, &i) in level_indices.iter_mut().zip(&idx[1..]) {
                        l.push(i);
                    }
                    (usize::from(idx[0]), out)
                }
            }
        } else {
            for l in &mut level_indices {
                l.push(0);
            }
            let i = cb.nearest(v - i64::from(prev));
            (i, prev.wrapping_add(cb.value(i) as i32))
        };
        if (i64::from(out) - v).abs() > tol {
            return None;
        }
        indices.push(i as u16);
        decoded.push(out);
        prev = out;
    }
    let nk = (0..x.len()).filter(|&f| is_key(f, k)).count() as u64;
    let nd = x.len() as u64 - nk;
    let (key, levels, key_bits) = match key_code {
        KeyCode::Table(key_cb) => (key_cb.clone(), Vec::new(), layout.coded_bits(key_cb, nk)),
        KeyCode::Levels(l) => (l[0].clone(), l[1..].to_vec(), levels_bits(l, nk, layout)),
    };
    let bits = key_bits + layout.coded_bits(cb, nd);
    Some(Candidate {
        code: ChannelCode {
            key,
            delta: Some(cb.clone()),
            levels: levels.into_iter().zip(level_indices).collect(),
            indices,
            decoded,
        },
        bits,
    })
}

/// Codes one channel for key interval `k`: the cheaper of its absolute
/// coding `abs` (the same for every `k`) and delta coding. A channel no
/// absolute table covers is delta-coded on key frames in levels, or at
/// `k = 0` coded in levels; `None` if that fails too.
fn code_channel(
    x: &[i64],
    tol: i64,
    k: usize,
    abs: Option<&Candidate>,
    layout: IndexLayout,
) -> Option<Candidate> {
    let Some(abs) = abs else {
        return if k == 0 {
            absolute_levels(x, tol, layout)
        } else {
            delta(x, tol, k, MAX_BITS, true, layout)
        };
    };
    if k == 0 || abs.code.key.bits <= 1 {
        return Some(abs.clone());
    }
    match delta(
        x,
        tol,
        k,
        abs.code.key.bits.saturating_sub(1),
        false,
        layout,
    ) {
        Some(d) if d.bits < abs.bits => Some(d),
        _ => Some(abs.clone()),
    }
}

/// A whole clip coded by the index codec.
#[derive(Clone, Debug)]
pub struct IndexEncoding {
    /// Key-frame interval K (0 = absolute only).
    pub key_interval: u16,
    /// Per channel.
    pub channels: Vec<ChannelCode>,
    /// The section layout [`IndexEncoding::to_section`] writes.
    pub layout: IndexLayout,
}

/// Why a clip could not be coded.
#[derive(Debug, Clone, PartialEq)]
pub struct ToleranceTooTight {
    /// Channel index.
    pub channel: usize,
}

/// Codes every channel (`x[channel][frame]`) within `tol[channel]` (same
/// units), trying each key interval of `intervals` and keeping the
/// smallest section. With `0` among the intervals it codes any clip
/// (channels no table covers in levels, SPEC.md §4.5); otherwise it fails
/// on the first channel no interval can code.
pub fn encode(
    x: &[Vec<i32>],
    tol: &[i64],
    intervals: &[u16],
    layout: IndexLayout,
) -> Result<IndexEncoding, ToleranceTooTight> {
    let wide: Vec<Vec<i64>> = x
        .iter()
        .map(|c| c.iter().map(|&v| i64::from(v)).collect())
        .collect();
    // Absolute coding does not depend on the key interval: fit it once.
    let absolutes: Vec<Option<Candidate>> = wide
        .iter()
        .enumerate()
        .map(|(c, series)| absolute(series, tol[c].max(0), layout))
        .collect();
    let mut best: Option<(u64, IndexEncoding)> = None;
    let mut failed: Option<usize> = None;
    'intervals: for &k in intervals {
        let mut total = 0u64;
        let mut channels = Vec::with_capacity(x.len());
        for (c, (series, abs)) in wide.iter().zip(&absolutes).enumerate() {
            let Some(cand) =
                code_channel(series, tol[c].max(0), usize::from(k), abs.as_ref(), layout)
            else {
                failed.get_or_insert(c);
                continue 'intervals;
            };
            total += cand.bits;
            channels.push(cand.code);
        }
        if best.as_ref().is_none_or(|(b, _)| total < *b) {
            best = Some((
                total,
                IndexEncoding {
                    key_interval: k,
                    channels,
                    layout,
                },
            ));
        }
    }
    match (best, failed) {
        (Some((_, e)), _) => Ok(e),
        (None, Some(channel)) => Err(ToleranceTooTight { channel }),
        (None, None) => Ok(IndexEncoding {
            key_interval: 0,
            channels: Vec::new(),
            layout,
        }),
    }
}

/// Lays codebooks into one pool, letting a table's unused tail overlap the
/// next table (SPEC.md §4.2 allows overlap); returns each codebook's offset.
struct Pool {
    entries: Vec<i16>,
}

impl Pool {
    fn place(&mut self, cb: &Codebook) -> u16 {
        let off = self.entries.len();
        self.entries.extend_from_slice(&cb.entries);
        off as u16
    }

    /// Pads so that every table's full `2^bits` range lies inside the pool.
    fn pad_for(&mut self, off: u16, bits: u8) {
        let end = usize::from(off) + (1usize << bits);
        if self.entries.len() < end {
            self.entries.resize(end, 0);
        }
    }
}

/// One coded channel of a set (SPEC.md §4.2).
#[derive(Clone, Copy)]
struct Entry {
    channel: u16,
    bits: u8,
    shift: u8,
    accumulate: bool,
    /// Which of the channel's key levels (0 = `key`, SPEC.md §4.5).
    level: u8,
    table: u16,
    base: i32,
}

/// Groups entries by (width, shift, accumulate) in a stable order and
/// returns the set's bytes and the entries in record order.
fn write_set(entries: &[Entry]) -> (Vec<u8>, Vec<Entry>) {
    let mut order: Vec<Entry> = entries.to_vec();
    order.sort_by_key(|e| (e.bits, e.shift, e.accumulate, e.channel));
    let mut out = Vec::new();
    let mut groups = 0u16;
    out.extend_from_slice(&[0, 0]);
    for run in
        order.chunk_by(|a, b| (a.bits, a.shift, a.accumulate) == (b.bits, b.shift, b.accumulate))
    {
        for chunk in run.chunks(usize::from(u16::MAX)) {
            let e0 = chunk[0];
            let flags = if e0.accumulate { FLAG_ACCUMULATE } else { 0 };
            let mut header = [0u8; GROUP_HEADER_LEN];
            header[0] = e0.bits;
            header[1] = e0.shift | flags;
            header[2..4].copy_from_slice(&(chunk.len() as u16).to_le_bytes());
            out.extend_from_slice(&header);
            for e in chunk {
                out.extend_from_slice(&e.channel.to_le_bytes());
                out.extend_from_slice(&e.table.to_le_bytes());
                out.extend_from_slice(&e.base.to_le_bytes());
            }
            groups += 1;
        }
    }
    out[0..2].copy_from_slice(&groups.to_le_bytes());
    (out, order)
}

/// One coded channel of a set in the fast layout (SPEC.md §4.6).
#[derive(Clone)]
struct FastEntry {
    channel: usize,
    width: u8,
    accumulate: bool,
    /// Which of the channel's key levels (0 = `key`, SPEC.md §4.5).
    level: u8,
    /// The final values of its table.
    values: Vec<i32>,
}

impl FastEntry {
    fn new(channel: usize, cb: &Codebook, accumulate: bool, level: u8) -> Self {
        FastEntry {
            channel,
            width: fast_width(cb.bits),
            accumulate,
            level,
            values: (0..cb.entries.len()).map(|i| cb.value(i) as i32).collect(),
        }
    }
}

/// Most record bits per frame a group may add by joining the next wider
/// group of its kind (SPEC.md §4.6): each group costs a decoder about 90
/// instructions per frame on a Cortex-M3 (its header, its slices, its
/// call), more than a few wider fields do.
const MERGE_BITS: usize = 32;

/// Moves the channels of a small group into the next wider group with the
/// same accumulate flag when that adds at most [`MERGE_BITS`] per record.
fn merge_small_groups(entries: &mut [FastEntry]) {
    for acc in [false, true] {
        let mut widths: Vec<(u8, usize)> = Vec::new();
        for e in entries
            .iter()
            .filter(|e| e.accumulate == acc && e.width > 0)
        {
            match widths.iter_mut().find(|(w, _)| *w == e.width) {
                Some((_, n)) => *n += 1,
                None => widths.push((e.width, 1)),
            }
        }
        widths.sort();
        for i in 0..widths.len().saturating_sub(1) {
            let (w, n) = widths[i];
            let (wider, _) = widths[i + 1];
            if n * usize::from(wider - w) <= MERGE_BITS {
                for e in entries
                    .iter_mut()
                    .filter(|e| e.accumulate == acc && e.width == w)
                {
                    e.width = wider;
                }
                widths[i + 1].1 += n;
            }
        }
    }
}

/// Groups entries by (width, accumulate) in a stable order and returns the
/// set's bytes and its groups' entries in record order (SPEC.md §4.6). A
/// group's tables are padded to its widest (with their last value).
fn write_fast_set(entries: &[FastEntry]) -> (Vec<u8>, Vec<Vec<FastEntry>>) {
    let mut order: Vec<FastEntry> = entries.to_vec();
    merge_small_groups(&mut order);
    order.sort_by_key(|e| (std::cmp::Reverse(e.width), e.accumulate, e.channel));
    let mut out = vec![0, 0];
    let mut groups = Vec::new();
    for run in order.chunk_by(|a, b| (a.width, a.accumulate) == (b.width, b.accumulate)) {
        for chunk in run.chunks(usize::from(u16::MAX)) {
            let e0 = &chunk[0];
            let stride = fast_stride(e0.width, chunk.iter().map(|e| e.values.len()));
            let flags = if e0.accumulate { FLAG_ACCUMULATE } else { 0 };
            let mut header = [0u8; FAST_GROUP_HEADER_LEN];
            header[0] = e0.width;
            header[1] = flags;
            header[2..4].copy_from_slice(&(chunk.len() as u16).to_le_bytes());
            header[4..6].copy_from_slice(&(stride as u16).to_le_bytes());
            out.extend_from_slice(&header);
            for e in chunk {
                out.extend_from_slice(&(e.channel as u16).to_le_bytes());
            }
            for e in chunk {
                let last = e.values.last().copied().unwrap_or(0);
                for i in 0..stride {
                    let v = e.values.get(i).copied().unwrap_or(last);
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
            groups.push(chunk.to_vec());
        }
    }
    let n = groups.len() as u16;
    out[0..2].copy_from_slice(&n.to_le_bytes());
    (out, groups)
}

fn entry(channel: usize, cb: &Codebook, table: u16, accumulate: bool) -> Entry {
    Entry {
        channel: channel as u16,
        bits: cb.bits,
        shift: cb.shift,
        accumulate,
        level: 0,
        table,
        base: cb.base,
    }
}

impl IndexEncoding {
    /// The codec section bytes (SPEC.md §4.1). Fails if the table pool
    /// exceeds the 16-bit offsets of the format.
    pub fn to_section(&self) -> Result<Vec<u8>, CodecError> {
        if self.layout == IndexLayout::Fast {
            return Ok(self.to_fast_section());
        }
        let mut pool = Pool {
            entries: Vec::new(),
        };
        let placed: Vec<(u16, Option<u16>)> = self
            .channels
            .iter()
            .map(|ch| {
                (
                    pool.place(&ch.key),
                    ch.delta.as_ref().map(|d| pool.place(d)),
                )
            })
            .collect();
        let level_offsets: Vec<Vec<u16>> = self
            .channels
            .iter()
            .map(|ch| ch.levels.iter().map(|(cb, _)| pool.place(cb)).collect())
            .collect();
        let mut key = Vec::new();
        let mut delta = Vec::new();
        for (c, (ch, &(key_off, delta_off))) in self.channels.iter().zip(&placed).enumerate() {
            pool.pad_for(key_off, ch.key.bits);
            // Levels (§4.5) all accumulate: their order in the set is free.
            let levels = !ch.levels.is_empty();
            key.push(entry(c, &ch.key, key_off, levels));
            for (l, ((cb, _), &off)) in ch.levels.iter().zip(&level_offsets[c]).enumerate() {
                pool.pad_for(off, cb.bits);
                key.push(Entry {
                    level: l as u8 + 1,
                    ..entry(c, cb, off, true)
                });
            }
            match (&ch.delta, delta_off) {
                (Some(d), Some(off)) => {
                    pool.pad_for(off, d.bits);
                    // A delta codebook of one zero step never changes the value.
                    if d.bits > 0 || d.value(0) != 0 {
                        delta.push(entry(c, d, off, true));
                    }
                }
                // Absolute channels: constant ones keep the key frame's value.
                _ if ch.key.bits > 0 => delta.push(entry(c, &ch.key, key_off, false)),
                _ => {}
            }
        }
        if pool.entries.len() > usize::from(u16::MAX) {
            return Err(CodecError::IndexTableTooLarge {
                entries: pool.entries.len(),
            });
        }
        let (key_bytes, key_order) = write_set(&key);
        let (delta_bytes, delta_order) = write_set(&delta);
        let frames = self.channels.first().map_or(0, |c| c.indices.len());
        let mut bits = BitWriter::default();
        for f in 0..frames {
            let is_key = self.key_interval == 0 || f % usize::from(self.key_interval) == 0;
            let order = if is_key { &key_order } else { &delta_order };
            for e in order {
                let ch = &self.channels[usize::from(e.channel)];
                let index = match e.level {
                    0 => ch.indices[f],
                    l => ch.levels[usize::from(l) - 1].1[f],
                };
                bits.write(u32::from(index), e.bits);
            }
        }
        let mut out = Vec::new();
        out.extend_from_slice(&self.key_interval.to_le_bytes());
        out.extend_from_slice(&(self.channels.len() as u16).to_le_bytes());
        out.extend_from_slice(&(pool.entries.len() as u32).to_le_bytes());
        out.extend_from_slice(&key_bytes);
        if self.key_interval > 0 {
            out.extend_from_slice(&delta_bytes);
        }
        for e in &pool.entries {
            out.extend_from_slice(&e.to_le_bytes());
        }
        out.extend_from_slice(&bits.finish());
        Ok(out)
    }

    /// The section bytes in the fast layout (SPEC.md §4.6, id `0x13`).
    fn to_fast_section(&self) -> Vec<u8> {
        let mut key = Vec::new();
        let mut delta = Vec::new();
        for (c, ch) in self.channels.iter().enumerate() {
            // Levels (§4.5) all accumulate.
            let levels = !ch.levels.is_empty();
            key.push(FastEntry::new(c, &ch.key, levels, 0));
            for (l, (cb, _)) in ch.levels.iter().enumerate() {
                key.push(FastEntry::new(c, cb, true, l as u8 + 1));
            }
            match &ch.delta {
                // A delta codebook of one zero step never changes the value.
                Some(d) if d.bits > 0 || d.value(0) != 0 => {
                    delta.push(FastEntry::new(c, d, true, 0))
                }
                Some(_) => {}
                // Absolute channels: constant ones keep the key frame's value.
                None if ch.key.bits > 0 => delta.push(FastEntry::new(c, &ch.key, false, 0)),
                None => {}
            }
        }
        let (key_bytes, key_groups) = write_fast_set(&key);
        let (delta_bytes, delta_groups) = write_fast_set(&delta);
        let mut out = Vec::new();
        out.extend_from_slice(&self.key_interval.to_le_bytes());
        out.extend_from_slice(&(self.channels.len() as u16).to_le_bytes());
        out.extend_from_slice(&key_bytes);
        if self.key_interval > 0 {
            out.extend_from_slice(&delta_bytes);
        }
        let frames = self.channels.first().map_or(0, |c| c.indices.len());
        for f in 0..frames {
            let is_key = self.key_interval == 0 || f % usize::from(self.key_interval) == 0;
            let groups = if is_key { &key_groups } else { &delta_groups };
            for g in groups {
                // Each group's fields start on a byte (§4.6).
                let mut bits = BitWriter::default();
                for e in g {
                    let ch = &self.channels[e.channel];
                    let index = match e.level {
                        0 => ch.indices[f],
                        l => ch.levels[usize::from(l) - 1].1[f],
                    };
                    bits.write(u32::from(index), e.width);
                }
                out.extend_from_slice(&bits.finish());
            }
        }
        out
    }

    /// Decoded values per channel, as the decoder will produce them.
    pub fn decoded(&self) -> Vec<Vec<i32>> {
        self.channels.iter().map(|c| c.decoded.clone()).collect()
    }
}

/// One group of a set (for `mocap info`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GroupInfo {
    /// Index width.
    pub bits: u8,
    /// Accumulating (delta) group.
    pub accumulate: bool,
    /// Channels of the group.
    pub channels: Vec<u16>,
}

/// What `mocap info` shows of an index section.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SectionInfo {
    /// Key-frame interval.
    pub key_interval: u16,
    /// Entries in the table pool.
    pub table_entries: u32,
    /// Groups of the key set.
    pub key: Vec<GroupInfo>,
    /// Groups of the delta set.
    pub delta: Vec<GroupInfo>,
    /// Payload bytes.
    pub payload_bytes: usize,
}

fn read_set(s: &[u8], at: &mut usize) -> Option<Vec<GroupInfo>> {
    let n = u16::from_le_bytes(s.get(*at..*at + 2)?.try_into().ok()?);
    *at += 2;
    let mut groups = Vec::new();
    for _ in 0..n {
        let h = s.get(*at..*at + GROUP_HEADER_LEN)?;
        let count = usize::from(u16::from_le_bytes([h[2], h[3]]));
        *at += GROUP_HEADER_LEN;
        let body = s.get(*at..*at + count * ENTRY_LEN)?;
        *at += count * ENTRY_LEN;
        groups.push(GroupInfo {
            bits: h[0],
            accumulate: h[1] & FLAG_ACCUMULATE != 0,
            channels: body
                .chunks_exact(ENTRY_LEN)
                .map(|e| u16::from_le_bytes([e[0], e[1]]))
                .collect(),
        });
    }
    Some(groups)
}

/// Reads the sets of an index section that the decoder validated.
pub fn inspect(section: &[u8]) -> Option<SectionInfo> {
    let key_interval = u16::from_le_bytes(section.get(0..2)?.try_into().ok()?);
    let table_entries = u32::from_le_bytes(section.get(4..8)?.try_into().ok()?);
    let mut at = 8;
    let key = read_set(section, &mut at)?;
    let delta = if key_interval > 0 {
        read_set(section, &mut at)?
    } else {
        Vec::new()
    };
    let payload_at = at + 2 * table_entries as usize;
    Some(SectionInfo {
        key_interval,
        table_entries,
        key,
        delta,
        payload_bytes: section.len().saturating_sub(payload_at),
    })
}

fn read_fast_set(s: &[u8], at: &mut usize) -> Option<Vec<GroupInfo>> {
    let n = u16::from_le_bytes(s.get(*at..*at + 2)?.try_into().ok()?);
    *at += 2;
    let mut groups = Vec::new();
    for _ in 0..n {
        let h = s.get(*at..*at + FAST_GROUP_HEADER_LEN)?;
        let count = usize::from(u16::from_le_bytes([h[2], h[3]]));
        let stride = usize::from(u16::from_le_bytes([h[4], h[5]]));
        *at += FAST_GROUP_HEADER_LEN;
        let dsts = s.get(*at..*at + 2 * count)?;
        *at += 2 * count + 4 * count * stride;
        groups.push(GroupInfo {
            bits: h[0],
            accumulate: h[1] & FLAG_ACCUMULATE != 0,
            channels: dsts
                .chunks_exact(2)
                .map(|d| u16::from_le_bytes([d[0], d[1]]))
                .collect(),
        });
    }
    Some(groups)
}

/// Reads the sets of an index section in the fast layout (SPEC.md §4.6)
/// that the decoder validated; `table_entries` counts its `i32` entries.
pub fn inspect_fast(section: &[u8]) -> Option<SectionInfo> {
    let key_interval = u16::from_le_bytes(section.get(0..2)?.try_into().ok()?);
    let mut at = 4;
    let start = at;
    let key = read_fast_set(section, &mut at)?;
    let delta = if key_interval > 0 {
        read_fast_set(section, &mut at)?
    } else {
        Vec::new()
    };
    let sets = at - start;
    let dst_bytes: usize = key
        .iter()
        .chain(&delta)
        .map(|g| FAST_GROUP_HEADER_LEN + 2 * g.channels.len())
        .sum();
    let header_bytes = 2 + if key_interval > 0 { 2 } else { 0 };
    Some(SectionInfo {
        key_interval,
        table_entries: ((sets - dst_bytes - header_bytes) / 4) as u32,
        key,
        delta,
        payload_bytes: section.len().saturating_sub(at),
    })
}

/// One channel's coding as stored in a section (for `mocap info`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DescriptorInfo {
    /// Bits per key-frame index.
    pub key_bits: u8,
    /// Bits per delta-frame index; `None` when delta frames leave the
    /// channel unchanged (it is absent from the delta set).
    pub delta_bits: Option<u8>,
    /// True if delta frames accumulate.
    pub accumulate: bool,
    /// Key-set entries of the channel: more than 1 for key frames in
    /// levels (SPEC.md §4.5).
    pub key_levels: u8,
}

impl SectionInfo {
    /// Per channel (`n` channels): how key and delta frames code it.
    pub fn per_channel(&self, n: usize) -> Vec<DescriptorInfo> {
        let mut out = vec![
            DescriptorInfo {
                key_bits: 0,
                delta_bits: None,
                accumulate: false,
                key_levels: 0,
            };
            n
        ];
        for g in &self.key {
            for &c in &g.channels {
                if let Some(d) = out.get_mut(usize::from(c)) {
                    d.key_bits += g.bits;
                    d.key_levels = d.key_levels.saturating_add(1);
                }
            }
        }
        for g in &self.delta {
            for &c in &g.channels {
                if let Some(d) = out.get_mut(usize::from(c)) {
                    d.delta_bits = Some(g.bits);
                    d.accumulate = g.accumulate;
                }
            }
        }
        if self.key_interval == 0 {
            for d in &mut out {
                d.delta_bits = Some(d.key_bits);
            }
        }
        out
    }

    /// The lines `mocap info` prints for the section of a clip with this
    /// `header`; with `channels`, one line per channel.
    pub fn describe(&self, header: &mocap_decoder::Header<'_>, channels: bool) -> String {
        let chans = self.per_channel(header.channel_count());
        let n = chans.len().max(1);
        let key: u32 = chans.iter().map(|c| u32::from(c.key_bits)).sum();
        let delta: u32 = chans
            .iter()
            .map(|c| u32::from(c.delta_bits.unwrap_or(0)))
            .sum();
        let unchanged = chans.iter().filter(|c| c.delta_bits.is_none()).count();
        let deltas = chans.iter().filter(|c| c.accumulate).count();
        let mut s = format!(
            "  index codec: key interval {}, table {} entries, payload {} bytes, {} key groups, {} delta groups\n  bits per frame: key {key} ({:.2}/channel), delta {delta} ({:.2}/channel)\n  channels: {unchanged} unchanged between key frames, {deltas} delta-coded, {} absolute\n",
            self.key_interval,
            self.table_entries,
            self.payload_bytes,
            self.key.len(),
            self.delta.len(),
            key as f64 / n as f64,
            delta as f64 / n as f64,
            n - unchanged - deltas
        );
        let levelled = chans.iter().filter(|c| c.key_levels > 1).count();
        if levelled > 0 {
            s += &format!("  key frames in levels (SPEC §4.5): {levelled} channels\n");
        }
        if channels {
            for (c, (ch, d)) in header.channels().zip(&chans).enumerate() {
                s += &format!(
                    "  {c:4} {}.{:<10} key {:2} bits{}, delta {} bits{} range [{}, {}]\n",
                    ch.joint_name,
                    ch.kind.name(),
                    d.key_bits,
                    if d.key_levels > 1 {
                        format!(" in {} levels", d.key_levels)
                    } else {
                        String::new()
                    },
                    d.delta_bits.map_or("-".to_string(), |b| format!("{b:2}")),
                    if d.accumulate { " (acc)" } else { "" },
                    ch.min,
                    ch.max
                );
            }
        }
        s
    }
}
