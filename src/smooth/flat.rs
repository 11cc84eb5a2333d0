//! Ohtake–Belyaev–Seidel denoising of a file's mesh on the builder's corner table, the
//! path of `meshpyr smooth` for `auto`, `adaptive` and `anisotropic`.
//!
//! The half-edge [`crate::mesh::Mesh`] is never made: the builder's repairs run on a corner
//! table ([`crate::mesh::CornerTable`]), whose arrays become the denoiser's flat surface, and
//! the new positions are written over the input's own (a vertex the builder split gets the
//! mean of its copies), so the output is the input with new positions and no second copy of
//! it exists. The surface is the one the half-edge mesh would give, so the result is the same
//! bit for bit (`docs/performance.md` has the memory and time this saves).

use super::{DenoiseOptions, Denoised, SmoothError};
use crate::fairing::ohtake::denoise_surface;
use crate::fairing::surface::FlatSurface;
use crate::mesh::{BuildReport, CornerTable, PolygonMesh};
use crate::progress::Progress;

/// Denoises `input` in place with `options` (validated): its positions become the smoothed
/// ones, everything else stays. Returns what the builder repaired and the denoiser's report
/// (whose positions are left empty: they are in `input`).
pub(crate) fn denoise_in_place(
    input: &mut PolygonMesh,
    options: &DenoiseOptions,
    progress: &dyn Progress,
) -> Result<(BuildReport, Denoised), SmoothError> {
    let repaired = CornerTable::from_polygons(input)?;
    let source = repaired.source;
    let vertex_source = &source.vertex_source;
    let surface = FlatSurface::from_corners(repaired.corners, vertex_source.len());
    let original = &input.positions;
    let at = |i: usize| original[vertex_source[i] as usize];
    let mut denoised = denoise_surface(surface, &at, options, progress);
    source.write_input_positions(&denoised.positions, &mut input.positions);
    denoised.positions = Vec::new();
    Ok((repaired.report, denoised))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fairing::denoise;
    use crate::mesh::{Attribute, AttributeData, BoundingBox, Mesh};
    use crate::progress::NoProgress;
    use crate::smooth::{SmoothMethod, smooth_mesh, smooth_mesh_owned};
    use glam::DVec3;

    fn read(name: &str) -> PolygonMesh {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        crate::io::read_mesh(dir.join(name)).expect("test mesh reads")
    }

    /// The reference: the half-edge mesh, denoised, mapped back onto the input.
    fn on_the_half_edge_mesh(input: &PolygonMesh, options: &DenoiseOptions) -> Vec<DVec3> {
        let built = Mesh::from_polygons(input).expect("builds");
        let r = denoise(&built.mesh, options, &NoProgress).expect("denoises");
        built
            .source
            .to_input_positions(&r.positions, &input.positions)
    }

    fn largest_difference_over_diagonal(a: &[DVec3], b: &[DVec3]) -> f64 {
        let diagonal = BoundingBox::of(a.iter().copied()).map_or(1.0, |b| b.diagonal());
        let d = a.iter().zip(b).map(|(p, q)| (*p - *q).abs().max_element());
        d.fold(0.0, f64::max) / diagonal
    }

    #[test]
    fn the_corner_table_path_gives_the_half_edge_meshs_positions_on_dirty_scans() {
        // Holes, pieces, non-manifold edges and vertices, zero-area and repeated-index faces,
        // polygons, marching-cubes slivers; every preset, the anisotropic metric among them.
        let mut repaired = BuildReport::default();
        for name in [
            "elephant_holes.ply",
            "spider_assimp.ply",
            "planar_pymeshfix_vtk.ply",
            "back_to_back_scad.stl",
            "cube_degenerate_om.obj",
            "mushroom_quad.ply",
            "mc/mc_implicit_n40.ply",
        ] {
            let input = read(name);
            for options in [
                DenoiseOptions::automatic(),
                DenoiseOptions::adaptive(),
                DenoiseOptions::anisotropic(),
            ] {
                let want = on_the_half_edge_mesh(&input, &options);
                let mut got = input.clone();
                let (report, _) = denoise_in_place(&mut got, &options, &NoProgress).unwrap();
                let d = largest_difference_over_diagonal(&got.positions, &want);
                assert!(d <= 1e-9, "{name}: {d:e}");
                assert_eq!(got.positions, want, "{name}: not bit for bit");
                repaired.non_manifold_edges += report.non_manifold_edges;
                repaired.split_vertices += report.split_vertices;
                repaired.zero_area_faces += report.zero_area_faces;
                repaired.dropped_repeated_index += report.dropped_repeated_index;
                repaired.triangulated_polygons += report.triangulated_polygons;
            }
        }
        // The inputs did exercise the repairs.
        assert!(repaired.non_manifold_edges > 0, "{repaired:?}");
        assert!(repaired.split_vertices > 0, "{repaired:?}");
        assert!(repaired.zero_area_faces > 0, "{repaired:?}");
        assert!(repaired.dropped_repeated_index > 0, "{repaired:?}");
        assert!(repaired.triangulated_polygons > 0, "{repaired:?}");
    }

    #[test]
    fn smoothing_changes_only_positions_and_leaves_unreferenced_vertices_alone() {
        let (p, t) = crate::mesh::shapes::icosphere(2);
        let wobble = |i: usize| 1.0 + 0.05 * ((i * 7919) as f64).sin();
        let mut p: Vec<DVec3> = p.iter().enumerate().map(|(i, &x)| x * wobble(i)).collect();
        let loose = DVec3::new(3.0, -2.0, 0.5);
        p.push(loose);
        let mut input = PolygonMesh::from_triangles(p, &t);
        let n = input.n_vertices();
        input.vertex_attributes.push(Attribute {
            name: "quality".into(),
            data: AttributeData::F32((0..n).map(|i| i as f32).collect()),
        });
        input.face_attributes.push(Attribute {
            name: "label".into(),
            data: AttributeData::U8((0..input.n_faces()).map(|i| i as u8).collect()),
        });
        input.comments.push("scanned".into());
        let out = smooth_mesh(&input, &SmoothMethod::Auto, &NoProgress)
            .unwrap()
            .mesh;
        assert_ne!(out.positions, input.positions);
        assert_eq!(out.positions[n - 1], loose);
        assert_eq!(
            PolygonMesh {
                positions: input.positions.clone(),
                ..out
            },
            input
        );
    }

    #[test]
    fn the_output_is_the_same_on_one_thread_and_on_several() {
        let input = read("elephant_holes.ply");
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            pool.install(|| smooth_mesh(&input, &SmoothMethod::Auto, &NoProgress))
                .unwrap()
                .mesh
        };
        let one = on(1);
        assert_eq!(one, on(3));
        assert_eq!(one, on(8));
    }

    #[test]
    fn bad_input_is_refused_without_panicking() {
        let square = || {
            let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
            PolygonMesh::from_triangles(p, &[[0, 1, 2], [0, 2, 3]])
        };
        let mut nan = square();
        nan.positions[2].y = f64::NAN;
        let mut out_of_range = square();
        out_of_range.face_indices[4] = 99;
        let mut flat = square();
        flat.positions = vec![DVec3::ZERO; 4];
        let repeated = PolygonMesh::from_triangles(vec![DVec3::ZERO; 3], &[[0, 1, 1]]);
        for method in [SmoothMethod::Auto, SmoothMethod::default()] {
            let refused = |m: PolygonMesh| smooth_mesh_owned(m, &method, &NoProgress).is_err();
            assert!(refused(nan.clone()));
            assert!(refused(out_of_range.clone()));
            assert!(refused(repeated.clone()));
            // All points in one place: nothing to smooth, returned unchanged.
            let same = smooth_mesh_owned(flat.clone(), &method, &NoProgress).unwrap();
            assert_eq!(same.mesh, flat);
        }
    }
}
