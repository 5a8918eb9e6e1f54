//! From words to a [`Tree`]: the stack machine of the language (paper §4.2).
//!
//! SDF words (`ball`, `cylinder`, `box`, `tpms.NAME`, `expression TEXT`, `file PATH`) push a
//! solid; unary words (`complement`, `offset ξ`, `shell Ξ`, `move v`, `scale k` or `scale v`,
//! `rotate v θ`, `orient v`) replace the solid on top with a modified one and read their
//! arguments from the words to their right; binary words (`union`, `intersection`,
//! `difference`, and `sigmoid-blend d x0 width` with its arguments to its right) pop two
//! solids and push their combination. At the end exactly one solid must
//! remain. Words are matched without regard to case.
//!
//! Invariants:
//! - The first problem, reading left to right, is the one reported, with the word at fault.
//! - Every argument is checked here, so a [`Tree`] is always meaningful (see `tree.rs`).

use super::args;
use super::error::ProgramError;
use super::tree::{Node, Op, Tree};
use super::words::{At, Word};
use crate::spelling::closest;
use crate::tpms;

/// Words that push a solid (`tpms.NAME` aside).
pub const SOLID_WORDS: [&str; 5] = ["ball", "cylinder", "box", "expression", "file"];
/// Words that modify the solid on top of the stack.
pub const UNARY_WORDS: [&str; 7] = [
    "complement",
    "offset",
    "shell",
    "move",
    "scale",
    "rotate",
    "orient",
];
/// Words that combine the two solids on top of the stack.
pub const BINARY_WORDS: [&str; 4] = ["union", "intersection", "difference", "sigmoid-blend"];

/// Names from other tools, and the word they mean here.
const SYNONYMS: [(&str, &str); 15] = [
    ("blend", "sigmoid-blend"),
    ("grade", "sigmoid-blend"),
    ("sigmoid", "sigmoid-blend"),
    ("sphere", "ball"),
    ("cube", "box"),
    ("translate", "move"),
    ("shift", "move"),
    ("invert", "complement"),
    ("not", "complement"),
    ("thicken", "shell"),
    ("subtract", "difference"),
    ("minus", "difference"),
    ("intersect", "intersection"),
    ("and", "intersection"),
    ("or", "union"),
];

/// Parses a program given as words.
pub fn parse(words: &[Word]) -> Result<Tree, ProgramError> {
    let mut parser = Parser {
        words,
        next: 0,
        nodes: Vec::new(),
        stack: Vec::new(),
    };
    while let Some(word) = parser.take() {
        parser.word(word)?;
    }
    match parser.stack.len() {
        0 => Err(ProgramError::Empty),
        1 => Ok(Tree {
            nodes: parser.nodes,
        }),
        count => {
            let first_unused = parser.stack[0];
            Err(ProgramError::Leftover {
                at: parser.nodes[first_unused].at.clone(),
                count,
            })
        }
    }
}

struct Parser<'w> {
    words: &'w [Word],
    next: usize,
    nodes: Vec<Node>,
    /// Indices of the nodes whose solids are on the stack, bottom first.
    stack: Vec<usize>,
}

impl<'w> Parser<'w> {
    fn take(&mut self) -> Option<&'w Word> {
        let word = self.words.get(self.next)?;
        self.next += 1;
        Some(word)
    }

    fn push(&mut self, op: Op, children: [usize; 2], at: At) {
        self.nodes.push(Node { op, children, at });
        self.stack.push(self.nodes.len() - 1);
    }

    /// Pops `arity` operands (checked to be there), bottom one first.
    fn pop(&mut self, arity: usize) -> [usize; 2] {
        let mut children = [usize::MAX; 2];
        for slot in (0..arity).rev() {
            children[slot] = self.stack.pop().unwrap_or(usize::MAX);
        }
        children
    }

    /// The word after `op`, which must be its argument.
    fn argument(
        &mut self,
        op: &Word,
        word: &'static str,
        expected: &'static str,
    ) -> Result<&'w Word, ProgramError> {
        self.take().ok_or_else(|| ProgramError::MissingArgument {
            at: op.at(),
            word,
            expected,
        })
    }

    /// The argument of `op` read by `read`; its failure becomes a [`ProgramError::BadArgument`].
    fn read<T>(
        &mut self,
        op: &Word,
        word: &'static str,
        expected: &'static str,
        read: impl FnOnce(&str) -> Result<T, String>,
    ) -> Result<T, ProgramError> {
        let arg = self.argument(op, word, expected)?;
        read(&arg.text).map_err(|problem| ProgramError::BadArgument {
            at: arg.at(),
            word,
            expected,
            problem,
        })
    }

    fn word(&mut self, word: &'w Word) -> Result<(), ProgramError> {
        let at = word.at();
        let lower = word.text.to_lowercase();
        if lower.starts_with('@') {
            return Err(ProgramError::UnexpandedInclude { at });
        }
        if let Some(name) = lower.strip_prefix("tpms.") {
            let surface = tpms::lookup(name).ok_or_else(|| ProgramError::UnknownTpms {
                at: at.clone(),
                name: name.to_string(),
                help: match tpms::suggest(name) {
                    Some(s) => format!("; did you mean `tpms.{s}`?"),
                    None => "; try `tpms.gyroid`, `tpms.d`, `tpms.p` or another surface of the \
                             library"
                        .to_string(),
                },
            })?;
            self.push(Op::Tpms(surface), [usize::MAX; 2], at);
            return Ok(());
        }
        let arity = if UNARY_WORDS.contains(&lower.as_str()) {
            1
        } else if BINARY_WORDS.contains(&lower.as_str()) {
            2
        } else {
            0
        };
        // The operands come before the arguments, so a missing operand is the earlier problem.
        if self.stack.len() < arity {
            let name = UNARY_WORDS
                .iter()
                .chain(&BINARY_WORDS)
                .find(|w| **w == lower)
                .copied()
                .unwrap_or("this word");
            return Err(ProgramError::Underflow {
                at,
                word: name,
                needs: arity,
                found: self.stack.len(),
            });
        }
        let op = match lower.as_str() {
            "ball" => Op::Ball,
            "cylinder" => Op::Cylinder,
            "box" => Op::Box,
            "expression" => {
                const EXPECTED: &str = "a formula in x, y, z";
                let arg = self.argument(word, "expression", EXPECTED)?;
                let expr =
                    crate::expr::parse(&arg.text).map_err(|e| ProgramError::BadExpression {
                        at: arg.at(),
                        byte: e.span.start,
                        message: e.message,
                        help: e.help.map(|h| format!("; {h}")).unwrap_or_default(),
                    })?;
                let text = arg.text.clone();
                Op::Expression { text, expr }
            }
            "file" => {
                let arg = self.argument(word, "file", "the path of a mesh")?;
                Op::File(arg.text.clone())
            }
            "complement" => Op::Complement,
            "offset" => {
                let v = self.read(word, "offset", "a radius", args::constant)?;
                Op::Offset(v)
            }
            "shell" => {
                let v = self.read(word, "shell", "a thickness of at least 0", |t| {
                    let v = args::constant(t)?;
                    if v < 0.0 {
                        return Err(format!("`{t}` is {v}, less than 0"));
                    }
                    Ok(v)
                })?;
                Op::Shell(v)
            }
            "move" => {
                let v = self.read(word, "move", "a distance dx,dy,dz", args::vector3)?;
                Op::Move(v)
            }
            "scale" => {
                const EXPECTED: &str = "a factor k or kx,ky,kz, none of them 0";
                let values = self.read(word, "scale", EXPECTED, |t| {
                    let values = args::constants(t)?;
                    if values.len() != 1 && values.len() != 3 {
                        return Err(format!(
                            "`{t}` has {} components, not one or three",
                            values.len()
                        ));
                    }
                    if values.contains(&0.0) {
                        return Err(format!("`{t}` has a factor of 0"));
                    }
                    Ok(values)
                })?;
                match values.as_slice() {
                    [k] => Op::Scale(*k),
                    [a, b, c] => Op::ScaleAxes([*a, *b, *c]),
                    _ => unreachable!("checked to have one or three components"),
                }
            }
            "rotate" => {
                let axis = self.read(word, "rotate", "an axis ax,ay,az (not 0,0,0)", |t| {
                    let v = args::vector3(t)?;
                    if v == [0.0; 3] {
                        return Err(format!("`{t}` is the zero vector, which has no direction"));
                    }
                    Ok(v)
                })?;
                let angle =
                    self.read(word, "rotate", "an angle in radians after its axis", |t| {
                        args::constant(t)
                    })?;
                Op::Rotate { axis, angle }
            }
            "orient" => {
                const EXPECTED: &str = "an axis ax,ay,az off the negative z half-axis";
                let v = self.read(word, "orient", EXPECTED, |t| {
                    let v = args::vector3(t)?;
                    if v[0] == 0.0 && v[1] == 0.0 && v[2] <= 0.0 {
                        return Err(format!(
                            "`{t}` lies on the negative z half-axis (x = y = 0, z ≤ 0), where the \
                             turn from z is not defined"
                        ));
                    }
                    Ok(v)
                })?;
                Op::Orient(v)
            }
            "union" => Op::Union,
            "intersection" => Op::Intersection,
            "difference" => Op::Difference,
            "sigmoid-blend" => self.sigmoid_blend(word)?,
            _ => return Err(unknown(word)),
        };
        let children = self.pop(arity);
        self.push(op, children, at);
        Ok(())
    }
}

impl<'w> Parser<'w> {
    /// The arguments of `sigmoid-blend`: a direction (made a unit vector, so that the
    /// position and width are lengths), the position of the transition along it, its width.
    fn sigmoid_blend(&mut self, word: &'w Word) -> Result<Op, ProgramError> {
        const WORD: &str = "sigmoid-blend";
        let direction = self.read(word, WORD, "a direction dx,dy,dz (not 0,0,0)", |t| {
            let v = args::vector3(t)?;
            let length = v.iter().map(|c| c * c).sum::<f64>().sqrt();
            if length == 0.0 || !length.is_finite() {
                return Err(format!("`{t}` has no direction"));
            }
            Ok(v.map(|c| c / length))
        })?;
        let x0 = self.read(
            word,
            WORD,
            "the position of the transition along the direction, after it",
            args::constant,
        )?;
        let width = self.read(
            word,
            WORD,
            "a transition width greater than 0, after the position",
            |t| {
                let v = args::constant(t)?;
                if v <= 0.0 {
                    return Err(format!("`{t}` is {v}, not greater than 0"));
                }
                Ok(v)
            },
        )?;
        Ok(Op::SigmoidBlend {
            direction,
            x0,
            width,
        })
    }
}

fn unknown(word: &Word) -> ProgramError {
    let text = &word.text;
    let lower = text.to_lowercase();
    let help = if args::constant(text).is_ok() {
        "; a number here is not the argument of any word (a word takes a fixed number of \
         arguments: `scale 2` or `scale 1,2,3`, `rotate 0,0,1 pi/2`)"
            .to_string()
    } else if let Some((_, meant)) = SYNONYMS.iter().find(|(s, _)| *s == lower) {
        format!("; the word for this is `{meant}`")
    } else {
        let known = SOLID_WORDS
            .iter()
            .chain(&UNARY_WORDS)
            .chain(&BINARY_WORDS)
            .copied();
        match closest(text, known) {
            Some(s) => format!("; did you mean `{s}`?"),
            None => "; expected a solid (`ball`, `cylinder`, `box`, `tpms.NAME`, `expression`, \
                     `file`) or an operation (`complement`, `offset`, `shell`, `move`, `scale`, \
                     `rotate`, `orient`, `union`, `intersection`, `difference`, \
                     `sigmoid-blend`)"
                .to_string(),
        }
    };
    ProgramError::UnknownWord {
        at: word.at(),
        help,
    }
}
