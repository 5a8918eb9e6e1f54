//! `latticebuild crystal FILE [--species Si] [--tolerance 1e-9] [--max-scale 8]
//! [--include-images] [--optimize] [--scale sx,sy,sz] [--rotate ax,ay,az,DEG]
//! [--translate tx,ty,tz] [--json]`: the loci surface through a crystal's atoms (Wang §5),
//! printed as a report and a table of terms like the paper's Tables 1–2 with its Chebyshev
//! form (eq. 4), or as JSON.
//!
//! The transform flags mean what a cell's `transform` key means (scale, then rotate, then
//! translate; degrees; cell coordinates) and move the printed terms exactly; the error and
//! porosity are the surface's before it is moved, where the atoms are.
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
use latticebuild_geom::periodic::PsModel;
use latticebuild_geom::periodic::model::{ChebyshevForm, PsTerm, describe_term};
use latticebuild_geom::periodic::reconstruct::{Metrics, ReconstructOptions};
use serde_json::json;

use crate::diagnostics::color::paint;
use crate::manifest::PsTransform;
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
    /// Raise the porosity (Wang's eq. 12), keeping the error below the tolerance
    #[arg(long)]
    pub optimize: bool,
    /// Scale the printed surface per axis first: sx,sy,sz (non-zero)
    #[arg(long, value_name = "SX,SY,SZ", allow_hyphen_values = true)]
    pub scale: Option<String>,
    /// Then rotate it about an axis through the origin by DEG degrees (right-hand rule)
    #[arg(long, value_name = "AX,AY,AZ,DEG", allow_hyphen_values = true)]
    pub rotate: Option<String>,
    /// Then translate it, in cell coordinates
    #[arg(long, value_name = "TX,TY,TZ", allow_hyphen_values = true)]
    pub translate: Option<String>,
    /// Print JSON: {atoms, dimension, max_error, porosity, multiplicity, terms: [{moment,
    /// scale, vector}], chebyshev, optimization, …}
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &CrystalArgs) -> ExitCode {
    let usage = |message: String| {
        eprint!("{}", paint(&format!("error: {message}\n")));
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
    let transform = match transform_of(args) {
        Ok(t) => t,
        Err(message) => return usage(message),
    };
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
    let model = match &transform {
        Some(t) => match t.apply(&found.reconstruction.model) {
            Some(m) => m,
            None => return usage("the transform is singular".to_string()),
        },
        None => found.reconstruction.model.clone(),
    };
    if args.json {
        let text =
            serde_json::to_string_pretty(&to_json(&given, &found, &model, transform.as_ref()))
                .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
        println!("{text}");
    } else {
        print!("{}", report(&given, args, &found, &model));
    }
    let r = &found.reconstruction;
    if r.converged {
        ExitCode::SUCCESS
    } else {
        eprint!(
            "{}",
            paint(&format!(
                "error: the error {:.3e} is above the tolerance {:e} at --max-scale {}\n",
                r.metrics.max_error, args.tolerance, args.max_scale
            ))
        );
        ExitCode::from(1)
    }
}

/// `--scale`, `--rotate` and `--translate` as one transform, `None` when none is given.
fn transform_of(args: &CrystalArgs) -> Result<Option<PsTransform>, String> {
    if args.scale.is_none() && args.rotate.is_none() && args.translate.is_none() {
        return Ok(None);
    }
    let mut t = PsTransform::IDENTITY;
    if let Some(text) = &args.scale {
        let s = numbers("--scale", text, "SX,SY,SZ")?;
        if s.contains(&0.0) {
            return Err(format!("--scale factors must not be 0, found `{text}`"));
        }
        t.scale = [s[0], s[1], s[2]];
    }
    if let Some(text) = &args.rotate {
        let r = numbers("--rotate", text, "AX,AY,AZ,DEG")?;
        if r[..3].iter().all(|v| *v == 0.0) {
            return Err(format!("--rotate needs a non-zero axis, found `{text}`"));
        }
        t.axis = [r[0], r[1], r[2]];
        t.angle_degrees = r[3];
    }
    if let Some(text) = &args.translate {
        let v = numbers("--translate", text, "TX,TY,TZ")?;
        t.translate = [v[0], v[1], v[2]];
    }
    Ok(Some(t))
}

/// Comma-separated finite numbers, as many as `form` has parts.
fn numbers(flag: &str, text: &str, form: &str) -> Result<Vec<f64>, String> {
    let want = form.split(',').count();
    let parsed: Option<Vec<f64>> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect();
    match parsed {
        Some(v) if v.len() == want => Ok(v),
        _ => Err(format!(
            "{flag} takes {want} comma-separated numbers {form}, found `{text}`"
        )),
    }
}

fn metrics_json(m: &Metrics) -> serde_json::Value {
    json!({
        "dimension": m.dimension,
        "max_error": m.max_error,
        "porosity": m.porosity,
        "multiplicity": m.multiplicity,
    })
}

fn terms_json(terms: &[PsTerm]) -> Vec<serde_json::Value> {
    terms
        .iter()
        .map(|t| json!({ "moment": t.moment, "scale": t.scale, "vector": t.vector }))
        .collect()
}

fn chebyshev_json(form: &ChebyshevForm) -> serde_json::Value {
    json!({
        "constant": form.constant,
        "planes": form.planes.iter().map(|p| {
            json!({ "vector": p.vector, "coefficients": p.coefficients })
        }).collect::<Vec<_>>(),
    })
}

fn to_json(
    given: &str,
    found: &FoundSurface,
    model: &PsModel,
    transform: Option<&PsTransform>,
) -> serde_json::Value {
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
        "multiplicity": r.metrics.multiplicity,
        "unique": r.metrics.multiplicity == 1,
        "steps": r.steps.iter().map(|s| {
            let mut m = metrics_json(&s.metrics);
            m["scales"] = json!(s.scales);
            m
        }).collect::<Vec<_>>(),
        "optimization": r.optimization.as_ref().map(|o| {
            json!({
                "before": metrics_json(&o.before),
                "after": metrics_json(&o.after),
                "method": o.method.describe(),
                "scales": o.scales,
                "freedom": o.freedom,
                "phase": o.phase.as_ref().map(|p| json!({
                    "theta": p.theta,
                    "evaluations": p.evaluations,
                    "porosity_at_zero": p.porosity_at_zero,
                    "porosity_at_theta": p.porosity_at_theta,
                })),
                "domain": DOMAIN,
            })
        }),
        "transform": transform.map(|t| json!({
            "scale": t.scale,
            "rotate": { "axis": t.axis, "angle": t.angle_degrees },
            "translate": t.translate,
        })),
        "terms": terms_json(&model.terms),
        "chebyshev": model.chebyshev().as_ref().map(chebyshev_json),
    })
}

/// The domain of eq. 11–12: fixed, since moving it changes nothing (`geom::periodic::phase`).
const DOMAIN: &str = "the unit cell [0, 1)³ (a period: moving it changes neither the surface \
                      nor the porosity)";

fn report(given: &str, args: &CrystalArgs, found: &FoundSurface, model: &PsModel) -> String {
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
    if let Some(o) = &r.optimization {
        let scales: Vec<String> = o.scales.iter().map(u32::to_string).collect();
        out.push_str(&format!(
            "optimised (eq. 12, {} on scales {}, {} exact fits): dimension {} → {}, \
             max error {:.3e} → {:.3e}, porosity {:.4} → {:.4}\n",
            o.method.describe(),
            scales.join(","),
            o.freedom,
            o.before.dimension,
            o.after.dimension,
            o.before.max_error,
            o.after.max_error,
            o.before.porosity,
            o.after.porosity
        ));
        if let Some(p) = &o.phase {
            let plain =
                |v: Option<f64>| v.map_or("not converged".to_string(), |v| format!("{v:.4}"));
            out.push_str(&format!(
                "phase shift θ = {} in every basis vector (searched over [0, ½) by {} plain \
                 searches; their porosity {} at θ = 0, {} at the best θ); domain: {DOMAIN}\n",
                p.theta,
                p.evaluations,
                plain(p.porosity_at_zero),
                plain(p.porosity_at_theta)
            ));
        }
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
    if r.metrics.multiplicity > 1 {
        let chosen = if r.optimization.is_some() {
            "the one of highest porosity found"
        } else {
            "the canonical one (the exact fit closest to a single term, the same whatever the \
             order of the atoms)"
        };
        out.push_str(&format!(
            "note: not unique: the smallest singular value is repeated {} times, so the atoms \
             lie on {} independent surfaces of this basis; shown is {chosen}\n",
            r.metrics.multiplicity, r.metrics.multiplicity
        ));
    }
    if args.scale.is_some() || args.rotate.is_some() || args.translate.is_some() {
        out.push_str(
            "terms moved by the transform (scale, then rotate, then translate); the error and \
             porosity above are the surface's where the atoms are\n",
        );
    }
    out.push_str(
        "model, normalised to max |ψ| = 1 (a lower porosity means more surface, Lemma 6):\n",
    );
    out.push_str(&format!(
        "  {:>12}  {:>5}  {:>26}  term\n",
        "moment", "scale", "vector [a, b, c, θ]"
    ));
    for t in &model.terms {
        let vector: Vec<String> = t.vector.iter().map(|v| format!("{v}")).collect();
        out.push_str(&format!(
            "  {:>12.6}  {:>5}  {:>26}  {}\n",
            t.moment,
            t.scale,
            format!("[{}]", vector.join(", ")),
            describe_term(t)
        ));
    }
    out.push_str(&chebyshev_table(model));
    out
}

/// The Chebyshev form (eq. 4), one polynomial per basis vector.
fn chebyshev_table(model: &PsModel) -> String {
    let Some(form) = model.chebyshev() else {
        return "no Chebyshev form: a scale is not a natural number\n".to_string();
    };
    let mut out = format!(
        "Chebyshev form (eq. 4), T_k(s) = cos(k arccos s):\n  constant {:+.6}\n",
        form.constant
    );
    for plane in &form.planes {
        let s = describe_term(&PsTerm {
            moment: 1.0,
            scale: 1.0,
            vector: plane.vector,
        });
        let polynomial: Vec<String> = plane
            .coefficients
            .iter()
            .enumerate()
            .filter(|(_, c)| **c != 0.0)
            .map(|(k, c)| format!("{c:+.6} T{k}(s)"))
            .collect();
        let s = s.trim_start_matches("+1.000000 ");
        out.push_str(&format!("  s = {s:<22} {}\n", polynomial.join(" ")));
    }
    out
}
