//! Bounds of a solid by interval reasoning over its tree, and the paper's box rule for what
//! cannot be bounded.
//!
//! A solid is `{f ≤ 0}`. Offsets, shells and complements move the level that matters, so the
//! reasoning asks, for each node, for a box containing one of its level sets: the *sublevel*
//! set `{f ≤ t}` or the *superlevel* set `{f ≥ t}`, with the level `t` carried down from the
//! root (which asks for `{f ≤ 0}`). Value transformations change the question (offset ξ:
//! `{f − ξ ≤ t} = {f ≤ t + ξ}`; complement swaps sub- and superlevel; a shell asks its child
//! for both), point transformations map the child's box back (`move δ` shifts it by δ, `scale
//! k` multiplies it by k, `rotate` and `orient` take the box of its turned corners), union
//! takes the union of the boxes of its operands' sublevel sets and intersection their
//! intersection (and the other way round for superlevel sets); a sigmoid blend, lying between
//! its operands' values, takes the union of their boxes for either level set.
//!
//! Leaves: the ball's `{f ≤ t}` is the ball of radius `1 + t` (empty below −1), the box's the
//! box of half-width `1 + t`, the cylinder's is unbounded along z; the superlevel sets of
//! primitives, and every level set of TPMS and expressions, are unbounded. A `file` solid has
//! the bounds its resolver reports, grown by `t` when its field is a true distance.
//!
//! The box rule (paper §4.2): Cesogen "maps −∞ to −1 and ∞ to 1", so an unbounded solid is
//! contoured in `[-1, 1]³`, the box of `box`. An axis bounded on one side only, `[a, ∞)`,
//! becomes `[a, max(1, a + 2)]` (and `(−∞, b]` becomes `[min(−1, b − 2), b]`), so the domain
//! is never inverted; an empty solid gets `[-1, 1]³`.
//!
//! Invariants: every box returned contains the level set asked for (it may be larger); the
//! walk is two passes over the post-order array, never recursive.

use super::affine::Affine;
use super::tree::{Op, Tree};

/// An axis-aligned box, possibly unbounded (infinite sides) or empty (`min > max` on an axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl Aabb {
    pub const EVERYTHING: Aabb = Aabb {
        min: [f64::NEG_INFINITY; 3],
        max: [f64::INFINITY; 3],
    };
    pub const EMPTY: Aabb = Aabb {
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
    };

    /// The cube `[-h, h]³` (empty for negative `h`).
    pub fn cube(h: f64) -> Aabb {
        if h < 0.0 {
            Aabb::EMPTY
        } else {
            Aabb {
                min: [-h; 3],
                max: [h; 3],
            }
        }
    }

    pub fn is_empty(&self) -> bool {
        // NaN sides count as empty too.
        (0..3).any(|a| {
            self.min[a]
                .partial_cmp(&self.max[a])
                .is_none_or(|o| o.is_gt())
        })
    }

    /// Finite on every side.
    pub fn is_bounded(&self) -> bool {
        self.min.iter().chain(&self.max).all(|v| v.is_finite())
    }

    pub fn union(&self, other: &Aabb) -> Aabb {
        match (self.is_empty(), other.is_empty()) {
            (true, _) => *other,
            (_, true) => *self,
            _ => Aabb {
                min: std::array::from_fn(|a| self.min[a].min(other.min[a])),
                max: std::array::from_fn(|a| self.max[a].max(other.max[a])),
            },
        }
    }

    pub fn intersection(&self, other: &Aabb) -> Aabb {
        let b = Aabb {
            min: std::array::from_fn(|a| self.min[a].max(other.min[a])),
            max: std::array::from_fn(|a| self.max[a].min(other.max[a])),
        };
        if b.is_empty() { Aabb::EMPTY } else { b }
    }

    /// The box grown by `d` on every side (shrunk for negative `d`, possibly to empty).
    pub fn grown(&self, d: f64) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        let b = Aabb {
            min: self.min.map(|v| v - d),
            max: self.max.map(|v| v + d),
        };
        if b.is_empty() { Aabb::EMPTY } else { b }
    }

    pub fn volume(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        (0..3).map(|a| self.max[a] - self.min[a]).product()
    }

    /// The domain to contour for a solid with these bounds: the box rule of the module doc.
    pub fn box_rule(&self) -> Aabb {
        if self.is_empty() {
            return Aabb::cube(1.0);
        }
        let mut b = *self;
        for a in 0..3 {
            let (lo, hi) = (self.min[a], self.max[a]);
            (b.min[a], b.max[a]) = match (lo.is_finite(), hi.is_finite()) {
                (true, true) => (lo, hi),
                (false, false) => (-1.0, 1.0),
                (true, false) => (lo, 1f64.max(lo + 2.0)),
                (false, true) => ((-1f64).min(hi - 2.0), hi),
            };
        }
        b
    }
}

/// Which level set of a node's field is asked for.
#[derive(Clone, Copy, Debug)]
enum Level {
    /// `{f ≤ t}`
    Below(f64),
    /// `{f ≥ t}`
    Above(f64),
}

/// Most level sets one node is asked about before the reasoning gives up on it.
const MAX_QUESTIONS: usize = 16;

/// What the caller knows of a `file` solid: its bounds, and whether its field is a true
/// distance (so that `{f ≤ t}` is the bounds grown by `t`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExternalBounds {
    pub bounds: Aabb,
    pub is_distance: bool,
}

/// A box containing the solid `{f ≤ 0}` of the tree; `file` leaves are described by
/// `external(node index)`.
pub fn solid_bounds(tree: &Tree, external: &dyn Fn(usize) -> ExternalBounds) -> Aabb {
    let nodes = tree.nodes();
    // Pass 1, parents before children: the questions each node is asked. A shell asks its
    // child two, so nested shells multiply them; past MAX_QUESTIONS a node gives up and
    // answers "unbounded" without asking its children anything.
    let mut asked: Vec<Vec<Level>> = vec![Vec::new(); nodes.len()];
    let mut gave_up = vec![false; nodes.len()];
    asked[tree.root()].push(Level::Below(0.0));
    for n in (0..nodes.len()).rev() {
        let node = &nodes[n];
        let [a, b] = node.children;
        let questions = std::mem::take(&mut asked[n]);
        if questions.len() > MAX_QUESTIONS {
            gave_up[n] = true;
            asked[n] = questions;
            continue;
        }
        for &q in &questions {
            match (&node.op, q) {
                (Op::Complement, Level::Below(t)) => asked[a].push(Level::Above(-t)),
                (Op::Complement, Level::Above(t)) => asked[a].push(Level::Below(-t)),
                (Op::Offset(xi), Level::Below(t)) => asked[a].push(Level::Below(t + xi)),
                (Op::Offset(xi), Level::Above(t)) => asked[a].push(Level::Above(t + xi)),
                (Op::Shell(th), Level::Below(t)) => {
                    // |f| − Ξ/2 ≤ t  ⟺  −(t + Ξ/2) ≤ f ≤ t + Ξ/2
                    let h = t + th / 2.0;
                    asked[a].push(Level::Below(h));
                    asked[a].push(Level::Above(-h));
                }
                (Op::Shell(th), Level::Above(t)) => {
                    // |f| ≥ t + Ξ/2  ⟺  f ≥ t + Ξ/2  or  f ≤ −(t + Ξ/2)
                    let h = t + th / 2.0;
                    asked[a].push(Level::Above(h));
                    asked[a].push(Level::Below(-h));
                }
                (Op::Scale(k), Level::Below(t)) => asked[a].push(Level::Below(t / k.abs())),
                (Op::Scale(k), Level::Above(t)) => asked[a].push(Level::Above(t / k.abs())),
                (Op::ScaleAxes(k), q) => {
                    // g = kmin·f where f ≥ 0 and kmax·f where f < 0 (eq. 4): for a level t ≥ 0
                    // (or > 0 above) only f ≥ 0 can reach it, scaled by kmin.
                    let kmin = k.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()));
                    let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    asked[a].push(match q {
                        Level::Below(t) => Level::Below(t / if t >= 0.0 { kmin } else { kmax }),
                        Level::Above(t) => Level::Above(t / if t > 0.0 { kmin } else { kmax }),
                    });
                }
                (
                    Op::Move(_)
                    | Op::Rotate { .. }
                    | Op::Orient(_)
                    | Op::Union
                    | Op::Intersection
                    | Op::SigmoidBlend { .. },
                    q,
                ) => {
                    asked[a].push(q);
                    if node.op.arity() == 2 {
                        asked[b].push(q);
                    }
                }
                (Op::Difference, q) => {
                    // max(f, −g)
                    asked[a].push(q);
                    asked[b].push(match q {
                        Level::Below(t) => Level::Above(-t),
                        Level::Above(t) => Level::Below(-t),
                    });
                }
                _ => {}
            }
        }
        asked[n] = questions;
    }

    // Pass 2, children before parents: the answers, in the order the questions were asked.
    let mut answers: Vec<Vec<Aabb>> = vec![Vec::new(); nodes.len()];
    let mut taken = vec![0usize; nodes.len()];
    for n in 0..nodes.len() {
        let node = &nodes[n];
        let [a, b] = node.children;
        let mut mine = Vec::with_capacity(asked[n].len());
        for &q in &asked[n] {
            let mut next = |child: usize| {
                let box_ = answers[child][taken[child]];
                taken[child] += 1;
                box_
            };
            let answer = match &node.op {
                _ if gave_up[n] => Aabb::EVERYTHING,
                Op::Ball | Op::Box => match q {
                    Level::Below(t) => Aabb::cube(1.0 + t),
                    Level::Above(_) => Aabb::EVERYTHING,
                },
                Op::Cylinder => match q {
                    Level::Below(t) if t < -1.0 => Aabb::EMPTY,
                    Level::Below(t) => Aabb {
                        min: [-(1.0 + t), -(1.0 + t), f64::NEG_INFINITY],
                        max: [1.0 + t, 1.0 + t, f64::INFINITY],
                    },
                    Level::Above(_) => Aabb::EVERYTHING,
                },
                Op::Tpms(_) | Op::Expression { .. } => Aabb::EVERYTHING,
                Op::File(_) => {
                    let e = external(n);
                    match q {
                        Level::Below(t) if e.is_distance => e.bounds.grown(t),
                        Level::Below(t) if t <= 0.0 => e.bounds,
                        _ => Aabb::EVERYTHING,
                    }
                }
                Op::Complement | Op::Offset(_) => next(a),
                Op::Shell(_) => {
                    let (first, second) = (next(a), next(a));
                    match q {
                        Level::Below(_) => first.intersection(&second),
                        Level::Above(_) => first.union(&second),
                    }
                }
                Op::Move(d) => Affine::translation(*d).image(&next(a)),
                Op::Scale(k) => Affine::diagonal([*k; 3]).image(&next(a)),
                Op::ScaleAxes(k) => Affine::diagonal(*k).image(&next(a)),
                // The child is evaluated at R x, so x lies in Rᵀ(child's box).
                Op::Rotate { axis, angle } => Affine::rotation(*axis, *angle)
                    .transpose_linear()
                    .image(&next(a)),
                // The child is evaluated at Rᵀ x, so x lies in R(child's box).
                Op::Orient(v) => Affine::turning_z_to(*v).image(&next(a)),
                // A convex combination of f and g is ≤ t only where one of them is, and ≥ t
                // only where one of them is.
                Op::SigmoidBlend { .. } => next(a).union(&next(b)),
                Op::Union | Op::Intersection | Op::Difference => {
                    let (left, right) = (next(a), next(b));
                    let widens = match (&node.op, q) {
                        (Op::Union, Level::Below(_)) => true,
                        (Op::Union, Level::Above(_)) => false,
                        (_, Level::Below(_)) => false,
                        (_, Level::Above(_)) => true,
                    };
                    if widens {
                        left.union(&right)
                    } else {
                        left.intersection(&right)
                    }
                }
            };
            mine.push(answer);
        }
        answers[n] = mine;
    }
    answers[tree.root()][0]
}
