//! A textured scan in `meshpyr view`'s API: the page gets the images as their files hold them
//! and a drawing layout whose split vertices carry the input's texture coordinates (over the
//! display budget, those of the shown level's corners), an untextured scan gets none of it,
//! and exports after an edit keep the per-corner data and materials, also over the budget.

mod view_support;

use meshpyr::io::MeshFormat;
use meshpyr::mesh::corners::{MATERIAL_ATTRIBUTE, TEXCOORD};
use view_support::{data, octaves_of, serve, serve_with_budget};

const OBJ: &str = "textured/anchor_tex.obj";

/// A display budget under anchor_tex's 1,050 triangles: the page shows a coarser level.
const COARSE_BUDGET: usize = 500;

/// `/api/texcoords` decoded: per drawn vertex the vertex it draws and its coordinates, the
/// triangles over drawn vertices, and the groups `[image, first, count]`.
struct Layout {
    vertex_of: Vec<u32>,
    uvs: Vec<[f32; 2]>,
    triangles: Vec<[u32; 3]>,
    groups: Vec<[u32; 3]>,
}

fn layout_of(bytes: &[u8]) -> Layout {
    let head: Vec<u32> = u32s(&bytes[..12]).collect();
    let (nd, nt, ng) = (head[0] as usize, head[1] as usize, head[2] as usize);
    let mut at = 12;
    let mut take = |n: usize| {
        let part = &bytes[at..at + 4 * n];
        at += 4 * n;
        part
    };
    let vertex_of: Vec<u32> = u32s(take(nd)).collect();
    let uvs: Vec<[f32; 2]> = take(2 * nd)
        .chunks_exact(8)
        .map(|c| {
            let x = |k: usize| f32::from_le_bytes(c[k..k + 4].try_into().unwrap());
            [x(0), x(4)]
        })
        .collect();
    let triples = |part: &[u8]| -> Vec<[u32; 3]> {
        let flat: Vec<u32> = u32s(part).collect();
        flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
    };
    let triangles = triples(take(3 * nt));
    let groups = triples(take(3 * ng));
    assert_eq!(at, bytes.len());
    Layout {
        vertex_of,
        uvs,
        triangles,
        groups,
    }
}

fn u32s(bytes: &[u8]) -> impl Iterator<Item = u32> + '_ {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
}

#[test]
fn info_lists_the_images_and_the_texture_endpoint_serves_their_files() {
    let server = serve(OBJ);
    let info = server.api("GET", "/api/info", b"").json();
    let texture = &info["texture"];
    assert_eq!(
        texture["images"],
        serde_json::json!(["textures/right.png", "textures/left.png"])
    );
    assert_eq!(texture["materials"][0]["name"], "right");
    assert_eq!(texture["materials"][1]["image"], 1);
    for (k, name) in ["textures/right.png", "textures/left.png"]
        .iter()
        .enumerate()
    {
        let image = server.api("GET", &format!("/api/texture?image={k}"), b"");
        assert_eq!(image.status, 200);
        assert_eq!(image.header("Content-Type"), Some("image/png"));
        let file = std::fs::read(data("textured").join(name)).unwrap();
        assert_eq!(image.body, file);
    }
    for bad in [
        "/api/texture?image=2",
        "/api/texture",
        "/api/texture?image=-1",
    ] {
        assert_eq!(server.api("GET", bad, b"").status, 400, "{bad}");
    }
}

#[test]
fn the_layout_splits_vertices_by_texture_coordinates_for_drawing_only() {
    let server = serve(OBJ);
    let input = meshpyr::read_mesh(data(OBJ)).unwrap();
    let uv = input.corner_attribute(TEXCOORD).unwrap();
    let layout = layout_of(&server.api("GET", "/api/texcoords", b"").body);
    let (nd, nt) = (layout.vertex_of.len(), layout.triangles.len());
    assert_eq!(nt, input.n_triangles());
    // As many drawn vertices as distinct (vertex, coordinates) pairs: more than the vertices
    // (seams), no more than the corners.
    assert!(
        nd > input.n_vertices() && nd <= input.face_indices.len(),
        "{nd}"
    );
    // Every corner of the input appears, at its vertex, with its coordinates.
    let mut drawn: Vec<(u32, [u32; 2])> = layout
        .triangles
        .iter()
        .flatten()
        .map(|&d| {
            let d = d as usize;
            (layout.vertex_of[d], layout.uvs[d].map(f32::to_bits))
        })
        .collect();
    let mut corners: Vec<(u32, [u32; 2])> = (0..input.face_indices.len())
        .map(|c| {
            let value = uv.value(c).unwrap();
            (
                input.face_indices[c],
                [(value[0] as f32).to_bits(), (value[1] as f32).to_bits()],
            )
        })
        .collect();
    drawn.sort_unstable();
    drawn.dedup();
    corners.sort_unstable();
    corners.dedup();
    assert_eq!(drawn, corners);
    // Two materials, each with its image: two groups covering every triangle.
    let groups = &layout.groups;
    assert_eq!(groups.len(), 2);
    assert_eq!((groups[0][0], groups[0][1]), (0, 0));
    assert_eq!((groups[1][0], groups[1][1]), (1, groups[0][2]));
    assert_eq!(groups[0][2] + groups[1][2], nt as u32);
}

/// The layout draws exactly `triangles` (PM indices), and every drawn corner is a corner the
/// input has at that vertex: a level's vertex `i` is PM vertex `i`, at its input position, so
/// each drawn triangle keeps one chart of the texture.
fn assert_layout_draws_with_the_inputs_corners(layout: &Layout, triangles: &[u32]) {
    let drawn: Vec<u32> = layout
        .triangles
        .iter()
        .flatten()
        .map(|&d| layout.vertex_of[d as usize])
        .collect();
    let sorted = |flat: &[u32]| {
        let mut t: Vec<&[u32]> = flat.chunks_exact(3).collect();
        t.sort_unstable();
        t.into_iter().map(<[u32]>::to_vec).collect::<Vec<_>>()
    };
    assert_eq!(sorted(&drawn), sorted(triangles));
    let input = meshpyr::read_mesh(data(OBJ)).unwrap();
    let pyramid = meshpyr::Pyramid::build(&input).unwrap();
    let pm = pyramid.pm.original_positions();
    let uv = input.corner_attribute(TEXCOORD).unwrap();
    let input_corners: std::collections::HashSet<([u64; 3], [u32; 2])> =
        (0..input.face_indices.len())
            .map(|c| {
                let p = input.positions[input.face_indices[c] as usize];
                let value = uv.value(c).unwrap();
                (
                    p.to_array().map(f64::to_bits),
                    [(value[0] as f32).to_bits(), (value[1] as f32).to_bits()],
                )
            })
            .collect();
    for (d, &v) in layout.vertex_of.iter().enumerate() {
        let key = (
            pm[v as usize].to_array().map(f64::to_bits),
            layout.uvs[d].map(f32::to_bits),
        );
        assert!(input_corners.contains(&key), "drawn vertex {d} (PM {v})");
    }
}

/// Over the budget the page draws the shown level: the layout covers exactly its triangles
/// (`/api/display`, PM indices), and every drawn corner is a corner the input has at that
/// vertex, so each triangle keeps one chart of the texture.
#[test]
fn over_the_budget_the_layout_textures_the_shown_level_with_the_inputs_corners() {
    let server = serve_with_budget(OBJ, COARSE_BUDGET);
    let info = server.api("GET", "/api/info", b"").json();
    assert_eq!(info["display"]["lod"], true);
    let display = server.api("GET", "/api/display", b"").body;
    let shown = u32s(&display[..4]).next().unwrap();
    let shown_triangles: Vec<u32> = u32s(&display[8..]).collect();
    let layout = layout_of(&server.api("GET", "/api/texcoords", b"").body);
    assert!(layout.vertex_of.iter().all(|&v| v < shown));
    assert_layout_draws_with_the_inputs_corners(&layout, &shown_triangles);
    // More drawn vertices than shown vertices: the level keeps seams.
    assert!(layout.vertex_of.len() > shown as usize, "no seam split");
    assert_eq!(layout.groups.len(), 2);
    assert_eq!(
        layout.groups.iter().map(|g| g[2]).sum::<u32>() as usize,
        layout.triangles.len()
    );
}

/// The scrubber's level `n`: the layout covers exactly `/api/level?n=N`'s triangles, and
/// every drawn corner is a corner the input has at that vertex.
#[test]
fn the_layout_of_a_scrubbed_level_textures_its_triangles_with_the_inputs_corners() {
    let server = serve(OBJ);
    let info = server.api("GET", "/api/info", b"").json();
    let min = info["levels"]["min"].as_u64().unwrap();
    let n = min + 20;
    let level = server.api("GET", &format!("/api/level?n={n}"), b"").body;
    let head: Vec<u32> = u32s(&level[..8]).collect();
    let (nv, nt) = (head[0] as usize, head[1] as usize);
    assert_eq!(nv as u64, n);
    let level_triangles: Vec<u32> = u32s(&level[8 + 12 * nv..]).collect();
    assert_eq!(level_triangles.len(), 3 * nt);
    let layout = layout_of(
        &server
            .api("GET", &format!("/api/texcoords?n={n}"), b"")
            .body,
    );
    assert!(layout.vertex_of.iter().all(|&v| (v as usize) < nv));
    assert_layout_draws_with_the_inputs_corners(&layout, &level_triangles);
    assert!(layout.vertex_of.len() > nv, "no seam split");
    assert_eq!(layout.groups.len(), 2);
    for bad in ["n=0", "n=abc", "n=100000"] {
        let reply = server.api("GET", &format!("/api/texcoords?{bad}"), b"");
        assert_eq!(reply.status, 400, "{bad}");
    }
}

#[test]
fn an_untextured_scan_has_no_texture_and_no_layout() {
    let server = serve("mc/mc_bunny_vox40.ply");
    let info = server.api("GET", "/api/info", b"").json();
    assert!(info["texture"].is_null());
    for path in [
        "/api/texcoords",
        "/api/texcoords?n=100",
        "/api/texture?image=0",
    ] {
        assert_eq!(server.api("GET", path, b"").status, 409, "{path}");
    }
}

#[test]
fn an_export_after_an_edit_keeps_the_texture_coordinates_and_materials() {
    export_after_an_edit_keeps_the_texture(&serve(OBJ));
}

/// Over the budget the page shows a coarse level, but the export is the whole result.
#[test]
fn over_the_budget_an_export_after_an_edit_keeps_the_texture_coordinates_and_materials() {
    let server = serve_with_budget(OBJ, COARSE_BUDGET);
    let info = server.api("GET", "/api/info", b"").json();
    assert_eq!(info["display"]["lod"], true);
    export_after_an_edit_keeps_the_texture(&server);
}

fn export_after_an_edit_keeps_the_texture(server: &view_support::Running) {
    let info = server.api("GET", "/api/info", b"").json();
    let gains = vec![1.0; octaves_of(&info).len()];
    let (min, max) = (&info["bbox"]["min"], &info["bbox"]["max"]);
    let centre: Vec<f64> = (0..3)
        .map(|k| 0.5 * (min[k].as_f64().unwrap() + max[k].as_f64().unwrap()))
        .collect();
    let diagonal = info["diagonal"].as_f64().unwrap();
    let state = serde_json::json!({"gains": gains, "moves": [{
        "level": info["levels"]["max"], "center": centre,
        "displacement": [0.0, 0.05 * diagonal, 0.0], "radius": 0.3 * diagonal}]});
    let body = state.to_string();
    let edited = server.api("POST", "/api/export?format=obj", body.as_bytes());
    assert_eq!(edited.status, 200);
    let exported = meshpyr::io::read_mesh_bytes(&edited.body, MeshFormat::Obj).unwrap();
    let input = meshpyr::read_mesh(data(OBJ)).unwrap();
    let values = |m: &meshpyr::PolygonMesh| -> Vec<Option<Vec<f32>>> {
        let uv = m.corner_attribute(TEXCOORD).unwrap();
        (0..m.face_indices.len())
            .map(|c| uv.value(c).map(|v| v.iter().map(|&x| x as f32).collect()))
            .collect()
    };
    assert!(
        values(&exported) == values(&input),
        "the corners' vt differ"
    );
    let names = |m: &meshpyr::PolygonMesh| -> Vec<String> {
        m.materials.list.iter().map(|x| x.name.clone()).collect()
    };
    assert_eq!(names(&exported), names(&input));
    // A download may be saved anywhere: its references are absolute, and from another
    // folder the file finds its library and images without a warning.
    let folder = input.materials.folder.clone().unwrap();
    let absolute: Vec<String> = input
        .materials
        .libraries
        .iter()
        .map(|l| folder.join(l).to_string_lossy().into_owned())
        .collect();
    assert_eq!(exported.materials.libraries, absolute);
    let elsewhere = tempfile::tempdir().unwrap();
    let saved = elsewhere.path().join("download.obj");
    std::fs::write(&saved, &edited.body).unwrap();
    let (reread, warnings) = meshpyr::io::read_mesh_reporting(&saved).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    for m in &reread.materials.list {
        let image = m.texture.as_deref().expect("the library names the image");
        assert!(std::path::Path::new(image).is_file(), "{image}");
    }
    assert!(
        exported.face_attribute(MATERIAL_ATTRIBUTE) == input.face_attribute(MATERIAL_ATTRIBUTE),
        "the faces' usemtl differ"
    );
    assert_eq!(exported.face_indices, input.face_indices);
    assert_ne!(
        exported.positions, input.positions,
        "the edit moved vertices"
    );
}
