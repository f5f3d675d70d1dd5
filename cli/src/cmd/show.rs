//! `mocap show build`: a show file (TOML: clips, rig, transitions, cue lists,
//! triggers) into one show `.mcb` (SPEC.md §9), every clip's bound proven.

use std::path::PathBuf;

use mocap_encoder::show::{self, file::ShowSpec};

use super::write;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Subcommand)]
enum Command {
    /// Encode every clip of a show file and assemble them into one show .mcb.
    Build(BuildArgs),
}

#[derive(clap::Args)]
struct BuildArgs {
    /// The show file (TOML; schema in assets/shows/README.md).
    input: PathBuf,
    /// Output .mcb show.
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(a: Args) -> super::Result {
    match a.command {
        Command::Build(b) => build(b),
    }
}

fn build(a: BuildArgs) -> super::Result {
    let spec = ShowSpec::read_file(&a.input)?;
    eprintln!(
        "{}: show `{}`, {} clips{}; encoding…",
        a.input.display(),
        spec.name,
        spec.clips.len(),
        spec.rig
            .as_ref()
            .map(|r| format!(" on the rig {}", r.display()))
            .unwrap_or_default()
    );
    let bar = crate::progress::Bar::new(spec.clips.len());
    let built = show::build_with(&spec, &|at, units, name| {
        bar.unit(at, units, format!("clip {name}"));
        Box::new(crate::progress::Nested {
            bar: &bar,
            at,
            units,
            label: format!("clip {name}"),
        })
    });
    bar.finish();
    let built = built?;
    write(&a.output, &built.bytes)?;
    print!("{}", show::report(&a.output, &spec, &built));
    Ok(())
}
