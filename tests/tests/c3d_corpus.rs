//! The C3D marker files of the corpus (`c3d/`): read (frames, rate,
//! points, labels, missing fraction printed), encoded with each codec at 5 mm
//! and 20 mm, the bound held on every present sample, the decoded mask equal
//! to the reader's; the marker clip plays through the rest of the chain
//! (`decode_against`, metrics, the BVH writer).

use mocap_decoder::Clip;
use mocap_encoder::encode::{Bound, CodecChoice, EncodeOptions};
use mocap_encoder::markers::{self, MissingMask};
use mocap_encoder::{bvh, c3d, clipfile};
use mocap_tests::corpus_files_ext;

#[test]
fn c3d_corpus_reads() {
    let Some(files) = corpus_files_ext("c3d", "c3d") else {
        return;
    };
    assert!(files.len() >= 2, "the corpus has two C3D files");
    for file in &files {
        let c = c3d::read_file(file).unwrap();
        let name = file.file_name().unwrap().to_string_lossy();
        eprintln!(
            "{name}: {}; labels {}",
            c.summary(),
            c.marker_names().join(" ")
        );
        assert!(
            c.labels.iter().all(Option::is_some),
            "{name}: every point is labelled"
        );
        let shape = (c.float, c.frames, c.rate_hz, c.points);
        match &*name {
            "01_Eb015pi.c3d" => assert_eq!(shape, (false, 450, 50.0, 26)),
            "00_Walk1.c3d" => {
                assert_eq!(shape, (true, 151, 60.0, 49));
                assert!((0.15..0.17).contains(&c.missing_fraction()));
            }
            _ => {}
        }
    }
}

#[test]
fn c3d_corpus_roundtrip() {
    let Some(files) = corpus_files_ext("c3d", "c3d") else {
        return;
    };
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        let clip = c3d::read_markers(file).unwrap();
        let mpu = clip.unit.metres();
        for codec in [
            CodecChoice::Index,
            CodecChoice::PcaSpline,
            CodecChoice::Predictive,
        ] {
            // 5 mm (the bench's tight marker bound), 20 mm and 50 mm + ARMS
            // 10 mm; the angle bound (1°) does not apply to a marker clip
            // (no rotation channel: the CLI refuses it with a message).
            for (mm, arms) in [(5.0, None), (20.0, None), (50.0, Some(10.0))] {
                let opts = EncodeOptions {
                    key_bits: None,
                    codec,
                    bound: Bound {
                        angle_deg: None,
                        position_mm: Some(mm),
                        arms_mm: arms,
                        foot_slide_mm_s: None,
                    },
                    metres_per_unit: mpu,
                    key_interval: None,
                    index_layout: Default::default(),
                    pattern: Default::default(),
                };
                let enc = markers::encode_markers(&clip, &opts)
                    .unwrap_or_else(|e| panic!("{name} {codec:?} {mm} mm: {e}"));
                let bytes = &enc.encoded.bytes;
                // Independently: decode, compare over the present samples.
                let parsed = Clip::parse(bytes).unwrap();
                let filled = markers::fill(&clip.motion, &clip.missing);
                let back = clipfile::decode_against(&parsed, &filled, mpu).unwrap();
                let x = markers::marker_errors(&clip.motion, &back, &clip.missing, mpu);
                assert_eq!(x, enc.error);
                assert!(x.max_mm <= mm, "{name} {codec:?} at {mm} mm: {x:?}");
                if let Some(a) = arms {
                    assert!(x.arms_mm <= a, "{name} {codec:?} ARMS {a} mm: {x:?}");
                }
                assert_eq!(x.missing, clip.missing.count());
                let decoded_mask = MissingMask::of_clip(&parsed).unwrap_or_else(|| {
                    MissingMask::none(clip.missing.frames, clip.missing.markers)
                });
                assert_eq!(decoded_mask, clip.missing, "{name}: the clip's mask");
                eprintln!(
                    "{name} {} @ {mm} mm, ARMS {arms:?} mm: {} bytes (ratio {:.1}:1 vs f32), marker error max {:.2} mm ({} at frame {}), ARMS {:.2} mm, RMS {:.2} mm over {} present samples, {} missing in {} runs",
                    codec.name(),
                    bytes.len(),
                    enc.encoded.metrics.ratio_f32,
                    x.max_mm,
                    x.max_marker,
                    x.max_frame,
                    x.arms_mm,
                    x.rms_mm,
                    x.present,
                    x.missing,
                    clip.missing.runs()
                );
            }
        }
        // The BVH writer takes the marker skeleton (roots without End Sites).
        let text = bvh::write_string(&clip.motion);
        let again = bvh::parse_str(&text, "markers.bvh").unwrap();
        assert_eq!(again.skeleton, clip.motion.skeleton);
    }
}
