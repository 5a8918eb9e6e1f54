//! The parameters a report echoes: each `[outputs.NAME]` table as the build read it (after
//! every `--set` and `--unset`), as JSON, so an automated caller sees exactly which values
//! produced the numbers beside them.
//!
//! Invariants:
//! - A value is the one validated, converted type for type: strings, booleans, arrays and
//!   tables as themselves; integers as JSON integers; floats as JSON numbers (a non-finite
//!   float cannot pass validation, and would be `null`); a date-time as its text.
//! - Defaults are not filled in: a key absent from the table is absent here (the manifest
//!   reference documents each default), so the object says what the caller asked for;
//!   `resolved.rs` fills them in from the model. Cells' and scaffolds' tables are kept the
//!   same way, for it.

use std::collections::BTreeMap;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// Every output's table by name (an output that is not a table is left out: validation
/// reports it).
pub(crate) fn of_outputs(root: &DeTable<'_>) -> BTreeMap<String, serde_json::Value> {
    of_tables(root, "outputs")
}

/// Every table of `[section.NAME]` by name (`cells`, `scaffolds`, `outputs`), the same way.
pub(crate) fn of_tables(root: &DeTable<'_>, section: &str) -> BTreeMap<String, serde_json::Value> {
    let Some(DeValue::Table(outputs)) = root.get(section).map(Spanned::get_ref) else {
        return BTreeMap::new();
    };
    outputs
        .iter()
        .filter(|(_, value)| matches!(value.get_ref(), DeValue::Table(_)))
        .map(|(name, value)| (name.get_ref().to_string(), to_json(value.get_ref())))
        .collect()
}

fn to_json(value: &DeValue<'_>) -> serde_json::Value {
    use serde_json::Value as J;
    match value {
        DeValue::String(text) => J::String(text.to_string()),
        DeValue::Integer(int) => i64::from_str_radix(int.as_str(), int.radix())
            .map(J::from)
            .unwrap_or_else(|_| J::String(int.as_str().to_string())),
        DeValue::Float(float) => float
            .as_str()
            .parse::<f64>()
            .ok()
            .and_then(serde_json::Number::from_f64)
            .map_or(J::Null, J::Number),
        DeValue::Boolean(b) => J::Bool(*b),
        DeValue::Datetime(datetime) => J::String(datetime.to_string()),
        DeValue::Array(items) => J::Array(items.iter().map(|v| to_json(v.get_ref())).collect()),
        DeValue::Table(table) => J::Object(
            table
                .iter()
                .map(|(k, v)| (k.get_ref().to_string(), to_json(v.get_ref())))
                .collect(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::of_outputs;
    use toml::de::DeTable;

    #[test]
    fn each_output_table_becomes_the_json_of_its_values() {
        let text = "[outputs.g]\ncell = \"c\"\nsamples = 0x20\noffset = -0.25\nascii = true\n\
                    domain = { min = [0, 0, 0], max = [1, 1.5, 2] }\n[outputs.h]\nvoxel = 1e-1\n";
        let tree = DeTable::parse(text).unwrap().into_inner();
        let parameters = of_outputs(&tree);
        let expected = serde_json::json!({
            "cell": "c", "samples": 32, "offset": -0.25, "ascii": true,
            "domain": { "min": [0, 0, 0], "max": [1, 1.5, 2] }
        });
        assert_eq!(parameters["g"], expected);
        assert_eq!(parameters["h"], serde_json::json!({ "voxel": 0.1 }));
        assert_eq!(parameters.len(), 2);
    }
}
