//! The schema of previews, in `[build]`: `previews = true|false` (default true) and
//! `preview_size = [width, height]` (default 1024 × 768).
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariant: a size is two integers from
//! [`MIN_SIZE`] to [`MAX_SIZE`] pixels, an error at the value otherwise.

use toml::de::DeValue;

use super::{Checker, Fields, Value};
use crate::stages::preview::DEFAULT_SIZE;

/// The smallest and largest preview side in pixels: big enough for the caption's text,
/// small enough that a picture is not a second large output.
pub(super) const MIN_SIZE: i64 = 64;
pub(super) const MAX_SIZE: i64 = 8192;

impl Checker<'_, '_, '_> {
    /// `build.previews` and `build.preview_size`: whether to draw, and how big; `None` when
    /// anything was reported.
    pub(super) fn previews(&mut self, fields: &Fields<'_, '_>) -> Option<(bool, [u32; 2])> {
        let on = match fields.get("previews") {
            None => Some(true),
            Some((_, value)) => self.boolean("build.previews", value),
        };
        let size = match fields.get("preview_size") {
            None => Some(DEFAULT_SIZE),
            Some((_, value)) => self.preview_size(value),
        };
        Some((on?, size?))
    }

    fn preview_size(&mut self, value: &Value<'_>) -> Option<[u32; 2]> {
        let key = "build.preview_size";
        let expected = "an array of two integers, `[width, height]`";
        let DeValue::Array(items) = value.get_ref() else {
            self.wrong_type(key, value, expected, None);
            return None;
        };
        if items.len() != 2 {
            self.error(
                value.span(),
                &format!("`{key}` must have 2 values (width, height)"),
                &format!("found {}", items.len()),
                None,
            );
            return None;
        }
        let mut size = [0u32; 2];
        for (k, item) in items.iter().enumerate() {
            let DeValue::Integer(int) = item.get_ref() else {
                self.wrong_type(key, item, "an integer number of pixels", None);
                return None;
            };
            match i64::from_str_radix(int.as_str(), int.radix()) {
                Ok(n) if (MIN_SIZE..=MAX_SIZE).contains(&n) => size[k] = n as u32,
                _ => {
                    let shown = self.raw(item);
                    self.error(
                        item.span(),
                        &format!("`{key}` must be from {MIN_SIZE} to {MAX_SIZE} pixels"),
                        &format!("found `{shown}`"),
                        None,
                    );
                    return None;
                }
            }
        }
        Some(size)
    }
}
