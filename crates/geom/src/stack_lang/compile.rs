//! Compiling a tree into a flat plan: leaves in world coordinates and a post-order list of
//! value operations for a stack machine.
//!
//! Point transformations (move, scale, rotate, orient) are affine, so the transformations on
//! the path from the root to a leaf compose into one map, which is substituted into the
//! leaf's formula: every leaf but `file` becomes one expression in world x, y, z
//! (`crate::expr`), compiled once, with the separable fast path wherever the transformed
//! formula has one (axis-aligned scalings and moves of TPMS keep theirs; a rotated TPMS
//! usually gains a longer one through the angle-addition formulas). What remains above the
//! leaves acts on values only: `a·v + c` (complement, offset, isotropic scale, merged when
//! consecutive), the sign-dependent factor of eq. 4, `|v| − h` (shell), min, max,
//! `max(a, −b)` (difference) and the sigmoid blend `a + w·(b − a)`, whose weight `w` is a
//! formula leaf of its own pushed after its two operands.
//!
//! Invariants:
//! - The plan computes the tree's function: each leaf is the leaf's formula at the composed
//!   point map, and the value operations are the tree's value semantics in post-order.
//! - `subtree_start[i]` is the first operation of the subtree ending at operation `i` (its
//!   operations are contiguous in post-order), so an operation's last operand is the subtree
//!   ending at `i − 1` and each earlier one the subtree ending just before the next starts.

use std::sync::Arc;

use super::affine::Affine;
use super::blend;
use super::external::ExternalField;
use super::tree::{Op, Tree};
use crate::expr::{BinOp, CompiledExpr, Expr, Func, Var};

/// A leaf of the plan.
pub(crate) enum Leaf {
    /// A formula in world coordinates.
    Formula(CompiledExpr),
    /// A field provided by the caller, evaluated at `map(world point)`.
    External {
        field: Arc<dyn ExternalField>,
        map: Affine,
    },
}

/// One operation of the stack machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum ValueOp {
    /// Push the value of a leaf.
    Leaf(usize),
    /// `v ← mul·v + add`
    Affine {
        mul: f64,
        add: f64,
    },
    /// `v ← above·v` where `v ≥ 0`, `below·v` where `v < 0` (eq. 4 as `min_i |κ_i| v`).
    SignScale {
        above: f64,
        below: f64,
    },
    /// `v ← |v| − half`
    Shell {
        half: f64,
    },
    Min,
    Max,
    /// `max(a, −b)`
    Difference,
    /// `a + w·(b − a)` of the three values on top, `w` the last (`blend.rs`).
    Blend,
}

impl ValueOp {
    pub fn arity(&self) -> usize {
        match self {
            ValueOp::Leaf(_) => 0,
            ValueOp::Min | ValueOp::Max | ValueOp::Difference => 2,
            ValueOp::Blend => 3,
            _ => 1,
        }
    }
}

pub(crate) struct Plan {
    pub leaves: Vec<Leaf>,
    pub ops: Vec<ValueOp>,
    pub subtree_start: Vec<usize>,
    /// Deepest the value stack gets.
    pub depth: usize,
}

impl Plan {
    /// Compiles `tree`; `external(node index)` gives the resolved field of a `file` node.
    pub fn new(tree: &Tree, external: &dyn Fn(usize) -> Arc<dyn ExternalField>) -> Plan {
        let nodes = tree.nodes();
        // Parents before children: the map from world coordinates to each node's own.
        let mut maps = vec![Affine::IDENTITY; nodes.len()];
        for n in (0..nodes.len()).rev() {
            let node = &nodes[n];
            let own = match &node.op {
                Op::Move(d) => Some(Affine::translation(d.map(|v| -v))),
                Op::Scale(k) => Some(Affine::diagonal([1.0 / k; 3])),
                Op::ScaleAxes(k) => Some(Affine::diagonal(k.map(|v| 1.0 / v))),
                Op::Rotate { axis, angle } => Some(Affine::rotation(*axis, *angle)),
                Op::Orient(v) => Some(Affine::turning_z_to(*v).transpose_linear()),
                _ => None,
            };
            let child_map = match own {
                Some(t) => t.after(&maps[n]),
                None => maps[n],
            };
            for &c in &node.children[..node.op.arity()] {
                maps[c] = child_map;
            }
        }

        let mut plan = Plan {
            leaves: Vec::new(),
            ops: Vec::new(),
            subtree_start: Vec::new(),
            depth: 0,
        };
        for (n, node) in nodes.iter().enumerate() {
            let formula = |e: Expr| {
                let world = substitute(&e, &affine_forms(&maps[n]));
                Some(Leaf::Formula(CompiledExpr::from_expr(&world)))
            };
            let leaf = match &node.op {
                Op::Ball => formula(ball()),
                Op::Cylinder => formula(cylinder()),
                Op::Box => formula(unit_box()),
                Op::Tpms(s) => {
                    formula(crate::expr::parse(s.formula).expect("library formulas parse"))
                }
                Op::Expression { expr, .. } => formula(expr.clone()),
                Op::File(_) => Some(Leaf::External {
                    field: external(n),
                    map: maps[n],
                }),
                _ => None,
            };
            if let Some(leaf) = leaf {
                plan.leaves.push(leaf);
                plan.push(ValueOp::Leaf(plan.leaves.len() - 1));
                continue;
            }
            let op = match &node.op {
                Op::Complement => ValueOp::Affine {
                    mul: -1.0,
                    add: 0.0,
                },
                Op::Offset(xi) => ValueOp::Affine { mul: 1.0, add: -xi },
                Op::Scale(k) => ValueOp::Affine {
                    mul: k.abs(),
                    add: 0.0,
                },
                Op::ScaleAxes(k) => {
                    let k = k.map(f64::abs);
                    ValueOp::SignScale {
                        above: k[0].min(k[1]).min(k[2]),
                        below: k[0].max(k[1]).max(k[2]),
                    }
                }
                Op::Shell(th) => ValueOp::Shell { half: th / 2.0 },
                Op::Union => ValueOp::Min,
                Op::Intersection => ValueOp::Max,
                Op::Difference => ValueOp::Difference,
                Op::SigmoidBlend {
                    direction,
                    x0,
                    width,
                } => {
                    let w = blend::weight(&maps[n], *direction, *x0, *width);
                    plan.leaves.push(Leaf::Formula(CompiledExpr::from_expr(&w)));
                    plan.push(ValueOp::Leaf(plan.leaves.len() - 1));
                    ValueOp::Blend
                }
                // Point transformations are already in the leaves' maps.
                _ => continue,
            };
            plan.push(op);
        }
        // A leaf adds a value to the stack, a binary operation takes one away.
        let mut stack = 0usize;
        for op in &plan.ops {
            stack = stack + 1 - op.arity();
            plan.depth = plan.depth.max(stack);
        }
        plan
    }

    /// Appends `op`, merging consecutive affine value maps.
    fn push(&mut self, op: ValueOp) {
        if let (ValueOp::Affine { mul, add }, Some(ValueOp::Affine { mul: m0, add: a0 })) =
            (op, self.ops.last().copied())
        {
            // mul·(m0·v + a0) + add
            let last = self.ops.len() - 1;
            self.ops[last] = ValueOp::Affine {
                mul: mul * m0,
                add: mul * a0 + add,
            };
            return;
        }
        // Each operand's subtree ends just before the next one's starts.
        let mut start = self.ops.len();
        for _ in 0..op.arity() {
            start = self.subtree_start[start - 1];
        }
        self.ops.push(op);
        self.subtree_start.push(start);
    }
}

/// `sqrt(x² + y² + z²) − 1`
fn ball() -> Expr {
    let sq = |v: Var| Expr::binary(BinOp::Pow, Expr::Var(v), Expr::Num(2.0));
    let sum = Expr::binary(
        BinOp::Add,
        Expr::binary(BinOp::Add, sq(Var::X), sq(Var::Y)),
        sq(Var::Z),
    );
    Expr::binary(BinOp::Sub, Expr::call(Func::Sqrt, sum), Expr::Num(1.0))
}

/// `sqrt(x² + y²) − 1`
fn cylinder() -> Expr {
    let sq = |v: Var| Expr::binary(BinOp::Pow, Expr::Var(v), Expr::Num(2.0));
    let sum = Expr::binary(BinOp::Add, sq(Var::X), sq(Var::Y));
    Expr::binary(BinOp::Sub, Expr::call(Func::Sqrt, sum), Expr::Num(1.0))
}

/// The exact distance to the box of half-width 1: with `q = |p| − 1`,
/// `|max(q, 0)| + min(max(q_x, q_y, q_z), 0)`.
fn unit_box() -> Expr {
    let q = |v: Var| {
        Expr::binary(
            BinOp::Sub,
            Expr::call(Func::Abs, Expr::Var(v)),
            Expr::Num(1.0),
        )
    };
    let pos_sq = |v: Var| {
        Expr::binary(
            BinOp::Pow,
            Expr::binary(BinOp::Max, q(v), Expr::Num(0.0)),
            Expr::Num(2.0),
        )
    };
    let outside = Expr::call(
        Func::Sqrt,
        Expr::binary(
            BinOp::Add,
            Expr::binary(BinOp::Add, pos_sq(Var::X), pos_sq(Var::Y)),
            pos_sq(Var::Z),
        ),
    );
    let largest = Expr::binary(
        BinOp::Max,
        Expr::binary(BinOp::Max, q(Var::X), q(Var::Y)),
        q(Var::Z),
    );
    let inside = Expr::binary(BinOp::Min, largest, Expr::Num(0.0));
    Expr::binary(BinOp::Add, outside, inside)
}

/// The three coordinates of `map(x, y, z)` as expressions, without zero terms, unit
/// coefficients or zero offsets, so that an identity map leaves a formula exactly as it was.
fn affine_forms(map: &Affine) -> [Expr; 3] {
    std::array::from_fn(|i| {
        let mut form: Option<Expr> = None;
        for (j, var) in Var::ALL.into_iter().enumerate() {
            let c = map.m[i][j];
            if c == 0.0 {
                continue;
            }
            let term = if c == 1.0 {
                Expr::Var(var)
            } else {
                Expr::binary(BinOp::Mul, Expr::Num(c), Expr::Var(var))
            };
            form = Some(match form {
                None => term,
                Some(f) => Expr::binary(BinOp::Add, f, term),
            });
        }
        let t = map.t[i];
        match form {
            None => Expr::Num(t),
            Some(f) if t == 0.0 => f,
            Some(f) => Expr::binary(BinOp::Add, f, Expr::Num(t)),
        }
    })
}

/// `e` with each variable replaced by its form.
fn substitute(e: &Expr, forms: &[Expr; 3]) -> Expr {
    match e {
        Expr::Num(_) => e.clone(),
        Expr::Var(v) => forms[v.index()].clone(),
        Expr::Neg(a) => Expr::Neg(Box::new(substitute(a, forms))),
        Expr::Call(f, a) => Expr::call(*f, substitute(a, forms)),
        Expr::Binary(op, a, b) => Expr::binary(*op, substitute(a, forms), substitute(b, forms)),
    }
}
