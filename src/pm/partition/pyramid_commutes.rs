//! The blocks' analyses commute (`docs/partitioned.md`, "The detail pyramid on a partitioned
//! hierarchy"): with the rule at pinned ring vertices, the details of a split do not depend on
//! how a pass's blocks are interleaved, which is what lets each block analyse its own splits.
//! Checked by building the same partitioned decimation twice, each pass's collapses once
//! interleaved by cost and once block by block (the last cell's first), and comparing every
//! split's touched vertices and details, matched by the input vertex it makes.

use super::{InputPoints, decimate_in_blocks_merged, first_cells, order};
use crate::mesh::{Mesh, SlotIndex};
use crate::pm::decimate::{Collapse, FlatMesh};
use crate::pm::progressive::decimate_params;
use crate::pm::{PmOptions, ProgressiveMesh};
use crate::progress::NoProgress;
use crate::pyramid::DetailPyramid;
use crate::relax::SecondDifference;
use glam::DVec3;

/// A bumpy, noisy open grid of `n × n` vertices.
fn bumpy_grid(n: usize) -> Mesh {
    let h = 1.0 / (n - 1) as f64;
    let mut positions = Vec::with_capacity(n * n);
    for y in 0..n {
        for x in 0..n {
            let (u, v) = (x as f64 * h, y as f64 * h);
            let i = (y * n + x) as u64;
            let noise = (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f64 / (1u64 << 24) as f64;
            let z = 0.08 * (6.0 * u).sin() * (5.0 * v).cos() + 0.1 * h * (noise - 0.5);
            positions.push(DVec3::new(u, v, z));
        }
    }
    let id = |x: usize, y: usize| (y * n + x) as u32;
    let mut faces = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            faces.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
            faces.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
        }
    }
    Mesh::from_triangles(&positions, &faces).unwrap().mesh
}

fn block_by_block(blocks: Vec<Vec<Collapse>>) -> Vec<Collapse> {
    blocks.into_iter().rev().flatten().collect()
}

fn hierarchy(
    mesh: &Mesh,
    block: usize,
    merge: fn(Vec<Vec<Collapse>>) -> Vec<Collapse>,
) -> ProgressiveMesh {
    let params = decimate_params(&PmOptions::default(), mesh.bbox_diagonal()).unwrap();
    let flat = FlatMesh::from_mesh(mesh);
    let positions = mesh.positions();
    let n = mesh.n_vertices();
    let points = InputPoints {
        positions: &positions,
        polygons: mesh.n_faces() as u64,
        source: None,
    };
    let first = first_cells(&points, n, block);
    let decimated =
        decimate_in_blocks_merged(flat, &params, block, (None, first), &NoProgress, merge).unwrap();
    let faces = |mesh_to_pm: &[u32]| {
        (mesh.faces())
            .map(|f| mesh.face_vertices(f).map(|v| mesh_to_pm[v.slot()]))
            .collect()
    };
    ProgressiveMesh::from_decimation(decimated, (n, n), &[], |v| positions[v as usize], faces)
        .unwrap()
}

/// Per input vertex a split makes: its touched vertices (input indices, the ring sorted) and
/// their details in units of the detail step.
fn details_by_input_vertex(
    pm: &ProgressiveMesh,
    pyramid: &DetailPyramid,
) -> Vec<Vec<(u32, DVec3)>> {
    let input = |v: u32| pm.pm_to_mesh()[v as usize];
    let step = pyramid.detail_step();
    let mut out = vec![Vec::new(); pm.pm_to_mesh().len()];
    for k in 0..pm.splits().len() {
        let (touched, details) = pyramid.split_details(k);
        let mut rows: Vec<(u32, DVec3)> = (touched.iter().zip(details))
            .map(|(&v, d)| (input(v), d / step))
            .collect();
        rows[1..].sort_unstable_by_key(|r| r.0);
        out[input(touched[0]) as usize] = rows;
    }
    out
}

/// The largest difference between the details of the same split in `a` and `b`, in steps
/// (infinite when a split touches other vertices).
fn largest_difference(a: &[Vec<(u32, DVec3)>], b: &[Vec<(u32, DVec3)>]) -> f64 {
    let mut largest = 0f64;
    for (x, y) in a.iter().zip(b) {
        if x.len() != y.len() || x.iter().zip(y).any(|(p, q)| p.0 != q.0) {
            return f64::INFINITY;
        }
        for (p, q) in x.iter().zip(y) {
            largest = largest.max((p.1 - q.1).abs().max_element());
        }
    }
    largest
}

#[test]
fn a_passs_blocks_interleaved_otherwise_give_every_split_the_same_details() {
    let mesh = bumpy_grid(40);
    let analyse = |pm: &ProgressiveMesh| {
        let pyramid = DetailPyramid::analyze(pm, &SecondDifference::default(), &NoProgress);
        details_by_input_vertex(pm, &pyramid.unwrap())
    };
    // The one-process analysis of the same hierarchy: the pins dropped.
    let bare = |pm: &ProgressiveMesh| {
        let mut pm = pm.clone();
        pm.set_pins(None).unwrap();
        analyse(&pm)
    };
    for block in [60, 200] {
        let by_cost = hierarchy(&mesh, block, order::merge_by_cost);
        let by_block = hierarchy(&mesh, block, block_by_block);
        assert!(by_cost.pins().is_some_and(|p| p.n_passes() >= 3));
        // Another collapse order: other PM numbers, the same collapses.
        assert_ne!(by_cost.pm_to_mesh(), by_block.pm_to_mesh());
        let with_rule = largest_difference(&analyse(&by_cost), &analyse(&by_block));
        assert_eq!(
            with_rule, 0.0,
            "blocks of {block}: the same details to the bit"
        );
        // Without the rule the order matters: a block writes its pinned ring vertices, which
        // the neighbouring blocks' splits read.
        let without = largest_difference(&bare(&by_cost), &bare(&by_block));
        assert!(without > 1.0, "blocks of {block}: {without} steps");
    }
}
