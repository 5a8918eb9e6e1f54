//! Numeric arguments: numbers written as expressions without coordinates (`2`, `1/2`, `pi/4`,
//! `2^-3`), and vectors of them joined by commas in one word (`0,-2,0`, `1,sqrt(2),0`).
//!
//! Invariants:
//! - A number is evaluated by the crate's expression language (`crate::expr`), so `pi`, `tau`,
//!   `e`, the functions and the operator precedence are the same as in `expression` words.
//! - Accepted values are finite; a coordinate (`x`, `y`, `z`) in an argument is an error.
//! - Components are split at commas outside parentheses only, so `min(1,2),0,0` has three.

use crate::expr::parse;

/// The value of a coordinate-free expression, or why it is not one.
pub fn constant(text: &str) -> Result<f64, String> {
    let expr = parse(text).map_err(|e| {
        let help = e.help.map(|h| format!(" ({h})")).unwrap_or_default();
        format!("`{text}` is not a number: {}{help}", e.message)
    })?;
    if expr.var_mask() != 0 {
        return Err(format!(
            "`{text}` uses a coordinate; arguments are numbers or expressions without x, y, z"
        ));
    }
    let value = expr
        .const_value()
        .ok_or_else(|| format!("`{text}` is not a number"))?;
    if !value.is_finite() {
        return Err(format!("`{text}` is {value}, not a finite number"));
    }
    Ok(value)
}

/// The comma-separated parts of `text`, splitting only at commas outside parentheses.
pub fn split_components(text: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let mut depth = 0i64;
    let mut start = 0;
    for (i, c) in text.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

/// The values of the comma-separated components of `text`, or why one is not a number.
pub fn constants(text: &str) -> Result<Vec<f64>, String> {
    split_components(text)
        .into_iter()
        .map(|part| {
            if part.trim().is_empty() {
                Err(format!("`{text}` has an empty component"))
            } else {
                constant(part)
            }
        })
        .collect()
}

/// Exactly three components.
pub fn vector3(text: &str) -> Result<[f64; 3], String> {
    let values = constants(text)?;
    <[f64; 3]>::try_from(values.as_slice()).map_err(|_| {
        format!(
            "`{text}` has {} component{}, not three",
            values.len(),
            if values.len() == 1 { "" } else { "s" }
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn numbers_are_constant_expressions() {
        assert_eq!(constant("2"), Ok(2.0));
        assert_eq!(constant("1/2"), Ok(0.5));
        assert_eq!(constant("pi/4"), Ok(PI / 4.0));
        assert_eq!(constant("2^-3"), Ok(0.125));
        assert_eq!(constant("-1.5e1"), Ok(-15.0));
        assert!(constant("x/2").unwrap_err().contains("uses a coordinate"));
        assert!(constant("1/0").unwrap_err().contains("not a finite number"));
        assert!(
            constant("abc")
                .unwrap_err()
                .starts_with("`abc` is not a number")
        );
    }

    #[test]
    fn vectors_split_outside_parentheses() {
        assert_eq!(split_components("0,-2,0"), ["0", "-2", "0"]);
        assert_eq!(split_components("min(1,2),0,0"), ["min(1,2)", "0", "0"]);
        assert_eq!(vector3("1,sqrt(4),-3"), Ok([1.0, 2.0, -3.0]));
        assert_eq!(
            vector3("1,2").unwrap_err(),
            "`1,2` has 2 components, not three"
        );
        assert!(vector3("1,,2").unwrap_err().contains("empty component"));
    }
}
