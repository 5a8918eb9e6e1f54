//! Pixel-level properties of previews, each against a number computed independently.

use super::*;
use crate::synthetic::icosphere;

fn sphere(levels: u32, r: f64) -> Mesh {
    let soup = icosphere(levels, r);
    Mesh {
        vertices: soup.positions.iter().map(|p| p.map(|c| c as f32)).collect(),
        triangles: soup.triangles,
    }
}

/// The unit cube `[0, 1]³`, outward.
fn cube() -> Mesh {
    let vertices = (0..8)
        .map(|i| [0, 1, 2].map(|a| ((i >> a) & 1) as f32))
        .collect();
    #[rustfmt::skip]
    let triangles = vec![
        [0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], // z = 0, z = 1
        [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7], // y = 0, y = 1
        [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5], // x = 0, x = 1
    ];
    Mesh {
        vertices,
        triangles,
    }
}

fn spec(bbox: [[f64; 3]; 2], cut: Option<f64>) -> Spec {
    Spec {
        size: (1024, 768),
        bbox,
        cut,
    }
}

fn caption() -> Vec<Line> {
    vec![Line {
        text: "unit".into(),
        warning: false,
    }]
}

fn render(mesh: &Mesh, spec: Spec) -> (Image, Camera, Layout) {
    let mut preview = Preview::new(spec);
    preview.add_mesh(mesh).unwrap();
    let (camera, layout) = (preview.camera(), preview.layout());
    (preview.finish(&caption()), camera, layout)
}

/// Pixels of the view panel (not background) and, of them, the red-tinted ones.
fn view_pixels(image: &Image, layout: &Layout) -> (usize, usize) {
    let (mut drawn, mut red) = (0, 0);
    for y in 0..layout.panel_height {
        for x in layout.view.0..layout.view.0 + layout.view.1 {
            let c = image.get(x, y);
            if c != BACKGROUND && c != LABEL {
                drawn += 1;
                if i32::from(c[0]) > i32::from(c[2]) + 40 {
                    red += 1;
                }
            }
        }
    }
    (drawn, red)
}

#[test]
fn a_cube_covers_its_isometric_hexagon_and_shows_no_inside() {
    let (image, camera, layout) = render(&cube(), spec([[0.0; 3], [1.0; 3]], Some(0.5)));
    let (drawn, red) = view_pixels(&image, &layout);
    // The isometric shadow of a unit cube is a regular hexagon of area √3.
    let expected = 3f64.sqrt() * camera.scale * camera.scale;
    let error = (drawn as f64 - expected).abs() / expected;
    assert!(error < 0.01, "{drawn} pixels, expected {expected:.0}");
    assert_eq!(red, 0, "a closed outward cube shows no back face");
}

#[test]
fn a_sphere_covers_its_disk_and_an_inverted_one_is_tinted() {
    let r = 1.0;
    let bbox = [[-r; 3], [r; 3]];
    let mesh = sphere(4, r);
    let (image, camera, layout) = render(&mesh, spec(bbox, Some(0.0)));
    let (drawn, red) = view_pixels(&image, &layout);
    let disk = std::f64::consts::PI * (r * camera.scale).powi(2);
    assert!(
        (drawn as f64 - disk).abs() / disk < 0.02,
        "{drawn} vs {disk:.0}"
    );
    assert_eq!(red, 0);

    let mut inverted = mesh.clone();
    for t in &mut inverted.triangles {
        t.swap(1, 2);
    }
    let (image, _, layout) = render(&inverted, spec(bbox, Some(0.0)));
    let (drawn_inv, red) = view_pixels(&image, &layout);
    assert_eq!(drawn_inv, drawn, "same silhouette");
    assert!(red as f64 > 0.99 * drawn as f64, "{red} of {drawn} tinted");
}

#[test]
fn the_middle_section_of_a_sphere_is_a_disk_of_its_radius() {
    let r = 2.0;
    let mesh = sphere(5, r);
    let mut preview = Preview::new(spec([[-r; 3], [r; 3]], Some(0.0)));
    preview.add_mesh(&mesh).unwrap();
    let layout = preview.layout();
    let image = preview.finish(&caption());
    let (x0, w) = layout.section.unwrap();
    let cut = (0..layout.panel_height)
        .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
        .filter(|&(x, y)| image.get(x, y) == CUT)
        .count();
    // The panel's scale: the box's 4 × 4 square fills FILL of the panel's smaller side.
    let scale = FILL * (w as f64 / (2.0 * r)).min(layout.panel_height as f64 / (2.0 * r));
    let disk = std::f64::consts::PI * (r * scale).powi(2);
    assert!(
        (cut as f64 - disk).abs() / disk < 0.01,
        "{cut} vs {disk:.0}"
    );
}

#[test]
fn a_section_has_its_pores_empty() {
    // Two nested spheres (the inner one inverted): a hollow ball, whose middle section is
    // an annulus.
    let outer = sphere(5, 2.0);
    let mut inner = sphere(5, 1.0);
    for t in &mut inner.triangles {
        t.swap(1, 2);
    }
    let n = outer.vertices.len() as u32;
    let mesh = Mesh {
        vertices: [outer.vertices, inner.vertices].concat(),
        triangles: outer
            .triangles
            .into_iter()
            .chain(inner.triangles.into_iter().map(|t| t.map(|i| i + n)))
            .collect(),
    };
    let mut preview = Preview::new(spec([[-2.0; 3], [2.0; 3]], Some(0.0)));
    preview.add_mesh(&mesh).unwrap();
    let layout = preview.layout();
    let image = preview.finish(&caption());
    let (x0, w) = layout.section.unwrap();
    let cut = (0..layout.panel_height)
        .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
        .filter(|&(x, y)| image.get(x, y) == CUT)
        .count();
    let scale = FILL * (w as f64 / 4.0).min(layout.panel_height as f64 / 4.0);
    let annulus = std::f64::consts::PI * (4.0 - 1.0) * scale * scale;
    assert!(
        (cut as f64 - annulus).abs() / annulus < 0.01,
        "{cut} vs {annulus:.0}"
    );
    // The centre is a pore.
    let centre = (x0 + w / 2, layout.panel_height / 2);
    assert_ne!(image.get(centre.0, centre.1), CUT);
}

#[test]
fn the_caption_draws_every_glyph_pixel_of_its_text() {
    let text = "gyroid: 123 triangles, volume fraction 0.3012";
    let s = spec([[0.0; 3], [1.0; 3]], Some(0.5));
    let lines = vec![
        Line {
            text: text.into(),
            warning: false,
        },
        Line {
            text: "loose pieces".into(),
            warning: true,
        },
    ];
    let layout = s.layout();
    let mut preview = Preview::new(s);
    preview.add_mesh(&cube()).unwrap();
    let image = preview.finish(&lines);
    let count = |c: Rgb| {
        (layout.panel_height..image.height)
            .flat_map(|y| (0..image.width).map(move |x| (x, y)))
            .filter(|&(x, y)| image.get(x, y) == c)
            .count()
    };
    let ink = |t: &str| -> usize {
        t.chars()
            .map(|c| {
                font::glyph(c)
                    .iter()
                    .map(|r| r.count_ones() as usize)
                    .sum::<usize>()
            })
            .sum::<usize>()
            * layout.text_scale
            * layout.text_scale
    };
    assert_eq!(count(TITLE), ink(text));
    assert_eq!(count(WARNING), ink("loose pieces"));
}

#[test]
fn the_image_is_the_same_for_any_thread_count_and_chunking() {
    let mesh = sphere(5, 1.0);
    let bbox = [[-1.0; 3], [1.0; 3]];
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| render(&mesh, spec(bbox, Some(0.0))).0)
    };
    let one = on(1);
    assert_eq!(one, on(3));
    let mut chunked = Preview::new(spec(bbox, Some(0.0)));
    for chunk in MeshChunk::split(&mesh, 700) {
        chunked.add_chunk(&chunk).unwrap();
    }
    assert_eq!(chunked.finish(&caption()), one);
}

#[test]
fn the_png_decodes_to_the_pixels() {
    let (image, _, _) = render(&cube(), spec([[0.0; 3], [1.0; 3]], Some(0.5)));
    let mut bytes = Vec::new();
    image.write_png(&mut bytes).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buffer).unwrap();
    assert_eq!((info.width, info.height), (1024, 768));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let pixels: Vec<u8> = image.rgb.iter().flatten().copied().collect();
    assert_eq!(&buffer[..info.buffer_size()], &pixels[..]);
}

#[test]
fn a_planar_region_is_seen_from_above() {
    // The unit square in z = 0, two triangles facing +z.
    let mesh = Mesh {
        vertices: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let (image, camera, layout) = render(&mesh, spec([[0.0; 3], [1.0, 1.0, 0.0]], None));
    assert!(layout.section.is_none());
    let (drawn, red) = view_pixels(&image, &layout);
    let expected = camera.scale * camera.scale;
    assert!((drawn as f64 - expected).abs() / expected < 0.01);
    assert_eq!(red, 0);
}
