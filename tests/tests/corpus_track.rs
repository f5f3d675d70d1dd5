//! Motion Track on the corpus: a decoded clip follows its source.

use mocap_report::track::features::{quat_frames, rotating_joints};
use mocap_report::track::som::SomConfig;
use mocap_report::track::{build_reference, Track, TrackOptions};
use mocap_tests::corpus_file;

#[test]
fn corpus_decoded_clip_tracks_its_source() {
    let (Some(walk), Some(run)) = (
        corpus_file("cmu", "35_01.bvh"),
        corpus_file("cmu", "35_17.bvh"),
    ) else {
        return;
    };
    let walk = mocap_encoder::bvh::read_file(&walk).unwrap();
    let run = mocap_encoder::bvh::read_file(&run).unwrap();
    let enc = mocap_tests::encode_index_1deg(&walk);
    let clip = mocap_decoder::Clip::parse(&enc).unwrap();
    let decoded = mocap_encoder::clipfile::to_motion(&clip).unwrap();
    let joints = rotating_joints(&walk);
    let qs: Vec<_> = [&walk, &run, &decoded]
        .iter()
        .map(|m| quat_frames(m, &joints).unwrap())
        .collect();
    // A small map (8×8 SOM, k = 12) trained briefly: enough to separate a
    // walk from a run, quick in a test.
    let opts = TrackOptions {
        som: SomConfig {
            width: 8,
            height: 8,
            epochs: 15,
            seed: 11,
            sigma_end: 0.7,
        },
        k: 12,
        neighbours: Some(8),
        ..TrackOptions::default()
    };
    let space = build_reference(&qs[..2].iter().collect::<Vec<_>>(), &opts).unwrap();
    let xy: Vec<_> = qs
        .iter()
        .map(|q| space.place(q, opts.scheme, opts.p, opts.neighbours))
        .collect();
    let tracks: Vec<Track> = xy
        .into_iter()
        .zip(["walk", "run", "walk decoded"])
        .zip(&qs)
        .map(|((xy, name), q)| Track {
            name: name.into(),
            xy,
            speed: q.speed.clone(),
        })
        .collect();
    // The decoded walk follows its source frame by frame, much closer than
    // the walk is to the run.
    let frame_gap: f64 = tracks[0]
        .xy
        .iter()
        .zip(&tracks[2].xy)
        .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt())
        .sum::<f64>()
        / tracks[0].xy.len() as f64;
    let stats = mocap_report::track::pair_stats(&tracks);
    let walk_run = stats.iter().find(|p| p.a == 0 && p.b == 1).unwrap().between;
    eprintln!("walk vs decoded walk: {frame_gap:.4} per frame; walk vs run: {walk_run:.4}");
    assert!(frame_gap < 0.25 * walk_run, "{frame_gap} vs {walk_run}");
}
