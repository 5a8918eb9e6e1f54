//! A z-buffered rasteriser of flat-shaded triangles for one orthographic view.
//!
//! Invariants:
//! - Deterministic for any thread count and any order: each triangle is projected and
//!   shaded by pure functions ([`Raster::screen`], [`Raster::colour`]), and a pixel keeps the
//!   least of its fragments' [`nearest`] numbers (depth first, then the triangle's place in
//!   the sequence). A least is the same however the triangles are shared among [`Frame`]s and
//!   in whatever order each draws its share, and it is the fragment that drawing every
//!   triangle in order, keeping only strictly nearer ones, would leave: the first triangle
//!   wins a tie. So the caller may hand runs of triangles to threads as they come free.
//! - A triangle is passed over as hidden ([`Frame::hides`]) only when every centre of its box
//!   already holds a fragment strictly nearer than any it could give (its least corner depth,
//!   less a margin past rounding): it could not have changed the picture, so what a frame
//!   happens to hold decides the work done, never the result.
//! - Watertight: a pixel centre on an edge shared by two triangles is drawn by exactly one of
//!   them. The edge function at a centre `p` is `(a − p) × (b − p)`, whose bits for `b → a`
//!   are exactly the negated bits for `a → b`, so both triangles see the same value, and an
//!   edge owns its zero line in one direction only (see [`owns`]).
//! - Flat shading with two directional lights fixed to the camera; a face seen from behind
//!   (its outward normal pointing away from the viewer) is tinted red, so an open or inverted
//!   surface shows where its inside is visible.
//!
//! Why no crate: what is needed is ~200 lines (orthographic camera, edge functions, z-buffer),
//! and the determinism and streaming above (chunks added as they are read) are easier to
//! guarantee in our own loop than through a general 3D renderer.

use rayon::prelude::*;

use crate::vec3::{cross, dot};

pub type Rgb = [u8; 3];

/// A face's colour seen from outside, and from inside (the tint).
pub const FRONT: [f32; 3] = [0.80, 0.82, 0.88];
pub const BACK: [f32; 3] = [0.90, 0.16, 0.12];

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 {
        [a[0] / n, a[1] / n, a[2] / n]
    } else {
        a
    }
}

fn mix(a: [f64; 3], b: [f64; 3], sa: f64, sb: f64) -> [f64; 3] {
    [
        a[0] * sa + b[0] * sb,
        a[1] * sa + b[1] * sb,
        a[2] * sa + b[2] * sb,
    ]
}

/// An orthographic camera fitted to a box: model point to pixel (x right, y down) and depth
/// (smaller is nearer).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Unit vectors: screen right, screen up, and from the scene toward the viewer.
    pub right: [f64; 3],
    pub up: [f64; 3],
    pub toward: [f64; 3],
    /// Pixels per model unit.
    pub scale: f64,
    /// The pixel of the model origin's projection.
    pub origin: [f64; 2],
}

impl Camera {
    /// Looking from `toward` (a direction, the viewer at infinity) with `up_hint` up on
    /// screen, the box `[min, max]` centred in a `width × height` panel and filling `fill` of
    /// it.
    pub fn fit(
        toward: [f64; 3],
        up_hint: [f64; 3],
        bbox: [[f64; 3]; 2],
        (width, height): (usize, usize),
        fill: f64,
    ) -> Camera {
        let toward = normalize(toward);
        let right = normalize(cross(up_hint, toward));
        let up = cross(toward, right);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for corner in 0..8 {
            let p = [0, 1, 2].map(|a| bbox[(corner >> a) & 1][a]);
            for (k, axis) in [right, up].into_iter().enumerate() {
                let v = dot(p, axis);
                lo[k] = lo[k].min(v);
                hi[k] = hi[k].max(v);
            }
        }
        let extent = [hi[0] - lo[0], hi[1] - lo[1]];
        let scale = [width as f64 / extent[0], height as f64 / extent[1]]
            .into_iter()
            .filter(|s| s.is_finite() && *s > 0.0)
            .fold(f64::INFINITY, f64::min);
        let scale = if scale.is_finite() { scale * fill } else { 1.0 };
        let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        Camera {
            right,
            up,
            toward,
            scale,
            origin: [
                width as f64 / 2.0 - centre[0] * scale,
                height as f64 / 2.0 + centre[1] * scale,
            ],
        }
    }
}

/// A triangle's corners in pixels, tested against pixel centres: it covers a centre `p`
/// where its three edge functions there, `(a − p) × (b − p)` for each edge `a → b`, have the
/// sign of its area, or are zero on an edge that owns its line ([`owns`]), run the way the
/// triangle turns. Two triangles sharing an edge compute the same bits for it, negated: the
/// products are the same, and a difference negates exactly. So a centre on a shared edge is
/// drawn by exactly one of them.
struct Corners {
    x: [f64; 3],
    y: [f64; 3],
    z: [f64; 3],
    /// The sign of the area: `1` when it turns counter-clockwise on screen, else `−1`.
    turn: f64,
    /// One over twice the area (positive): a multiplication per centre, not a division.
    per_area: f64,
    /// Whether edge `k` (from corner `k + 1` to `k + 2`), run the way the triangle turns,
    /// owns the centres on its line.
    owns: [bool; 3],
}

impl Corners {
    /// `None` for a triangle that covers no centre: of zero area, or with a corner not
    /// finite.
    #[inline]
    fn new(x: [f32; 3], y: [f32; 3], z: [f32; 3]) -> Option<Corners> {
        let (x, y, z) = (x.map(f64::from), y.map(f64::from), z.map(f64::from));
        let area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
        if area == 0.0 || !area.is_finite() {
            return None;
        }
        // Selections, not branches: which way a triangle turns is random.
        let turn = if area > 0.0 { 1.0 } else { -1.0 };
        let owns = [0, 1, 2].map(|k| {
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            let (a, b) = ((x[a], y[a]), (x[b], y[b]));
            owns(if area > 0.0 { (a, b) } else { (b, a) })
        });
        Some(Corners {
            x,
            y,
            z,
            turn,
            per_area: 1.0 / (area * turn),
            owns,
        })
    }

    /// Whether the triangle covers the centre of pixel `(px, py)`, and its depth there
    /// (meaningless where it does not). Without branches: which way each test goes is random.
    #[inline(always)]
    fn fragment(&self, px: u32, py: u32) -> (bool, f32) {
        let (cx, cy) = (f64::from(px) + 0.5, f64::from(py) + 0.5);
        let rx = self.x.map(|x| x - cx);
        let ry = self.y.map(|y| y - cy);
        // Edge `k` runs from corner `k + 1` to `k + 2`.
        let w = [
            rx[1] * ry[2] - ry[1] * rx[2],
            rx[2] * ry[0] - ry[2] * rx[0],
            rx[0] * ry[1] - ry[0] * rx[1],
        ]
        .map(|w| w * self.turn);
        // Inside an edge, or on its line if it owns it.
        let within = |k: usize| (w[k] > 0.0) | ((w[k] == 0.0) & self.owns[k]);
        let z = self.z;
        let depth = ((w[0] * z[0] + w[1] * z[1] + w[2] * z[2]) * self.per_area) as f32;
        (within(0) & within(1) & within(2), depth)
    }

    /// The depth at the centre of pixel `(px, py)`, if the triangle covers it.
    #[cfg(test)]
    fn depth_at(&self, px: u32, py: u32) -> Option<f32> {
        let (covers, depth) = self.fragment(px, py);
        covers.then_some(depth)
    }
}

/// What part of a view's triangles drew: at each pixel, the nearest fragment found so far.
/// A view's triangles may be shared among several frames in any way (one per thread, say):
/// [`Raster::pixels`] takes the nearest of theirs, which is the same whatever the sharing.
pub struct Frame {
    /// The fragment's depth and triangle as one number ([`nearest`]), [`EMPTY`] where none.
    nearest: Vec<u64>,
    /// The fragment's colour, packed ([`pack`]).
    rgb: Vec<u32>,
}

/// A pixel no triangle has drawn.
const EMPTY: u64 = u64::MAX;

/// A fragment of depth `depth` (finite or −∞, not NaN) from the triangle numbered `index` in
/// the order triangles were added, as one number: the smaller number is the nearer fragment,
/// or on a tie of depth the earlier triangle's. So the nearest over any sharing of the
/// triangles is the one the first triangle of least depth draws, as drawing them one by one in
/// order and keeping only strictly nearer fragments would leave. Below [`EMPTY`].
#[inline(always)]
fn nearest(depth: f32, index: u64) -> u64 {
    // `+ 0.0` makes −0 into +0, which compares equal to it. The bits of a float, with the
    // sign bit flipped when positive and all bits when negative, order as the float does.
    let bits = (depth + 0.0).to_bits();
    let ordered = bits ^ ((bits as i32 >> 31) as u32 | 1 << 31);
    // The index wraps past 2³² triangles: ties (of exactly equal depth) are then settled by
    // the colour too ([`Frame::offer`]), still the same whatever the sharing.
    u64::from(ordered) << 32 | (index & 0xffff_ffff)
}

/// A colour as one number, ordered as the colour is (red, then green, then blue).
fn pack([r, g, b]: Rgb) -> u32 {
    u32::from(r) << 16 | u32::from(g) << 8 | u32::from(b)
}

fn unpack(rgb: u32) -> Rgb {
    [(rgb >> 16) as u8, (rgb >> 8) as u8, rgb as u8]
}

impl Frame {
    /// Whether a fragment nearer than any the small triangle of screen positions `s` could
    /// give is already at each centre of its box `(cols, rows)`, in a frame `width` wide: then
    /// drawing it would change nothing, and it is passed over (drawn front to back, most of
    /// a big mesh's triangles behind its first layer are). Never true where it could draw.
    #[inline(always)]
    fn hides(
        &self,
        width: usize,
        s: [[f32; 3]; 3],
        (cols, rows): ((u32, u32), (u32, u32)),
    ) -> bool {
        // Only small triangles (most of a big mesh's), for which the bound below holds.
        if cols.1 - cols.0 > 2 || rows.1 - rows.0 > 2 {
            return false;
        }
        let (x, y) = (s.map(|c| f64::from(c[0])), s.map(|c| f64::from(c[1])));
        let area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
        // A fragment's depth is the corners' depths weighted by its edge functions over
        // twice the area: weights that sum to one but for rounding. For a triangle at most
        // 4 pixels across and of area at least 2⁻¹⁶ pixels², each weight is exact but for one
        // rounding and so is the area but for a few parts in 10¹⁰: a fragment is nearer than
        // the least corner depth by far less than a millionth of the depths' size. (NaN
        // fails too.)
        let spread = |v: [f64; 3]| v[0].max(v[1]).max(v[2]) - v[0].min(v[1]).min(v[2]);
        let small = (spread(x) <= 4.0) & (spread(y) <= 4.0) & (area.abs() >= 1.0 / 65536.0);
        if !small {
            return false;
        }
        let z = s.map(|c| f64::from(c[2]));
        let (low, high) = (z[0].min(z[1]).min(z[2]), z[0].max(z[1]).max(z[2]));
        let bound = (low - (low.abs() + high.abs()) / 1_048_576.0) as f32;
        if !bound.is_finite() {
            return false;
        }
        // Below the `f32` under the bound (which may round up to it): nearer than any.
        let below = nearest(bound.next_down(), 0) >> 32;
        let mut hidden = true;
        each_centre((cols, rows), |px, py| {
            let at = py as usize * width + px as usize;
            hidden &= self.nearest[at] >> 32 < below;
        });
        hidden
    }

    /// Keeps, if `keep`, the fragment `key` ([`nearest`]) of colour `rgb` ([`pack`]) at pixel
    /// `at` when it is nearer than the one there (or, for the same key, of a smaller colour).
    /// Without branches: which fragments are kept is random.
    #[inline(always)]
    fn offer(&mut self, keep: bool, at: usize, key: u64, rgb: u32) {
        let (here, here_rgb) = (self.nearest[at], self.rgb[at]);
        let wins = keep & ((key < here) | ((key == here) & (rgb < here_rgb)));
        self.nearest[at] = if wins { key } else { here };
        self.rgb[at] = if wins { rgb } else { here_rgb };
    }
}

/// One view: its camera and lighting, and the map from model points to pixels.
pub struct Raster {
    pub camera: Camera,
    /// The camera's map to pixels across, down and depth, as `f32` rows `[x, y, z, 1]·row`.
    to_screen: [[f32; 4]; 3],
    /// Half a pixel past the last centre across and down: where [`Raster::cells`] clamps.
    last_cell: [f32; 2],
    width: usize,
    height: usize,
    background: Rgb,
    lighting: Lighting,
}

/// Two directional lights fixed to the camera, and the direction toward the viewer (which
/// tells a face seen from behind).
#[derive(Clone, Copy)]
struct Lighting {
    toward: [f32; 3],
    lights: [[f32; 3]; 2],
}

impl Lighting {
    /// The colour of a face of (unnormalised) outward normal `n`. In `f32` and without
    /// branches: it runs for every triangle drawn, and which way a face turns is random.
    #[inline(always)]
    fn shade(&self, n: [f32; 3]) -> Rgb {
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let length = dot(n, n).sqrt();
        let front = dot(n, self.toward) >= 0.0;
        // A face seen from behind is lit as if turned toward the viewer. A zero normal
        // (a degenerate face) gets the ambient light only.
        let scale = if length > 0.0 { 1.0 / length } else { 0.0 };
        let scale = if front { scale } else { -scale };
        let lit = |light: [f32; 3]| (dot(n, light) * scale).max(0.0);
        let light = 0.22 + 0.68 * lit(self.lights[0]) + 0.30 * lit(self.lights[1]);
        let base = if front { FRONT } else { BACK };
        // `+ 0.5` then truncation rounds a non-negative value, without `round` (a library
        // call on the baseline x86-64 target).
        base.map(|c| (255.0 * (c * light).clamp(0.0, 1.0) + 0.5) as u8)
    }
}

/// Calls `at(px, py)` for each pixel of columns `cols` and rows `rows` (`[first, last + 1)`
/// each, not empty), row by row, in one loop without branches but the loop's own: most boxes
/// hold one to four centres, and what is done at each is decided without branches too.
#[inline(always)]
fn each_centre((cols, rows): ((u32, u32), (u32, u32)), mut at: impl FnMut(u32, u32)) {
    let (mut px, mut py) = (cols.0, rows.0);
    for _ in 0..(cols.1 - cols.0) * (rows.1 - rows.0) {
        at(px, py);
        px += 1;
        let wrap = px == cols.1;
        px = if wrap { cols.0 } else { px };
        py += u32::from(wrap);
    }
}

/// Whether the directed edge `a → b` owns the pixel centres exactly on it: exactly one of
/// `a → b` and `b → a` does, so two triangles sharing an edge never both draw, nor both skip,
/// such a pixel.
fn owns((a, b): ((f64, f64), (f64, f64))) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    dy > 0.0 || (dy == 0.0 && dx > 0.0)
}

/// The pixels `i` of `0..n` whose centre `i + 0.5` lies in `[lo, hi]`, as `(first, last + 1)`,
/// empty (`first ≥ last + 1`) when there are none or a bound is NaN. Without branches (most
/// triangles of a big mesh are looked at here, and which way a test goes is random) and
/// without `ceil`/`floor` (library calls on the baseline x86-64 target).
#[inline(always)]
fn centres(lo: f32, hi: f32, n: usize) -> (u32, u32) {
    let top = n as f64 - 1.0;
    // Exact: an f32 less a half is an f64. `max`/`min` drop a NaN, so a NaN `lo` becomes `n`
    // and a NaN `hi` becomes −1: nothing between.
    let lo = (f64::from(lo) - 0.5).max(0.0).min(n as f64);
    let hi = (f64::from(hi) - 0.5).min(top).max(-1.0);
    // `lo` in [0, n] and `hi + 1` in [0, n], where truncation is the floor.
    let first = lo as u32 + u32::from(f64::from(lo as u32) < lo);
    let end = (hi + 1.0) as u32;
    (first, end)
}

impl Raster {
    /// A view of `size` pixels for `camera`, `background` where nothing is drawn.
    pub fn new(camera: Camera, (width, height): (usize, usize), background: Rgb) -> Raster {
        // A key light from the viewer's upper left, a weaker fill from the right.
        let key = normalize(mix(
            camera.toward,
            mix(camera.up, camera.right, 0.6, -0.5),
            1.0,
            1.0,
        ));
        let fill = normalize(mix(
            camera.toward,
            mix(camera.right, camera.up, 0.9, -0.2),
            0.6,
            1.0,
        ));
        let row = |axis: [f64; 3], scale: f64, offset: f64| {
            [axis[0] * scale, axis[1] * scale, axis[2] * scale, offset].map(|v| v as f32)
        };
        let to_screen = [
            row(camera.right, camera.scale, camera.origin[0]),
            row(camera.up, -camera.scale, camera.origin[1]),
            row(camera.toward, -1.0, 0.0),
        ];
        Raster {
            camera,
            to_screen,
            last_cell: [width as f32 + 0.5, height as f32 + 0.5],
            width,
            height,
            background,
            lighting: Lighting {
                toward: camera.toward.map(|v| v as f32),
                lights: [key, fill].map(|l| l.map(|v| v as f32)),
            },
        }
    }

    /// The pixel position (`origin + p·right·scale` across, `origin − p·up·scale` down) and
    /// depth (`−p·toward`) of model point `p`, worked out in `f32`, precise enough for a
    /// picture and cheaper per vertex: a pure function, so every triangle using a vertex gets
    /// the same bits for it.
    #[inline(always)]
    pub fn screen(&self, p: [f32; 3]) -> [f32; 3] {
        self.to_screen
            .map(|r| r[0] * p[0] + r[1] * p[1] + r[2] * p[2] + r[3])
    }

    /// The cells between pixel centres that screen position `s` lies in, across and down:
    /// `i` when it lies strictly between the centres of columns `i − 1` and `i` (`0` before
    /// the first centre, `n` after the last), `None` on a centre's line, or NaN; the same for
    /// rows. A triangle whose corners share a cell on either axis covers no pixel centre
    /// ([`Raster::covers`] is `None`): most triangles of a big mesh are seen to be passed over
    /// by comparing numbers worked out once per vertex.
    #[inline(always)]
    pub fn cells(&self, s: [f32; 3]) -> [Option<u32>; 2] {
        let axis = |v: f32, last: f32| {
            // Cell `i` is where `i < v + 0.5 < i + 1`. Rounding the sum can land on a whole
            // number, never past one: a wrong cell is never given, at worst none.
            let w = v + 0.5;
            // Clamped to non-whole bounds, so a point off the panel is never on a line; NaN
            // stays NaN (no cell).
            let w = if w < 0.5 { 0.5 } else { w };
            let w = if w > last { last } else { w };
            // Truncation is the floor here (w > 0); a whole w, or NaN, is no cell.
            let cell = w as u32;
            ((cell as f32) < w).then_some(cell)
        };
        [axis(s[0], self.last_cell[0]), axis(s[1], self.last_cell[1])]
    }

    /// The pixel columns and rows whose centres the bounding box of a triangle of screen
    /// positions `s` holds; `None` when it covers no pixel centre. Most triangles of a big
    /// mesh are smaller than a pixel and cover none, so that is decided first, from the
    /// projected corners alone.
    #[inline]
    pub fn covers(&self, s: [[f32; 3]; 3]) -> Option<((u32, u32), (u32, u32))> {
        // A NaN corner drops out of the box here; the triangle then has a NaN area and is
        // drawn nowhere ([`Corners::new`]).
        let lo = [0, 1].map(|k| s[0][k].min(s[1][k]).min(s[2][k]));
        let hi = [0, 1].map(|k| s[0][k].max(s[1][k]).max(s[2][k]));
        let cols = centres(lo[0], hi[0], self.width);
        let rows = centres(lo[1], hi[1], self.height);
        // One branch for both axes.
        ((cols.0 < cols.1) & (rows.0 < rows.1)).then_some((cols, rows))
    }

    /// The (unnormalised) outward normal of a face of model corners `corners`.
    #[inline]
    fn normal([a, b, c]: [[f32; 3]; 3]) -> [f32; 3] {
        let (u, v) = (
            [0, 1, 2].map(|k| b[k] - a[k]),
            [0, 1, 2].map(|k| c[k] - a[k]),
        );
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    }

    /// The colour of a face of model corners `corners`, packed for [`Raster::draw`].
    #[inline]
    pub fn colour(&self, corners: [[f32; 3]; 3]) -> u32 {
        pack(self.lighting.shade(Raster::normal(corners)))
    }

    /// The bytes a frame of this view takes ([`Raster::frame`]).
    pub fn frame_bytes(&self) -> usize {
        self.width * self.height * (size_of::<u64>() + size_of::<u32>())
    }

    /// A frame of this view with nothing drawn.
    pub fn frame(&self) -> Frame {
        Frame {
            nearest: vec![EMPTY; self.width * self.height],
            rgb: vec![0; self.width * self.height],
        }
    }

    /// Draws into `frame` the triangle numbered `index` (in the order triangles are added),
    /// of screen positions `s` and model corners `corners`, coloured by its face; `(cols,
    /// rows)` are the pixels whose centres its box holds ([`Raster::covers`]).
    #[inline]
    pub fn draw(
        &self,
        frame: &mut Frame,
        index: u64,
        (s, corners): ([[f32; 3]; 3], [[f32; 3]; 3]),
        (cols, rows): ((u32, u32), (u32, u32)),
    ) {
        if frame.hides(self.width, s, (cols, rows)) {
            return;
        }
        let Some(c) = Corners::new(s.map(|c| c[0]), s.map(|c| c[1]), s.map(|c| c[2])) else {
            return;
        };
        let rgb = self.colour(corners);
        each_centre((cols, rows), |px, py| {
            let (covers, depth) = c.fragment(px, py);
            // Not drawn at a NaN or +∞ depth, as a z-buffer starting at +∞ would not.
            let keep = covers & (depth < f32::INFINITY);
            let at = py as usize * self.width + px as usize;
            frame.offer(keep, at, nearest(depth, index), rgb);
        });
    }

    /// The picture, row by row: at each pixel the nearest fragment of all `frames`, which
    /// together drew every triangle.
    pub fn pixels(&self, frames: &[Frame]) -> Vec<Rgb> {
        (0..self.width * self.height)
            .into_par_iter()
            .with_min_len(4096)
            .map(|at| {
                let best = frames.iter().map(|f| (f.nearest[at], f.rgb[at])).min();
                match best {
                    Some((key, rgb)) if key != EMPTY => unpack(rgb),
                    _ => self.background,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::xorshift;

    /// A frame of `size` pixels looking down on the unit cube.
    fn seen_from_above(size: (usize, usize), background: Rgb) -> Raster {
        let top = [0.0, 0.0, 1.0];
        let camera = Camera::fit(top, [0.0, 1.0, 0.0], [[0.0; 3], [1.0; 3]], size, 0.9);
        Raster::new(camera, size, background)
    }

    #[test]
    fn a_triangle_within_one_cell_covers_no_pixel_centre() {
        let (width, height) = (24, 16);
        let raster = seen_from_above((width, height), [0; 3]);
        // Coordinates on centres, between them, on the panel's edges, far off it, NaN.
        let mut values: Vec<f32> = (-12..=4 * width as i32 + 12)
            .map(|k| k as f32 / 4.0)
            .collect();
        values.extend([
            -1e9,
            1e9,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            0.5001,
            0.4999,
        ]);
        let mut random = xorshift(0x2545_f491_4f6c_dd1d);
        let mut pick = || values[(random() % values.len() as u64) as usize];
        let (mut shared, mut covering) = (0, 0);
        for round in 0..300_000 {
            // Corners near one another (most share a cell) or anywhere.
            let near = [pick(), pick()];
            let mut corner = |k: usize| {
                let nudge = [pick(), pick()].map(|v| if v.is_finite() { v % 0.5 } else { 0.0 });
                match k % 2 {
                    0 => [near[0] + nudge[0], near[1] + nudge[1], 0.0],
                    _ => [pick(), pick(), 0.0],
                }
            };
            let s: [[f32; 3]; 3] =
                std::array::from_fn(|c| corner(if round % 3 == 0 { c } else { 0 }));
            let cells = s.map(|p| raster.cells(p));
            let cover = raster.covers(s);
            covering += usize::from(cover.is_some());
            for axis in 0..2 {
                let cell = cells[0][axis];
                if cell.is_some() && cells.iter().all(|c| c[axis] == cell) {
                    shared += 1;
                    assert_eq!(cover, None, "{s:?} in cell {cell:?} on axis {axis}");
                }
            }
            // A point's cell is the pair of centres around it.
            for (p, cells) in s.iter().zip(cells) {
                for (v, c, n) in [(p[0], cells[0], width), (p[1], cells[1], height)] {
                    let Some(c) = c else { continue };
                    let v = f64::from(v);
                    assert!(c == 0 || v > f64::from(c) - 0.5, "{v} in cell {c}");
                    assert!(c as usize == n || v < f64::from(c) + 0.5, "{v} in cell {c}");
                }
            }
        }
        // Both cases were met often.
        assert!(shared > 10_000 && covering > 10_000, "{shared} {covering}");
    }

    #[test]
    fn a_triangulated_square_covers_each_centre_inside_exactly_once() {
        // A 24 × 24-pixel square cut into triangles whose corners sit on pixel centres, on
        // half-pixels and in between, so many edges run exactly through centres; both turns
        // (a face seen from the front and from behind) and both diagonals.
        let n = 48;
        let mut random = xorshift(0x9e37_79b9_7f4a_7c15);
        let mut jitter = || [0.0, 0.0, 0.25, 0.1, -0.125][(random() % 5) as usize];
        let corner: Vec<Vec<(f32, f32)>> = (0..=n)
            .map(|j| {
                (0..=n)
                    .map(|i| {
                        // The square's outline stays straight.
                        let edge = i == 0 || j == 0 || i == n || j == n;
                        let (dx, dy) = if edge {
                            (0.0, 0.0)
                        } else {
                            (jitter(), jitter())
                        };
                        (4.0 + i as f32 * 0.5 + dx, 4.0 + j as f32 * 0.5 + dy)
                    })
                    .collect()
            })
            .collect();
        for backwards in [false, true] {
            let mut claims = vec![0u32; 40 * 40];
            for j in 0..n {
                for i in 0..n {
                    let (a, b, c, d) = (
                        corner[j][i],
                        corner[j][i + 1],
                        corner[j + 1][i + 1],
                        corner[j + 1][i],
                    );
                    let halves = if (i + j) % 2 == 0 {
                        [[a, b, c], [a, c, d]]
                    } else {
                        [[a, b, d], [b, c, d]]
                    };
                    for mut t in halves {
                        if backwards {
                            t.swap(1, 2);
                        }
                        let Some(corners) = Corners::new(t.map(|p| p.0), t.map(|p| p.1), [1.0; 3])
                        else {
                            continue;
                        };
                        for py in 0..40 {
                            for px in 0..40 {
                                if let Some(depth) = corners.depth_at(px, py) {
                                    assert_eq!(depth, 1.0);
                                    claims[(py * 40 + px) as usize] += 1;
                                }
                            }
                        }
                    }
                }
            }
            // Centres strictly inside the square (4, 28)²: 4.5 … 27.5.
            for py in 0..40 {
                for px in 0..40 {
                    let inside = (4..28).contains(&px) && (4..28).contains(&py);
                    let expected = u32::from(inside);
                    let got = claims[py * 40 + px];
                    assert_eq!(got, expected, "pixel ({px}, {py}), backwards {backwards}");
                }
            }
        }
    }

    /// Draws triangle `t` (model corners) if its box holds a centre.
    fn draw(raster: &Raster, frame: &mut Frame, index: u64, t: [[f32; 3]; 3]) {
        let s = t.map(|p| raster.screen(p));
        if let Some(centres) = raster.covers(s) {
            raster.draw(frame, index, (s, t), centres);
        }
    }

    #[test]
    fn triangles_shared_among_frames_in_any_order_draw_what_drawing_each_in_order_draws() {
        // Triangles from less than a pixel to most of the frame across, many overlapping at
        // random depths, some with corners off the panel; and some drawn again later, the
        // same or turned the other way (the same depths, another colour), which must lose.
        let (width, height) = (200, 150);
        let raster = seen_from_above((width, height), [7, 8, 9]);
        let mut random = xorshift(0x5851_f42d_4c95_7f2d);
        let mut unit = {
            let mut random = xorshift(0x2545_f491_4f6c_dd1d);
            move || (random() >> 11) as f32 / (1u64 << 53) as f32
        };
        let mut triangles: Vec<[[f32; 3]; 3]> = (0..4000)
            .map(|i| {
                let size = [0.004, 0.03, 0.3, 1.2][i % 4];
                let centre = [unit() * 1.2 - 0.1, unit() * 1.2 - 0.1, unit()];
                std::array::from_fn(|_| {
                    [
                        centre[0] + (unit() - 0.5) * size,
                        centre[1] + (unit() - 0.5) * size,
                        centre[2] + (unit() - 0.5) * 0.1,
                    ]
                })
            })
            .collect();
        for i in (0..4000).step_by(7) {
            let [a, b, c] = triangles[i];
            triangles.push(if i % 2 == 0 { [a, c, b] } else { [a, b, c] });
        }
        // The reference: each triangle, in order, tested at every pixel of the frame, a
        // fragment kept only when strictly nearer.
        let mut depth = vec![f32::INFINITY; width * height];
        let mut rgb = vec![[7u8, 8, 9]; width * height];
        for t in &triangles {
            let s = t.map(|p| raster.screen(p));
            let Some(c) = Corners::new(s.map(|p| p[0]), s.map(|p| p[1]), s.map(|p| p[2])) else {
                continue;
            };
            for py in 0..height {
                for px in 0..width {
                    let at = py * width + px;
                    if let Some(d) = c.depth_at(px as u32, py as u32)
                        && d < depth[at]
                    {
                        depth[at] = d;
                        rgb[at] = unpack(raster.colour(*t));
                    }
                }
            }
        }
        // Shared among one to four frames at random, each drawing its share backwards.
        for frames in 1..=4 {
            let mut shares = vec![Vec::new(); frames];
            for (i, t) in triangles.iter().enumerate() {
                shares[(random() % frames as u64) as usize].push((i as u64, *t));
            }
            let drawn: Vec<Frame> = shares
                .iter()
                .map(|share| {
                    let mut frame = raster.frame();
                    for &(i, t) in share.iter().rev() {
                        draw(&raster, &mut frame, i, t);
                    }
                    frame
                })
                .collect();
            let pixels = raster.pixels(&drawn);
            assert!(pixels == rgb, "{frames} frames draw another picture");
        }
        // Most of the frame was drawn; and the repeated triangles turned the other way would
        // show (as red) where they won ties: the tie rule is tested, not idle.
        let covered = depth.iter().filter(|d| d.is_finite()).count();
        assert!(covered > width * height / 2, "{covered} pixels drawn");
        let mut last_wins = raster.frame();
        for (i, t) in triangles.iter().enumerate() {
            draw(&raster, &mut last_wins, (triangles.len() - i) as u64, *t);
        }
        let ties = (raster.pixels(&[last_wins]).iter().zip(&rgb))
            .filter(|(a, b)| a != b)
            .count();
        assert!(ties > 100, "{ties} pixels won on a tie");
    }

    #[test]
    fn a_triangle_is_passed_over_as_hidden_only_where_it_would_change_nothing() {
        // Triangles of about a pixel in layers: some far apart in depth, some a ten-millionth
        // apart, some at exactly one depth (ties the earlier triangle must win), with slivers.
        // Drawn from front to back, most are seen to be hidden; the picture is the in-order one.
        let (width, height) = (80, 60);
        let raster = seen_from_above((width, height), [7, 8, 9]);
        let mut unit = {
            let mut random = xorshift(0x9e37_79b9_7f4a_7c15);
            move || (random() >> 11) as f32 / (1u64 << 53) as f32
        };
        let layers = [0.2, 0.5, 0.5 + 1e-7, 0.5, 0.8];
        let triangles: Vec<[[f32; 3]; 3]> = (0..40_000)
            .map(|i| {
                let (size, z) = ([0.02, 0.03, 0.035][i % 3], layers[i % 5]);
                let centre = [unit(), unit()];
                let sliver = i % 7 == 0;
                std::array::from_fn(|k| {
                    let t = if sliver { k as f32 * 0.5 } else { unit() };
                    let u = if sliver { t * 1e-4 } else { unit() };
                    [
                        centre[0] + (t - 0.5) * size,
                        centre[1] + (u - 0.5) * size,
                        z,
                    ]
                })
            })
            .collect();
        // The reference: each triangle in order over its box, keeping strictly nearer ones.
        let mut depth = vec![f32::INFINITY; width * height];
        let mut rgb = vec![[7u8, 8, 9]; width * height];
        for t in &triangles {
            let s = t.map(|p| raster.screen(p));
            let (Some(((x0, x1), (y0, y1))), Some(c)) = (
                raster.covers(s),
                Corners::new(s.map(|p| p[0]), s.map(|p| p[1]), s.map(|p| p[2])),
            ) else {
                continue;
            };
            for py in y0..y1 {
                for px in x0..x1 {
                    let at = py as usize * width + px as usize;
                    if let Some(d) = c.depth_at(px, py)
                        && d < depth[at]
                    {
                        depth[at] = d;
                        rgb[at] = unpack(raster.colour(*t));
                    }
                }
            }
        }
        // Nearest first (the view looks down: higher is nearer), ties in reverse order.
        let mut order: Vec<usize> = (0..triangles.len()).collect();
        order.sort_by(|&a, &b| {
            triangles[b][0][2]
                .total_cmp(&triangles[a][0][2])
                .then(b.cmp(&a))
        });
        let mut frame = raster.frame();
        let mut hidden = 0;
        for &i in &order {
            let s = triangles[i].map(|p| raster.screen(p));
            if let Some(centres) = raster.covers(s) {
                hidden += usize::from(frame.hides(width, s, centres));
                raster.draw(&mut frame, i as u64, (s, triangles[i]), centres);
            }
        }
        assert!(
            raster.pixels(&[frame]) == rgb,
            "hidden triangles changed the picture"
        );
        assert!(hidden > triangles.len() / 10, "{hidden} hidden");
    }
}
