//! Display for [`ParseError`], so it can be shown and used as a `std::error::Error`.
//!
//! Invariant: the display is the message alone; span and help are structured data that a
//! caller renders with the source text (a caret under the span, the help below).

use std::fmt;

use super::ParseError;

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for ParseError {}
