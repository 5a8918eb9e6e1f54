//! `latticebuild cell MANIFEST NAME`: a fitted cell's coefficients, constraint and values, as
//! JSON (`--json`) or as a readable table of its largest terms.
//!
//! Conventions (docs/method.md §Conjugation): coefficients are `c_f = ⟨g, φ_f⟩` in centred
//! coordinates, with
//! `f` in skew integer coordinates for D3; points are in the cell's Cartesian reference frame
//! (centroid at the origin, cell size 1); `value` is Re Φ and `gradient` its Cartesian gradient.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use latticebuild_geom::symmetric::Group;

use super::{Failure, ManifestArgs, compile, load_manifest, open_cache};
use crate::build::Builder;
use crate::files::OutputDir;
use crate::progress;
use crate::stages::symmetric::{AutoSummary, FittedPayload, Measures, OptimizationSummary};

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

pub fn run(args: &CellArgs) -> Result<(), Failure> {
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
            read_points(&path.display().to_string(), &text, group.dimension())
                .map_err(Failure::Usage)?
        }
    };
    let mut graph = compile(&manifest)?;
    let node = graph
        .compile_cell(&manifest, &args.name)
        .map_err(|c| Failure::Usage(format!("error: {c}\n")))?;
    let cache = open_cache(&manifest.path, true)?;
    let sink = OutputDir::new(manifest.out_dir.clone());
    // A fit can take minutes (N = 512, `n = "auto"`): its stages show bars like a build's.
    let bars = progress::on_stderr(false);
    let payload = Builder::new(&graph, &cache, &sink, bars.as_ref())
        .build_node(node)
        .map_err(|e| Failure::Build(e.to_string()))?;
    drop(bars);
    let fitted = crate::stages::symmetric::FittedPayload::from_bytes(&payload)
        .map_err(|e| Failure::Build(e.to_string()))?;
    let report = report(&args.name, &fitted, &group, &points).map_err(Failure::Build)?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).expect("cell report serializes")
        );
    } else {
        print!("{}", table(&report, 20));
    }
    Ok(())
}

#[derive(Debug, Serialize)]
pub struct CellReport {
    pub name: String,
    pub group: String,
    pub n: usize,
    pub extend: String,
    pub coefficients: Vec<CoefficientRow>,
    pub constraint: ConstraintRow,
    /// How `n = "auto"` chose N; `None` for a fixed N.
    pub auto: Option<AutoSummary>,
    /// `None` when the cell has no `optimize`.
    pub optimization: Option<OptimizationSummary>,
    /// The cell's volume fraction and surface-area density in its reference element
    /// (docs/method.md §Surface area), measured on the optimisation's sharp grid.
    pub measures: Measures,
    pub values: Vec<ValueRow>,
}

#[derive(Debug, Serialize)]
pub struct CoefficientRow {
    pub f: Vec<i32>,
    pub re: f64,
    pub im: f64,
    pub k: f64,
}

#[derive(Debug, Serialize)]
pub struct ConstraintRow {
    pub applied: bool,
    pub delta_norm: f64,
    /// `None` when the constraint was not asked for.
    pub max_face_residual: Option<f64>,
}

#[derive(Debug, Serialize)]
pub struct ValueRow {
    pub point: Vec<f64>,
    pub value: f64,
    pub gradient: Vec<f64>,
}

/// Reads points, one per line, `dimension` whitespace-separated numbers each; blank lines and
/// `#` comments are skipped. Errors name the file and line.
pub fn read_points(file: &str, text: &str, dimension: usize) -> Result<Vec<[f64; 3]>, String> {
    let mut points = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let numbers: Result<Vec<f64>, _> = line.split_whitespace().map(str::parse::<f64>).collect();
        match numbers {
            Ok(v) if v.len() == dimension && v.iter().all(|x| x.is_finite()) => {
                points.push(std::array::from_fn(|a| v.get(a).copied().unwrap_or(0.0)));
            }
            _ => {
                return Err(format!(
                    "error: {file}:{}: expected {dimension} finite numbers separated by spaces, found `{line}`\n",
                    i + 1
                ));
            }
        }
    }
    Ok(points)
}

pub fn report(
    name: &str,
    payload: &FittedPayload,
    group: &Group,
    points: &[[f64; 3]],
) -> Result<CellReport, String> {
    let cell = payload.cell(group).map_err(|e| e.to_string())?;
    let d = group.dimension();
    let coefficients = cell
        .coefficients()
        .iter()
        .map(|c| CoefficientRow {
            f: c.f[..d].to_vec(),
            re: c.c.re,
            im: c.c.im,
            k: c.k_f,
        })
        .collect();
    let values = points
        .iter()
        .map(|&p| {
            let (value, gradient) = cell.value_gradient(p);
            ValueRow {
                point: p[..d].to_vec(),
                value,
                gradient: gradient[..d].to_vec(),
            }
        })
        .collect();
    let constraint = match &payload.constraint {
        Some(c) => ConstraintRow {
            applied: c.applied,
            delta_norm: c.delta_norm,
            max_face_residual: Some(c.max_face_residual),
        },
        None => ConstraintRow {
            applied: false,
            delta_norm: 0.0,
            max_face_residual: None,
        },
    };
    let measured = latticebuild_geom::symmetric::measure(&cell).map_err(|e| e.to_string())?;
    Ok(CellReport {
        measures: Measures {
            volume_fraction: measured.volume_fraction,
            surface_area: measured.surface_area,
        },
        name: name.to_string(),
        group: payload.group.clone(),
        n: payload.n,
        extend: payload.extend.clone(),
        coefficients,
        constraint,
        auto: payload.auto.clone(),
        optimization: payload.optimization.clone(),
        values,
    })
}

/// How `n = "auto"` chose N, in the words of its warning when it stopped at `max_n`.
fn auto_line(a: &AutoSummary) -> String {
    if a.converged {
        format!(
            "N = {} chosen automatically: doubling it to {} moves the surface {:.2e} cell units, \
             within the tolerance {:.1e} (max_n {})",
            a.n,
            2 * a.n,
            a.movement,
            a.tolerance,
            a.max_n
        )
    } else {
        format!(
            "N = {} reached max_n: {}",
            a.n,
            a.warning().unwrap_or_default()
        )
    }
}

/// The iterations of `optimize`: volume fraction (and area) and change per iterate, the
/// measures before and after, then the outcome.
fn optimization_table(o: &OptimizationSummary) -> String {
    let mut goals = Vec::new();
    if let Some(t) = o.target {
        goals.push(format!("volume fraction {t:.4} of the reference element"));
    }
    if let Some(a) = &o.surface_area {
        goals.push(format!("surface area {:.4} per element volume", a.target));
    }
    let area_column = o.surface_area.as_ref().map(|a| &a.iterations);
    let mut s = format!(
        "\noptimize: {}\n{:>5}  {:>14}{}  {:>12}  {:>10}\n",
        goals.join(", "),
        "iter",
        "fraction (ε)",
        if area_column.is_some() {
            format!("  {:>12}", "area (ε)")
        } else {
            String::new()
        },
        "‖c − c₀‖",
        "ε"
    );
    for (i, (fraction, change, eps)) in o.iterations.iter().enumerate() {
        let area = match area_column.and_then(|a| a.get(i)) {
            Some(a) => format!("  {a:>12.6}"),
            None => String::new(),
        };
        s.push_str(&format!(
            "{i:>5}  {fraction:>14.6}{area}  {change:>12.4e}  {eps:>10.3e}\n"
        ));
    }
    s.push_str(&format!(
        "reached {:.6} (sharp count), ‖c − c₀‖ = {:.4e}, {}\n",
        o.reached,
        o.change,
        if o.converged {
            "converged"
        } else {
            "NOT converged"
        }
    ));
    if let (Some(b), Some(a)) = (&o.before, &o.after) {
        s.push_str(&format!(
            "before → after: volume fraction {:.6} → {:.6}, surface area {:.6} → {:.6}\n",
            b.volume_fraction, a.volume_fraction, b.surface_area, a.surface_area
        ));
    }
    if let Some(w) = o.warning() {
        s.push_str(&format!("warning: {w}\n"));
    }
    s
}

/// The largest terms first, then the constraint and the values.
pub fn table(report: &CellReport, largest: usize) -> String {
    let mut rows: Vec<&CoefficientRow> = report.coefficients.iter().collect();
    rows.sort_by(|a, b| b.re.hypot(b.im).total_cmp(&a.re.hypot(a.im)));
    let mut s = format!(
        "cell `{}`: group {}, N = {}, extend {}, {} coefficients\n\n{:>16}  {:>14}  {:>14}  {:>12}\n",
        report.name,
        report.group,
        report.n,
        report.extend,
        report.coefficients.len(),
        "f",
        "re",
        "im",
        "K_f"
    );
    if let Some(a) = &report.auto {
        s.insert_str(
            s.find('\n').unwrap_or(s.len()),
            &format!("\n{}", auto_line(a)),
        );
    }
    for row in rows.iter().take(largest) {
        let f: Vec<String> = row.f.iter().map(i32::to_string).collect();
        s.push_str(&format!(
            "{:>16}  {:>14.6e}  {:>14.6e}  {:>12.6e}\n",
            format!("({})", f.join(", ")),
            row.re,
            row.im,
            row.k
        ));
    }
    if rows.len() > largest {
        s.push_str(&format!(
            "{:>16}\n",
            format!("… {} more", rows.len() - largest)
        ));
    }
    match report.constraint.max_face_residual {
        Some(r) => s.push_str(&format!(
            "\nnormal_to_faces: {}, ‖Δc‖ = {:.3e}, max |∇Φ·n| on the faces = {:.3e}\n",
            if report.constraint.applied {
                "applied"
            } else {
                "already held"
            },
            report.constraint.delta_norm,
            r
        )),
        None => s.push_str("\nnormal_to_faces: not asked for\n"),
    }
    s.push_str(&format!(
        "measured: volume fraction {:.6}, surface area {:.6} per element volume\n",
        report.measures.volume_fraction, report.measures.surface_area
    ));
    if let Some(o) = &report.optimization {
        s.push_str(&optimization_table(o));
    }
    for v in &report.values {
        s.push_str(&format!(
            "Φ({:?}) = {:.12e}, ∇Φ = {:?}\n",
            v.point, v.value, v.gradient
        ));
    }
    s
}
