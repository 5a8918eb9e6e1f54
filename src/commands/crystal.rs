//! `latticebuild crystal FILE [--species Si] [--tolerance 1e-9] [--max-scale 8]
//! [--include-images] [--optimize] [--json]`: the loci surface through a crystal's atoms
//! (Wang §5), printed as a report and a table of terms like the paper's Tables 1–2, or as JSON.
//!
//! Exit codes: 0 when the surface passes through every atom within the tolerance; 1 when the
//! search reached `--max-scale` first (the report is still printed); 2 for bad arguments or a
//! file that cannot be read or parsed (the error names its line and column).
//!
//! Invariant: the file is read here (through `files.rs`); the geometry is the
//! same function the `crystal` stage runs.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;
use latticebuild_geom::periodic::model::describe_term;
use latticebuild_geom::periodic::reconstruct::{Metrics, ReconstructOptions};
use serde_json::json;

use crate::stages::crystal::{FoundSurface, reconstruct_crystal};

#[derive(Args, Debug, Clone)]
pub struct CrystalArgs {
    /// The crystal structure: CIF, or extended XYZ with a `Lattice="…"`
    pub file: PathBuf,
    /// Only the atoms of this element (default: every atom)
    #[arg(long)]
    pub species: Option<String>,
    /// Stop once max |ψ(atom)| / max |ψ| over the cell is below this
    #[arg(long, default_value_t = 1e-9)]
    pub tolerance: f64,
    /// The largest scale tried (1, 2, 4, … up to it; at most 64)
    #[arg(long, default_value_t = 8)]
    pub max_scale: u32,
    /// Also pass through the periodic images of atoms on faces, edges and corners
    #[arg(long)]
    pub include_images: bool,
    /// Drop terms greedily to raise the porosity, keeping the error below the tolerance
    #[arg(long)]
    pub optimize: bool,
    /// Print JSON: {atoms, dimension, max_error, porosity, terms: [{moment, scale, vector}], …}
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &CrystalArgs) -> ExitCode {
    let usage = |message: String| {
        eprintln!("error: {message}");
        ExitCode::from(2)
    };
    if !(args.tolerance > 0.0 && args.tolerance.is_finite()) {
        return usage(format!(
            "--tolerance must be a positive number, found {}",
            args.tolerance
        ));
    }
    if !(1..=64).contains(&args.max_scale) {
        return usage(format!(
            "--max-scale must be between 1 and 64, found {}",
            args.max_scale
        ));
    }
    let given = args.file.display().to_string();
    let bytes = match crate::files::read_input(&args.file) {
        Ok(b) => b,
        Err(e) => return usage(format!("cannot read `{given}`: {e}")),
    };
    let options = ReconstructOptions {
        tolerance: args.tolerance,
        max_scale: args.max_scale,
        optimize: args.optimize,
        ..ReconstructOptions::default()
    };
    let found = match reconstruct_crystal(
        &given,
        &bytes,
        args.species.as_deref(),
        args.include_images,
        &options,
    ) {
        Ok(f) => f,
        Err(e) => return usage(e.to_string()),
    };
    if args.json {
        let text = serde_json::to_string_pretty(&to_json(&given, &found))
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
        println!("{text}");
    } else {
        print!("{}", report(&given, args, &found));
    }
    let r = &found.reconstruction;
    if r.converged {
        ExitCode::SUCCESS
    } else {
        eprintln!(
            "error: the error {:.3e} is above the tolerance {:e} at --max-scale {}",
            r.metrics.max_error, args.tolerance, args.max_scale
        );
        ExitCode::from(1)
    }
}

fn metrics_json(m: &Metrics) -> serde_json::Value {
    json!({ "dimension": m.dimension, "max_error": m.max_error, "porosity": m.porosity })
}

fn to_json(given: &str, found: &FoundSurface) -> serde_json::Value {
    let r = &found.reconstruction;
    json!({
        "file": given,
        "name": found.name,
        "species": found.species,
        "atoms": r.atoms,
        "dimension": r.metrics.dimension,
        "max_error": r.metrics.max_error,
        "porosity": r.metrics.porosity,
        "porosity_grid": r.grid,
        "converged": r.converged,
        "steps": r.steps.iter().map(|s| {
            let mut m = metrics_json(&s.metrics);
            m["scales"] = json!(s.scales);
            m
        }).collect::<Vec<_>>(),
        "optimization": r.optimization.as_ref().map(|(before, after)| {
            json!({ "before": metrics_json(before), "after": metrics_json(after) })
        }),
        "terms": r.model.terms.iter().map(|t| {
            json!({ "moment": t.moment, "scale": t.scale, "vector": t.vector })
        }).collect::<Vec<_>>(),
    })
}

fn report(given: &str, args: &CrystalArgs, found: &FoundSurface) -> String {
    let r = &found.reconstruction;
    let which = args.species.as_deref().unwrap_or("all");
    let images = if args.include_images {
        ", with images on faces"
    } else {
        ""
    };
    let mut out = format!(
        "{given}: `{}`, {} atoms ({which}{images}); species {}\n",
        found.name,
        r.atoms,
        found.species.join(", ")
    );
    out.push_str("search (error relative to max |ψ| over the cell):\n");
    for s in &r.steps {
        let scales: Vec<String> = s.scales.iter().map(u32::to_string).collect();
        out.push_str(&format!(
            "  scales {:<14} dimension {:>3}   max error {:>9.3e}   porosity {:.4}\n",
            scales.join(","),
            s.metrics.dimension,
            s.metrics.max_error,
            s.metrics.porosity
        ));
    }
    if let Some((before, after)) = &r.optimization {
        out.push_str(&format!(
            "optimised (§5.3): dimension {} → {}, max error {:.3e} → {:.3e}, porosity {:.4} → {:.4}\n",
            before.dimension,
            after.dimension,
            before.max_error,
            after.max_error,
            before.porosity,
            after.porosity
        ));
    }
    let verdict = if r.converged {
        "passes through every atom"
    } else {
        "does NOT reach the tolerance"
    };
    out.push_str(&format!(
        "surface {verdict}: dimension {}, max error {:.3e} (tolerance {:e}), porosity {:.4} \
         on a {}³ grid\n",
        r.metrics.dimension, r.metrics.max_error, args.tolerance, r.metrics.porosity, r.grid
    ));
    out.push_str(
        "model, normalised to max |ψ| = 1 (a lower porosity means more surface, Lemma 6):\n",
    );
    out.push_str(&format!(
        "  {:>12}  {:>5}  {:>26}  term\n",
        "moment", "scale", "vector [a, b, c, θ]"
    ));
    for t in &r.model.terms {
        let vector: Vec<String> = t.vector.iter().map(|v| format!("{v}")).collect();
        out.push_str(&format!(
            "  {:>12.6}  {:>5}  {:>26}  {}\n",
            t.moment,
            t.scale,
            format!("[{}]", vector.join(", ")),
            describe_term(t)
        ));
    }
    out
}
