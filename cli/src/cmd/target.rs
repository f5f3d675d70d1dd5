//! `mocap target`: the chips `encode --target` knows (`list`), a clip's
//! predicted cost on them (`cost`), a servo clip's power levels (`levels`),
//! and the cost model's fit to QEMU measurements (`fit`, run by
//! `scripts/cost.sh`).

use std::path::{Path, PathBuf};

use mocap_encoder::target::{self, fit, Chip, Core, Cost, CHIPS};

use super::read_clip;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Subcommand)]
enum Command {
    /// The chips: core, clock, flash, RAM.
    List,
    /// A clip's predicted decode cost, state, stack and flash on each chip.
    Cost {
        /// The clip (.mcb).
        clip: PathBuf,
        /// Only these chips (repeatable; default every chip).
        #[arg(long)]
        target: Vec<String>,
        /// For a `Player<N>` of N words (default: what the clip can use;
        /// a smaller `pca-spline` player caches fewer groups).
        #[arg(long, conflicts_with = "capacities")]
        player: Option<usize>,
        /// One row per `Player<N>` worth building for the clip, smallest
        /// first (`pca-spline`: from no group cached to every group cached).
        #[arg(long)]
        capacities: bool,
    },
    /// A servo clip's power levels (SPEC.md §6.1; `mocap play --power`,
    /// the firmware's `--power`): poses sampled per second and the
    /// difference from level 0 (every tick sampled) at each level.
    Levels {
        /// The servo clip (.mcb, `mocap encode --rig`).
        clip: PathBuf,
        /// Servo ticks per second (default: the rig's rate_hz).
        #[arg(long)]
        rate: Option<f64>,
    },
    /// Fit the cost model to measurements (scripts/cost.sh writes them).
    Fit {
        /// measured.tsv: board, core, set (fit|check), clip, decode_per_pose,
        /// playback_stack_bytes; boards.tsv beside it: board, core,
        /// state_bytes, max_channels, decoder_code_bytes.
        measured: PathBuf,
        /// Also write the coefficients as Rust source to this file
        /// (encoder/src/target/calibration.rs).
        #[arg(long)]
        write: Option<PathBuf>,
    },
}

pub fn run(a: Args) -> super::Result {
    match a.command {
        Command::List => {
            print!("{}", list());
            Ok(())
        }
        Command::Cost {
            clip,
            target,
            player,
            capacities,
        } => {
            let bytes = read_clip(&clip)?;
            let chips = resolve(&target)?;
            let at = |n: Option<usize>| {
                target::Features::with_capacity(&bytes, n)
                    .map_err(|e| format!("{}: {e}", clip.display()))
            };
            let features = at(player)?;
            if player.is_some_and(|n| n < features.channels) {
                return Err(format!(
                    "--player {}: a player holds at least the clip's {} channels",
                    player.unwrap_or(0),
                    features.channels
                )
                .into());
            }
            let all = if capacities {
                features
                    .capacities
                    .iter()
                    .map(|&n| at(Some(n)))
                    .collect::<Result<Vec<_>, _>>()?
            } else {
                vec![features]
            };
            let rows: Vec<Cost> = chips
                .iter()
                .flat_map(|c| {
                    all.iter()
                        .map(move |f| target::cost::predict_features(f, c))
                })
                .collect::<Result<_, _>>()
                .map_err(|e| format!("{}: {e}", clip.display()))?;
            print!("{}", cost_table(&rows));
            Ok(())
        }
        Command::Levels { clip, rate } => {
            let bytes = read_clip(&clip)?;
            let c = super::parse_clip(&clip, &bytes)?;
            let rows = mocap_encoder::play::level_errors(&c, rate)
                .map_err(|e| format!("{}: {e}", clip.display()))?;
            println!(
                "{:>5} {:>10} {:>12} {:>12} {:>13}",
                "level", "samples/s", "max deg", "RMS deg", "max pulse µs"
            );
            for r in rows {
                println!(
                    "{:>5} {:>10.2} {:>12.3} {:>12.3} {:>13.2}",
                    r.level, r.samples_per_s, r.max_deg, r.rms_deg, r.max_pulse_us
                );
            }
            Ok(())
        }
        Command::Fit { measured, write } => fit_command(&measured, write.as_deref()),
    }
}

/// The chips named on the command line (all when none), or an error naming
/// the ones that exist.
pub fn resolve(names: &[String]) -> super::Result<Vec<&'static Chip>> {
    if names.is_empty() {
        return Ok(CHIPS.iter().collect());
    }
    names
        .iter()
        .map(|n| {
            target::chip(n).ok_or_else(|| {
                format!("unknown chip '{n}' (known: {})", target::chip_names()).into()
            })
        })
        .collect()
}

fn list() -> String {
    let mut s = format!(
        "{:<11} {:<5} {:>8} {:>9} {:>9}  part\n",
        "chip", "core", "MHz", "flash KB", "RAM KB"
    );
    for c in CHIPS {
        s += &format!(
            "{:<11} {:<5} {:>8} {:>9} {:>9}  {}\n",
            c.name,
            c.core.name(),
            c.clock_hz / 1_000_000,
            c.flash_bytes / 1024,
            c.ram_bytes / 1024,
            c.part
        );
    }
    s
}

/// One line per chip: the figures of [`Cost`].
pub fn cost_table(rows: &[Cost]) -> String {
    let mut s = format!(
        "{:<11} {:<5} {:>10} {:>9} {:>8} {:>6} {:>7} {:>6} {:>6} {:>8} {:>9}\n",
        "chip",
        "core",
        "instr/pose",
        "instr/s",
        "cpu",
        "N",
        "state",
        "pose",
        "stack",
        "ram",
        "flash"
    );
    for c in rows {
        s += &format!(
            "{:<11} {:<5} {:>10.0} {:>9.0} {:>7.3}% {:>6} {:>7} {:>6} {:>6} {:>8} {:>9}{}\n",
            c.chip.name,
            c.chip.core.name(),
            c.instructions_per_pose,
            c.instructions_per_pose * c.poses_per_second,
            c.cpu_share * 100.0,
            c.state_words,
            c.state_bytes,
            c.pose_bytes,
            c.playback_stack_bytes,
            c.ram_bytes(),
            c.flash_bytes,
            if c.model_core != c.chip.core {
                format!("  (the {} model)", c.model_core)
            } else {
                String::new()
            }
        );
    }
    s += "instructions per pose at the clip's frame rate, one instruction per cycle; N = words of the Player<N>; ram = state + pose + playback stack; flash = clip + decoder code\n";
    s
}

/// Per board: the player's state at its capacity and the decoder's code.
struct BoardFigures {
    board: String,
    core: Core,
    state_bytes: usize,
    max_channels: usize,
    decoder_code_bytes: usize,
}

fn read_boards(path: &Path) -> super::Result<Vec<BoardFigures>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split('\t').collect();
        let bad = || {
            format!(
                "{}:{}: expected board, core, state_bytes, max_channels, decoder_code_bytes",
                path.display(),
                i + 1
            )
        };
        let [board, core, state, max, code] = f[..] else {
            return Err(bad().into());
        };
        out.push(BoardFigures {
            board: board.to_string(),
            core: Core::from_name(core).ok_or_else(bad)?,
            state_bytes: state.parse().map_err(|_| bad())?,
            max_channels: max.parse().map_err(|_| bad())?,
            decoder_code_bytes: code.parse().map_err(|_| bad())?,
        });
    }
    Ok(out)
}

fn fit_command(measured: &Path, write: Option<&Path>) -> super::Result {
    let boards = read_boards(&measured.with_file_name("boards.tsv"))?;
    let rows = fit::read_measurements(measured, |board| {
        boards
            .iter()
            .find(|b| b.board == board)
            .map(|b| b.max_channels)
    })?;
    // The codecs measured are fitted (and printed); the others keep the
    // models shipped.
    let measured_models = fit::fit(&rows)?;
    let fitted = fit::with_shipped(measured_models.clone());
    println!(
        "Cost model: instructions per pose = coefficients · features, least squares of the relative error per core and codec on the calibration rows (`mocap target fit {}`).\n",
        measured.display()
    );
    for f in &measured_models {
        let names = f.codec.feature_names();
        let mut terms = String::new();
        for (i, (n, c)) in names.iter().zip(&f.coefficients).enumerate() {
            let sign = match (i, *c < 0.0) {
                (0, false) => "",
                (0, true) => "−",
                (_, false) => " + ",
                (_, true) => " − ",
            };
            terms += &format!("{sign}{:.2}·[{n}]", c.abs());
        }
        println!("- {} {}: {terms}", f.core, f.codec);
    }
    println!();
    print!("{}", fit::report(&rows, |r| fit::predict_with(&fitted, r)));
    if let Some(out) = write {
        let fixed = boards
            .iter()
            .map(|b| b.state_bytes.saturating_sub(4 * b.max_channels))
            .max()
            .ok_or("boards.tsv lists no board")?;
        let mut code: Vec<(Core, usize)> = boards
            .iter()
            .map(|b| (b.core, b.decoder_code_bytes))
            .collect();
        code.sort();
        code.dedup_by_key(|(c, _)| *c);
        std::fs::write(
            out,
            fit::calibration_source(&fitted, &fit::stacks_with_shipped(&rows), fixed, &code),
        )
        .map_err(|e| format!("{}: {e}", out.display()))?;
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}
