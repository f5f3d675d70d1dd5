//! `mocap encode`: a BVH file into a `.mcb` clip (or, with `--rig`, a servo
//! clip; a `.c3d` marker file into a marker clip, [`super::markers`]), the
//! bound proven by decoding; `--emit` also writes it as source.

use std::path::{Path, PathBuf};

use mocap_encoder::codec::index::IndexLayout;
use mocap_encoder::codec::CodecChoice;
use mocap_encoder::encode::{self, Bound, BoundSpec, EncodeOptions};
use mocap_encoder::motion::Motion;
use mocap_encoder::rig::Rig;
use mocap_encoder::servo_clip;
use mocap_encoder::target::{self, Budget, Chip};

use super::{write, CodecArg, MotionArgs, UnitArg};

#[derive(clap::Args)]
pub struct Args {
    /// Input motion: a BVH file, an AMC file with its ASF skeleton
    /// (`--skeleton`, or the `.asf` beside it), or a C3D marker file (`.c3d`).
    input: PathBuf,
    #[command(flatten)]
    motion: MotionArgs,
    /// Output .mcb file.
    #[arg(short, long)]
    output: PathBuf,
    /// Target of the bitstream: `mcu` (any microcontroller) or a chip
    /// (`mocap target list`: rp2040, stm32f411, esp32c3, the QEMU boards…);
    /// for a chip the encoder prints the clip's predicted decode cost there
    /// (`mocap target cost`) and keeps the chip's flash and RAM.
    #[arg(long, default_value = "mcu")]
    target: String,
    /// With a chip --target: what playing the clip may take of it,
    /// `cpu=2%,ram=4k,flash=64k` (any of the three). Without --codec every
    /// codec is tried and the smallest clip that fits is kept.
    #[arg(long, value_parser = parse_budget)]
    budget: Option<Budget>,
    /// Codec (default: `index` for motion clips — the cheapest to decode —
    /// and `predictive` for servo and marker clips — the smallest).
    #[arg(long, value_enum)]
    codec: Option<CodecArg>,
    /// Error bound, repeatable: `1deg` (rotation channels), `8mm` (max
    /// joint position error by forward kinematics), `arms:10mm` (mean
    /// RMS joint error), `slide:20mm/s` (the decoded feet's slide where the
    /// source's are planted, above the source's own; on top of the
    /// others); `+` joins several in one value. Default: `1deg`;
    /// a C3D marker file takes lengths only (the marker position error),
    /// default `1mm`.
    #[arg(long = "max-error", visible_alias = "bound", value_parser = parse_bounds)]
    max_error: Vec<Vec<BoundSpec>>,
    /// Length unit of the input (auto: the ASF's declared unit or a C3D
    /// file's POINT:UNITS, else from the skeleton's height).
    #[arg(long, default_value = "auto")]
    units: UnitArg,
    /// Force the key-frame interval of the index codec (0 = none), or the
    /// block length in frames of the predictive codec (default: 10 s).
    #[arg(long)]
    key_interval: Option<u16>,
    /// Layout of the index codec's section: `compact` (SPEC.md §4.1, the
    /// smallest clip) or `fast` (SPEC.md §4.6: final-value tables, index
    /// widths of 1, 2, 4, 8 or 16 bits on whole bytes — about 2.2× fewer
    /// decode instructions on a Cortex-M3 for a ~60 % larger clip; BENCHMARKS.md §2).
    /// Default: compact; with a chip as --target, both are tried and the
    /// smaller clip that fits the budget is kept.
    #[arg(long)]
    index_layout: Option<IndexLayout>,
    /// The `pattern` codec's body-part nodes: joint names, `,` between
    /// the joints of a node and `;` between nodes, e.g.
    /// `LeftUpLeg,LeftLeg,LeftFoot,LeftToeBase;RightUpLeg,RightLeg`.
    /// Joints in no node keep the skeleton's limbs (the default: chains of
    /// joints between branchings, the root's translations and heading
    /// together). A show file sets them with `pattern_nodes`.
    #[arg(long, value_parser = parse_nodes)]
    pattern_nodes: Option<PatternNodes>,
    /// The `pattern` codec's layout: `packed` (SPEC.md §11.3c: codes
    /// bit-packed, the smallest clip) or `columns` (§11.3b: whole-byte
    /// codes, 14–28 % larger and a quarter fewer decode instructions on a
    /// Cortex-M3; BENCHMARKS.md §11). A show file sets it with
    /// `pattern_layout`.
    #[arg(long, value_parser = parse_pattern_layout, default_value = "packed")]
    pattern_layout: mocap_encoder::codec::pattern::Layout,
    /// With `--codec rma` (or `auto`): draw the repeated-motion analysis
    /// for tuning it (`.png` or `.svg`): the self-distance plot with its
    /// similar-posture paths, the analysis's primary / repeated / unique
    /// clips, and the repeated clips the encoder kept with their `Ref(t)`.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Also write the clip as a source file beside the output.
    #[arg(long, value_enum)]
    emit: Option<Emit>,
    /// Encode the servos of this rig in servo space (a servo clip with
    /// the rig table, SPEC.md §3.5); the bound is then in degrees of
    /// servo travel.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// With --rig: code the servo signals at the rig's tick rate
    /// (`rate_hz`, where the firmware samples them) or at the capture's
    /// frame rate.
    #[arg(long, value_enum, default_value = "rig", requires = "rig")]
    servo_rate: ServoRateArg,
    /// With --rig: keep the servo names in the clip (players never read
    /// them; `strip` leaves them out).
    #[arg(long, value_enum, default_value = "strip", requires = "rig")]
    servo_names: ServoNamesArg,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Emit {
    /// A Rust source file with a `pub static CLIP: [u8; N]`.
    Rust,
    /// A C header with `static const uint8_t clip[]`.
    C,
}

/// `--servo-rate`: [`servo_clip::ServoRate`] as a command-line value.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum ServoRateArg {
    /// One frame per servo tick of the rig (`rate_hz`), the only times the
    /// firmware and `mocap play` sample a servo clip.
    Rig,
    /// One frame per frame of the captured motion.
    Capture,
}

/// `--servo-names`: [`servo_clip::ServoNames`] as a command-line value.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum ServoNamesArg {
    /// No names: servos are channels `0..S` (players never read names).
    Strip,
    /// Servo names as the header's joint names.
    Keep,
}

fn parse_bounds(s: &str) -> Result<Vec<BoundSpec>, encode::BoundError> {
    s.split('+').map(str::parse).collect()
}

fn parse_budget(s: &str) -> Result<Budget, target::BudgetError> {
    s.parse()
}

/// `--target`: `None` for `mcu` (no chip), else the chip.
fn chip_of(a: &Args) -> super::Result<Option<&'static Chip>> {
    if a.target == "mcu" {
        if a.budget.is_some() {
            return Err(format!(
                "--budget needs a chip as --target, not mcu (one of: {})",
                target::chip_names()
            )
            .into());
        }
        return Ok(None);
    }
    super::target::resolve(std::slice::from_ref(&a.target)).map(|c| c.first().copied())
}

/// A clip made with a chip --target: its predicted cost, checked against the
/// budget and the chip (servo and marker clips: their one codec).
fn check_cost(bytes: &[u8], chip: &'static Chip, budget: &Budget) -> super::Result {
    let cost = target::best_capacity(target::predict_capacities(bytes, chip)?, budget)?;
    print!("{}", super::target::cost_table(std::slice::from_ref(&cost)));
    println!(
        "play it with a Player<{}> (the state is {} B)",
        cost.state_words, cost.state_bytes
    );
    let over = budget.overruns(&cost);
    if !over.is_empty() {
        return Err(format!(
            "the clip does not fit the {} ({}); try another --codec or a looser --max-error",
            chip.name,
            over.join(", ")
        )
        .into());
    }
    Ok(())
}

pub fn run(a: Args) -> super::Result {
    let chip = chip_of(&a)?;
    let budget = a.budget.unwrap_or_default();
    let specs = a.max_error.concat();
    if a.plot.is_some() && (a.rig.is_some() || super::markers::is_marker_file(&a.input)) {
        return Err(
            "--plot draws the repeated-motion analysis of a motion clip (--codec rma), \
                    not of a servo or marker clip"
                .into(),
        );
    }
    if super::markers::is_marker_file(&a.input) {
        if a.rig.is_some() {
            return Err("--rig needs a skeleton: a C3D marker file has none".into());
        }
        return match chip {
            Some(c) if a.codec.is_none() => encode_markers_for(&a, &specs, c, &budget),
            Some(c) => {
                encode_markers(&a, &specs)?;
                check_cost(&std::fs::read(&a.output)?, c, &budget)
            }
            None => encode_markers(&a, &specs),
        };
    }
    let input = a.motion.read(&a.input)?;
    let unit = a.units.resolve(&input);
    let m = input.motion;
    let bound = if specs.is_empty() {
        Bound::from_specs(&[BoundSpec::Degrees(1.0)])
    } else {
        Bound::from_specs(&specs)
    };
    if let Some(rig_path) = &a.rig {
        if bound.foot_slide_mm_s.is_some() {
            return Err(
                "a servo clip's bound is in degrees of servo travel (e.g. 0.5deg); \
                        slide: bounds the feet of a motion clip"
                    .into(),
            );
        }
        let opts = servo_clip::ServoEncodeOptions {
            codec: a.codec.map_or(CodecChoice::Predictive, Into::into),
            bound,
            key_interval: a.key_interval,
            rate: match a.servo_rate {
                ServoRateArg::Rig => servo_clip::ServoRate::Rig,
                ServoRateArg::Capture => servo_clip::ServoRate::Capture,
            },
            names: match a.servo_names {
                ServoNamesArg::Strip => servo_clip::ServoNames::Strip,
                ServoNamesArg::Keep => servo_clip::ServoNames::Keep,
            },
        };
        encode_servo_clip(&m, rig_path, unit.metres(), opts, &a.output)?;
        return match chip {
            Some(c) => check_cost(&std::fs::read(&a.output)?, c, &budget),
            None => Ok(()),
        };
    }
    // A budget without --codec: every codec, the smallest that fits.
    let default = if a.budget.is_some() {
        CodecChoice::Auto
    } else {
        CodecChoice::Index
    };
    let codec = a.codec.map_or(default, Into::into);
    if a.plot.is_some() && !matches!(codec, CodecChoice::Rma | CodecChoice::Auto) {
        return Err(format!(
            "--plot draws the repeated-motion analysis of --codec rma (or auto), not {}; \
             mocap eval --plot draws any clip's per-frame error",
            codec.name()
        )
        .into());
    }
    eprintln!(
        "{}: {} frames × {} channels at {:.1} Hz, units {unit}; encoding ({codec:?}, bound {bound})…",
        a.input.display(),
        m.frames(),
        m.channels(),
        1.0 / m.frame_time
    );
    let opts = EncodeOptions {
        key_bits: None,
        codec,
        bound,
        metres_per_unit: unit.metres(),
        key_interval: a.key_interval,
        index_layout: a.index_layout.unwrap_or_default(),
        pattern: mocap_encoder::codec::pattern::PatternOptions {
            nodes: a.pattern_nodes.clone().map(|n| n.0).unwrap_or_default(),
            layout: a.pattern_layout,
            ..Default::default()
        },
    };
    let enc = match chip {
        None => {
            let bar = crate::progress::Bar::new(1);
            let enc = encode::encode_with(&m, &opts, &bar);
            bar.finish();
            enc?
        }
        Some(chip) => encode_for(&m, &opts, a.index_layout, chip, &budget)?,
    };
    write(&a.output, &enc.bytes)?;
    let file_bytes = std::fs::metadata(&a.input).map(|m| m.len()).unwrap_or(0);
    let x = &enc.metrics;
    println!(
        "{}: {} bytes, ratio {:.2}:1 vs f32 ({:.1}:1 vs file), angle max {:.3}°, rms {:.3}°, joint max {:.2} mm, ARMS {:.2} mm, d {:.2}%{} (bound {bound} holds; {})",
        a.output.display(),
        enc.bytes.len(),
        x.ratio_f32,
        file_bytes as f64 / enc.bytes.len() as f64,
        x.angle_max_deg,
        x.angle_rms_deg,
        x.max_joint_err_mm,
        x.arms_mm,
        x.distortion_pct,
        if x.foot_pairs > 0 {
            format!(
                ", foot slide {:.0} mm/s (source {:.0})",
                x.foot_slide_mm_s, x.foot_slide_source_mm_s
            )
        } else {
            String::new()
        },
        match enc.codec {
            CodecChoice::Index => format!("index, key interval {}", enc.key_interval),
            CodecChoice::Predictive => format!("predictive, blocks of {} frames", enc.key_interval),
            c => c.name().to_string(),
        }
    );
    if let Some(kind) = a.emit {
        let p = emit_source(kind, &a.output, &enc.bytes)?;
        eprintln!("wrote {}", p.display());
    }
    if let Some(p) = &a.plot {
        plot_rma(p, &m, &enc, &a.input)?;
    }
    Ok(())
}

/// `--plot`: the analysis of `m` and the repeated clips `enc` kept.
fn plot_rma(path: &Path, m: &Motion, enc: &encode::Encoded, input: &Path) -> super::Result {
    use mocap_encoder::codec::rma;
    let analysis = rma::analyse(m, &rma::Params::default());
    let kept = rma::section::inspect_clip(&enc.bytes)
        .map(|info| info.clips)
        .unwrap_or_default();
    let name = input.file_name().unwrap_or_default().to_string_lossy();
    mocap_report::plot::rma::self_distance_plot(path, &analysis, Some(&kept), &name)?;
    let [p, r, u] = analysis.frames_by_kind();
    let kept_frames: u32 = kept.iter().map(|c| c.last - c.start + 1).sum();
    eprintln!(
        "wrote {}: the analysis's clips {p} primary, {r} repeated, {u} unique frames; {}",
        path.display(),
        if enc.codec == CodecChoice::Rma {
            format!(
                "the clip keeps {} repeated clip{} over {kept_frames} frames",
                kept.len(),
                if kept.len() == 1 { "" } else { "s" }
            )
        } else {
            format!("auto chose {}: no repeated clip kept", enc.codec.name())
        }
    );
    Ok(())
}

/// A motion clip for a chip: each candidate codec's clip, its predicted
/// cost, and the smallest that fits the budget and the chip.
/// `index` is tried in both layouts unless `--index-layout` names one.
fn encode_for(
    m: &Motion,
    opts: &EncodeOptions,
    layout: Option<IndexLayout>,
    chip: &'static Chip,
    budget: &Budget,
) -> super::Result<encode::Encoded> {
    let codecs: Vec<CodecChoice> = if opts.codec == CodecChoice::Auto {
        mocap_encoder::target::CANDIDATE_CODECS.to_vec()
    } else {
        vec![opts.codec]
    };
    let variants = variants(&codecs, layout);
    let bar = crate::progress::Bar::new(variants.len());
    let results: Vec<_> = variants
        .iter()
        .map(|&(codec, index_layout)| {
            let one = EncodeOptions {
                codec,
                index_layout,
                ..opts.clone()
            };
            let r = encode::encode_with(m, &one, &bar);
            (target::candidate_label(codec, index_layout), r)
        })
        .collect();
    bar.finish();
    choose_for(results, chip, budget)
}

/// The codecs to try for a chip, `index` in both layouts unless `layout`
/// fixes one.
fn variants(
    codecs: &[CodecChoice],
    layout: Option<IndexLayout>,
) -> Vec<(CodecChoice, IndexLayout)> {
    codecs
        .iter()
        .flat_map(|&codec| match (codec, layout) {
            (CodecChoice::Index, None) => IndexLayout::ALL.map(|l| (codec, l)).to_vec(),
            (_, l) => vec![(codec, l.unwrap_or_default())],
        })
        .collect()
}

/// Judges every candidate clip on `chip` under `budget`, prints them and
/// returns the smallest that fits.
fn choose_for<E: std::fmt::Display>(
    results: Vec<(&'static str, Result<encode::Encoded, E>)>,
    chip: &'static Chip,
    budget: &Budget,
) -> super::Result<encode::Encoded> {
    let (candidates, best) = target::choose(results, chip, budget);
    println!(
        "{} ({}, {} MHz, {} KB flash, {} KB RAM), budget {budget}:",
        chip.name,
        chip.core,
        chip.clock_hz / 1_000_000,
        chip.flash_bytes / 1024,
        chip.ram_bytes / 1024
    );
    for (i, c) in candidates.iter().enumerate() {
        let size = c.encoded.as_ref().map_or_else(
            |e| format!("no clip: {e}"),
            |e| format!("{} bytes", e.bytes.len()),
        );
        let cost = c.cost.as_ref().map_or_else(
            |e| e.clone(),
            |k| {
                format!(
                    "predicted {:.0} instructions/pose = {:.3}% cpu at {:.0} Hz, ram {} B (Player<{}> {} + pose {} + stack {}), flash {} B",
                    k.instructions_per_pose,
                    k.cpu_share * 100.0,
                    k.poses_per_second,
                    k.ram_bytes(),
                    k.state_words,
                    k.state_bytes,
                    k.pose_bytes,
                    k.playback_stack_bytes,
                    k.flash_bytes
                )
            },
        );
        let verdict = if Some(i) == best {
            "chosen".to_string()
        } else if c.fits() {
            "fits".to_string()
        } else if c.overruns.is_empty() {
            "-".to_string()
        } else {
            format!("over: {}", c.overruns.join(", "))
        };
        println!("  {:<10} {size}; {cost} [{verdict}]", c.label);
    }
    let Some(best) = best else {
        return Err(format!(
            "no codec's clip fits the {} under budget {budget}: loosen --max-error or the budget, or pick a faster chip",
            chip.name
        )
        .into());
    };
    let chosen = candidates.into_iter().nth(best);
    if let Some(Ok(cost)) = chosen.as_ref().map(|c| &c.cost) {
        println!(
            "  play it with a Player<{}> (mocap_decoder::Player::<{}>::new; the state is {} B)",
            cost.state_words, cost.state_words, cost.state_bytes
        );
    }
    chosen
        .and_then(|c| c.encoded.ok())
        .ok_or_else(|| "the chosen clip vanished".into())
}

/// `mocap encode markers.c3d`: a marker clip (no rig: a marker file has no
/// skeleton to drive one).
fn encode_markers(a: &Args, specs: &[BoundSpec]) -> super::Result {
    // The smallest clips, and the one codec whose 12-bit-free residuals meet
    // the default 1 mm over metres of walking (`index` stops near 2 mm there).
    let codec = a.codec.map_or(CodecChoice::Predictive, Into::into);
    let bytes = super::markers::encode(&a.input, &a.units, specs, codec, a.key_interval)?;
    write_marker_clip(a, &bytes)
}

/// `mocap encode markers.c3d --target CHIP` without `--codec`: every codec
/// the cost model knows makes a marker clip (`index` in both layouts), and
/// the smallest that fits the chip and the budget is written.
fn encode_markers_for(
    a: &Args,
    specs: &[BoundSpec],
    chip: &'static Chip,
    budget: &Budget,
) -> super::Result {
    let variants = variants(&target::CANDIDATE_CODECS, a.index_layout);
    let results =
        super::markers::encode_each(&a.input, &a.units, specs, &variants, a.key_interval)?
            .into_iter()
            .map(|((codec, layout), r)| {
                (target::candidate_label(codec, layout), r.map(|e| e.encoded))
            })
            .collect();
    let best = choose_for(results, chip, budget)?;
    write_marker_clip(a, &best.bytes)
}

/// Writes a marker clip (and its source file with `--emit`).
fn write_marker_clip(a: &Args, bytes: &[u8]) -> super::Result {
    write(&a.output, bytes)?;
    println!("wrote {}", a.output.display());
    if let Some(kind) = a.emit {
        let p = emit_source(kind, &a.output, bytes)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

/// `mocap encode --rig`: the rig's servo signals as a servo clip.
fn encode_servo_clip(
    m: &Motion,
    rig_path: &Path,
    metres_per_unit: f64,
    opts: servo_clip::ServoEncodeOptions,
    output: &Path,
) -> super::Result {
    if opts.bound.positional() {
        return Err(
            "a servo clip's bound is in degrees of servo travel (e.g. --max-error 0.5deg)".into(),
        );
    }
    let rig = Rig::read_file(rig_path)?;
    let channels = rig.resolve(&m.skeleton)?;
    let tracks = rig.servo_tracks(m, &channels, metres_per_unit);
    eprint!("{tracks}");
    let sc = servo_clip::encode_servo_clip(&rig, &tracks, &opts)?;
    write(output, &sc.bytes)?;
    print!("{}", servo_clip::report(output, &rig, &tracks, &sc));
    Ok(())
}

/// Writes the clip as a Rust or C source file beside `output`.
fn emit_source(kind: Emit, output: &Path, bytes: &[u8]) -> super::Result<PathBuf> {
    let body: Vec<String> = bytes
        .chunks(16)
        .map(|c| {
            c.iter()
                .map(|b| format!("0x{b:02x},"))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect();
    let (ext, text) = match kind {
        Emit::Rust => (
            "rs",
            format!(
                "// Generated by `mocap encode`; a .mcb clip (SPEC.md).\npub static CLIP: [u8; {}] = [\n    {}\n];\n",
                bytes.len(),
                body.join("\n    ")
            ),
        ),
        Emit::C => (
            "h",
            format!(
                "/* Generated by `mocap encode`; a .mcb clip (SPEC.md). */\n#include <stdint.h>\nstatic const uint8_t clip[{}] = {{\n    {}\n}};\n",
                bytes.len(),
                body.join("\n    ")
            ),
        ),
    };
    let path = output.with_extension(ext);
    write(&path, text.as_bytes())?;
    Ok(path)
}

/// `--pattern-layout`.
fn parse_pattern_layout(s: &str) -> Result<mocap_encoder::codec::pattern::Layout, String> {
    s.parse()
}

/// `--pattern-nodes`' value: the nodes' joint names.
#[derive(Clone, Debug)]
struct PatternNodes(Vec<Vec<String>>);

/// `--pattern-nodes`: nodes split by `;`, joint names by `,`.
fn parse_nodes(s: &str) -> Result<PatternNodes, String> {
    let nodes: Vec<Vec<String>> = s
        .split(';')
        .map(|n| {
            n.split(',')
                .map(str::trim)
                .filter(|j| !j.is_empty())
                .map(String::from)
                .collect()
        })
        .collect();
    if nodes.is_empty() || nodes.iter().any(Vec::is_empty) {
        return Err(format!(
            "'{s}': give nodes as joint names, `,` between joints and `;` between nodes (no empty node)"
        ));
    }
    Ok(PatternNodes(nodes))
}
