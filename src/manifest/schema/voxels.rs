//! The schema of captured-data cells: voxel images, `voxels = "part.npy"` (or a `.raw` file
//! with `shape`, `dtype` and `byte_order`), read as `values = "occupancy"` (with `threshold`)
//! or `"distance"`; and oriented point clouds, `points = "scan.ply"`, which take no options.
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariants:
//! - No IO: the file's existence is checked when the manifest is loaded from disk, its
//!   content by the build (a `.npy` header's shape and type are known only then).
//! - The raw layout keys are required for a `.raw` file and errors for a `.npy` one (its
//!   header says); every option is an error on a cell without `voxels`, naming that key.

use latticebuild_geom::voxels::{VoxelType, VoxelValues};
use toml::de::DeValue;

use super::super::model::{CellSource, RawLayout, VoxelCell};
use super::meshes::FileKind;
use super::{Checker, Fields, Value};

const POINT_FILES: FileKind = FileKind {
    extensions: &["ply", "xyz"],
    noun: "point cloud",
    help: "save the points with normals as PLY (`nx`, `ny`, `nz` properties), or as text of \
           six columns `x y z nx ny nz` (`.xyz`)",
};

const VOXEL_FILES: FileKind = FileKind {
    extensions: &["npy", "raw"],
    noun: "voxel",
    help: "save the image with NumPy's `np.save` (`.npy`), or as raw bytes (`.raw`) with \
           `shape` and `dtype`",
};

/// The keys only a voxel cell takes, and those only a raw file's.
const VOXEL_OPTIONS: [&str; 5] = ["shape", "dtype", "byte_order", "values", "threshold"];
const RAW_OPTIONS: [&str; 3] = ["shape", "dtype", "byte_order"];
const VALUES: [&str; 2] = ["occupancy", "distance"];
const BYTE_ORDERS: [&str; 2] = ["little", "big"];

impl Checker<'_, '_, '_> {
    /// `voxels = "file"`: a cell source; the layout and values are filled in by
    /// [`Checker::voxel_options`].
    pub(super) fn voxel_source(&mut self, cell: &str, value: &Value<'_>) -> Option<CellSource> {
        let key = format!("cells.{cell}.voxels");
        let given = self.string(&key, value)?;
        let file = self.input_file(&format!("`{key}`"), given, value.span(), &VOXEL_FILES)?;
        Some(CellSource::Voxels(VoxelCell {
            file,
            raw: None,
            values: VoxelValues::Occupancy { threshold: None },
        }))
    }

    /// `points = "file"`: a cell source of oriented points (no options).
    pub(super) fn points_source(&mut self, cell: &str, value: &Value<'_>) -> Option<CellSource> {
        let key = format!("cells.{cell}.points");
        let given = self.string(&key, value)?;
        self.input_file(&format!("`{key}`"), given, value.span(), &POINT_FILES)
            .map(CellSource::Points)
    }

    /// The options of a voxel cell: `(raw layout, values)`, and an error for each of them
    /// given to another cell. `raw_file`: whether the `voxels` file is `.raw`.
    pub(super) fn voxel_options(
        &mut self,
        cell: &str,
        fields: &Fields<'_, '_>,
        voxels: Option<(&Value<'_>, bool)>,
    ) -> Option<(Option<RawLayout>, VoxelValues)> {
        let path = |k: &str| format!("cells.{cell}.{k}");
        let Some((source, raw_file)) = voxels else {
            for k in VOXEL_OPTIONS {
                if let Some((key, _)) = fields.get(k) {
                    self.error(
                        key.span(),
                        &format!("`{}` applies only to voxel cells", path(k)),
                        &format!("cell `{cell}` has no `voxels`"),
                        Some(&format!(
                            "remove `{k}`, or give the cell a `voxels = \"part.npy\"`"
                        )),
                    );
                }
            }
            return None;
        };
        let raw = if raw_file {
            self.raw_layout(cell, fields, source)
        } else {
            for k in RAW_OPTIONS {
                if let Some((key, _)) = fields.get(k) {
                    self.error(
                        key.span(),
                        &format!("`{}` does not apply to a `.npy` file", path(k)),
                        "its header gives the shape, type and byte order",
                        Some(&format!("remove `{k}`")),
                    );
                }
            }
            Some(None)
        };
        let values = self.voxel_values(cell, fields);
        Some((raw?, values?))
    }

    /// `shape`, `dtype` and `byte_order` of a raw file (the first two required).
    fn raw_layout(
        &mut self,
        cell: &str,
        fields: &Fields<'_, '_>,
        source: &Value<'_>,
    ) -> Option<Option<RawLayout>> {
        let path = |k: &str| format!("cells.{cell}.{k}");
        let within = format!("in cell `{cell}`");
        let shape = match fields.get("shape") {
            Some((_, v)) => self.voxel_shape(&path("shape"), v),
            None => {
                self.missing(
                    fields,
                    &source.span(),
                    "shape",
                    &within,
                    "a raw file does not say its size",
                    "add `shape = [nx, ny, nz]`, the voxels along x, y and z",
                );
                None
            }
        };
        let names = VoxelType::NAMES.map(|(name, _)| name);
        let dtype = match fields.get("dtype") {
            Some((_, v)) => self
                .choice(&path("dtype"), v, &names, "voxel type")
                .and_then(|name| VoxelType::NAMES.iter().find(|(n, _)| *n == name))
                .map(|(_, t)| *t),
            None => {
                self.missing(
                    fields,
                    &source.span(),
                    "dtype",
                    &within,
                    "a raw file does not say its number type",
                    "add `dtype = \"uint8\"` (or \"uint16\", \"int16\", \"float32\", \"float64\")",
                );
                None
            }
        };
        let big_endian = match fields.get("byte_order") {
            None => Some(false),
            Some((_, v)) => self
                .choice(&path("byte_order"), v, &BYTE_ORDERS, "byte order")
                .map(|o| o == "big"),
        };
        Some(Some(RawLayout {
            shape: shape?,
            dtype: dtype?,
            big_endian: big_endian?,
        }))
    }

    /// `shape = [nx, ny, nz]`: three integers of at least 1.
    fn voxel_shape(&mut self, key: &str, value: &Value<'_>) -> Option<[u64; 3]> {
        let DeValue::Array(items) = value.get_ref() else {
            self.wrong_type(key, value, "an array of 3 integers [nx, ny, nz]", None);
            return None;
        };
        if items.len() != 3 {
            self.wrong_length(key, value, items.len());
            return None;
        }
        let mut shape = [0u64; 3];
        for (axis, item) in items.iter().enumerate() {
            let n = match item.get_ref() {
                DeValue::Integer(int) => i64::from_str_radix(int.as_str(), int.radix()).ok(),
                _ => {
                    self.wrong_type(key, item, "an integer", None);
                    continue;
                }
            };
            match n.and_then(|n| u64::try_from(n).ok()).filter(|n| *n >= 1) {
                Some(n) => shape[axis] = n,
                None => {
                    let shown = self.raw(item);
                    self.error(
                        item.span(),
                        &format!("`{key}` must be at least 1 voxel per axis"),
                        &format!("found `{shown}`"),
                        None,
                    );
                }
            }
        }
        shape.iter().all(|n| *n >= 1).then_some(shape)
    }

    /// `values` and `threshold`: occupancy by default; a threshold only with occupancy.
    fn voxel_values(&mut self, cell: &str, fields: &Fields<'_, '_>) -> Option<VoxelValues> {
        let path = |k: &str| format!("cells.{cell}.{k}");
        let kind = match fields.get("values") {
            None => Some("occupancy"),
            Some((_, v)) => self.choice(&path("values"), v, &VALUES, "kind of values"),
        }?;
        let threshold = match fields.get("threshold") {
            None => None,
            Some((key, _)) if kind == "distance" => {
                self.error(
                    key.span(),
                    &format!("`{}` does not apply to a distance image", path("threshold")),
                    "the surface of a distance image is where it is 0",
                    Some("remove `threshold`, or set `values = \"occupancy\"`"),
                );
                return None;
            }
            Some((_, v)) => Some(self.finite_number(&path("threshold"), v)?),
        };
        Some(match kind {
            "distance" => VoxelValues::Distance,
            _ => VoxelValues::Occupancy { threshold },
        })
    }
}
