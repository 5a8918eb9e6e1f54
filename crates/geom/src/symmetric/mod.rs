//! Symmetric Fourier unit cells (Chen, Kabaria & Lew 2025, with the corrections of
//! `docs/method.md` §Departures).
//!
//! A cell is `Φ(x) = Re Σ_{f∈F} c_f φ_f(x)` with `φ_f(x) = K_f Σ_{Q∈S} exp(2πi fᵀQx)`: a
//! trigonometric polynomial invariant under a point group `S` (`Φ(Qx) = Φ(x)`), negative inside.
//!
//! - [`group`] — D3, D4, Td, Oh and groups from generators; frames, reference elements,
//!   sampling domains.
//! - [`frequency`] — orbits `f ↦ Qᵀf`, representatives (lexicographically largest member),
//!   stabilisers, conjugate partners, band-limited frequency sets.
//! - [`basis`] — `φ_f`.
//! - [`domain`] — sampling sources on the domain grid; mirroring Td/D3 cells; symmetrization.
//! - [`fit`](mod@fit) — FFT fit `c_f = K_f Σ_Q ĝ(Qᵀf)` (with the conjugate) and [`FittedCell`].
//! - [`eval`] — direct summation (value, gradient) and inverse-FFT grids; `FittedCell` is a
//!   [`ScalarField`](crate::field::ScalarField) whose grid sampler is separable per axis
//!   (private `sampler` module), so the contourer can mesh rich fits.
//! - [`blend`] — weighted averages and Minkowski sum/difference.
//! - [`constrain`] — the face-normal constraint `∇Φ·n = 0` on the reference element's faces
//!   (docs/method.md §Face-normal condition): a least-change projection of the coefficients
//!   (`row_space.rs`: LSQR on the sparse constraint rows).
//! - [`optimize`] — the least change of the coefficients that reaches a target volume
//!   fraction, keeping the face-normal condition.
//! - [`auto`] — automatic `N`: double until the zero set moves less than a tolerance,
//!   sampling only the points each doubling adds.
//! - `fft` (private) — realfft along x (contiguous), rustfft along y and z, rayon across
//!   planes and rows.
//!
//! Invariant: every result (coefficients, grids, reports) is the same bits for any rayon
//! thread count. Parallel work writes disjoint outputs, or sums fixed ranges and adds them in
//! order (`fft`'s fold over the spectrum); nothing sums in a hash map's iteration order.
//!
//! Errors: one [`FitError`] for sampling, fitting, evaluating and blending, and [`GroupError`]
//! for groups; nothing here panics on user input.
//!
//! Frames: every public point and gradient is Cartesian, in the reference frame where the cell
//! has size 1 and its centroid at the origin. Frequencies and grid coordinates are in the
//! group's frame (skew for D3). 2D cells use `[x, y, 0]` and frequencies `[f1, f2, 0]`.

pub mod auto;
pub mod basis;
pub mod blend;
mod coefficient_space;
pub mod constrain;
pub mod domain;
pub mod eval;
mod fft;
pub mod fit;
pub mod frequency;
pub mod group;
pub mod measure;
mod objective;
pub mod optimize;
mod row_space;
mod sampler;

pub use auto::{AUTO_START_N, AutoFit, PROBE_N, fit_auto, surface_movement};
pub use blend::{minkowski_difference, minkowski_sum, weighted_average};
pub use constrain::{CONSTRAINT_TOLERANCE, ConstraintReport, FACE_SAMPLES};
pub use domain::{Extend, FnSource, SampleOptions, Source, from_fn, max_grid_n, sample};
pub use eval::PRUNE_TOLERANCE;
pub use fit::{
    Coefficient, FitError, FitOptions, FittedCell, Side, check_surface, fit, fit_samples,
};
pub use group::{
    Domain, Frame, Group, GroupError, IDENTITY, MAX_GROUP_ORDER, Matrix, ReferenceElement,
    TETRAHEDRON_FACE_NORMALS,
};
pub use measure::{CellMeasures, measure};
pub use optimize::{Iterate, Optimization, OptimizationReport, OptimizationTargets};
pub use rustfft::num_complex::Complex64;
