//! What a written file says about itself besides its mesh: the tool that wrote it, the unit of
//! its lengths, a title and the parameters it was made with.
//!
//! Invariants:
//! - A stamp changes only headers, comments and metadata, never a coordinate: the mesh read
//!   back is the same with any stamp.
//! - [`Stamp::default`] is anonymous (generator `latticebuild`, no unit, no title, no
//!   parameters): the headers then are the ones written before stamps existed, but for 3MF,
//!   which always names its unit (`millimeter`, the format's own default, when none is given).
//! - Text put in a header never breaks its format: [`Stamp::line`] drops line breaks and
//!   control characters, XML text is escaped where it is written.

/// A length unit of the manifest's `units`, as the file formats name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Units {
    Micron,
    Millimeter,
    Centimeter,
    Meter,
    Inch,
}

impl Units {
    pub const ALL: [Units; 5] = [
        Units::Micron,
        Units::Millimeter,
        Units::Centimeter,
        Units::Meter,
        Units::Inch,
    ];

    /// The manifest's name (`units = "mm"`), also the one headers carry (`units: mm`).
    pub fn name(self) -> &'static str {
        match self {
            Units::Micron => "um",
            Units::Millimeter => "mm",
            Units::Centimeter => "cm",
            Units::Meter => "m",
            Units::Inch => "in",
        }
    }

    pub fn from_name(name: &str) -> Option<Units> {
        Units::ALL.into_iter().find(|u| u.name() == name)
    }

    /// The 3MF core specification's name (`<model unit="…">`); it also has `foot`, which the
    /// manifest does not.
    pub fn three_mf(self) -> &'static str {
        match self {
            Units::Micron => "micron",
            Units::Millimeter => "millimeter",
            Units::Centimeter => "centimeter",
            Units::Meter => "meter",
            Units::Inch => "inch",
        }
    }

    /// The unit a 3MF `unit` attribute names, with its length in millimetres when the
    /// manifest has no such unit (`foot`).
    pub fn from_three_mf(name: &str) -> Option<Result<Units, f64>> {
        match name {
            "foot" => Some(Err(304.8)),
            _ => Units::ALL
                .into_iter()
                .find(|u| u.three_mf() == name)
                .map(Ok),
        }
    }

    /// The length of one unit in millimetres (exact: the inch is 25.4 mm by definition).
    pub fn millimeters(self) -> f64 {
        match self {
            Units::Micron => 1e-3,
            Units::Millimeter => 1.0,
            Units::Centimeter => 10.0,
            Units::Meter => 1000.0,
            Units::Inch => 25.4,
        }
    }

    /// A length of `value` of this unit as a CSS length SVG takes: a number and one of `mm`,
    /// `cm`, `in` (CSS has no micron or metre, so those are given in mm and cm).
    pub fn css_length(self, value: f64) -> (f64, &'static str) {
        match self {
            Units::Micron => (value * 1e-3, "mm"),
            Units::Millimeter => (value, "mm"),
            Units::Centimeter => (value, "cm"),
            Units::Meter => (value * 100.0, "cm"),
            Units::Inch => (value, "in"),
        }
    }
}

/// What a written file says about itself (see the module docs).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Stamp {
    /// The tool and its version, `latticebuild 0.1.0`; empty: `latticebuild`.
    pub generator: String,
    /// The unit of the mesh's lengths; `None`: unsaid (3MF: millimetres).
    pub units: Option<Units>,
    /// A title (the output's name); empty: none.
    pub title: String,
    /// Name and value of each parameter the mesh was made with, for formats with metadata
    /// (3MF). Names are letters, digits, `_` and `.` (a nested key, `cell.name`); others are
    /// replaced by `_` where written.
    pub parameters: Vec<(String, String)>,
}

impl Stamp {
    /// The generator, `latticebuild` when unsaid, as one line.
    pub fn generator(&self) -> String {
        match self.generator.is_empty() {
            true => "latticebuild".to_string(),
            false => Stamp::line(&self.generator),
        }
    }

    /// `generator` and, when known, `, units: mm`: what one-line headers carry.
    pub fn summary(&self) -> String {
        match self.units {
            Some(units) => format!("{}, units: {}", self.generator(), units.name()),
            None => self.generator(),
        }
    }

    /// `text` with every control character (line breaks included) replaced by a space, so it
    /// stays on the header line it is put on.
    pub fn line(text: &str) -> String {
        text.chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_lengths_are_the_definitions() {
        for units in Units::ALL {
            assert_eq!(Units::from_name(units.name()), Some(units));
            assert_eq!(Units::from_three_mf(units.three_mf()), Some(Ok(units)));
            let (value, css) = units.css_length(2.0);
            let css_mm = match css {
                "mm" => 1.0,
                "cm" => 10.0,
                "in" => 25.4,
                other => panic!("{other}"),
            };
            assert!((value * css_mm - 2.0 * units.millimeters()).abs() < 1e-12);
        }
        assert_eq!(Units::from_three_mf("foot"), Some(Err(304.8)));
        assert_eq!(Units::from_three_mf("furlong"), None);
    }

    #[test]
    fn header_text_stays_on_its_line() {
        let stamp = Stamp {
            generator: "latticebuild 1.2\nsolid x".into(),
            units: Some(Units::Inch),
            ..Stamp::default()
        };
        assert_eq!(stamp.summary(), "latticebuild 1.2 solid x, units: in");
        assert_eq!(Stamp::default().summary(), "latticebuild");
    }
}
