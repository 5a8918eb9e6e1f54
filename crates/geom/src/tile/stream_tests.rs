//! Streamed tiling: the chunks of every chunk size concatenate to the whole mesh, bit for bit,
//! and keep the [`MeshChunk`] invariants (dense ids, borrowed positions, open ids) on real Gmsh
//! scaffolds — linear and quadratic, tets and hexes, uniform, graded, transition and skinned.

use super::*;
use crate::scaffold::{Scaffold, read_scaffold};
use std::collections::BTreeSet;

/// Schwarz P less an offset: Oh-symmetric, hence Td too.
struct SchwarzP(f64);

impl ScalarField for SchwarzP {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let tau = std::f64::consts::TAU;
        for i in 0..out.len() {
            out[i] = (tau * xs[i]).cos() + (tau * ys[i]).cos() + (tau * zs[i]).cos() - self.0;
        }
    }
}

fn example(name: &str) -> Scaffold {
    let path = format!("{}/tests/data/scaffolds/{name}", env!("CARGO_MANIFEST_DIR"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    read_scaffold(&bytes, &path, None).unwrap_or_else(|e| panic!("{e}"))
}

fn stream(
    scaffold: &Scaffold,
    solid: &TiledSolid,
    skin: Option<f64>,
    resolution: usize,
    per_chunk: usize,
) -> (Vec<MeshChunk>, TileStats) {
    let mut chunks = Vec::new();
    let spare = SpareArrays::default();
    let stats = stream_scaffold(
        scaffold,
        solid,
        skin,
        resolution,
        per_chunk,
        &spare,
        &mut |c| {
            chunks.push(c);
            Ok(())
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    (chunks, stats)
}

/// The chunks keep the invariants of [`MeshChunk`] and concatenate to `whole`; returns the
/// largest open set.
fn assert_chunks_make(chunks: &[MeshChunk], whole: &Mesh) -> usize {
    let mut next = 0;
    let mut concatenated = Mesh::default();
    let mut largest_open = 0;
    for (k, chunk) in chunks.iter().enumerate() {
        assert_eq!(chunk.first_vertex, next, "chunk {k}: ids are dense");
        next = chunk.end_vertex();
        let used: BTreeSet<u32> = chunk.triangles.iter().flatten().copied().collect();
        let borrowed: Vec<u32> = chunk.borrowed.iter().map(|&(id, _)| id).collect();
        let earlier: Vec<u32> = used.range(..chunk.first_vertex).copied().collect();
        assert_eq!(
            borrowed, earlier,
            "chunk {k}: borrows exactly the earlier ids it uses"
        );
        for &(id, p) in &chunk.borrowed {
            assert_eq!(
                p, whole.vertices[id as usize],
                "chunk {k}: position of {id}"
            );
        }
        assert!(
            used.iter().all(|&v| v < chunk.end_vertex()),
            "chunk {k}: a later id"
        );
        // Open: a superset of what later chunks use (a later element may or may not use a
        // vertex on its boundary), all of it already numbered.
        let later: BTreeSet<u32> = chunks[k + 1..]
            .iter()
            .flat_map(|c| c.borrowed.iter().map(|&(id, _)| id))
            .filter(|&id| id < chunk.end_vertex())
            .collect();
        let open: BTreeSet<u32> = chunk.open.iter().copied().collect();
        assert!(
            chunk.open.windows(2).all(|w| w[0] < w[1]),
            "chunk {k}: open ids sorted, each listed once"
        );
        assert!(
            later.is_subset(&open),
            "chunk {k}: a later chunk uses an id not open"
        );
        assert!(chunk.open.iter().all(|&v| v < chunk.end_vertex()));
        largest_open = largest_open.max(open.len());
        concatenated.vertices.extend(&chunk.vertices);
        concatenated.triangles.extend(&chunk.triangles);
    }
    assert!(chunks.last().is_some_and(|c| c.open.is_empty()));
    assert!(
        concatenated == *whole,
        "the chunks concatenate to the whole mesh"
    );
    largest_open
}

#[test]
fn streamed_chunks_concatenate_to_the_whole_mesh_on_every_kind() {
    let cell = SchwarzP(0.3);
    let twist = SchwarzP(-0.2);
    let sphere = example("sphere_r10_tet4_thickness.msh");
    let weight: Vec<f64> = sphere
        .nodes
        .iter()
        .map(|p| (p[0] / 20.0 + 0.5).clamp(0.0, 1.0))
        .collect();
    let thickness: Vec<f64> = sphere.nodes.iter().map(|p| 2.0 + 0.05 * p[2]).collect();
    let cases: Vec<(&str, Scaffold, TiledSolid, Option<f64>, usize)> = vec![
        (
            "tet4 transition",
            sphere.clone(),
            TiledSolid {
                transition: Some(Transition {
                    to: &twist,
                    weight: &weight,
                }),
                ..TiledSolid::of(&cell, Solid::Inside { offset: 0.0 })
            },
            None,
            5,
        ),
        (
            "tet4 graded shell",
            sphere.clone(),
            TiledSolid {
                thickness: Some(&thickness),
                ..TiledSolid::of(&cell, Solid::Shell { thickness: 2.0 })
            },
            None,
            5,
        ),
        (
            "tet10 skinned",
            example("sphere_r10_tet10.msh"),
            TiledSolid::of(&cell, Solid::Inside { offset: 0.0 }),
            Some(0.5),
            4,
        ),
        (
            "hex8 uniform",
            example("box_4x3x2_hex8.msh"),
            TiledSolid::of(&cell, Solid::Inside { offset: 0.0 }),
            None,
            6,
        ),
        (
            "hex20 uniform",
            example("cylinder_r5h20_hex20.msh"),
            TiledSolid::of(&cell, Solid::Outside { offset: 0.0 }),
            None,
            4,
        ),
    ];
    for (what, scaffold, solid, skin, resolution) in &cases {
        let (whole, stats) = tile_scaffold_with_skin(scaffold, solid, *skin, *resolution)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(
            whole.triangles.len() > 1000,
            "{what}: a real mesh, not {}",
            whole.triangles.len()
        );
        let count = scaffold.element_count();
        for per_chunk in [1, 7, 97, count, usize::MAX] {
            let (chunks, streamed) = stream(scaffold, solid, *skin, *resolution, per_chunk);
            assert_eq!(streamed, stats, "{what}");
            assert_eq!(chunks.len(), count.div_ceil(per_chunk.min(count)), "{what}");
            let open = assert_chunks_make(&chunks, &whole);
            if per_chunk >= count {
                assert_eq!(open, 0, "{what}: one chunk leaves nothing open");
            } else {
                // What is held between chunks is a fraction of the mesh.
                assert!(
                    open < whole.vertices.len() / 2,
                    "{what}, {per_chunk} per chunk: {open} of {} vertices open",
                    whole.vertices.len()
                );
            }
        }
    }
}

#[test]
fn a_failing_sink_stops_the_tiling_with_its_message() {
    let scaffold = example("box_4x3x2_hex8.msh");
    let cell = SchwarzP(0.0);
    let solid = TiledSolid::of(&cell, Solid::Inside { offset: 0.0 });
    let mut calls = 0;
    let result = stream_scaffold(
        &scaffold,
        &solid,
        None,
        4,
        5,
        &SpareArrays::default(),
        &mut |_| {
            calls += 1;
            if calls == 2 {
                Err("disk full".into())
            } else {
                Ok(())
            }
        },
    );
    assert_eq!(result, Err(TileError::Sink("disk full".into())));
    assert_eq!(calls, 2, "no chunk after the failing one");
}
