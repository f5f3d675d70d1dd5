//! What sharing `index` codebooks across the clips of a show could save
//! (BENCHMARKS.md §6): of every `index` codec section of a show (SPEC.md
//! §4.1), the bytes of its table pool (`T` entries of `i16`), and how many
//! of its tables are byte-identical to another table of the same clip or of
//! another clip. A measurement only: no bitstream section is written.
//!
//!   cargo run --release -p mocap-encoder --example show_pools -- show.mcb
//!
//! A *table* is the run of pool entries one or more set entries point at
//! (§4.2): from its offset to the next table's offset (the encoder lays the
//! codebooks back to back, each table's unused tail overlapping the next),
//! at most `2^b` entries — so the tables partition the pool, constants
//! (`b = 0`) one entry each. Two tables are identical when their `i16`
//! entries are; the entries' own `base` and `shift` stay per clip. A table
//! repeated inside one clip could point at one copy today (§4.2 allows
//! shared tables, an encoder-only change); one repeated across clips would
//! need a shared pool section.

use std::collections::{BTreeMap, HashMap, HashSet};

use mocap_decoder::{consts, Show};

/// One table of a clip's pool.
struct Table {
    entries: Vec<i16>,
    constant: bool,
}

/// The tables of one `index` section and its sizes.
struct Pool {
    section_bytes: usize,
    pool_entries: usize,
    tables: Vec<Table>,
}

fn u16_at(b: &[u8], at: usize) -> usize {
    usize::from(u16::from_le_bytes([b[at], b[at + 1]]))
}

fn u32_at(b: &[u8], at: usize) -> usize {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as usize
}

/// The (table offset, index width) of every entry of the set at `*at`.
fn read_set(s: &[u8], at: &mut usize, out: &mut Vec<(usize, u8)>) {
    let groups = u16_at(s, *at);
    *at += 2;
    for _ in 0..groups {
        let bits = s[*at];
        let count = u16_at(s, *at + 2);
        *at += 4;
        for e in 0..count {
            out.push((u16_at(s, *at + e * 8 + 2), bits));
        }
        *at += count * 8;
    }
}

/// The tables of an `index` section (validated by `Show::parse`).
fn pool(section: &[u8]) -> Pool {
    let key_interval = u16_at(section, 0);
    let t = u32_at(section, 4);
    let mut at = 8;
    let mut refs = Vec::new();
    read_set(section, &mut at, &mut refs);
    if key_interval > 0 {
        read_set(section, &mut at, &mut refs);
    }
    let pool: Vec<i16> = section[at..at + 2 * t]
        .chunks_exact(2)
        .map(|b| i16::from_le_bytes([b[0], b[1]]))
        .collect();
    // Offset → widest width pointing there.
    let mut starts: BTreeMap<usize, u8> = BTreeMap::new();
    for (off, bits) in refs {
        let w = starts.entry(off).or_insert(bits);
        *w = (*w).max(bits);
    }
    let offsets: Vec<(usize, u8)> = starts.into_iter().collect();
    let tables = offsets
        .iter()
        .enumerate()
        .map(|(i, &(off, bits))| {
            let next = offsets.get(i + 1).map_or(t, |n| n.0);
            let end = next.min(off + (1usize << bits)).min(t);
            Table {
                entries: pool[off..end].to_vec(),
                constant: bits == 0,
            }
        })
        .collect();
    Pool {
        section_bytes: section.len(),
        pool_entries: t,
        tables,
    }
}

/// The bytes of section `i` of a container.
fn section(file: &[u8], i: usize) -> (u8, &[u8]) {
    let e = 8 + 12 * i;
    let (off, len) = (u32_at(file, e + 4), u32_at(file, e + 8));
    (file[e], &file[off..off + len])
}

/// A distinct table of the show: the clips that hold it.
struct Distinct {
    clips: HashSet<usize>,
    entries: usize,
    constant: bool,
}

/// Counts of a set of tables.
#[derive(Default)]
struct Count {
    tables: usize,
    entries: usize,
    constants: usize,
}

impl Count {
    fn add(&mut self, t: &Table) {
        self.tables += 1;
        self.entries += t.entries.len();
        self.constants += usize::from(t.constant);
    }
}

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: show_pools SHOW.mcb");
        std::process::exit(2);
    };
    let bytes = std::fs::read(&path).unwrap_or_else(|e| {
        eprintln!("{path}: {e}");
        std::process::exit(1);
    });
    let show = Show::parse(&bytes).unwrap_or_else(|e| {
        eprintln!("{path}: not a show: {e:?}");
        std::process::exit(1);
    });
    let mut pools = Vec::new();
    for i in 0..show.clip_count() {
        let entry = show.entry(i).expect("a parsed show's entry");
        let (id, s) = section(&bytes, usize::from(entry.codec_section));
        if id == consts::SECTION_CODEC_INDEX {
            pools.push((entry.name.to_string(), pool(s)));
        }
    }
    println!(
        "{path}: {} bytes, {} clips, {} with the index codec",
        bytes.len(),
        show.clip_count(),
        pools.len()
    );
    if pools.is_empty() {
        return;
    }
    println!("| clip | index section B | pool entries T | pool B | tables | of them constants (b = 0) | tables identical to an earlier one of the clip | their entries |");
    println!("|---|---|---|---|---|---|---|---|");
    let (mut section_bytes, mut pool_entries) = (0, 0);
    let (mut all, mut within) = (Count::default(), Count::default());
    // Distinct tables of the whole show, by content.
    let mut show_tables: HashMap<&[i16], Distinct> = HashMap::new();
    for (k, (name, p)) in pools.iter().enumerate() {
        let mut seen: HashSet<&[i16]> = HashSet::new();
        let (mut count, mut dup) = (Count::default(), Count::default());
        for t in &p.tables {
            count.add(t);
            if !seen.insert(&t.entries) {
                dup.add(t);
            }
            let d = show_tables.entry(&t.entries).or_insert(Distinct {
                clips: HashSet::new(),
                entries: t.entries.len(),
                constant: t.constant,
            });
            d.clips.insert(k);
        }
        println!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} |",
            p.section_bytes,
            p.pool_entries,
            2 * p.pool_entries,
            count.tables,
            count.constants,
            dup.tables,
            dup.entries
        );
        section_bytes += p.section_bytes;
        pool_entries += p.pool_entries;
        all.tables += count.tables;
        all.entries += count.entries;
        all.constants += count.constants;
        within.tables += dup.tables;
        within.entries += dup.entries;
        within.constants += dup.constants;
    }
    let pool_bytes = 2 * pool_entries;
    let pct = |a: usize, b: usize| a as f64 * 100.0 / b.max(1) as f64;
    println!();
    println!(
        "pools: {pool_bytes} B ({pool_entries} entries) of the index sections' {section_bytes} B ({:.1} %), {:.1} % of the show's {} B",
        pct(pool_bytes, section_bytes),
        pct(pool_bytes, bytes.len()),
        bytes.len()
    );
    println!(
        "tables: {} ({} constants of one entry), {} entries (the rest of the pools, {} entries, is padding past the last table)",
        all.tables,
        all.constants,
        all.entries,
        pool_entries - all.entries
    );
    println!(
        "identical inside a clip (one copy per clip would do, SPEC §4.2 allows it today): {} tables ({} constants), {} entries = {} B ({:.1} % of the pools)",
        within.tables,
        within.constants,
        within.entries,
        2 * within.entries,
        pct(2 * within.entries, pool_bytes)
    );
    let distinct_entries: usize = show_tables.values().map(|d| d.entries).sum();
    let in_many: Vec<&Distinct> = show_tables.values().filter(|d| d.clips.len() > 1).collect();
    let many_tables = in_many.len();
    let many_constants = in_many.iter().filter(|d| d.constant).count();
    let many_entries: usize = in_many.iter().map(|d| d.entries).sum();
    let copies: usize = in_many.iter().map(|d| d.clips.len()).sum();
    println!(
        "identical across clips: {many_tables} distinct tables ({many_constants} constants, {many_entries} entries) occur in 2 or more clips, {copies} clip copies of them"
    );
    let saved = 2 * (all.entries - distinct_entries);
    println!(
        "one shared pool of the show's distinct tables: {} distinct tables, {distinct_entries} entries = {} B against the tables' {} B: saves {saved} B ({:.1} % of the pools, {:.1} % of the show), of which {} B inside clips and {} B across clips (before the shared section's own framing and padding)",
        show_tables.len(),
        2 * distinct_entries,
        2 * all.entries,
        pct(saved, pool_bytes),
        pct(saved, bytes.len()),
        2 * within.entries,
        saved - 2 * within.entries
    );
}
