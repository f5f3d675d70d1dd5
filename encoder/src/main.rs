//! `mocap`: the command-line front end of the encoder.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use mocap_decoder::Clip;
use mocap_encoder::codec::{index, pca_spline};
use mocap_encoder::encode::{self, Bound, BoundSpec, CodecChoice, EncodeOptions};
use mocap_encoder::units::LengthUnit;
use mocap_encoder::{bench, bvh, clipfile, fixed, generate, metrics, servo_clip, units};

#[derive(Parser)]
#[command(
    name = "mocap",
    version,
    about = "Motion-capture codec for microcontrollers"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Target {
    /// A microcontroller: integer decoder, tables in flash.
    Mcu,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Emit {
    /// A Rust source file with a `pub static CLIP: [u8; N]`.
    Rust,
    /// A C header with `static const uint8_t clip[]`.
    C,
}

#[derive(Subcommand)]
enum Command {
    /// Encode a BVH file into a .mcb clip, proving the error bound.
    Encode {
        /// Input BVH file.
        input: PathBuf,
        /// Output .mcb file.
        #[arg(short, long)]
        output: PathBuf,
        /// Target of the bitstream.
        #[arg(long, value_enum, default_value = "mcu")]
        target: Target,
        /// Codec (default: `index` for motion clips — the cheapest to decode —
        /// and `predictive` for servo clips — the smallest).
        #[arg(long, value_enum)]
        codec: Option<CodecChoice>,
        /// Error bound, repeatable: `1deg` (rotation channels), `8mm` (max
        /// joint position error by forward kinematics), `arms:10mm` (mean
        /// RMS joint error); `+` joins several in one value.
        #[arg(long = "max-error", default_value = "1deg", value_parser = parse_bounds)]
        max_error: Vec<Vec<BoundSpec>>,
        /// Length unit of the input (auto: from the skeleton's height).
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
        servo_rate: mocap_encoder::servo_clip::ServoRate,
        /// With --rig: keep the servo names in the clip (players never read
        /// them; `strip` leaves them out).
        #[arg(long, value_enum, default_value = "strip", requires = "rig")]
        servo_names: mocap_encoder::servo_clip::ServoNames,
    },
    /// Decode a .mcb clip into BVH (or the firmware's text format).
    Decode {
        /// Input .mcb clip.
        input: PathBuf,
        /// Output file (BVH unless --text).
        #[arg(short, long)]
        output: PathBuf,
        /// Write the firmware's UART text format instead of BVH.
        #[arg(long)]
        text: bool,
    },
    /// Show a clip's sections, channels and codec parameters.
    Info {
        /// Input .mcb clip.
        input: PathBuf,
        /// List every channel.
        #[arg(long)]
        channels: bool,
    },
    /// Decode a clip with the no_std decoder and measure it against its source.
    Eval {
        /// The source BVH.
        input: PathBuf,
        /// The clip.
        clip: PathBuf,
        /// One JSON object on stdout.
        #[arg(long)]
        json: bool,
        /// Length unit of the input.
        #[arg(long, default_value = "auto")]
        units: UnitArg,
        /// Also draw the per-frame joint-position error (`.svg` or `.png`).
        #[arg(long)]
        plot: Option<PathBuf>,
    },
    /// Rate–distortion table over files or folders of BVH.
    Bench {
        /// BVH files or folders.
        paths: Vec<PathBuf>,
        /// Error bounds, repeatable; `+` joins several into one
        /// (`50mm+arms:10mm`).
        #[arg(long = "max-error", default_values = ["1deg", "0.25deg"])]
        max_error: Vec<String>,
        /// Codecs, repeatable (`auto` keeps the smallest per file).
        #[arg(long, value_enum, default_values = ["index"])]
        codec: Vec<CodecChoice>,
        /// Write the rows as JSON here too.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Also draw the rate–distortion plot (`.svg` or `.png`).
        #[arg(long)]
        plot: Option<PathBuf>,
    },
    /// Play a clip through a servo rig: servo-controller commands to a port or a file.
    Play {
        /// Input .mcb clip.
        clip: PathBuf,
        /// Rig file (TOML, see assets/rigs/README.md); not needed for a
        /// servo clip (`encode --rig`), which carries its rig table.
        #[arg(long)]
        rig: Option<PathBuf>,
        /// Servo controller protocol.
        #[arg(long, value_enum)]
        protocol: mocap_encoder::play::Protocol,
        #[command(flatten)]
        dest: Destination,
        /// Servo ticks per second (default: the rig's rate_hz).
        #[arg(long)]
        rate: Option<f64>,
    },
    /// Stream a clip to the firmware's streaming mode (postcard + COBS + CRC frames).
    ///
    /// Writes a `00` and `Hello`, then either the clip in 64-byte `ClipChunk`s and `Play`
    /// (the firmware plays it from its RAM), repeated `--passes` times, or with `--poses` one
    /// `Pose` per servo tick of a servo clip, decoded here at the rig's rate (`seq` = tick
    /// number; the firmware holds the last pose over lost ones), then `Stop`. See SPEC.md §8.
    Send {
        /// Input .mcb clip.
        clip: PathBuf,
        #[command(flatten)]
        dest: Destination,
        /// Line rate used for pacing the clip upload, bit/s (8N1).
        #[arg(long, default_value_t = 115_200)]
        baud: u32,
        /// Ask the firmware to loop the clip.
        #[arg(long = "loop", conflicts_with = "poses")]
        looped: bool,
        /// Send the whole upload (every chunk in order, then `Play`) this many times: a
        /// carousel for a lossy line without a way back. The firmware keeps each chunk from
        /// whichever pass brings it intact and starts the clip once it has every chunk and a
        /// `Play`; a `Play` that comes first is remembered. At 1 % corrupted bytes the demo's
        /// 19-chunk servo clip arrives whole with 1 pass never, 8 passes 87 %, 16 passes
        /// 100 % (BENCHMARKS.md §5). Each pass costs the clip's bytes again.
        #[arg(long, default_value_t = 1, conflicts_with = "poses",
              value_parser = clap::value_parser!(u32).range(1..))]
        passes: u32,
        /// Send live poses (a servo clip's pulses at its rig's rate, paced in real time
        /// unless --fast) instead of uploading the clip.
        #[arg(long)]
        poses: bool,
    },
    /// Motion Track picture (Hu et al. 2010): clips as curves in a 2-D map of key poses.
    Track(mocap_encoder::track::TrackArgs),
    /// Write the procedural demo clip the project ships.
    Generate {
        /// Output BVH file.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// Where `play` and `send` write, and whether they keep real time.
#[derive(clap::Args, Debug)]
struct Destination {
    /// Serial device to write to (e.g. /dev/ttyACM0; set its line speed
    /// beforehand, e.g. `stty -F /dev/ttyUSB0 115200 raw`).
    #[arg(long, conflicts_with = "output", required_unless_present = "output")]
    port: Option<PathBuf>,
    /// Write the bytes to this file instead of a port.
    #[arg(long)]
    output: Option<PathBuf>,
    /// Do not pace the writes in real time.
    #[arg(long)]
    fast: bool,
}

impl Destination {
    /// Writes `chunks` in order, chunk `i` not before `due(i)` after the
    /// start unless `--fast`; returns the path written.
    fn write(
        &self,
        chunks: &[Vec<u8>],
        due: impl Fn(usize) -> std::time::Duration,
    ) -> Result<PathBuf, String> {
        let dest = self
            .port
            .clone()
            .or_else(|| self.output.clone())
            .ok_or("give --port or --output")?;
        let fail = |e: std::io::Error| format!("{}: {e}", dest.display());
        let mut file = std::fs::File::create(&dest).map_err(fail)?;
        let start = std::time::Instant::now();
        for (i, chunk) in chunks.iter().enumerate() {
            if !self.fast {
                let at = start + due(i);
                std::thread::sleep(at.saturating_duration_since(std::time::Instant::now()));
            }
            std::io::Write::write_all(&mut file, chunk).map_err(fail)?;
        }
        Ok(dest)
    }
}

fn parse_bounds(s: &str) -> Result<Vec<BoundSpec>, String> {
    s.split('+').map(str::parse).collect()
}

#[derive(Clone, Debug)]
enum UnitArg {
    Auto,
    Fixed(LengthUnit),
}

impl std::str::FromStr for UnitArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            Ok(UnitArg::Auto)
        } else {
            s.parse::<LengthUnit>()
                .map(UnitArg::Fixed)
                .map_err(|e| e.to_string())
        }
    }
}

fn resolve_units(arg: &UnitArg, m: &mocap_encoder::motion::Motion) -> LengthUnit {
    match arg {
        UnitArg::Auto => units::detect(m),
        UnitArg::Fixed(u) => *u,
    }
}

fn read_clip(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn parse_clip<'a>(path: &Path, bytes: &'a [u8]) -> Result<Clip<'a>, String> {
    Clip::parse(bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn emit_source(kind: Emit, output: &Path, bytes: &[u8]) -> Result<PathBuf, String> {
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

/// `mocap encode --rig`: the rig's servo signals as a servo clip.
fn encode_servo_clip(
    m: &mocap_encoder::motion::Motion,
    rig_path: &Path,
    metres_per_unit: f64,
    opts: servo_clip::ServoEncodeOptions,
    output: &Path,
) -> Result<(), String> {
    use mocap_encoder::rig::Rig;
    if opts.bound.positional() {
        return Err(
            "a servo clip's bound is in degrees of servo travel (e.g. --max-error 0.5deg)".into(),
        );
    }
    let rig = Rig::read_file(rig_path).map_err(|e| e.to_string())?;
    let channels = rig.resolve(&m.skeleton).map_err(|e| e.to_string())?;
    let tracks = rig.servo_tracks(m, &channels, metres_per_unit);
    eprint!("{tracks}");
    let sc = servo_clip::encode_servo_clip(&rig, &tracks, &opts)?;
    write(output, &sc.bytes)?;
    print!("{}", servo_clip::report(output, &rig, &tracks, &sc));
    Ok(())
}

fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Encode {
            input,
            output,
            target: Target::Mcu,
            codec,
            max_error,
            units: unit_arg,
            key_interval,
            emit,
            rig,
            servo_rate,
            servo_names,
        } => {
            let m = bvh::read_file(&input).map_err(|e| e.to_string())?;
            let unit = resolve_units(&unit_arg, &m);
            let bound = Bound::from_specs(&max_error.concat());
            if let Some(rig_path) = rig {
                return encode_servo_clip(
                    &m,
                    &rig_path,
                    unit.metres(),
                    servo_clip::ServoEncodeOptions {
                        codec: codec.unwrap_or(CodecChoice::Predictive),
                        bound,
                        key_interval,
                        rate: servo_rate,
                        names: servo_names,
                    },
                    &output,
                );
            }
            let codec = codec.unwrap_or(CodecChoice::Index);
            eprintln!(
                "{}: {} frames × {} channels at {:.1} Hz, units {unit}; encoding ({codec:?}, bound {bound})…",
                input.display(),
                m.frames(),
                m.channels(),
                1.0 / m.frame_time
            );
            let opts = EncodeOptions {
                codec,
                bound,
                metres_per_unit: unit.metres(),
                key_interval,
            };
            let enc = encode::encode(&m, &opts)?;
            write(&output, &enc.bytes)?;
            let file_bytes = std::fs::metadata(&input).map(|m| m.len()).unwrap_or(0);
            let x = &enc.metrics;
            println!(
                "{}: {} bytes, ratio {:.2}:1 vs f32 ({:.1}:1 vs file), angle max {:.3}°, rms {:.3}°, joint max {:.2} mm, ARMS {:.2} mm, d {:.2}% (bound {bound} holds; {})",
                output.display(),
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
                    c => bench::codec_name(c).to_string(),
                }
            );
            if let Some(kind) = emit {
                let p = emit_source(kind, &output, &enc.bytes)?;
                eprintln!("wrote {}", p.display());
            }
            Ok(())
        }
        Command::Decode {
            input,
            output,
            text,
        } => {
            let bytes = read_clip(&input)?;
            let clip = parse_clip(&input, &bytes)?;
            if text {
                let frames = clipfile::decode_all(&clip).map_err(|e| e.to_string())?;
                let s = clipfile::uart_text(&frames, clip.header().channel_count());
                write(&output, s.as_bytes())?;
            } else {
                let m = clipfile::to_motion(&clip).map_err(|e| e.to_string())?;
                bvh::write_file(&m, &output).map_err(|e| format!("{}: {e}", output.display()))?;
            }
            eprintln!("wrote {}", output.display());
            Ok(())
        }
        Command::Info { input, channels } => {
            let bytes = read_clip(&input)?;
            let clip = parse_clip(&input, &bytes)?;
            print!("{}", info_text(&clip, channels));
            Ok(())
        }
        Command::Eval {
            input,
            clip: clip_path,
            json,
            units: unit_arg,
            plot,
        } => {
            let m = bvh::read_file(&input).map_err(|e| e.to_string())?;
            let unit = resolve_units(&unit_arg, &m);
            let bytes = read_clip(&clip_path)?;
            let clip = parse_clip(&clip_path, &bytes)?;
            let h = clip.header();
            if h.channel_count() != m.channels() || h.frame_count() as usize != m.frames() {
                return Err(format!(
                    "{} has {} frames × {} channels but {} has {} × {}",
                    clip_path.display(),
                    h.frame_count(),
                    h.channel_count(),
                    input.display(),
                    m.frames(),
                    m.channels()
                ));
            }
            let frames = clipfile::decode_all(&clip).map_err(|e| e.to_string())?;
            let back = fixed::from_fixed(&m.skeleton, m.frame_time, &frames, unit.metres());
            let file_bytes = std::fs::metadata(&input)
                .map(|x| x.len() as usize)
                .unwrap_or(0);
            let x = metrics::compare(&m, &back, unit.metres(), None, bytes.len(), file_bytes);
            if let Some(p) = plot {
                mocap_encoder::plot::frame_error_plot(
                    &p,
                    &m,
                    &back,
                    unit.metres(),
                    &clip_path.display().to_string(),
                )?;
                eprintln!("wrote {}", p.display());
            }
            if json {
                println!("{}", serde_json::to_string(&x).map_err(|e| e.to_string())?);
            } else {
                println!("bytes            {}", x.bytes);
                println!("ratio vs f32     {:.2}:1", x.ratio_f32);
                println!("ratio vs file    {:.2}:1", x.ratio_file);
                println!("ARMS             {:.3} mm", x.arms_mm);
                println!(
                    "max joint error  {:.3} mm ({} at frame {})",
                    x.max_joint_err_mm, x.max_joint_err_joint, x.max_joint_err_frame
                );
                println!("distortion d     {:.3} %", x.distortion_pct);
                println!(
                    "angle RMS / max  {:.4}° / {:.4}°",
                    x.angle_rms_deg, x.angle_max_deg
                );
                println!("frames×channels  {}×{}", x.frames, x.channels);
            }
            Ok(())
        }
        Command::Bench {
            paths,
            max_error,
            codec,
            json,
            plot,
        } => {
            let rows = bench::run(&paths, &codec, &max_error)?;
            print!("{}", bench::markdown(&rows));
            if let Some(p) = json {
                write(
                    &p,
                    serde_json::to_string_pretty(&rows)
                        .map_err(|e| e.to_string())?
                        .as_bytes(),
                )?;
            }
            if let Some(p) = plot {
                mocap_encoder::plot::rate_distortion_plot(&p, &rows)?;
                eprintln!("wrote {}", p.display());
            }
            Ok(())
        }
        Command::Play {
            clip,
            rig,
            protocol,
            dest,
            rate,
        } => {
            let bytes = read_clip(&clip)?;
            let c = parse_clip(&clip, &bytes)?;
            let s = match rig {
                Some(rig) => {
                    let rig =
                        mocap_encoder::rig::Rig::read_file(&rig).map_err(|e| e.to_string())?;
                    mocap_encoder::play::servo_stream(&c, &rig, protocol, rate)?
                }
                None => mocap_encoder::play::servo_clip_stream(&c, protocol, rate)?,
            };
            if let Some(t) = &s.tracks {
                eprint!("{t}");
            }
            let rate = s.rate_hz;
            let period = std::time::Duration::from_secs_f64(1.0 / rate);
            let dest = dest.write(&s.ticks, |i| period * i as u32)?;
            eprintln!(
                "{}: {} ticks at {rate} Hz ({} of the clip, {} back to neutral), {} bytes",
                dest.display(),
                s.ticks.len(),
                s.clip_ticks,
                s.ticks.len() - s.clip_ticks,
                s.ticks.iter().map(Vec::len).sum::<usize>()
            );
            Ok(())
        }
        Command::Send {
            clip,
            dest,
            poses: true,
            ..
        } => {
            let bytes = read_clip(&clip)?;
            let c = parse_clip(&clip, &bytes)?;
            let p = mocap_encoder::play::pose_frames(&c)?;
            let dest = dest.write(&p.frames, |i| std::time::Duration::from_micros(p.due_us(i)))?;
            eprintln!(
                "{}: {} poses at {} Hz, {} frames, {} bytes",
                dest.display(),
                p.frames.len() - 2,
                f64::from(p.rate_mhz) / 1000.0,
                p.frames.len(),
                p.frames.iter().map(Vec::len).sum::<usize>()
            );
            Ok(())
        }
        Command::Send {
            clip,
            dest,
            baud,
            looped,
            passes,
            poses: false,
        } => {
            let bytes = read_clip(&clip)?;
            parse_clip(&clip, &bytes)?;
            let frames = mocap_encoder::play::clip_frames(&bytes, looped, passes)?;
            // Frame i goes out once the bytes before it have crossed the
            // line: 10 bits per byte on an 8N1 line.
            let before: Vec<usize> = frames
                .iter()
                .scan(0, |sent, f| {
                    let at = *sent;
                    *sent += f.len();
                    Some(at)
                })
                .collect();
            let bit = 1.0 / f64::from(baud.max(1));
            let dest = dest.write(&frames, |i| {
                std::time::Duration::from_secs_f64(before[i] as f64 * 10.0 * bit)
            })?;
            eprintln!(
                "{}: {passes} pass(es), {} frames, {} bytes",
                dest.display(),
                frames.len(),
                frames.iter().map(Vec::len).sum::<usize>()
            );
            Ok(())
        }
        Command::Track(args) => mocap_encoder::track::run(&args),
        Command::Generate { output } => {
            bvh::write_file(&generate::animatronic_demo(), &output)
                .map_err(|e| format!("{}: {e}", output.display()))?;
            eprintln!("wrote {}", output.display());
            Ok(())
        }
    }
}

fn info_text(clip: &Clip<'_>, list_channels: bool) -> String {
    let h = clip.header();
    let mut s = String::new();
    s += &format!(
        "clip: {} bytes, version {}, {} frames × {} channels, {:.3} Hz ({} ns/frame), {:.3} s, {} joints, source unit {} nm\n",
        clip.bytes().len(),
        mocap_decoder::consts::VERSION,
        h.frame_count(),
        h.channel_count(),
        1e9 / f64::from(h.frame_time_ns()),
        h.frame_time_ns(),
        h.duration_us() as f64 * 1e-6,
        h.joint_count(),
        h.source_unit_nm()
    );
    if let Some(rig) = clip.rig() {
        s += &format!(
            "servo clip: {} servos at {:.3} Hz (channel i = servo i, millidegrees of travel)\n",
            rig.servo_count(),
            f64::from(rig.rate_mhz()) / 1000.0
        );
    }
    for sec in clip.sections() {
        s += &format!("section {:#04x}: {} bytes\n", sec.id, sec.bytes.len());
        if sec.id == mocap_decoder::consts::SECTION_CODEC_INDEX {
            if let Some(info) = index::inspect(sec.bytes) {
                let chans = info.per_channel(h.channel_count());
                let n = chans.len().max(1);
                let key: u32 = chans.iter().map(|c| u32::from(c.key_bits)).sum();
                let delta: u32 = chans
                    .iter()
                    .map(|c| u32::from(c.delta_bits.unwrap_or(0)))
                    .sum();
                let unchanged = chans.iter().filter(|c| c.delta_bits.is_none()).count();
                let deltas = chans.iter().filter(|c| c.accumulate).count();
                s += &format!(
                    "  index codec: key interval {}, table {} entries, payload {} bytes, {} key groups, {} delta groups\n  bits per frame: key {key} ({:.2}/channel), delta {delta} ({:.2}/channel)\n  channels: {unchanged} unchanged between key frames, {deltas} delta-coded, {} absolute\n",
                    info.key_interval,
                    info.table_entries,
                    info.payload_bytes,
                    info.key.len(),
                    info.delta.len(),
                    key as f64 / n as f64,
                    delta as f64 / n as f64,
                    n - unchanged - deltas
                );
                if list_channels {
                    for (c, (ch, d)) in h.channels().zip(&chans).enumerate() {
                        s += &format!(
                            "  {c:4} {}.{:<10} key {:2} bits, delta {} bits{} range [{}, {}]\n",
                            ch.joint_name,
                            ch.kind.name(),
                            d.key_bits,
                            d.delta_bits.map_or("-".to_string(), |b| format!("{b:2}")),
                            if d.accumulate { " (acc)" } else { "" },
                            ch.min,
                            ch.max
                        );
                    }
                }
            }
        }
        if sec.id == mocap_decoder::consts::SECTION_CODEC_PREDICTIVE {
            if let Some(info) = mocap_encoder::codec::predictive::inspect(sec.bytes) {
                s += &format!(
                    "  predictive codec: {} coded + {} constant channels, blocks of {} frames, {} blocks, {} bytes of range-coded residuals, state {} words\n  predictor weights (of 4) 0/2/3/4: {:?} channels\n",
                    info.coded,
                    info.constant,
                    info.block_frames,
                    info.blocks,
                    info.payload_bytes,
                    info.state_words,
                    info.weights
                );
            }
        }
        if sec.id == mocap_decoder::consts::SECTION_CODEC_PCA_SPLINE {
            if let Some(info) = pca_spline::inspect(sec.bytes) {
                let keys: usize = info
                    .segments
                    .iter()
                    .flat_map(|(_, _, g)| g.iter().map(|&(_, m)| m))
                    .sum();
                s += &format!(
                    "  pca-spline codec: {} groups, {} constant channels, {} segments, {keys} keys\n  bytes: means {}, bases {}, keys {}, patches {}\n",
                    info.groups,
                    info.consts,
                    info.segments.len(),
                    info.mean_bytes,
                    info.basis_bytes,
                    info.key_bytes,
                    info.patch_bytes
                );
                for (start, end, groups) in &info.segments {
                    let g: Vec<String> = groups.iter().map(|(k, m)| format!("k{k}/{m}")).collect();
                    s += &format!("  segment {start}..={end}: {}\n", g.join(" "));
                }
            }
        }
    }
    s
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("mocap: error: {e}");
            ExitCode::FAILURE
        }
    }
}
