//! Solids the language cannot compute itself: the `file PATH` word names one, and the caller
//! says what it is.
//!
//! The language records the path and nothing else; turning it into a field (reading a mesh,
//! building its signed distance) is the caller's business, through [`ExternalSolids`]. That
//! keeps this crate free of paths and lets a manifest hash the file for its cache key.
//!
//! Invariant: an external field is used only through [`ScalarField::eval_points`], its
//! [`bounds`](ExternalField::bounds) and [`is_distance`](ExternalField::is_distance); the
//! pruning of empty blocks relies on `is_distance` (a 1-Lipschitz field) and never assumes it
//! otherwise.

use std::sync::Arc;

use super::bounds::Aabb;
use crate::field::ScalarField;
use crate::mesh_sdf::{MeshSdf, Mode};

/// The field of a `file` solid, negative inside, in the file's own coordinates.
pub trait ExternalField: ScalarField {
    /// A box containing the solid (`f ≤ 0`).
    fn bounds(&self) -> Aabb;

    /// Whether the field is a true signed distance: `|f(p) − f(q)| ≤ |p − q|`, and the set
    /// `{f ≤ t}` is the solid grown by `t`. Only then may bounds be grown by offsets and
    /// blocks be skipped by the distance at their centre.
    fn is_distance(&self) -> bool;
}

/// Resolves the paths of `file` words to fields.
pub trait ExternalSolids {
    /// The field of the mesh at `path` (as written in the program), or why there is none.
    /// `from` is the include file holding the `file` word (its id, as the
    /// [`IncludeResolver`](super::IncludeResolver) gave it), `None` for top-level words: a
    /// relative path is meant relative to that file.
    fn resolve(&self, path: &str, from: Option<&str>) -> Result<Arc<dyn ExternalField>, String>;
}

/// A resolver for programs that may not use `file` words.
pub struct NoExternalSolids;

impl ExternalSolids for NoExternalSolids {
    fn resolve(&self, _path: &str, _from: Option<&str>) -> Result<Arc<dyn ExternalField>, String> {
        Err("meshes are not available here".to_string())
    }
}

/// A mesh's signed distance is a `file` solid: its bounds are the triangles' box, and it is a
/// true distance unless it samples containment only or clamps distances to a band.
impl ExternalField for MeshSdf {
    fn bounds(&self) -> Aabb {
        let (min, max) = MeshSdf::bounds(self);
        Aabb { min, max }
    }

    fn is_distance(&self) -> bool {
        let options = self.options();
        options.mode == Mode::SignedDistance && options.band.is_none()
    }
}
