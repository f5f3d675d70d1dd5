//! Motion Track (src/track/): SOM, LLE, IDW, the SVG's structure (the
//! corpus check is tests/tests/corpus_track.rs).

use mocap_encoder::motion::{ChannelKind::*, Joint, Motion, Skeleton};
use mocap_report::track::features::{self, quat_frames, rotating_joints};
use mocap_report::track::idw::{self, Scheme};
use mocap_report::track::som::{self, SomConfig, SplitMix64};
use mocap_report::track::{build_reference, lle, render, Track, TrackOptions};

fn gauss(rng: &mut SplitMix64) -> f64 {
    // Box–Muller.
    let u = rng.next_f64().max(1e-12);
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

#[test]
fn som_converges_on_synthetic_clusters() {
    let dim = 6;
    let centres: Vec<Vec<f32>> = (0..4)
        .map(|c| (0..dim).map(|d| if d == c { 3.0 } else { 0.0 }).collect())
        .collect();
    let mut rng = SplitMix64(42);
    let mut data = Vec::new();
    for i in 0..800 {
        let c = &centres[i % 4];
        data.extend(c.iter().map(|&v| v + 0.05 * gauss(&mut rng) as f32));
    }
    let cfg = SomConfig {
        width: 4,
        height: 4,
        epochs: 20,
        seed: 3,
        sigma_end: 0.5,
    };
    let map = som::train(&data, dim, &cfg);
    // Every cluster centre has a node close to it.
    for c in &centres {
        let (_, d2) = som::nearest(&map.nodes, dim, c);
        assert!(
            d2.sqrt() < 0.1,
            "no node near cluster centre {c:?}: {}",
            d2.sqrt()
        );
    }
    // Quantisation error is of the order of the noise (0.05·√6 ≈ 0.12),
    // far below the clusters' separation (3·√2 ≈ 4.2).
    let qe = map.quantisation_error(&data);
    assert!(qe < 0.2, "quantisation error {qe}");
    // Each cluster's frames map to nodes that no other cluster uses.
    let bmus = map.bmus(&data);
    for i in 0..bmus.len() {
        for j in 0..bmus.len() {
            if i % 4 != j % 4 {
                assert_ne!(bmus[i], bmus[j]);
            }
        }
    }
    // Reproducible for a seed.
    assert_eq!(som::train(&data, dim, &cfg).nodes, map.nodes);
}

/// Least-squares fit of `target` by an affine function of `x` (rows of 2);
/// returns R².
fn affine_r2(x: &[[f64; 2]], target: &[f64]) -> f64 {
    use nalgebra::{DMatrix, DVector};
    let n = x.len();
    let a = DMatrix::from_fn(n, 3, |i, j| if j < 2 { x[i][j] } else { 1.0 });
    let b = DVector::from_column_slice(target);
    let sol = (a.transpose() * &a)
        .lu()
        .solve(&(a.transpose() * &b))
        .unwrap();
    let fit = &a * sol;
    let mean = target.iter().sum::<f64>() / n as f64;
    let ss_res: f64 = (0..n).map(|i| (target[i] - fit[i]).powi(2)).sum();
    let ss_tot: f64 = target.iter().map(|t| (t - mean).powi(2)).sum();
    1.0 - ss_res / ss_tot
}

#[test]
fn lle_unrolls_a_swiss_roll_up_to_an_affine_map() {
    // A swiss roll sampled on a jittered grid of its intrinsic (t, h).
    let mut rng = SplitMix64(9);
    // About as long along the roll (arc ≈ 33) as across it (26), so the
    // two slowest modes are the two intrinsic directions.
    let (nt, nh) = (25, 20);
    let mut pts = Vec::new();
    let mut intrinsic = Vec::new();
    for i in 0..nt {
        for j in 0..nh {
            let t =
                1.5 * std::f64::consts::PI * (1.0 + (i as f64 + 0.3 * rng.next_f64()) / nt as f64);
            let h = 26.0 * (j as f64 + 0.3 * rng.next_f64()) / nh as f64;
            pts.extend([t * t.cos(), h, t * t.sin()]);
            intrinsic.push([t, h]);
        }
    }
    let y = lle::embed(&pts, 3, 10, 2).unwrap();
    let y: Vec<[f64; 2]> = y.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    // The roll's arc length s(t) ∝ t² is the natural unrolled coordinate.
    let s: Vec<f64> = intrinsic.iter().map(|p| p[0] * p[0]).collect();
    let t: Vec<f64> = intrinsic.iter().map(|p| p[0]).collect();
    let h: Vec<f64> = intrinsic.iter().map(|p| p[1]).collect();
    let r2_t = affine_r2(&y, &t).max(affine_r2(&y, &s));
    let r2_h = affine_r2(&y, &h);
    eprintln!("swiss roll: R² along the roll {r2_t:.3}, across {r2_h:.3}");
    assert!(r2_t > 0.9 && r2_h > 0.9, "R² {r2_t} / {r2_h}");
}

#[test]
fn idw_weights_sum_to_one() {
    let mut rng = SplitMix64(5);
    for trial in 0..200 {
        let n = 1 + rng.below(40);
        let mut h: Vec<f64> = (0..n).map(|_| rng.next_f64() * 3.0).collect();
        if trial % 10 == 0 {
            h[rng.below(n)] = 0.0;
        }
        for scheme in [Scheme::Eq2, Scheme::Eq3, Scheme::Eq4] {
            for p in [1.0, 2.0, 8.0] {
                let w = idw::weights(&h, scheme, p);
                let sum: f64 = w.iter().sum();
                assert!((sum - 1.0).abs() < 1e-9, "{scheme} p={p}: sum {sum}");
                assert!(w.iter().all(|x| x.is_finite() && *x >= 0.0));
                // Nearer key frames never weigh less.
                for a in 0..n {
                    for b in 0..n {
                        if h[a] < h[b] {
                            assert!(w[a] >= w[b] - 1e-12, "{scheme}: not monotone");
                        }
                    }
                }
            }
        }
    }
    // A frame on a key frame sits on it (eq. 2 and 3).
    let key_xy = [[1.0, 2.0], [5.0, -1.0], [0.0, 0.0]];
    for scheme in [Scheme::Eq2, Scheme::Eq3] {
        assert_eq!(
            idw::place(&[0.7, 0.0, 1.2], &key_xy, scheme, 2.0),
            [5.0, -1.0]
        );
    }
}

/// Degenerate distances: a frame on a key frame (h = 0), all key frames at
/// the frame (R = 0), a single key frame, all at the same distance, distances
/// so small or large, and p so large, that the plain powers overflow or
/// underflow. The weights stay finite and sum to one, and the placed point
/// stays inside the key frames' bounding box (it is a convex combination).
#[test]
fn idw_weights_finite_in_degenerate_cases() {
    let cases: [&[f64]; 9] = [
        &[0.0],
        &[0.0, 0.0, 0.0],
        &[0.0, 1.0, 2.0],
        &[1.5],
        &[0.7, 0.7, 0.7, 0.7],
        &[2e-12, 1.0, 3.0],
        &[1e-200, 1e-100, 1.0],
        &[1e200, 1e250, 1e300],
        &[1e-3, 1e-3 * (1.0 + 1e-15), 5.0],
    ];
    let key_xy = [[1.0, 2.0], [5.0, -1.0], [0.0, 0.0], [-3.0, 4.0]];
    for h in cases {
        for scheme in [Scheme::Eq2, Scheme::Eq3, Scheme::Eq4] {
            for p in [1.0, 2.0, 8.0, 64.0, 400.0] {
                let w = idw::weights(h, scheme, p);
                let sum: f64 = w.iter().sum();
                assert!(
                    w.iter().all(|x| x.is_finite() && *x >= 0.0) && (sum - 1.0).abs() < 1e-9,
                    "{scheme} p={p} h={h:?}: {w:?}"
                );
                let xy = idw::place(h, &key_xy[..h.len()], scheme, p);
                for c in 0..2 {
                    let lo = key_xy[..h.len()]
                        .iter()
                        .map(|k| k[c])
                        .fold(f64::INFINITY, f64::min);
                    let hi = key_xy[..h.len()]
                        .iter()
                        .map(|k| k[c])
                        .fold(f64::NEG_INFINITY, f64::max);
                    assert!(
                        xy[c] >= lo - 1e-9 && xy[c] <= hi + 1e-9,
                        "{scheme} p={p} h={h:?}: {xy:?}"
                    );
                }
            }
        }
    }
    // Eq. 3 with a key frame just outside the exact-hit tolerance and a
    // large p: the old plain power overflowed to ∞ and fell back to equal
    // weights (the centroid); the frame belongs on that key frame.
    let w = idw::weights(&[2e-12, 1.0, 3.0], Scheme::Eq3, 64.0);
    assert!(w[0] > 1.0 - 1e-9, "{w:?}");
}

/// A small skeleton: root (6 channels), spine, two arms (3 rotations each).
fn skeleton() -> Skeleton {
    let rot = vec![Zrotation, Xrotation, Yrotation];
    let j = |name: &str, parent: Option<usize>, offset: [f64; 3], channels: Vec<_>| Joint {
        name: name.into(),
        parent,
        offset,
        channels,
        end_site: false,
    };
    Skeleton {
        joints: vec![
            j(
                "Hips",
                None,
                [0.0; 3],
                vec![
                    Xposition, Yposition, Zposition, Zrotation, Xrotation, Yrotation,
                ],
            ),
            j("Spine", Some(0), [0.0, 10.0, 0.0], rot.clone()),
            j("LeftArm", Some(1), [5.0, 5.0, 0.0], rot.clone()),
            j("RightArm", Some(1), [-5.0, 5.0, 0.0], rot),
        ],
    }
}

/// A periodic motion: `style` changes amplitudes and phase; the root turns
/// and travels (the translation the features must ignore).
fn synthetic(style: f64, frames: usize) -> Motion {
    let sk = skeleton();
    let c = sk.channel_count();
    let mut values = Vec::with_capacity(frames * c);
    for f in 0..frames {
        let t = f as f64 / 30.0;
        let w = std::f64::consts::TAU * (1.0 + style) * t;
        let a = 20.0 + 40.0 * style;
        values.extend([
            3.0 * t,
            90.0,
            t,
            0.0,
            5.0 * style,
            120.0 * t, // heading: removed
            10.0 * w.sin(),
            style * 30.0,
            0.0,
            a * w.sin(),
            a * w.cos(),
            10.0,
            -a * w.sin(),
            style * 50.0,
            -10.0,
        ]);
    }
    Motion {
        skeleton: sk,
        frame_time: 1.0 / 30.0,
        values,
    }
}

#[test]
fn heading_and_root_translation_do_not_change_the_features() {
    let m = synthetic(0.3, 40);
    let mut still = m.clone();
    let c = m.channels();
    for f in 0..m.frames() {
        still.values[f * c] = 0.0;
        still.values[f * c + 1] = 0.0;
        still.values[f * c + 2] = 0.0;
    }
    let joints = rotating_joints(&m);
    let (a, b) = (
        quat_frames(&m, &joints).unwrap(),
        quat_frames(&still, &joints).unwrap(),
    );
    for (x, y) in a.data.iter().zip(&b.data) {
        assert!((x - y).abs() < 1e-5);
    }
    // Unit quaternions with w ≥ 0.
    for q in a.data.chunks_exact(4) {
        let n: f32 = q.iter().map(|v| v * v).sum();
        assert!((n - 1.0).abs() < 1e-5 && q[0] >= 0.0);
    }
    // A turn about the world's vertical axis before the root's rotation
    // leaves its tilt unchanged.
    let mut rng = SplitMix64(1);
    for _ in 0..100 {
        let mut q = [1.0, 0.0, 0.0, 0.0];
        for axis in [2, 0, 1] {
            q = features::qmul(q, features::axis_quat(axis, 360.0 * rng.next_f64() - 180.0));
        }
        let turned = features::qmul(features::axis_quat(1, 360.0 * rng.next_f64()), q);
        let (a, b) = (
            features::remove_heading(q),
            features::remove_heading(turned),
        );
        let dot: f64 = (0..4).map(|i| a[i] * b[i]).sum();
        assert!((dot.abs() - 1.0).abs() < 1e-9, "{a:?} vs {b:?}");
        assert!(a[2].abs() < 1e-9, "tilt has a twist about Y: {a:?}");
    }
}

fn small_options() -> TrackOptions {
    TrackOptions {
        som: SomConfig {
            width: 5,
            height: 5,
            epochs: 15,
            seed: 11,
            sigma_end: 0.7,
        },
        k: 8,
        neighbours: Some(8),
        ..TrackOptions::default()
    }
}

#[test]
fn svg_has_one_path_per_clip_and_one_marker_per_key_frame() {
    let motions = [synthetic(0.0, 90), synthetic(0.5, 90), synthetic(1.0, 60)];
    let joints = rotating_joints(&motions[0]);
    let q: Vec<_> = motions
        .iter()
        .map(|m| quat_frames(m, &joints).unwrap())
        .collect();
    let opts = small_options();
    let space = build_reference(&q.iter().collect::<Vec<_>>(), &opts).unwrap();
    assert!(space.key_count() > 3 && space.key_count() <= 25);
    let tracks: Vec<Track> = q
        .iter()
        .enumerate()
        .map(|(i, qf)| Track {
            name: format!("clip{i}"),
            xy: space.place(qf, opts.scheme, opts.p, opts.neighbours),
            speed: qf.speed.clone(),
        })
        .collect();
    for t in &tracks {
        assert!(t.xy.iter().all(|p| p[0].is_finite() && p[1].is_finite()));
    }
    let dir = std::env::temp_dir().join(format!("mocap-track-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("track.svg");
    render::render(&path, "test", &tracks, &space.key_xy).unwrap();
    let svg = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let hex = |c: plotters::style::RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
    for (i, t) in tracks.iter().enumerate() {
        let stroke = format!("stroke=\"{}\"", hex(render::PALETTE[i]));
        let paths = svg
            .split("<polyline")
            .skip(1)
            .filter(|e| e.split('>').next().unwrap().contains(&stroke))
            .count();
        assert_eq!(paths, 1, "clip {i}: {paths} paths");
        // One dot per frame.
        assert!(svg.matches("<circle").count() >= t.xy.len());
        assert!(
            svg.contains(&format!(">{}<", t.name)) || svg.contains(&t.name),
            "legend lacks {}",
            t.name
        );
    }
    assert_eq!(svg.matches("<polyline").count(), tracks.len());
    let key_fill = format!("fill=\"{}\"", hex(render::KEY_COLOUR));
    let markers = svg
        .split("<rect")
        .skip(1)
        .filter(|e| e.split('>').next().unwrap().contains(&key_fill))
        .count();
    // One per key frame, and the legend's sample.
    assert_eq!(markers, space.key_count() + 1);
}
