//! The first picture of a mesh file: the mesh itself when its triangles fit the display
//! budget, else the mesh clustered on a uniform grid (Rossignac and Borrel's vertex
//! clustering). Clustering is one pass over the vertices and one over the triangles, so a scan
//! of millions of triangles gets a picture within seconds of being read, long before its
//! progressive mesh exists. The picture is only looked at: it is replaced by the hierarchy's
//! level within the budget as soon as the progressive mesh is built.

use super::opening::Picture;
use glam::DVec3;
use meshpyr::mesh::PolygonMesh;
use std::collections::HashMap;

/// Clustering passes before giving up on the budget: each one coarsens the grid by the excess.
const MAX_PASSES: usize = 8;

/// The picture of `mesh` within `max_triangles`: its fan triangles, or the clustered mesh.
pub fn first_picture(mesh: &PolygonMesh, max_triangles: usize) -> Picture {
    let n = mesh.n_vertices() as u32;
    let triangles: Vec<[u32; 3]> = fan_triangles(mesh)
        .filter(|t| t.iter().all(|&i| i < n))
        .collect();
    if triangles.len() <= max_triangles {
        let what = format!("the input, {} triangles", triangles.len());
        return Picture::new(what, &mesh.positions, triangles);
    }
    clustered(mesh, &triangles, max_triangles)
}

fn fan_triangles(mesh: &PolygonMesh) -> impl Iterator<Item = [u32; 3]> + '_ {
    mesh.faces()
        .flat_map(|f| (1..f.len().saturating_sub(1)).map(move |k| [f[0], f[k], f[k + 1]]))
}

/// Vertex clustering with a cell size that lands near `max_triangles` (a surface through a
/// grid of cell size `h` keeps about two triangles per occupied cell, about `area / h²` of
/// them), coarsened until the result fits.
fn clustered(mesh: &PolygonMesh, triangles: &[[u32; 3]], max_triangles: usize) -> Picture {
    let p = &mesh.positions;
    let area: f64 = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let mut cell = (2.0 * area / max_triangles.max(1) as f64).sqrt();
    let mut best = None;
    for _ in 0..MAX_PASSES {
        let (cells, kept) = cluster_once(p, triangles, cell);
        if kept.len() <= max_triangles || !cell.is_finite() || cell <= 0.0 {
            best = Some((cells, kept));
            break;
        }
        cell *= 1.05 * (kept.len() as f64 / max_triangles as f64).sqrt();
        best = Some((cells, kept));
    }
    let (cells, kept) = best.unwrap_or_default();
    let what = format!(
        "the input clustered to {} triangles while its hierarchy is built",
        kept.len()
    );
    Picture::new(what, &cells, kept)
}

/// One clustering: cell representatives (the mean of their vertices, in order of first use)
/// and the triangles between three different cells, each once.
fn cluster_once(p: &[DVec3], triangles: &[[u32; 3]], cell: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let lo = p.iter().fold(DVec3::splat(f64::INFINITY), |a, &b| a.min(b));
    let inv = if cell > 0.0 && cell.is_finite() {
        1.0 / cell
    } else {
        0.0
    };
    let key = |x: DVec3| {
        let g = ((x - lo) * inv).floor();
        // 21 bits per axis: finer grids than two million cells a side are never asked for.
        let axis = |v: f64| (v.clamp(0.0, ((1u64 << 21) - 1) as f64)) as u64;
        axis(g.x) | (axis(g.y) << 21) | (axis(g.z) << 42)
    };
    let mut index: HashMap<u64, u32> = HashMap::new();
    let mut sum: Vec<(DVec3, u32)> = Vec::new();
    let mut cell_of = vec![u32::MAX; p.len()];
    for t in triangles {
        for &v in t {
            let v = v as usize;
            if cell_of[v] != u32::MAX {
                continue;
            }
            let next = sum.len() as u32;
            let c = *index.entry(key(p[v])).or_insert(next);
            if c == next {
                sum.push((DVec3::ZERO, 0));
            }
            sum[c as usize].0 += p[v];
            sum[c as usize].1 += 1;
            cell_of[v] = c;
        }
    }
    let cells = sum.iter().map(|&(s, k)| s / f64::from(k)).collect();
    let mut kept: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| cell_of[v as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .map(|[a, b, c]| {
            // The same turn starting at its smallest index, so duplicates sort together.
            if a < b && a < c {
                [a, b, c]
            } else if b < c {
                [b, c, a]
            } else {
                [c, a, b]
            }
        })
        .collect();
    kept.sort_unstable();
    kept.dedup();
    (cells, kept)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `k` × `k` grid of quads in the plane z = 0, as triangles.
    fn grid(k: u32) -> PolygonMesh {
        let mut positions = Vec::new();
        for j in 0..=k {
            for i in 0..=k {
                positions.push(DVec3::new(f64::from(i), f64::from(j), 0.0));
            }
        }
        let mut mesh = PolygonMesh::new();
        mesh.positions = positions;
        for j in 0..k {
            for i in 0..k {
                let v = j * (k + 1) + i;
                mesh.push_face(&[v, v + 1, v + k + 2, v + k + 1]);
            }
        }
        mesh
    }

    #[test]
    fn a_mesh_within_the_budget_is_its_own_picture() {
        let mesh = grid(10);
        let picture = first_picture(&mesh, 200);
        assert_eq!(picture.n_triangles(), 200);
        assert!(picture.what().starts_with("the input, 200"));
    }

    #[test]
    fn a_mesh_over_the_budget_is_clustered_within_it_and_keeps_its_extent() {
        let mesh = grid(200);
        for budget in [1000, 5000, 20_000] {
            let picture = first_picture(&mesh, budget);
            assert!(picture.n_triangles() <= budget, "{budget}");
            assert!(
                picture.n_triangles() >= budget / 8,
                "{budget}: {}",
                picture.n_triangles()
            );
            let (lo, hi) = picture.bbox();
            // Cell means sit at most a cell inside the border.
            assert!(lo[0] < 20.0 && hi[0] > 180.0 && lo[1] < 20.0 && hi[1] > 180.0);
        }
    }

    #[test]
    fn clustering_is_deterministic() {
        let mesh = grid(120);
        let a = first_picture(&mesh, 3000);
        let b = first_picture(&mesh, 3000);
        assert_eq!(a.bytes(), b.bytes());
    }
}
