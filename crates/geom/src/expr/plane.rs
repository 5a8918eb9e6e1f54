//! Sampling a separable form on a grid from per-axis tables.
//!
//! Plane `k` is `Σ_a X_a[i] · W_a[j]` with `W_a[j] = Σ_{t: X_t = a} c_t · Y_t[j] · Z_t[k]`,
//! where `a` runs over the distinct x factors (and "no x factor", which gives a row offset).
//! Every 1-D factor is sampled once per grid, so a sample costs one multiply-add per distinct
//! x factor and no transcendental function at all.
//!
//! Invariants:
//! - Planes are pure functions of `k`: the tables are fixed when the sampler is built and
//!   every sum is accumulated in the same fixed order, so any thread, at any time, gets the
//!   same bits for the same plane.
//! - The tables are sampled at exactly [`Grid::coord`], the coordinates the pointwise sampler
//!   uses, so the two differ only by the rounding of the expanded form.

use std::ops::Range;

use super::program::Program;
use super::separable::SeparableForm;
use crate::field::{Grid, PlaneSampler};

/// Terms sharing one x factor (or none), reduced to what a plane needs.
struct Group {
    /// Index into `x_tables`; `None` means the factor 1.
    x: Option<usize>,
    /// `(c, y table, z table)` for each term of the group.
    terms: Vec<(f64, Option<usize>, Option<usize>)>,
}

pub(crate) struct SeparableSampler {
    grid: Grid,
    x_tables: Vec<Vec<f64>>,
    y_tables: Vec<Vec<f64>>,
    z_tables: Vec<Vec<f64>>,
    /// The group without an x factor, if any, is first.
    groups: Vec<Group>,
}

impl SeparableSampler {
    pub fn new(form: &SeparableForm, grid: &Grid) -> SeparableSampler {
        let tables = |axis: usize| -> Vec<Vec<f64>> {
            let coords = grid.axis(axis);
            let zeros = vec![0.0; coords.len()];
            form.factors[axis]
                .iter()
                .map(|factor| {
                    let mut inputs = [zeros.as_slice(); 3];
                    inputs[axis] = &coords;
                    let mut out = vec![0.0; coords.len()];
                    Program::new(factor).eval(inputs[0], inputs[1], inputs[2], &mut out);
                    out
                })
                .collect()
        };
        let mut groups: Vec<Group> = Vec::new();
        for t in &form.terms {
            let pos = match groups.iter().position(|g| g.x == t.f[0]) {
                Some(pos) => pos,
                None => {
                    groups.push(Group {
                        x: t.f[0],
                        terms: Vec::new(),
                    });
                    groups.len() - 1
                }
            };
            groups[pos].terms.push((t.c, t.f[1], t.f[2]));
        }
        groups.sort_by_key(|g| g.x.is_some());
        SeparableSampler {
            grid: *grid,
            x_tables: tables(0),
            y_tables: tables(1),
            z_tables: tables(2),
            groups,
        }
    }
}

impl PlaneSampler for SeparableSampler {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        let ny = rows.len();
        assert_eq!(out.len(), nx * ny, "row buffer must hold nx * rows samples");

        // W_a[j] for every group a, over the requested rows.
        let mut w = vec![0.0; self.groups.len() * ny];
        for (group, wg) in self.groups.iter().zip(w.chunks_exact_mut(ny.max(1))) {
            for &(c, y, z) in &group.terms {
                let cz = match z {
                    Some(z) => c * self.z_tables[z][k],
                    None => c,
                };
                match y {
                    Some(y) => {
                        for (w, &yv) in wg.iter_mut().zip(&self.y_tables[y][rows.clone()]) {
                            *w += cz * yv;
                        }
                    }
                    None => wg.iter_mut().for_each(|w| *w += cz),
                }
            }
        }

        let (offset, scaled) = match self.groups.first() {
            Some(g) if g.x.is_none() => (Some(&w[..ny]), &self.groups[1..]),
            _ => (None, &self.groups[..]),
        };
        let first_scaled = self.groups.len() - scaled.len();
        let x_of = |g: &Group| g.x.map_or(&[][..], |x| self.x_tables[x].as_slice());
        for (j, row) in out.chunks_exact_mut(nx.max(1)).enumerate() {
            let base = offset.map_or(0.0, |o| o[j]);
            let weight = |g: usize| w[(first_scaled + g) * ny + j];
            if scaled.is_empty() {
                row.fill(base);
            }
            // Up to four groups per pass over the row: the row is read and written once per
            // pass, so fewer passes means fewer loads and stores per multiply-add.
            for (c, chunk) in scaled.chunks(4).enumerate() {
                let init = (c == 0).then_some(base);
                let g0 = 4 * c;
                match chunk {
                    [a] => fused(row, init, [x_of(a)], [weight(g0)]),
                    [a, b] => fused(row, init, [x_of(a), x_of(b)], [weight(g0), weight(g0 + 1)]),
                    [a, b, d] => fused(
                        row,
                        init,
                        [x_of(a), x_of(b), x_of(d)],
                        [weight(g0), weight(g0 + 1), weight(g0 + 2)],
                    ),
                    [a, b, d, e] => fused(
                        row,
                        init,
                        [x_of(a), x_of(b), x_of(d), x_of(e)],
                        [weight(g0), weight(g0 + 1), weight(g0 + 2), weight(g0 + 3)],
                    ),
                    _ => {}
                }
            }
        }
    }
}

/// `row[i] = (init or row[i]) + Σ_g xs[g][i] · ws[g]`, summed left to right. The order is
/// fixed by the group order alone, so chunking never changes a bit of the result.
#[inline(always)]
fn fused<const N: usize>(row: &mut [f64], init: Option<f64>, xs: [&[f64]; N], ws: [f64; N]) {
    let len = row.len();
    // Equal lengths let the compiler drop the bounds checks and vectorise the loop.
    let xs = xs.map(|x| &x[..len]);
    match init {
        Some(base) => {
            for (i, o) in row.iter_mut().enumerate() {
                let mut acc = base;
                for g in 0..N {
                    acc += xs[g][i] * ws[g];
                }
                *o = acc;
            }
        }
        None => {
            for (i, o) in row.iter_mut().enumerate() {
                let mut acc = *o;
                for g in 0..N {
                    acc += xs[g][i] * ws[g];
                }
                *o = acc;
            }
        }
    }
}
