//! Extended XYZ with a lattice: a count line, a comment line of `key=value` pairs holding
//! `Lattice="ax ay az bx by bz cx cy cz"` (and optionally `Properties=species:S:1:pos:R:3:…`),
//! then one atom per line with Cartesian positions.
//!
//! Invariants: positions are converted to fractional coordinates of the lattice (the columns
//! of `[a b c]`), always finite; the structure has no symmetry operations beyond the
//! identity; a missing, singular or overflowing lattice, a short file or a bad number is an
//! error at its line and column.

use super::{Crystal, CrystalError, Site, SymOp};

fn error(file: &str, line: usize, column: usize, message: impl Into<String>) -> CrystalError {
    CrystalError {
        file: file.to_string(),
        line,
        column,
        message: message.into(),
    }
}

/// `key=value` pairs of the comment line, values unquoted, with their 1-based columns.
fn pairs(line: &str) -> Vec<(String, String, usize)> {
    let chars: Vec<char> = line.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        while i < chars.len() && chars[i].is_whitespace() {
            i += 1;
        }
        let start = i;
        while i < chars.len() && chars[i] != '=' && !chars[i].is_whitespace() {
            i += 1;
        }
        let key: String = chars[start..i].iter().collect();
        if i >= chars.len() || chars[i] != '=' {
            continue;
        }
        i += 1;
        let value_column = i + 1;
        let value = if i < chars.len() && (chars[i] == '"' || chars[i] == '\'') {
            let quote = chars[i];
            let v0 = i + 1;
            i += 1;
            while i < chars.len() && chars[i] != quote {
                i += 1;
            }
            let v: String = chars[v0..i.min(chars.len())].iter().collect();
            i += 1;
            v
        } else {
            let v0 = i;
            while i < chars.len() && !chars[i].is_whitespace() {
                i += 1;
            }
            chars[v0..i].iter().collect()
        };
        out.push((key, value, value_column));
    }
    out
}

/// Reads an extended XYZ file's first frame.
pub fn read(file: &str, bytes: &[u8]) -> Result<Crystal, CrystalError> {
    let text = std::str::from_utf8(bytes).map_err(|_| error(file, 0, 0, "not UTF-8 text"))?;
    let lines: Vec<&str> = text.lines().collect();
    let count_text = lines.first().map_or("", |l| l.trim());
    let count: usize = count_text.parse().map_err(|_| {
        error(
            file,
            1,
            1,
            format!("expected the number of atoms, found `{count_text}`"),
        )
    })?;
    let comment = lines
        .get(1)
        .ok_or_else(|| error(file, 2, 0, "missing the comment line with `Lattice=\"…\"`"))?;
    let pairs = pairs(comment);
    let cell = XyzLattice::new(file, &pairs)?;
    let columns = match pairs
        .iter()
        .find(|(k, ..)| k.eq_ignore_ascii_case("properties"))
    {
        None => (0, 1),
        Some((_, spec, column)) => properties(file, spec, *column)?,
    };
    // The count is the file's word: reserve no more than there are lines for.
    let mut sites = Vec::with_capacity(count.min(lines.len().saturating_sub(2)));
    for n in 0..count {
        let line = lines.get(n + 2).ok_or_else(|| {
            error(
                file,
                n + 3,
                0,
                format!("expected {count} atoms, the file ends after {n}"),
            )
        })?;
        sites.push(cell.atom(file, n, line, columns)?);
    }
    Ok(Crystal {
        name: comment.trim().to_string(),
        lengths: cell.lengths,
        angles: [cell.angle(1, 2), cell.angle(0, 2), cell.angle(0, 1)],
        sites,
        operations: vec![SymOp::IDENTITY],
    })
}

/// The comment line's lattice.
struct XyzLattice {
    /// a, b, c.
    vectors: [[f64; 3]; 3],
    lengths: [f64; 3],
    /// Cartesian to fractional coordinates.
    to_fractional: [[f64; 3]; 3],
}

impl XyzLattice {
    /// The `Lattice` of the comment line's `pairs`: nine finite numbers spanning a volume.
    fn new(file: &str, pairs: &[(String, String, usize)]) -> Result<XyzLattice, CrystalError> {
        let lattice = pairs
            .iter()
            .find(|(k, ..)| k.eq_ignore_ascii_case("lattice"))
            .ok_or_else(|| {
                error(
                    file,
                    2,
                    0,
                    "no `Lattice=\"ax ay az bx by bz cx cy cz\"` on the comment line",
                )
            })?;
        let numbers: Vec<f64> = lattice
            .1
            .split_whitespace()
            .map(str::parse::<f64>)
            .collect::<Result<_, _>>()
            .map_err(|_| error(file, 2, lattice.2, "`Lattice` must be 9 numbers"))?;
        if numbers.len() != 9 || numbers.iter().any(|v| !v.is_finite()) {
            return Err(error(
                file,
                2,
                lattice.2,
                "`Lattice` must be 9 finite numbers",
            ));
        }
        let vectors: [[f64; 3]; 3] =
            std::array::from_fn(|v| std::array::from_fn(|c| numbers[3 * v + c]));
        // Columns of M are a, b, c: r = M f.
        let m: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| vectors[c][r]));
        let lengths = vectors.map(|v| v.iter().map(|c| c * c).sum::<f64>().sqrt());
        let flat = || {
            error(
                file,
                2,
                lattice.2,
                "the lattice vectors span no volume (one is zero or they lie in a plane)",
            )
        };
        // Finite numbers can still overflow in the lengths (`1e308`), which would make the
        // flatness test below meaningless and put atoms at NaN.
        let out_of_range = || {
            error(
                file,
                2,
                lattice.2,
                "`Lattice` is out of range: its lengths or inverse overflow",
            )
        };
        if lengths.iter().any(|v| !v.is_finite()) {
            return Err(out_of_range());
        }
        // Judged by the volume relative to the edges' lengths, as a CIF's angles are, so that
        // neither the unit nor the cell's size decides whether it is flat.
        let unit_volume = det3(m) / (lengths[0] * lengths[1] * lengths[2]);
        // NaN (a zero edge) is flat too.
        let spans = (unit_volume * unit_volume).partial_cmp(&super::FLAT_CELL);
        if spans != Some(std::cmp::Ordering::Greater) {
            return Err(flat());
        }
        let to_fractional = invert(m).ok_or_else(flat)?;
        if to_fractional.iter().flatten().any(|v| !v.is_finite()) {
            return Err(out_of_range());
        }
        Ok(XyzLattice {
            vectors,
            lengths,
            to_fractional,
        })
    }

    /// The angle between vectors `i` and `j`, in degrees.
    fn angle(&self, i: usize, j: usize) -> f64 {
        let dot: f64 = (0..3)
            .map(|c| self.vectors[i][c] * self.vectors[j][c])
            .sum();
        (dot / (self.lengths[i] * self.lengths[j]))
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    /// Atom `n` (0-based) from its `line`, whose species and first position columns are
    /// `columns`.
    fn atom(
        &self,
        file: &str,
        n: usize,
        line: &str,
        (species_column, position_column): (usize, usize),
    ) -> Result<Site, CrystalError> {
        let number = n + 3;
        let words: Vec<(usize, &str)> = word_columns(line);
        let word = |c: usize| {
            words.get(c).copied().ok_or_else(|| {
                error(
                    file,
                    number,
                    0,
                    format!("atom {}: expected at least {} columns", n + 1, c + 1),
                )
            })
        };
        let (_, species) = word(species_column)?;
        let mut r = [0.0; 3];
        for (axis, v) in r.iter_mut().enumerate() {
            let (column, text) = word(position_column + axis)?;
            *v = text
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    error(
                        file,
                        number,
                        column,
                        format!("expected a coordinate, found `{text}`"),
                    )
                })?;
        }
        let fract: [f64; 3] =
            std::array::from_fn(|i| (0..3).map(|j| self.to_fractional[i][j] * r[j]).sum());
        if fract.iter().any(|f| !f.is_finite()) {
            return Err(error(
                file,
                number,
                0,
                format!("atom {}: its fractional coordinates overflow", n + 1),
            ));
        }
        let element: String = species
            .chars()
            .take_while(|c| c.is_ascii_alphabetic())
            .collect();
        Ok(Site {
            label: format!("{element}{}", n + 1),
            species: element,
            fract,
        })
    }
}

fn det3(m: [[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// The inverse of `m`, whose columns the caller has checked span a volume.
fn invert(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = det3(m);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let adj = [
        [c(1, 2, 1, 2), -c(0, 2, 1, 2), c(0, 1, 1, 2)],
        [-c(1, 2, 0, 2), c(0, 2, 0, 2), -c(0, 1, 0, 2)],
        [c(1, 2, 0, 1), -c(0, 2, 0, 1), c(0, 1, 0, 1)],
    ];
    Some(adj.map(|row| row.map(|v| v / det)))
}

/// Whitespace-separated words with their 1-based columns.
fn word_columns(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, c) in line.char_indices() {
        match (c.is_whitespace(), start) {
            (false, None) => start = Some(i),
            (true, Some(s)) => {
                out.push((s + 1, &line[s..i]));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s + 1, &line[s..]));
    }
    out
}

/// The word columns of `species:S:1` and the first of `pos:R:3` in a `Properties` spec.
fn properties(file: &str, spec: &str, column: usize) -> Result<(usize, usize), CrystalError> {
    let fields: Vec<&str> = spec.split(':').collect();
    if !fields.len().is_multiple_of(3) {
        return Err(error(
            file,
            2,
            column,
            "`Properties` must be name:type:count triples",
        ));
    }
    let (mut species, mut position, mut at) = (None, None, 0usize);
    for triple in fields.chunks(3) {
        let count: usize = triple[2].parse().map_err(|_| {
            error(
                file,
                2,
                column,
                format!("bad column count `{}` in `Properties`", triple[2]),
            )
        })?;
        match (triple[0].to_ascii_lowercase().as_str(), triple[1], count) {
            ("species", "S", 1) => species = Some(at),
            ("pos", "R", 3) => position = Some(at),
            _ => {}
        }
        at = at.checked_add(count).ok_or_else(|| {
            error(
                file,
                2,
                column,
                "the counts of `Properties` add up to more columns than a line can have",
            )
        })?;
    }
    match (species, position) {
        (Some(s), Some(p)) => Ok((s, p)),
        _ => Err(error(
            file,
            2,
            column,
            "`Properties` needs `species:S:1` and `pos:R:3`",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cartesian_positions_become_fractional() {
        let text = "2\nLattice=\"4 0 0 0 5 0 0 0 2\" Properties=species:S:1:pos:R:3 pbc=\"T T T\"\n\
                    Si 1.0 2.5 0.5\nO 2 0 1\n";
        let c = read("t.xyz", text.as_bytes()).unwrap();
        assert_eq!(c.sites.len(), 2);
        assert_eq!(c.sites[0].fract, [0.25, 0.5, 0.25]);
        assert_eq!(c.sites[1].species, "O");
        assert_eq!(c.lengths, [4.0, 5.0, 2.0]);
        assert_eq!(c.angles, [90.0, 90.0, 90.0]);
    }

    /// Found by `cargo xtask fuzz` (tests/fuzz_corpus/crystal-xyz): each of these panicked
    /// (an overflowing column sum, a capacity overflow) or gave atoms at NaN.
    #[test]
    fn hostile_counts_and_overflowing_numbers_are_errors() {
        let e = read(
            "t.xyz",
            b"2\nLattice=\"4 0 0 0 5 0 0 0 2\"Properties=::18446744073709551615:::3\n",
        )
        .unwrap_err();
        assert_eq!((e.line, e.column), (2, 39), "{e}");
        assert!(e.message.contains("add up to more columns"), "{e}");
        // A count far past the lines: an error about the short file, not an allocation.
        let e = read(
            "t.xyz",
            b"18446744073709551615\nLattice=\"4 0 0 0 5 0 0 0 2\"\nSi 0 0 0\n",
        )
        .unwrap_err();
        assert_eq!(e.line, 4, "{e}");
        assert!(e.message.contains("the file ends after 1"), "{e}");
        // Finite numbers whose lengths and inverse overflow.
        let e = read("t.xyz", b"1\nLattice=\"4 0 0 1 5 0 1e308 5 2\"\nSi 0 2 0\n").unwrap_err();
        assert_eq!((e.line, e.column), (2, 9), "{e}");
        assert!(e.message.contains("out of range"), "{e}");
        // A fine lattice, but a position whose fractional coordinate overflows.
        let e = read(
            "t.xyz",
            b"2\nLattice=\"1e-4 0 0 0 1e-4 0 0 0 1e4\"\nSi 0 0 0\nO 1e305 0 0\n",
        )
        .unwrap_err();
        assert_eq!(e.line, 4, "{e}");
        assert!(e.message.contains("atom 2"), "{e}");
    }

    #[test]
    fn errors_name_line_and_column() {
        let text = "2\nLattice=\"4 0 0 0 5 0 0 0 2\"\nSi 1.0 2.5 0.5\nO 2 zero 1\n";
        let e = read("t.xyz", text.as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (4, 5), "{e}");
        let e = read("t.xyz", b"1\nno lattice\nSi 0 0 0\n").unwrap_err();
        assert_eq!(e.line, 2, "{e}");
    }

    #[test]
    fn a_flat_lattice_is_an_error_whatever_its_size() {
        let with = |lattice: &str| format!("1\nLattice=\"{lattice}\"\nSi 0 0 0\n");
        // Kilometre-long edges, c in the plane of a and b but for 1e-9: a determinant of
        // 1e-3 (an absolute test passes it) in a cell whose volume is ~7e-13 of a·b·c.
        let e = read("t.xyz", with("1000 0 0 0 1000 0 1000 1000 1e-9").as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (2, 9), "{e}");
        assert!(e.message.contains("span no volume"), "{e}");
        let e = read("t.xyz", with("4 0 0 0 5 0 0 0 0").as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (2, 9), "{e}");
        // A tiny but square cell is a cell: 1e-5 edges, determinant 1e-15.
        let c = read("t.xyz", with("1e-5 0 0 0 1e-5 0 0 0 1e-5").as_bytes()).unwrap();
        assert_eq!(c.angles, [90.0, 90.0, 90.0]);
    }
}
