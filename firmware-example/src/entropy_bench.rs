//! The entropy coder's cost on the MCU (`MOCAP_ENTROPY_BENCH=1`, `scripts/firmware.sh run
//! --entropy-bench --icount`): decodes the rANS streams build.rs encoded (SPEC.md §10) with
//! `mocap_decoder::entropy`, times them with SysTick (instructions exactly under `-icount
//! shift=0`) and prints one `# entropy` line per stream: symbols, alphabet, precision, bytes,
//! the instructions of `Table::parse` + `Decoder::new` and per symbol (×100), and whether the
//! symbols' checksum matches the encoder's; then the same through the table's index in RAM
//! (`Table::index`, `Decoder::symbol_in`: binary search instead of the scan), with the
//! instructions to build it. A loop of the same shape without the decoder is timed too
//! (`# entropy_loop`), so the decoder's own share is the difference.

use core::hint::black_box;

use mocap_decoder::entropy::{Decoder, Index, Table};

use crate::{calibrate, instructions, ticks, Out};

/// One stream: a table and one block (SPEC.md §10.2–§10.3).
pub struct Stream {
    pub name: &'static str,
    pub symbols: u32,
    /// `sum = sum · 31 + symbol` (wrapping) over the symbols.
    pub checksum: u32,
    pub bytes: &'static [u8],
}

mod data {
    use super::Stream;
    include!(concat!(env!("OUT_DIR"), "/entropy_bench.rs"));
}

/// Symbols per timed span (SysTick is 24 bits: spans stay far below 2^24 ticks).
const CHUNK: u32 = 500;

#[inline(never)]
fn parse(bytes: &'static [u8]) -> Option<(Table<'static>, Decoder<'static, 'static>)> {
    let (table, used) = Table::parse(bytes).ok()?;
    let decoder = Decoder::new(table, bytes.get(used..)?).ok()?;
    Some((table, decoder))
}

/// Decodes `n` symbols into the checksum.
#[inline(never)]
fn decode(d: &mut Decoder<'static, 'static>, n: u32, mut sum: u32) -> u32 {
    for _ in 0..n {
        sum = sum.wrapping_mul(31).wrapping_add(d.symbol());
    }
    sum
}

/// Decodes `n` symbols through the index into the checksum.
#[inline(never)]
fn decode_in(d: &mut Decoder<'static, 'static>, index: &Index, n: u32, mut sum: u32) -> u32 {
    for _ in 0..n {
        sum = sum.wrapping_mul(31).wrapping_add(d.symbol_in(index));
    }
    sum
}

/// Entries of the index buffer (alphabets up to 1 023 symbols; 2 KB of stack).
const INDEX_ENTRIES: usize = 1024;

/// The stream decoded again through the table's index: (instructions to build the index,
/// instructions ×100 per symbol, whether the checksum matches); `None` if the alphabet does not
/// fit the buffer or the stream does not parse.
#[inline(never)]
fn run_indexed(s: &Stream, cal: u32) -> Option<(u64, u64, bool)> {
    let (table, mut d) = parse(s.bytes)?;
    let mut buf = [0u16; INDEX_ENTRIES];
    let t0 = ticks::now();
    let index = table.index(&mut buf).ok()?;
    let build_ticks = ticks::since(t0, ticks::now());
    let (mut sum, mut total, mut left) = (0u32, 0u64, s.symbols);
    while left > 0 {
        let n = left.min(CHUNK);
        let t0 = ticks::now();
        sum = decode_in(&mut d, &index, n, sum);
        total += u64::from(ticks::since(t0, ticks::now()));
        left -= n;
    }
    Some((
        instructions(u64::from(build_ticks), cal),
        instructions(total, cal) * 100 / u64::from(s.symbols.max(1)),
        sum == s.checksum && d.is_finished(),
    ))
}

/// The same loop without the decoder.
#[inline(never)]
fn baseline(n: u32, mut sum: u32) -> u32 {
    for i in 0..n {
        sum = sum.wrapping_mul(31).wrapping_add(black_box(i));
    }
    sum
}

/// Runs every stream; `false` if one fails to parse or decodes to other symbols.
pub fn run(text: &mut Out) -> bool {
    let cal = calibrate();
    let mut ok = true;
    let t0 = ticks::now();
    let sum = baseline(CHUNK, 0);
    let loop_ticks = ticks::since(t0, ticks::now());
    text.str("# entropy_loop")
        .kv("symbols", u64::from(CHUNK))
        .kv(
            "per_symbol_x100",
            instructions(u64::from(loop_ticks), cal) * 100 / u64::from(CHUNK),
        )
        .kv("sum", u64::from(sum & 1))
        .nl();
    for s in data::STREAMS {
        let t0 = ticks::now();
        let parsed = parse(s.bytes);
        let parse_ticks = ticks::since(t0, ticks::now());
        let Some((table, mut d)) = parsed else {
            text.str("# entropy stream=")
                .str(s.name)
                .str(" error=parse")
                .nl();
            ok = false;
            continue;
        };
        let mut sum = 0u32;
        let mut total = 0u64;
        let mut left = s.symbols;
        while left > 0 {
            let n = left.min(CHUNK);
            let t0 = ticks::now();
            sum = decode(&mut d, n, sum);
            total += u64::from(ticks::since(t0, ticks::now()));
            left -= n;
        }
        let good = sum == s.checksum && d.is_finished();
        ok &= good;
        let per_x100 = instructions(total, cal) * 100 / u64::from(s.symbols.max(1));
        text.str("# entropy stream=")
            .str(s.name)
            .kv("symbols", u64::from(s.symbols))
            .kv("alphabet", u64::from(table.alphabet()))
            .kv("n", u64::from(table.precision()))
            .kv("bytes", s.bytes.len() as u64)
            .kv(
                "parse_instructions",
                instructions(u64::from(parse_ticks), cal),
            )
            .kv("per_symbol_x100", per_x100)
            .kv("ok", u64::from(good));
        match run_indexed(s, cal) {
            Some((build, per_x100, good)) => {
                ok &= good;
                text.kv("index_instructions", build)
                    .kv("indexed_per_symbol_x100", per_x100)
                    .kv("indexed_ok", u64::from(good));
            }
            None => {
                text.str(" indexed=none");
            }
        }
        text.nl();
    }
    ok
}
