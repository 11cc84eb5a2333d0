//! Unit tests of the rasteriser through the public drawing functions.

use super::*;

fn cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let p: Vec<DVec3> = (0..8)
        .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let t = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    (p, t)
}

#[test]
fn cube_covers_the_centre_and_leaves_the_corners_empty() {
    let (p, t) = cube();
    let opts = RenderOptions {
        width: 64,
        height: 48,
        ..Default::default()
    };
    let img = render(
        Triangles {
            positions: &p,
            triangles: &t,
        },
        &opts,
    );
    assert_eq!((img.width, img.height), (64, 48));
    assert_ne!(img.pixel(32, 24), Some(opts.background));
    assert_eq!(img.pixel(0, 0), Some(opts.background));
    // Fitted to the height with a 5% margin: the square front face spans ~90% of 48 rows.
    let covered = (0..48)
        .filter(|&y| img.pixel(32, y) != Some(opts.background))
        .count();
    assert!((41..=45).contains(&covered), "{covered}");
}

#[test]
fn nearer_faces_win_the_depth_test() {
    // Two overlapping squares at z = 0 (dark) and z = 1 (facing the light): the nearer one
    // must be visible whatever the drawing order.
    let p = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.2, 0.2, 1.0),
        DVec3::new(0.8, 0.2, 1.0),
        DVec3::new(0.5, 0.8, 1.0),
    ];
    let back = [[0, 1, 2], [0, 2, 3]];
    let front = [[4, 5, 6]];
    let opts = RenderOptions {
        width: 40,
        height: 40,
        color: [200, 0, 0],
        ..Default::default()
    };
    let order_a: Vec<[u32; 3]> = back.iter().chain(front.iter()).copied().collect();
    let order_b: Vec<[u32; 3]> = front.iter().chain(back.iter()).copied().collect();
    let a = render(
        Triangles {
            positions: &p,
            triangles: &order_a,
        },
        &opts,
    );
    let b = render(
        Triangles {
            positions: &p,
            triangles: &order_b,
        },
        &opts,
    );
    assert_eq!(a, b);
}

#[test]
fn panels_share_a_camera_and_png_is_deterministic() {
    let (p, t) = cube();
    let small: Vec<DVec3> = p.iter().map(|&q| q * 0.5).collect();
    let opts = RenderOptions {
        width: 50,
        height: 50,
        yaw_degrees: 30.0,
        pitch_degrees: 20.0,
        ..Default::default()
    };
    let meshes = [
        Triangles {
            positions: &p,
            triangles: &t,
        },
        Triangles {
            positions: &small,
            triangles: &t,
        },
    ];
    let img = render_panels(&meshes, &opts);
    assert_eq!((img.width, img.height), (100, 50));
    let count = |x0: usize| {
        (0..50)
            .flat_map(|y| (x0..x0 + 50).map(move |x| (x, y)))
            .filter(|&(x, y)| img.pixel(x, y) != Some(opts.background))
            .count()
    };
    // Same camera: the half-size cube covers about a quarter of the pixels.
    let (big, half) = (count(0) as f64, count(50) as f64);
    assert!((half / big - 0.25).abs() < 0.06, "{big} {half}");
    let png1 = img.encode_png().unwrap();
    let png2 = render_panels(&meshes, &opts).encode_png().unwrap();
    assert_eq!(png1, png2);
    assert_eq!(&png1[1..4], b"PNG");
}

#[test]
fn garbage_input_does_not_panic() {
    let p = vec![DVec3::splat(f64::NAN), DVec3::X, DVec3::Y];
    let t = vec![[0, 1, 2], [0, 1, 7], [1, 1, 2]];
    let img = render(
        Triangles {
            positions: &p,
            triangles: &t,
        },
        &RenderOptions::default(),
    );
    assert!(img.rgb.iter().all(|&c| c == 255));
    let empty = render(
        Triangles {
            positions: &[],
            triangles: &[],
        },
        &RenderOptions::default(),
    );
    assert_eq!(empty.width, 480);
    assert!(Image::new(0, 0, [0; 3]).encode_png().is_err());
}

/// An 8×8 image of four 4×4 blocks: red and green on top, blue and white below.
fn checker() -> Image {
    let mut image = Image::new(8, 8, [0, 0, 0]);
    for y in 0..8 {
        for x in 0..8 {
            let color = match (x < 4, y < 4) {
                (true, true) => [255, 0, 0],
                (false, true) => [0, 255, 0],
                (true, false) => [0, 0, 255],
                (false, false) => [255, 255, 255],
            };
            image.set(x, y, color);
        }
    }
    image
}

/// The unit square facing the viewer as one quad whose corners map to the corners of texture
/// space, showing material 0.
fn textured_square() -> crate::PolygonMesh {
    use crate::mesh::corners::{MATERIAL_ATTRIBUTE, TEXCOORD};
    use crate::mesh::{Attribute, AttributeData, CornerAttribute, Material};
    let mut m = crate::PolygonMesh::new();
    m.positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    m.push_face(&[0, 1, 2, 3]);
    m.corner_attributes.push(CornerAttribute::from_rows(
        TEXCOORD,
        ["u", "v"],
        &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        vec![0, 1, 2, 3],
    ));
    m.face_attributes.push(Attribute {
        name: MATERIAL_ATTRIBUTE.into(),
        data: AttributeData::I32(vec![0]),
    });
    m.materials.list.push(Material {
        name: "checker".into(),
        texture: Some("checker.png".into()),
    });
    m
}

fn unlit() -> RenderOptions {
    RenderOptions {
        width: 40,
        height: 40,
        margin: 0.0,
        ambient: 1.0,
        ..RenderOptions::default()
    }
}

#[test]
fn a_textured_square_shows_its_image_upright_at_the_quarters() {
    let mesh = textured_square();
    let textures = Textures {
        images: vec![Some(std::sync::Arc::new(checker()))],
    };
    let image = render_textured_meshes(&[("", &mesh, Some(&textures))], &unlit()).unwrap();
    // Fully ambient light: the pixels are the texture's colours; v = 1 is the picture's top.
    assert_eq!(image.pixel(10, 10), Some([255, 0, 0]));
    assert_eq!(image.pixel(30, 10), Some([0, 255, 0]));
    assert_eq!(image.pixel(10, 30), Some([0, 0, 255]));
    assert_eq!(image.pixel(30, 30), Some([255, 255, 255]));
    // Across a block edge the colours blend bilinearly.
    let edge = image.pixel(20, 10).unwrap();
    assert!(
        edge[0] > 0 && edge[0] < 255 && edge[1] > 0 && edge[1] < 255,
        "{edge:?}"
    );
}

#[test]
fn the_texture_is_shaded_like_the_plain_surface() {
    let mesh = textured_square();
    let white = Textures {
        images: vec![Some(std::sync::Arc::new(Image::new(4, 4, [255, 255, 255])))],
    };
    let options = RenderOptions {
        color: [255, 255, 255],
        ..unlit()
    };
    let lit = RenderOptions {
        ambient: 0.3,
        ..options.clone()
    };
    for options in [options, lit] {
        let plain = render_mesh(&mesh, &options).unwrap();
        let textured = render_textured_meshes(&[("", &mesh, Some(&white))], &options).unwrap();
        assert_eq!(plain, textured);
    }
}

#[test]
fn without_an_image_or_texture_coordinates_the_picture_is_the_plain_one() {
    let mesh = textured_square();
    let plain = render_mesh(&mesh, &unlit()).unwrap();
    let none = Textures { images: vec![None] };
    let drawn = render_textured_meshes(&[("", &mesh, Some(&none))], &unlit()).unwrap();
    assert_eq!(drawn, plain);
    let mut bare = mesh.clone();
    bare.corner_attributes.clear();
    let checker = Textures {
        images: vec![Some(std::sync::Arc::new(checker()))],
    };
    let drawn = render_textured_meshes(&[("", &bare, Some(&checker))], &unlit()).unwrap();
    assert_eq!(drawn, plain);
}

#[test]
fn colour_by_a_value_wins_over_the_texture() {
    let mut mesh = textured_square();
    mesh.vertex_attributes.push(crate::mesh::Attribute {
        name: "height".into(),
        data: crate::mesh::AttributeData::F64(vec![0.0, 0.0, 1.0, 1.0]),
    });
    let options = RenderOptions {
        color_by: Some("height".into()),
        ..unlit()
    };
    let checker = Textures {
        images: vec![Some(std::sync::Arc::new(checker()))],
    };
    let textured = render_textured_meshes(&[("", &mesh, Some(&checker))], &options).unwrap();
    assert_eq!(textured, render_mesh(&mesh, &options).unwrap());
}

#[test]
fn textures_load_once_per_file_and_name_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("checker.png"),
        checker().encode_png().unwrap(),
    )
    .unwrap();
    std::fs::write(dir.path().join("broken.png"), b"\x89PNG\r\n\x1a\nbroken").unwrap();
    let mut mesh = textured_square();
    let image = |name: &str| crate::mesh::Material {
        name: name.into(),
        texture: Some(format!("{name}.png")),
    };
    mesh.materials.list = vec![
        image("checker"),
        image("checker"),
        image("gone"),
        image("broken"),
    ];
    mesh.materials.list[1].name = "again".into();
    mesh.materials.folder = Some(dir.path().to_path_buf());
    let (textures, warnings) = Textures::load(&mesh);
    let loaded = &textures.images;
    assert_eq!(loaded[0].as_deref(), Some(&checker()));
    assert!(std::sync::Arc::ptr_eq(
        loaded[0].as_ref().unwrap(),
        loaded[1].as_ref().unwrap()
    ));
    assert!(loaded[2].is_none() && loaded[3].is_none());
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(
        warnings[0].starts_with("image gone.png cannot be read"),
        "{warnings:?}"
    );
    assert!(
        warnings[1].starts_with("image broken.png cannot be decoded"),
        "{warnings:?}"
    );
}
