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
