//! `mocap encode`: a BVH file into a `.mcb` clip (or, with `--rig`, a servo
//! clip; a `.c3d` marker file into a marker clip, [`super::markers`]), the
//! bound proven by decoding; `--emit` also writes it as source.

use std::path::{Path, PathBuf};

use mocap_encoder::codec::CodecChoice;
use mocap_encoder::encode::{self, Bound, BoundSpec, EncodeOptions};
use mocap_encoder::motion::Motion;
use mocap_encoder::rig::Rig;
use mocap_encoder::servo_clip;

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
    /// Target of the bitstream.
    #[arg(long, value_enum, default_value = "mcu")]
    target: Target,
    /// Codec (default: `index` for motion clips — the cheapest to decode —
    /// and `predictive` for servo and marker clips — the smallest).
    #[arg(long, value_enum)]
    codec: Option<CodecArg>,
    /// Error bound, repeatable: `1deg` (rotation channels), `8mm` (max
    /// joint position error by forward kinematics), `arms:10mm` (mean
    /// RMS joint error); `+` joins several in one value. Default: `1deg`;
    /// a C3D marker file takes lengths only (the marker position error),
    /// default `1mm`.
    #[arg(long = "max-error", value_parser = parse_bounds)]
    max_error: Vec<Vec<BoundSpec>>,
    /// Length unit of the input (auto: the ASF's declared unit or a C3D
    /// file's POINT:UNITS, else from the skeleton's height).
    #[arg(long, default_value = "auto")]
    units: UnitArg,
    /// Force the key-frame interval of the index codec (0 = none), or the
    /// block length in frames of the predictive codec (default: 10 s).
    #[arg(long)]
    key_interval: Option<u16>,
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
enum Target {
    /// A microcontroller: integer decoder, tables in flash.
    Mcu,
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

pub fn run(a: Args) -> super::Result {
    let Target::Mcu = a.target;
    let specs = a.max_error.concat();
    if super::markers::is_marker_file(&a.input) {
        return encode_markers(&a, &specs);
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
        return encode_servo_clip(&m, rig_path, unit.metres(), opts, &a.output);
    }
    let codec = a.codec.map_or(CodecChoice::Index, Into::into);
    eprintln!(
        "{}: {} frames × {} channels at {:.1} Hz, units {unit}; encoding ({codec:?}, bound {bound})…",
        a.input.display(),
        m.frames(),
        m.channels(),
        1.0 / m.frame_time
    );
    let opts = EncodeOptions {
        codec,
        bound,
        metres_per_unit: unit.metres(),
        key_interval: a.key_interval,
    };
    let bar = crate::progress::Bar::new(1);
    let enc = encode::encode_with(&m, &opts, &bar);
    bar.finish();
    let enc = enc?;
    write(&a.output, &enc.bytes)?;
    let file_bytes = std::fs::metadata(&a.input).map(|m| m.len()).unwrap_or(0);
    let x = &enc.metrics;
    println!(
        "{}: {} bytes, ratio {:.2}:1 vs f32 ({:.1}:1 vs file), angle max {:.3}°, rms {:.3}°, joint max {:.2} mm, ARMS {:.2} mm, d {:.2}% (bound {bound} holds; {})",
        a.output.display(),
        enc.bytes.len(),
        x.ratio_f32,
        file_bytes as f64 / enc.bytes.len() as f64,
        x.angle_max_deg,
        x.angle_rms_deg,
        x.max_joint_err_mm,
        x.arms_mm,
        x.distortion_pct,
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
    Ok(())
}

/// `mocap encode markers.c3d`: a marker clip (no rig: a marker file has no
/// skeleton to drive one).
fn encode_markers(a: &Args, specs: &[BoundSpec]) -> super::Result {
    if a.rig.is_some() {
        return Err("--rig needs a skeleton: a C3D marker file has none".into());
    }
    // The smallest clips, and the one codec whose 12-bit-free residuals meet
    // the default 1 mm over metres of walking (`index` stops near 2 mm there).
    let codec = a.codec.map_or(CodecChoice::Predictive, Into::into);
    let bytes = super::markers::encode(&a.input, &a.units, specs, codec, a.key_interval)?;
    write(&a.output, &bytes)?;
    println!("wrote {}", a.output.display());
    if let Some(kind) = a.emit {
        let p = emit_source(kind, &a.output, &bytes)?;
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
