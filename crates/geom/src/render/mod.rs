//! Preview images of meshes: a headless software render, with no GPU and no display.
//!
//! A preview is an isometric view of the mesh ([`raster`]: z-buffered, flat-shaded by two
//! lights, faces seen from behind tinted red) beside its section by the plane through the
//! middle of its box ([`section`]: the cut region filled, pores empty), over a caption band
//! of text lines ([`font`]). A planar region (a 2D output) is drawn alone, seen from above.
//!
//! Invariants:
//! - The image is a pure function of the [`Spec`] and of the sequence of triangles added,
//!   the same bytes for any thread count (see [`raster`] and [`section`]).
//! - Triangles may be added in any number of calls (a tiling's chunks, streamed): the result
//!   is that of adding them all at once, so a mesh is never needed whole in memory.
//! - The caption is given last ([`Preview::finish`]) and its band has one height, room for a
//!   title and [`MAX_WARNINGS`] warnings, whatever it holds: the panels can be drawn before
//!   the caption is known (a tiling's, while it tiles) and come out the same.
//! - PNG bytes come from the `png` crate at fixed settings: same pixels, same bytes.

pub mod font;
mod pass;
pub mod raster;
pub mod section;

use std::io::{self, Write};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::mesh::{Mesh, MeshChunk};

use rayon::prelude::*;

use pass::Keyed;
use raster::{Camera, Frame, Raster, Rgb};
use section::{Section, Segment};

const BACKGROUND: Rgb = [250, 250, 250];
const CAPTION_BACKGROUND: Rgb = [32, 34, 40];
const TITLE: Rgb = [240, 240, 240];
const WARNING: Rgb = [255, 190, 70];
const LABEL: Rgb = [120, 120, 130];
/// The section's solid, and the frame of the box it is cut from.
pub const CUT: Rgb = [60, 92, 150];
const FRAME: Rgb = [200, 200, 205];
/// Warnings shown (one line each, cut to the width); more are counted on the last line.
const MAX_WARNINGS: usize = 4;
/// The share of a panel the drawing fills.
const FILL: f64 = 0.86;
/// Triangles one task takes in a row, so the thread pool's cost per task is small against it.
const RUN: usize = pass::RUN;
/// At most this many frames draw a view at once (each is the size of the view)...
const MAX_PARTS: usize = 8;
/// ...and no more than fit in this many bytes together (a preview 8192 pixels a side has
/// frames of 400 MB: it is drawn by one worker).
const FRAMES_BUDGET: usize = 256 << 20;

/// What one worker drew: its frame of the view, and the cuts by the section's plane not yet
/// recorded.
struct Part {
    frame: Frame,
    cuts: Vec<Segment>,
    /// The first triangle it met with a corner the chunk does not have.
    bad: Option<usize>,
}

/// One line of the caption.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    pub text: String,
    pub warning: bool,
}

/// What to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Spec {
    /// Width and height in pixels.
    pub size: (usize, usize),
    /// The box the views are fitted to (the mesh's).
    pub bbox: [[f64; 3]; 2],
    /// `Some(z0)`: isometric view and the section at `z = z0`; `None`: a planar region, seen
    /// from above.
    pub cut: Option<f64>,
}

/// An RGB image, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<Rgb>,
}

/// Where things go in the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    /// The text's scale (pixels per font pixel).
    pub text_scale: usize,
    /// The panels' height (the caption band is below).
    pub panel_height: usize,
    /// The view's panel `(x0, width)`, and the section's.
    pub view: (usize, usize),
    pub section: Option<(usize, usize)>,
}

/// A caption's lines as drawn: the title, then at most [`MAX_WARNINGS`] warnings (the last
/// saying how many more there were).
pub fn caption_lines(caption: &[Line]) -> Vec<Line> {
    let mut lines: Vec<Line> = caption.iter().take(1 + MAX_WARNINGS).cloned().collect();
    let hidden = caption.len().saturating_sub(1 + MAX_WARNINGS);
    if hidden > 0
        && let Some(last) = lines.last_mut()
    {
        last.text = format!("(+{} more warnings) {}", hidden + 1, last.text);
    }
    lines
}

impl Spec {
    pub fn layout(&self) -> Layout {
        let (width, height) = self.size;
        let text_scale = if width >= 900 { 2 } else { 1 };
        // Room for every line a caption may have, whatever this one holds: the panels are
        // drawn before the caption is known (a tiling's, while it tiles).
        let band = (1 + MAX_WARNINGS) * font::CELL.1 * text_scale + 8 * text_scale;
        let panel_height = height.saturating_sub(band).max(1);
        let (view, section) = match self.cut {
            Some(_) => ((0, width / 2), Some((width / 2, width - width / 2))),
            None => ((0, width), None),
        };
        Layout {
            text_scale,
            panel_height,
            view,
            section,
        }
    }
}

/// A preview being drawn: add the mesh's triangles, then [`Preview::finish`].
pub struct Preview {
    spec: Spec,
    layout: Layout,
    view: Raster,
    section: Option<Section>,
    /// One per worker, made when the first triangles come.
    parts: Vec<Part>,
    /// Triangles added so far: the next one's number.
    added: u64,
    /// The keys of a chunk's vertices, kept from one chunk to the next: a tiling's hundreds
    /// of chunks would otherwise each fault fresh pages in for them.
    keys: pass::Keys,
}

impl Preview {
    pub fn new(spec: Spec) -> Preview {
        let layout = spec.layout();
        let h = layout.panel_height;
        let (toward, up) = match spec.cut {
            // Isometric, from +x −y +z, z up.
            Some(_) => ([1.0, -1.0, 1.0], [0.0, 0.0, 1.0]),
            None => ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        };
        let camera = Camera::fit(toward, up, spec.bbox, (layout.view.1, h), FILL);
        let view = Raster::new(camera, (layout.view.1, h), BACKGROUND);
        let section = match (spec.cut, layout.section) {
            (Some(z0), Some((_, w))) => Some(Section::new(z0, spec.bbox, (w, h), FILL)),
            _ => None,
        };
        Preview {
            spec,
            layout,
            view,
            section,
            parts: Vec::new(),
            added: 0,
            keys: pass::Keys::default(),
        }
    }

    pub fn layout(&self) -> Layout {
        self.layout
    }

    pub fn spec(&self) -> &Spec {
        &self.spec
    }

    /// The view's camera (in its panel's pixels).
    pub fn camera(&self) -> Camera {
        self.view.camera
    }

    /// Adds `triangles`, their corners found in `vertices`; `Err(i)` when triangle `i` has
    /// one that is not there. Workers take runs of triangles as they come free, each drawing
    /// into its own frame (the picture does not depend on which drew what, see [`raster`]).
    /// Only the triangles not passed over ([`pass`]) are looked at: their corners projected,
    /// their box and cut found.
    fn add(
        view: &Raster,
        section: Option<&Section>,
        parts: &mut [Part],
        (triangles, first_index): (&[[u32; 3]], u64),
        vertices: &Keyed,
    ) -> Result<(), usize> {
        let runs = triangles.len().div_ceil(RUN);
        let next = AtomicUsize::new(0);
        let backwards = nearer_last(view, triangles, vertices);
        parts.par_iter_mut().for_each(|part| {
            loop {
                let r = next.fetch_add(1, Ordering::Relaxed);
                if r >= runs {
                    break;
                }
                let r = if backwards { runs - 1 - r } else { r };
                let first = r * RUN;
                let last = (first + RUN).min(triangles.len());
                let (looked_at, count) = vertices.look_at(&triangles[first..last]);
                for &k in &looked_at[..count] {
                    let i = first + k as usize;
                    let t = triangles[i];
                    let (Some(a), Some(b), Some(c)) = (
                        vertices.corner(t[0]),
                        vertices.corner(t[1]),
                        vertices.corner(t[2]),
                    ) else {
                        part.bad = Some(part.bad.map_or(i, |b| b.min(i)));
                        break;
                    };
                    let model = [a.0, b.0, c.0];
                    // Projected again (the same bits as for its key).
                    let screen = model.map(|p| view.screen(p));
                    // The box's centres from the keys where they tell (most often).
                    let centres = pass::centres([a.1, b.1, c.1]).or_else(|| view.covers(screen));
                    if let Some(centres) = centres {
                        let index = first_index + i as u64;
                        view.draw(&mut part.frame, index, (screen, model), centres);
                    }
                    if let Some(s) = section
                        && s.meets([model[0][2], model[1][2], model[2][2]])
                    {
                        part.cuts.extend(s.segment(model));
                    }
                }
            }
        });
        if let Some(bad) = parts.iter_mut().filter_map(|p| p.bad.take()).min() {
            return Err(bad);
        }
        Ok(())
    }

    /// Adds `triangles` whose corners are `first, first + 1, …` in `own` and, below
    /// `first`, the ids of `borrowed`; each vertex is placed once, however many triangles
    /// share it.
    fn add_indexed(
        &mut self,
        triangles: &[[u32; 3]],
        first: u32,
        own: &[[f32; 3]],
        borrowed: &[(u32, [f32; 3])],
    ) -> Result<(), usize> {
        if self.parts.is_empty() {
            let fit = FRAMES_BUDGET / self.view.frame_bytes().max(1);
            let workers = rayon::current_num_threads().min(MAX_PARTS).min(fit).max(1);
            // Each frame is made (its pages faulted in and filled) by a thread of the pool.
            let view = &self.view;
            self.parts = (0..workers)
                .into_par_iter()
                .map(|_| Part {
                    frame: view.frame(),
                    cuts: Vec::new(),
                    bad: None,
                })
                .collect();
        }
        let z0 = self.section.as_ref().map(|s| s.z0);
        let vertices = self.keys.key(&self.view, z0, first, own, borrowed);
        let added = Preview::add(
            &self.view,
            self.section.as_ref(),
            &mut self.parts,
            (triangles, self.added),
            &vertices,
        );
        self.added += triangles.len() as u64;
        // The section's crossings are sorted before it is filled: any order will do.
        if let Some(section) = &mut self.section {
            for part in &mut self.parts {
                for cut in part.cuts.drain(..) {
                    section.cross(cut);
                }
            }
        }
        added
    }

    /// Adds a whole mesh. The keys kept for a next chunk are let go (a whole mesh has none):
    /// for a mesh of millions of vertices they are tens of megabytes.
    pub fn add_mesh(&mut self, mesh: &Mesh) -> Result<(), usize> {
        let added = self.add_indexed(&mesh.triangles, 0, &mesh.vertices, &[]);
        self.keys = pass::Keys::default();
        added
    }

    /// Adds a chunk's triangles (corners resolved through the chunk's own and borrowed
    /// vertices).
    pub fn add_chunk(&mut self, chunk: &MeshChunk) -> Result<(), usize> {
        self.add_indexed(
            &chunk.triangles,
            chunk.first_vertex,
            &chunk.vertices,
            &chunk.borrowed,
        )
    }

    /// The finished image, with `caption` (a title line, then warnings) below the panels.
    pub fn finish(mut self, caption: &[Line]) -> Image {
        let (width, height) = self.spec.size;
        let layout = self.layout;
        let mut image = Image {
            width,
            height,
            rgb: vec![BACKGROUND; width * height],
        };
        let h = layout.panel_height.min(height);
        let frames: Vec<Frame> = self.parts.drain(..).map(|p| p.frame).collect();
        let view = self.view.pixels(&frames);
        image.blit(layout.view.0, &view, layout.view.1, h);
        let s = layout.text_scale;
        if let (Some(section), Some((x0, w))) = (self.section.as_mut(), layout.section) {
            let inside = section.inside();
            let cut: Vec<Rgb> = inside
                .iter()
                .map(|&i| if i { CUT } else { BACKGROUND })
                .collect();
            image.blit(x0, &cut, w, h);
            // The box's outline, so pores reaching its faces read as pores.
            let b = self.spec.bbox;
            let px = |x: f64| (section.origin[0] + x * section.scale).round();
            let py = |y: f64| (section.origin[1] - y * section.scale).round();
            image.frame(
                (x0 as f64 + px(b[0][0]), py(b[1][1])),
                (x0 as f64 + px(b[1][0]), py(b[0][1])),
                h,
                FRAME,
            );
            for y in 0..h {
                image.set(x0, y, FRAME);
            }
            let label = format!("section z = {}", short(section.z0));
            image.text(x0 + 4 * s, 4 * s, &label, s, LABEL, x0 + w);
            image.text(4 * s, 4 * s, "isometric", s, LABEL, x0);
        }
        // The caption band.
        for y in h..height {
            for x in 0..width {
                image.set(x, y, CAPTION_BACKGROUND);
            }
        }
        for (k, line) in caption_lines(caption).iter().enumerate() {
            let y = h + 4 * s + k * font::CELL.1 * s;
            let colour = if line.warning { WARNING } else { TITLE };
            image.text(6 * s, y, &line.text, s, colour, width);
        }
        image
    }
}

/// Whether the last of `triangles` is nearer the viewer than the first. Drawn from the last,
/// a mesh made from back to front is then drawn from front to back, so that most of what
/// lies behind its first layer is seen to be hidden before it is drawn ([`raster`]).
fn nearer_last(view: &Raster, triangles: &[[u32; 3]], vertices: &Keyed) -> bool {
    let depth = |t: Option<&[u32; 3]>| {
        let (p, _) = vertices.corner(t?[0])?;
        Some(view.screen(p)[2])
    };
    matches!((depth(triangles.first()), depth(triangles.last())), (Some(a), Some(b)) if b < a)
}

/// A number in few characters (`0.5`, `12.25`, `1.2e-5`).
fn short(v: f64) -> String {
    if v == 0.0 || (1e-3..1e5).contains(&v.abs()) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.3e}")
    }
}

impl Image {
    fn set(&mut self, x: usize, y: usize, c: Rgb) {
        if x < self.width && y < self.height {
            self.rgb[y * self.width + x] = c;
        }
    }

    pub fn get(&self, x: usize, y: usize) -> Rgb {
        self.rgb[y * self.width + x]
    }

    /// Copies a `w × h` frame to column `x0`.
    fn blit(&mut self, x0: usize, frame: &[Rgb], w: usize, h: usize) {
        for y in 0..h.min(self.height) {
            for x in 0..w.min(self.width.saturating_sub(x0)) {
                self.rgb[y * self.width + x0 + x] = frame[y * w + x];
            }
        }
    }

    /// A one-pixel rectangle outline, clipped to the rows above `h`.
    fn frame(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), h: usize, c: Rgb) {
        let clip = |v: f64, n: usize| v.clamp(0.0, n as f64 - 1.0) as usize;
        let (x0, x1) = (clip(x0, self.width), clip(x1, self.width));
        let (y0, y1) = (clip(y0, h), clip(y1, h));
        for x in x0..=x1 {
            for y in [y0, y1] {
                if self.get(x, y) == BACKGROUND {
                    self.set(x, y, c);
                }
            }
        }
        for y in y0..=y1 {
            for x in [x0, x1] {
                if self.get(x, y) == BACKGROUND {
                    self.set(x, y, c);
                }
            }
        }
    }

    /// Draws `text` at (`x`, `y`) at `scale`, cut with `...` where it would pass `right`.
    fn text(&mut self, x: usize, y: usize, text: &str, scale: usize, c: Rgb, right: usize) {
        let advance = font::CELL.0 * scale;
        let fits = right.saturating_sub(x + 2 * scale) / advance;
        let chars: Vec<char> = text.chars().map(font::ascii).collect();
        let shown: Vec<char> = if chars.len() > fits {
            let keep = fits.saturating_sub(3);
            chars[..keep].iter().copied().chain("...".chars()).collect()
        } else {
            chars
        };
        for (k, ch) in shown.into_iter().enumerate() {
            for gy in 0..8 {
                for gx in 0..5 {
                    if font::lit(ch, gx, gy) {
                        for dy in 0..scale {
                            for dx in 0..scale {
                                self.set(x + k * advance + gx * scale + dx, y + gy * scale + dy, c);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Encodes the image as an 8-bit RGB PNG.
    pub fn write_png(&self, out: &mut dyn Write) -> io::Result<()> {
        let mut encoder = png::Encoder::new(out, self.width as u32, self.height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Fast);
        encoder.set_filter(png::Filter::Sub);
        let mut writer = encoder.write_header().map_err(io::Error::other)?;
        let bytes: Vec<u8> = self.rgb.iter().flatten().copied().collect();
        writer.write_image_data(&bytes).map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)
    }
}

/// A xorshift generator for the tests' random cases: the same numbers on every run.
#[cfg(test)]
fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    }
}

#[cfg(test)]
mod tests;
