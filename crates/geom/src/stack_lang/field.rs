//! [`ProgramField`]: a parsed program with its `file` solids resolved, compiled once, ready to be
//! evaluated at points or sampled on grids by the contourer.
//!
//! Invariants:
//! - Immutable after construction and `Send + Sync`; evaluation is a pure function of the
//!   points, and grid samples a pure function of their indices.
//! - [`ScalarField::eval_points`] evaluates the plan exactly at each point; the grid sampler
//!   may use separable tables (equal to rounding) and may replace the values of tiles whose
//!   sign is proven, which never changes the contoured mesh (see `sampler.rs`).

use std::sync::Arc;

use super::bounds::{Aabb, ExternalBounds, solid_bounds};
use super::compile::{Leaf, Plan, ValueOp};
use super::error::ProgramError;
use super::external::{ExternalField, ExternalSolids};
use super::machine::{self, BLOCK, Stack};
use super::sampler::SdfSampler;
use super::tree::{Op, Tree};
use super::words::Origin;
use crate::field::{Grid, PlaneSampler, ScalarField};

/// A compiled SDF program.
pub struct ProgramField {
    plan: Plan,
    bounds: Aabb,
    pruning: bool,
}

impl ProgramField {
    /// Resolves the `file` words of `tree` through `externals` and compiles it.
    pub fn new(tree: &Tree, externals: &dyn ExternalSolids) -> Result<ProgramField, ProgramError> {
        let nodes = tree.nodes();
        let mut resolved: Vec<Option<Arc<dyn ExternalField>>> = vec![None; nodes.len()];
        for (n, node) in nodes.iter().enumerate() {
            if let Op::File(path) = &node.op {
                let from = match &node.at.origin {
                    Origin::File { file, .. } => Some(&**file),
                    Origin::Arg(_) => None,
                };
                let field =
                    externals
                        .resolve(path, from)
                        .map_err(|message| ProgramError::File {
                            at: node.at.clone(),
                            message,
                        })?;
                resolved[n] = Some(field);
            }
        }
        let field_of = |n: usize| -> Arc<dyn ExternalField> {
            resolved[n]
                .clone()
                .expect("every file node was resolved above")
        };
        let bounds = solid_bounds(tree, &|n| {
            let f = field_of(n);
            ExternalBounds {
                bounds: f.bounds(),
                is_distance: f.is_distance(),
            }
        });
        Ok(ProgramField {
            plan: Plan::new(tree, &field_of),
            bounds,
            pruning: true,
        })
    }

    /// A box containing the solid `{f ≤ 0}`; infinite where the reasoning finds no bound.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The box to contour when none is given: the bounds, with the paper's box rule for
    /// unbounded sides (see `bounds.rs`).
    pub fn domain(&self) -> Aabb {
        self.bounds.box_rule()
    }

    /// Turns the skipping of provably empty or full tiles on or off (on by default). The mesh
    /// is the same either way; this exists to measure and test that.
    pub fn set_pruning(&mut self, on: bool) {
        self.pruning = on;
    }

    /// The value at one point.
    pub fn eval(&self, p: [f64; 3]) -> f64 {
        let mut out = [0.0];
        self.eval_points(&[p[0]], &[p[1]], &[p[2]], &mut out);
        out[0]
    }

    /// Number of leaves and value operations of the compiled plan.
    pub fn plan_size(&self) -> (usize, usize) {
        (self.plan.leaves.len(), self.plan.ops.len())
    }
}

impl ScalarField for ProgramField {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let len = out.len();
        assert!(
            xs.len() == len && ys.len() == len && zs.len() == len,
            "eval_points needs equally long slices"
        );
        let mut stack = Stack::new(&self.plan);
        let mut mapped: [Vec<f64>; 3] = Default::default();
        let mut start = 0;
        while start < len {
            let n = (len - start).min(BLOCK);
            let (x, y, z) = (
                &xs[start..start + n],
                &ys[start..start + n],
                &zs[start..start + n],
            );
            let values =
                machine::run(&self.plan, None, n, &mut stack, |l, dst| {
                    match &self.plan.leaves[l] {
                        Leaf::Formula(expr) => expr.eval_points(x, y, z, dst),
                        Leaf::External { field, map } => {
                            for (a, m) in mapped.iter_mut().enumerate() {
                                let row = map.m[a];
                                m.clear();
                                m.extend((0..n).map(|i| {
                                    row[0] * x[i] + row[1] * y[i] + row[2] * z[i] + map.t[a]
                                }));
                            }
                            field.eval_points(&mapped[0], &mapped[1], &mapped[2], dst);
                        }
                    }
                });
            out[start..start + n].copy_from_slice(values);
            start += n;
        }
    }

    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        // A lone separable formula (`tpms.gyroid`, `tpms.p scale 2`) costs a few multiply-adds
        // per sample, less than proving tiles empty: it takes the expression's own sampler.
        if let ([ValueOp::Leaf(0)], [Leaf::Formula(expr)]) =
            (self.plan.ops.as_slice(), self.plan.leaves.as_slice())
            && expr.is_separable()
        {
            return expr.sampler(grid);
        }
        Box::new(SdfSampler::new(&self.plan, grid, self.pruning))
    }
}
