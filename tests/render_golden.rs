//! Pictures compared byte for byte with committed golden PNGs (tests/data/golden): any change
//! to the rasteriser, the shading, the colour map, the font or the layout shows up here.
//!
//! After an intended change, regenerate them with
//! `MESHPYR_UPDATE_GOLDEN=1 cargo test --test render_golden`, look at them, and commit them.

mod common;

use common::data;
use meshpyr::mesh::{Attribute, AttributeData, PolygonMesh};
use meshpyr::{RenderOptions, Shading, View, render_mesh, render_meshes};

const UPDATE: &str = "MESHPYR_UPDATE_GOLDEN";

/// Compares `png` with the golden file `name`, or writes it when `MESHPYR_UPDATE_GOLDEN` is set.
fn check_golden(name: &str, png: &[u8]) {
    let path = data("golden").join(name);
    if std::env::var_os(UPDATE).is_some() {
        std::fs::write(&path, png).unwrap();
        return;
    }
    let golden = std::fs::read(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (set {UPDATE}=1 to create it)", path.display()));
    assert!(
        golden == png,
        "{name} differs from {} ({} vs {} bytes); if the change is intended, regenerate with {UPDATE}=1",
        path.display(),
        png.len(),
        golden.len()
    );
}

fn small(view: View) -> RenderOptions {
    let (yaw_degrees, pitch_degrees) = view.angles();
    RenderOptions {
        width: 96,
        height: 96,
        yaw_degrees,
        pitch_degrees,
        ..RenderOptions::default()
    }
}

/// The mesh with a per-vertex `height` attribute: its y coordinate.
fn with_height(mut mesh: PolygonMesh) -> PolygonMesh {
    let y = mesh.positions.iter().map(|p| p.y as f32).collect();
    mesh.vertex_attributes.push(Attribute {
        name: "height".into(),
        data: AttributeData::F32(y),
    });
    mesh
}

#[test]
fn flat_front_view_matches_golden() {
    let teapot = meshpyr::read_mesh(data("teapot.ply")).unwrap();
    let image = render_mesh(&teapot, &small(View::Front)).unwrap();
    assert_eq!((image.width, image.height), (96, 96));
    check_golden("teapot_front_flat.png", &image.encode_png().unwrap());
}

#[test]
fn smooth_iso_view_with_wireframe_matches_golden() {
    let teapot = meshpyr::read_mesh(data("teapot.ply")).unwrap();
    let options = RenderOptions {
        shading: Shading::Smooth,
        wireframe: true,
        ..small(View::Iso)
    };
    let image = render_mesh(&teapot, &options).unwrap();
    check_golden("teapot_iso_smooth_wire.png", &image.encode_png().unwrap());
}

#[test]
fn labelled_panels_coloured_by_an_attribute_match_golden() {
    let cone = with_height(meshpyr::read_mesh(data("cone20.ply")).unwrap());
    let cross = with_height(meshpyr::read_mesh(data("cross.ply")).unwrap());
    let options = RenderOptions {
        color_by: Some("height".into()),
        ..small(View::Iso)
    };
    let image = render_meshes(&[("cone20.ply", &cone), ("cross.ply", &cross)], &options).unwrap();
    // Two panels wide; a caption strip above and a colour bar below add to the height.
    assert_eq!(image.width, 192);
    assert!(image.height > 96);
    check_golden("panels_height_iso.png", &image.encode_png().unwrap());
}

#[test]
fn pictures_do_not_depend_on_the_thread_pool() {
    let teapot = with_height(meshpyr::read_mesh(data("teapot.ply")).unwrap());
    let options = RenderOptions {
        color_by: Some("height".into()),
        shading: Shading::Smooth,
        ..small(View::Iso)
    };
    let draw = || {
        render_mesh(&teapot, &options)
            .unwrap()
            .encode_png()
            .unwrap()
    };
    let one = common::on_threads(1, draw);
    let four = common::on_threads(4, draw);
    assert_eq!(one, four);
}
