//! An analytic sphere standing in for a mesh in `file` words of SDF programs.

use std::sync::Arc;

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::stack_lang::{Aabb, ExternalField, ExternalSolids};

/// The sphere of `radius` at the origin, a true signed distance.
pub struct Sphere {
    pub radius: f64,
}

impl ScalarField for Sphere {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = (xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i]).sqrt() - self.radius;
        }
    }
}

impl ExternalField for Sphere {
    fn bounds(&self) -> Aabb {
        Aabb::cube(self.radius)
    }
    fn is_distance(&self) -> bool {
        true
    }
}

/// Resolves `name` (or every path, when `None`) to a sphere of `radius`; other paths fail with
/// `cannot read`.
pub struct SphereFile {
    pub name: Option<&'static str>,
    pub radius: f64,
}

impl ExternalSolids for SphereFile {
    fn resolve(&self, path: &str, _from: Option<&str>) -> Result<Arc<dyn ExternalField>, String> {
        match self.name {
            Some(name) if name != path => Err(format!("cannot read `{path}`")),
            _ => Ok(Arc::new(Sphere {
                radius: self.radius,
            })),
        }
    }
}
