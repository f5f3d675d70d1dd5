//! uf2: converts a firmware ELF into a UF2 file for drag-and-drop flashing (the RP2040's boot
//! ROM: hold BOOTSEL, plug in, copy the file to the RPI-RP2 drive).
//!
//!   uf2 IN.elf OUT.uf2 [--family 0xe48bff56] [--flash 0x10000000:0x1000000]
//!
//! Every loadable segment's file bytes (PT_LOAD, at its physical address: where .data's initial
//! values sit in flash) must lie in the flash range; they are cut into 256-byte pages aligned
//! to 256 (gaps inside a page are zero), one 512-byte UF2 block per page, in address order,
//! each with the family ID (default RP2040's). The format: https://github.com/microsoft/uf2.
//!
//! A single std-only file, compiled by scripts/firmware.sh with the host's rustc in a second, so
//! CI needs no tool from crates.io (elf2uf2-rs pulls in clap, sysinfo and serialport). Tests:
//! `rustc --edition 2021 --test scripts/uf2.rs -o target/uf2-test && target/uf2-test`.

use std::collections::BTreeMap;
use std::process::exit;

const MAGIC_START0: u32 = 0x0A32_4655;
const MAGIC_START1: u32 = 0x9E5D_5157;
const MAGIC_END: u32 = 0x0AB1_6F30;
/// Flag: the family ID field is set.
const FLAG_FAMILY_ID: u32 = 0x0000_2000;
const PAGE: u32 = 256;
const BLOCK: usize = 512;
const DATA_AT: usize = 32;
const RP2040_FAMILY: u32 = 0xE48B_FF56;
/// The RP2040's XIP flash window (up to 16 MB).
const RP2040_FLASH: (u32, u32) = (0x1000_0000, 0x0100_0000);

/// A segment to flash: physical address and bytes.
struct Segment {
    addr: u32,
    bytes: Vec<u8>,
}

fn u16_at(b: &[u8], at: usize) -> Result<u16, String> {
    b.get(at..at + 2)
        .map(|s| u16::from_le_bytes([s[0], s[1]]))
        .ok_or_else(|| format!("ELF truncated at byte {at}"))
}

fn u32_at(b: &[u8], at: usize) -> Result<u32, String> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        .ok_or_else(|| format!("ELF truncated at byte {at}"))
}

/// The PT_LOAD segments with file bytes of a 32-bit little-endian ELF.
fn load_segments(elf: &[u8]) -> Result<Vec<Segment>, String> {
    if elf.get(..4) != Some(b"\x7fELF") {
        return Err("not an ELF file".into());
    }
    if elf.get(4) != Some(&1) || elf.get(5) != Some(&1) {
        return Err("not a 32-bit little-endian ELF (the Cortex-M's)".into());
    }
    let phoff = u32_at(elf, 28)? as usize;
    let phentsize = usize::from(u16_at(elf, 42)?);
    let phnum = usize::from(u16_at(elf, 44)?);
    let mut segments = Vec::new();
    for i in 0..phnum {
        let ph = phoff + i * phentsize;
        let (p_type, offset, paddr, filesz) = (
            u32_at(elf, ph)?,
            u32_at(elf, ph + 4)? as usize,
            u32_at(elf, ph + 12)?,
            u32_at(elf, ph + 16)? as usize,
        );
        if p_type != 1 || filesz == 0 {
            continue; // not PT_LOAD, or nothing to flash (.bss, .uninit)
        }
        let bytes = elf
            .get(offset..offset + filesz)
            .ok_or_else(|| format!("segment {i} runs past the end of the file"))?;
        segments.push(Segment {
            addr: paddr,
            bytes: bytes.to_vec(),
        });
    }
    Ok(segments)
}

/// The UF2 blocks of `segments` (all inside `flash`: start, size).
fn uf2(segments: &[Segment], family: u32, flash: (u32, u32)) -> Result<Vec<u8>, String> {
    let (start, size) = flash;
    let end = u64::from(start) + u64::from(size);
    let mut pages: BTreeMap<u32, [u8; PAGE as usize]> = BTreeMap::new();
    for s in segments {
        let s_end = u64::from(s.addr) + s.bytes.len() as u64;
        if s.addr < start || s_end > end {
            return Err(format!(
                "segment at {:#010x}..{:#010x} lies outside the flash {:#010x}..{:#010x}",
                s.addr, s_end, start, end
            ));
        }
        for (i, &b) in s.bytes.iter().enumerate() {
            let a = s.addr + i as u32;
            let page = pages.entry(a & !(PAGE - 1)).or_insert([0; PAGE as usize]);
            page[(a & (PAGE - 1)) as usize] = b;
        }
    }
    if pages.is_empty() {
        return Err("nothing to flash: no loadable segment with bytes".into());
    }
    let count = pages.len() as u32;
    let mut out = Vec::with_capacity(pages.len() * BLOCK);
    for (n, (addr, data)) in pages.iter().enumerate() {
        let mut block = [0u8; BLOCK];
        let words = [
            MAGIC_START0,
            MAGIC_START1,
            FLAG_FAMILY_ID,
            *addr,
            PAGE,
            n as u32,
            count,
            family,
        ];
        for (k, w) in words.iter().enumerate() {
            block[4 * k..4 * k + 4].copy_from_slice(&w.to_le_bytes());
        }
        block[DATA_AT..DATA_AT + PAGE as usize].copy_from_slice(data);
        block[BLOCK - 4..].copy_from_slice(&MAGIC_END.to_le_bytes());
        out.extend_from_slice(&block);
    }
    Ok(out)
}

fn parse_u32(s: &str) -> Result<u32, String> {
    let r = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => s.parse(),
    };
    r.map_err(|_| format!("not a number: '{s}'"))
}

fn run(args: &[String]) -> Result<(), String> {
    let mut files = Vec::new();
    let mut family = RP2040_FAMILY;
    let mut flash = RP2040_FLASH;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--family" => family = parse_u32(it.next().ok_or("--family needs a value")?)?,
            "--flash" => {
                let v = it.next().ok_or("--flash needs START:SIZE")?;
                let (s, n) = v.split_once(':').ok_or("--flash needs START:SIZE")?;
                flash = (parse_u32(s)?, parse_u32(n)?);
            }
            _ if a.starts_with('-') => return Err(format!("unknown option {a}")),
            _ => files.push(a),
        }
    }
    let [elf, out] = files.as_slice() else {
        return Err("usage: uf2 IN.elf OUT.uf2 [--family ID] [--flash START:SIZE]".into());
    };
    let bytes = std::fs::read(elf).map_err(|e| format!("{elf}: {e}"))?;
    let segments = load_segments(&bytes).map_err(|e| format!("{elf}: {e}"))?;
    let uf2 = uf2(&segments, family, flash).map_err(|e| format!("{elf}: {e}"))?;
    std::fs::write(out, &uf2).map_err(|e| format!("{out}: {e}"))?;
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Err(e) = run(&args) {
        eprintln!("uf2: error: {e}");
        exit(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn word(b: &[u8], at: usize) -> u32 {
        u32_at(b, at).unwrap()
    }

    #[test]
    fn blocks_cover_the_pages_in_order_with_gaps_zeroed() {
        let segments = [
            Segment {
                addr: 0x1000_0000,
                bytes: vec![0xAA; 300], // two pages, the second partly
            },
            Segment {
                addr: 0x1000_0400, // a page of its own after a gap of one
                bytes: vec![1, 2, 3],
            },
        ];
        let out = uf2(&segments, RP2040_FAMILY, RP2040_FLASH).unwrap();
        assert_eq!(out.len(), 3 * BLOCK);
        for (n, addr) in [0x1000_0000u32, 0x1000_0100, 0x1000_0400].iter().enumerate() {
            let b = &out[n * BLOCK..(n + 1) * BLOCK];
            assert_eq!(word(b, 0), MAGIC_START0);
            assert_eq!(word(b, 4), MAGIC_START1);
            assert_eq!(word(b, 8), FLAG_FAMILY_ID);
            assert_eq!(word(b, 12), *addr);
            assert_eq!(word(b, 16), 256);
            assert_eq!(word(b, 20), n as u32);
            assert_eq!(word(b, 24), 3);
            assert_eq!(word(b, 28), 0xE48B_FF56);
            assert_eq!(word(b, 508), MAGIC_END);
            assert!(b[DATA_AT + 256..508].iter().all(|&x| x == 0));
        }
        let second = &out[BLOCK + DATA_AT..BLOCK + DATA_AT + 256];
        assert!(second[..44].iter().all(|&x| x == 0xAA));
        assert!(second[44..].iter().all(|&x| x == 0));
        assert_eq!(&out[2 * BLOCK + DATA_AT..2 * BLOCK + DATA_AT + 4], &[1, 2, 3, 0]);
    }

    #[test]
    fn refuses_segments_outside_the_flash() {
        let ram = [Segment {
            addr: 0x2000_0000,
            bytes: vec![0; 4],
        }];
        assert!(uf2(&ram, RP2040_FAMILY, RP2040_FLASH).is_err());
        assert!(uf2(&[], RP2040_FAMILY, RP2040_FLASH).is_err());
    }

    #[test]
    fn reads_only_loadable_segments_with_bytes() {
        // ELF header + two program headers: PT_LOAD with 4 bytes, PT_LOAD with none (.bss).
        let mut elf = vec![0u8; 52 + 2 * 32 + 4];
        elf[..6].copy_from_slice(b"\x7fELF\x01\x01");
        elf[28..32].copy_from_slice(&52u32.to_le_bytes());
        elf[42..44].copy_from_slice(&32u16.to_le_bytes());
        elf[44..46].copy_from_slice(&2u16.to_le_bytes());
        for (i, (paddr, filesz)) in [(0x1000_0000u32, 4u32), (0x2000_0000, 0)].iter().enumerate() {
            let ph = 52 + 32 * i;
            elf[ph..ph + 4].copy_from_slice(&1u32.to_le_bytes());
            elf[ph + 4..ph + 8].copy_from_slice(&116u32.to_le_bytes());
            elf[ph + 12..ph + 16].copy_from_slice(&paddr.to_le_bytes());
            elf[ph + 16..ph + 20].copy_from_slice(&filesz.to_le_bytes());
        }
        elf[116..120].copy_from_slice(&[9, 8, 7, 6]);
        let s = load_segments(&elf).unwrap();
        assert_eq!(s.len(), 1);
        assert_eq!((s[0].addr, s[0].bytes.as_slice()), (0x1000_0000, &[9u8, 8, 7, 6][..]));
        assert!(load_segments(b"not an elf").is_err());
    }
}
