//! The reader on synthetic files written here in every encoding (Intel, DEC,
//! MIPS; integer and float; with and without labels, missing samples and
//! analog channels), and on malformed ones: every truncation, bad pointers,
//! wrong counts, bad numbers, unknown processor — an error with its offset,
//! never a panic.

use super::bytes::{dec_bytes, dec_f32};
use super::*;

/// What the test writer writes.
#[derive(Clone)]
struct Spec {
    processor: Processor,
    float: bool,
    /// Labels, split over `LABELS` and `LABELS2` when there are more than 2.
    labels: Option<Vec<&'static str>>,
    /// Analog channels (two samples per frame each).
    analog: usize,
    frames: usize,
    points: usize,
    units: Option<&'static str>,
    /// `POINT:USED` as written (default: `points`).
    used: Option<u16>,
    /// `POINT:FRAMES` as written (default: `frames`, at most 65 535).
    frames_param: Option<u16>,
    /// How a take of more than 65 535 frames states its length.
    long: Option<Long>,
}

/// The conventions for takes the header's 16-bit words cannot count.
#[derive(Clone, Copy, PartialEq)]
enum Long {
    /// `TRIAL:ACTUAL_START_FIELD` / `ACTUAL_END_FIELD` (Vicon).
    Trial,
    /// `POINT:LONG_FRAMES`, a float (C3Dserver).
    LongFrames,
}

impl Spec {
    fn new(processor: Processor, float: bool) -> Spec {
        Spec {
            processor,
            float,
            labels: Some(vec!["LHEE", "RTOE", "RTOE", "  C7"]),
            analog: 2,
            frames: 7,
            points: 4,
            units: Some("mm"),
            used: None,
            frames_param: None,
            long: None,
        }
    }

    /// The frame count as a 16-bit header word holds it.
    fn frames16(&self) -> u16 {
        self.frames.min(usize::from(u16::MAX)) as u16
    }

    /// Position of point `p` at frame `f`: multiples of 0.5, exact in every
    /// encoding (int16 × 0.5, f32, DEC).
    fn position(f: usize, p: usize) -> [f64; 3] {
        let (f, p) = (f as f64, p as f64);
        [
            100.0 * p + 0.5 * f,
            -250.5 + 3.0 * f,
            1000.0 - 20.5 * p + f * f,
        ]
    }

    /// Missing: point 1 at frames 0–1 and 5, point 3 at frame 6.
    fn missing(f: usize, p: usize) -> bool {
        (p == 1 && [0, 1, 5].contains(&f)) || (p == 3 && f == 6)
    }

    fn u16(&self, out: &mut Vec<u8>, v: u16) {
        match self.processor {
            Processor::Mips => out.extend(v.to_be_bytes()),
            _ => out.extend(v.to_le_bytes()),
        }
    }

    fn f32(&self, out: &mut Vec<u8>, v: f32) {
        match self.processor {
            Processor::Intel => out.extend(v.to_le_bytes()),
            Processor::Dec => out.extend(dec_bytes(v)),
            Processor::Mips => out.extend(v.to_be_bytes()),
        }
    }

    fn scale(&self) -> f32 {
        if self.float {
            -0.5
        } else {
            0.5
        }
    }

    /// One parameter record (`next` 0 when `last`).
    fn param(&self, out: &mut Vec<u8>, group: i8, name: &str, kind: i8, dims: &[u8], data: &[u8]) {
        out.push(name.len() as u8);
        out.push(group as u8);
        out.extend(name.as_bytes());
        let next = 2 + 1 + 1 + dims.len() + data.len() + 1;
        self.u16(out, next as u16);
        out.push(kind as u8);
        out.push(dims.len() as u8);
        out.extend(dims);
        out.extend(data);
        out.push(0); // no description
    }

    fn group(&self, out: &mut Vec<u8>, id: i8, name: &str) {
        out.push(name.len() as u8);
        out.push((-id) as u8);
        out.extend(name.as_bytes());
        self.u16(out, 3);
        out.push(0);
    }

    fn int(&self, v: u16) -> Vec<u8> {
        let mut d = Vec::new();
        self.u16(&mut d, v);
        d
    }

    fn float(&self, v: f32) -> Vec<u8> {
        let mut d = Vec::new();
        self.f32(&mut d, v);
        d
    }

    fn rate(&self) -> f32 {
        50.0
    }

    /// The parameter section (without its 4-byte header).
    fn params(&self) -> Vec<u8> {
        let mut p = Vec::new();
        self.group(&mut p, 1, "POINT");
        self.group(&mut p, 2, "ANALOG");
        let used = self.used.unwrap_or(self.points as u16);
        self.param(&mut p, 1, "USED", 2, &[], &self.int(used));
        self.param(&mut p, 1, "SCALE", 4, &[], &self.float(self.scale()));
        self.param(&mut p, 1, "RATE", 4, &[], &self.float(self.rate()));
        let frames = self.frames_param.unwrap_or(self.frames16());
        self.param(&mut p, 1, "FRAMES", 2, &[], &self.int(frames));
        match self.long {
            Some(Long::Trial) => {
                self.group(&mut p, 3, "TRIAL");
                let words = |v: u32| {
                    let mut d = self.int(v as u16);
                    d.extend(self.int((v >> 16) as u16));
                    d
                };
                self.param(&mut p, 3, "ACTUAL_START_FIELD", 2, &[2], &words(1));
                let end = words(self.frames as u32);
                self.param(&mut p, 3, "ACTUAL_END_FIELD", 2, &[2], &end);
            }
            Some(Long::LongFrames) => {
                let n = self.float(self.frames as f32);
                self.param(&mut p, 1, "LONG_FRAMES", 4, &[], &n);
            }
            None => {}
        }
        if let Some(u) = self.units {
            self.param(&mut p, 1, "UNITS", -1, &[u.len() as u8], u.as_bytes());
        }
        if let Some(labels) = &self.labels {
            let (a, b) = labels.split_at(labels.len().min(2));
            for (name, list) in [("LABELS", a), ("LABELS2", b)] {
                if list.is_empty() {
                    continue;
                }
                let text: Vec<u8> = list
                    .iter()
                    .flat_map(|l| format!("{l:<4}").into_bytes())
                    .collect();
                self.param(&mut p, 1, name, -1, &[4, list.len() as u8], &text);
            }
        }
        self.param(&mut p, 2, "USED", 2, &[], &self.int(self.analog as u16));
        self.param(&mut p, 2, "RATE", 4, &[], &self.float(2.0 * self.rate()));
        // DATA_START last, with next = 0.
        let start = p.len();
        self.param(
            &mut p,
            1,
            "DATA_START",
            2,
            &[],
            &self.int(self.data_block() as u16),
        );
        let next_at = start + 2 + "DATA_START".len();
        p[next_at] = 0;
        p[next_at + 1] = 0;
        p
    }

    fn params_len_raw(&self) -> usize {
        let labels: usize = self.labels.as_ref().map_or(0, |l| {
            let (a, b) = l.split_at(l.len().min(2));
            [("LABELS", a), ("LABELS2", b)]
                .iter()
                .filter(|(_, x)| !x.is_empty())
                .map(|(n, x)| 2 + n.len() + 2 + 2 + 2 + 4 * x.len() + 1)
                .sum()
        });
        let units = self.units.map_or(0, |u| 2 + 5 + 2 + 2 + 1 + u.len() + 1);
        let num = |name: &str, w: usize| 2 + name.len() + 2 + 2 + w + 1;
        let long = match self.long {
            Some(Long::Trial) => {
                (2 + 5 + 3)
                    + 2 * (num("ACTUAL_END_FIELD", 4) + 1)
                    + ("ACTUAL_START_FIELD".len() - "ACTUAL_END_FIELD".len())
            }
            Some(Long::LongFrames) => num("LONG_FRAMES", 4),
            None => 0,
        };
        long + (2 + 5 + 3)
            + (2 + 6 + 3)
            + num("USED", 2)
            + num("SCALE", 4)
            + num("RATE", 4)
            + num("FRAMES", 2)
            + units
            + labels
            + num("USED", 2)
            + num("RATE", 4)
            + num("DATA_START", 2)
    }

    fn data_block(&self) -> usize {
        2 + (4 + self.params_len_raw()).div_ceil(512)
    }

    fn write(&self) -> Vec<u8> {
        let word = if self.float { 4 } else { 2 };
        let analog_per_frame = self.analog * 2;
        let mut h = vec![2u8, 0x50];
        self.u16(&mut h, self.points as u16);
        self.u16(&mut h, analog_per_frame as u16);
        self.u16(&mut h, 1);
        self.u16(&mut h, self.frames16());
        self.u16(&mut h, 0);
        self.f32(&mut h, self.scale());
        self.u16(&mut h, self.data_block() as u16);
        self.u16(&mut h, 2);
        self.f32(&mut h, self.rate());
        h.resize(512, 0);
        let params = self.params();
        assert_eq!(params.len(), self.params_len_raw());
        let blocks = self.data_block() - 2;
        h.extend([1, 0x50, blocks as u8, self.processor.code()]);
        h.extend(params);
        h.resize((self.data_block() - 1) * 512, 0);
        for f in 0..self.frames {
            for p in 0..self.points {
                let pos = Self::position(f, p);
                let gone = Self::missing(f, p);
                if self.float {
                    for v in pos {
                        self.f32(&mut h, if gone { 0.0 } else { v as f32 });
                    }
                    self.f32(&mut h, if gone { -1.0 } else { 2.5 });
                } else {
                    for v in pos {
                        self.u16(&mut h, if gone { 0 } else { (v / 0.5) as i16 as u16 });
                    }
                    self.u16(&mut h, if gone { 0xffff } else { 0x0305 });
                }
            }
            // Analog samples: values no reader should look at.
            for _ in 0..analog_per_frame {
                h.extend(std::iter::repeat_n(0xff, word));
            }
        }
        h
    }

    /// Offset of point `p`'s values at frame `f`.
    fn point_at(&self, f: usize, p: usize) -> usize {
        let word = if self.float { 4 } else { 2 };
        (self.data_block() - 1) * 512
            + f * (self.points * 4 + self.analog * 2) * word
            + p * 4 * word
    }
}

const ALL: [Processor; 3] = [Processor::Intel, Processor::Dec, Processor::Mips];

fn read(spec: &Spec) -> Result<C3d, C3dError> {
    parse(&spec.write(), "t.c3d")
}

#[test]
fn identical_reads_across_encodings() {
    for float in [false, true] {
        for analog in [0, 2] {
            for labels in [true, false] {
                let mut first: Option<C3d> = None;
                for processor in ALL {
                    let mut s = Spec::new(processor, float);
                    s.analog = analog;
                    if !labels {
                        s.labels = None;
                    }
                    let c = read(&s).unwrap_or_else(|e| panic!("{processor:?} float {float}: {e}"));
                    assert_eq!(c.processor, processor);
                    assert_eq!((c.frames, c.points, c.float), (7, 4, float));
                    assert_eq!(c.rate_hz, 50.0);
                    assert_eq!(c.analog_per_frame, 2 * analog);
                    assert_eq!(c.unit, LengthUnit::Mm);
                    for f in 0..7 {
                        for p in 0..4 {
                            let i = f * 4 + p;
                            assert_eq!(c.missing[i], Spec::missing(f, p), "{f} {p}");
                            let want = if Spec::missing(f, p) {
                                [0.0; 3]
                            } else {
                                Spec::position(f, p)
                            };
                            assert_eq!(c.positions[i], want, "{processor:?} {float} {f} {p}");
                        }
                    }
                    match &first {
                        None => first = Some(c),
                        Some(a) => {
                            assert_eq!(a.positions, c.positions);
                            assert_eq!(a.missing, c.missing);
                            assert_eq!(a.labels, c.labels);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn labels_names_and_motion() {
    let c = read(&Spec::new(Processor::Intel, false)).unwrap();
    assert_eq!(
        c.labels,
        [Some("LHEE"), Some("RTOE"), Some("RTOE"), Some("C7")].map(|s| s.map(String::from))
    );
    assert_eq!(c.marker_names(), ["LHEE", "RTOE", "RTOE_2", "C7"]);
    let mut s = Spec::new(Processor::Mips, true);
    s.labels = None;
    s.units = None;
    let c = read(&s).unwrap();
    assert_eq!(c.marker_names(), ["P01", "P02", "P03", "P04"]);
    assert_eq!(c.unit_source, UnitSource::Default);
    let m = c.to_markers();
    assert_eq!(m.motion.frames(), 7);
    assert_eq!(m.motion.channels(), 12);
    assert!((m.motion.frame_time - 0.02).abs() < 1e-15);
    assert_eq!(m.missing.count(), 4);
    assert_eq!(m.motion.frame(2)[3..6], Spec::position(2, 1));
    let mut s = Spec::new(Processor::Dec, false);
    s.units = Some("cm");
    let c = read(&s).unwrap();
    assert_eq!(
        (c.unit, c.unit_source),
        (LengthUnit::Cm, UnitSource::Parameter("cm".into()))
    );
}

#[test]
fn dec_floats_convert_exactly() {
    for v in [
        1.0f32,
        -1.0,
        0.5,
        3.25,
        -250.5,
        1e-30,
        6.5e30,
        f32::MIN_POSITIVE * 4.0,
    ] {
        assert_eq!(dec_f32(dec_bytes(v)), Some(f64::from(v)), "{v}");
    }
    assert_eq!(dec_f32([0, 0, 0, 0]), Some(0.0));
    // A dirty zero (exponent 0, fraction set) is 0; with the sign set, the reserved operand.
    assert_eq!(dec_f32([0x12, 0x00, 0x34, 0x56]), Some(0.0));
    assert_eq!(dec_f32([0x00, 0x80, 0x00, 0x00]), None);
    // The largest exponent (IEEE's inf/NaN bits) is an ordinary number: (1 − 2^-24) · 2^127.
    let max = dec_f32([0xff, 0x7f, 0xff, 0xff]).unwrap();
    assert_eq!(max, (2f64.powi(24) - 1.0) * 2f64.powi(127 - 24));
    // The smallest: 0.5 · 2^(1 − 128), below f32's normal range.
    assert_eq!(dec_f32([0x80, 0x00, 0x00, 0x00]), Some(2f64.powi(-128)));
}

#[test]
fn every_truncation_is_an_error_with_offset() {
    for processor in ALL {
        for float in [false, true] {
            let bytes = Spec::new(processor, float).write();
            for n in 0..bytes.len() {
                let e = parse(&bytes[..n], "t.c3d").expect_err("a truncated file is an error");
                let at = e.offset.expect("an offset");
                assert!(at <= bytes.len(), "{processor:?} {float} at {n}: {e}");
                assert!(e.to_string().starts_with("t.c3d: byte "), "{e}");
            }
        }
    }
}

/// `bytes` with `f` applied, read.
fn patched(spec: &Spec, f: impl FnOnce(&mut Vec<u8>)) -> C3dError {
    let mut b = spec.write();
    f(&mut b);
    parse(&b, "bad.c3d").expect_err("malformed")
}

fn assert_err(e: C3dError, offset: usize, text: &str) {
    assert_eq!(e.offset, Some(offset), "{e}");
    assert!(e.message.contains(text), "{e} (wanted '{text}')");
}

#[test]
fn malformed_files_name_the_offset() {
    let s = Spec::new(Processor::Intel, true);
    assert_err(patched(&s, |b| b[1] = 0x51), 1, "not a C3D file");
    assert_err(patched(&s, |b| b[0] = 1), 0, "parameter block pointer is 1");
    assert_err(patched(&s, |b| b[0] = 0), 0, "parameter block pointer is 0");
    assert_err(patched(&s, |b| b[0] = 200), 0, "past the end of the file");
    assert_err(
        patched(&s, |b| b[512 + 3] = 83),
        515,
        "unknown processor type 83",
    );
    // The header's counts against the parameters'.
    assert_err(
        patched(&s, |b| b[2] = 5),
        516 + 10 + 11,
        "POINT:USED is 4, the header says 5",
    );
    let mut t = s.clone();
    t.frames_param = Some(9);
    let e = read(&t).unwrap_err();
    assert!(e.message.contains("POINT:FRAMES is 9"), "{e}");
    assert_err(patched(&s, |b| b[8] = 0), 8, "before the first frame");
    assert_err(patched(&s, |b| b[4] = 3), 4, "analog values per frame");
    let block = s.data_block() as u8;
    let e = patched(&s, |b| b[16] = block + 1);
    assert!(e.message.contains("POINT:DATA_START is block"), "{e}");
    // Bad numbers: NaN and infinite floats where they are read.
    let nan = f32::NAN.to_le_bytes();
    assert_err(
        patched(&s, |b| b[12..16].copy_from_slice(&nan)),
        12,
        "the header's scale is not a number",
    );
    let at = s.point_at(3, 2) + 4;
    assert_err(
        patched(&s, |b| {
            b[at..at + 4].copy_from_slice(&f32::INFINITY.to_le_bytes())
        }),
        at,
        "the y coordinate of point 3 at frame 4 is not a number",
    );
    let at = s.point_at(3, 2) + 12;
    assert_err(
        patched(&s, |b| b[at..at + 4].copy_from_slice(&nan)),
        at,
        "residual is not a number",
    );
    // A NaN coordinate of a missing sample is never read.
    let mut b = s.write();
    let at = s.point_at(0, 1);
    b[at..at + 4].copy_from_slice(&nan);
    assert!(parse(&b, "ok.c3d").is_ok());
    // DEC's reserved operand.
    let d = Spec::new(Processor::Dec, true);
    let at = d.point_at(2, 0);
    assert_err(
        patched(&d, |b| b[at..at + 4].copy_from_slice(&[0, 0x80, 0, 0])),
        at,
        "not a number",
    );
    // Units that are no length.
    let mut u = s.clone();
    u.units = Some("ft");
    let e = read(&u).unwrap_err();
    assert!(e.message.contains("POINT:UNITS 'ft'"), "{e}");
    // A record pointing backwards, and one past the section.
    let first_next = 512 + 4 + 2 + 5;
    assert_err(
        patched(&s, |b| {
            b[first_next..first_next + 2].copy_from_slice(&(-4i16).to_le_bytes())
        }),
        first_next,
        "points backwards",
    );
    assert_err(
        patched(&s, |b| {
            b[first_next..first_next + 2].copy_from_slice(&2000i16.to_le_bytes())
        }),
        first_next,
        "past the parameter section's end",
    );
    // A parameter of an unknown type.
    let kind_at = 512 + 4 + 10 + 11 + 2 + 4 + 2;
    assert_err(patched(&s, |b| b[kind_at] = 3), kind_at, "has type 3");
}

/// Takes of more than 65 535 frames: the header's words stop at 65 535;
/// TRIAL's 32-bit fields or POINT:LONG_FRAMES give the length, in every
/// encoding.
#[test]
fn takes_longer_than_65535_frames() {
    for (processor, long) in [
        (Processor::Intel, Long::Trial),
        (Processor::Mips, Long::Trial),
        (Processor::Dec, Long::LongFrames),
        (Processor::Intel, Long::LongFrames),
    ] {
        let mut s = Spec::new(processor, true);
        s.points = 1;
        s.labels = None;
        s.analog = 0;
        s.frames = 70_001;
        s.long = Some(long);
        let c = read(&s).unwrap();
        assert_eq!(c.frames, 70_001);
        assert_eq!(c.first_frame, 1);
        let last = Spec::position(70_000, 0).map(|v| v as f32 as f64);
        assert_eq!(c.positions[70_000], last);
        // One frame short: the frame that is cut is named.
        let mut b = s.write();
        b.truncate(b.len() - 16);
        let e = parse(&b, "long.c3d").unwrap_err();
        assert!(e.message.contains("frame 70001 of 70001"), "{e}");
    }
    // An end before the start is an error at the parameter.
    let mut s = Spec::new(Processor::Intel, false);
    s.long = Some(Long::Trial);
    s.frames = 70_000;
    let mut b = s.write();
    let name = b"ACTUAL_END_FIELD";
    let at = b.windows(name.len()).position(|w| w == name).unwrap() + name.len() + 2 + 3;
    b[at..at + 4].copy_from_slice(&[0, 0, 0, 0]);
    let e = parse(&b, "t.c3d").unwrap_err();
    assert!(e.message.contains("is before ACTUAL_START_FIELD"), "{e}");
}

#[test]
fn reads_the_corpus_shapes_when_counts_are_large() {
    // More points than fit the data: the frame that is cut is named.
    let mut s = Spec::new(Processor::Mips, false);
    s.frames = 3;
    let mut b = s.write();
    b.truncate(b.len() - 1);
    let e = parse(&b, "cut.c3d").unwrap_err();
    assert!(e.message.contains("frame 3 of 3"), "{e}");
    assert_eq!(e.offset, Some(s.point_at(2, 0)));
}

/// A file read in the wrong encoding: Intel and MIPS swapped break the
/// parameter records' offsets (an error with its offset); DEC read as Intel
/// or the other way gives other numbers or an error — never a panic, never
/// the same read.
#[test]
fn wrong_encodings_are_caught() {
    let processor_at = 512 + 3;
    for (from, to) in [
        (Processor::Intel, Processor::Mips),
        (Processor::Mips, Processor::Intel),
        (Processor::Dec, Processor::Mips),
    ] {
        let s = Spec::new(from, true);
        let e = patched(&s, |b| b[processor_at] = to.code());
        assert!(e.offset.is_some(), "{from:?} as {to:?}: {e}");
    }
    for (from, to) in [
        (Processor::Intel, Processor::Dec),
        (Processor::Dec, Processor::Intel),
    ] {
        for float in [false, true] {
            let s = Spec::new(from, float);
            let mut b = s.write();
            b[processor_at] = to.code();
            match parse(&b, "t.c3d") {
                Ok(c) => assert_ne!(Some(c), read(&s).ok(), "{from:?} as {to:?}"),
                Err(e) => assert!(e.offset.is_some(), "{e}"),
            }
        }
    }
}

/// Every byte of a file set to 0x00, 0x7f, 0x80 and 0xff in turn: the reader
/// reads it or says where it breaks, never panics.
#[test]
fn every_byte_changed_reads_or_errs_with_offset() {
    for processor in ALL {
        let s = Spec::new(processor, processor != Processor::Dec);
        let bytes = s.write();
        for i in 0..bytes.len() {
            for v in [0x00, 0x7f, 0x80, 0xff] {
                let mut b = bytes.clone();
                b[i] = v;
                if let Err(e) = parse(&b, "t.c3d") {
                    assert!(e.offset.is_some_and(|o| o < b.len()), "{i} = {v:#x}: {e}");
                }
            }
        }
    }
}

/// A header that claims 65 535 frames the file does not hold: an error at the
/// first missing frame, before anything is allocated for them.
#[test]
fn claimed_frames_past_the_file() {
    let mut s = Spec::new(Processor::Intel, false);
    s.frames_param = Some(0xffff);
    let e = patched(&s, |b| b[8..10].copy_from_slice(&0xffffu16.to_le_bytes()));
    assert_eq!(e.offset, Some(s.point_at(7, 0)));
    assert!(
        e.message.contains("file ends inside frame 8 of 65535"),
        "{e}"
    );
}
