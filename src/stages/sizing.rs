//! Turning a solid sized in the user's terms (`wall`, `grow`, `volume_fraction`) into a field
//! and a solid the contourers take as they are, and the `density` stage: the table `V(level)`
//! of a cell, from which volume fractions are solved.
//!
//! Invariants:
//! - `wall` and `grow` are model units on the distance field `(f − c)/|∇f|`
//!   (`latticebuild_geom::distance`); graded ones divide or shift it point by point
//!   (`latticebuild_geom::graded`): a graded shell is `|h / (W(x)/2)| ≤ 1`, a graded growth
//!   `h − D(x) ≤ 0`.
//! - A uniform volume fraction is solved by bisection on the table (the iterations are
//!   reported); a graded one reads the table's quantile at `φ(x)` directly — the same
//!   piecewise-linear inverse, so the two agree where `φ` is constant.
//! - The table is of the field `f` for `inside`/`outside` (levels in field values) and of
//!   `|h|` for shells (half walls in the units of `scale`): [`DensityStage`] is a pure
//!   function of the cell payload and its parameters, so outputs sharing a cell, a region and
//!   (for shells) a level and scale share one table.
//! - A graded volume fraction outside (0, 1), or a graded wall ≤ 0, anywhere it is probed is
//!   an error giving the point and the value (and the reachable range); between probes a
//!   fraction is clamped into the range and a wall to a billionth of a unit.

use std::sync::Arc;

use latticebuild_geom::density::{self, LevelTable, Region};
use latticebuild_geom::distance::DistanceField;
use latticebuild_geom::expr;
use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::graded::{GradedField, Spatial};
use latticebuild_geom::symmetric::ReferenceElement;
use serde::{Deserialize, Serialize};

use super::StageError;
use super::symmetric::{FittedPayload, group_of};
use crate::cache::{KeyBuilder, Param};
use crate::manifest::{GroupSpec, NodalValue, Sizing, Target};

/// 1: quantiles of 128³ (3D) or 512² (2D) midpoint samples. 2: point distances projected
/// onto the surface, as the tiler evaluates them.
pub const VERSION: u32 = 2;

/// Midpoints per axis of a table's samples.
const TABLE_SAMPLES_3D: usize = 128;
const TABLE_SAMPLES_2D: usize = 512;

/// Where a table's samples are taken, before the cell's group is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Over {
    /// One period of the cell (its group's domain for a fitted cell; `[0, 1)^dimension` for a
    /// formula).
    Period { dimension: usize },
    /// The cell's reference element.
    Element,
}

/// `density`: the table `V(level)` of one cell.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityStage {
    pub fitted: Option<GroupSpec>,
    pub over: Over,
    /// For shells: the level and the model units per cell unit of the distance field whose
    /// `|h|` is tabled; `None`: the field itself.
    pub distance: Option<(f64, [f64; 3])>,
    /// Sample the distance point by point, projected onto the surface, as the tiler does
    /// (`latticebuild_geom::distance`), on a coarser grid; `false`: the grid's first-order
    /// distance, as the box contourers sample it.
    pub projected: bool,
}

/// Midpoints per axis of a table of projected distances (each point costs up to 49
/// evaluations of the cell).
const TABLE_SAMPLES_PROJECTED: usize = 64;

/// A field sampled point by point (its `eval_points`), whatever sampler it has.
struct Pointwise<F>(F);

impl<F: ScalarField> ScalarField for Pointwise<F> {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        self.0.eval_points(xs, ys, zs, out);
    }
}

impl DensityStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        let group = match &self.fitted {
            None => String::new(),
            Some(GroupSpec::Named(name)) => name.clone(),
            Some(GroupSpec::Generators { .. }) => "generators".into(),
        };
        let over = match self.over {
            Over::Period { dimension } => format!("period{dimension}"),
            Over::Element => "element".into(),
        };
        let distance = match self.distance {
            None => Vec::new(),
            Some((level, scale)) => std::iter::once(level)
                .chain(scale)
                .map(Param::F64)
                .collect(),
        };
        key.param("fitted", group.as_str())
            .param("over", over.as_str())
            .param("distance", Param::List(distance))
            .param("projected", self.projected)
    }

    /// The table of the cell whose payload is `cell_payload`, as bytes.
    pub fn run(&self, cell_payload: &[u8]) -> Result<Vec<u8>, StageError> {
        let field = cell_field(cell_payload, self.fitted.as_ref())?;
        let region = match (&self.fitted, self.over) {
            (None, Over::Period { dimension }) => Region::Period {
                frame: latticebuild_geom::symmetric::Frame::Cartesian,
                dimension,
            },
            (None, Over::Element) => {
                return Err(StageError::Internal(
                    "a reference element needs a fitted cell".into(),
                ));
            }
            (Some(spec), over) => {
                let group = group_of(spec)?;
                match (over, group.reference_element()) {
                    (Over::Element, Some(element)) => Region::Element(element),
                    (Over::Element, None) => {
                        return Err(StageError::DoesNotFit(format!(
                            "group {} has no reference element",
                            group.name()
                        )));
                    }
                    (Over::Period { .. }, _) => Region::Period {
                        frame: group.domain().frame(),
                        dimension: group.domain().dimension(),
                    },
                }
            }
        };
        let dimension = match region {
            Region::Period { dimension, .. } => dimension,
            Region::Element(ReferenceElement::Square | ReferenceElement::Triangle) => 2,
            Region::Element(_) => 3,
        };
        let n = if dimension == 2 {
            TABLE_SAMPLES_2D
        } else {
            TABLE_SAMPLES_3D
        };
        let samples = match self.distance {
            None => density::sample(&field, region, n),
            Some((level, scale)) => {
                let distance = DistanceField {
                    inner: field,
                    level,
                    scale,
                };
                let mut values = match self.projected {
                    true => density::sample(&Pointwise(distance), region, TABLE_SAMPLES_PROJECTED),
                    false => density::sample(&distance, region, n),
                };
                for v in &mut values {
                    *v = v.abs();
                }
                values
            }
        };
        let table = LevelTable::from_samples(samples)?;
        Ok(table.to_bytes())
    }
}

/// The field of a cell payload: a formula (or mesh or crystal cell), or a fitted cell.
pub fn cell_field(
    payload: &[u8],
    fitted: Option<&GroupSpec>,
) -> Result<Box<dyn ScalarField>, StageError> {
    match fitted {
        None => super::cell::cell_field(payload),
        Some(spec) => {
            let group = group_of(spec)?;
            Ok(Box::new(FittedPayload::from_bytes(payload)?.cell(&group)?))
        }
    }
}

/// What the report says of a solid sized in the user's terms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SizingSummary {
    /// `wall`, `grow` or `volume_fraction`.
    pub by: String,
    /// The value asked for (model units, or the fraction); `None` when graded.
    pub target: Option<f64>,
    /// For a volume fraction: the level solved (field values, `inside`/`outside`)…
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solved_level: Option<f64>,
    /// …or the wall solved (model units, shells).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solved_wall: Option<f64>,
    /// Bisection steps over the table of a uniform solve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u32>,
}

/// A field and the solid to contour it as.
pub struct SizedField {
    pub field: Box<dyn ScalarField>,
    pub solid: Solid,
    pub summary: Option<SizingSummary>,
}

/// The field and solid for `sizing`: `scale` is model units per cell unit, `table` the
/// cell's table (needed for a volume fraction), `probes` model points where a graded volume
/// fraction is checked to lie in (0, 1).
pub fn sized_field(
    field: Box<dyn ScalarField>,
    solid: Solid,
    sizing: &Sizing,
    scale: [f64; 3],
    table: Option<&LevelTable>,
    probes: &[[f64; 3]],
) -> Result<SizedField, StageError> {
    let shell = solid.band().is_some();
    let distance = |field: Box<dyn ScalarField>, level: f64| -> Box<dyn ScalarField> {
        Box::new(DistanceField {
            inner: field,
            level,
            scale,
        })
    };
    let graded = |inner: Box<dyn ScalarField>, shift: Spatial, divide: Spatial| {
        Box::new(GradedField {
            inner,
            scale,
            shift,
            divide,
        }) as Box<dyn ScalarField>
    };
    match sizing {
        Sizing::Field => Ok(SizedField {
            field,
            solid,
            summary: None,
        }),
        Sizing::Length {
            level,
            graded: amount,
        } => {
            let summary = length_summary(&solid, amount.is_none());
            let h = distance(field, *level);
            let Some(amount) = amount else {
                return Ok(SizedField {
                    field: h,
                    solid,
                    summary: Some(summary),
                });
            };
            let values = expression(amount)?;
            if shell {
                check_range(
                    values.as_ref(),
                    probes,
                    |w| w > 0.0,
                    "wall",
                    "greater than 0",
                )?;
            }
            let (field, solid) = match solid {
                Solid::Inside { .. } => (
                    graded(h, mapped(values, |v| v), Spatial::Constant(1.0)),
                    Solid::Inside { offset: 0.0 },
                ),
                Solid::Outside { .. } => (
                    graded(h, mapped(values, |v| -v), Spatial::Constant(1.0)),
                    Solid::Outside { offset: 0.0 },
                ),
                _ => (
                    graded(h, Spatial::Constant(0.0), mapped(values, |v| 0.5 * v)),
                    Solid::Shell { thickness: 2.0 },
                ),
            };
            Ok(SizedField {
                field,
                solid,
                summary: Some(summary),
            })
        }
        Sizing::VolumeFraction { level, target } => {
            let table = table
                .ok_or_else(|| {
                    StageError::Internal("a volume fraction needs the cell's table".into())
                })?
                .clone();
            match target {
                Target::Uniform(phi) => {
                    let (solid, summary) = solve_uniform(&table, solid, *phi)?;
                    let field = match shell {
                        true => distance(field, *level),
                        false => field,
                    };
                    Ok(SizedField {
                        field,
                        solid,
                        summary: Some(summary),
                    })
                }
                Target::Graded(amount) => {
                    let values = expression(amount)?;
                    check_range(
                        values.as_ref(),
                        probes,
                        |phi| phi > 0.0 && phi < 1.0,
                        "volume fraction",
                        "between 0 and 1 (the reachable range is 0 < volume_fraction < 1)",
                    )?;
                    let lookup = move |phi: f64| table.level_at(tabled_fraction(&solid, phi));
                    let summary = graded_fraction_summary();
                    let (field, solid) = match solid {
                        Solid::Inside { .. } | Solid::Outside { .. } => (
                            graded(field, mapped(values, lookup), Spatial::Constant(1.0)),
                            match solid {
                                Solid::Inside { .. } => Solid::Inside { offset: 0.0 },
                                _ => Solid::Outside { offset: 0.0 },
                            },
                        ),
                        _ => (
                            graded(
                                distance(field, *level),
                                Spatial::Constant(0.0),
                                mapped(values, lookup),
                            ),
                            Solid::Shell { thickness: 2.0 },
                        ),
                    };
                    Ok(SizedField {
                        field,
                        solid,
                        summary: Some(summary),
                    })
                }
            }
        }
    }
}

/// The length a `wall` or `grow` asks for, from the solid it was parsed into (an outside
/// solid's offset is minus its growth: see `manifest::Sizing`).
pub fn asked_length(solid: &Solid) -> f64 {
    match *solid {
        Solid::Shell { thickness } | Solid::EccentricShell { thickness, .. } => thickness,
        Solid::Inside { offset } => offset,
        Solid::Outside { offset } => -offset,
    }
}

/// The summary of a `wall` (shells) or `grow`: its value when uniform.
pub fn length_summary(solid: &Solid, uniform: bool) -> SizingSummary {
    SizingSummary {
        by: if solid.band().is_some() {
            "wall"
        } else {
            "grow"
        }
        .into(),
        target: uniform.then(|| asked_length(solid)),
        solved_level: None,
        solved_wall: None,
        iterations: None,
    }
}

/// The summary of a graded volume fraction (nothing solved once: a level per point).
pub fn graded_fraction_summary() -> SizingSummary {
    SizingSummary {
        by: "volume_fraction".into(),
        target: None,
        solved_level: None,
        solved_wall: None,
        iterations: None,
    }
}

/// The fraction of the tabled quantity below the solved value for a target `phi`: the field
/// for inside (below its level) and outside (above it: `1 − φ` below), `|h|` for shells.
pub fn tabled_fraction(solid: &Solid, phi: f64) -> f64 {
    match solid {
        Solid::Outside { .. } => 1.0 - phi,
        _ => phi,
    }
}

/// A uniform volume fraction solved on the table: the solid at the level found (a shell's
/// wall is twice the `|h|` found, in the table's units) and the summary saying so.
pub fn solve_uniform(
    table: &LevelTable,
    solid: Solid,
    phi: f64,
) -> Result<(Solid, SizingSummary), StageError> {
    let solved = table.level_for(tabled_fraction(&solid, phi))?;
    let mut summary = SizingSummary {
        by: "volume_fraction".into(),
        target: Some(phi),
        solved_level: None,
        solved_wall: None,
        iterations: Some(solved.iterations),
    };
    let solid = match solid {
        Solid::Inside { .. } => Solid::Inside {
            offset: solved.level,
        },
        Solid::Outside { .. } => Solid::Outside {
            offset: solved.level,
        },
        _ => Solid::Shell {
            thickness: 2.0 * solved.level,
        },
    };
    match solid {
        Solid::Shell { thickness } => summary.solved_wall = Some(thickness),
        _ => summary.solved_level = Some(solved.level),
    }
    Ok((solid, summary))
}

/// A graded value's expression, compiled (node data only reaches tiled outputs, which
/// evaluate it at their nodes).
fn expression(value: &NodalValue) -> Result<Arc<dyn ScalarField>, StageError> {
    match value {
        NodalValue::Expr(text) => {
            let compiled = expr::compile(text)?;
            Ok(Arc::new(compiled))
        }
        NodalValue::NodeData(view) => Err(StageError::DoesNotFit(format!(
            "node data `{view}` belongs to a scaffold's nodes, and this output has none"
        ))),
    }
}

fn mapped(
    field: Arc<dyn ScalarField>,
    map: impl Fn(f64) -> f64 + Send + Sync + 'static,
) -> Spatial {
    Spatial::Field {
        field,
        map: Some(Arc::new(map)),
    }
}

/// An error at the first probe where a graded value is not `allowed`.
fn check_range(
    values: &dyn ScalarField,
    probes: &[[f64; 3]],
    allowed: impl Fn(f64) -> bool,
    what: &str,
    range: &str,
) -> Result<(), StageError> {
    let [xs, ys, zs] = std::array::from_fn(|a| probes.iter().map(|p| p[a]).collect::<Vec<_>>());
    let mut out = vec![0.0; probes.len()];
    values.eval_points(&xs, &ys, &zs, &mut out);
    match out.iter().position(|&v| !allowed(v)) {
        None => Ok(()),
        Some(i) => Err(StageError::ValueOutOfRange(format!(
            "the graded {what} is {} at ({}, {}, {}), but it must be {range} everywhere in the \
             domain",
            out[i], probes[i][0], probes[i][1], probes[i][2]
        ))),
    }
}

/// The table in a payload.
pub fn table_of(payload: &[u8]) -> Result<LevelTable, StageError> {
    LevelTable::from_bytes(payload).ok_or_else(|| StageError::malformed("density table"))
}
