//! The body of the `pyramid_ops` fuzz target, kept in the library so that the committed corpus
//! is replayed by `cargo test` without cargo-fuzz.

use super::{DetailPyramid, Filter, LevelGains, LevelSpec, MoveHandle, Pyramid, PyramidOptions};
use crate::mesh::PolygonMesh;
use crate::pm::fuzz::{Bytes, mesh_from_bytes};
use crate::progress::NoProgress;
use crate::relax::SecondDifference;
use glam::DVec3;
use std::sync::OnceLock;

/// Pools of 1 and 3 threads, built once per process: a fuzzer runs thousands of inputs.
fn pools() -> &'static [rayon::ThreadPool; 2] {
    static POOLS: OnceLock<[rayon::ThreadPool; 2]> = OnceLock::new();
    POOLS.get_or_init(|| {
        [1, 3].map(|n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("a thread pool")
        })
    })
}

/// A gain band from three bytes: levels as fractions of the hierarchy, gain in `[0, 4)`.
fn band(r: &mut Bytes, n0: usize, n: usize) -> (LevelSpec, LevelSpec, f64) {
    let at = |b: u8| n0 + (n - n0) * b as usize / 255;
    let (a, b) = (at(r.u8()), at(r.u8()));
    let g = r.u8() as f64 / 64.0;
    (
        LevelSpec::Vertices(a.min(b)),
        LevelSpec::Vertices(a.max(b)),
        g,
    )
}

/// Interprets `data` as a small mesh (grid, torus, grid with holes or two components; some
/// vertices optionally snapped onto others, which leaves zero-length edges and zero-area
/// faces for the builder to repair), builds its pyramid, and checks:
///
/// - the analysis gives the same pyramid (storage order, base, every detail) on 1 and 3
///   threads;
/// - unit gains reproduce the analysed signal to 1e-6 of the bounding-box diagonal (the
///   details are quantised, docs/algorithms.md §1f);
/// - a filter of up to three bands from the bytes gives finite values, the same bits on 1 and
///   3 threads, and the same bits when resumed from a level in the middle or run as an edit
///   that moves nothing;
/// - an edit with a handle from the bytes gives finite values;
/// - the output mesh has exactly the input's vertex count and faces.
///
/// Inputs the builder rejects (say, every face degenerate) must fail with an error.
///
/// # Panics
/// On any violated invariant — that is how the fuzzer reports a bug.
pub(crate) fn fuzz_pyramid(data: &[u8]) {
    let mut r = Bytes::new(data);
    let (mut pos, tris) = mesh_from_bytes(&mut r);
    for _ in 0..r.u8() % 4 {
        let (a, b) = (r.u8() as usize % pos.len(), r.u8() as usize % pos.len());
        pos[a] = pos[b];
    }
    let input = PolygonMesh::from_triangles(pos, &tris);
    let relax = SecondDifference::default();
    let [one, three] = pools();
    let Ok(scan) =
        one.install(|| Pyramid::build_with(input.clone(), &PyramidOptions::default(), &NoProgress))
    else {
        return;
    };
    let pyr = &scan.pyramid;
    let (n0, n) = (pyr.n_base_vertices(), pyr.n_vertices());

    let again = three
        .install(|| DetailPyramid::analyze(&scan.pm, &relax, &NoProgress))
        .expect("the analysis succeeded on one thread");
    assert!(pyr.base() == again.base(), "base differs on 3 threads");
    for k in 0..pyr.n_splits() {
        assert_eq!(pyr.split_slot(k), again.split_slot(k));
        assert!(
            pyr.split_details(k).0 == again.split_details(k).0
                && pyr.split_details(k).1.eq(again.split_details(k).1),
            "split {k} differs on 3 threads"
        );
    }

    let original = scan.pm.original_positions();
    let unit = one.install(|| pyr.synthesize(&LevelGains::unit()));
    let tolerance = 1e-6 * pyr.bbox_diagonal().max(f64::MIN_POSITIVE);
    for (i, (a, b)) in unit.iter().zip(original).enumerate() {
        assert!(
            a.distance(*b) <= tolerance,
            "vertex {i}: unit gains give {a} for {b}"
        );
    }

    let mut filter = Filter::default();
    for _ in 0..1 + r.u8() % 3 {
        let (a, b, g) = band(&mut r, n0, n);
        filter = filter.gain(a, b, g);
    }
    filter.normal_only = r.u8() % 2 == 1;
    let gains = filter.resolve(pyr.surface_area());
    let filtered = one.install(|| pyr.synthesize(&gains));
    assert!(filtered.iter().all(|p| p.is_finite()), "non-finite filter");
    let parallel = three.install(|| pyr.synthesize(&gains));
    assert!(filtered == parallel, "filter differs on 3 threads");
    let mid = n0 + (n - n0) * r.u8() as usize / 255;
    let mut resumed = pyr.base_signal();
    pyr.synthesize_range(&mut resumed, n0, mid, &gains);
    pyr.synthesize_range(&mut resumed, mid, n, &gains);
    assert!(
        filtered == resumed,
        "resuming at level {mid} changes the bits"
    );
    let unmoved = three
        .install(|| pyr.edit_with(mid, &gains, |_| {}))
        .expect("a level inside the pyramid");
    assert!(
        filtered == unmoved,
        "an edit moving nothing at {mid} changes the bits"
    );

    // A built pyramid has vertices, so `unit` is not empty.
    let handle = MoveHandle {
        center: unit[r.u8() as usize % unit.len()],
        displacement: DVec3::new(r.u8() as f64, r.u8() as f64, r.u8() as f64) / 256.0,
        radius: (1 + r.u8() as usize) as f64 / 64.0,
    };
    let edited = pyr
        .edit(mid, &[handle], &gains)
        .expect("a valid handle and level");
    assert!(edited.iter().all(|p| p.is_finite()), "non-finite edit");

    let out = scan.output_mesh(&filtered);
    assert_eq!(out.positions.len(), input.positions.len());
    assert!(out.face_starts == input.face_starts && out.face_indices == input.face_indices);
}

/// The pyramid's side of the `read_pyr` target, on a decoded file whose stored details fit
/// it: the spectrum and a pyramid from the stored details, and a filter.
pub(crate) fn fuzz_loaded_pyr(d: crate::format::PyrData) {
    let _ = d.stored_spectrum(None);
    if let Ok(p) = d.into_pyramid(&NoProgress) {
        let _ = p.filter(&Filter::new().gain(p.pyramid.n_base_vertices(), usize::MAX, 1.5));
        let _ = p.spectrum();
    }
}
