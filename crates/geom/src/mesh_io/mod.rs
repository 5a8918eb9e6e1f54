//! Mesh writers: STL, PLY, OBJ, OFF and VTK legacy polydata, streamed to any `io::Write`.
//!
//! Invariant: writers never open files; the caller hands them a buffered writer (the CLI
//! writes to a temporary file and renames it into place).

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Format {
    Stl,
    Ply,
    Obj,
    Off,
    Vtk,
}

/// Binary or text, for the formats that have both (STL, PLY, VTK). OBJ and OFF are always text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Encoding {
    #[default]
    Binary,
    Ascii,
}

impl Format {
    pub const ALL: [Format; 5] = [
        Format::Stl,
        Format::Ply,
        Format::Obj,
        Format::Off,
        Format::Vtk,
    ];

    /// The manifest name of the format, which is also its file extension.
    pub fn name(self) -> &'static str {
        match self {
            Format::Stl => "stl",
            Format::Ply => "ply",
            Format::Obj => "obj",
            Format::Off => "off",
            Format::Vtk => "vtk",
        }
    }

    pub fn from_name(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name)
    }
}
