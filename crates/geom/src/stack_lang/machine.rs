//! The stack machine that runs a plan's value operations over a block of points, and the same
//! operations over intervals.
//!
//! Invariants:
//! - Every operation is one tight loop over the block (at most [`BLOCK`] values), with no
//!   allocation and no branch on the operation inside the loop, so the loops vectorize.
//! - [`Step`]s only ever skip work whose result is provably not used: an operand of a min or
//!   max that cannot win anywhere in the block (a blend needs all its operands). With every
//!   step [`Step::Run`] the machine computes the plan exactly; with skips it computes
//!   bit-identical values.
//! - The interval evaluation follows the same operations and encloses every value the block
//!   can produce (see `interval.rs`).

use super::blend;
use super::compile::{Plan, ValueOp};
use super::interval::Interval;

/// Points per pass over the operations.
pub const BLOCK: usize = 256;

/// What to do with one operation for one block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Not needed: the operation's value is never used.
    Skip,
    /// Computed as usual.
    Run,
    /// A binary operation whose result is its left operand (the right one was skipped).
    Left,
    /// A binary operation whose result is its right operand (max and min), or its negation
    /// (difference).
    Right,
}

/// Value buffers for the machine's stack, reused across blocks.
pub struct Stack {
    data: Vec<f64>,
}

impl Stack {
    pub fn new(plan: &Plan) -> Stack {
        Stack {
            data: vec![0.0; plan.depth.max(1) * BLOCK],
        }
    }
}

/// Runs `plan` over a block of `n` points. `leaf(index, out)` writes a leaf's values;
/// `steps` (one per operation) may skip work, `None` runs everything. Returns the values.
pub fn run<'s>(
    plan: &Plan,
    steps: Option<&[Step]>,
    n: usize,
    stack: &'s mut Stack,
    mut leaf: impl FnMut(usize, &mut [f64]),
) -> &'s [f64] {
    debug_assert!(n <= BLOCK);
    let mut top = 0usize; // number of values on the stack
    for (i, op) in plan.ops.iter().enumerate() {
        let step = steps.map_or(Step::Run, |s| s[i]);
        if step == Step::Skip {
            continue;
        }
        match *op {
            ValueOp::Leaf(l) => {
                leaf(l, &mut stack.data[top * BLOCK..top * BLOCK + n]);
                top += 1;
            }
            ValueOp::Affine { mul, add } => {
                for v in slot(stack, top - 1, n) {
                    *v = *v * mul + add;
                }
            }
            ValueOp::SignScale { above, below } => {
                for v in slot(stack, top - 1, n) {
                    *v *= if *v >= 0.0 { above } else { below };
                }
            }
            ValueOp::Shell { half } => {
                for v in slot(stack, top - 1, n) {
                    *v = v.abs() - half;
                }
            }
            ValueOp::Blend => {
                let (lower, upper) = stack.data.split_at_mut((top - 2) * BLOCK);
                let a = &mut lower[(top - 3) * BLOCK..(top - 3) * BLOCK + n];
                let (b, w) = upper.split_at(BLOCK);
                for ((u, &v), &t) in a.iter_mut().zip(&b[..n]).zip(&w[..n]) {
                    *u = blend::value(*u, v, t);
                }
                top -= 2;
            }
            ValueOp::Min | ValueOp::Max | ValueOp::Difference => match step {
                Step::Left => {}
                Step::Right => {
                    if *op == ValueOp::Difference {
                        for v in slot(stack, top - 1, n) {
                            *v = -*v;
                        }
                    }
                }
                _ => {
                    let (lower, upper) = stack.data.split_at_mut((top - 1) * BLOCK);
                    let a = &mut lower[(top - 2) * BLOCK..(top - 2) * BLOCK + n];
                    let b = &upper[..n];
                    match op {
                        ValueOp::Min => a.iter_mut().zip(b).for_each(|(u, &v)| *u = u.min(v)),
                        ValueOp::Max => a.iter_mut().zip(b).for_each(|(u, &v)| *u = u.max(v)),
                        _ => a.iter_mut().zip(b).for_each(|(u, &v)| *u = u.max(-v)),
                    }
                    top -= 1;
                }
            },
        }
    }
    &stack.data[..n]
}

fn slot(stack: &mut Stack, index: usize, n: usize) -> &mut [f64] {
    &mut stack.data[index * BLOCK..index * BLOCK + n]
}

/// The interval of every operation's value, given the intervals of the leaves. Operands are
/// read from `out` itself: a unary operation's is the one before it, a binary operation's
/// right operand ends before it and its left operand ends where the right one starts.
pub fn intervals(plan: &Plan, leaves: &[Interval], out: &mut Vec<Interval>) {
    out.clear();
    for (i, op) in plan.ops.iter().enumerate() {
        let value = match *op {
            ValueOp::Leaf(l) => leaves[l],
            ValueOp::Affine { mul, add } => out[i - 1].scale(mul).add(Interval::point(add)),
            ValueOp::SignScale { above, below } => {
                // Increasing in v, so the ends map to the ends.
                let v = out[i - 1];
                let f = |x: f64| x * if x >= 0.0 { above } else { below };
                let mut r = Interval::new(f(v.lo), f(v.hi));
                r.nan = v.nan;
                r
            }
            ValueOp::Shell { half } => out[i - 1].abs().sub(Interval::point(half)),
            ValueOp::Blend => {
                let w = out[i - 1];
                let b_end = plan.subtree_start[i - 1] - 1;
                let a = out[plan.subtree_start[b_end] - 1];
                blend::interval(a, out[b_end], w)
            }
            ValueOp::Min | ValueOp::Max | ValueOp::Difference => {
                let b = out[i - 1];
                let a = out[plan.subtree_start[i - 1] - 1];
                match op {
                    ValueOp::Min => a.min(b),
                    ValueOp::Max => a.max(b),
                    _ => a.max(b.neg()),
                }
            }
        };
        out.push(value);
    }
}

/// Which operations a block needs, given every operation's interval: an operand of a min or
/// max is skipped when the other operand is smaller (larger) everywhere, strictly, and
/// neither may be NaN. Returns false when nothing can be skipped.
pub fn plan_steps(plan: &Plan, values: &[Interval], steps: &mut Vec<Step>) -> bool {
    let count = plan.ops.len();
    steps.clear();
    steps.resize(count, Step::Skip);
    steps[count - 1] = Step::Run;
    let mut skipped = false;
    for i in (0..count).rev() {
        if steps[i] == Step::Skip {
            continue;
        }
        let op = plan.ops[i];
        match op.arity() {
            0 => {}
            1 => steps[i - 1] = Step::Run,
            3 => {
                // A blend needs all three operands everywhere.
                let mut end = i - 1;
                for _ in 0..3 {
                    steps[end] = Step::Run;
                    end = plan.subtree_start[end].wrapping_sub(1);
                }
            }
            _ => {
                let right = i - 1;
                let left = plan.subtree_start[right] - 1;
                let (a, b) = (values[left], values[right]);
                let b = if op == ValueOp::Difference {
                    b.neg()
                } else {
                    b
                };
                let sure = !a.nan && !b.nan;
                let (keep_left, keep_right) = match op {
                    ValueOp::Max if sure && a.lo > b.hi => (true, false),
                    ValueOp::Max if sure && b.lo > a.hi => (false, true),
                    ValueOp::Difference if sure && a.lo > b.hi => (true, false),
                    ValueOp::Difference if sure && b.lo > a.hi => (false, true),
                    ValueOp::Min if sure && a.hi < b.lo => (true, false),
                    ValueOp::Min if sure && b.hi < a.lo => (false, true),
                    _ => (true, true),
                };
                steps[i] = match (keep_left, keep_right) {
                    (true, false) => Step::Left,
                    (false, true) => Step::Right,
                    _ => Step::Run,
                };
                skipped |= steps[i] != Step::Run;
                if keep_left {
                    steps[left] = Step::Run;
                }
                if keep_right {
                    steps[right] = Step::Run;
                }
            }
        }
    }
    skipped
}
