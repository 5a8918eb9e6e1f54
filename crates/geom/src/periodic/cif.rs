//! A CIF 1.1 reader for crystal structures: one data block, its cell, its symmetry operations
//! (`_space_group_symop_operation_xyz`, CIF 1.1's `_symmetry_equiv_pos_as_xyz`, or
//! `_symmetry_equivalent_pos_as_xyz`, in a loop or alone) and its atom sites (`_atom_site_fract_x/y/z` with labels and type symbols; numbers
//! may carry uncertainties like `0.1234(5)`).
//!
//! Invariants:
//! - Tags are compared lower case with `.` read as `_`, so DDLm names (`_atom_site.fract_x`)
//!   are the same items.
//! - Whatever would change the structure but is not understood — a second data block, save
//!   frames, Cartesian sites, a space group given only by name, an operation that does not
//!   parse or takes a site out of the range of `f64` — is an error at its line and column,
//!   never skipped. Items that do not change the
//!   structure (occupancies, displacements, bibliography) are read past.

use super::{Crystal, CrystalError, Site, SymOp};

#[derive(Clone, Debug, PartialEq)]
enum Kind {
    Tag,
    Loop,
    Data,
    /// `save_`, `global_`, `stop_`: constructs this reader does not support.
    Reserved,
    Value,
}

#[derive(Clone, Debug)]
struct Token {
    kind: Kind,
    text: String,
    line: usize,
    column: usize,
    /// Quoted or a text field: never a tag or keyword, and never `?`/`.`-as-unknown.
    quoted: bool,
}

struct Reader<'a> {
    file: &'a str,
}

impl Reader<'_> {
    fn error(&self, line: usize, column: usize, message: impl Into<String>) -> CrystalError {
        CrystalError {
            file: self.file.to_string(),
            line,
            column,
            message: message.into(),
        }
    }

    fn at(&self, token: &Token, message: impl Into<String>) -> CrystalError {
        self.error(token.line, token.column, message)
    }

    fn tokenize(&self, text: &str) -> Result<Vec<Token>, CrystalError> {
        let mut tokens = Vec::new();
        let lines: Vec<&str> = text.lines().collect();
        let mut n = 0;
        while n < lines.len() {
            let line = lines[n];
            let number = n + 1;
            if let Some(first) = line.strip_prefix(';') {
                // A text field runs to the next line starting with `;`.
                let mut body = first.to_string();
                let mut end = n + 1;
                while end < lines.len() && !lines[end].starts_with(';') {
                    body.push('\n');
                    body.push_str(lines[end]);
                    end += 1;
                }
                if end == lines.len() {
                    return Err(self.error(
                        number,
                        1,
                        "text field opened with `;` is never closed",
                    ));
                }
                tokens.push(Token {
                    kind: Kind::Value,
                    text: body,
                    line: number,
                    column: 1,
                    quoted: true,
                });
                n = end + 1;
                continue;
            }
            let chars: Vec<(usize, char)> = line.char_indices().collect();
            let mut i = 0;
            while i < chars.len() {
                let (start, c) = chars[i];
                if c.is_whitespace() {
                    i += 1;
                    continue;
                }
                let column = i + 1;
                if c == '#' {
                    break;
                }
                if c == '\'' || c == '"' {
                    // A quote closes only when whitespace (or the line's end) follows it.
                    let mut j = i + 1;
                    let close = loop {
                        if j >= chars.len() {
                            break None;
                        }
                        if chars[j].1 == c && chars.get(j + 1).is_none_or(|n| n.1.is_whitespace()) {
                            break Some(j);
                        }
                        j += 1;
                    };
                    let Some(close) = close else {
                        return Err(self.error(number, column, format!("unclosed {c} quote")));
                    };
                    let text: String = chars[i + 1..close].iter().map(|(_, c)| *c).collect();
                    tokens.push(Token {
                        kind: Kind::Value,
                        text,
                        line: number,
                        column,
                        quoted: true,
                    });
                    i = close + 1;
                    continue;
                }
                let mut j = i;
                while j < chars.len() && !chars[j].1.is_whitespace() {
                    j += 1;
                }
                let end = chars.get(j).map_or(line.len(), |(b, _)| *b);
                let word = &line[start..end];
                let lower = word.to_ascii_lowercase();
                let kind = if word.starts_with('_') {
                    Kind::Tag
                } else if lower == "loop_" {
                    Kind::Loop
                } else if lower.starts_with("data_") {
                    Kind::Data
                } else if lower.starts_with("save_")
                    || lower.starts_with("global_")
                    || lower.starts_with("stop_")
                {
                    Kind::Reserved
                } else {
                    Kind::Value
                };
                tokens.push(Token {
                    kind,
                    text: word.to_string(),
                    line: number,
                    column,
                    quoted: false,
                });
                i = j;
            }
            n += 1;
        }
        Ok(tokens)
    }
}

/// A tag's normal form: lower case, DDLm dots read as underscores.
fn normal(tag: &str) -> String {
    tag.to_ascii_lowercase().replace('.', "_")
}

struct Block {
    name: String,
    /// First line of the block (for errors about missing items).
    line: usize,
    items: Vec<(Token, Token)>,
    loops: Vec<Loop>,
}

struct Loop {
    tags: Vec<Token>,
    rows: Vec<Vec<Token>>,
}

impl Loop {
    fn column(&self, tag: &str) -> Option<usize> {
        self.tags.iter().position(|t| normal(&t.text) == tag)
    }
}

impl Block {
    fn item(&self, tag: &str) -> Option<&(Token, Token)> {
        self.items.iter().find(|(t, _)| normal(&t.text) == tag)
    }

    fn find_loop(&self, tag: &str) -> Option<&Loop> {
        self.loops.iter().find(|l| l.column(tag).is_some())
    }

    /// The values of `tag`: a loop's column, or a single item; with the tag's token.
    fn values(&self, tag: &str) -> Option<(&Token, Vec<&Token>)> {
        if let Some(l) = self.find_loop(tag) {
            let c = l.column(tag)?;
            return Some((&l.tags[c], l.rows.iter().map(|r| &r[c]).collect()));
        }
        self.item(tag).map(|(t, v)| (t, vec![v]))
    }
}

/// Reads the crystal of the single data block of a CIF file.
pub fn read(file: &str, bytes: &[u8]) -> Result<Crystal, CrystalError> {
    let reader = Reader { file };
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        reader.error(line, 0, "not UTF-8 (or ASCII) text")
    })?;
    let tokens = reader.tokenize(text)?;
    let block = parse_block(&reader, tokens)?;
    let lengths = cell_values(
        &reader,
        &block,
        ["a", "b", "c"].map(|a| format!("_cell_length_{a}")),
        None,
        (|v| v > 0.0, "positive"),
    )?;
    let angle_tags = ["alpha", "beta", "gamma"].map(|a| format!("_cell_angle_{a}"));
    let angles = cell_values(
        &reader,
        &block,
        angle_tags.clone(),
        Some(90.0),
        (
            |v| v > 0.0 && v < 180.0,
            "strictly between 0 and 180 degrees",
        ),
    )?;
    if super::unit_volume_squared(angles) <= super::FLAT_CELL {
        // Shown at the first angle the file gives (a cell of defaults is never flat).
        let first = angle_tags
            .iter()
            .filter_map(|t| block.item(t))
            .min_by_key(|(tag, _)| (tag.line, tag.column));
        let [a, b, g] = angles;
        let message = format!(
            "the cell angles α = {a}°, β = {b}°, γ = {g}° give a cell of no volume: \
             1 − cos²α − cos²β − cos²γ + 2 cosα cosβ cosγ must be positive"
        );
        return Err(match first {
            Some((tag, _)) => reader.at(tag, message),
            None => reader.error(block.line, 0, message),
        });
    }
    let operations = operations(&reader, &block)?;
    let sites = sites(&reader, &block)?;
    // Numbers near the range of `f64` can overflow in `W r + w`: such an image has no place
    // in the cell (and would reach the models as NaN).
    for (op, token) in &operations {
        if let Some(site) = sites
            .iter()
            .find(|s| op.apply(s.fract).iter().any(|c| !c.is_finite()))
        {
            let message = format!("symmetry operation overflows on site `{}`", site.label);
            return Err(match token {
                Some(t) => reader.at(t, message),
                None => reader.error(block.line, 0, message),
            });
        }
    }
    let operations = operations.into_iter().map(|(op, _)| op).collect();
    Ok(Crystal {
        name: block.name,
        lengths,
        angles,
        sites,
        operations,
    })
}

fn parse_block(reader: &Reader<'_>, tokens: Vec<Token>) -> Result<Block, CrystalError> {
    let mut block: Option<Block> = None;
    let mut i = 0;
    while i < tokens.len() {
        let token = &tokens[i];
        match token.kind {
            Kind::Data => {
                if let Some(b) = &block {
                    return Err(reader.at(
                        token,
                        format!(
                            "a second data block `{}` after `data_{}`: one crystal per file is read",
                            token.text, b.name
                        ),
                    ));
                }
                block = Some(Block {
                    name: token.text[5..].to_string(),
                    line: token.line,
                    items: Vec::new(),
                    loops: Vec::new(),
                });
                i += 1;
                continue;
            }
            Kind::Reserved => {
                return Err(reader.at(token, format!("`{}` frames are not supported", token.text)));
            }
            _ => {}
        }
        let Some(b) = block.as_mut() else {
            return Err(reader.at(token, "data before the first `data_` block header"));
        };
        match token.kind {
            Kind::Tag => {
                let value = tokens.get(i + 1).filter(|v| v.kind == Kind::Value);
                let Some(value) = value else {
                    return Err(reader.at(token, format!("`{}` has no value", token.text)));
                };
                b.items.push((token.clone(), value.clone()));
                i += 2;
            }
            Kind::Loop => {
                let mut j = i + 1;
                let mut tags = Vec::new();
                while j < tokens.len() && tokens[j].kind == Kind::Tag {
                    tags.push(tokens[j].clone());
                    j += 1;
                }
                if tags.is_empty() {
                    return Err(reader.at(token, "`loop_` without tags"));
                }
                let mut values = Vec::new();
                while j < tokens.len() && tokens[j].kind == Kind::Value {
                    values.push(tokens[j].clone());
                    j += 1;
                }
                if !values.len().is_multiple_of(tags.len()) {
                    return Err(reader.at(
                        token,
                        format!(
                            "loop of {} tags has {} values, not a multiple of {}",
                            tags.len(),
                            values.len(),
                            tags.len()
                        ),
                    ));
                }
                let rows = values.chunks(tags.len()).map(<[Token]>::to_vec).collect();
                b.loops.push(Loop { tags, rows });
                i = j;
            }
            _ => {
                return Err(reader.at(token, format!("value `{}` without a tag", token.text)));
            }
        }
    }
    block.ok_or_else(|| reader.error(1, 0, "no `data_` block"))
}

/// A number, without its standard uncertainty: `0.1234(5)` is 0.1234.
fn number(reader: &Reader<'_>, tag: &str, token: &Token) -> Result<f64, CrystalError> {
    let text = token.text.trim();
    let digits = match text.find('(') {
        Some(open) if text.ends_with(')') => &text[..open],
        _ => text,
    };
    match digits.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(reader.at(
            token,
            format!("`{tag}` must be a number, found `{}`", token.text),
        )),
    }
}

/// The three values of `tags`, each passing `valid` (described by `expected`), or `default`.
fn cell_values(
    reader: &Reader<'_>,
    block: &Block,
    tags: [String; 3],
    default: Option<f64>,
    (valid, expected): (fn(f64) -> bool, &str),
) -> Result<[f64; 3], CrystalError> {
    let mut out = [0.0; 3];
    for (o, tag) in out.iter_mut().zip(&tags) {
        *o = match block.item(tag) {
            Some((_, value)) => {
                let v = number(reader, tag, value)?;
                if !valid(v) {
                    return Err(reader.at(
                        value,
                        format!("`{tag}` must be {expected}, found `{}`", value.text),
                    ));
                }
                v
            }
            None => match default {
                Some(d) => d,
                None => {
                    return Err(reader.error(
                        block.line,
                        0,
                        format!("missing `{tag}` in `data_{}`", block.name),
                    ));
                }
            },
        };
    }
    Ok(out)
}

const SYMOP_TAGS: [&str; 3] = [
    "_space_group_symop_operation_xyz",
    "_symmetry_equiv_pos_as_xyz",
    "_symmetry_equivalent_pos_as_xyz",
];

/// The operations, each with the token it was read from (none for the implied identity).
fn operations(
    reader: &Reader<'_>,
    block: &Block,
) -> Result<Vec<(SymOp, Option<Token>)>, CrystalError> {
    let Some((_, values)) = SYMOP_TAGS.iter().find_map(|t| block.values(t)) else {
        // Without operations the sites are the whole structure, which is right only for P1.
        let named = [
            "_symmetry_space_group_name_h-m",
            "_space_group_name_h-m_alt",
        ]
        .iter()
        .find_map(|t| block.item(t));
        if let Some((tag, value)) = named {
            let compact: String = value.text.chars().filter(|c| !c.is_whitespace()).collect();
            if !compact.eq_ignore_ascii_case("P1") {
                return Err(reader.at(
                    tag,
                    format!(
                        "space group `{}` is given by name only: list its operations in a \
                         `_space_group_symop_operation_xyz` loop",
                        value.text
                    ),
                ));
            }
        }
        return Ok(vec![(SymOp::IDENTITY, None)]);
    };
    values
        .into_iter()
        .map(|token| {
            let op = parse_operation(&token.text).map_err(|(offset, message)| {
                let column = token.column + usize::from(token.quoted) + offset;
                reader.error(
                    token.line,
                    column,
                    format!("symmetry operation `{}`: {message}", token.text),
                )
            })?;
            Ok((op, Some(token.clone())))
        })
        .collect()
}

/// Parses `x,y,z`, `-y+1/2,x,z+3/4`, `1/2+x-y,2*z,0.25-x`: three affine expressions in x, y, z.
/// Errors carry the character offset in the text.
pub fn parse_operation(text: &str) -> Result<SymOp, (usize, String)> {
    let parts: Vec<(usize, &str)> = {
        let mut parts = Vec::new();
        let mut start = 0;
        for (i, c) in text.char_indices() {
            if c == ',' {
                parts.push((start, &text[start..i]));
                start = i + 1;
            }
        }
        parts.push((start, &text[start..]));
        parts
    };
    if parts.len() != 3 {
        return Err((
            0,
            format!("expected 3 comma-separated parts, found {}", parts.len()),
        ));
    }
    let mut op = SymOp {
        rotation: [[0.0; 3]; 3],
        translation: [0.0; 3],
    };
    for (row, (offset, part)) in parts.into_iter().enumerate() {
        let (coefficients, constant) = parse_affine(part).map_err(|(at, m)| (offset + at, m))?;
        op.rotation[row] = coefficients;
        op.translation[row] = constant;
    }
    Ok(op)
}

fn parse_affine(text: &str) -> Result<([f64; 3], f64), (usize, String)> {
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    let mut coefficients = [0.0; 3];
    let mut constant = 0.0;
    let mut terms = 0;
    let skip = |i: &mut usize| {
        while *i < chars.len() && chars[*i].is_whitespace() {
            *i += 1;
        }
    };
    loop {
        skip(&mut i);
        if i == chars.len() {
            break;
        }
        let mut sign = 1.0;
        if chars[i] == '+' || chars[i] == '-' {
            if chars[i] == '-' {
                sign = -1.0;
            }
            i += 1;
            skip(&mut i);
        } else if terms > 0 {
            return Err((i, format!("expected `+` or `-`, found `{}`", chars[i])));
        }
        let start = i;
        while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
            i += 1;
        }
        let mut value = None;
        if i > start {
            let numerator: String = chars[start..i].iter().collect();
            let mut v = numerator
                .parse::<f64>()
                .map_err(|_| (start, format!("bad number `{numerator}`")))?;
            if i < chars.len() && chars[i] == '/' {
                let d0 = i + 1;
                i += 1;
                while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                    i += 1;
                }
                let denominator: String = chars[d0..i].iter().collect();
                match denominator.parse::<f64>() {
                    Ok(d) if d != 0.0 => v /= d,
                    _ => return Err((d0, "expected a non-zero denominator".to_string())),
                }
            }
            if !v.is_finite() {
                return Err((start, "the number is out of range".to_string()));
            }
            value = Some(v);
            skip(&mut i);
            if i < chars.len() && chars[i] == '*' {
                i += 1;
                skip(&mut i);
            }
        }
        let axis = chars.get(i).and_then(|c| match c.to_ascii_lowercase() {
            'x' => Some(0),
            'y' => Some(1),
            'z' => Some(2),
            _ => None,
        });
        match (value, axis) {
            (v, Some(axis)) => {
                coefficients[axis] += sign * v.unwrap_or(1.0);
                i += 1;
            }
            (Some(v), None) => constant += sign * v,
            (None, None) => {
                let found = chars
                    .get(i)
                    .map_or("the end".to_string(), |c| format!("`{c}`"));
                return Err((i, format!("expected a number or x, y, z, found {found}")));
            }
        }
        terms += 1;
    }
    if terms == 0 {
        return Err((0, "empty part".to_string()));
    }
    if !constant.is_finite() || coefficients.iter().any(|c| !c.is_finite()) {
        return Err((
            0,
            "the numbers add up past the range of a number".to_string(),
        ));
    }
    Ok((coefficients, constant))
}

/// The element of a type symbol or label: its leading letters (`Si4+` and `Si1` give `Si`).
fn element(text: &str) -> String {
    text.chars()
        .take_while(|c| c.is_ascii_alphabetic())
        .collect()
}

fn sites(reader: &Reader<'_>, block: &Block) -> Result<Vec<Site>, CrystalError> {
    let Some(sites) = block.find_loop("_atom_site_fract_x") else {
        if let Some(l) = block.find_loop("_atom_site_cartn_x") {
            let c = l.column("_atom_site_cartn_x").unwrap_or(0);
            return Err(reader.at(
                &l.tags[c],
                "Cartesian atom sites are not supported: give `_atom_site_fract_x/y/z`",
            ));
        }
        if let Some((tag, _)) = block.item("_atom_site_fract_x") {
            return Err(reader.at(tag, "a single atom site outside a loop is not supported"));
        }
        return Err(reader.error(
            block.line,
            0,
            format!("no `_atom_site_fract_x` loop in `data_{}`", block.name),
        ));
    };
    let column = |tag: &str| sites.column(tag);
    let axes = ["x", "y", "z"].map(|a| format!("_atom_site_fract_{a}"));
    let mut fract_columns = [0; 3];
    for (c, tag) in fract_columns.iter_mut().zip(&axes) {
        *c = column(tag).ok_or_else(|| {
            reader.at(&sites.tags[0], format!("the atom-site loop has no `{tag}`"))
        })?;
    }
    let label = column("_atom_site_label");
    let symbol = column("_atom_site_type_symbol");
    if label.is_none() && symbol.is_none() {
        return Err(reader.at(
            &sites.tags[0],
            "the atom-site loop has neither `_atom_site_label` nor `_atom_site_type_symbol`",
        ));
    }
    let mut out = Vec::with_capacity(sites.rows.len());
    for (n, row) in sites.rows.iter().enumerate() {
        let mut fract = [0.0; 3];
        for (axis, &c) in fract_columns.iter().enumerate() {
            fract[axis] = number(reader, &axes[axis], &row[c])?;
        }
        let label_text = label.map(|c| row[c].text.clone());
        let species_token = symbol.map(|c| &row[c]).or(label.map(|c| &row[c]));
        let species = species_token.map(|t| element(&t.text)).unwrap_or_default();
        if species.is_empty() {
            let token = species_token.unwrap_or(&row[fract_columns[0]]);
            return Err(reader.at(
                token,
                format!("atom site {} has no element in `{}`", n + 1, token.text),
            ));
        }
        out.push(Site {
            label: label_text.unwrap_or_else(|| format!("{species}{}", n + 1)),
            species,
            fract,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operations_parse_as_affine_maps() {
        let op = parse_operation("-y+1/2, x, z+3/4").unwrap();
        assert_eq!(op.apply([0.1, 0.2, 0.3]), [0.5 - 0.2, 0.1, 0.3 + 0.75]);
        let op = parse_operation("1/2+x-y,2*z,0.25-X").unwrap();
        assert_eq!(
            op.rotation,
            [[1.0, -1.0, 0.0], [0.0, 0.0, 2.0], [-1.0, 0.0, 0.0]]
        );
        assert_eq!(op.translation, [0.5, 0.0, 0.25]);
        assert_eq!(parse_operation("x,y").unwrap_err().0, 0);
        let (at, message) = parse_operation("x,y+q,z").unwrap_err();
        assert_eq!(at, 4, "{message}");
    }

    const P1_HEADER: &str = "data_t\n_cell_length_a 5\n_cell_length_b 5\n_cell_length_c 5\n";

    /// CIF 1.1's own name for the operations loop; it used to be read past, leaving P1.
    #[test]
    fn the_cif_1_1_operations_tag_is_read() {
        let text = format!(
            "{P1_HEADER}loop_\n_symmetry_equiv_pos_as_xyz\n'x,y,z'\n'-x,-y,z+1/2'\n\
             loop_\n_atom_site_label\n_atom_site_fract_x\n_atom_site_fract_y\n\
             _atom_site_fract_z\nZn1 0.25 0.5 0.125\n"
        );
        let c = read("t.cif", text.as_bytes()).unwrap();
        assert_eq!(c.operations.len(), 2);
        assert_eq!(
            c.operations[1].apply([0.25, 0.5, 0.125]),
            [-0.25, -0.5, 0.625]
        );
    }

    /// Found by `cargo xtask fuzz` (tests/fuzz_corpus/crystal-cif): an operation whose
    /// number overflowed, or that overflowed on a site, put atoms at NaN.
    #[test]
    fn operations_that_overflow_are_errors() {
        let huge = "1".repeat(330);
        let (at, message) = parse_operation(&format!("y,-z+{huge}-x+1/2,-y")).unwrap_err();
        assert_eq!(at, 5, "{message}");
        let (at, message) =
            parse_operation(&format!("x+{0}+{0},y,z", "9".repeat(308))).unwrap_err();
        assert_eq!(at, 0, "{message}");
        let text = format!(
            "{P1_HEADER}loop_\n_space_group_symop_operation_xyz\n'x,y,z'\n'2*x,y,z'\n\
             loop_\n_atom_site_label\n_atom_site_fract_x\n_atom_site_fract_y\n\
             _atom_site_fract_z\nNa1 0 0 0\nCl1 1e308 0.5 0.5\n"
        );
        let e = read("t.cif", text.as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (8, 1), "{e}");
        assert!(e.message.contains("`Cl1`"), "{e}");
    }

    #[test]
    fn uncertainties_are_dropped_and_quotes_kept_whole() {
        let text = "data_t\n_cell_length_a 5.1(2)\n_cell_length_b 5\n_cell_length_c 5\n\
                    _symmetry_space_group_name_H-M 'P 1'\nloop_\n_atom_site_label\n\
                    _atom_site_fract_x\n_atom_site_fract_y\n_atom_site_fract_z\n\
                    Si1 0.1234(5) 0.5 0.25 # comment\n";
        let c = read("t.cif", text.as_bytes()).unwrap();
        assert_eq!(c.lengths, [5.1, 5.0, 5.0]);
        assert_eq!(c.sites[0].fract, [0.1234, 0.5, 0.25]);
        assert_eq!(c.sites[0].species, "Si");
        assert_eq!(c.operations, vec![SymOp::IDENTITY]);
    }

    /// A P1 cell with the given angle lines, and one atom.
    fn cell_with(angles: &str) -> String {
        format!(
            "data_t\n_cell_length_a 5\n_cell_length_b 5\n_cell_length_c 5\n{angles}\
             _symmetry_space_group_name_H-M 'P 1'\nloop_\n_atom_site_label\n\
             _atom_site_fract_x\n_atom_site_fract_y\n_atom_site_fract_z\nSi1 0 0 0\n"
        )
    }

    #[test]
    fn cell_angles_must_lie_strictly_between_0_and_180_degrees() {
        let e = read("t.cif", cell_with("_cell_angle_gamma 180\n").as_bytes()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.cif:5:19: `_cell_angle_gamma` must be strictly between 0 and 180 degrees, \
             found `180`"
        );
        let e = read("t.cif", cell_with("_cell_angle_beta 0.0(1)\n").as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (5, 18), "{e}");
        let e = read("t.cif", cell_with("_cell_angle_alpha 270\n").as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (5, 19), "{e}");
        let e = read("t.cif", cell_with("_cell_angle_alpha -90\n").as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (5, 19), "{e}");
        let c = read("t.cif", cell_with("_cell_angle_gamma 179.9\n").as_bytes()).unwrap();
        assert_eq!(c.angles, [90.0, 90.0, 179.9]);
    }

    #[test]
    fn angles_no_three_edges_can_have_are_an_error_at_the_first_angle() {
        // α + β = γ: the third edge lies in the plane of the other two (volume exactly 0).
        let flat = "_cell_angle_alpha 60\n_cell_angle_beta 60\n_cell_angle_gamma 120\n";
        let e = read("t.cif", cell_with(flat).as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (5, 1), "{e}");
        assert!(e.message.contains("no volume"), "{e}");
        // α + β < γ: no vectors have these angles (the volume would be imaginary).
        let impossible = "_cell_angle_gamma 150\n_cell_angle_alpha 30\n_cell_angle_beta 30\n";
        let e = read("t.cif", cell_with(impossible).as_bytes()).unwrap_err();
        assert_eq!((e.line, e.column), (5, 1), "{e}");
        assert!(
            {
                let c = [30f64, 30.0, 150.0].map(|d| d.to_radians().cos());
                1.0 - c[0] * c[0] - c[1] * c[1] - c[2] * c[2] + 2.0 * c[0] * c[1] * c[2]
            } < -0.5,
            "an independent check that the cell is impossible"
        );
        // Just off flat, a real (if thin) cell: accepted.
        let thin = "_cell_angle_alpha 60\n_cell_angle_beta 60\n_cell_angle_gamma 119.9\n";
        assert!(read("t.cif", cell_with(thin).as_bytes()).is_ok());
    }
}
