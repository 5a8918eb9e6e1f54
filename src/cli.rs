//! The command line: argument parsing, the commands, and exit codes (0 ok, 1 build failure,
//! 2 usage or manifest error). With the cache, the only module that touches the filesystem.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{ArgAction, Args, Parser, Subcommand};

use crate::build::{Builder, NoProgress, Progress};
use crate::cache::Cache;
use crate::diagnostics::render;
use crate::files::{OutputDir, write_atomically};
use crate::graph::Graph;
use crate::manifest::{self, Manifest};
use crate::progress::Bars;
use crate::report::Report;

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
    /// Internal: frees files a build renamed away (temporary names only), after it returned
    #[command(hide = true)]
    FreeFiles { paths: Vec<std::path::PathBuf> },
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

#[derive(Args, Debug, Clone)]
pub struct ManifestArgs {
    /// The manifest (TOML)
    pub manifest: PathBuf,
    /// Override a manifest value, e.g. `--set outputs.g.offset=0.12` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

#[derive(Args, Debug, Clone)]
pub struct BuildArgs {
    #[command(flatten)]
    pub manifest: ManifestArgs,
    /// Outputs to build (default: all)
    pub targets: Vec<String>,
    /// Worker threads (default: one per core)
    #[arg(short = 'j', long = "jobs", value_name = "N")]
    pub jobs: Option<usize>,
    /// Print nothing but errors
    #[arg(short, long, conflicts_with = "verbose")]
    pub quiet: bool,
    /// Say for every stage whether it ran and why
    #[arg(short, long, action = ArgAction::Count)]
    pub verbose: u8,
    /// Also write the reports as one JSON array to FILE (`-` for stdout)
    #[arg(long, value_name = "FILE")]
    pub report: Option<String>,
    /// Succeed even when an output's mesh is not watertight or not manifold (the files and
    /// reports are written either way; the report lists the defects)
    #[arg(long)]
    pub allow_defects: bool,
    /// Build even when the estimated memory or disk use exceeds what the machine has
    #[arg(long)]
    pub allow_large: bool,
}

/// Why a build did not succeed, with its exit code.
pub enum Failure {
    /// Bad manifest or arguments: exit 2. The text is already rendered.
    Usage(String),
    /// The build itself failed: exit 1.
    Build(String),
}

impl Failure {
    pub fn exit(self) -> ExitCode {
        match self {
            Failure::Usage(text) => {
                eprint!("{text}");
                ExitCode::from(2)
            }
            Failure::Build(text) => {
                eprintln!("error: {text}");
                ExitCode::from(1)
            }
        }
    }
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
        Command::FreeFiles { paths } => {
            crate::deferred_free::free_files(&paths);
            ExitCode::SUCCESS
        }
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
    let group = crate::stages::symmetric::group_of(&spec.group).map_err(Failure::Build)?;
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
    let fitted =
        crate::stages::symmetric::FittedPayload::from_bytes(&payload).map_err(Failure::Build)?;
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

/// Loads and validates the manifest, rendering every diagnostic on failure.
pub fn load_manifest(args: &ManifestArgs) -> Result<Manifest, Failure> {
    manifest::load(&args.manifest, &args.set).map_err(|diags| Failure::Usage(render(&diags)))
}

fn open_cache(path: &Path, quiet: bool) -> Result<Cache, Failure> {
    Cache::open_with(path, || {
        if !quiet {
            eprintln!(
                "waiting for another build of `{}` to finish…",
                path.display()
            );
        }
    })
    .map_err(|e| Failure::Build(e.to_string()))
}

fn compile(manifest: &Manifest) -> Result<Graph, Failure> {
    Graph::compile(manifest).map_err(|cycle| Failure::Usage(format!("error: {cycle}\n")))
}

/// One build: manifest to files and reports.
pub fn run_build(args: &BuildArgs) -> Result<(), Failure> {
    let manifest = load_manifest(&args.manifest)?;
    crate::files::check_report_path(args.report.as_deref(), &manifest).map_err(Failure::Usage)?;
    let graph = compile(&manifest)?;
    if let Err(unknown) = graph.needed(&args.targets) {
        let names: Vec<&str> = graph.outputs.keys().map(String::as_str).collect();
        let mut text = String::new();
        for name in unknown {
            text.push_str(&format!(
                "error: no output named `{name}` in `{}`\n",
                args.manifest.manifest.display()
            ));
            match latticebuild_geom::spelling::closest(&name, names.iter().copied()) {
                Some(s) => text.push_str(&format!("  = help: did you mean `{s}`?\n")),
                None => text.push_str(&format!("  = help: outputs are: {}\n", names.join(", "))),
            }
        }
        return Err(Failure::Usage(text));
    }
    let estimates = crate::budget::estimate(&manifest, &args.targets);
    if !args.allow_large {
        let machine = crate::budget::Machine::probe(&manifest.out_dir);
        let refused = crate::budget::refusals(&estimates, machine);
        if !refused.is_empty() {
            let mut text = String::new();
            for why in refused {
                text.push_str(&format!("error: {why}\n"));
            }
            text.push_str(
                "  = help: lower the samples or resolution, or pass `--allow-large` to build \
                 anyway (the figures are upper-end estimates)\n",
            );
            return Err(Failure::Usage(text));
        }
    }
    let cache = open_cache(&manifest.path, args.quiet)?;
    sweep_outputs(&manifest, args.verbose > 0);
    let sink = OutputDir::new(manifest.out_dir.clone());
    let bars;
    let progress: &dyn Progress = if !args.quiet && std::io::stderr().is_terminal() {
        bars = Bars::new();
        &bars
    } else {
        &NoProgress
    };
    let results = Builder::new(&graph, &cache, &sink, progress)
        .build(&args.targets)
        .map_err(|e| Failure::Build(e.to_string()))?;
    // The outputs are in place: what they replaced, and the cache entries gc collected, are
    // freed by a detached helper, so the command need not wait for the disk. Handed over
    // before anything is printed: a closed stdout or stderr ends the process at its next
    // write (SIGPIPE, see main.rs), which would leave them under their temporary names.
    let mut freed = sink.take_replaced();
    freed.extend(cache.take_collected());
    crate::deferred_free::free_detached(freed);
    let mut reports = Vec::new();
    for result in &results {
        if args.verbose > 0 {
            for run in &result.stages {
                if run.cached {
                    eprintln!("  {}: cached", run.node);
                } else {
                    eprintln!(
                        "  {}: ran in {:.2} s because {}",
                        run.node,
                        run.seconds,
                        run.why.join("; ")
                    );
                }
            }
        }
        let mut report = Report::new(&manifest, result);
        report.estimate = estimates
            .iter()
            .find(|(name, _)| *name == result.name)
            .map(|(_, e)| e.clone());
        let path = manifest
            .out_dir
            .join(format!("{}.report.json", result.name));
        let json = serde_json::to_string_pretty(&report).expect("report serializes");
        write_atomically(&path, &mut |w| w.write_all(json.as_bytes()))
            .map_err(|e| Failure::Build(format!("cannot write `{}`: {e}", path.display())))?;
        if !args.quiet {
            eprintln!("{}", report.summary_line());
            for line in report.warning_lines() {
                eprintln!("{line}");
            }
        }
        reports.push(report);
    }
    match args.report.as_deref() {
        None => {}
        Some("-") => {
            let json = serde_json::to_string_pretty(&reports).expect("reports serialize");
            println!("{json}");
        }
        Some(file) => {
            let json = serde_json::to_string_pretty(&reports).expect("reports serialize");
            crate::files::write_user_file(Path::new(file), &mut |w| w.write_all(json.as_bytes()))
                .map_err(|e| Failure::Build(format!("cannot write `{file}`: {e}")))?;
        }
    }
    let defective: Vec<String> = reports
        .iter()
        .filter(|r| !r.defects.is_empty())
        .map(|r| format!("`{}`: {}", r.name, r.defects.join("; ")))
        .collect();
    if !defective.is_empty() && !args.allow_defects {
        return Err(Failure::Build(format!(
            "{} output(s) failed the mesh check (written and reported, but not usable as \
             solids; `--allow-defects` accepts them):\n  {}",
            defective.len(),
            defective.join("\n  ")
        )));
    }
    Ok(())
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

/// Removes the temporary files that killed builds left among the outputs.
fn sweep_outputs(manifest: &Manifest, verbose: bool) {
    for path in crate::files::sweep_stale_temporaries(&manifest::output_dirs(manifest)) {
        if verbose {
            eprintln!(
                "  removed `{}`, left by an interrupted build",
                path.display()
            );
        }
    }
}

fn run_clean(args: &ManifestArgs) -> Result<(), Failure> {
    let manifest = load_manifest(args)?;
    let mut cache = open_cache(&manifest.path, false)?;
    sweep_outputs(&manifest, false);
    cache.clean().map_err(|e| Failure::Build(e.to_string()))?;
    eprintln!("removed the cache of `{}`", manifest.path.display());
    Ok(())
}
