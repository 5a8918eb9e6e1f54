//! Expressions: parsing, constant folding, compiled evaluation and separable analysis.
