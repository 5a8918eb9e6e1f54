//! The TPMS library: every surface of Table 2 of the Cesogen paper (after Fisher et al. 2023,
//! "Catalog of triply periodic minimal surfaces, equation-based lattice structures, and their
//! homogenized property data", Data in Brief 49:109311), with period 1.
//!
//! Conventions: `C_f = cos(τ f)` and `S_f = sin(τ f)` with `τ = 2π`, so every surface repeats
//! with period 1 along x, y and z. Each formula is stored as an expression in this crate's
//! expression language, so the library and user expressions share one evaluator (and its
//! separable fast path).
//!
//! Names follow Cesogen's: lower case, parentheses become a hyphen (`C(Y)` → `c-y`), spaces
//! become hyphens (`Split P` → `split-p`), primes are spelled out (`G'` → `g-prime`) and `±`
//! becomes `pm`. A few common aliases (`schwarz-p`, `diamond`, …) resolve to the same surface.
//!
//! The P+C(P) row is cut off in our copy of the Cesogen paper after `+ 0.1(C_x C_y`; it is
//! completed from Fisher et al. as `+ 0.1(C_x C_y + C_y C_z + C_z C_x)`.

/// One surface of the library.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Surface {
    /// Canonical name, as used in manifests (`tpms = "c-y"`) and SDF programs (`tpms.c-y`).
    pub name: &'static str,
    /// The name as printed in the paper's Table 2.
    pub title: &'static str,
    /// The implicit function in x, y, z (period 1); the surface is its zero set.
    pub formula: &'static str,
}

const fn s(name: &'static str, title: &'static str, formula: &'static str) -> Surface {
    Surface {
        name,
        title,
        formula,
    }
}

/// The 27 surfaces, in the order of the paper's Table 2.
pub static LIBRARY: [Surface; 27] = [
    s(
        "gyroid",
        "Gyroid",
        "cos(tau*x)*sin(tau*y) + cos(tau*y)*sin(tau*z) + cos(tau*z)*sin(tau*x)",
    ),
    s(
        "d",
        "D",
        "sin(tau*x)*sin(tau*y)*sin(tau*z) + cos(tau*x)*sin(tau*y)*cos(tau*z) \
         + cos(tau*y)*sin(tau*z)*cos(tau*x) + cos(tau*z)*sin(tau*x)*cos(tau*y)",
    ),
    s("p", "P", "cos(tau*x) + cos(tau*y) + cos(tau*z)"),
    s(
        "iwp",
        "IWP",
        "2*(cos(tau*x)*cos(tau*y) + cos(tau*y)*cos(tau*z) + cos(tau*z)*cos(tau*x)) \
         - (cos(2*tau*x) + cos(2*tau*y) + cos(2*tau*z))",
    ),
    s(
        "neovius",
        "Neovius",
        "4*cos(tau*x)*cos(tau*y)*cos(tau*z) + 3*(cos(tau*x) + cos(tau*y) + cos(tau*z))",
    ),
    s(
        "c-y",
        "C(Y)",
        "-sin(tau*x)*sin(tau*y)*sin(tau*z) + sin(2*tau*x)*sin(tau*y) + sin(2*tau*y)*sin(tau*z) \
         + sin(2*tau*z)*sin(tau*x) - cos(tau*x)*cos(tau*y)*cos(tau*z) + cos(tau*x)*sin(2*tau*y) \
         + cos(tau*y)*sin(2*tau*z) + cos(tau*z)*sin(2*tau*x)",
    ),
    s(
        "lidinoid",
        "Lidinoid",
        "sin(2*tau*x)*cos(tau*y)*sin(tau*z) + sin(2*tau*y)*cos(tau*z)*sin(tau*x) \
         + sin(2*tau*z)*cos(tau*x)*sin(tau*y) - (cos(2*tau*x)*cos(2*tau*y) \
         + cos(2*tau*y)*cos(2*tau*z) + cos(2*tau*z)*cos(2*tau*x)) + 0.3",
    ),
    s(
        "octo",
        "OCTO",
        "0.6*(cos(tau*x)*cos(tau*y) + cos(tau*y)*cos(tau*z) + cos(tau*z)*cos(tau*x)) \
         - 0.4*(cos(tau*x) + cos(tau*y) + cos(tau*z)) + 0.25",
    ),
    s(
        "frd",
        "FRD",
        "8*cos(tau*x)*cos(tau*y)*cos(tau*z) + cos(2*tau*x)*cos(2*tau*y)*cos(2*tau*z) \
         - (cos(2*tau*x)*cos(2*tau*y) + cos(2*tau*y)*cos(2*tau*z) + cos(2*tau*z)*cos(2*tau*x))",
    ),
    s(
        "s",
        "S",
        "cos(2*tau*x)*sin(tau*y)*cos(tau*z) + cos(2*tau*y)*sin(tau*z)*cos(tau*x) \
         + cos(2*tau*z)*sin(tau*x)*cos(tau*y)",
    ),
    s(
        "p+c-p",
        "P+C(P)",
        "0.3*cos(tau*x)*cos(tau*y)*cos(tau*z) + 0.1*cos(2*tau*x)*cos(2*tau*y)*cos(2*tau*z) \
         + 0.2*(cos(tau*x) + cos(tau*y) + cos(tau*z)) + 0.1*(cos(2*tau*x) + cos(2*tau*y) \
         + cos(2*tau*z)) + 0.05*(cos(3*tau*x) + cos(3*tau*y) + cos(3*tau*z)) \
         + 0.1*(cos(tau*x)*cos(tau*y) + cos(tau*y)*cos(tau*z) + cos(tau*z)*cos(tau*x))",
    ),
    s(
        "split-p",
        "Split P",
        "1.1*(sin(2*tau*x)*cos(tau*y)*sin(tau*z) + sin(2*tau*y)*cos(tau*z)*sin(tau*x) \
         + sin(2*tau*z)*cos(tau*x)*sin(tau*y)) - 0.2*(cos(2*tau*x)*cos(2*tau*y) \
         + cos(2*tau*y)*cos(2*tau*z) + cos(2*tau*z)*cos(2*tau*x)) \
         - 0.4*(cos(2*tau*x) + cos(2*tau*y) + cos(2*tau*z))",
    ),
    s("f", "F", "cos(tau*x)*cos(tau*y)*cos(tau*z)"),
    s(
        "c-d",
        "C(D)",
        "cos(tau*(3*x + y))*cos(tau*z) - sin(tau*(3*x - y))*sin(tau*z) \
         + cos(tau*(x + 3*y))*cos(tau*z) + sin(tau*(x - 3*y))*sin(tau*z) \
         + cos(tau*(x - y))*cos(3*tau*z) - sin(tau*(x + y))*sin(3*tau*z)",
    ),
    s(
        "g-prime",
        "G'",
        "sin(2*tau*x)*cos(tau*y)*sin(tau*z) + sin(2*tau*y)*cos(tau*z)*sin(tau*x) \
         + sin(2*tau*z)*cos(tau*x)*sin(tau*y) + 0.32",
    ),
    s(
        "g-prime-2",
        "G'₂",
        "5*(sin(2*tau*x)*cos(tau*y)*sin(tau*z) + sin(2*tau*y)*cos(tau*z)*sin(tau*x) \
         + sin(2*tau*z)*cos(tau*x)*sin(tau*y)) + cos(2*tau*x)*cos(2*tau*y) \
         + cos(2*tau*y)*cos(2*tau*z) + cos(2*tau*z)*cos(2*tau*x)",
    ),
    s(
        "d-prime",
        "D'",
        "0.5*(cos(tau*x)*cos(tau*y)*cos(tau*z) + sin(tau*x)*cos(tau*y)*sin(tau*z) \
         + sin(tau*y)*cos(tau*z)*sin(tau*x) + sin(tau*z)*cos(tau*x)*sin(tau*y)) \
         - 0.5*(sin(2*tau*x)*sin(2*tau*y) + sin(2*tau*y)*sin(2*tau*z) \
         + sin(2*tau*z)*sin(2*tau*x)) - 0.2",
    ),
    s(
        "k",
        "K",
        "0.3*(cos(tau*x) + cos(tau*y) + cos(tau*z) + cos(tau*x)*cos(tau*y) \
         + cos(tau*y)*cos(tau*z) + cos(tau*z)*cos(tau*x)) \
         - 0.4*(cos(2*tau*x) + cos(2*tau*y) + cos(2*tau*z)) + 0.2",
    ),
    s(
        "c-s",
        "C(S)",
        "cos(2*tau*x) + cos(2*tau*y) + cos(2*tau*z) + 2*(sin(2*tau*x)*cos(tau*y)*sin(3*tau*z) \
         + sin(2*tau*y)*cos(tau*z)*sin(3*tau*x) + sin(2*tau*z)*cos(tau*x)*sin(3*tau*y)) \
         + 2*(sin(2*tau*x)*cos(3*tau*y)*sin(tau*z) + sin(2*tau*y)*cos(3*tau*z)*sin(tau*x) \
         + sin(2*tau*z)*cos(3*tau*x)*sin(tau*y))",
    ),
    s(
        "y",
        "Y",
        "sin(tau*x)*sin(tau*y)*sin(tau*z) + cos(tau*x)*sin(2*tau*y) + cos(tau*y)*sin(2*tau*z) \
         + cos(tau*z)*sin(2*tau*x) + cos(tau*x)*cos(tau*y)*cos(tau*z) + sin(2*tau*x)*sin(tau*y) \
         + sin(2*tau*y)*sin(tau*z) + sin(2*tau*z)*sin(tau*x)",
    ),
    s(
        "pm-y",
        "±Y",
        "2*cos(tau*x)*cos(tau*y)*cos(tau*z) + sin(2*tau*x)*sin(tau*y) + sin(2*tau*y)*sin(tau*z) \
         + sin(2*tau*z)*sin(tau*x)",
    ),
    s(
        "c-pm-y",
        "C(±Y)",
        "-2*cos(tau*x)*cos(tau*y)*cos(tau*z) + sin(2*tau*x)*sin(tau*y) + sin(2*tau*y)*sin(tau*z) \
         + sin(2*tau*z)*sin(tau*x)",
    ),
    s(
        "c-i2-y**",
        "C(I2-Y**)",
        "2*(sin(2*tau*x)*cos(tau*y)*sin(tau*z) + sin(2*tau*y)*cos(tau*z)*sin(tau*x) \
         + sin(2*tau*z)*cos(tau*x)*sin(tau*y)) + cos(2*tau*x)*cos(2*tau*y) \
         + cos(2*tau*y)*cos(2*tau*z) + cos(2*tau*z)*cos(2*tau*x)",
    ),
    s(
        "w",
        "W",
        "cos(2*tau*x)*cos(tau*y) + cos(2*tau*y)*cos(tau*z) + cos(2*tau*z)*cos(tau*x) \
         - (cos(tau*x)*cos(2*tau*y) + cos(tau*y)*cos(2*tau*z) + cos(tau*z)*cos(2*tau*x))",
    ),
    s(
        "q*",
        "Q*",
        "(cos(tau*x) - 2*cos(tau*y))*cos(tau*z) - sqrt(3)*sin(tau*z)*(cos(tau*(x - y)) \
         - cos(tau*x)) + cos(tau*(x - y))*cos(tau*z)",
    ),
    s(
        "c-g",
        "C(G)",
        "3*(sin(tau*x)*cos(tau*y) + sin(tau*y)*cos(tau*z) + sin(tau*z)*cos(tau*x)) \
         + 2*(sin(3*tau*x)*cos(tau*y) + sin(3*tau*y)*cos(tau*z) + sin(3*tau*z)*cos(tau*x)) \
         - 2*(sin(tau*x)*cos(3*tau*y) + sin(tau*y)*cos(3*tau*z) + sin(tau*z)*cos(3*tau*x))",
    ),
    s(
        "slotted-p",
        "Slotted P",
        "-2*(cos(tau*x)*cos(tau*y) + cos(tau*y)*cos(tau*z) + cos(tau*z)*cos(tau*x)) \
         - 2*(cos(2*tau*x) + cos(2*tau*y) + cos(2*tau*z)) + cos(2*tau*x)*cos(tau*y) \
         + cos(2*tau*y)*cos(tau*z) + cos(2*tau*z)*cos(tau*x) \
         - (cos(tau*x)*cos(2*tau*y) + cos(tau*y)*cos(2*tau*z) + cos(tau*z)*cos(2*tau*x))",
    ),
];

/// Other spellings users reach for, and the canonical name each means.
pub static ALIASES: [(&str, &str); 14] = [
    ("g", "gyroid"),
    ("schoen-g", "gyroid"),
    ("diamond", "d"),
    ("schwarz-d", "d"),
    ("primitive", "p"),
    ("schwarz-p", "p"),
    ("i-wp", "iwp"),
    ("schoen-iwp", "iwp"),
    ("g'", "g-prime"),
    ("g'2", "g-prime-2"),
    ("d'", "d-prime"),
    ("±y", "pm-y"),
    ("c(±y)", "c-pm-y"),
    ("fischer-koch-s", "s"),
];

/// The surface with this canonical name or alias (case-insensitive).
pub fn lookup(name: &str) -> Option<&'static Surface> {
    let lower = name.to_lowercase();
    let canonical = ALIASES
        .iter()
        .find(|(alias, _)| *alias == lower)
        .map_or(lower.as_str(), |(_, target)| target);
    LIBRARY.iter().find(|s| s.name == canonical)
}

/// The canonical name closest to a misspelled one, for "did you mean" help.
pub fn suggest(name: &str) -> Option<&'static str> {
    let names = LIBRARY
        .iter()
        .map(|s| s.name)
        .chain(ALIASES.iter().map(|(a, _)| *a));
    crate::spelling::closest(name, names).and_then(|n| lookup(n).map(|s| s.name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_has_every_row_of_table_2_once() {
        assert_eq!(LIBRARY.len(), 27);
        let mut names: Vec<_> = LIBRARY.iter().map(|s| s.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), 27);
    }

    #[test]
    fn aliases_and_case_resolve() {
        assert_eq!(lookup("Gyroid").map(|s| s.name), Some("gyroid"));
        assert_eq!(lookup("schwarz-p").map(|s| s.name), Some("p"));
        assert_eq!(lookup("C-Y").map(|s| s.title), Some("C(Y)"));
        assert!(lookup("gyroyd").is_none());
        assert_eq!(suggest("gyroyd"), Some("gyroid"));
        assert_eq!(suggest("neovious"), Some("neovius"));
        for (alias, target) in ALIASES {
            assert_eq!(lookup(alias).map(|s| s.name), Some(target), "{alias}");
        }
    }
}
