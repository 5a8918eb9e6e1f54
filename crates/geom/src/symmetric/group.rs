//! Point groups as integer matrices, their frames, reference elements and sampling domains.
//!
//! Conventions (docs/method.md §Reference elements, §Symmetry groups):
//! - An element `Q` acts on positions about the cell centre, `x ↦ Q x`, in the coordinates of the
//!   group's [`Frame`]: Cartesian for D4, Oh and Td; skew (hexagonal) for D3, where
//!   `x = s1·e1 + s2·e2`, `e1 = (1, 0)`, `e2 = (½, √3/2)`. A symmetric field satisfies
//!   `Φ(Q x) = Φ(x)`. Frequencies transform by the transpose, `f ↦ Qᵀ f`.
//! - Every matrix is stored as 3×3 integers; a 2D group uses the upper-left 2×2 block and keeps
//!   the third row and column of the identity, so 2D frequencies are `[f1, f2, 0]`.
//! - A group is finite because every element is an integer matrix that is orthogonal for the
//!   frame's metric (`Mᵀ G M = G` with `G` the Gram matrix of the frame's basis): such matrices
//!   form a finite set, so closure always terminates; the element bound only guards against
//!   pathological input.
//!
//! Reference elements (cell size 1, centroid at the origin) and sampling domains:
//!
//! ```text
//!   D4: square [-½,½)²         Oh: cube [-½,½)³        Td: tetrahedron inside the cube,
//!                                                          vertices at the corners whose
//!                                                          coordinates multiply to < 0;
//!                                                          sampled on the cube
//!   D3: triangle T, sampled on the rhombus Ω = [-⅓,⅔)² in skew coordinates (s1, s2):
//!
//!         s2 = ⅔  +-----------+            T   = {s1 ≥ -⅓, s2 ≥ -⅓, s1 + s2 ≤ ⅓}
//!                / \  mirror /             Ω∖T = T mirrored across s1 + s2 = ⅓
//!               /   \  of T /
//!              /  T  \     /               (drawn sheared: e2 leans 60° from e1)
//!             /   ·   \   /
//!   s2 = -⅓  +---------+-+
//!          s1 = -⅓     s1 = ⅔
//! ```

use std::collections::BTreeSet;
use std::fmt;

/// An integer matrix acting on column vectors, rows first (`m[row][col]`).
pub type Matrix = [[i32; 3]; 3];

/// The identity matrix.
pub const IDENTITY: Matrix = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];

/// Closure stops with an error beyond this many elements.
pub const MAX_GROUP_ORDER: usize = 1000;

/// The coordinates a group's matrices act on (and the frequencies of its basis live in).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Frame {
    /// Cartesian coordinates.
    Cartesian,
    /// Skew coordinates in the xy-plane, `x = s1·(1,0) + s2·(½,√3/2)`; z (if any) Cartesian.
    Hexagonal,
}

impl Frame {
    /// Domain (frame) coordinates to Cartesian.
    #[inline]
    pub fn to_cartesian(self, s: [f64; 3]) -> [f64; 3] {
        match self {
            Frame::Cartesian => s,
            Frame::Hexagonal => [s[0] + 0.5 * s[1], s[1] * (0.75f64).sqrt(), s[2]],
        }
    }

    /// Cartesian coordinates to domain (frame) coordinates.
    #[inline]
    pub fn from_cartesian(self, x: [f64; 3]) -> [f64; 3] {
        match self {
            Frame::Cartesian => x,
            Frame::Hexagonal => {
                let s2 = x[1] / (0.75f64).sqrt();
                [x[0] - 0.5 * s2, s2, x[2]]
            }
        }
    }

    /// A gradient in frame coordinates (∂/∂s) to a Cartesian gradient: `∇x = B⁻ᵀ ∇s`.
    #[inline]
    pub fn gradient_to_cartesian(self, g: [f64; 3]) -> [f64; 3] {
        match self {
            Frame::Cartesian => g,
            // B = [[1, ½], [0, √3/2]], B⁻ᵀ = [[1, 0], [-1/√3, 2/√3]].
            Frame::Hexagonal => {
                let r3 = 3f64.sqrt();
                [g[0], (2.0 * g[1] - g[0]) / r3, g[2]]
            }
        }
    }

    /// Twice the Gram matrix of the frame's basis (integer): an element `M` is orthogonal in
    /// this frame iff `Mᵀ G M = G`.
    fn gram2(self) -> Matrix {
        match self {
            Frame::Cartesian => [[2, 0, 0], [0, 2, 0], [0, 0, 2]],
            Frame::Hexagonal => [[2, 1, 0], [1, 2, 0], [0, 0, 2]],
        }
    }
}

/// The reference element of a named group (cell size 1, centroid at the origin).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ReferenceElement {
    /// `[-½, ½]²`.
    Square,
    /// `[-½, ½]³`.
    Cube,
    /// The regular tetrahedron of docs/method.md §Reference elements (edge √2) inscribed in the
    /// cube.
    Tetrahedron,
    /// The equilateral triangle of side 1 pointing to +y.
    Triangle,
}

impl ReferenceElement {
    /// Vertices in Cartesian coordinates (z = 0 in 2D). For the tetrahedron, vertex `i` is
    /// opposite face `i` of [`TETRAHEDRON_FACE_NORMALS`].
    pub fn vertices(self) -> Vec<[f64; 3]> {
        match self {
            ReferenceElement::Square => vec![
                [-0.5, -0.5, 0.0],
                [0.5, -0.5, 0.0],
                [0.5, 0.5, 0.0],
                [-0.5, 0.5, 0.0],
            ],
            ReferenceElement::Cube => (0..8)
                .map(|i| {
                    let c = |b: usize| if i >> b & 1 == 1 { 0.5 } else { -0.5 };
                    [c(0), c(1), c(2)]
                })
                .collect(),
            ReferenceElement::Tetrahedron => vec![
                [-0.5, -0.5, -0.5],
                [0.5, 0.5, -0.5],
                [-0.5, 0.5, 0.5],
                [0.5, -0.5, 0.5],
            ],
            ReferenceElement::Triangle => {
                let h = 3f64.sqrt() / 6.0;
                vec![[-0.5, -h, 0.0], [0.5, -h, 0.0], [0.0, 2.0 * h, 0.0]]
            }
        }
    }

    /// Whether the element is a simplex that the sampling domain extends (Td, D3).
    pub fn is_simplex(self) -> bool {
        matches!(
            self,
            ReferenceElement::Tetrahedron | ReferenceElement::Triangle
        )
    }
}

/// Outward normals `n_i` of the reference tetrahedron's faces; face `i` is the plane
/// `n_i · x = ½`, opposite vertex `p_i`.
pub const TETRAHEDRON_FACE_NORMALS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
];

/// The periodic domain a group's cells are sampled on (one period of the lattice `Zᵈ` in the
/// group's frame). The sampling grid is `s_i = origin + i/N` per axis; the upper end is not
/// sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Domain {
    /// `[-½, ½)²`, Cartesian.
    Square,
    /// `[-½, ½)³`, Cartesian.
    Cube,
    /// `[-⅓, ⅔)²` in skew coordinates: the triangle and its mirror image.
    Rhombus,
    /// `[-⅓, ⅔)² × [-½, ½)`: skew in xy, Cartesian in z.
    RhombicPrism,
}

impl Domain {
    /// Number of axes.
    pub fn dimension(self) -> usize {
        match self {
            Domain::Square | Domain::Rhombus => 2,
            Domain::Cube | Domain::RhombicPrism => 3,
        }
    }

    /// The frame of the domain's coordinates.
    pub fn frame(self) -> Frame {
        match self {
            Domain::Square | Domain::Cube => Frame::Cartesian,
            Domain::Rhombus | Domain::RhombicPrism => Frame::Hexagonal,
        }
    }

    /// The lower corner `x_0` per axis as a fraction `(numerator, denominator)`; unused axes
    /// (z in 2D) are `(0, 1)`. Exact fractions let phases `exp(−2πi k·x_0)` be looked up
    /// instead of computed from rounded arguments.
    pub fn origin_fraction(self) -> [(i64, i64); 3] {
        match self {
            Domain::Square => [(-1, 2), (-1, 2), (0, 1)],
            Domain::Cube => [(-1, 2); 3],
            Domain::Rhombus => [(-1, 3), (-1, 3), (0, 1)],
            Domain::RhombicPrism => [(-1, 3), (-1, 3), (-1, 2)],
        }
    }

    /// The lower corner `x_0` in domain coordinates.
    pub fn origin(self) -> [f64; 3] {
        self.origin_fraction().map(|(p, q)| p as f64 / q as f64)
    }
}

/// Errors building a group.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GroupError {
    #[error("unknown symmetry group `{0}`; expected one of D3, D4, Td, Oh")]
    UnknownName(String),
    #[error("a symmetry group has dimension 2 or 3, not {0}")]
    Dimension(usize),
    #[error(
        "generator {index} is not a {dimension}D matrix: outside the upper-left {dimension}×{dimension} block it must equal the identity"
    )]
    NotEmbedded { index: usize, dimension: usize },
    #[error("generator {index} is not invertible over the integers (determinant {det}, not ±1)")]
    NotInvertible { index: usize, det: i64 },
    #[error(
        "generator {index} is not orthogonal in the {frame:?} frame, so the generators do not form a finite group"
    )]
    NotOrthogonal { index: usize, frame: Frame },
    #[error("the generators do not form a finite group of at most {bound} elements")]
    TooLarge { bound: usize },
}

/// A finite point group of integer matrices.
///
/// Invariants: `elements` is closed under multiplication, contains the identity, holds no
/// duplicates, and is sorted (so two groups with the same elements compare equal).
#[derive(Clone, Debug)]
pub struct Group {
    name: String,
    dimension: usize,
    frame: Frame,
    elements: Vec<Matrix>,
    transposes: Vec<Matrix>,
    reference: Option<ReferenceElement>,
    domain: Domain,
}

impl PartialEq for Group {
    /// Groups are equal when they act by the same matrices in the same frame; the name is
    /// only a label.
    fn eq(&self, other: &Group) -> bool {
        self.dimension == other.dimension
            && self.frame == other.frame
            && self.elements == other.elements
    }
}

impl fmt::Display for Group {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (order {})", self.name, self.elements.len())
    }
}

/// Matrix product `a · b`.
#[inline]
pub fn mat_mul(a: &Matrix, b: &Matrix) -> Matrix {
    let mut m = [[0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// Transpose.
#[inline]
pub fn transpose(a: &Matrix) -> Matrix {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}

/// `m · v` for an integer vector.
#[inline]
pub fn mat_vec(m: &Matrix, v: [i32; 3]) -> [i32; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// `m · v` for a real vector.
#[inline]
pub fn mat_vec_f64(m: &Matrix, v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] as f64 * v[0] + m[i][1] as f64 * v[1] + m[i][2] as f64 * v[2])
}

fn det(m: &Matrix) -> i64 {
    // i128: a product of three arbitrary i32 entries overflows i64.
    let m = m.map(|r| r.map(i128::from));
    let d = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    d.clamp(i64::MIN as i128, i64::MAX as i128) as i64
}

/// All signed permutation matrices of size `dim` (embedded in 3×3), optionally only those
/// whose non-zero entries multiply to +1.
fn signed_permutations(dim: usize, positive_product_only: bool) -> Vec<Matrix> {
    let perms: Vec<Vec<usize>> = if dim == 2 {
        vec![vec![0, 1], vec![1, 0]]
    } else {
        vec![
            vec![0, 1, 2],
            vec![0, 2, 1],
            vec![1, 0, 2],
            vec![1, 2, 0],
            vec![2, 0, 1],
            vec![2, 1, 0],
        ]
    };
    let mut out = Vec::new();
    for p in &perms {
        for signs in 0..(1u32 << dim) {
            let sign = |r: usize| if signs >> r & 1 == 1 { -1 } else { 1 };
            let product: i32 = (0..dim).map(sign).product();
            if positive_product_only && product != 1 {
                continue;
            }
            let mut m = IDENTITY;
            for r in 0..dim {
                m[r] = [0; 3];
                m[r][p[r]] = sign(r);
            }
            out.push(m);
        }
    }
    out
}

impl Group {
    fn from_elements(
        name: &str,
        dimension: usize,
        frame: Frame,
        elements: Vec<Matrix>,
        reference: Option<ReferenceElement>,
    ) -> Group {
        let elements: Vec<Matrix> = elements
            .into_iter()
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let transposes = elements.iter().map(transpose).collect();
        let domain = match (dimension, frame) {
            (2, Frame::Cartesian) => Domain::Square,
            (2, Frame::Hexagonal) => Domain::Rhombus,
            (_, Frame::Cartesian) => Domain::Cube,
            (_, Frame::Hexagonal) => Domain::RhombicPrism,
        };
        Group {
            name: name.to_string(),
            dimension,
            frame,
            elements,
            transposes,
            reference,
            domain,
        }
    }

    /// D3, the symmetry group of the reference triangle, in skew coordinates (order 6).
    pub fn d3() -> Group {
        let m = |a: [[i32; 2]; 2]| [[a[0][0], a[0][1], 0], [a[1][0], a[1][1], 0], [0, 0, 1]];
        let elements = vec![
            m([[1, 0], [0, 1]]),
            m([[-1, -1], [1, 0]]),
            m([[0, 1], [-1, -1]]),
            m([[-1, -1], [0, 1]]),
            m([[0, 1], [1, 0]]),
            m([[1, 0], [-1, -1]]),
        ];
        Group::from_elements(
            "D3",
            2,
            Frame::Hexagonal,
            elements,
            Some(ReferenceElement::Triangle),
        )
    }

    /// D4, the symmetry group of the square: all 8 signed 2×2 permutation matrices.
    pub fn d4() -> Group {
        Group::from_elements(
            "D4",
            2,
            Frame::Cartesian,
            signed_permutations(2, false),
            Some(ReferenceElement::Square),
        )
    }

    /// Td, the symmetry group of the reference tetrahedron: the 24 signed 3×3 permutation
    /// matrices whose non-zero entries multiply to +1 (it does not contain −I).
    pub fn td() -> Group {
        Group::from_elements(
            "Td",
            3,
            Frame::Cartesian,
            signed_permutations(3, true),
            Some(ReferenceElement::Tetrahedron),
        )
    }

    /// Oh, the symmetry group of the cube: all 48 signed 3×3 permutation matrices.
    pub fn oh() -> Group {
        Group::from_elements(
            "Oh",
            3,
            Frame::Cartesian,
            signed_permutations(3, false),
            Some(ReferenceElement::Cube),
        )
    }

    /// A named group: `D3`, `D4`, `Td` or `Oh` (case-insensitive).
    pub fn by_name(name: &str) -> Result<Group, GroupError> {
        match name.trim().to_ascii_lowercase().as_str() {
            "d3" => Ok(Group::d3()),
            "d4" => Ok(Group::d4()),
            "td" => Ok(Group::td()),
            "oh" => Ok(Group::oh()),
            _ => Err(GroupError::UnknownName(name.to_string())),
        }
    }

    /// The group generated by `generators` acting on Cartesian coordinates.
    pub fn from_generators(dimension: usize, generators: &[Matrix]) -> Result<Group, GroupError> {
        Group::from_generators_in(dimension, Frame::Cartesian, generators)
    }

    /// The group generated by `generators` acting on coordinates of `frame`. Each generator
    /// must be invertible over the integers and orthogonal for the frame's metric; the closure
    /// is computed. The result has no reference element, so only `Extend::None` applies to
    /// it, and its sampling domain is the square/cube (Cartesian) or rhombus/rhombic prism
    /// (hexagonal).
    pub fn from_generators_in(
        dimension: usize,
        frame: Frame,
        generators: &[Matrix],
    ) -> Result<Group, GroupError> {
        if dimension != 2 && dimension != 3 {
            return Err(GroupError::Dimension(dimension));
        }
        let g2 = frame.gram2();
        for (index, m) in generators.iter().enumerate() {
            if dimension == 2 && (m[2] != [0, 0, 1] || m[0][2] != 0 || m[1][2] != 0) {
                return Err(GroupError::NotEmbedded { index, dimension });
            }
            let d = det(m);
            if d != 1 && d != -1 {
                return Err(GroupError::NotInvertible { index, det: d });
            }
            // Entries are small for any orthogonal matrix; wide arithmetic keeps arbitrary
            // user input from overflowing before the check rejects it.
            let wide = |a: &Matrix| a.map(|r| r.map(i128::from));
            let (mw, gw) = (wide(m), wide(&g2));
            let mut ok = true;
            for i in 0..3 {
                for j in 0..3 {
                    let mut s: i128 = 0;
                    for k in 0..3 {
                        for l in 0..3 {
                            s += mw[k][i] * gw[k][l] * mw[l][j];
                        }
                    }
                    ok &= s == gw[i][j];
                }
            }
            if !ok {
                return Err(GroupError::NotOrthogonal { index, frame });
            }
        }
        let mut set: BTreeSet<Matrix> = BTreeSet::new();
        set.insert(IDENTITY);
        let mut frontier = vec![IDENTITY];
        while let Some(a) = frontier.pop() {
            for g in generators {
                let p = mat_mul(&a, g);
                if set.insert(p) {
                    if set.len() > MAX_GROUP_ORDER {
                        return Err(GroupError::TooLarge {
                            bound: MAX_GROUP_ORDER,
                        });
                    }
                    frontier.push(p);
                }
            }
        }
        Ok(Group::from_elements(
            "custom",
            dimension,
            frame,
            set.into_iter().collect(),
            None,
        ))
    }

    /// The same group under another name.
    pub fn with_name(mut self, name: &str) -> Group {
        self.name = name.to_string();
        self
    }

    /// The group's name (`D3`, `D4`, `Td`, `Oh`, or `custom`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// 2 or 3.
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The coordinates the matrices act on.
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// The elements, sorted; the identity is among them.
    pub fn elements(&self) -> &[Matrix] {
        &self.elements
    }

    /// The transposes of [`elements`](Self::elements), in the same order: they act on
    /// frequencies.
    pub fn transposes(&self) -> &[Matrix] {
        &self.transposes
    }

    /// The number of elements.
    pub fn order(&self) -> usize {
        self.elements.len()
    }

    /// The reference element, for the named groups.
    pub fn reference_element(&self) -> Option<ReferenceElement> {
        self.reference
    }

    /// The periodic sampling domain.
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// Whether the group contains −I (then every basis function is real).
    pub fn contains_inversion(&self) -> bool {
        let mut minus = IDENTITY;
        for (r, row) in minus.iter_mut().enumerate().take(self.dimension) {
            row[r] = -1;
        }
        self.elements.binary_search(&minus).is_ok()
    }
}
