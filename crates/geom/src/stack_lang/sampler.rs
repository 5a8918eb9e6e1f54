//! Sampling a compiled SDF on a grid, tile by tile, skipping what provably does not matter.
//!
//! A plane is cut into tiles of [`TILE_X`] × [`TILE_Y`] samples, aligned to the grid (not to
//! the rows a caller asks for). For each tile the leaves are bounded by intervals over the
//! tile *grown by one sample in every direction, including the planes above and below*, and
//! the plan is evaluated on those intervals (`machine::intervals`):
//!
//! ```text
//!     k+1  . . . . . .        The box of samples the interval covers: the tile (#) and
//!     k    . # # # # .        its one-sample margin (.), in x, y and on planes k ± 1.
//!     k−1  . . . . . .        If the whole box has one sign, no edge from a tile sample
//! ```                         can cross the surface, so the tile's values are never
//!                             interpolated and a constant of that sign replaces them.
//!
//! Otherwise the tile is computed, skipping operands of min/max that cannot win in it, which
//! leaves every value bit-identical. So pruning changes no sign and no interpolated vertex:
//! the mesh is the same with and without it (a test checks this). The proof is sound for any
//! field, distance or not: it bounds the values that are actually sampled.
//!
//! Order of work for a call: per band of tile rows, decide every tile of the band (the
//! separable leaves' y and z factors are bounded once per band); then per row, evaluate each
//! pointwise or external leaf in one batch over the columns of the computed tiles that need
//! it, and run each computed tile's row segment through the stack machine.
//!
//! Leaf intervals: a separable leaf (a TPMS, possibly scaled or moved) is bounded from its
//! per-axis factor tables, by the smallest and largest table entry over the tile's index
//! range, so the bound is about the very samples; other formulas by interval arithmetic over
//! the tile's box; a `file` field by its value at the box centre ± half the box diagonal when
//! it is a true distance, and not at all otherwise.
//!
//! Invariants:
//! - Every sample is a pure function of its grid indices: tiles are fixed by the grid, sums
//!   are taken in a fixed order, and a tile's decision depends only on the tile.
//! - Memory per call is a row of values per pointwise leaf and a block per stack slot; tables
//!   are one row per factor per axis, made when the sampler is.

use std::ops::Range;

use super::affine::Affine;
use super::compile::{Leaf, Plan, ValueOp};
use super::external::ExternalField;
use super::interval::{Interval, eval_expr};
use super::machine::{self, BLOCK, Stack, Step};
use crate::expr::CompiledExpr;
use crate::field::{Grid, PlaneSampler, ScalarField};

/// Tile width (samples along x); at most the machine's block.
pub const TILE_X: usize = 32;
/// Tile height (samples along y). 32 × 8 measured best for the Figure 6 command at 400³
/// among 16–64 × 4–16.
pub const TILE_Y: usize = 8;
const _: () = assert!(TILE_X <= BLOCK, "a tile row is one block of the machine");

pub(crate) struct SdfSampler<'a> {
    plan: &'a Plan,
    grid: Grid,
    coords: [Vec<f64>; 3],
    leaves: Vec<LeafSampler<'a>>,
    /// The index of each leaf's operation in the plan.
    leaf_ops: Vec<usize>,
    pruning: bool,
}

enum LeafSampler<'a> {
    Separable(Box<SeparableTiles>),
    Pointwise(&'a CompiledExpr),
    External {
        field: &'a dyn ExternalField,
        map: Affine,
    },
}

/// A separable leaf `Σ_t c_t X_t(x) Y_t(y) Z_t(z)` sampled from per-axis tables.
struct SeparableTiles {
    /// `tables[axis][factor][index]`
    tables: [Vec<Vec<f64>>; 3],
    /// Terms as `(c, [x, y, z] factor or None for 1)`.
    terms: Vec<(f64, [Option<usize>; 3])>,
    /// Terms grouped by x factor, the group without one first.
    groups: Vec<(Option<usize>, Vec<usize>)>,
    /// `x_ranges[column tile][factor]`, `y_ranges[row tile][factor]`: table intervals over the
    /// tile and its margin.
    x_ranges: Vec<Vec<Interval>>,
    y_ranges: Vec<Vec<Interval>>,
}

/// What a tile needs.
#[derive(Clone, Copy)]
enum Decision {
    /// Every sample of the tile and its margin has this value's sign.
    Fill(f64),
    /// Compute the tile; `steps` is where its steps start in the band's list when it skips
    /// work.
    Compute { steps: Option<usize> },
}

impl<'a> SdfSampler<'a> {
    pub fn new(plan: &'a Plan, grid: &Grid, pruning: bool) -> SdfSampler<'a> {
        let coords = [grid.axis(0), grid.axis(1), grid.axis(2)];
        let leaves = plan
            .leaves
            .iter()
            .map(|leaf| match leaf {
                Leaf::Formula(expr) => match expr.separable_form() {
                    Some(_) => LeafSampler::Separable(Box::new(SeparableTiles::new(expr, &coords))),
                    None => LeafSampler::Pointwise(expr),
                },
                Leaf::External { field, map } => LeafSampler::External {
                    field: field.as_ref(),
                    map: *map,
                },
            })
            .collect();
        let mut leaf_ops = vec![0; plan.leaves.len()];
        for (i, op) in plan.ops.iter().enumerate() {
            if let ValueOp::Leaf(l) = op {
                leaf_ops[*l] = i;
            }
        }
        SdfSampler {
            plan,
            grid: *grid,
            coords,
            leaves,
            leaf_ops,
            pruning,
        }
    }
}

/// Index range of tile `t` of size `size` along an axis of `n` samples.
fn tile(t: usize, size: usize, n: usize) -> Range<usize> {
    t * size..((t + 1) * size).min(n)
}

/// The tile's index range grown by the one-sample margin, as an inclusive range.
fn with_margin(r: &Range<usize>, n: usize) -> (usize, usize) {
    (r.start.saturating_sub(1), r.end.min(n - 1))
}

/// The smallest and largest of `values` (exact: no widening), flagging NaN.
fn range_of(values: &[f64]) -> Interval {
    let mut r = Interval {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
        nan: false,
    };
    for &v in values {
        if v.is_nan() {
            r.nan = true;
        } else {
            r.lo = r.lo.min(v);
            r.hi = r.hi.max(v);
        }
    }
    if r.nan { Interval::UNKNOWN } else { r }
}

impl SeparableTiles {
    fn new(expr: &CompiledExpr, coords: &[Vec<f64>; 3]) -> SeparableTiles {
        let form = expr
            .separable_form()
            .expect("only separable leaves get tables");
        let tables: [Vec<Vec<f64>>; 3] = std::array::from_fn(|axis| {
            let n = coords[axis].len();
            let zeros = vec![0.0; n];
            form.factors[axis]
                .iter()
                .map(|factor| {
                    let mut inputs = [zeros.as_slice(); 3];
                    inputs[axis] = &coords[axis];
                    let mut out = vec![0.0; n];
                    CompiledExpr::from_expr(factor)
                        .eval_points(inputs[0], inputs[1], inputs[2], &mut out);
                    out
                })
                .collect()
        });
        let terms: Vec<(f64, [Option<usize>; 3])> = form.terms.iter().map(|t| (t.c, t.f)).collect();
        let mut groups: Vec<(Option<usize>, Vec<usize>)> = Vec::new();
        for (i, t) in terms.iter().enumerate() {
            match groups.iter_mut().find(|g| g.0 == t.1[0]) {
                Some(g) => g.1.push(i),
                None => groups.push((t.1[0], vec![i])),
            }
        }
        groups.sort_by_key(|g| g.0.is_some());
        let ranges = |axis: usize, size: usize| -> Vec<Vec<Interval>> {
            let n = coords[axis].len();
            (0..n.div_ceil(size))
                .map(|t| {
                    let (lo, hi) = with_margin(&tile(t, size, n), n);
                    tables[axis].iter().map(|f| range_of(&f[lo..=hi])).collect()
                })
                .collect()
        };
        SeparableTiles {
            x_ranges: ranges(0, TILE_X),
            y_ranges: ranges(1, TILE_Y),
            tables,
            terms,
            groups,
        }
    }

    /// `z_ranges[factor]` for plane `k` and its neighbours.
    fn z_ranges(&self, k: usize) -> Vec<Interval> {
        let n = self.tables[2].first().map_or(1, Vec::len);
        let (lo, hi) = with_margin(&(k..k + 1), n);
        self.tables[2]
            .iter()
            .map(|f| range_of(&f[lo..=hi]))
            .collect()
    }

    /// The interval of each group's weight `Σ c · Y · Z` over row tile `ty` and plane `k`
    /// (with margins): shared by every tile of the band.
    fn band_weights(&self, ty: usize, z: &[Interval], out: &mut Vec<Interval>) {
        out.clear();
        for (_, members) in &self.groups {
            let mut w = Interval::point(0.0);
            for &t in members {
                let (c, f) = self.terms[t];
                let mut v = Interval::point(c);
                if let Some(y) = f[1] {
                    v = v.mul(self.y_ranges[ty][y]);
                }
                if let Some(zf) = f[2] {
                    v = v.mul(z[zf]);
                }
                w = w.add(v);
            }
            out.push(w);
        }
    }

    /// The interval of the leaf over column tile `tx`, from its band's weights.
    fn interval(&self, tx: usize, weights: &[Interval]) -> Interval {
        let mut sum = Interval::point(0.0);
        for ((x, _), w) in self.groups.iter().zip(weights) {
            sum = sum.add(match x {
                None => *w,
                Some(x) => self.x_ranges[tx][*x].mul(*w),
            });
        }
        sum
    }

    /// Each group's weight `Σ c · Y[j] · Z[k]` for row `j` of plane `k`, summed in term order.
    fn row_weights(&self, j: usize, k: usize, out: &mut Vec<f64>) {
        out.clear();
        for (_, members) in &self.groups {
            let mut w = 0.0;
            for &t in members {
                let (c, f) = self.terms[t];
                let mut v = c;
                if let Some(y) = f[1] {
                    v *= self.tables[1][y][j];
                }
                if let Some(z) = f[2] {
                    v *= self.tables[2][z][k];
                }
                w += v;
            }
            out.push(w);
        }
    }

    /// Values on columns `cols` of the row whose weights are `weights`: the group without an
    /// x factor first, then `X[i] · w` for each group in order.
    fn fill(&self, weights: &[f64], cols: Range<usize>, out: &mut [f64]) {
        let mut first = true;
        for ((x, _), &w) in self.groups.iter().zip(weights) {
            match (x, first) {
                (None, _) => out.fill(w),
                (Some(x), true) => {
                    let xs = &self.tables[0][*x][cols.clone()];
                    for (o, &xv) in out.iter_mut().zip(xs) {
                        *o = xv * w;
                    }
                }
                (Some(x), false) => {
                    let xs = &self.tables[0][*x][cols.clone()];
                    for (o, &xv) in out.iter_mut().zip(xs) {
                        *o += xv * w;
                    }
                }
            }
            first = false;
        }
        if first {
            out.fill(0.0);
        }
    }
}

/// Scratch of one `sample_rows` call.
struct Scratch {
    stack: Stack,
    leaf_intervals: Vec<Interval>,
    op_intervals: Vec<Interval>,
    /// Per leaf: the band's group weight intervals (separable leaves), then the row's weights.
    band_weights: Vec<Vec<Interval>>,
    row_weights: Vec<Vec<f64>>,
    /// The steps of the tile being decided.
    tile_steps: Vec<Step>,
    /// Per pointwise or external leaf: its values on the current row, where computed tiles
    /// need them (one batched evaluation per row).
    row_values: Vec<Vec<f64>>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
    values: Vec<f64>,
    mapped: [Vec<f64>; 3],
}

impl SdfSampler<'_> {
    /// The grid box of the tile and its margin, in world coordinates.
    fn world_box(&self, cols: &Range<usize>, rows: &Range<usize>, k: usize) -> [Interval; 3] {
        let n = self.grid.counts;
        let ranges = [
            with_margin(cols, n[0]),
            with_margin(rows, n[1]),
            with_margin(&(k..k + 1), n[2]),
        ];
        std::array::from_fn(|a| {
            let (lo, hi) = (self.coords[a][ranges[a].0], self.coords[a][ranges[a].1]);
            Interval::new(lo.min(hi), lo.max(hi))
        })
    }

    /// Decides tile `tx` of band `ty` on plane `k`; the steps of a tile that skips work are
    /// left in `scratch.tile_steps`.
    fn decide(&self, tx: usize, ty: usize, k: usize, scratch: &mut Scratch) -> Decision {
        let n = self.grid.counts;
        let cols = tile(tx, TILE_X, n[0]);
        let rows = tile(ty, TILE_Y, n[1]);
        let mut world = None;
        scratch.leaf_intervals.clear();
        for (l, leaf) in self.leaves.iter().enumerate() {
            let mut world_box = || *world.get_or_insert_with(|| self.world_box(&cols, &rows, k));
            let interval = match leaf {
                LeafSampler::Separable(s) => s.interval(tx, &scratch.band_weights[l]),
                LeafSampler::Pointwise(expr) => eval_expr(expr.expr(), &world_box()),
                LeafSampler::External { field, map } => {
                    external_interval(*field, map, &world_box())
                }
            };
            scratch.leaf_intervals.push(interval);
        }
        machine::intervals(
            self.plan,
            &scratch.leaf_intervals,
            &mut scratch.op_intervals,
        );
        let root = scratch.op_intervals[scratch.op_intervals.len() - 1];
        if root.proves_outside() {
            return Decision::Fill(root.lo);
        }
        if root.proves_inside() {
            return Decision::Fill(root.hi);
        }
        let skips = machine::plan_steps(self.plan, &scratch.op_intervals, &mut scratch.tile_steps);
        Decision::Compute {
            steps: skips.then_some(0),
        }
    }

    /// Evaluates the pointwise and external leaves on row `j` of plane `k`, in one batch per
    /// leaf over the columns of the computed tiles that need it, into `scratch.row_values`.
    fn batch_leaves(
        &self,
        k: usize,
        j: usize,
        decisions: &[Decision],
        band_steps: &[Step],
        scratch: &mut Scratch,
    ) {
        let nx = self.grid.counts[0];
        let ops = self.plan.ops.len();
        let Scratch {
            row_values,
            xs,
            ys,
            zs,
            values,
            mapped,
            ..
        } = scratch;
        for (l, leaf) in self.leaves.iter().enumerate() {
            if matches!(leaf, LeafSampler::Separable(_)) {
                continue;
            }
            let needs = |d: &Decision| match *d {
                Decision::Fill(_) => false,
                Decision::Compute { steps: None } => true,
                Decision::Compute { steps: Some(at) } => {
                    band_steps[at..at + ops][self.leaf_ops[l]] != Step::Skip
                }
            };
            xs.clear();
            for (tx, d) in decisions.iter().enumerate() {
                if needs(d) {
                    xs.extend_from_slice(&self.coords[0][tile(tx, TILE_X, nx)]);
                }
            }
            if xs.is_empty() {
                continue;
            }
            let n = xs.len();
            ys.clear();
            ys.resize(n, self.coords[1][j]);
            zs.clear();
            zs.resize(n, self.coords[2][k]);
            values.clear();
            values.resize(n, 0.0);
            match leaf {
                LeafSampler::Pointwise(expr) => expr.eval_points(xs, ys, zs, values),
                LeafSampler::External { field, map } => {
                    for (a, m) in mapped.iter_mut().enumerate() {
                        let row = map.m[a];
                        m.clear();
                        m.extend(
                            (0..n).map(|i| {
                                row[0] * xs[i] + row[1] * ys[i] + row[2] * zs[i] + map.t[a]
                            }),
                        );
                    }
                    field.eval_points(&mapped[0], &mapped[1], &mapped[2], values);
                }
                LeafSampler::Separable(_) => unreachable!("skipped above"),
            }
            let row = &mut row_values[l];
            row.resize(nx, 0.0);
            let mut at = 0;
            for (tx, d) in decisions.iter().enumerate() {
                if needs(d) {
                    let cols = tile(tx, TILE_X, nx);
                    let len = cols.len();
                    row[cols].copy_from_slice(&values[at..at + len]);
                    at += len;
                }
            }
        }
    }

    /// Computes columns `cols` of the current row into `out`.
    fn compute(
        &self,
        cols: Range<usize>,
        steps: Option<&[Step]>,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) {
        let Scratch {
            stack,
            row_weights,
            row_values,
            ..
        } = scratch;
        let leaf = |l: usize, dst: &mut [f64]| match &self.leaves[l] {
            LeafSampler::Separable(s) => s.fill(&row_weights[l], cols.clone(), dst),
            _ => dst.copy_from_slice(&row_values[l][cols.clone()]),
        };
        if let [ValueOp::Leaf(l)] = self.plan.ops.as_slice() {
            // A lone leaf writes straight into the output.
            leaf(*l, out);
            return;
        }
        let values = machine::run(self.plan, steps, cols.len(), stack, leaf);
        out.copy_from_slice(values);
    }
}

/// Bounds of a caller's field over a world box: by its value at the centre of the mapped box
/// when it is 1-Lipschitz, otherwise none.
fn external_interval(field: &dyn ExternalField, map: &Affine, world: &[Interval; 3]) -> Interval {
    if !field.is_distance() {
        return Interval::UNKNOWN;
    }
    let b = super::bounds::Aabb {
        min: world.map(|i| i.lo),
        max: world.map(|i| i.hi),
    };
    let local = map.image(&b);
    let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * (local.min[a] + local.max[a]));
    let half_diagonal = 0.5
        * (0..3)
            .map(|a| (local.max[a] - local.min[a]).powi(2))
            .sum::<f64>()
            .sqrt();
    let mut v = [0.0];
    field.eval_points(&[centre[0]], &[centre[1]], &[centre[2]], &mut v);
    if !v[0].is_finite() || !half_diagonal.is_finite() {
        return Interval::UNKNOWN;
    }
    Interval::new(v[0] - half_diagonal, v[0] + half_diagonal)
}

impl PlaneSampler for SdfSampler<'_> {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let [nx, ny, _] = self.grid.counts;
        assert_eq!(
            out.len(),
            nx * rows.len(),
            "row buffer must hold nx * rows samples"
        );
        if rows.is_empty() || nx == 0 {
            return;
        }
        let ops = self.plan.ops.len();
        let leaves = self.leaves.len();
        let mut scratch = Scratch {
            stack: Stack::new(self.plan),
            leaf_intervals: Vec::with_capacity(leaves),
            op_intervals: Vec::with_capacity(ops),
            band_weights: vec![Vec::new(); leaves],
            row_weights: vec![Vec::new(); leaves],
            tile_steps: Vec::with_capacity(ops),
            row_values: vec![Vec::new(); leaves],
            xs: Vec::new(),
            ys: Vec::new(),
            zs: Vec::new(),
            values: Vec::new(),
            mapped: Default::default(),
        };
        let z_ranges: Vec<Vec<Interval>> = self
            .leaves
            .iter()
            .map(|leaf| match leaf {
                LeafSampler::Separable(s) if self.pruning => s.z_ranges(k),
                _ => Vec::new(),
            })
            .collect();
        let tiles_x = nx.div_ceil(TILE_X);
        // Per column tile of a band: what to do, and the steps of the tiles that skip work.
        let mut decisions: Vec<Decision> = Vec::with_capacity(tiles_x);
        let mut band_steps: Vec<Step> = Vec::new();
        for ty in rows.start / TILE_Y..rows.end.div_ceil(TILE_Y) {
            let band = tile(ty, TILE_Y, ny);
            decisions.clear();
            band_steps.clear();
            if self.pruning {
                for (l, leaf) in self.leaves.iter().enumerate() {
                    if let LeafSampler::Separable(s) = leaf {
                        s.band_weights(ty, &z_ranges[l], &mut scratch.band_weights[l]);
                    }
                }
                for tx in 0..tiles_x {
                    let mut decision = self.decide(tx, ty, k, &mut scratch);
                    if let Decision::Compute { steps: Some(_) } = decision {
                        decision = Decision::Compute {
                            steps: Some(band_steps.len()),
                        };
                        band_steps.extend_from_slice(&scratch.tile_steps);
                    }
                    decisions.push(decision);
                }
            } else {
                decisions.resize(tiles_x, Decision::Compute { steps: None });
            }
            for j in band.start.max(rows.start)..band.end.min(rows.end) {
                let row = &mut out[(j - rows.start) * nx..(j - rows.start + 1) * nx];
                for (l, leaf) in self.leaves.iter().enumerate() {
                    if let LeafSampler::Separable(s) = leaf {
                        s.row_weights(j, k, &mut scratch.row_weights[l]);
                    }
                }
                self.batch_leaves(k, j, &decisions, &band_steps, &mut scratch);
                for (tx, decision) in decisions.iter().enumerate() {
                    let cols = tile(tx, TILE_X, nx);
                    match *decision {
                        Decision::Fill(v) => row[cols].fill(v),
                        Decision::Compute { steps } => {
                            let steps = steps.map(|at| &band_steps[at..at + ops]);
                            let dst = &mut row[cols.clone()];
                            self.compute(cols, steps, &mut scratch, dst);
                        }
                    }
                }
            }
        }
    }
}
