//! A reference decoder written from SPEC.md's prose alone — the container
//! (§2), the header in both forms (§3.1, §3.4), `index` (§4), `pca-spline`
//! (§5), `predictive` (§5b), `pattern` (§11) and `rma` (§12) — sharing no code with `mocap-decoder` or
//! `mocap-encoder`. The
//! spec examples are decoded with it and with the real decoder; both must
//! give the values SPEC.md states. Written for clarity, not speed: it
//! panics on anything malformed (the examples are valid clips).

/// A parsed clip: what the codecs need of the header, and the codec section.
pub struct Clip {
    pub frame_time_ns: u32,
    pub frame_count: u32,
    pub channels: usize,
    pub codec: Codec,
}

pub enum Codec {
    Index(Index),
    IndexFast(IndexFast),
    PcaSpline(Pca),
    Predictive(Predictive),
    Pattern(Pattern),
    Rma(Rma),
}

/// §2 (§9.1 for `version` 2): preamble, section table, CRC; the sections
/// in table order.
fn sections(bytes: &[u8], version: u8) -> Vec<(u8, &[u8])> {
    assert_eq!(&bytes[..4], b"MOCB", "magic");
    assert_eq!(bytes[4..6], [version, 0], "version {version}, flags 0");
    let n = usize::from(u16::from_le_bytes([bytes[6], bytes[7]]));
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    assert_eq!(
        u32::from_le_bytes(crc.try_into().unwrap()),
        crc32(body),
        "CRC"
    );
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    (0..n)
        .map(|e| {
            let entry = 8 + 12 * e;
            assert_eq!(bytes[entry + 1..entry + 4], [0, 0, 0], "reserved");
            let (offset, len) = (u32_at(entry + 4), u32_at(entry + 8));
            (bytes[entry], &bytes[offset..offset + len])
        })
        .collect()
}

/// §2: preamble, section table, CRC; §3.1 / §3.4: the header's counts.
pub fn parse(bytes: &[u8]) -> Clip {
    let mut header = None;
    let mut codec = None;
    for (id, section) in sections(bytes, 1) {
        match id {
            0x01 | 0x02 => header = Some((id, section)),
            0x10..=0x15 => codec = Some((id, section)),
            id => panic!("the reference reads no section {id:#04x}"),
        }
    }
    let (header_id, header) = header.expect("a header");
    let (frame_time_ns, frame_count, channels) = header_counts(header_id, header);
    let (id, section) = codec.expect("a codec section");
    let codec = match id {
        0x10 => Codec::Index(Index::parse(section, channels)),
        0x13 => Codec::IndexFast(IndexFast::parse(section, channels)),
        0x11 => Codec::PcaSpline(Pca::parse(section, channels)),
        0x14 => Codec::Pattern(Pattern::parse(section, None, channels)),
        0x15 => Codec::Rma(Rma::parse(section, channels)),
        _ => Codec::Predictive(Predictive::parse(section, channels, frame_count)),
    };
    Clip {
        frame_time_ns,
        frame_count,
        channels,
        codec,
    }
}

impl Clip {
    /// Every frame, `[frame][channel]`.
    pub fn frames(&self) -> Vec<Vec<i32>> {
        match &self.codec {
            Codec::PcaSpline(p) => (0..self.frame_count)
                .map(|i| p.pose(u64::from(i) << 16, self.channels))
                .collect(),
            Codec::Predictive(p) => p.decode(self.channels, self.frame_count),
            Codec::Index(x) => x.decode(self.channels, self.frame_count),
            Codec::IndexFast(x) => x.decode(self.channels, self.frame_count),
            Codec::Pattern(p) => (0..self.frame_count)
                .map(|f| p.frame(f, self.frame_count, self.channels))
                .collect(),
            Codec::Rma(r) => (0..self.frame_count)
                .map(|i| r.pose(u64::from(i) << 16, self.channels, self.frame_count))
                .collect(),
        }
    }

    /// `sample_at(t_us)`: §5.4's position for `pca-spline`, §6's linear
    /// interpolation for `predictive`.
    pub fn sample_at(&self, t_us: u64) -> Vec<i32> {
        let ns = t_us.saturating_mul(1000);
        let ft = u64::from(self.frame_time_ns);
        let i = ns / ft;
        let frac = ((ns % ft) << 16) / ft;
        let last = u64::from(self.frame_count - 1);
        let pos = if i >= last {
            last << 16
        } else {
            (i << 16) | frac
        };
        match &self.codec {
            Codec::PcaSpline(p) => p.pose(pos, self.channels),
            Codec::Rma(r) => r.pose(pos, self.channels, self.frame_count),
            Codec::Predictive(_) | Codec::Index(_) | Codec::IndexFast(_) | Codec::Pattern(_) => {
                let frames = self.frames();
                if i >= last {
                    return frames[last as usize].clone();
                }
                let (a, b) = (&frames[i as usize], &frames[i as usize + 1]);
                a.iter()
                    .zip(b)
                    .map(|(&a, &b)| {
                        let d = i64::from(b.wrapping_sub(a));
                        a.wrapping_add(((d * frac as i64) >> 16) as i32)
                    })
                    .collect()
            }
        }
    }
}

/// §12: added channels, repeated clips, a `pca-spline` body.
pub struct Rma {
    pub added: Vec<usize>,
    pub clips: Vec<RepeatedClip>,
    pub body: Pca,
}

pub struct RepeatedClip {
    pub start: u32,
    pub last: u32,
    /// `(t_i, r_i)`: frames from `start`, reference in 1/256 frames.
    pub knots: Vec<(u32, i64)>,
}

impl Rma {
    /// §12.1, §12.2.
    pub fn parse(section: &[u8], channels: usize) -> Rma {
        let mut r = Reader::new(section);
        assert_eq!(r.u8(), 0, "form 0");
        let mut added = Vec::new();
        let mut next = 0usize;
        for _ in 0..r.varint() {
            let s = next + r.varint() as usize;
            let len = r.varint() as usize;
            assert!(len >= 1 && s + len <= channels);
            added.extend(s..s + len);
            next = s + len;
        }
        let mut clips = Vec::new();
        let mut after = 0u32;
        for _ in 0..r.varint() {
            let start = after + r.varint();
            let last = start + r.varint();
            let m = r.varint();
            assert!(m >= 1);
            let (mut t, mut v) = (0u32, i64::from(start) * 256);
            let knots = (0..m)
                .map(|i| {
                    let dt = r.varint();
                    assert!(if i == 0 {
                        dt == 0
                    } else {
                        (1..1 << 15).contains(&dt)
                    });
                    t += dt;
                    assert!(t <= last - start, "knot in the clip");
                    v += i64::from(r.zigzag());
                    assert!(i32::try_from(v).is_ok());
                    (t, v)
                })
                .collect();
            clips.push(RepeatedClip { start, last, knots });
            after = last + 1;
        }
        let rest = r.take(section.len() - r.pos);
        Rma {
            added,
            clips,
            body: Pca::parse(rest, channels),
        }
    }

    /// §12.3: the pose at `pos` (frames, 16.16).
    pub fn pose(&self, pos: u64, channels: usize, frames: u32) -> Vec<i32> {
        let mut out = self.body.pose(pos, channels);
        let f = pos >> 16;
        let phi = (pos & 0xFFFF) as i64;
        for c in &self.clips {
            let (start, last) = (u64::from(c.start), u64::from(c.last));
            let w = if (start <= f && f < last) || (f == last && phi == 0) {
                65536
            } else if f == last {
                65536 - phi
            } else if f + 1 == start {
                phi
            } else {
                0
            };
            if w == 0 {
                continue;
            }
            // 1. Ref: linear between the knots around rel, the last knot after them.
            let rel = (pos as i64 - ((start as i64) << 16)).max(0);
            let (t_last, r_last) = *c.knots.last().unwrap();
            let reference = if c.knots.len() == 1 || rel >= i64::from(t_last) << 16 {
                r_last
            } else {
                let i = (1..c.knots.len())
                    .find(|&i| i64::from(c.knots[i].0) << 16 > rel)
                    .unwrap();
                let (t0, r0) = c.knots[i - 1];
                let (t1, r1) = c.knots[i];
                let t0 = i64::from(t0) << 16;
                r0 + ((r1 - r0) * (rel - t0)).div_euclid((i64::from(t1) << 16) - t0)
            };
            let at = (reference << 8).clamp(0, i64::from(frames - 1) << 16);
            let primary = self.body.pose(at as u64, channels);
            for &k in &self.added {
                out[k] = out[k].wrapping_add(((i64::from(primary[k]) * w) >> 16) as i32);
            }
        }
        out
    }
}

/// CRC-32/ISO-HDLC, bit by bit (§2.3).
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = u32::MAX;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Bytes in order: postcard varints and zigzag (§3.1), little-endian fixed
/// widths, and LSB-first bit fields (§4.4).
pub struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes, pos: 0 }
    }

    pub fn done(&self) -> bool {
        self.pos == self.bytes.len()
    }

    pub fn u8(&mut self) -> u8 {
        let b = self.bytes[self.pos];
        self.pos += 1;
        b
    }

    pub fn take(&mut self, n: usize) -> &'a [u8] {
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        s
    }

    pub fn varint(&mut self) -> u32 {
        let mut v: u64 = 0;
        for i in 0..5 {
            let b = self.u8();
            v |= u64::from(b & 0x7F) << (7 * i);
            if b & 0x80 == 0 {
                return u32::try_from(v).expect("varint fits 32 bits");
            }
        }
        panic!("varint longer than 5 bytes")
    }

    pub fn zigzag(&mut self) -> i32 {
        let v = self.varint();
        ((v >> 1) as i32) ^ -((v & 1) as i32)
    }
}

/// LSB-first bits (§4.4): bit `p` is bit `p mod 8` of byte `p div 8`, a
/// field's bit 0 first.
struct Bits<'a> {
    bytes: &'a [u8],
    bit: usize,
}

impl Bits<'_> {
    fn read(&mut self, width: u32) -> u32 {
        let mut v = 0u32;
        for i in 0..width {
            let p = self.bit + i as usize;
            v |= u32::from((self.bytes[p / 8] >> (p % 8)) & 1) << i;
        }
        self.bit += width as usize;
        v
    }
}

// ---------------------------------------------------------------- §10

/// §10.2: a table's counts (they add up to `M = 2^n`), read from the start
/// of `r`.
pub struct RansTable {
    pub n: u32,
    pub counts: Vec<u32>,
}

impl RansTable {
    pub fn read(r: &mut Reader<'_>) -> RansTable {
        let head = r.u8();
        let (n, big_w) = (u32::from(head & 15), u32::from(head >> 4));
        let a = r.varint() as usize;
        assert!((1..=65_536).contains(&a), "alphabet");
        let rest = &r.bytes[r.pos..];
        let mut bits = Bits {
            bytes: rest,
            bit: 0,
        };
        let mut left = 1u32 << n;
        let mut counts = Vec::new();
        for _ in 0..a - 1 {
            let width = big_w.min(32 - left.leading_zeros());
            let f = bits.read(width);
            assert!(f <= left, "a count above what is left");
            left -= f;
            counts.push(f);
        }
        counts.push(left);
        let used = bits.bit.div_ceil(8);
        assert_eq!(bits.read((used * 8 - bits.bit) as u32), 0, "padding");
        r.take(used);
        RansTable { n, counts }
    }
}

/// §10.3: a stream being decoded (one block).
pub struct RansStream<'a> {
    x: u32,
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> RansStream<'a> {
    pub fn new(bytes: &'a [u8]) -> RansStream<'a> {
        let x = u32::from_le_bytes(bytes[..4].try_into().unwrap());
        assert!((1 << 23..1 << 31).contains(&x), "x0 in range");
        RansStream { x, bytes, pos: 4 }
    }

    fn renormalise(&mut self) {
        while self.x < 1 << 23 {
            let b = self.bytes.get(self.pos).copied().unwrap_or(0);
            self.pos += 1;
            self.x = (self.x << 8) | u32::from(b);
        }
    }

    pub fn symbol(&mut self, t: &RansTable) -> u32 {
        let slot = self.x & ((1 << t.n) - 1);
        let mut cum = 0;
        for (s, &f) in t.counts.iter().enumerate() {
            if slot < cum + f {
                self.x = f * (self.x >> t.n) + slot - cum;
                self.renormalise();
                return s as u32;
            }
            cum += f;
        }
        unreachable!("the counts add up to M")
    }

    pub fn raw(&mut self, k: u32) -> u32 {
        let v = self.x & ((1 << k) - 1);
        self.x >>= k;
        self.renormalise();
        v
    }

    /// §10.4: an escaped value.
    pub fn value(&mut self, t: &RansTable) -> u32 {
        let e = t.counts.len() as u32 - 1;
        let s = self.symbol(t);
        if s < e {
            return s;
        }
        let k = self.raw(5);
        let r = if k > 16 {
            let lo = self.raw(16);
            (self.raw(k - 16) << 16) | lo
        } else {
            self.raw(k)
        };
        e.wrapping_add((1u32 << k) | r).wrapping_sub(1)
    }

    /// Every byte read and the state where the encoder started (§10.5).
    pub fn finished(&self) -> bool {
        self.pos == self.bytes.len() && self.x == 1 << 23
    }
}

// ---------------------------------------------------------------- §3.7

/// §3.7: the missing samples of a marker clip, `[marker][frame]` (true:
/// missing), from a section for `markers` markers of `frames` frames.
/// Panics where a rule of §3.7 is broken.
pub fn missing_samples(section: &[u8], markers: usize, frames: u32) -> Vec<Vec<bool>> {
    let mut r = Reader::new(section);
    assert_eq!(r.varint() as usize, markers, "marker count");
    let mut out = Vec::new();
    for _ in 0..markers {
        let runs = r.varint();
        let mut mask = Vec::new();
        for i in 0..runs {
            let len = r.varint();
            assert!(i == 0 || len > 0, "a run after the first is 0 long");
            mask.extend(std::iter::repeat_n(i % 2 == 1, len as usize));
        }
        if runs == 0 {
            mask = vec![false; frames as usize];
        }
        assert_eq!(mask.len(), frames as usize, "runs add up to the frames");
        out.push(mask);
    }
    assert!(r.done(), "bytes after the last marker");
    out
}

// ---------------------------------------------------------------- §4

#[derive(Debug)]
pub struct Index {
    pub key_interval: u32,
    pub key_set: Vec<IndexGroup>,
    pub delta_set: Vec<IndexGroup>,
    pub pool: Vec<i32>,
    pub payload: Vec<u8>,
}

/// A group of a set: `(bits, shift, accumulate)` and its entries
/// `(channel, table, base)`.
#[derive(Debug)]
pub struct IndexGroup {
    pub bits: u32,
    pub shift: u32,
    pub accumulate: bool,
    pub entries: Vec<(usize, usize, i32)>,
}

impl Index {
    /// §4.1, §4.2.
    pub fn parse(section: &[u8], channels: usize) -> Index {
        let mut r = Reader::new(section);
        let u16_le = |r: &mut Reader<'_>| u16::from_le_bytes([r.u8(), r.u8()]);
        let key_interval = u32::from(u16_le(&mut r));
        assert_eq!(usize::from(u16_le(&mut r)), channels);
        let t = u32::from_le_bytes(r.take(4).try_into().unwrap()) as usize;
        let set = |r: &mut Reader<'_>| -> Vec<IndexGroup> {
            let groups = u16_le(r);
            (0..groups)
                .map(|_| {
                    let bits = u32::from(r.u8());
                    let flags = r.u8();
                    assert!(bits <= 12 && flags & 0x60 == 0 && u32::from(flags & 0x1F) <= 24);
                    let count = u16_le(r);
                    let entries = (0..count)
                        .map(|_| {
                            let channel = usize::from(u16_le(r));
                            let table = usize::from(u16_le(r));
                            let base = i32::from_le_bytes(r.take(4).try_into().unwrap());
                            assert!(channel < channels && table + (1 << bits) <= t);
                            (channel, table, base)
                        })
                        .collect();
                    IndexGroup {
                        bits,
                        shift: u32::from(flags & 0x1F),
                        accumulate: flags & 0x80 != 0,
                        entries,
                    }
                })
                .collect()
        };
        let key_set = set(&mut r);
        // §4.2: at least C entries (levels, §4.5, name a channel again).
        assert!(key_set.iter().map(|g| g.entries.len()).sum::<usize>() >= channels);
        let delta_set = if key_interval > 0 {
            set(&mut r)
        } else {
            Vec::new()
        };
        let pool = (0..t)
            .map(|_| i32::from(i16::from_le_bytes([r.u8(), r.u8()])))
            .collect();
        let payload = r.bytes[r.pos..].to_vec();
        Index {
            key_interval,
            key_set,
            delta_set,
            pool,
            payload,
        }
    }

    /// §4.3, §4.4: every frame, in order.
    pub fn decode(&self, channels: usize, frames: u32) -> Vec<Vec<i32>> {
        let bits_of = |set: &[IndexGroup]| -> usize {
            set.iter().map(|g| g.bits as usize * g.entries.len()).sum()
        };
        let (kb, db) = (bits_of(&self.key_set), bits_of(&self.delta_set));
        let k = self.key_interval as usize;
        let keys = |f: usize| if k == 0 { f } else { f.div_ceil(k) };
        let start = |f: usize| keys(f) * kb + (f - keys(f)) * db;
        assert_eq!(self.payload.len(), start(frames as usize).div_ceil(8));
        let mut bits = Bits {
            bytes: &self.payload,
            bit: 0,
        };
        let mut value = vec![0i32; channels];
        let mut out = Vec::new();
        for f in 0..frames as usize {
            assert_eq!(bits.bit, start(f), "records back to back");
            let key = k == 0 || f % k == 0;
            if key {
                value.fill(0);
            }
            let set = if key { &self.key_set } else { &self.delta_set };
            for g in set {
                for &(c, table, base) in &g.entries {
                    let i = bits.read(g.bits) as usize;
                    let v = base.wrapping_add(self.pool[table + i].wrapping_shl(g.shift));
                    value[c] = if g.accumulate {
                        value[c].wrapping_add(v)
                    } else {
                        v
                    };
                }
            }
            out.push(value.clone());
        }
        out
    }
}

// ---------------------------------------------------------------- §4.6

#[derive(Debug)]
pub struct IndexFast {
    pub key_interval: u32,
    pub key_set: Vec<FastGroup>,
    pub delta_set: Vec<FastGroup>,
    pub payload: Vec<u8>,
}

/// A group of the fast layout: width, accumulate, stride, destinations and
/// `tables[j]` (`S` entries each).
#[derive(Debug)]
pub struct FastGroup {
    pub width: u32,
    pub accumulate: bool,
    pub dsts: Vec<usize>,
    pub tables: Vec<Vec<i32>>,
}

impl IndexFast {
    /// §4.6: the section.
    pub fn parse(section: &[u8], channels: usize) -> IndexFast {
        let mut r = Reader::new(section);
        let u16_le = |r: &mut Reader<'_>| usize::from(u16::from_le_bytes([r.u8(), r.u8()]));
        let key_interval = u16_le(&mut r) as u32;
        assert_eq!(u16_le(&mut r), channels);
        let set = |r: &mut Reader<'_>| -> Vec<FastGroup> {
            (0..u16_le(r))
                .map(|_| {
                    let width = u32::from(r.u8());
                    let flags = r.u8();
                    let (n, stride) = (u16_le(r), u16_le(r));
                    assert!(flags & 0x7F == 0);
                    match width {
                        0 => assert_eq!(stride, 1),
                        1 | 2 | 4 => assert_eq!(stride, 1 << width),
                        8 | 16 => assert!(stride >= 1 && stride <= 1 << width),
                        _ => panic!("width {width}"),
                    }
                    let dsts: Vec<usize> = (0..n).map(|_| u16_le(r)).collect();
                    assert!(dsts.iter().all(|&c| c < channels));
                    let tables = (0..n)
                        .map(|_| {
                            (0..stride)
                                .map(|_| i32::from_le_bytes(r.take(4).try_into().unwrap()))
                                .collect()
                        })
                        .collect();
                    FastGroup {
                        width,
                        accumulate: flags & 0x80 != 0,
                        dsts,
                        tables,
                    }
                })
                .collect()
        };
        let key_set = set(&mut r);
        assert!(key_set.iter().map(|g| g.dsts.len()).sum::<usize>() >= channels);
        let delta_set = if key_interval > 0 {
            set(&mut r)
        } else {
            Vec::new()
        };
        IndexFast {
            key_interval,
            key_set,
            delta_set,
            payload: r.bytes[r.pos..].to_vec(),
        }
    }

    /// §4.6: every frame, in order.
    pub fn decode(&self, channels: usize, frames: u32) -> Vec<Vec<i32>> {
        let block = |g: &FastGroup| (g.dsts.len() * g.width as usize).div_ceil(8);
        let bytes_of = |set: &[FastGroup]| -> usize { set.iter().map(block).sum() };
        let (kb, db) = (bytes_of(&self.key_set), bytes_of(&self.delta_set));
        let k = self.key_interval as usize;
        let keys = |f: usize| if k == 0 { f } else { f.div_ceil(k) };
        let start = |f: usize| keys(f) * kb + (f - keys(f)) * db;
        assert_eq!(self.payload.len(), start(frames as usize));
        let mut value = vec![0i32; channels];
        let mut out = Vec::new();
        for f in 0..frames as usize {
            let key = k == 0 || f % k == 0;
            if key {
                value.fill(0);
            }
            let mut at = start(f);
            for g in if key { &self.key_set } else { &self.delta_set } {
                // Fields LSB first within the group's block.
                let mut bits = Bits {
                    bytes: &self.payload[at..at + block(g)],
                    bit: 0,
                };
                for (j, &c) in g.dsts.iter().enumerate() {
                    let i = bits.read(g.width) as usize;
                    let Some(&v) = g.tables[j].get(i) else {
                        continue;
                    };
                    value[c] = if g.accumulate {
                        value[c].wrapping_add(v)
                    } else {
                        v
                    };
                }
                at += block(g);
            }
            out.push(value.clone());
        }
        out
    }
}

// ---------------------------------------------------------------- §5

#[derive(Debug)]
pub struct Pca {
    pub groups: Vec<Vec<usize>>,
    pub consts: Vec<(usize, i32)>,
    pub segments: Vec<Segment>,
}

#[derive(Debug)]
pub struct Segment {
    pub start: u32,
    pub end: u32,
    pub groups: Vec<Group>,
    /// `(frame relative to start, channel, value)`.
    pub patches: Vec<(u32, usize, i32)>,
}

#[derive(Debug)]
pub struct Group {
    pub k: usize,
    pub ms: u32,
    /// Stored means (before `<< ms`).
    pub mean: Vec<i32>,
    /// `basis[c][j]`.
    pub basis: Vec<Vec<i32>>,
    /// Key times relative to the segment's start.
    pub times: Vec<u32>,
    /// `control[r][j]`: component `j`'s value at key `r`.
    pub control: Vec<Vec<i32>>,
}

impl Pca {
    /// §5.1–§5.3, §5.5.
    pub fn parse(section: &[u8], channels: usize) -> Pca {
        let mut r = Reader::new(section);
        let w = r.u8();
        assert!(w == 1 || w == 2);
        let index = |r: &mut Reader<'_>| -> usize {
            if w == 1 {
                usize::from(r.u8())
            } else {
                usize::from(u16::from_le_bytes([r.u8(), r.u8()]))
            }
        };
        let g = r.varint();
        let groups: Vec<Vec<usize>> = (0..g)
            .map(|_| {
                let n = r.varint();
                (0..n).map(|_| index(&mut r)).collect()
            })
            .collect();
        let z = r.varint() as usize;
        let idx: Vec<usize> = (0..z).map(|_| index(&mut r)).collect();
        let consts: Vec<(usize, i32)> = idx.into_iter().map(|c| (c, r.zigzag())).collect();
        let mut all: Vec<usize> = groups.iter().flatten().copied().collect();
        all.extend(consts.iter().map(|&(c, _)| c));
        all.sort_unstable();
        assert_eq!(all, (0..channels).collect::<Vec<_>>(), "every channel once");
        let s = r.varint();
        let segments = (0..s)
            .map(|_| {
                let start = r.varint();
                let end = r.varint();
                let len = r.varint() as usize;
                let mut body = Reader::new(r.take(len));
                let gs = groups
                    .iter()
                    .map(|g| Group::parse(&mut body, g.len(), end - start))
                    .collect();
                assert!(body.done(), "group records fill the body");
                let len = r.varint() as usize;
                let mut p = Reader::new(r.take(len));
                let mut patches = Vec::new();
                let mut frame = 0;
                while !p.done() {
                    frame += p.varint();
                    let c = index(&mut p);
                    patches.push((frame, c, p.zigzag()));
                }
                Segment {
                    start,
                    end,
                    groups: gs,
                    patches,
                }
            })
            .collect();
        assert!(r.done(), "bytes after the last segment");
        Pca {
            groups,
            consts,
            segments,
        }
    }

    /// §5.4: the pose at `pos` (frames, 16.16).
    pub fn pose(&self, pos: u64, channels: usize) -> Vec<i32> {
        let mut out = vec![0i32; channels];
        let f = (pos >> 16) as u32;
        let frac = (pos & 0xFFFF) as i64;
        // 1. The primary segment, constants.
        let p = self
            .segments
            .iter()
            .rposition(|s| s.start <= f)
            .expect("a primary segment");
        for &(c, v) in &self.consts {
            out[c] = v;
        }
        // 2. Blend with a neighbour, or evaluate the primary segment alone.
        let blend_with = if p > 0 && pos < u64::from(self.segments[p - 1].end + 1) << 16 {
            Some((p - 1, p))
        } else if p + 1 < self.segments.len()
            && pos > u64::from(self.segments[p + 1].start - 1) << 16
        {
            Some((p, p + 1))
        } else {
            None
        };
        match blend_with {
            None => self.evaluate(&self.segments[p], pos, &mut out),
            Some((a, b)) => {
                // 4. Blend.
                let mut va = out.clone();
                let mut vb = out.clone();
                self.evaluate(&self.segments[a], pos, &mut va);
                self.evaluate(&self.segments[b], pos, &mut vb);
                let s = i64::from(self.segments[b].start);
                let e = i64::from(self.segments[a].end);
                let w = ((pos as i64 - ((s - 1) << 16)) / (e - s + 2)).clamp(0, 65536);
                for c in 0..channels {
                    let d = i64::from(vb[c].wrapping_sub(va[c]));
                    out[c] = va[c].wrapping_add(((d * w) >> 16) as i32);
                }
            }
        }
        // 5. Patches of f (weight 1 − frac) and f + 1 (weight frac).
        let mut patch = |frame: u32, weight: i64| {
            let Some(seg) = self.segments.iter().rfind(|s| s.start <= frame) else {
                return;
            };
            for &(rel, c, v) in &seg.patches {
                if seg.start + rel == frame {
                    out[c] = out[c].wrapping_add(((i64::from(v) * weight) >> 16) as i32);
                }
            }
        };
        patch(f, 65536 - frac);
        if frac > 0 {
            patch(f + 1, frac);
        }
        out
    }

    /// §5.4 step 3.
    fn evaluate(&self, seg: &Segment, pos: u64, out: &mut [i32]) {
        let rel = (pos as i64 - (i64::from(seg.start) << 16))
            .clamp(0, i64::from(seg.end - seg.start) << 16);
        for (channels, g) in self.groups.iter().zip(&seg.groups) {
            if g.k == 0 {
                for (&c, &mean) in channels.iter().zip(&g.mean) {
                    out[c] = mean.wrapping_shl(g.ms);
                }
                continue;
            }
            let a = catmull_rom(&g.times, &g.control, rel);
            for (row, &c) in channels.iter().enumerate() {
                let acc = g.basis[row]
                    .iter()
                    .zip(&a)
                    .fold(64i32, |acc, (&b, &a)| acc.wrapping_add(b.wrapping_mul(a)));
                out[c] = (g.mean[row] << g.ms).wrapping_add(acc >> 7);
            }
        }
    }
}

/// §5.4's fixed-point non-uniform Catmull-Rom: the `k` coefficients at
/// `rel` (16.16 frames from the segment's start).
pub fn catmull_rom(times: &[u32], control: &[Vec<i32>], rel: i64) -> Vec<i32> {
    let m = times.len();
    let i = (0..=m - 2)
        .rev()
        .find(|&i| i64::from(times[i]) << 16 <= rel)
        .unwrap_or(0);
    let key = |q: isize| (q.clamp(0, m as isize - 1)) as usize;
    let keys = [key(i as isize - 1), i, i + 1, key(i as isize + 2)];
    let t = keys.map(|q| i64::from(times[q]));
    let [ta, t0, t1, tb] = t;
    let span = t1 - t0;
    let u = (rel - (t0 << 16)) / span;
    let u2 = (u * u) >> 16;
    let u3 = (u2 * u) >> 16;
    let h00 = 2 * u3 - 3 * u2 + 65536;
    let h10 = u3 - 2 * u2 + u;
    let h01 = 3 * u2 - 2 * u3;
    let h11 = u3 - u2;
    let ra = (span << 16) / (t1 - ta);
    let rb = (span << 16) / (tb - t0);
    let x = (h10 * ra) >> 16;
    let y = (h11 * rb) >> 16;
    let w = [-x, h00 - y, h01 + x, y];
    assert_eq!(w.iter().sum::<i64>(), 65536, "weights sum to one");
    (0..control[0].len())
        .map(|j| {
            let s: i64 = (0..4).map(|q| w[q] * i64::from(control[keys[q]][j])).sum();
            ((s + 32768) >> 16) as i32
        })
        .collect()
}

impl Group {
    /// §5.3, for a group of `n` channels in a segment of `last + 1` frames.
    fn parse(r: &mut Reader<'_>, n: usize, last: u32) -> Group {
        let k = usize::from(r.u8());
        let ms = u32::from(r.u8());
        assert!(k <= 16 && ms <= 16);
        if k == 0 {
            return Group {
                k,
                ms,
                mean: (0..n).map(|_| r.zigzag()).collect(),
                basis: Vec::new(),
                times: Vec::new(),
                control: Vec::new(),
            };
        }
        let mean = (0..n)
            .map(|_| i32::from(i16::from_le_bytes([r.u8(), r.u8()])))
            .collect();
        let basis = (0..n)
            .map(|_| (0..k).map(|_| i32::from(r.u8() as i8)).collect())
            .collect();
        let m = r.varint() as usize;
        let tb = u32::from(r.u8());
        assert!((1..=15).contains(&tb) && last < 1 << tb);
        let comps: Vec<(u32, u32, i32)> = (0..k)
            .map(|_| (u32::from(r.u8()), u32::from(r.u8()), r.zigzag()))
            .collect();
        let rest = r.bytes.get(r.pos..).unwrap_or_default();
        let mut bits = Bits {
            bytes: rest,
            bit: 0,
        };
        let times: Vec<u32> = (0..m).map(|_| bits.read(tb)).collect();
        assert_eq!(times[0], 0);
        assert_eq!(times[m - 1], last);
        assert!(times.windows(2).all(|w| w[0] < w[1]));
        let control = (0..m)
            .map(|_| {
                comps
                    .iter()
                    .map(|&(width, shift, offset)| {
                        offset.wrapping_add((bits.read(width) as i32).wrapping_shl(shift))
                    })
                    .collect()
            })
            .collect();
        r.take(bits.bit.div_ceil(8));
        Group {
            k,
            ms,
            mean,
            basis,
            times,
            control,
        }
    }
}

// ---------------------------------------------------------------- §5b

#[derive(Debug)]
pub struct Predictive {
    pub block_frames: u32,
    /// Per channel: `Err(value)` constant, `Ok((weight quarters, step))`.
    pub modes: Vec<Result<(i64, i64), i32>>,
    pub blocks: Vec<Vec<u8>>,
}

impl Predictive {
    /// §5b.1.
    pub fn parse(section: &[u8], channels: usize, frames: u32) -> Predictive {
        let mut r = Reader::new(section);
        assert_eq!(r.varint() as usize, channels);
        let block_frames = r.varint();
        let unit = r.varint();
        assert!(block_frames >= 1 && unit >= 1);
        let modes = (0..channels)
            .map(|_| {
                let mode = r.varint();
                if mode & 4 != 0 {
                    assert_eq!(mode, 4, "a constant channel's mode is exactly 4");
                    Err(r.zigzag())
                } else {
                    let a = [0, 2, 3, 4][(mode & 3) as usize];
                    let s = i64::from(unit) * i64::from(mode >> 3);
                    assert!((1..=1 << 30).contains(&s));
                    Ok((a, s))
                }
            })
            .collect();
        let k = r.varint();
        assert_eq!(k, frames.div_ceil(block_frames));
        let lengths: Vec<usize> = (0..k).map(|_| r.varint() as usize).collect();
        let blocks = lengths.iter().map(|&n| r.take(n).to_vec()).collect();
        assert!(r.done(), "block lengths add up to the rest");
        Predictive {
            block_frames,
            modes,
            blocks,
        }
    }

    /// §5b.2: every frame, in order.
    pub fn decode(&self, channels: usize, frames: u32) -> Vec<Vec<i32>> {
        self.decode_traced(channels, frames).0
    }

    /// [`Self::decode`], and the residuals `[frame][channel]` (0 for a
    /// constant channel) and each block's [`RangeDecoder::trace`].
    pub fn decode_traced(&self, channels: usize, frames: u32) -> (Vec<Vec<i32>>, Residuals) {
        let mut out: Vec<Vec<i32>> = Vec::new();
        let mut residuals = Residuals::default();
        let mut rc = RangeDecoder::new(&[]);
        let mut probs = [1024u32; 30];
        let mut ctx = vec![0usize; channels];
        for f in 0..frames {
            let j = f % self.block_frames;
            if j == 0 {
                let next = RangeDecoder::new(&self.blocks[(f / self.block_frames) as usize]);
                let done = std::mem::replace(&mut rc, next);
                if f > 0 {
                    residuals.traces.push(done.trace);
                }
                probs = [1024; 30];
                ctx.fill(0);
            }
            let mut frame = Vec::with_capacity(channels);
            let mut qs = vec![0i64; channels];
            for (c, mode) in self.modes.iter().enumerate() {
                let (a, s) = match *mode {
                    Err(v) => {
                        frame.push(v);
                        continue;
                    }
                    Ok(m) => m,
                };
                let v1 = |back: usize| i64::from(out[out.len() - back][c]);
                let pred = match j {
                    0 => 0,
                    1 => v1(1),
                    _ => v1(1) + ((a * (v1(1) - v1(2))) >> 2),
                };
                let q = rc.residual(&mut probs, ctx[c]);
                frame.push((pred + q * s) as i32);
                ctx[c] = q.unsigned_abs().min(2) as usize;
                qs[c] = q;
            }
            out.push(frame);
            residuals.q.push(qs);
        }
        residuals.traces.push(rc.trace);
        (out, residuals)
    }
}

/// What [`Predictive::decode_traced`] saw.
#[derive(Debug, Default)]
pub struct Residuals {
    /// `q[frame][channel]`.
    pub q: Vec<Vec<i64>>,
    /// Per block, every bit read (see [`RangeDecoder::trace`]).
    pub traces: Vec<Vec<TracedBit>>,
}

/// One bit read: `(p before, or None for a direct bit; range and code
/// before; the bit)`.
pub type TracedBit = (Option<u32>, u32, u32, u32);

/// LZMA's range decoder as §5b.2 gives it.
pub struct RangeDecoder<'a> {
    block: &'a [u8],
    next: usize,
    range: u32,
    code: u32,
    /// Every bit read, for SPEC.md's worked example.
    pub trace: Vec<TracedBit>,
}

impl<'a> RangeDecoder<'a> {
    pub fn new(block: &'a [u8]) -> Self {
        let mut d = RangeDecoder {
            block,
            next: 0,
            range: u32::MAX,
            code: 0,
            trace: Vec::new(),
        };
        for _ in 0..4 {
            d.code = (d.code << 8) | d.byte();
        }
        d
    }

    fn byte(&mut self) -> u32 {
        let b = self.block.get(self.next).copied().unwrap_or(0);
        self.next += 1;
        u32::from(b)
    }

    fn normalise(&mut self) {
        while self.range < 1 << 24 {
            self.range <<= 8;
            self.code = (self.code << 8) | self.byte();
        }
    }

    pub fn bit(&mut self, p: &mut u32) -> u32 {
        let before = (Some(*p), self.range, self.code);
        let bound = (self.range >> 11) * *p;
        let bit = if self.code < bound {
            self.range = bound;
            *p += (2048 - *p) >> 5;
            0
        } else {
            self.code -= bound;
            self.range -= bound;
            *p -= *p >> 5;
            1
        };
        self.trace.push((before.0, before.1, before.2, bit));
        self.normalise();
        bit
    }

    pub fn direct(&mut self) -> u32 {
        let before = (None, self.range, self.code);
        self.range >>= 1;
        let bit = if self.code >= self.range {
            self.code -= self.range;
            1
        } else {
            0
        };
        self.trace.push((before.0, before.1, before.2, bit));
        self.normalise();
        bit
    }

    /// A residual in context `x`, probabilities `P[x·10 … x·10 + 9]`.
    pub fn residual(&mut self, probs: &mut [u32; 30], x: usize) -> i64 {
        let p = &mut probs[x * 10..x * 10 + 10];
        if self.bit(&mut p[0]) == 0 {
            return 0;
        }
        let negative = self.bit(&mut p[1]) == 1;
        let mut a: i64 = 1;
        while a <= 8 && self.bit(&mut p[1 + a as usize]) == 1 {
            a += 1;
        }
        if a == 9 {
            let mut n = 0;
            while n < 30 && self.direct() == 1 {
                n += 1;
            }
            let mut r: i64 = 0;
            for _ in 0..n {
                r = (r << 1) | i64::from(self.direct());
            }
            a = 9 + (1 << n) - 1 + r;
        }
        if negative {
            -a
        } else {
            a
        }
    }
}

/// §3.1 / §3.4: frame time, frame count and channel count of header
/// section `header_id`.
fn header_counts(header_id: u8, header: &[u8]) -> (u32, u32, usize) {
    let mut r = Reader::new(header);
    let mut frame_time_ns = r.varint();
    let (frame_count, channels);
    if header_id == 0x01 {
        // §3.1: postcard.
        frame_count = r.varint();
        let _source_unit_nm = r.varint();
        let joints = r.varint();
        let mut kinds = 0;
        for _ in 0..joints {
            let name = r.varint() as usize;
            r.take(name);
            match r.u8() {
                0 => {}
                1 => {
                    r.varint();
                }
                b => panic!("option byte {b}"),
            }
            for _ in 0..3 {
                r.zigzag();
            }
            assert!(r.u8() <= 1, "bool");
            let n = r.varint() as usize;
            r.take(n);
            kinds += n;
        }
        channels = r.varint() as usize;
        assert_eq!(channels, kinds, "one channel per kind");
        for _ in 0..channels {
            r.u8();
            let (min, max) = (r.zigzag(), r.zigzag());
            assert!(min <= max);
        }
    } else if frame_time_ns == 0 {
        // §3.4.1 servo form.
        frame_time_ns = r.varint();
        frame_count = r.varint();
        channels = r.varint() as usize;
    } else {
        frame_count = r.varint();
        let _source_unit_nm = r.varint();
        let joints = r.varint();
        let mut c = 0;
        for _ in 0..joints {
            let flags = r.u8();
            let kinds = usize::from(flags & 7);
            if flags & 0x10 != 0 {
                r.varint(); // back
            }
            let name = r.varint() as usize;
            r.take(name);
            for _ in 0..3 {
                r.zigzag();
            }
            r.take(kinds);
            c += kinds;
        }
        for _ in 0..c {
            r.zigzag();
            r.varint();
        }
        channels = c;
    }
    assert!(r.done(), "header trailing bytes");
    (frame_time_ns, frame_count, channels)
}

/// §9: a show's clips, by name, each a [`Clip`] of the shared header's
/// channels with its own frame count and codec section (§9.2).
pub fn parse_show(bytes: &[u8]) -> Vec<(String, Clip)> {
    let sections = sections(bytes, 2);
    let (header_id, header) = *sections
        .iter()
        .find(|(id, _)| matches!(id, 0x01 | 0x02))
        .expect("a header");
    let (frame_time_ns, total, channels) = header_counts(header_id, header);
    let table = sections
        .iter()
        .find(|(id, _)| *id == 0x04)
        .expect("a show table")
        .1;
    let mut r = Reader::new(table);
    let count = r.varint();
    let mut clips = Vec::new();
    let mut sum = 0;
    for _ in 0..count {
        let len = r.varint() as usize;
        let name = String::from_utf8(r.take(len).to_vec()).unwrap();
        let codec_at = r.varint() as usize;
        let frame_count = r.varint();
        if r.u8() & 1 == 1 {
            let (start, end, seam) = (r.varint(), r.varint(), r.varint());
            assert!(
                start < end && end < frame_count && seam < end - start,
                "loop points"
            );
        }
        let models: Vec<usize> = (0..r.varint()).map(|_| r.varint() as usize).collect();
        let (id, section) = sections[codec_at];
        let codec = match id {
            0x10 => Codec::Index(Index::parse(section, channels)),
            0x13 => Codec::IndexFast(IndexFast::parse(section, channels)),
            0x11 => Codec::PcaSpline(Pca::parse(section, channels)),
            0x12 => Codec::Predictive(Predictive::parse(section, channels, frame_count)),
            0x15 => Codec::Rma(Rma::parse(section, channels)),
            0x14 => {
                // §11.1: a SHARED section reads the clip's first model section.
                let model = models.first().map(|&m| {
                    assert_eq!(sections[m].0, 0x20, "a pattern database model");
                    sections[m].1
                });
                Codec::Pattern(Pattern::parse(section, model, channels))
            }
            id => panic!("clip {name}: section {id:#04x} is no codec"),
        };
        sum += frame_count;
        clips.push((
            name,
            Clip {
                frame_time_ns,
                frame_count,
                channels,
                codec,
            },
        ));
    }
    assert!(r.done(), "show table trailing bytes");
    assert_eq!(sum, total, "the header counts every clip's frames");
    clips
}

// ---------------------------------------------------------------- §11

/// §11: the database's nodes and each node's segments.
pub struct Pattern {
    pub nodes: Vec<PatternNode>,
}

/// A node: its channels, patterns, segments `(start, pattern)`.
pub type PatternNode = (Vec<usize>, Vec<PatternRecord>, Vec<(u32, usize)>);

/// §11.3 and §11.3b: a pattern of `len` samples; per channel `(shift,
/// width, base)` and the codes `[sample][channel]`; `steps` in layout 1
/// (the value is `(base + code) << shift`, not `base + (code << shift)`).
pub struct PatternRecord {
    pub len: u32,
    pub heads: Vec<(u32, usize, i32)>,
    pub codes: Vec<Vec<u32>>,
    pub steps: bool,
}

impl Pattern {
    /// §11.1–§11.3; `model` is the shared database of a SHARED section.
    pub fn parse(section: &[u8], model: Option<&[u8]>, channels: usize) -> Pattern {
        let mut r = Reader::new(section);
        let flags = r.u8();
        assert_eq!(flags & !3, 0, "reserved flags");
        let mut db_reader;
        let db = if flags & 1 == 1 {
            db_reader = Reader::new(model.expect("a shared database"));
            &mut db_reader
        } else {
            &mut r
        };
        let u16 = |r: &mut Reader<'_>| u16::from_le_bytes([r.u8(), r.u8()]);
        let u32 = |r: &mut Reader<'_>| u32::from_le_bytes([r.u8(), r.u8(), r.u8(), r.u8()]);
        let n = db.u8() as usize;
        let layout = db.u8();
        assert!(n >= 1, "node count");
        assert!(layout <= 2, "layout");
        let mut nodes = Vec::new();
        let mut seen = vec![0; channels];
        for _ in 0..n {
            let (c, p, d) = (u16(db) as usize, u16(db) as usize, u32(db) as usize);
            let list: Vec<usize> = (0..c).map(|_| u16(db) as usize).collect();
            let shifts: Vec<u32> = if layout == 2 {
                (0..c).map(|_| u32::from(db.u8())).collect()
            } else {
                Vec::new()
            };
            assert!(list.windows(2).all(|w| w[0] < w[1]), "channels increase");
            for &ch in &list {
                seen[ch] += 1;
            }
            let offsets: Vec<usize> = (0..p).map(|_| u32(db) as usize).collect();
            let data = db.take(d);
            let records = offsets
                .iter()
                .map(|&o| {
                    let mut q = Reader::new(&data[o..]);
                    if layout == 1 {
                        return columns(&mut q, c);
                    }
                    if layout == 2 {
                        return packed(&mut q, &shifts);
                    }
                    let len = u32::from(u16(&mut q));
                    let row = u16(&mut q) as usize;
                    let heads: Vec<u8> = (0..c).map(|_| q.u8()).collect();
                    let bases: Vec<i32> = (0..c).map(|_| u32(&mut q) as i32).collect();
                    let heads: Vec<(u32, usize, i32)> = heads
                        .iter()
                        .zip(&bases)
                        .map(|(&h, &b)| {
                            assert_eq!(h & 0x80, 0, "head bit 7");
                            (u32::from(h & 31), [0, 1, 2, 4][usize::from(h >> 5)], b)
                        })
                        .collect();
                    assert_eq!(row, heads.iter().map(|h| h.1).sum::<usize>(), "row bytes");
                    let codes = (0..len)
                        .map(|_| {
                            heads
                                .iter()
                                .map(|&(_, w, _)| {
                                    let mut v = 0u32;
                                    for i in 0..w {
                                        v |= u32::from(q.u8()) << (8 * i);
                                    }
                                    v
                                })
                                .collect()
                        })
                        .collect();
                    PatternRecord {
                        len,
                        heads,
                        codes,
                        steps: false,
                    }
                })
                .collect();
            nodes.push((list, records, Vec::new()));
        }
        assert!(seen.iter().all(|&k| k == 1), "every channel in one node");
        // §11.1b: CODED lists, after the two tables.
        let tables = (flags & 2 == 2).then(|| (RansTable::read(&mut r), RansTable::read(&mut r)));
        for node in &mut nodes {
            let s = u16(&mut r) as usize;
            node.2 = match &tables {
                None => (0..s)
                    .map(|_| (u32(&mut r), u16(&mut r) as usize))
                    .collect(),
                Some((lengths, patterns)) => {
                    let b = r.u8();
                    assert!(b <= 15, "b");
                    let k = s.div_ceil(1 << b);
                    let index: Vec<(u32, u32, usize)> = (0..k)
                        .map(|_| (u32(&mut r), u32::from(u16(&mut r)), u32(&mut r) as usize))
                        .collect();
                    let streams = r.take(index.last().unwrap().2);
                    let mut segs = Vec::new();
                    let mut from = 0;
                    for (i, &(start, pattern, end)) in index.iter().enumerate() {
                        let mut st = RansStream::new(&streams[from..end]);
                        let (mut at, mut p) = (start, pattern);
                        for j in 0..(s - i * (1 << b)).min(1 << b) {
                            if j > 0 {
                                let v = st.value(patterns);
                                let d = ((v >> 1) as i32) ^ -((v & 1) as i32);
                                p = p.wrapping_add(1).wrapping_add(d as u32);
                            }
                            segs.push((at, p as usize));
                            at += st.value(lengths) + 1;
                        }
                        assert!(st.finished(), "a block's stream ends where it started");
                        if let Some(next) = index.get(i + 1) {
                            assert_eq!(next.0, at, "the next block starts where this one ends");
                        }
                        from = end;
                    }
                    segs
                }
            };
            assert_eq!(node.2[0].0, 0, "first segment at 0");
        }
        assert!(r.done(), "bytes after the segment lists");
        Pattern { nodes }
    }

    /// §11.4: frame `f` of a clip of `frames` frames.
    pub fn frame(&self, f: u32, frames: u32, channels: usize) -> Vec<i32> {
        let mut out = vec![0; channels];
        for (list, records, segments) in &self.nodes {
            let i = segments.iter().rposition(|s| s.0 <= f).unwrap();
            let start = segments[i].0;
            let end = segments.get(i + 1).map_or(frames, |s| s.0);
            let p = &records[segments[i].1];
            let (n, l, t) = (end - start, p.len, f - start);
            let (j, frac) = if n <= 1 || l <= 1 {
                (0, 0)
            } else {
                let (q, d) = (t * (l - 1), n - 1);
                (q / d, ((q % d) << 16) / d)
            };
            for (c, &ch) in list.iter().enumerate() {
                let (s, _, base) = p.heads[c];
                let code = |k: u32| i64::from(p.codes[k as usize][c]);
                let value = |code: i32| {
                    if p.steps {
                        base.wrapping_add(code).wrapping_shl(s)
                    } else {
                        base.wrapping_add(code.wrapping_shl(s))
                    }
                };
                out[ch] = if frac == 0 {
                    value(code(j) as i32)
                } else {
                    let u = ((frac >> 4) & 0xFFF) as i64;
                    let u2 = (u * u) >> 12;
                    let u3 = (u2 * u) >> 12;
                    let mut w = [
                        (2 * u2 - u3 - u) >> 1,
                        0,
                        (4 * u2 - 3 * u3 + u) >> 1,
                        (u3 - u2) >> 1,
                    ];
                    w[1] = 4096 - w[0] - w[2] - w[3];
                    if j == 0 {
                        w[1] += 2 * w[0];
                        w[2] -= w[0];
                        w[0] = 0;
                    }
                    if j + 1 == l - 1 {
                        w[2] += 2 * w[3];
                        w[1] -= w[3];
                        w[3] = 0;
                    }
                    let tap = |k: i64| code((j as i64 + k).clamp(0, i64::from(l) - 1) as u32);
                    let acc: i64 = (0..4).map(|k| w[k as usize] * tap(k - 1)).sum();
                    value(((acc + 2048) >> 12) as i32)
                };
            }
        }
        out
    }
}

/// §11.3b: a layout-1 record of `c` channels, each its head, its base (in
/// steps; `i32` with head bit 7, else `i16`) and its `L` codes.
fn columns(q: &mut Reader<'_>, c: usize) -> PatternRecord {
    let len = u32::from(u16::from_le_bytes([q.u8(), q.u8()]));
    let mut heads = Vec::new();
    let mut by_channel = Vec::new();
    for _ in 0..c {
        let h = q.u8();
        let base = if h & 0x80 == 0 {
            i32::from(i16::from_le_bytes([q.u8(), q.u8()]))
        } else {
            i32::from_le_bytes([q.u8(), q.u8(), q.u8(), q.u8()])
        };
        let width = [0, 1, 2, 4][usize::from((h >> 5) & 3)];
        let codes: Vec<u32> = (0..len)
            .map(|_| (0..width).fold(0u32, |v, i| v | u32::from(q.u8()) << (8 * i)))
            .collect();
        heads.push((u32::from(h & 31), width, base));
        by_channel.push(codes);
    }
    let codes = (0..len as usize)
        .map(|k| by_channel.iter().map(|col| col[k]).collect())
        .collect();
    PatternRecord {
        len,
        heads,
        codes,
        steps: true,
    }
}

/// §11.3c: a layout-2 record, each channel its head (width in bits, wide
/// base), its base and its `L` codes bit-packed LSB first; the shifts are
/// the node's.
fn packed(q: &mut Reader<'_>, shifts: &[u32]) -> PatternRecord {
    let len = u32::from(u16::from_le_bytes([q.u8(), q.u8()]));
    let mut heads = Vec::new();
    let mut by_channel = Vec::new();
    for &shift in shifts {
        let h = q.u8();
        assert_eq!(h & 0x80, 0, "head bit 7");
        let base = if h & 0x40 == 0 {
            i32::from(i16::from_le_bytes([q.u8(), q.u8()]))
        } else {
            i32::from_le_bytes([q.u8(), q.u8(), q.u8(), q.u8()])
        };
        let b = usize::from(h & 63);
        let column = q.take((len as usize * b).div_ceil(8));
        let bit = |i: usize| u32::from(column[i / 8] >> (i % 8) & 1);
        let codes: Vec<u32> = (0..len as usize)
            .map(|k| (0..b).fold(0u32, |v, i| v | bit(k * b + i) << i))
            .collect();
        heads.push((shift, b, base));
        by_channel.push(codes);
    }
    let codes = (0..len as usize)
        .map(|k| by_channel.iter().map(|col| col[k]).collect())
        .collect();
    PatternRecord {
        len,
        heads,
        codes,
        steps: true,
    }
}
