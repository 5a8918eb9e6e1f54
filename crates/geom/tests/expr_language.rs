//! The expression language as users meet it: values, precedence, error reports, and
//! robustness against arbitrary text.

mod expr {
    use std::f64::consts::{E, PI, SQRT_2, TAU};
    use std::panic::{AssertUnwindSafe, catch_unwind};

    use latticebuild_geom::expr::{
        BinOp, Expr, MAX_HEIGHT, MAX_NESTING, ParseError, Var, compile, parse,
    };

    const OPERAND_HELP: &str = "expected a number, a variable, a function call or `(`";

    fn value(text: &str, p: [f64; 3]) -> f64 {
        compile(text)
            .unwrap_or_else(|e| panic!("{text}: {e:?}"))
            .eval(p)
    }

    #[test]
    fn precedence_and_values() {
        let p = [0.5, -2.0, 3.0];
        #[rustfmt::skip]
        let table: &[(&str, f64)] = &[
            ("-2^2", -4.0),
            ("2^3^2", 512.0),
            ("(2^3)^2", 64.0),
            ("1-2-3", -4.0),
            ("8/4/2", 1.0),
            ("2*3+4", 10.0),
            ("2+3*4", 14.0),
            ("(2+3)*4", 20.0),
            ("-2*3", -6.0),
            ("2*-3", -6.0),
            ("2^-1", 0.5),
            ("-2^-2", -0.25),
            ("2^2*3", 12.0),
            ("3*2^2", 12.0),
            ("--3", 3.0),
            ("+3", 3.0),
            ("-+-3", 3.0),
            ("1 - -1", 2.0),
            ("min(3,1,2)", 1.0),
            ("max(3, 1, 2)", 3.0),
            ("min(4, max(1, 2))", 2.0),
            ("1e-3*1000", 1.0),
            ("2.5E+2", 250.0),
            (".5 + .5", 1.0),
            ("0.25", 0.25),
            ("  1 +\t2\n", 3.0),
            ("pi", PI),
            ("tau", TAU),
            ("e", E),
            ("sin(pi/2)", 1.0),
            ("cos(0)", 1.0),
            ("cos(pi)", -1.0),
            ("exp(1)", E),
            ("exp(0)", 1.0),
            ("log(e^2)", 2.0),
            ("sqrt(16)", 4.0),
            ("abs(-3)", 3.0),
            ("abs(3)", 3.0),
            ("x*y - z", -4.0),
            ("x^2 + y^2", 4.25),
            ("-x^2", -0.25),
            ("(-x)^2", 0.25),
            ("2^x", SQRT_2),
            ("y^3", -8.0),
            ("min(x, y, z)", -2.0),
            ("max(x, y, z)", 3.0),
            ("z/y/x", -3.0),
            ("x - y - z", -0.5),
        ];
        for &(text, want) in table {
            let got = value(text, p);
            assert!(
                (got - want).abs() <= 1e-15 * want.abs().max(1.0),
                "{text}: {got} vs {want}"
            );
        }
        assert!((value("tan(pi/4)", p) - 1.0).abs() < 1e-15);
        assert!((value("sin(tau*x)", p)).abs() < 1e-15);
    }

    #[test]
    fn tree_shapes() {
        let n = |v: f64| Expr::Num(v);
        let bin = Expr::binary;
        assert_eq!(
            parse("-x^2"),
            Ok(Expr::Neg(Box::new(bin(
                BinOp::Pow,
                Expr::Var(Var::X),
                n(2.0)
            ))))
        );
        assert_eq!(
            parse("2^3^2"),
            Ok(bin(BinOp::Pow, n(2.0), bin(BinOp::Pow, n(3.0), n(2.0))))
        );
        assert_eq!(
            parse("1-2-3"),
            Ok(bin(BinOp::Sub, bin(BinOp::Sub, n(1.0), n(2.0)), n(3.0)))
        );
        assert_eq!(
            parse("min(x, y, z)"),
            Ok(bin(
                BinOp::Min,
                bin(BinOp::Min, Expr::Var(Var::X), Expr::Var(Var::Y)),
                Expr::Var(Var::Z)
            ))
        );
        assert_eq!(parse("+x"), Ok(Expr::Var(Var::X)));
        assert_eq!(parse("((x))"), Ok(Expr::Var(Var::X)));
    }

    fn err(span: std::ops::Range<usize>, message: &str, help: Option<&str>) -> ParseError {
        ParseError {
            span,
            message: message.into(),
            help: help.map(Into::into),
        }
    }

    #[test]
    fn error_reports() {
        let names =
            "unknown variable `w`: the available names are `x`, `y`, `z`, `pi`, `tau` and `e`";
        let all_functions = "the available functions are `sin`, `cos`, `tan`, `exp`, `log`, \
                             `sqrt`, `abs`, `min`, `max`";
        let table: Vec<(&str, ParseError)> = vec![
            // Unknown names.
            (
                "sinn(x)",
                err(0..4, "unknown function `sinn`", Some("did you mean `sin`?")),
            ),
            (
                "2*Cos(x)",
                err(2..5, "unknown function `Cos`", Some("did you mean `cos`?")),
            ),
            (
                "foo(x)",
                err(0..3, "unknown function `foo`", Some(all_functions)),
            ),
            ("x + w", err(4..5, names, None)),
            (
                "2*X",
                err(
                    2..3,
                    "unknown variable `X`: the available names are `x`, `y`, `z`, `pi`, `tau` and `e`",
                    Some("did you mean `x`?"),
                ),
            ),
            (
                "cos(tua*x)",
                err(
                    4..7,
                    "unknown variable `tua`: the available names are `x`, `y`, `z`, `pi`, `tau` and `e`",
                    Some("did you mean `tau`?"),
                ),
            ),
            (
                "sin + 1",
                err(
                    0..3,
                    "function `sin` needs its arguments in parentheses",
                    Some("write `sin(...)`"),
                ),
            ),
            (
                "x(1)",
                err(
                    0..1,
                    "`x` is not a function",
                    Some("multiplication needs an explicit `*`: write `x*(...)`"),
                ),
            ),
            // Arity.
            (
                "sin(x, y)",
                err(0..9, "`sin` takes 1 argument but was given 2", None),
            ),
            (
                "1 + sin()",
                err(4..9, "`sin` takes 1 argument but was given 0", None),
            ),
            (
                "min(x)",
                err(
                    0..6,
                    "`min` takes at least 2 arguments but was given 1",
                    None,
                ),
            ),
            (
                "max()",
                err(
                    0..5,
                    "`max` takes at least 2 arguments but was given 0",
                    None,
                ),
            ),
            // Parentheses.
            (
                "(x + 1",
                err(0..1, "unclosed `(`", Some("add a matching `)`")),
            ),
            (
                "cos(tau*(x + y)",
                err(3..4, "unclosed `(`", Some("add a matching `)`")),
            ),
            (
                "(x + (y)",
                err(0..1, "unclosed `(`", Some("add a matching `)`")),
            ),
            ("x + 1)", err(5..6, "unmatched `)`", None)),
            (")", err(0..1, "unmatched `)`", None)),
            ("(x))", err(3..4, "unmatched `)`", None)),
            // Unexpected tokens and end of input.
            ("x + * y", err(4..5, "unexpected `*`", Some(OPERAND_HELP))),
            (
                "x +",
                err(3..3, "unexpected end of input", Some(OPERAND_HELP)),
            ),
            (
                "sin(",
                err(4..4, "unexpected end of input", Some(OPERAND_HELP)),
            ),
            (
                "x y",
                err(
                    2..3,
                    "unexpected `y`",
                    Some("expected an operator or the end of the expression"),
                ),
            ),
            ("min(x,)", err(6..7, "unexpected `)`", Some(OPERAND_HELP))),
            ("()", err(1..2, "unexpected `)`", Some(OPERAND_HELP))),
            (
                "sin(x y)",
                err(
                    6..7,
                    "unexpected `y`",
                    Some("expected an operator, `,` or `)`"),
                ),
            ),
            (
                "(x 1)",
                err(3..4, "unexpected `1`", Some("expected an operator or `)`")),
            ),
            (
                "(x, y)",
                err(2..3, "unexpected `,`", Some("expected an operator or `)`")),
            ),
            (
                "x ** 2",
                err(
                    2..4,
                    "unexpected `**`",
                    Some("write powers with `^`, e.g. `x^2`"),
                ),
            ),
            ("", err(0..0, "empty expression", Some(OPERAND_HELP))),
            ("  ", err(0..2, "empty expression", Some(OPERAND_HELP))),
            // Characters and numbers.
            ("x # y", err(2..3, "unexpected character `#`", None)),
            ("x + é", err(4..6, "unexpected character `é`", None)),
            ("1.2.3 + x", err(0..5, "invalid number `1.2.3`", None)),
            ("x - 1e+", err(4..7, "invalid number `1e+`", None)),
            (
                "2x",
                err(
                    0..2,
                    "invalid number `2x`",
                    Some("multiplication needs an explicit `*`: write `2*x`"),
                ),
            ),
            (
                "3pi/2",
                err(
                    0..3,
                    "invalid number `3pi`",
                    Some("multiplication needs an explicit `*`: write `3*pi`"),
                ),
            ),
            ("1e999", err(0..5, "number `1e999` is too large", None)),
            // The leftmost problem wins.
            (
                "sinn(x) + w",
                err(0..4, "unknown function `sinn`", Some("did you mean `sin`?")),
            ),
            ("x $ (", err(2..3, "unexpected character `$`", None)),
        ];
        for (text, want) in table {
            assert_eq!(parse(text), Err(want), "{text:?}");
        }
    }

    #[test]
    fn nesting_limits() {
        let deep =
            |open: &str, close: &str, n: usize| format!("{}x{}", open.repeat(n), close.repeat(n));
        // Within the limit everything works, including every later pass.
        for text in [
            deep("(", ")", MAX_NESTING - 2),
            deep("-", "", MAX_NESTING - 2),
            deep("sin(", ")", MAX_NESTING - 2),
            format!("x{}", "+x".repeat(MAX_HEIGHT - 2)),
            format!("cos(x{})", "-y".repeat(MAX_HEIGHT - 3)),
            format!("min(x{})", ",y".repeat(MAX_HEIGHT - 2)),
        ] {
            let c = compile(&text).unwrap_or_else(|e| panic!("{}: {e:?}", &text[..20]));
            assert!(c.eval([0.1, 0.2, 0.3]).is_finite());
        }
        // Far beyond it, a clean error rather than a stack overflow.
        for text in [
            deep("(", ")", 100_000),
            deep("-", "", 100_000),
            deep("sin(", ")", 100_000),
            deep("2^", "", 100_000),
            format!("x{}", "+x".repeat(100_000)),
            format!("min(x{})", ",x".repeat(100_000)),
        ] {
            let e = parse(&text).expect_err("too deep");
            assert_eq!(e.message, "expression is nested too deeply");
            assert!(e.span.end <= text.len());
        }
        let long_sum = parse(&format!("x{}", "+x".repeat(MAX_HEIGHT))).expect_err("too tall");
        assert_eq!(
            long_sum.help.as_deref(),
            Some("at most 1024 chained operations are supported; group long sums in parentheses")
        );
        let parens = parse(&deep("(", ")", MAX_NESTING + 1)).expect_err("too deep");
        assert_eq!(parens.span, MAX_NESTING..MAX_NESTING + 1);
        // Within the limit, parentheses don't count towards the tree height.
        assert_eq!(
            value(&deep("(", ")", MAX_NESTING / 2), [1.5, 0.0, 0.0]),
            1.5
        );
    }

    /// A small deterministic generator (xorshift64*), so failures reproduce.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
    }

    fn check_never_panics(text: &str) {
        let outcome = catch_unwind(AssertUnwindSafe(|| match parse(text) {
            Ok(tree) => {
                let compiled = compile(text).expect("parse succeeded");
                let p = [0.3, -0.7, 1.1];
                let got = compiled.eval(p);
                let want = tree.eval_tree(p);
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "{text:?}: compiled {got} vs tree {want}"
                );
            }
            Err(e) => {
                assert!(
                    e.span.start <= e.span.end && e.span.end <= text.len(),
                    "{text:?}: {e:?}"
                );
                assert!(text.is_char_boundary(e.span.start) && text.is_char_boundary(e.span.end));
                let first = e.message.chars().next().expect("message is not empty");
                assert!(
                    first.is_lowercase() || first == '`',
                    "{text:?}: {}",
                    e.message
                );
            }
        }));
        assert!(outcome.is_ok(), "panicked on {text:?}");
    }

    #[test]
    fn random_token_strings_never_panic() {
        let alphabet = [
            "x", "y", "z", "pi", "tau", "e", "1", "0.5", ".5", "1e-3", "2.5E+2", "3", "+", "-",
            "*", "/", "^", "(", ")", ",", "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "min",
            "max", " ", "(", ")", "sinn", "w", "1.2.3", "$", "é", "**", "1e999", "1e", ".", "_",
            "2x", "\t",
        ];
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let mut parsed = 0;
        for _ in 0..30_000 {
            let len = rng.below(16);
            let text: String = (0..len)
                .map(|_| alphabet[rng.below(alphabet.len())])
                .collect();
            check_never_panics(&text);
            parsed += usize::from(parse(&text).is_ok());
        }
        // The alphabet is rich enough that the evaluator sees plenty of valid input too.
        assert!(parsed > 500, "only {parsed} strings parsed");
    }

    #[test]
    fn random_grammatical_strings_never_panic() {
        // Grammar-shaped input reaches the evaluator far more often than token soup.
        fn grammatical(rng: &mut Rng, depth: u32) -> String {
            let atoms = ["x", "y", "z", "pi", "2", "0.5", "1e-3", "tau", "e", "0"];
            if depth == 0 || rng.below(4) == 0 {
                return atoms[rng.below(atoms.len())].to_string();
            }
            let ops = ["+", "-", "*", "/", "^"];
            let funcs = ["sin", "cos", "tan", "exp", "log", "sqrt", "abs"];
            match rng.below(5) {
                0 | 1 => {
                    let op = ops[rng.below(ops.len())];
                    format!(
                        "{} {op} {}",
                        grammatical(rng, depth - 1),
                        grammatical(rng, depth - 1)
                    )
                }
                2 => format!(
                    "{}({})",
                    funcs[rng.below(funcs.len())],
                    grammatical(rng, depth - 1)
                ),
                3 => format!("-({})", grammatical(rng, depth - 1)),
                _ => format!(
                    "min({}, {}, {})",
                    grammatical(rng, depth - 1),
                    grammatical(rng, 0),
                    grammatical(rng, depth - 1)
                ),
            }
        }
        let mut rng = Rng(42);
        for _ in 0..5_000 {
            let text = grammatical(&mut rng, 5);
            assert!(parse(&text).is_ok(), "{text}");
            check_never_panics(&text);
        }
    }

    #[test]
    fn random_unicode_never_panics() {
        let mut rng = Rng(7);
        for _ in 0..10_000 {
            let len = rng.below(12);
            let text: String = (0..len)
                .map(|_| match rng.below(4) {
                    0 => char::from(b' ' + rng.below(95) as u8),
                    1 => char::from_u32(rng.below(0x3000) as u32).unwrap_or('?'),
                    _ => ['x', '(', ')', '1', '.', 'e', '-', '^', 's'][rng.below(9)],
                })
                .collect();
            check_never_panics(&text);
        }
    }

    #[test]
    fn errors_display_their_message() {
        let e = parse("sinn(x)").expect_err("unknown function");
        assert_eq!(e.to_string(), "unknown function `sinn`");
        let boxed: Box<dyn std::error::Error> = Box::new(e);
        assert_eq!(boxed.to_string(), "unknown function `sinn`");
    }
}
