//! The `pattern` codec (SPEC.md §11): motion pattern indexing after Gu,
//! Peng & Deng (CGF 2008; METHODS.md §4).
//!
//! 1. **Hierarchy**: the channels are split into body-part nodes — the
//!    root's translations and heading alone, then one node per limb (the
//!    `pca-spline` codec's groups, [`crate::codec::pca_spline::pca_groups`]:
//!    chains of joints between branchings from the skeleton's topology, so
//!    any rig works). A node's rotation channels are the joints' local
//!    rotations, relative to the parent joint by construction.
//! 2. **Segmentation** per node ([`segment`], Algorithm 1), weighted by the
//!    inverse of each channel's tolerance (tighter joints cut sooner).
//! 3. **Patterns** per node ([`cluster`]): time normalisation to the mean
//!    segment length, adaptive k-means growing K until every segment is
//!    within the threshold, then each group's pattern at the fewest samples
//!    that play all its members within tolerance; each segment is a
//!    (pattern, length) pair.
//!
//! Every segment is within [`Accept`] of its pattern by construction (the
//! encoder plays every segment exactly as the decoder does); the search
//! around it proves the bound by decoding.

pub mod cluster;
pub mod lists;
pub mod segment;

use mocap_decoder::consts;

use super::CodecError;
pub use cluster::Accept;
use cluster::{NodeInput, NodePatterns};
use segment::SegmentParams;

/// The body-part hierarchy's nodes: the `pca-spline` codec's limb groups
/// (chains of joints between branchings, from the topology), with the
/// root's channels that group keeps alone (translations, heading) joined
/// into one root node: a node costs a segment search per frame, so a node
/// of one channel is the dearest per channel.
pub fn nodes(m: &crate::motion::Motion) -> Vec<Vec<usize>> {
    let joint_of = m.skeleton.channel_joints();
    let is_root = |c: usize| m.skeleton.joints[joint_of[c]].parent.is_none();
    let mut root = Vec::new();
    let mut out = Vec::new();
    for g in crate::codec::pca_spline::pca_groups(m, 9) {
        if g.len() == 1 && is_root(g[0]) {
            root.extend(g);
        } else {
            out.push(g);
        }
    }
    if !root.is_empty() {
        out.insert(0, root);
    }
    out
}

/// The body-part nodes with `given` nodes first, each a list of joint
/// names (a show file's `pattern_nodes`, `mocap encode --pattern-nodes`):
/// each given node holds its joints' channels, and the channels of the
/// joints in none keep [`nodes`]' limbs (less the given joints). Joint
/// names match exactly, else ignoring case. Empty `given`: [`nodes`].
pub fn nodes_with(
    m: &crate::motion::Motion,
    given: &[Vec<String>],
) -> Result<Vec<Vec<usize>>, CodecError> {
    if given.is_empty() {
        return Ok(nodes(m));
    }
    let joints = &m.skeleton.joints;
    let joint_of = m.skeleton.channel_joints();
    let has_channels = |j: usize| joint_of.contains(&j);
    let find = |name: &str| {
        let named = |f: &dyn Fn(&str) -> bool| {
            (0..joints.len()).find(|&j| has_channels(j) && f(&joints[j].name))
        };
        named(&|n| n == name).or_else(|| named(&|n| n.eq_ignore_ascii_case(name)))
    };
    let mut node_of_joint: Vec<Option<usize>> = vec![None; joints.len()];
    for (k, names) in given.iter().enumerate() {
        for name in names {
            let j = find(name).ok_or_else(|| CodecError::PatternNodeJoint {
                node: k,
                joint: name.clone(),
                known: (0..joints.len())
                    .filter(|&j| has_channels(j))
                    .map(|j| joints[j].name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })?;
            match node_of_joint[j] {
                Some(first) if first != k => {
                    return Err(CodecError::PatternNodeTwice {
                        joint: joints[j].name.clone(),
                        first,
                        second: k,
                    })
                }
                _ => node_of_joint[j] = Some(k),
            }
        }
    }
    let mut out: Vec<Vec<usize>> = vec![Vec::new(); given.len()];
    for (c, &j) in joint_of.iter().enumerate() {
        if let Some(k) = node_of_joint[j] {
            out[k].push(c);
        }
    }
    for limb in nodes(m) {
        let rest: Vec<usize> = limb
            .into_iter()
            .filter(|&c| node_of_joint[joint_of[c]].is_none())
            .collect();
        if !rest.is_empty() {
            out.push(rest);
        }
    }
    out.retain(|n| !n.is_empty());
    Ok(out)
}

/// How a `pattern` clip's records are stored (SPEC.md §11.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Layout {
    /// Bit-packed columns (§11.3c, layout 2): the smallest.
    #[default]
    Packed,
    /// Columns of whole-byte codes (§11.3b, layout 1): a quarter fewer
    /// decode instructions on a Cortex-M3, 14–28 % more bytes
    /// (BENCHMARKS.md §11).
    Columns,
}

impl std::str::FromStr for Layout {
    type Err = String;
    fn from_str(s: &str) -> Result<Layout, String> {
        match s {
            "packed" => Ok(Layout::Packed),
            "columns" => Ok(Layout::Columns),
            _ => Err(format!(
                "unknown pattern layout '{s}' (expected packed, the smallest, or columns, the fastest to decode)"
            )),
        }
    }
}

impl Layout {
    /// Its `layout` byte.
    pub fn byte(self) -> u8 {
        match self {
            Layout::Packed => mocap_decoder::pattern::LAYOUT_PACKED,
            Layout::Columns => mocap_decoder::pattern::LAYOUT_COLUMNS,
        }
    }
}

/// The `pattern` codec's settings (`EncodeOptions::pattern`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PatternOptions {
    /// Body-part nodes, each a list of joint names ([`nodes_with`]; empty:
    /// the skeleton's limbs).
    pub nodes: Vec<Vec<String>>,
    /// How the records are stored.
    pub layout: Layout,
    /// Segments per block of coded segment lists, as a power of two
    /// (§11.1b; `None`: [`lists::BLOCK_BITS`]): a seek decodes up to a
    /// block, each block costs about 14 bytes.
    pub block_bits: Option<u8>,
}

/// How close a segment must be to its pattern under `bound`: strict under
/// an angle bound (every value within its tolerance), relaxed under a
/// bound on joint positions alone ([`Accept::POSITIONAL`]).
pub fn accept_for(bound: &crate::encode::Bound) -> Accept {
    if bound.angle_deg.is_some() {
        Accept::STRICT
    } else {
        Accept::POSITIONAL
    }
}

/// A coded clip: the section and what the decoder will play.
#[derive(Clone, Debug)]
pub struct Encoded {
    /// The codec section (§11.1), its database inside.
    pub section: Vec<u8>,
    /// The decoded values, `[channel][frame]`.
    pub decoded: Vec<Vec<i32>>,
}

/// Several takes coded with one database (a show's clips, §9.2).
#[derive(Clone, Debug)]
pub struct Shared {
    /// The database (§11.2): the payload of a shared model section.
    pub database: Vec<u8>,
    /// Per take, its codec section (§11.1, flag `SHARED`).
    pub sections: Vec<Vec<u8>>,
    /// Per take, the decoded values, `[channel][frame]`.
    pub decoded: Vec<Vec<Vec<i32>>>,
}

/// Codes `values` (`[channel][frame]`) at tolerances `tol` per channel
/// (each segment within `accept` of its pattern), with the channels split
/// into `nodes`, at `fps` frames per second; the database in the section.
pub fn encode(
    values: &[Vec<i32>],
    tol: &[i64],
    accept: Accept,
    nodes: &[Vec<usize>],
    fps: f64,
    store: &PatternOptions,
) -> Result<Encoded, CodecError> {
    let mut shared = encode_shared(&[values], tol, accept, nodes, fps, store)?;
    let segments = shared.sections.pop().unwrap_or_default();
    Ok(Encoded {
        section: with_database(&shared.database, &segments),
        decoded: shared.decoded.pop().unwrap_or_default(),
    })
}

/// A clip's section with `database` inside (§11.1, flags 0), from its
/// section `shared` that reads it from a model section (flag `SHARED`):
/// the same segment lists, the same decoded values.
pub fn with_database(database: &[u8], shared: &[u8]) -> Vec<u8> {
    let flags = shared.first().copied().unwrap_or(0);
    let mut section = vec![flags & !mocap_decoder::pattern::FLAG_SHARED];
    section.extend(database);
    section.extend(shared.get(1..).unwrap_or(&[]));
    section
}

/// Codes several takes of the same channels (`[take][channel][frame]`)
/// with one database: each node's segments of every take are clustered
/// together, so a movement repeated in another take costs a reference.
pub fn encode_shared(
    takes: &[&[Vec<i32>]],
    tol: &[i64],
    accept: Accept,
    nodes: &[Vec<usize>],
    fps: f64,
    store: &PatternOptions,
) -> Result<Shared, CodecError> {
    let layout = store.layout;
    let lengths: Vec<usize> = takes
        .iter()
        .map(|t| t.first().map_or(0, Vec::len))
        .collect();
    if takes.is_empty() || lengths.contains(&0) {
        return Err(CodecError::NoFrames);
    }
    if nodes.is_empty() || nodes.len() > mocap_decoder::pattern::MAX_NODES {
        return Err(CodecError::PatternNodes(nodes.len()));
    }
    let channels = takes[0].len();
    // The takes end to end; no segment crosses from one to the next.
    let joined: Vec<Vec<i32>> = (0..channels)
        .map(|c| takes.iter().flat_map(|t| t[c].iter().copied()).collect())
        .collect();
    let firsts: Vec<usize> = lengths
        .iter()
        .scan(0, |at, &n| {
            let first = *at;
            *at += n;
            Some(first)
        })
        .collect();
    let params = SegmentParams::at_rate(fps);
    let mut decoded = vec![vec![Vec::new(); channels]; takes.len()];
    let mut database = vec![nodes.len() as u8, layout.byte()];
    let mut node_lists: Vec<Vec<lists::NodeList>> = vec![Vec::new(); takes.len()];
    for channels in nodes {
        let mut channels = channels.clone();
        channels.sort_unstable();
        let input = NodeInput {
            values: channels.iter().map(|&c| joined[c].as_slice()).collect(),
            tol: channels.iter().map(|&c| tol[c].max(0)).collect(),
            accept,
        };
        // Segments of each take (Algorithm 1 on the take alone).
        let mut spans = Vec::new();
        let mut per_take = Vec::new();
        for (&first, &n) in firsts.iter().zip(&lengths) {
            let scaled: Vec<Vec<f64>> = input
                .values
                .iter()
                .zip(&input.tol)
                .map(|(x, &t)| {
                    let k = 1.0 / t.max(1) as f64;
                    x[first..first + n]
                        .iter()
                        .map(|&v| f64::from(v) * k)
                        .collect()
                })
                .collect();
            let starts = segment::segment(&scaled, n, &params);
            per_take.push((spans.len(), starts.len()));
            for (i, &a) in starts.iter().enumerate() {
                let end = starts.get(i + 1).copied().unwrap_or(n);
                spans.push((first + a, end - a));
            }
        }
        let np = cluster::patterns(&input, &spans).in_order_of_use();
        let most = per_take.iter().map(|p| p.1).max().unwrap_or(0);
        if most > usize::from(u16::MAX) || np.patterns.len() > usize::from(u16::MAX) {
            return Err(CodecError::PatternTooMany {
                segments: most,
                patterns: np.patterns.len(),
            });
        }
        write_node(&mut database, &channels, &np, layout);
        for (take, &(from, count)) in per_take.iter().enumerate() {
            let first = firsts[take];
            let (starts, patterns) = spans[from..from + count]
                .iter()
                .zip(&np.of_segment[from..from + count])
                .map(|(&(a, _), &p)| ((a - first) as u32, p as u16))
                .unzip();
            node_lists[take].push(lists::NodeList { starts, patterns });
            for (i, &c) in channels.iter().enumerate() {
                decoded[take][c] = (from..from + count)
                    .flat_map(|s| {
                        let (_, n) = spans[s];
                        let p = &np.patterns[np.of_segment[s]];
                        (0..n).map(move |t| p.play(i, t, n))
                    })
                    .collect();
            }
        }
    }
    let sections = node_lists
        .iter()
        .zip(&lengths)
        .map(|(l, &n)| {
            let bits = store.block_bits.unwrap_or(lists::BLOCK_BITS);
            let (flag, bytes) = lists::write(l, n as u32, bits);
            let mut section = vec![mocap_decoder::pattern::FLAG_SHARED | flag];
            section.extend(bytes);
            section
        })
        .collect();
    Ok(Shared {
        database,
        sections,
        decoded,
    })
}

/// Appends a database node record (§11.2): the channels, in layout 2
/// their shifts (one per channel: every pattern steps a channel alike),
/// the pattern offsets and records, in layout 2 the 3 closing bytes.
fn write_node(out: &mut Vec<u8>, channels: &[usize], np: &NodePatterns, layout: Layout) {
    let records: Vec<Vec<u8>> = np
        .patterns
        .iter()
        .map(|p| p.record(layout.byte()))
        .collect();
    let packed = layout == Layout::Packed;
    let tail = if packed {
        mocap_decoder::pattern::PACKED_TAIL
    } else {
        0
    };
    let data_len: usize = records.iter().map(Vec::len).sum::<usize>() + tail;
    out.extend((channels.len() as u16).to_le_bytes());
    out.extend((np.patterns.len() as u16).to_le_bytes());
    out.extend((data_len as u32).to_le_bytes());
    for &c in channels {
        out.extend((c as u16).to_le_bytes());
    }
    if packed {
        let first = np.patterns.first();
        for i in 0..channels.len() {
            let shift = first.map_or(0, |p| p.heads[i].1);
            debug_assert!(np.patterns.iter().all(|p| p.heads[i].1 == shift));
            out.push(shift);
        }
    }
    let mut at = 0u32;
    for r in &records {
        out.extend(at.to_le_bytes());
        at += r.len() as u32;
    }
    for r in records {
        out.extend(r);
    }
    out.extend(std::iter::repeat_n(0u8, tail));
}

/// What `mocap info` shows of a `pattern` section.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SectionInfo {
    /// Per node: channels, segments, patterns, pattern samples (all
    /// channels), bytes of its database record.
    pub nodes: Vec<[usize; 5]>,
    /// Bytes of the database.
    pub database_len: usize,
    /// Its records' layout (§11.2): 0 rows, 1 columns.
    pub layout: u8,
    /// Layouts 1 and 2: bytes the codes take in whole bytes per code
    /// (layout 1).
    pub code_bytes: usize,
    /// Layouts 1 and 2: bytes the codes take bit-packed, each channel of a
    /// pattern at its largest code's bit length (layout 2, without its
    /// columns' padding to whole bytes).
    pub packed_bytes: usize,
    /// Bytes of the segment lists (with their tables if coded).
    pub lists_bytes: usize,
    /// Whether the lists are entropy coded (§11.1b).
    pub coded_lists: bool,
    /// Coded lists: their bytes taken apart, beside the values' entropy.
    pub lists: Option<lists::Report>,
}

/// Reads the sizes of a `pattern` section (`None` if it does not parse,
/// or its database is a shared model section: see [`inspect_database`]).
pub fn inspect(section: &[u8]) -> Option<SectionInfo> {
    let flags = *section.first()?;
    if flags & mocap_decoder::pattern::FLAG_SHARED != 0 {
        return None;
    }
    let mut info = inspect_database(&section[1..])?;
    let lists = section.get(1 + info.database_len..)?;
    info.lists_bytes = lists.len();
    info.coded_lists = flags & mocap_decoder::pattern::FLAG_CODED != 0;
    let mut at = 0;
    let mut tables = Vec::new();
    if info.coded_lists {
        for _ in 0..2 {
            let (t, len) = mocap_decoder::entropy::Table::parse(lists.get(at..)?).ok()?;
            tables.push(t);
            at += len;
        }
    }
    let (mut node_lists, mut frames) = (Vec::new(), 0);
    let bits = lists.get(at + 2).copied().unwrap_or(0);
    for node in &mut info.nodes {
        let (n, len) = if let [lengths, patterns] = tables[..] {
            let mut l = lists::NodeList::default();
            mocap_decoder::pattern::for_each_coded_segment(
                lists,
                at,
                lengths,
                patterns,
                |start, end, p| {
                    l.starts.push(start);
                    l.patterns.push(p as u16);
                    frames = end;
                },
            )?;
            node_lists.push(l);
            mocap_decoder::pattern::coded_extent(lists, at)?
        } else {
            let n = usize::from(u16::from_le_bytes(lists.get(at..at + 2)?.try_into().ok()?));
            (n, 2 + n * 6)
        };
        node[1] = n;
        at += len;
    }
    if info.coded_lists {
        info.lists = lists::report(&node_lists, frames, bits).ok();
    }
    (at == lists.len()).then_some(info)
}

/// Reads the sizes of a pattern database (§11.2): a shared model section,
/// or the start of a section's bytes after its flags.
pub fn inspect_database(db: &[u8]) -> Option<SectionInfo> {
    let u16_at = |at: usize| -> Option<usize> {
        Some(usize::from(u16::from_le_bytes(
            db.get(at..at + 2)?.try_into().ok()?,
        )))
    };
    let u32_at = |at: usize| -> Option<usize> {
        Some(u32::from_le_bytes(db.get(at..at + 4)?.try_into().ok()?) as usize)
    };
    let n = usize::from(*db.first()?);
    let mut at = 2;
    let mut nodes = Vec::new();
    let (mut code_bytes, mut packed_bits) = (0usize, 0usize);
    for _ in 0..n {
        let (nc, patterns, data) = (u16_at(at)?, u16_at(at + 2)?, u32_at(at + 4)?);
        let packed = db.get(1) == Some(&mocap_decoder::pattern::LAYOUT_PACKED);
        let offsets = at + 8 + nc * 2 + if packed { nc } else { 0 };
        let data_at = offsets + patterns * 4;
        let mut samples = 0;
        for p in 0..patterns {
            let rec = data_at + u32_at(offsets + p * 4)?;
            let len = u16_at(rec)?;
            samples += len * nc;
            if db.get(1) != Some(&mocap_decoder::pattern::LAYOUT_ROWS) {
                let (c, b) = column_code_sizes(db.get(rec + 2..)?, nc, len, packed)?;
                code_bytes += c;
                packed_bits += b;
            }
        }
        let end = data_at + data;
        nodes.push([nc, 0, patterns, samples, end - at]);
        at = end;
    }
    Some(SectionInfo {
        nodes,
        database_len: at,
        layout: *db.get(1)?,
        code_bytes,
        packed_bytes: packed_bits.div_ceil(8),
        ..SectionInfo::default()
    })
}

/// A layout-1 or -2 record's channels (SPEC.md §11.3b, §11.3c; `rec` from
/// its first head on): the bytes their codes take in whole bytes (layout
/// 1's widths 0, 1, 2, 4), and the bits they take bit-packed, each channel
/// of the pattern at its largest code's bit length (layout 2).
fn column_code_sizes(rec: &[u8], nc: usize, len: usize, packed: bool) -> Option<(usize, usize)> {
    let (mut at, mut bytes, mut bits) = (0usize, 0usize, 0usize);
    for _ in 0..nc {
        let h = *rec.get(at)?;
        let (b, stored, wide) = if packed {
            let b = usize::from(h & 63);
            let wide = h & mocap_decoder::pattern::WIDE_BASE_2 != 0;
            (b, (len * b).div_ceil(8), wide)
        } else {
            let w = [0usize, 1, 2, 4][usize::from(h >> 5 & 3)];
            let codes = rec.get(at + if h & 0x80 == 0 { 3 } else { 5 }..)?;
            let largest = (0..len)
                .map(|k| {
                    codes[k * w..k * w + w]
                        .iter()
                        .rev()
                        .fold(0u32, |v, &b| v << 8 | u32::from(b))
                })
                .max()
                .unwrap_or(0);
            (
                32 - largest.leading_zeros() as usize,
                len * w,
                h & 0x80 != 0,
            )
        };
        let whole = match b {
            0 => 0,
            1..=8 => 1,
            9..=16 => 2,
            _ => 4,
        };
        bytes += len * whole;
        bits += len * b;
        at += if wide { 5 } else { 3 } + stored;
    }
    Some((bytes, bits))
}

impl SectionInfo {
    /// The lines `mocap info` prints.
    pub fn describe(&self) -> String {
        let sum = |i: usize| self.nodes.iter().map(|n| n[i]).sum::<usize>();
        let mut s = format!(
            "  nodes: {}, segments: {}, patterns: {}, pattern samples: {}, database {} B ({})\n",
            self.nodes.len(),
            sum(1),
            sum(2),
            sum(3),
            self.database_len,
            ["rows", "columns", "bit-packed columns"]
                .get(usize::from(self.layout))
                .unwrap_or(&"?")
        );
        match &self.lists {
            Some(r) => {
                s += &format!(
                    "  segment lists: {} B rANS-coded (plain {} B): tables {} B, counts and block \
                     index {} B, streams {} B; the values' Shannon entropy: lengths {:.0} B, \
                     patterns {:.0} B\n",
                    r.coded,
                    r.plain,
                    r.tables,
                    r.index,
                    r.streams,
                    r.shannon_lengths,
                    r.shannon_patterns
                );
            }
            None if self.lists_bytes > 0 => {
                s += &format!("  segment lists: {} B (plain)\n", self.lists_bytes);
            }
            None => {}
        }
        if self.code_bytes > 0 {
            s += &format!(
                "  codes: {} B bit-packed at each pattern's channel widths, {} B in whole bytes\n",
                self.packed_bytes, self.code_bytes
            );
        }
        for (i, n) in self.nodes.iter().enumerate() {
            s += &format!(
                "  node {i}: {} channels, {} segments, {} patterns, {} samples, {} B\n",
                n[0], n[1], n[2], n[3], n[4]
            );
        }
        s
    }
}

/// The section id.
pub const SECTION_ID: u8 = consts::SECTION_CODEC_PATTERN;
