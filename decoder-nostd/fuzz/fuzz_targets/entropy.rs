//! Any byte string: the entropy coder's table parser (SPEC.md §10.2) and
//! decoder (§10.3–§10.4) must return an `Err` or symbols inside the
//! alphabet, never panic, read out of bounds or loop without end. The first
//! byte picks how the rest is split into table and stream and what is read:
//! symbols, raw bits or escaped values. Inputs that parse are also checked
//! against the encoder: the symbols decoded from a valid table re-encode to
//! a stream that decodes to them again; and where the alphabet fits 4 096
//! symbols, the table's index (`Table::index`, `Decoder::symbol_in`) decodes
//! the same bytes to the same symbols and states as the scan.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mocap_decoder::entropy::{Decoder, Table};

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let Ok((table, used)) = Table::parse(rest) else {
        return;
    };
    assert!(table.alphabet() >= 1 && table.precision() <= 15);
    let total: u64 = (0..table.alphabet().min(256))
        .map(|s| u64::from(table.count(s)))
        .sum();
    if table.alphabet() <= 256 {
        assert_eq!(total, 1u64 << table.precision(), "counts add up to M");
    }
    let Ok(mut d) = Decoder::new(table, &rest[used..]) else {
        return;
    };
    let mut buf = vec![0u16; 4097];
    let index = table.index(&mut buf).ok();
    let mut di = d.clone();
    let mut symbols = Vec::new();
    for i in 0..512u32 {
        match mode % 3 {
            0 => {
                let s = d.symbol();
                assert!(s < table.alphabet());
                if let Some(index) = &index {
                    assert_eq!(di.symbol_in(index), s, "index and scan agree");
                    assert_eq!(di.state(), d.state());
                }
                symbols.push(s);
            }
            1 => {
                let k = (mode as u32 >> 2).wrapping_add(i) % 17;
                assert!(d.raw(k) < 1 << k);
            }
            _ => {
                let _ = d.value();
            }
        }
        assert!(d.state() < 1 << 31);
    }
    // The decoded symbols re-encode with a table of the encoder's own and
    // come back unchanged.
    if mode % 3 == 0 && !symbols.is_empty() {
        let bytes = mocap_encoder::entropy::encode_all(&symbols).expect("encodes");
        let (t, used) = Table::parse(&bytes).expect("own table");
        let mut d = Decoder::new(t, &bytes[used..]).expect("own state");
        for &s in &symbols {
            assert_eq!(d.symbol(), s);
        }
        assert!(d.is_finished());
    }
});
