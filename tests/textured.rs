//! Textured scans keep their texture: per-corner texture coordinates and normals with seams,
//! materials, groups and the files they name, through reading, writing, converting and the
//! commands that keep faces. The scans are tests/data/textured (made by
//! benches/compare/make_textured_scans.py from anchor.ply).

mod common;

use common::*;
use glam::DVec3;
use meshpyr::format::PyramidOptions;
use meshpyr::io::{
    MeshFormat, PlyEncoding, read_mesh, read_mesh_bytes, read_mesh_reporting, write_mesh,
    write_mesh_bytes, write_mesh_with,
};
use meshpyr::mesh::{AttributeData, PolygonMesh};
use meshpyr::{Filter, MoveHandle, Pyramid};
use std::collections::{BTreeSet, HashMap};

const OBJ: &str = "textured/anchor_tex.obj";
const PLY: &str = "textured/anchor_tex.ply";

/// Every corner's value of the corner attribute `name`, as f64 bits (`None`: no value).
fn corner_values(m: &PolygonMesh, name: &str) -> Vec<Option<Vec<u64>>> {
    let a = m.corner_attribute(name).unwrap();
    (0..m.face_indices.len())
        .map(|c| a.value(c).map(|v| v.iter().map(|x| x.to_bits()).collect()))
        .collect()
}

/// Every face's material name.
fn face_materials(m: &PolygonMesh) -> Vec<String> {
    let a = m.face_attribute("texnumber").unwrap();
    (0..m.n_faces())
        .map(|f| m.materials.list[a.data.get_f64(f) as usize].name.clone())
        .collect()
}

/// Every face's group name.
fn face_groups(m: &PolygonMesh) -> Vec<String> {
    let a = m.face_attribute("obj_group").unwrap();
    (0..m.n_faces())
        .map(|f| m.group_names[a.data.get_f64(f) as usize].clone())
        .collect()
}

/// The images of the materials, as paths that exist, sorted (an OBJ names its materials in
/// order of first use, a PLY in the order of its `TextureFile` lines).
fn images(m: &PolygonMesh) -> Vec<std::path::PathBuf> {
    let folder = m.materials.folder.clone().unwrap();
    let mut all: Vec<_> = m
        .materials
        .list
        .iter()
        .map(|x| {
            let p = folder.join(x.texture.as_ref().unwrap());
            p.canonicalize()
                .unwrap_or_else(|_| panic!("{} exists", p.display()))
        })
        .collect();
    all.sort();
    all
}

/// Every face's image.
fn face_images(m: &PolygonMesh) -> Vec<Option<String>> {
    let a = m.face_attribute("texnumber").unwrap();
    (0..m.n_faces())
        .map(|f| {
            let t = m.materials.list[a.data.get_f64(f) as usize]
                .texture
                .as_ref()?;
            let p = m.materials.folder.as_ref()?.join(t).canonicalize().ok()?;
            Some(p.display().to_string())
        })
        .collect()
}

#[test]
fn an_obj_with_seams_keeps_its_vt_and_vn_lines_and_indices_through_a_write() {
    let (m, warnings) = read_mesh_reporting(data(OBJ)).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let uv = m.corner_attribute("texcoord").unwrap();
    assert!(
        uv.pool_len() > m.n_vertices(),
        "seams split the texture coordinates"
    );
    let again = trip(&m, MeshFormat::Obj, &Default::default());
    assert_eq!(again.corner_attributes, m.corner_attributes);
    assert_eq!(again.face_attributes, m.face_attributes);
    assert_eq!(again.group_names, m.group_names);
    assert_eq!(again.object_names, m.object_names);
    assert_eq!(again.materials.libraries, m.materials.libraries);
    assert_eq!(position_bits(&again), position_bits(&m));
    assert_eq!(m.materials.list.len(), 2);
    assert_eq!(images(&m).len(), 2);
}

#[test]
fn a_ply_with_texcoord_lists_reads_the_same_corners_as_the_obj_and_round_trips() {
    let obj = read_mesh(data(OBJ)).unwrap();
    let (scan, warnings) = read_mesh_reporting(data(PLY)).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(
        corner_values(&scan, "texcoord"),
        corner_values(&obj, "texcoord")
    );
    assert_eq!(images(&scan), images(&obj));
    assert_eq!(face_images(&scan), face_images(&obj));
    for enc in ENCODINGS {
        let again = trip(&scan, MeshFormat::Ply, &ply(enc));
        assert_eq!(
            corner_values(&again, "texcoord"),
            corner_values(&scan, "texcoord")
        );
        assert_eq!(again.face_attributes, scan.face_attributes);
        assert_eq!(again.materials.list, scan.materials.list);
    }
}

#[test]
fn obj_to_ply_to_obj_in_other_folders_gives_the_same_corners_materials_groups_and_files() {
    let obj = read_mesh(data(OBJ)).unwrap();
    let ply_path = scratch("obj_ply_obj", "a/scan.ply");
    std::fs::create_dir_all(ply_path.parent().unwrap()).unwrap();
    write_mesh(&ply_path, &obj).unwrap();
    let (ply, warnings) = read_mesh_reporting(&ply_path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let back_path = scratch("obj_ply_obj", "b/c/back.obj");
    std::fs::create_dir_all(back_path.parent().unwrap()).unwrap();
    write_mesh(&back_path, &ply).unwrap();
    let (back, warnings) = read_mesh_reporting(&back_path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    for name in ["texcoord", "normal"] {
        assert_eq!(
            corner_values(&back, name),
            corner_values(&obj, name),
            "{name}"
        );
    }
    assert_eq!(face_materials(&back), face_materials(&obj));
    assert_eq!(face_groups(&back), face_groups(&obj));
    assert_eq!(images(&back), images(&obj));
    assert_eq!(position_bits(&back), position_bits(&obj));
}

#[test]
fn a_ply_with_textures_written_as_obj_gets_a_material_library_beside_it() {
    let ply = read_mesh(data(PLY)).unwrap();
    let out = scratch("ply_to_obj_library", "out.obj");
    write_mesh(&out, &ply).unwrap();
    let (obj, warnings) = read_mesh_reporting(&out).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(obj.materials.libraries, ["out.mtl"]);
    assert_eq!(images(&obj), images(&ply));
    assert_eq!(face_images(&obj), face_images(&ply));
    assert_eq!(face_materials(&obj), face_materials(&ply));
    assert_eq!(
        corner_values(&obj, "texcoord"),
        corner_values(&ply, "texcoord")
    );
}

#[test]
fn a_missing_library_image_or_material_is_a_warning_naming_it() {
    let dir = scratch("missing_references", "x");
    let dir = dir.parent().unwrap();
    let obj = b"mtllib here.mtl gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n\
        usemtl painted\nf 1/1 2/1 3/1\nusemtl nowhere\nf 1/1 3/1 2/1\n";
    std::fs::write(dir.join("scan.obj"), obj).unwrap();
    std::fs::write(
        dir.join("here.mtl"),
        "newmtl painted\nmap_Kd -s 1 1 1 paint.png\n",
    )
    .unwrap();
    let (m, warnings) = read_mesh_reporting(dir.join("scan.obj")).unwrap();
    assert_eq!(m.n_faces(), 2);
    let all = warnings.join("\n");
    assert_eq!(warnings.len(), 3, "{all}");
    assert!(all.contains("gone.mtl"), "{all}");
    assert!(all.contains("material nowhere"), "{all}");
    assert!(all.contains("image paint.png not found"), "{all}");
}

#[test]
fn a_vt_index_past_the_last_vt_is_a_one_line_error_with_its_line() {
    let src = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/9\n";
    let e = read_mesh_bytes(src, MeshFormat::Obj)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "line 5: texture coordinate index 9 but the file has 1 texture coordinates"
    );
}

#[test]
fn a_texcoord_list_of_the_wrong_length_is_a_one_line_error_with_its_line() {
    let src = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
        property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 4 0 0 1 0\n";
    let e = read_mesh_bytes(src, MeshFormat::Ply)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "line 14: face 0: list \"texcoord\" has 4 values for 3 corners (2 per corner)"
    );
}

#[test]
fn other_face_lists_are_kept() {
    let src = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
        property list uchar short flags\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 2 7 -1\n";
    let m = read_mesh_bytes(src, MeshFormat::Ply).unwrap();
    assert_eq!(m.face_lists[0].items, [7.0, -1.0]);
    let out = write_mesh_bytes(&m, MeshFormat::Ply, &ply(PlyEncoding::Ascii)).unwrap();
    assert!(
        String::from_utf8(out)
            .unwrap()
            .contains("property list uchar short flags")
    );
}

/// The angle in degrees between each corner's stored normal and the area-weighted normal of
/// the faces of its cluster (corners of one vertex with the same stored normal).
fn normal_angles(m: &PolygonMesh) -> Vec<f64> {
    let n = m.corner_attribute("normal").unwrap();
    let area = |f: usize| {
        let face = m.face(f);
        let mut a = DVec3::ZERO;
        for (i, &v) in face.iter().enumerate() {
            a += m.positions[v as usize].cross(m.positions[face[(i + 1) % face.len()] as usize]);
        }
        a
    };
    let mut sums = std::collections::HashMap::new();
    for f in 0..m.n_faces() {
        for c in m.face_starts[f] as usize..m.face_starts[f + 1] as usize {
            *sums
                .entry((m.face_indices[c], n.indices[c]))
                .or_insert(DVec3::ZERO) += area(f);
        }
    }
    (0..m.face_indices.len())
        .map(|c| {
            let v = n.value(c).unwrap();
            let stored = DVec3::new(v[0], v[1], v[2]);
            stored
                .angle_between(sums[&(m.face_indices[c], n.indices[c])])
                .to_degrees()
        })
        .collect()
}

/// Distinct stored normals per vertex: the hard edges.
fn normals_per_vertex(m: &PolygonMesh) -> Vec<usize> {
    let n = m.corner_attribute("normal").unwrap();
    let mut per = vec![std::collections::BTreeSet::new(); m.n_vertices()];
    for c in 0..m.face_indices.len() {
        let v = n.value(c).unwrap();
        per[m.face_indices[c] as usize].insert(v.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
    }
    per.iter().map(|s| s.len()).collect()
}

/// A command that keeps faces kept everything but positions and normals, and the normals
/// follow the new surface with the input's hard edges.
fn assert_carried(input: &PolygonMesh, out: &PolygonMesh, what: &str) {
    assert_ne!(
        position_bits(out),
        position_bits(input),
        "{what} moved vertices"
    );
    assert_eq!(
        corner_values(out, "texcoord"),
        corner_values(input, "texcoord"),
        "{what}"
    );
    assert_eq!(out.face_attributes, input.face_attributes, "{what}");
    assert_eq!(out.materials, input.materials, "{what}");
    assert_eq!(out.group_names, input.group_names, "{what}");
    assert_eq!(out.face_indices, input.face_indices, "{what}");
    let angles = normal_angles(out);
    let mean = angles.iter().sum::<f64>() / angles.len() as f64;
    assert!(
        mean < 2.0,
        "{what}: stored normals {mean:.2}° off the surface on average"
    );
    assert_eq!(
        normals_per_vertex(out),
        normals_per_vertex(input),
        "{what}: hard edges"
    );
}

#[test]
fn filter_edit_and_smooth_keep_every_corner_material_and_group_and_normals_follow() {
    let input = read_mesh(data(OBJ)).unwrap();
    let before = normal_angles(&input).iter().sum::<f64>() / (input.face_indices.len() as f64);
    assert!(
        before < 2.0,
        "the scan's own normals agree with it ({before:.2}°)"
    );
    let pyramid = Pyramid::build(&input).unwrap();
    let filtered = pyramid.filter(&Filter::new().lowpass(60));
    assert_carried(&input, &filtered, "filter");
    let handle = MoveHandle {
        center: input.positions[0],
        displacement: DVec3::Y * 0.2,
        radius: 0.5,
    };
    // The hierarchy keeps the seams, so its coarsest level is the seam floor (about a fifth of
    // the scan's vertices), not the few dozen vertices of the untextured anchor: edit between
    // the base and the finest level.
    let levels = pyramid.levels();
    let level = (levels.start() + levels.end()) / 2;
    let edited = pyramid.edit(level, &[handle], &Filter::new()).unwrap();
    assert_carried(&input, &edited, "edit");
    let method = meshpyr::SmoothMethod::default();
    let smoothed = meshpyr::smooth_mesh(&input, &method, &meshpyr::NoProgress)
        .unwrap()
        .mesh;
    assert_carried(&input, &smoothed, "smooth");
}

#[test]
fn stored_vertex_normals_follow_a_filter_and_unmoved_ones_keep_their_bits() {
    let mut m = read_mesh(data("anchor.ply")).unwrap();
    let stale: Vec<f32> = (0..m.n_vertices()).map(|i| (i % 3) as f32).collect();
    for name in ["nx", "ny", "nz"] {
        m.set_vertex_attribute(meshpyr::mesh::Attribute {
            name: name.into(),
            data: AttributeData::F32(stale.clone()),
        })
        .unwrap();
    }
    let same = Pyramid::build(&m).unwrap().filter(&Filter::new());
    assert_eq!(
        same.vertex_attributes, m.vertex_attributes,
        "no vertex moved"
    );
    let out = Pyramid::build(&m)
        .unwrap()
        .filter(&Filter::new().lowpass(60));
    let col = |name: &str| out.vertex_attribute(name).unwrap().data.clone();
    let (x, y, z) = (col("nx"), col("ny"), col("nz"));
    let mut sum = vec![DVec3::ZERO; out.n_vertices()];
    for f in out.faces() {
        let p = |k: usize| out.positions[f[k] as usize];
        let a = (p(1) - p(0)).cross(p(2) - p(0));
        for &v in f {
            sum[v as usize] += a;
        }
    }
    let mean = (0..out.n_vertices())
        .map(|v| {
            let stored = DVec3::new(x.get_f64(v), y.get_f64(v), z.get_f64(v));
            stored.angle_between(sum[v]).to_degrees()
        })
        .sum::<f64>()
        / out.n_vertices() as f64;
    assert!(mean < 2.0, "{mean:.2}°");
}

#[test]
fn writing_into_another_folder_points_at_the_same_library_with_a_relative_path() {
    let m = read_mesh(data(OBJ)).unwrap();
    let out = scratch("relative_library", "deeper/still/copy.obj");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    write_mesh_with(&out, &m, &Default::default()).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    let lib = text.lines().find(|l| l.starts_with("mtllib ")).unwrap();
    assert!(lib.starts_with("mtllib ../"), "{lib}");
    let again = read_mesh(&out).unwrap();
    assert_eq!(images(&again), images(&m));
}

#[test]
fn build_then_extract_restores_the_textured_input_exactly_in_a_2_3_file() {
    let input = read_mesh(data(OBJ)).unwrap();
    let (bytes, _) = Pyramid::build(&input).unwrap().to_pyr_bytes().unwrap();
    assert_eq!(
        u16::from_le_bytes([bytes[10], bytes[11]]),
        3,
        "minor version"
    );
    let restored = meshpyr::format::decode(&bytes).unwrap().input;
    assert_eq!(restored, input);
    let plain = read_mesh(data("anchor.ply")).unwrap();
    let (bytes, _) = Pyramid::build(&plain).unwrap().to_pyr_bytes().unwrap();
    assert_eq!(
        u16::from_le_bytes([bytes[10], bytes[11]]),
        1,
        "untextured files stay 2.1"
    );
}

/// The faces along an edge, each with its texture coordinates at the edge's lower and higher
/// vertex.
type EdgeSides = Vec<(usize, Vec<u64>, Vec<u64>)>;

/// The charts with a corner of each (vertex, texture coordinates, material).
type ChartsAt = HashMap<(u32, Vec<u64>, i64), BTreeSet<usize>>;

/// The texture charts of `m`: faces joined across every edge whose two faces have the same
/// material and the same texture coordinates at both ends. Returns, for every (vertex,
/// texture coordinates, material) a corner has, the charts with such a corner.
fn charts(m: &PolygonMesh) -> ChartsAt {
    let uv = |c: usize| {
        let a = m.corner_attribute("texcoord").unwrap();
        a.value(c)
            .unwrap()
            .iter()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    let material = |f: usize| m.face_attribute("texnumber").unwrap().data.get_f64(f) as i64;
    let mut parent: Vec<usize> = (0..m.n_faces()).collect();
    fn find(p: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while p[r] != r {
            r = p[r];
        }
        p[x] = r;
        r
    }
    let mut edges: HashMap<(u32, u32), EdgeSides> = HashMap::new();
    for f in 0..m.n_faces() {
        let (s, e) = (m.face_starts[f] as usize, m.face_starts[f + 1] as usize);
        for c in s..e {
            let d = if c + 1 == e { s } else { c + 1 };
            let (a, b) = (m.face_indices[c], m.face_indices[d]);
            let (ua, ub) = (uv(c), uv(d));
            let key = (a.min(b), a.max(b));
            let ends = if a < b { (ua, ub) } else { (ub, ua) };
            for (g, ga, gb) in edges.get(&key).into_iter().flatten() {
                if (ga, gb) == (&ends.0, &ends.1) && material(*g) == material(f) {
                    let (x, y) = (find(&mut parent, *g), find(&mut parent, f));
                    parent[x] = y;
                }
            }
            edges.entry(key).or_default().push((f, ends.0, ends.1));
        }
    }
    let mut out: ChartsAt = HashMap::new();
    for f in 0..m.n_faces() {
        let chart = find(&mut parent, f);
        for c in m.face_starts[f] as usize..m.face_starts[f + 1] as usize {
            out.entry((m.face_indices[c], uv(c), material(f)))
                .or_default()
                .insert(chart);
        }
    }
    out
}

/// Every triangle of `out` (a simplification of `input` with `source_rows`) lies in one
/// texture chart of `input` with its material: each corner's texture coordinates are some
/// input corner's at that vertex in a face of that material, and the three corners share a
/// chart. Returns the number of seam corners checked (corners whose vertex is in two charts).
fn assert_no_texture_across_seams(
    input: &PolygonMesh,
    out: &PolygonMesh,
    source_rows: &[u32],
    what: &str,
) -> usize {
    let charts = charts(input);
    let tc = out.corner_attribute("texcoord").unwrap();
    let material = out.face_attribute("texnumber").unwrap();
    let mut seam_corners = 0;
    for f in 0..out.n_faces() {
        let m = material.data.get_f64(f) as i64;
        let mut common: Option<BTreeSet<usize>> = None;
        for c in out.face_starts[f] as usize..out.face_starts[f + 1] as usize {
            let v = source_rows[out.face_indices[c] as usize];
            let uv: Vec<u64> = tc.value(c).unwrap().iter().map(|x| x.to_bits()).collect();
            let Some(here) = charts.get(&(v, uv, m)) else {
                panic!("{what}: face {f} corner {c}: not a value its vertex had");
            };
            let at_vertex = charts.keys().filter(|k| k.0 == v).count();
            seam_corners += usize::from(at_vertex > 1);
            common = Some(match common {
                None => here.clone(),
                Some(s) => s.intersection(here).copied().collect(),
            });
        }
        assert!(
            !common.unwrap().is_empty(),
            "{what}: face {f} stretches the texture across a seam"
        );
    }
    seam_corners
}

#[test]
fn simplify_keeps_every_triangle_inside_one_texture_chart_with_its_material() {
    for name in [OBJ, PLY] {
        let input = read_mesh(data(name)).unwrap();
        for ratio in [0.5, 0.1, 0.02] {
            let what = format!("{name} at {ratio}");
            let s = meshpyr::simplify(
                &input,
                meshpyr::SimplifyTarget::Ratio(ratio),
                &Default::default(),
                &meshpyr::NoProgress,
            )
            .unwrap();
            assert!(s.mesh.n_faces() < input.n_faces() * 3 / 4, "{what}");
            assert_eq!(s.mesh.materials, input.materials, "{what}");
            assert_eq!(s.mesh.group_names, input.group_names, "{what}");
            let seam = assert_no_texture_across_seams(&input, &s.mesh, &s.source_rows, &what);
            assert!(seam > 0, "{what}: no seam left to check");
            // What is written reads back the same.
            let format = if name.ends_with(".obj") {
                MeshFormat::Obj
            } else {
                MeshFormat::Ply
            };
            let bytes = write_mesh_bytes(&s.mesh, format, &Default::default()).unwrap();
            let back = read_mesh_bytes(&bytes, format).unwrap();
            assert_eq!(
                corner_values(&back, "texcoord"),
                corner_values(&s.mesh, "texcoord"),
                "{what}"
            );
        }
    }
}

/// `mesh` (triangles) textured in many small charts, as an automatic atlas of a scan is: each
/// face goes to the chart of the cell of a `cells`³ grid over the bounding box that holds its
/// centroid, and each chart projects its corners along the axis nearest its summed normal into
/// its own tile of the unit square.
fn with_grid_charts(mut mesh: PolygonMesh, cells: usize) -> PolygonMesh {
    let (lo, hi) = mesh.positions.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let size = (hi - lo) / cells as f64;
    let corners = |f: usize| mesh.face_starts[f] as usize..mesh.face_starts[f + 1] as usize;
    let corner_position = |c: usize| mesh.positions[mesh.face_indices[c] as usize];
    let cell_of = |f: usize| {
        let centroid = corners(f).map(corner_position).sum::<DVec3>() / corners(f).len() as f64;
        let k = ((centroid - lo) / size).to_array();
        k.map(|x| (x as usize).min(cells - 1))
    };
    let mut normal: HashMap<[usize; 3], DVec3> = HashMap::new();
    for f in 0..mesh.n_faces() {
        let p: Vec<DVec3> = corners(f).map(corner_position).collect();
        *normal.entry(cell_of(f)).or_default() += (p[1] - p[0]).cross(p[2] - p[0]);
    }
    let side = (cells.pow(3) as f64).sqrt().ceil() as usize;
    let mut rows = Vec::new();
    for f in 0..mesh.n_faces() {
        let cell = cell_of(f);
        let n = normal[&cell].abs();
        let axis = if n.x >= n.y && n.x >= n.z {
            0
        } else if n.y >= n.z {
            1
        } else {
            2
        };
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = lo + size * DVec3::new(cell[0] as f64, cell[1] as f64, cell[2] as f64);
        let tile = (cell[0] * cells + cell[1]) * cells + cell[2];
        let (tx, ty) = ((tile % side) as f64, (tile / side) as f64);
        for c in corners(f) {
            let local = (corner_position(c) - corner) / size;
            let fit = |x: f64| x.clamp(-0.5, 1.5) * 0.5 + 0.25;
            let u = (tx + fit(local[a])) / side as f64;
            let v = (ty + fit(local[b])) / side as f64;
            rows.push([u as f32, v as f32]);
        }
    }
    let indices = (0..rows.len() as u32).collect();
    mesh.corner_attributes = vec![meshpyr::mesh::CornerAttribute::from_rows(
        "texcoord",
        ["u", "v"],
        &rows,
        indices,
    )];
    mesh
}

/// The test scan `name` in 6³ grid charts, and its `simplify` at 2 % with the default options.
fn grid_charted_at_2_percent(name: &str) -> (PolygonMesh, meshpyr::Simplified) {
    let input = with_grid_charts(read_mesh(data(name)).unwrap(), 6);
    let s = meshpyr::simplify(
        &input,
        meshpyr::SimplifyTarget::Ratio(0.02),
        &Default::default(),
        &meshpyr::NoProgress,
    )
    .unwrap();
    (input, s)
}

#[test]
fn a_scan_cut_into_many_charts_stops_at_its_seam_floor_without_relaxing_the_shape_rules() {
    // Marching-cubes output (zero-area faces, coincident vertices) in a few hundred charts: the
    // seam floor comes long before the topology's. There the relaxed rules would fold faces up
    // to the fold bound across the charts around the seams, so none are relaxed.
    let (input, s) = grid_charted_at_2_percent("mc/mc_implicit_n40.ply");
    assert_eq!(s.relaxed_collapses, 0);
    let shortfall = s
        .shortfall()
        .expect("stops at the seam floor, short of 2 %");
    assert!(shortfall.contains("seam would break"), "{shortfall}");
    assert!(
        s.mesh.n_faces() < input.n_faces() / 5,
        "{}",
        s.mesh.n_faces()
    );
    // Every corner keeps a value its vertex had.
    let tc = s.mesh.corner_attribute("texcoord").unwrap();
    let had: BTreeSet<(u32, Vec<u64>)> = (0..input.face_indices.len())
        .map(|c| (input.face_indices[c], bits(&input, c)))
        .collect();
    for c in 0..s.mesh.face_indices.len() {
        let v = s.source_rows[s.mesh.face_indices[c] as usize];
        assert!(had.contains(&(v, bits(&s.mesh, c))), "corner {c}");
    }
    assert!(tc.pool_len() > 0);
}

#[test]
fn at_the_seam_floor_a_scan_with_holes_stops_short_of_collapses_far_dearer_than_those_made() {
    // A scan with holes in many charts cannot reach 2 %: past the last pass with a cost cut
    // only dear collapses are legal, such as a rim eating the tip of a strip one face wide.
    // They are left, and the report names them.
    let (input, s) = grid_charted_at_2_percent("mc/mc_armadillo_open52.ply");
    let shortfall = s.shortfall().expect("stops short of 2 %");
    assert!(
        shortfall.contains("dearer than the seam floor allows"),
        "{shortfall}"
    );
    assert!(s.mesh.n_faces() > input.n_faces() / 50, "{shortfall}");
}

/// The texture coordinates of corner `c` as f64 bits.
fn bits(m: &PolygonMesh, c: usize) -> Vec<u64> {
    let tc = m.corner_attribute("texcoord").unwrap();
    tc.value(c).unwrap().iter().map(|x| x.to_bits()).collect()
}

#[test]
fn simplify_keeps_corner_normals_of_the_surviving_corners() {
    let input = read_mesh(data(OBJ)).unwrap();
    let s = meshpyr::simplify(
        &input,
        meshpyr::SimplifyTarget::Ratio(0.1),
        &Default::default(),
        &meshpyr::NoProgress,
    )
    .unwrap();
    let normals = |m: &PolygonMesh, rows: &[u32]| {
        let a = m.corner_attribute("normal").unwrap();
        let mut per: HashMap<u32, BTreeSet<Vec<u64>>> = HashMap::new();
        for c in 0..m.face_indices.len() {
            let v = rows[m.face_indices[c] as usize];
            let n = a.value(c).unwrap().iter().map(|x| x.to_bits()).collect();
            per.entry(v).or_default().insert(n);
        }
        per
    };
    let identity: Vec<u32> = (0..input.positions.len() as u32).collect();
    let before = normals(&input, &identity);
    let after = normals(&s.mesh, &s.source_rows);
    for (v, set) in &after {
        assert!(
            set.is_subset(&before[v]),
            "vertex {v} got a normal it did not have"
        );
    }
}

/// The input rows of level `n`'s vertices (PM vertices `0..n`).
fn level_rows(pyramid: &Pyramid, n: usize) -> Vec<u32> {
    pyramid.pm.pm_to_mesh()[..n]
        .iter()
        .map(|&v| pyramid.source.vertex_source[v as usize])
        .collect()
}

#[test]
fn every_level_of_a_textured_pyramid_keeps_each_triangle_inside_one_texture_chart() {
    for name in [OBJ, PLY] {
        let input = read_mesh(data(name)).unwrap();
        let pyramid = Pyramid::build(&input).unwrap();
        assert!(pyramid.pm.keeps_seams(), "{name}");
        let levels = pyramid.levels();
        let (base, finest) = (*levels.start(), *levels.end());
        assert!(
            base * 2 < finest,
            "{name}: the hierarchy went far ({base} of {finest})"
        );
        for n in [base, base + 1, (base + finest) / 2, finest - 1, finest] {
            let what = format!("{name} level {n}");
            let level = pyramid.level_mesh(n).unwrap();
            assert_eq!(level.n_vertices(), n, "{what}");
            assert_eq!(level.n_faces(), pyramid.pm.n_faces_at(n), "{what}");
            let tris: Vec<[u32; 3]> = level
                .face_indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect();
            assert_eq!(tris, pyramid.pm.level_triangles(n), "{what}");
            assert_eq!(level.materials, input.materials, "{what}");
            assert_eq!(level.group_names, input.group_names, "{what}");
            let seam =
                assert_no_texture_across_seams(&input, &level, &level_rows(&pyramid, n), &what);
            assert!(seam > 0, "{what}: no seam left to check");
            if name == OBJ {
                assert!(
                    level.corner_attribute("normal").is_some(),
                    "{what}: corner normals"
                );
            }
        }
    }
}

#[test]
fn the_base_level_of_a_textured_build_is_what_simplify_writes_for_the_same_target() {
    let input = read_mesh(data(OBJ)).unwrap();
    let target = input.n_faces() / 4;
    let options = meshpyr::format::PyramidOptions {
        pm: meshpyr::pm::PmOptions {
            target_faces: target,
            ..Default::default()
        },
        ..Default::default()
    };
    let pyramid = Pyramid::build_with(input.clone(), &options, &meshpyr::NoProgress).unwrap();
    let simplified = meshpyr::simplify(
        &input,
        meshpyr::SimplifyTarget::Faces(target),
        &Default::default(),
        &meshpyr::NoProgress,
    )
    .unwrap();
    // The replay of the records over the finest corners finds the wedges the decimator kept.
    let base = pyramid.level_mesh(*pyramid.levels().start()).unwrap();
    assert_eq!(base, simplified.mesh);
}

#[test]
fn a_pyr_file_gives_the_same_level_bytes_as_the_pyramid_in_memory_and_records_the_uv_weight() {
    let input = read_mesh(data(OBJ)).unwrap();
    let options = meshpyr::format::PyramidOptions {
        pm: meshpyr::pm::PmOptions {
            uv_weight: 2.0,
            ..Default::default()
        },
        ..Default::default()
    };
    let pyramid = Pyramid::build_with(input.clone(), &options, &meshpyr::NoProgress).unwrap();
    let (bytes, _) = pyramid.to_pyr_bytes().unwrap();
    let file = meshpyr::format::decode(&bytes).unwrap();
    assert_eq!(file.info.pm.uv_weight, 2.0);
    assert!(file.pm.keeps_seams());
    let (base, finest) = (*pyramid.levels().start(), *pyramid.levels().end());
    for n in [base, (2 * base + finest) / 3, finest - 1] {
        for format in [MeshFormat::Obj, MeshFormat::Ply] {
            let in_memory = pyramid.level_mesh(n).unwrap();
            let read = file.level_mesh(n).unwrap();
            assert_eq!(
                write_mesh_bytes(&read, format, &Default::default()).unwrap(),
                write_mesh_bytes(&in_memory, format, &Default::default()).unwrap(),
                "level {n} as {format:?}"
            );
        }
    }
}

fn in_blocks(block_vertices: usize, block_scratch: Option<std::path::PathBuf>) -> PyramidOptions {
    PyramidOptions {
        pm: meshpyr::pm::PmOptions {
            block_vertices: Some(block_vertices),
            block_scratch,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A hierarchy built in blocks keeps the seams as one built in one process: its records replay
/// exactly through the validating constructor, every level keeps each triangle inside one
/// texture chart with its material, and its `.pyr` file gives the same levels.
#[test]
fn a_hierarchy_built_in_blocks_keeps_each_triangle_inside_one_texture_chart_at_every_level() {
    for name in [OBJ, PLY] {
        let input = read_mesh(data(name)).unwrap();
        let whole = Pyramid::build(&input).unwrap();
        for block in [48, 128] {
            let options = in_blocks(block, None);
            let pyramid =
                Pyramid::build_with(input.clone(), &options, &meshpyr::NoProgress).unwrap();
            let what = format!("{name} in blocks of {block}");
            assert!(pyramid.pm.keeps_seams(), "{what}");
            let again = meshpyr::pm::ProgressiveMesh::from_parts(pyramid.pm.to_parts())
                .expect("the splits replay exactly to the input");
            assert_eq!(again.n_base_faces(), pyramid.pm.n_base_faces(), "{what}");
            let (base, finest) = (*pyramid.levels().start(), *pyramid.levels().end());
            // The blocks stop where the one-process build does, at the seam floor, give or
            // take the vertices pinned at a border when no frame's blocks find more.
            let floor = *whole.levels().start();
            assert!(
                base * 2 < finest,
                "{what}: the hierarchy went far ({base} of {finest})"
            );
            assert!(
                base <= floor + floor / 4,
                "{what}: base {base}, one process {floor}"
            );
            let (bytes, _) = pyramid.to_pyr_bytes().unwrap();
            let file = meshpyr::format::decode(&bytes).unwrap();
            assert!(file.pm.keeps_seams(), "{what}");
            for n in [base, base + 1, (base + finest) / 2, finest - 1] {
                let what = format!("{what}, level {n}");
                let level = pyramid.level_mesh(n).unwrap();
                assert_eq!(level.n_faces(), pyramid.pm.n_faces_at(n), "{what}");
                let seam =
                    assert_no_texture_across_seams(&input, &level, &level_rows(&pyramid, n), &what);
                assert!(seam > 0, "{what}: no seam left to check");
                assert!(
                    file.level_mesh(n).unwrap() == level,
                    "{what}: the file's level"
                );
            }
        }
    }
}

/// The task files of a partitioned build do not carry the seams: a hierarchy built through
/// them does not claim them, and its coarser levels carry materials but no corners.
#[test]
fn a_build_through_task_files_does_not_claim_the_seams_and_its_levels_carry_no_corners() {
    let input = read_mesh(data(OBJ)).unwrap();
    let scratch = tempfile::tempdir().unwrap();
    let options = in_blocks(128, Some(scratch.path().to_path_buf()));
    let pyramid = Pyramid::build_with(input.clone(), &options, &meshpyr::NoProgress).unwrap();
    assert!(!pyramid.pm.keeps_seams());
    let (bytes, _) = pyramid.to_pyr_bytes().unwrap();
    let file = meshpyr::format::decode(&bytes).unwrap();
    assert!(!file.pm.keeps_seams());
    let level = file.level_mesh(*pyramid.levels().start()).unwrap();
    assert!(level.corner_attributes.is_empty());
    assert_eq!(
        level.materials, input.materials,
        "faces keep their materials"
    );
}

#[test]
fn levels_below_the_seam_floor_are_refused_as_for_any_mesh() {
    let input = read_mesh(data(OBJ)).unwrap();
    let pyramid = Pyramid::build(&input).unwrap();
    let base = *pyramid.levels().start();
    let handle = MoveHandle {
        center: input.positions[0],
        displacement: DVec3::Y * 0.2,
        radius: 0.5,
    };
    let err = pyramid
        .edit(base - 1, &[handle], &Filter::new())
        .unwrap_err();
    assert!(
        err.to_string().contains("outside the pyramid's levels"),
        "{err}"
    );
}

/// `bytes` re-written with minor version `minor`, its `OPTS` section dropped (`None`) or
/// replaced by `opts`.
fn with_options(bytes: &[u8], minor: u16, opts: Option<&[u8]>) -> Vec<u8> {
    use meshpyr::format::container::{Container, Section, write_container};
    let c = Container::parse(bytes).unwrap();
    let sections: Vec<Section> = c
        .sections
        .iter()
        .filter_map(|e| {
            let mut b = bytes[e.offset as usize..(e.offset + e.length) as usize].to_vec();
            if &e.tag == b"OPTS" {
                b = opts?.to_vec();
            }
            Some(Section {
                tag: e.tag,
                flags: e.flags,
                bytes: b,
            })
        })
        .collect();
    write_container(meshpyr::format::MAJOR, minor, &sections)
}

#[test]
fn a_2_2_file_without_build_options_still_reads_with_its_coarse_levels_untextured() {
    let input = read_mesh(data(OBJ)).unwrap();
    let (bytes, _) = Pyramid::build(&input).unwrap().to_pyr_bytes().unwrap();
    let old = meshpyr::format::decode(&with_options(&bytes, 2, None)).unwrap();
    assert_eq!(old.input, input);
    assert!(!old.pm.keeps_seams());
    let level = old.level_mesh(old.pm.n_base_vertices()).unwrap();
    assert!(level.corner_attributes.is_empty());
    assert_eq!(face_materials(&level).len(), level.n_faces());
}

#[test]
fn damaged_build_options_and_records_that_break_a_seam_are_typed_errors() {
    let input = read_mesh(data(OBJ)).unwrap();
    let (bytes, _) = Pyramid::build(&input).unwrap().to_pyr_bytes().unwrap();
    let mut opts = 0.25f64.to_le_bytes().to_vec();
    opts.push(2);
    let err = meshpyr::format::decode(&with_options(&bytes, 3, Some(&opts))).unwrap_err();
    assert!(
        err.to_string().contains("seam flag must be 0 or 1"),
        "{err}"
    );
    let err = meshpyr::format::decode(&with_options(&bytes, 3, Some(&[0u8; 3]))).unwrap_err();
    assert!(err.to_string().contains("OPTS"), "{err}");
    // A build through task files breaks seams; a file claiming otherwise is refused where the
    // replay meets the first such record.
    let scratch = tempfile::tempdir().unwrap();
    let options = in_blocks(128, Some(scratch.path().to_path_buf()));
    let blocks = Pyramid::build_with(input.clone(), &options, &meshpyr::NoProgress).unwrap();
    let (bytes, _) = blocks.to_pyr_bytes().unwrap();
    let mut claims = 0.25f64.to_le_bytes().to_vec();
    claims.push(1);
    let file = meshpyr::format::decode(&with_options(&bytes, 3, Some(&claims))).unwrap();
    let err = file.level_mesh(file.pm.n_base_vertices()).unwrap_err();
    assert!(err.to_string().contains("breaks a texture seam"), "{err}");
}
