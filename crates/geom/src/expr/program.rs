//! Register bytecode for evaluating an expression over blocks of points.
//!
//! Invariants:
//! - A program is built once from a tree; evaluating it walks a flat instruction list once
//!   per block of [`BLOCK`] points, and every instruction is a tight loop over block-sized
//!   register arrays. Nothing is allocated per point, and the tree is never consulted again.
//! - Each instruction computes exactly [`Func::apply`] / [`BinOp::apply`] of its operands, in
//!   the operand order of the tree, so a program and the tree agree bit for bit.
//! - Identical subtrees are computed once (value numbering), and an instruction's destination
//!   register is never one of its operands, which lets every loop borrow its operands
//!   immutably and its destination mutably.
//! - Registers 0, 1 and 2 hold x, y and z and are never reused for anything else.

use std::collections::HashMap;

use super::ast::{BinOp, Expr, Func, Var};

/// Points evaluated per pass over the program: large enough to amortise the dispatch of an
/// instruction, small enough that the registers of a typical formula stay in L1.
pub const BLOCK: usize = 256;

type Reg = usize;

#[derive(Clone, Copy, Debug)]
enum Op {
    Const(f64),
    Neg(Reg),
    Call(Func, Reg),
    Square(Reg),
    Bin(BinOp, Reg, Reg),
    /// `a op k`
    BinK(BinOp, Reg, f64),
    /// `k op a`
    KBin(BinOp, f64, Reg),
}

#[derive(Clone, Copy, Debug)]
struct Instr {
    dst: Reg,
    op: Op,
}

/// A compiled expression.
#[derive(Clone, Debug)]
pub struct Program {
    code: Vec<Instr>,
    registers: usize,
    result: Reg,
    /// Which of x, y, z the code reads (bit per axis), so unused inputs are not copied.
    inputs: u8,
}

/// A value-numbered node: operands refer to earlier nodes by index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Node {
    Var(Var),
    Const(u64),
    Neg(usize),
    Call(Func, usize),
    Bin(BinOp, usize, usize),
}

#[derive(Default)]
struct Numbering {
    nodes: Vec<Node>,
    ids: HashMap<Node, usize>,
}

impl Numbering {
    fn add(&mut self, e: &Expr) -> usize {
        let node = match e {
            Expr::Num(v) => Node::Const(v.to_bits()),
            Expr::Var(v) => Node::Var(*v),
            Expr::Neg(a) => Node::Neg(self.add(a)),
            Expr::Call(f, a) => Node::Call(*f, self.add(a)),
            Expr::Binary(op, a, b) => {
                let a = self.add(a);
                let b = self.add(b);
                Node::Bin(*op, a, b)
            }
        };
        if let Some(&id) = self.ids.get(&node) {
            return id;
        }
        self.nodes.push(node);
        self.ids.insert(node, self.nodes.len() - 1);
        self.nodes.len() - 1
    }
}

impl Program {
    pub fn new(expr: &Expr) -> Program {
        let mut numbering = Numbering::default();
        let root = numbering.add(expr);
        let nodes = numbering.nodes;
        let is_const = |id: usize| matches!(nodes[id], Node::Const(_));

        // Operands that must live in a register (a constant beside a register operand is
        // passed as an immediate instead).
        let reg_operands = |node: &Node| -> Vec<usize> {
            match *node {
                Node::Var(_) | Node::Const(_) => vec![],
                Node::Neg(a) | Node::Call(_, a) => vec![a],
                Node::Bin(_, a, b) => match (is_const(a), is_const(b)) {
                    (true, false) => vec![b],
                    (false, true) => vec![a],
                    _ if a == b => vec![a],
                    _ => vec![a, b],
                },
            }
        };
        let mut last_use = vec![None; nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            for a in reg_operands(node) {
                last_use[a] = Some(i);
            }
        }
        last_use[root] = Some(usize::MAX);

        let mut reg_of: Vec<Reg> = vec![usize::MAX; nodes.len()];
        let mut free: Vec<Reg> = Vec::new();
        let mut registers = 3;
        let mut code = Vec::new();
        let mut inputs = 0u8;
        let value = |id: usize| match nodes[id] {
            Node::Const(bits) => f64::from_bits(bits),
            _ => f64::NAN,
        };
        for (i, node) in nodes.iter().enumerate() {
            if let Node::Var(v) = node {
                reg_of[i] = v.index();
                inputs |= 1 << v.index();
                continue;
            }
            if last_use[i].is_none() {
                continue; // a constant only ever used as an immediate
            }
            let dst = free.pop().unwrap_or_else(|| {
                registers += 1;
                registers - 1
            });
            let op = match *node {
                Node::Var(_) => continue,
                Node::Const(bits) => Op::Const(f64::from_bits(bits)),
                Node::Neg(a) => Op::Neg(reg_of[a]),
                Node::Call(f, a) => Op::Call(f, reg_of[a]),
                Node::Bin(op, a, b) => match (is_const(a), is_const(b)) {
                    (false, true) if op == BinOp::Pow && value(b) == 2.0 => Op::Square(reg_of[a]),
                    (false, true) => Op::BinK(op, reg_of[a], value(b)),
                    (true, false) => Op::KBin(op, value(a), reg_of[b]),
                    _ => Op::Bin(op, reg_of[a], reg_of[b]),
                },
            };
            code.push(Instr { dst, op });
            reg_of[i] = dst;
            for a in reg_operands(node) {
                if last_use[a] == Some(i) && reg_of[a] >= 3 && !free.contains(&reg_of[a]) {
                    free.push(reg_of[a]);
                }
            }
        }
        Program {
            code,
            registers,
            result: reg_of[root],
            inputs,
        }
    }

    /// Evaluates at `(xs[n], ys[n], zs[n])` into `out[n]`. All four slices must have the
    /// same length.
    pub fn eval(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let len = out.len();
        assert!(
            xs.len() == len && ys.len() == len && zs.len() == len,
            "eval_points needs equally long slices"
        );
        // Registers are `stride` long: a single point (or a short row) needs no full block.
        let stride = len.clamp(1, BLOCK);
        let mut regs = Registers {
            data: vec![0.0; self.registers * stride],
            stride,
        };
        let mut start = 0;
        while start < len {
            let n = (len - start).min(BLOCK);
            for (axis, src) in [xs, ys, zs].into_iter().enumerate() {
                if self.inputs & (1 << axis) != 0 {
                    regs.get_mut(axis, n)
                        .copy_from_slice(&src[start..start + n]);
                }
            }
            for ins in &self.code {
                exec(ins, &mut regs, n);
            }
            out[start..start + n].copy_from_slice(regs.get_mut(self.result, n));
            start += n;
        }
    }

    /// Number of instructions (for tests of value numbering).
    #[cfg(test)]
    fn len(&self) -> usize {
        self.code.len()
    }
}

fn exec(ins: &Instr, regs: &mut Registers, n: usize) {
    let d = ins.dst;
    match ins.op {
        Op::Const(k) => regs.get_mut(d, n).fill(k),
        Op::Neg(a) => map1(regs, d, a, n, |v| -v),
        Op::Square(a) => map1(regs, d, a, n, |v| v * v),
        Op::Call(f, a) => match f {
            Func::Sin => map1(regs, d, a, n, f64::sin),
            Func::Cos => map1(regs, d, a, n, f64::cos),
            Func::Tan => map1(regs, d, a, n, f64::tan),
            Func::Exp => map1(regs, d, a, n, f64::exp),
            Func::Log => map1(regs, d, a, n, f64::ln),
            Func::Sqrt => map1(regs, d, a, n, f64::sqrt),
            Func::Abs => map1(regs, d, a, n, f64::abs),
        },
        Op::Bin(op, a, b) => match op {
            BinOp::Add => map2(regs, d, a, b, n, |u, v| u + v),
            BinOp::Sub => map2(regs, d, a, b, n, |u, v| u - v),
            BinOp::Mul => map2(regs, d, a, b, n, |u, v| u * v),
            BinOp::Div => map2(regs, d, a, b, n, |u, v| u / v),
            BinOp::Pow => map2(regs, d, a, b, n, super::ast::pow),
            BinOp::Min => map2(regs, d, a, b, n, f64::min),
            BinOp::Max => map2(regs, d, a, b, n, f64::max),
        },
        Op::BinK(op, a, k) => match op {
            BinOp::Add => map1(regs, d, a, n, |v| v + k),
            BinOp::Sub => map1(regs, d, a, n, |v| v - k),
            BinOp::Mul => map1(regs, d, a, n, |v| v * k),
            BinOp::Div => map1(regs, d, a, n, |v| v / k),
            BinOp::Pow => map1(regs, d, a, n, |v| super::ast::pow(v, k)),
            BinOp::Min => map1(regs, d, a, n, |v| v.min(k)),
            BinOp::Max => map1(regs, d, a, n, |v| v.max(k)),
        },
        Op::KBin(op, k, a) => match op {
            BinOp::Add => map1(regs, d, a, n, |v| k + v),
            BinOp::Sub => map1(regs, d, a, n, |v| k - v),
            BinOp::Mul => map1(regs, d, a, n, |v| k * v),
            BinOp::Div => map1(regs, d, a, n, |v| k / v),
            BinOp::Pow => map1(regs, d, a, n, |v| super::ast::pow(k, v)),
            BinOp::Min => map1(regs, d, a, n, |v| k.min(v)),
            BinOp::Max => map1(regs, d, a, n, |v| k.max(v)),
        },
    }
}

/// Block-sized register arrays in one allocation.
struct Registers {
    data: Vec<f64>,
    stride: usize,
}

impl Registers {
    fn range(&self, r: Reg, n: usize) -> std::ops::Range<usize> {
        r * self.stride..r * self.stride + n
    }

    fn get_mut(&mut self, r: Reg, n: usize) -> &mut [f64] {
        let range = self.range(r, n);
        &mut self.data[range]
    }
}

#[inline(always)]
fn map1(regs: &mut Registers, d: Reg, a: Reg, n: usize, f: impl Fn(f64) -> f64) {
    let (rd, ra) = (regs.range(d, n), regs.range(a, n));
    let [dst, a] = regs
        .data
        .get_disjoint_mut([rd, ra])
        .expect("destination is never an operand");
    for (o, &u) in dst.iter_mut().zip(a.iter()) {
        *o = f(u);
    }
}

#[inline(always)]
fn map2(regs: &mut Registers, d: Reg, a: Reg, b: Reg, n: usize, f: impl Fn(f64, f64) -> f64) {
    if a == b {
        return map1(regs, d, a, n, |u| f(u, u));
    }
    let ranges = [regs.range(d, n), regs.range(a, n), regs.range(b, n)];
    let [dst, a, b] = regs
        .data
        .get_disjoint_mut(ranges)
        .expect("destination is never an operand");
    for ((o, &u), &v) in dst.iter_mut().zip(a.iter()).zip(b.iter()) {
        *o = f(u, v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{fold, parse};

    fn program(text: &str) -> (Expr, Program) {
        let e = fold(&parse(text).expect(text));
        let p = Program::new(&e);
        (e, p)
    }

    #[test]
    fn agrees_with_the_tree_bit_for_bit() {
        let texts = [
            "x",
            "3",
            "x*x",
            "x^2 + y^2 - z^2",
            "2^x + x^2.5 + (-x)^3",
            "min(x, y, 0.2) - max(0.1, z)",
            "sin(x)/cos(y) + tan(z) - exp(x)*log(abs(y)) + sqrt(z)",
            "-x - -y - 1/x + 1 - x",
            "cos(tau*x)*sin(tau*y) + cos(tau*y)*sin(tau*z) + cos(tau*z)*sin(tau*x)",
        ];
        let n = 700; // not a multiple of the block size
        let xs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * 2.0).collect();
        let ys: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos() * 1.5).collect();
        let zs: Vec<f64> = (0..n).map(|i| i as f64 / n as f64 - 0.3).collect();
        for text in texts {
            let (e, p) = program(text);
            let mut out = vec![0.0; n];
            p.eval(&xs, &ys, &zs, &mut out);
            for i in 0..n {
                let want = e.eval_tree([xs[i], ys[i], zs[i]]);
                assert!(
                    out[i].to_bits() == want.to_bits() || (out[i].is_nan() && want.is_nan()),
                    "{text} at {i}: {} vs {want}",
                    out[i]
                );
            }
        }
    }

    #[test]
    fn repeated_subtrees_are_computed_once() {
        // tau*x, cos(tau*x) once each; the product, the sum: 4 instructions.
        let (_, p) = program("cos(tau*x) + cos(tau*x)*cos(tau*x)");
        assert_eq!(p.len(), 4);
        let (_, p) = program("x");
        assert_eq!(p.len(), 0);
    }

    #[test]
    fn registers_are_reused() {
        let (_, p) = program("x+1+2+3+4+5+6+7+8+9+10");
        assert!(p.registers <= 5, "{} registers", p.registers);
    }
}
