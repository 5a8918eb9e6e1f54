//! `latticebuild build`: a manifest to files and reports, once (`watch` runs it on every
//! change).

use std::io::IsTerminal;
use std::path::Path;

use clap::{ArgAction, Args};

use super::{Failure, ManifestArgs, compile, load_manifest, open_cache, sweep_outputs};
use crate::build::Builder;
use crate::cache::SizeLimit;
use crate::diagnostics::color::paint;
use crate::files::{OutputDir, write_atomically};
use crate::progress::{Bars, NoProgress, Progress};
use crate::report::{FailedOutput, Report};

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
    /// Draw no `NAME.png` previews (as `[build] previews = false`): for optimisation loops
    #[arg(long)]
    pub no_previews: bool,
}

/// What a build produced, for `watch --serve`: the reports and the stage graph it ran.
pub struct Built {
    pub reports: Vec<Report>,
    pub graph: crate::graph::Graph,
    /// The nodes the build needed, in build order.
    pub needed: Vec<crate::graph::NodeId>,
}

/// One build: manifest to files and reports.
pub fn run_build(args: &BuildArgs) -> Result<(), Failure> {
    run_build_keeping(args, &mut None)
}

/// [`run_build`], also leaving what it built in `built` once every report is written (even
/// when it then fails over defective meshes).
pub fn run_build_keeping(args: &BuildArgs, built: &mut Option<Built>) -> Result<(), Failure> {
    let mut manifest = load_manifest(&args.manifest)?;
    if args.no_previews {
        manifest.previews = false;
    }
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
    let limit = SizeLimit {
        max_bytes: manifest.cache_max_size,
        free_disk: crate::budget::free_disk(cache.dir()),
    };
    let outcome = Builder::new(&graph, &cache, &sink, progress)
        .with_cache_limit(limit)
        .build(&args.targets)
        .map_err(|e| Failure::Build(e.to_string()))?;
    let mut reports = Vec::new();
    for result in &outcome.results {
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
                eprint!("{}", paint(&format!("{line}\n")));
            }
        }
        reports.push(report);
    }
    // The reports of what built and an entry per output that failed, in output-name order.
    let mut entries: Vec<(&str, serde_json::Value)> = reports
        .iter()
        .map(|r| (r.name.as_str(), serde_json::to_value(r)))
        .chain(outcome.failed.iter().map(|(name, error)| {
            let failed = FailedOutput::new(name, error.clone());
            (name.as_str(), serde_json::to_value(failed))
        }))
        .map(|(name, value)| (name, value.expect("reports serialize")))
        .collect();
    entries.sort_by(|a, b| a.0.cmp(b.0));
    let entries: Vec<serde_json::Value> = entries.into_iter().map(|(_, v)| v).collect();
    match args.report.as_deref() {
        None => {}
        Some("-") => {
            let json = serde_json::to_string_pretty(&entries).expect("reports serialize");
            println!("{json}");
        }
        Some(file) => {
            let json = serde_json::to_string_pretty(&entries).expect("reports serialize");
            crate::files::write_user_file(Path::new(file), &mut |w| w.write_all(json.as_bytes()))
                .map_err(|e| Failure::Build(format!("cannot write `{file}`: {e}")))?;
        }
    }
    // Each failing stage once, however many outputs needed it.
    let mut errors: Vec<&str> = Vec::new();
    for (_, error) in &outcome.failed {
        if !errors.contains(&error.as_str()) {
            errors.push(error);
        }
    }
    let errors = errors.join("\nerror: ");
    let defective: Vec<String> = reports
        .iter()
        .filter(|r| !r.defects.is_empty())
        .map(|r| format!("`{}`: {}", r.name, r.defects.join("; ")))
        .collect();
    let needed = graph.needed(&args.targets).unwrap_or_default();
    // What did build is kept even when another output failed, so `watch --serve` shows it.
    *built = Some(Built {
        reports,
        graph,
        needed,
    });
    if !errors.is_empty() {
        return Err(Failure::Build(errors));
    }
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
