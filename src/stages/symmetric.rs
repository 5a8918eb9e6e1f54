//! The stages of symmetric Fourier cells (docs/method.md §Overview): `sample` → `fit` →
//! `constrain`, and the
//! combinations `blend` and `minkowski`.
//!
//! Payloads: `sample` stores the raw samples (`LBSAMP01`, N and dimension, then `N^d` f64);
//! every other stage stores a [`FittedPayload`] as JSON, whose floats serde_json writes in
//! shortest round-trip form, so a coefficient table reloads bit for bit.
//!
//! Invariants: the group in a payload is the one the manifest asked for; coefficients are
//! representatives of their orbits inside the band of `n` (checked again on load by
//! `FittedCell::from_coefficients`).

use serde::{Deserialize, Serialize};

use latticebuild_geom::symmetric::{
    self, Complex64, Extend, FitOptions, FittedCell, Group, OptimizationTargets, SampleOptions,
    Side, check_surface, fit_samples, minkowski_difference, minkowski_sum, weighted_average,
};

use super::StageError;
use crate::cache::{KeyBuilder, Param};
use crate::manifest::{FitResolution, GroupSpec, MinkowskiOp, Symmetric};

pub const VERSION: u32 = 5;

const SAMPLES_MAGIC: &[u8; 8] = b"LBSAMP01";

/// The group of a manifest's group spec.
pub fn group_of(spec: &GroupSpec) -> Result<Group, StageError> {
    match spec {
        GroupSpec::Named(name) => Ok(Group::by_name(name)?),
        GroupSpec::Generators {
            dimension,
            generators,
        } => Ok(Group::from_generators(*dimension, generators)?),
    }
}

fn group_param(spec: &GroupSpec) -> Param {
    match spec {
        GroupSpec::Named(name) => Param::Str(name.clone()),
        GroupSpec::Generators {
            dimension,
            generators,
        } => {
            let mut items = vec![Param::U64(*dimension as u64)];
            items.extend(
                generators
                    .iter()
                    .flatten()
                    .flatten()
                    .map(|&v| Param::I64(i64::from(v))),
            );
            Param::List(items)
        }
    }
}

fn sample_options(spec: &Symmetric) -> SampleOptions {
    SampleOptions {
        extend: if spec.mirror {
            Extend::Mirror
        } else {
            Extend::None
        },
        symmetrize: spec.symmetrize,
    }
}

/// What `constrain` did, for `latticebuild cell` and the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConstraintSummary {
    pub applied: bool,
    pub delta_norm: f64,
    pub max_face_residual: f64,
}

/// What `optimize` did (docs/method.md §Coefficient optimisation), for `latticebuild cell`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OptimizationSummary {
    /// The volume-fraction target; `None` for a surface area alone.
    #[serde(default)]
    pub target: Option<f64>,
    /// The sharp volume fraction of the reference element reached.
    pub reached: f64,
    pub converged: bool,
    /// Not converged because the residual stopped shrinking (the target is out of reach from
    /// this cell), not because `max_iterations` ran out. Absent when false, so other payloads
    /// keep their bytes.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stalled: bool,
    /// `‖c − c₀‖`: the L² change of the field.
    pub change: f64,
    /// Per iterate (0: the cell before): the smoothed volume fraction, `‖c − c₀‖` and the
    /// smoothing half-width (cell units).
    pub iterations: Vec<(f64, f64, f64)>,
    /// With a `surface_area` target: the target, what was reached (sharp) and the smoothed
    /// area per iterate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_area: Option<AreaSummary>,
    /// The sharp measures of the cell before and after (docs/method.md §Surface area).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub before: Option<Measures>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub after: Option<Measures>,
}

/// A surface-area target and what became of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AreaSummary {
    pub target: f64,
    pub reached: f64,
    /// The smoothed area density per iterate.
    pub iterations: Vec<f64>,
}

/// A cell's volume fraction and surface-area density in its reference element.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measures {
    pub volume_fraction: f64,
    pub surface_area: f64,
}

impl OptimizationSummary {
    /// The warning for a run that did not converge, with what it reached.
    pub fn warning(&self) -> Option<String> {
        (!self.converged).then(|| {
            let mut missed = Vec::new();
            if let Some(target) = self.target {
                missed.push(format!(
                    "the volume fraction reached is {:.4}, not {:.4}",
                    self.reached, target
                ));
            }
            if let Some(a) = &self.surface_area {
                missed.push(format!(
                    "the surface area reached is {:.4}, not {:.4}",
                    a.reached, a.target
                ));
            }
            let steps = self.iterations.len().saturating_sub(1);
            if self.stalled {
                format!(
                    "optimize did not reach its target: it stopped after {steps} iterations \
                     without progress, so the target is out of reach from this cell: {}; the \
                     last cell is used",
                    missed.join(", and ")
                )
            } else {
                format!(
                    "optimize did not converge in {steps} iterations: {}; raise \
                     `max_iterations` or loosen `tolerance`",
                    missed.join(", and ")
                )
            }
        })
    }
}

/// A fitted cell as stored in the cache.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FittedPayload {
    /// Canonical group name, or `generators` for a group given by generators.
    pub group: String,
    pub n: usize,
    /// Whether D3/Td cells were extended by mirroring (reported by `latticebuild cell`).
    pub extend: String,
    /// `[fx, fy, fz, re, im]` per representative frequency, sorted by frequency.
    pub coefficients: Vec<(i32, i32, i32, f64, f64)>,
    pub constraint: Option<ConstraintSummary>,
    /// With `n = "auto"`: how N was chosen (absent otherwise, so fixed-N payloads keep their
    /// bytes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auto: Option<AutoSummary>,
    /// Absent unless the cell has `optimize`, so other payloads keep their bytes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimization: Option<OptimizationSummary>,
}

/// How `n = "auto"` chose N: the movement of the surface from `n` to `2n` (or from
/// `max_n / 2` to `max_n` when the tolerance was not met by `max_n`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AutoSummary {
    pub n: usize,
    pub movement: f64,
    pub tolerance: f64,
    pub max_n: usize,
    pub converged: bool,
}

impl AutoSummary {
    /// The report's warning when the tolerance was not met, naming both numbers.
    pub fn warning(&self) -> Option<String> {
        (!self.converged).then(|| {
            format!(
                "automatic N stopped at max_n = {}: the fitted surface still moved {:.2e} cell \
                 units from N = {} to N = {}, above the tolerance {:.1e}; the fit at N = {} is \
                 used (raise `max_n` or loosen `tolerance` to meet it)",
                self.max_n,
                self.movement,
                self.max_n / 2,
                self.max_n,
                self.tolerance,
                self.max_n
            )
        })
    }
}

impl FittedPayload {
    pub fn new(cell: &FittedCell, spec: &Symmetric, constraint: Option<ConstraintSummary>) -> Self {
        FittedPayload {
            group: cell.group().name().to_string(),
            n: cell.n(),
            extend: if spec.mirror { "mirror" } else { "none" }.to_string(),
            coefficients: cell
                .coefficients()
                .iter()
                .map(|c| (c.f[0], c.f[1], c.f[2], c.c.re, c.c.im))
                .collect(),
            constraint,
            auto: None,
            optimization: None,
        }
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).expect("fitted payload serializes")
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<FittedPayload, StageError> {
        serde_json::from_slice(bytes).map_err(|e| StageError::Malformed {
            payload: "fitted cell",
            detail: Some(e.to_string()),
        })
    }

    /// The cell, rebuilt on `group` (which the payload's coefficients were fitted with).
    pub fn cell(&self, group: &Group) -> Result<FittedCell, StageError> {
        FittedCell::from_coefficients(
            group.clone(),
            self.n,
            self.coefficients
                .iter()
                .map(|&(a, b, c, re, im)| ([a, b, c], Complex64::new(re, im))),
        )
        .map_err(StageError::from)
    }
}

/// `sample`: the source evaluated on the `N^d` grid of the group's sampling domain.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleStage {
    pub spec: Symmetric,
    pub n: usize,
}

impl SampleStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        key.param("group", group_param(&self.spec.group))
            .param("n", self.n as u64)
            .param("mirror", self.spec.mirror)
            .param("symmetrize", self.spec.symmetrize)
    }

    pub fn run(&self, formula: &[u8]) -> Result<Vec<u8>, StageError> {
        let group = group_of(&self.spec.group)?;
        let field = super::cell::cell_field(formula)?;
        let samples = symmetric::sample(&group, self.n, &field, sample_options(&self.spec))?;
        let (min, max) = samples
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if min >= 0.0 || max <= 0.0 {
            let side = if max <= 0.0 {
                Side::Inside
            } else {
                Side::Outside
            };
            return Err(symmetric::FitError::EmptyInput { side }.into());
        }
        let mut out = Vec::with_capacity(24 + samples.len() * 8);
        out.extend_from_slice(SAMPLES_MAGIC);
        out.extend_from_slice(&(self.n as u64).to_le_bytes());
        out.extend_from_slice(&(group.dimension() as u64).to_le_bytes());
        out.extend_from_slice(bytemuck::cast_slice(&samples));
        Ok(out)
    }
}

fn decode_samples(payload: &[u8]) -> Result<(usize, Vec<f64>), StageError> {
    let bad = || StageError::malformed("samples");
    if payload.get(..8) != Some(SAMPLES_MAGIC.as_slice())
        || payload.len() < 24
        || !(payload.len() - 24).is_multiple_of(8)
    {
        return Err(bad());
    }
    let n = u64::from_le_bytes(payload[8..16].try_into().map_err(|_| bad())?) as usize;
    Ok((n, bytemuck::pod_collect_to_vec(&payload[24..])))
}

/// `fit`: coefficients from the samples (fixed N) or from the source (`n = "auto"`).
#[derive(Clone, Debug, PartialEq)]
pub struct FitStage {
    pub spec: Symmetric,
}

impl FitStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        let key = key.param("group", group_param(&self.spec.group));
        match self.spec.n {
            FitResolution::Fixed(n) => key.param("n", n as u64),
            FitResolution::Auto { tolerance, max_n } => key
                .param("tolerance", tolerance)
                .param("max_n", max_n as u64)
                .param("mirror", self.spec.mirror)
                .param("symmetrize", self.spec.symmetrize),
        }
    }

    /// Whether the input is the sample payload (fixed N) or the cell's formula (auto N).
    pub fn reads_samples(&self) -> bool {
        matches!(self.spec.n, FitResolution::Fixed(_))
    }

    pub fn run(&self, input: &[u8]) -> Result<Vec<u8>, StageError> {
        let group = group_of(&self.spec.group)?;
        match self.spec.n {
            FitResolution::Fixed(_) => {
                let (n, samples) = decode_samples(input)?;
                let scale = samples.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let cell = fit_samples(&group, n, &samples)?;
                check_surface(&cell, scale)?;
                Ok(FittedPayload::new(&cell, &self.spec, None).to_bytes())
            }
            FitResolution::Auto { tolerance, max_n } => {
                let field = super::cell::cell_field(input)?;
                let options = FitOptions {
                    sample: sample_options(&self.spec),
                    check_vanishing: true,
                };
                // Not meeting the tolerance by `max_n` is the report's warning, not an error:
                // the finest fit is the best there is, and the user chose the bound.
                let found = symmetric::fit_auto(&group, &field, &options, tolerance, max_n)?;
                let mut payload = FittedPayload::new(&found.cell, &self.spec, None);
                payload.auto = Some(AutoSummary {
                    n: found.n,
                    movement: found.movement,
                    tolerance,
                    max_n,
                    converged: found.converged,
                });
                Ok(payload.to_bytes())
            }
        }
    }
}

/// `blend` and `minkowski`: combinations of fitted cells of one group.
#[derive(Clone, Debug, PartialEq)]
pub struct CombineStage {
    pub spec: Symmetric,
    pub combination: Combination,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Combination {
    Blend { weights: Vec<f64> },
    Minkowski { op: MinkowskiOp, n: usize },
}

impl CombineStage {
    pub fn kind(&self) -> &'static str {
        match self.combination {
            Combination::Blend { .. } => "blend",
            Combination::Minkowski { .. } => "minkowski",
        }
    }

    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        let key = key.param("group", group_param(&self.spec.group));
        match &self.combination {
            Combination::Blend { weights } => key.param(
                "weights",
                Param::List(weights.iter().map(|&w| Param::F64(w)).collect()),
            ),
            Combination::Minkowski { op, n } => key
                .param(
                    "op",
                    if *op == MinkowskiOp::Sum {
                        "sum"
                    } else {
                        "difference"
                    },
                )
                .param("n", *n as u64),
        }
    }

    pub fn run(&self, inputs: &[&[u8]]) -> Result<Vec<u8>, StageError> {
        let group = group_of(&self.spec.group)?;
        let cells: Vec<FittedCell> = inputs
            .iter()
            .map(|bytes| FittedPayload::from_bytes(bytes)?.cell(&group))
            .collect::<Result<_, _>>()?;
        let combined = match &self.combination {
            Combination::Blend { weights } => {
                let pairs: Vec<(&FittedCell, f64)> =
                    cells.iter().zip(weights.iter().copied()).collect();
                weighted_average(&pairs)
            }
            Combination::Minkowski {
                op: MinkowskiOp::Sum,
                n,
            } => minkowski_sum(&cells[0], &cells[1], *n),
            Combination::Minkowski {
                op: MinkowskiOp::Difference,
                n,
            } => minkowski_difference(&cells[0], &cells[1], *n),
        }?;
        Ok(FittedPayload::new(&combined, &self.spec, None).to_bytes())
    }
}

/// `constrain`: the face-normal condition (docs/method.md §Face-normal condition), then offset,
/// inversion and the coefficient optimisation (docs/method.md §Coefficient optimisation).
#[derive(Clone, Debug, PartialEq)]
pub struct ConstrainStage {
    pub spec: Symmetric,
}

impl ConstrainStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        key.param("group", group_param(&self.spec.group))
            .param("normal_to_faces", self.spec.normal_to_faces)
            .param("offset", self.spec.offset)
            .param("invert", self.spec.invert)
            .param(
                "optimize",
                Param::List(match self.spec.optimize {
                    None => Vec::new(),
                    Some(o) => vec![
                        Param::F64(o.volume_fraction.unwrap_or(-1.0)),
                        Param::F64(o.surface_area.unwrap_or(-1.0)),
                        Param::U64(o.max_iterations as u64),
                        Param::F64(o.tolerance),
                    ],
                }),
            )
    }

    pub fn run(&self, input: &[u8]) -> Result<Vec<u8>, StageError> {
        let group = group_of(&self.spec.group)?;
        let fitted = FittedPayload::from_bytes(input)?;
        let mut cell = fitted.cell(&group)?;
        let constraint = if self.spec.normal_to_faces {
            let (constrained, report) = cell.constrain_normal_to_faces()?;
            cell = constrained;
            Some(ConstraintSummary {
                applied: report.applied,
                delta_norm: report.delta_norm,
                max_face_residual: report.max_face_residual,
            })
        } else {
            None
        };
        // Dilation grows the solid {Φ ≤ 0}: Φ − offset.
        if self.spec.offset != 0.0 {
            cell = cell.offset(-self.spec.offset);
        }
        if self.spec.invert {
            cell = cell.negated();
        }
        let mut optimization = None;
        if let Some(o) = self.spec.optimize {
            let (optimized, report) = cell.optimize_for(&OptimizationTargets {
                volume_fraction: o.volume_fraction,
                surface_area: o.surface_area,
                keep_face_normal: self.spec.normal_to_faces,
                max_iterations: o.max_iterations,
                tolerance: o.tolerance,
            })?;
            cell = optimized;
            optimization = Some(OptimizationSummary {
                target: report.target,
                reached: report.reached,
                converged: report.converged,
                stalled: report.stalled,
                change: report.change,
                iterations: report
                    .iterates
                    .iter()
                    .map(|i| (i.volume_fraction, i.change, i.smoothing))
                    .collect(),
                surface_area: report.area_target.map(|target| AreaSummary {
                    target,
                    reached: report.area_reached,
                    iterations: report.iterates.iter().map(|i| i.surface_area).collect(),
                }),
                before: Some(Measures {
                    volume_fraction: report.before.volume_fraction,
                    surface_area: report.before.surface_area,
                }),
                after: Some(Measures {
                    volume_fraction: report.reached,
                    surface_area: report.area_reached,
                }),
            });
        }
        let mut payload = FittedPayload::new(&cell, &self.spec, constraint);
        payload.optimization = optimization;
        // How N was chosen stays with the cell, for `latticebuild cell`.
        payload.auto = fitted.auto;
        Ok(payload.to_bytes())
    }
}
