//! The two header sections (SPEC.md §3.1 postcard `0x01`, §3.4 compact
//! `0x02`) describe the same clip: same skeleton, same channels, ranges of
//! the compact form enclosing the exact ones, identical decoded frames.

use mocap_decoder::{consts, Clip};
use mocap_encoder::container::{assemble, HeaderWire};
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{clipfile, fixed, generate, units};

#[test]
fn compact_and_full_headers_agree() {
    let m = generate::animatronic_demo();
    let mpu = units::detect(&m).metres();
    let opts = EncodeOptions {
        key_bits: None,
        codec: CodecChoice::PcaSpline,
        bound: Bound::from_specs(&["1deg".parse::<BoundSpec>().unwrap()]),
        metres_per_unit: mpu,
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    let enc = encode::encode(&m, &opts).unwrap();
    let compact = Clip::parse(&enc.bytes).unwrap();
    assert!(compact
        .sections()
        .any(|s| s.id == consts::SECTION_HEADER_COMPACT));
    let codec = compact
        .sections()
        .find(|s| s.id == consts::SECTION_CODEC_PCA_SPLINE)
        .unwrap();
    let frames = clipfile::decode_all(&compact).unwrap();
    let n = m.channels();
    let decoded = fixed::FixedChannels {
        kinds: m.skeleton.channel_kinds(),
        values: (0..n)
            .map(|c| frames.iter().skip(c).step_by(n).copied().collect())
            .collect(),
    };
    let header = HeaderWire::new(&m, mpu, &decoded);
    let full_bytes = assemble(&[
        (consts::SECTION_HEADER, header.to_bytes()),
        (codec.id, codec.bytes.to_vec()),
    ]);
    let full = Clip::parse(&full_bytes).unwrap();
    assert!(header.to_compact().len() < header.to_bytes().len());
    assert_eq!(clipfile::decode_all(&full).unwrap(), frames);
    assert_eq!(clipfile::skeleton(&full), clipfile::skeleton(&compact));
    let (hf, hc) = (full.header(), compact.header());
    assert_eq!(hf.frame_time_ns(), hc.frame_time_ns());
    assert_eq!(hf.frame_count(), hc.frame_count());
    assert_eq!(hf.source_unit_nm(), hc.source_unit_nm());
    for (a, b) in hf.channels().zip(hc.channels()) {
        assert_eq!((a.joint, a.kind, a.unit), (b.joint, b.kind, b.unit));
        assert!(b.min <= a.min && a.max <= b.max, "{a:?} vs {b:?}");
        assert!(a.min - b.min < 1024 && b.max - a.max < 1024);
    }
    assert_eq!(hf.channels().count(), hc.channels().count());
    // Both forms in one clip are rejected.
    let both = assemble(&[
        (consts::SECTION_HEADER, header.to_bytes()),
        (consts::SECTION_HEADER_COMPACT, header.to_compact()),
        (codec.id, codec.bytes.to_vec()),
    ]);
    assert!(matches!(
        Clip::parse(&both),
        Err(mocap_decoder::Error::ContainerDuplicateSection { .. })
    ));
}
