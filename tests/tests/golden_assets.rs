//! The files the project ships stay what their generators make: the demo
//! BVH is the generator's output, and the firmware's default clip is exactly
//! what `mocap encode` (defaults: index codec, 1°) makes of it today. A change
//! to the encoder or the bitstream shows up here as a golden-file diff;
//! regenerate with the commands in README.md ("Shipped files").

use mocap_decoder::Clip;
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::{bvh, generate, units};
use mocap_tests::workspace_root;

#[test]
fn demo_bvh_is_the_generators_output() {
    let shipped = bvh::read_file(&workspace_root().join("assets/animatronic_demo.bvh")).unwrap();
    let made = generate::animatronic_demo();
    assert_eq!(shipped.skeleton, made.skeleton);
    assert_eq!(shipped.frames(), made.frames());
    for (a, b) in shipped.values.iter().zip(&made.values) {
        assert!((a - b).abs() < 1e-6);
    }
}

#[test]
fn firmware_default_clip_is_current() {
    let shipped = std::fs::read(workspace_root().join("firmware-example/clips/demo.mcb")).unwrap();
    let m = bvh::read_file(&workspace_root().join("assets/animatronic_demo.bvh")).unwrap();
    let opts = EncodeOptions {
        key_bits: None,
        codec: CodecChoice::Index,
        bound: Bound::from_specs(&["1deg".parse::<BoundSpec>().unwrap()]),
        metres_per_unit: units::detect(&m).metres(),
        key_interval: None,
        index_layout: Default::default(),
        pattern: Default::default(),
    };
    let enc = encode::encode(&m, &opts).unwrap();
    Clip::parse(&shipped).unwrap();
    assert!(
        enc.bytes == shipped,
        "firmware-example/clips/demo.mcb is stale: regenerate it (README.md, Shipped files)"
    );
}

#[test]
fn firmware_demo_show_is_current() {
    use mocap_encoder::show::{self, file::ShowSpec};
    let shipped =
        std::fs::read(workspace_root().join("firmware-example/clips/demo_show.mcb")).unwrap();
    let spec = ShowSpec::read_file(&workspace_root().join("assets/shows/demo.toml")).unwrap();
    let built = show::build(&spec).unwrap().bytes;
    mocap_decoder::Show::parse(&shipped).unwrap();
    assert!(
        built == shipped,
        "firmware-example/clips/demo_show.mcb is stale: regenerate it (README.md, Shipped files)"
    );
}
