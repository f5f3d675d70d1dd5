//! `mocap`: the command line of the encoder. One module per subcommand
//! (`cmd/`); the library (`mocap-encoder`) does the work and returns typed
//! errors, which [`main`] prints.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cmd;
mod progress;

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

#[derive(Subcommand)]
enum Command {
    /// Encode a BVH file into a .mcb clip, proving the error bound.
    Encode(cmd::encode::Args),
    /// Decode a .mcb clip into BVH (or the firmware's text format).
    Decode(cmd::decode::Args),
    /// Show a clip's sections, channels and codec parameters.
    Info(cmd::info::Args),
    /// Decode a clip with the no_std decoder and measure it against its source.
    Eval(cmd::eval::Args),
    /// Rate–distortion table over motion files or folders: our codecs beside what users pick instead.
    ///
    /// Sizes: "bytes" and "ratio f32" include the skeleton header (a clip: the whole .mcb
    /// file; a baseline: its bytes + the header our clip of the same input carries); "w/o
    /// header" and bits/ch/frame leave it out on both sides. Every error is measured on the
    /// motion decoded from the bytes, by the encoder's own metrics; each baseline but raw16 is
    /// tuned by the encoder's own tolerance search until the same bound holds ("holds" says
    /// whether it does). The baselines are size references, not MCU bitstreams.
    Bench(cmd::bench::Args),
    /// Play a clip through a servo rig: servo-controller commands to a port or a file.
    Play(cmd::play::Args),
    /// Stream a clip to the firmware's streaming mode (postcard + COBS + CRC frames).
    ///
    /// Writes a `00` and `Hello`, then either the clip in 64-byte `ClipChunk`s and `Play`
    /// (the firmware plays it from its RAM), repeated `--passes` times, or with `--poses` one
    /// `Pose` per servo tick of a servo clip, decoded here at the rig's rate (`seq` = tick
    /// number; the firmware holds the last pose over lost ones), then `Stop`. See SPEC.md §8.
    Send(cmd::send::Args),
    /// Shows: many clips in one file, with cue lists and triggers (`mocap show build show.toml -o show.mcb`).
    Show(cmd::show::Args),
    /// Motion Track picture (Hu et al. 2010): clips as curves in a 2-D map of key poses.
    Track(cmd::track::Args),
    /// A self-contained HTML page that plays a BVH in 3-D, with its decoded .mcb clip overlaid.
    View(cmd::view::Args),
    /// Write the procedural demo clip the project ships.
    Generate(cmd::generate::Args),
    /// The chips `encode --target` knows, a clip's predicted cost on them, the cost model's fit.
    Target(cmd::target::Args),
}

fn run(cli: Cli) -> cmd::Result {
    match cli.command {
        Command::Encode(a) => cmd::encode::run(a),
        Command::Target(a) => cmd::target::run(a),
        Command::Decode(a) => cmd::decode::run(a),
        Command::Info(a) => cmd::info::run(a),
        Command::Eval(a) => cmd::eval::run(a),
        Command::Bench(a) => cmd::bench::run(a),
        Command::Play(a) => cmd::play::run(a),
        Command::Send(a) => cmd::send::run(a),
        Command::Show(a) => cmd::show::run(a),
        Command::Track(a) => cmd::track::run(a),
        Command::View(a) => cmd::view::run(a),
        Command::Generate(a) => cmd::generate::run(a),
    }
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<cmd::Stopped>() => {
            eprintln!("mocap: stopped: {e}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("mocap: error: {e}");
            ExitCode::FAILURE
        }
    }
}
