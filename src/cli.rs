//! The command line: argument parsing, dispatch to the commands, and exit codes (0 ok, 1
//! build failure, 2 usage or manifest error). `build` and what the commands share are in
//! [`crate::commands`].

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use crate::build::Builder;
use crate::commands::build::{BuildArgs, run_build};
use crate::commands::{Failure, ManifestArgs, compile, load_manifest, open_cache, sweep_outputs};
use crate::files::OutputDir;
use crate::progress::NoProgress;

mod crystal_command;
mod sdf_command;

#[derive(Parser, Debug)]
#[command(
    name = "latticebuild",
    version,
    about = "Build lattice microstructures from a TOML manifest through a cached stage DAG",
    long_about = "latticebuild turns a TOML manifest of unit cells and outputs into watertight \
                  lattice meshes. Every stage (cell, sample, fit, constrain, contour, write) is \
                  cached under .latticebuild/ next to the manifest, so a rebuild only redoes what \
                  changed."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Build every output that is out of date (or only the named ones)
    Build(BuildArgs),
    /// Build, then rebuild whenever the manifest or a file it references is saved
    Watch(BuildArgs),
    /// Print the stage graph, marking what is cached and what is stale
    Graph(ManifestArgs),
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
                            intersection, difference. @FILE inserts the words of FILE.\n\n\
                            Options, anywhere among the words: -s SAMPLES (a total like 100^3, \
                            or NX,NY,NZ; default 60^3), -b X0,Y0,Z0,X1,Y1,Z1 (default: the \
                            solid's bounds), -o FILE (default out.ply; .stl .ply .obj .off .vtk), \
                            -q (no summary), --allow-large (contour even a grid estimated \
                            to need more memory or disk than the machine has)."
    )]
    Sdf(SdfArgs),
    /// Reconstruct the periodic surface through a crystal's atoms (CIF or extended XYZ)
    Crystal(crystal_command::CrystalArgs),
}

#[derive(Args, Debug, Clone)]
pub struct SdfArgs {
    /// The program's words, with -s, -b, -o and @FILE anywhere among them
    #[arg(
        value_name = "WORDS",
        required = true,
        trailing_var_arg = true,
        allow_hyphen_values = true
    )]
    pub words: Vec<String>,
}

#[derive(Args, Debug, Clone)]
pub struct CellArgs {
    #[command(flatten)]
    pub manifest: ManifestArgs,
    /// The cell, by its name in the manifest
    pub name: String,
    /// Print JSON instead of a table of the largest terms
    #[arg(long)]
    pub json: bool,
    /// Also evaluate the cell at these points (one per line, in the reference frame)
    #[arg(long, value_name = "FILE")]
    pub points: Option<PathBuf>,
}

pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Build(args) => {
            if let Err(f) = set_jobs(args.jobs) {
                return f.exit();
            }
            match run_build(&args) {
                Ok(()) => ExitCode::SUCCESS,
                Err(f) => f.exit(),
            }
        }
        Command::Watch(args) => {
            if let Err(f) = set_jobs(args.jobs) {
                return f.exit();
            }
            crate::watch::watch(&args)
        }
        Command::Graph(args) => match run_graph(&args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(f) => f.exit(),
        },
        Command::Clean(args) => match run_clean(&args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(f) => f.exit(),
        },
        Command::Cell(args) => match run_cell(&args) {
            Ok(()) => ExitCode::SUCCESS,
            Err(f) => f.exit(),
        },
        Command::Sdf(args) => sdf_command::run(&args.words),
        Command::Crystal(args) => crystal_command::run(&args),
    }
}

fn run_cell(args: &CellArgs) -> Result<(), Failure> {
    let manifest = load_manifest(&args.manifest)?;
    let file = args.manifest.manifest.display().to_string();
    let Some(cell) = manifest.cells.get(&args.name) else {
        let names = manifest.cells.keys().map(String::as_str);
        let help = match latticebuild_geom::spelling::closest(&args.name, names) {
            Some(s) => format!("  = help: did you mean `{s}`?\n"),
            None => String::new(),
        };
        return Err(Failure::Usage(format!(
            "error: no cell named `{}` in `{file}`\n{help}",
            args.name
        )));
    };
    let Some(spec) = &cell.symmetric else {
        return Err(Failure::Usage(format!(
            "error: cell `{}` has no `symmetry`, so it has no coefficients to show\n  = help: add `symmetry = \"Oh\"` (or D3, D4, Td) to `[cells.{}]`\n",
            args.name, args.name
        )));
    };
    let group = crate::stages::symmetric::group_of(&spec.group)
        .map_err(|e| Failure::Build(e.to_string()))?;
    let points = match &args.points {
        None => Vec::new(),
        Some(path) => {
            let text = crate::files::read_input_text(path).map_err(|e| {
                Failure::Usage(format!("error: cannot read `{}`: {e}\n", path.display()))
            })?;
            crate::inspect::read_points(&path.display().to_string(), &text, group.dimension())
                .map_err(Failure::Usage)?
        }
    };
    let mut graph = compile(&manifest)?;
    let node = graph
        .compile_cell(&manifest, &args.name)
        .map_err(|c| Failure::Usage(format!("error: {c}\n")))?;
    let cache = open_cache(&manifest.path, true)?;
    let sink = OutputDir::new(manifest.out_dir.clone());
    let payload = Builder::new(&graph, &cache, &sink, &NoProgress)
        .build_node(node)
        .map_err(|e| Failure::Build(e.to_string()))?;
    let fitted = crate::stages::symmetric::FittedPayload::from_bytes(&payload)
        .map_err(|e| Failure::Build(e.to_string()))?;
    let report =
        crate::inspect::report(&args.name, &fitted, &group, &points).map_err(Failure::Build)?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).expect("cell report serializes")
        );
    } else {
        print!("{}", crate::inspect::table(&report, 20));
    }
    Ok(())
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
        eprintln!("warning: `--jobs {jobs}` is more than this machine can use; using {most}");
        jobs = most;
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build_global()
        .map_err(|e| Failure::Build(format!("cannot start {jobs} worker threads: {e}")))
}

fn run_graph(args: &ManifestArgs) -> Result<(), Failure> {
    let manifest = load_manifest(args)?;
    let graph = compile(&manifest)?;
    let cache = open_cache(&manifest.path, false)?;
    let sink = OutputDir::new(manifest.out_dir.clone());
    for line in crate::graph::status::lines(&graph, &cache, &sink) {
        println!("{line}");
    }
    Ok(())
}

fn run_clean(args: &ManifestArgs) -> Result<(), Failure> {
    let manifest = load_manifest(args)?;
    let mut cache = open_cache(&manifest.path, false)?;
    sweep_outputs(&manifest, false);
    cache.clean().map_err(|e| Failure::Build(e.to_string()))?;
    eprintln!("removed the cache of `{}`", manifest.path.display());
    Ok(())
}
