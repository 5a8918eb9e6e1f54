//! The command line: argument parsing, `--jobs`, `--color`, and dispatch to the commands in
//! [`crate::commands`], one module per command; `completions` prints a shell's completion
//! script for this parser. Exit codes: 0 ok, 1 build failure, 2 usage or manifest error.

use std::process::ExitCode;

use std::io::IsTerminal;

use clap::{CommandFactory, Parser, Subcommand, ValueEnum};

use crate::commands::build::{BuildArgs, run_build};
use crate::commands::cell::CellArgs;
use crate::commands::crystal::CrystalArgs;
use crate::commands::graph::GraphArgs;
use crate::commands::sdf::SdfArgs;
use crate::commands::{self, Failure, ManifestArgs};

#[derive(Parser, Debug)]
#[command(
    name = "latticebuild",
    version,
    propagate_version = true,
    about = "Build lattice microstructures from a TOML manifest through a cached stage DAG",
    long_about = "latticebuild turns a TOML manifest of unit cells and outputs into watertight \
                  lattice meshes. Every stage (cell, sample, fit, constrain, contour, write) is \
                  cached under .latticebuild/ next to the manifest, so a rebuild only redoes what \
                  changed."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Colour diagnostics: `auto` only on a terminal (and not under `NO_COLOR`)
    #[arg(long, global = true, value_enum, value_name = "WHEN", default_value_t = Color::Auto)]
    color: Color,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum Color {
    Auto,
    Always,
    Never,
}

/// The parser, for `cargo xtask man` and the completion scripts.
pub fn command() -> clap::Command {
    Cli::command()
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Build every output that is out of date (or only the named ones)
    Build(BuildArgs),
    /// Build, then rebuild whenever the manifest or a file it references is saved (`--serve`:
    /// and show the outputs live in a browser)
    Watch(commands::watch::WatchArgs),
    /// Print the stage graph, marking what is cached and what is stale
    Graph(GraphArgs),
    /// Remove this manifest's cache entries
    Clean(ManifestArgs),
    /// Fit a symmetric cell (from the cache when fresh) and print its coefficients and values
    Cell(CellArgs),
    /// Contour an SDF program in the Cesogen stack language (`latticebuild sdf ball scale 2`)
    #[command(
        long_about = "Contour an SDF program in the Cesogen stack language: a Cesogen \
                            command line with the program name replaced.\n\n\
                            Solids: ball, cylinder, box, tpms.NAME, expression FORMULA, file PATH. \
                            Unary: complement, offset R, shell T, move X,Y,Z, scale K or \
                            scale KX,KY,KZ, rotate AX,AY,AZ ANGLE, orient AX,AY,AZ. Binary: union, \
                            intersection, difference, sigmoid-blend DX,DY,DZ X0 WIDTH (graded \
                            from the first solid to the second along the direction). @FILE inserts the words of FILE.\n\n\
                            Options, anywhere among the words: -s SAMPLES (a total like 100^3, \
                            or NX,NY,NZ; default 60^3), -b X0,Y0,Z0,X1,Y1,Z1 (default: the \
                            solid's bounds), -o FILE (default out.ply; .stl .ply .obj .off .vtk), \
                            --contour tetrahedra (marching tetrahedra; default cubes), \
                            --units UNIT (mm, cm, m, um or in, for the file's header; default mm), \
                            -q (no summary), --allow-large (contour even a grid estimated \
                            to need more memory or disk than the machine has)."
    )]
    Sdf(SdfArgs),
    /// Reconstruct the periodic surface through a crystal's atoms (CIF or extended XYZ)
    Crystal(CrystalArgs),
    /// Print a completion script for SHELL (see the README for where to put it)
    Completions {
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

pub fn main() -> ExitCode {
    let cli = Cli::parse();
    use crate::diagnostics::color::{self, ColorChoice};
    let choice = match cli.color {
        Color::Auto => ColorChoice::Auto,
        Color::Always => ColorChoice::Always,
        Color::Never => ColorChoice::Never,
    };
    color::set(color::decide(
        choice,
        std::io::stderr().is_terminal(),
        |name: &str| std::env::var_os(name),
    ));
    match cli.command {
        Command::Build(args) => {
            if let Err(f) = set_jobs(args.jobs) {
                return f.exit();
            }
            exit(run_build(&args))
        }
        Command::Watch(args) => {
            if let Err(f) = set_jobs(args.build.jobs) {
                return f.exit();
            }
            commands::watch::watch(&args)
        }
        Command::Graph(args) => exit(commands::graph::run(&args)),
        Command::Clean(args) => exit(commands::clean::run(&args)),
        Command::Cell(args) => exit(commands::cell::run(&args)),
        Command::Sdf(args) if args.asks_for_help() => {
            let mut cli = Cli::command();
            if let Some(sdf) = cli.find_subcommand_mut("sdf") {
                let _ = sdf.print_long_help();
            }
            ExitCode::SUCCESS
        }
        Command::Sdf(args) => commands::sdf::run(&args),
        Command::Crystal(args) => commands::crystal::run(&args),
        Command::Completions { shell } => {
            clap_complete::generate(
                shell,
                &mut Cli::command(),
                "latticebuild",
                &mut std::io::stdout(),
            );
            ExitCode::SUCCESS
        }
    }
}

fn set_jobs(jobs: Option<usize>) -> Result<(), Failure> {
    let Some(mut jobs) = jobs else { return Ok(()) };
    if jobs == 0 {
        return Err(Failure::Usage(
            "error: `--jobs` must be at least 1\n".into(),
        ));
    }
    // More threads than this only cost memory and start-up time (`-j 100000` spent a minute
    // spawning threads): the work splits into far fewer pieces.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let most = (4 * cores).max(64);
    if jobs > most {
        eprint!(
            "{}",
            crate::diagnostics::color::paint(&format!(
                "warning: `--jobs {jobs}` is more than this machine can use; using {most}\n"
            ))
        );
        jobs = most;
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build_global()
        .map_err(|e| Failure::Build(format!("cannot start {jobs} worker threads: {e}")))
}

fn exit(result: Result<(), Failure>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => f.exit(),
    }
}
