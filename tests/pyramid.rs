//! The detail pyramid on synthetic meshes: perfect reconstruction (closed, open, several
//! components), the Burt–Adelson property, filters touching only their bands, editing.

mod common;

use common::{closed_loop_bound, on_threads};
use glam::DVec3;
use meshpyr::mesh::{Mesh, SlotIndex};
use meshpyr::pm::{PmOptions, ProgressiveMesh};
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{DetailPyramid, Filter, LevelGains, LevelSpec, MoveHandle};
use meshpyr::relax::SecondDifference;

/// Icosphere with `levels` 1-to-4 subdivisions, made bumpy and (deterministically) noisy.
fn bumpy_sphere(levels: usize, noise: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let (v, f) = meshpyr::mesh::shapes::icosphere(levels);
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let p = v
        .iter()
        .map(|&x| {
            x * (1.0 + 0.08 * (5.0 * x.x).sin() * (4.0 * x.y).cos())
                + noise * DVec3::new(rnd(), rnd(), rnd())
        })
        .collect();
    (p, f)
}

/// A bumpy open height field on an `n × n` grid.
fn bumpy_grid(n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
            p.push(DVec3::new(x, y, 0.05 * (7.0 * x).sin() * (5.0 * y).cos()));
        }
    }
    let mut t = Vec::new();
    let id = |i: usize, j: usize| (j * n + i) as u32;
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, t)
}

fn pyramid_of(p: &[DVec3], t: &[[u32; 3]]) -> (ProgressiveMesh, DetailPyramid) {
    let mesh = Mesh::from_triangles(p, t).unwrap().mesh;
    let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
    let pyr = DetailPyramid::analyze(&pm, &SecondDifference::default(), &NoProgress).unwrap();
    (pm, pyr)
}

/// Mean distance of a vertex to the centroid of its neighbours, over the vertices whose
/// original position passes `keep`.
fn roughness(pm: &ProgressiveMesh, x: &[DVec3], keep: impl Fn(DVec3) -> bool) -> f64 {
    let mesh = Mesh::from_triangles(pm.original_positions(), pm.finest_faces())
        .unwrap()
        .mesh;
    let (mut s, mut n) = (0.0, 0);
    for v in mesh.vertices() {
        let nb = mesh.neighbors(v);
        if nb.is_empty() || !keep(pm.original_positions()[v.slot()]) {
            continue;
        }
        let c: DVec3 = nb.iter().map(|u| x[u.slot()]).sum::<DVec3>() / nb.len() as f64;
        // Normal component only: tangential irregularity is not roughness.
        let xi = x[v.slot()];
        let mut nrm = DVec3::ZERO;
        for k in 0..nb.len() {
            let (a, b) = (x[nb[k].slot()] - xi, x[nb[(k + 1) % nb.len()].slot()] - xi);
            nrm += a.cross(b);
        }
        s += (xi - c).dot(nrm.normalize_or_zero()).abs();
        n += 1;
    }
    s / n as f64
}

fn max_dist(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max)
}

fn assert_reconstructs(p: &[DVec3], t: &[[u32; 3]]) -> (ProgressiveMesh, DetailPyramid) {
    let (pm, pyr) = pyramid_of(p, t);
    assert!(pyr.n_splits() > 0);
    let out = pyr.synthesize(&LevelGains::unit());
    let diag = pyr.bbox_diagonal();
    let err = max_dist(&out, pm.original_positions());
    assert!(
        err <= closed_loop_bound(&pyr),
        "reconstruction error {err:e} (diag {diag})"
    );
    (pm, pyr)
}

#[test]
fn unit_gains_reproduce_a_closed_noisy_surface() {
    let (p, t) = bumpy_sphere(3, 0.01);
    let (pm, pyr) = assert_reconstructs(&p, &t);
    // About 1 + valence details per split: the pyramid is oversampled.
    let per_split = pyr.n_details() as f64 / pyr.n_splits() as f64;
    assert!((5.0..9.0).contains(&per_split), "{per_split}");
    assert!(pm.n_base_vertices() < 50, "{}", pm.n_base_vertices());
}

#[test]
fn unit_gains_reproduce_open_and_multi_component_meshes() {
    let (p, t) = bumpy_grid(20);
    assert_reconstructs(&p, &t);
    // Two spheres and a grid in one mesh, plus an unreferenced vertex.
    let (mut p, mut t) = bumpy_sphere(2, 0.005);
    let (p2, t2) = bumpy_grid(12);
    for (pp, tt) in [(p.clone(), t.clone()), (p2, t2)] {
        let off = p.len() as u32;
        p.extend(pp.iter().map(|&x| x + DVec3::new(3.0, 0.0, 0.0)));
        t.extend(tt.iter().map(|f| f.map(|i| i + off)));
    }
    p.push(DVec3::new(-5.0, 0.0, 0.0));
    let (pm, pyr) = assert_reconstructs(&p, &t);
    assert_eq!(pyr.signal_len(), p.len());
    assert_eq!(pm.original_positions().len(), p.len());
}

#[test]
fn reconstruction_does_not_depend_on_the_presmoothing() {
    // The Burt–Adelson property: a signal that is not the geometry (a wild one) still
    // reconstructs exactly, although the weights come from the geometry.
    let (p, t) = bumpy_sphere(2, 0.0);
    let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
    let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
    let signal: Vec<DVec3> = (0..pm.original_positions().len())
        .map(|i| {
            DVec3::new(
                (i as f64 * 0.37).sin(),
                (i % 7) as f64,
                1.0 / (1.0 + i as f64),
            )
        })
        .collect();
    let pyr =
        DetailPyramid::analyze_signal(&pm, &SecondDifference::default(), &signal, &NoProgress)
            .unwrap();
    let out = pyr.synthesize(&LevelGains::unit());
    // Frames built from a wild signal are badly conditioned (tiny, twisted predicted fans), and
    // the closed loop bounds the error all the same.
    let err = max_dist(&out, &signal);
    assert!(err <= closed_loop_bound(&pyr), "{err:e}");
}

/// The bumpy grid with deterministic noise added to the heights, and the clean height function.
fn noisy_height_field(n: usize, amplitude: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let (mut p, t) = bumpy_grid(n);
    let mut state = 12345u64;
    for q in &mut p {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        q.z += amplitude * (((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5);
    }
    (p, t)
}

fn clean_height(q: DVec3) -> f64 {
    0.05 * (7.0 * q.x).sin() * (5.0 * q.y).cos()
}

#[test]
fn lowpass_removes_noise_and_gains_act_only_on_their_levels() {
    let (p, t) = noisy_height_field(40, 0.004);
    let (pm, pyr) = pyramid_of(&p, &t);
    // Height error against the clean surface at each vertex's own (x, y): a normal-direction
    // error that ignores the (free) tangential placement.
    let err = |x: &[DVec3]| {
        let s: f64 = x.iter().map(|q| (q.z - clean_height(*q)).powi(2)).sum();
        (s / x.len() as f64).sqrt()
    };
    let n = pyr.n_vertices();
    let low = pyr.synthesize(
        &Filter::default()
            .lowpass(LevelSpec::Vertices(n / 2))
            .resolve(1.0),
    );
    let (e0, e1) = (err(pm.original_positions()), err(&low));
    assert!(e1 < 0.6 * e0, "height error {e0} → {e1}");
    // Cutting far too low loses the bumps themselves: the filter really acts by level.
    let too_low = pyr.synthesize(
        &Filter::default()
            .lowpass(LevelSpec::Vertices(n / 16))
            .resolve(1.0),
    );
    assert!(err(&too_low) > 2.0 * e0);
    let everywhere = |_: DVec3| true;
    let (r0, r1) = (
        roughness(&pm, pm.original_positions(), everywhere),
        roughness(&pm, &low, everywhere),
    );
    assert!(r1 < 0.7 * r0, "roughness {r0} → {r1}");
    assert!(max_dist(&low, pm.original_positions()) < 0.02 * pyr.bbox_diagonal());

    // Enhancement makes it rougher; the levels below the band are untouched.
    let cut = n / 4;
    let band = Filter::default()
        .gain(LevelSpec::Vertices(cut), LevelSpec::Vertices(n), 2.0)
        .resolve(1.0);
    let enhanced = pyr.synthesize(&band);
    assert!(roughness(&pm, &enhanced, everywhere) > 1.5 * r0);
    let mut a = pyr.base_signal();
    let mut b = pyr.base_signal();
    pyr.synthesize_range(&mut a, pyr.n_base_vertices(), cut, &band);
    pyr.synthesize_range(&mut b, pyr.n_base_vertices(), cut, &LevelGains::unit());
    assert_eq!(a[..cut], b[..cut]);
}

/// Levels a filter removes take a shortcut in synthesis (no frames, the prediction alone):
/// it must give what a vanishing gain gives through the frames.
#[test]
fn removed_levels_give_what_a_vanishing_gain_gives() {
    let (p, t) = noisy_height_field(30, 0.004);
    let (_, pyr) = pyramid_of(&p, &t);
    let n = pyr.n_vertices();
    let diag = pyr.bbox_diagonal();
    let (a, b) = (LevelSpec::Vertices(n / 8), LevelSpec::Vertices(n / 2));
    for (removed, vanishing) in [
        (
            Filter::default().lowpass(a),
            Filter::default().gain(a, LevelSpec::Vertices(n), 1e-200),
        ),
        (
            Filter::default().stopband(a, b),
            Filter::default().gain(a, b, 1e-200),
        ),
    ] {
        let x = pyr.synthesize(&removed.resolve(1.0));
        let y = pyr.synthesize(&vanishing.resolve(1.0));
        assert!(max_dist(&x, &y) <= 1e-14 * diag, "{}", max_dist(&x, &y));
        // And the levels really were removed.
        assert!(max_dist(&x, &pyr.synthesize(&LevelGains::unit())) > 1e-4 * diag);
    }
}

#[test]
fn planar_linear_signal_has_no_details() {
    // Linear precision carried through the whole pyramid: on a flat mesh the prediction of
    // every split is exact up to the rounding of its weights to f32 (a fraction 1e-7 of the
    // stencil's extent), so every detail is a step or two at most and any filter returns the
    // input to within the details' quantisation.
    let (mut p, t) = bumpy_grid(15);
    for q in &mut p {
        q.z = 0.0;
    }
    let (pm, pyr) = pyramid_of(&p, &t);
    let largest = (0..pyr.n_splits())
        .flat_map(|k| pyr.split_details(k).1)
        .map(|d| d.length())
        .fold(0.0, f64::max);
    assert!(largest <= 2.0 * pyr.detail_step(), "{largest:e}");
    let low = pyr.synthesize(
        &Filter::default()
            .lowpass(LevelSpec::Vertices(0))
            .resolve(1.0),
    );
    let off = max_dist(&low, pm.original_positions());
    assert!(off < 1e-6 * pyr.bbox_diagonal(), "{off:e}");
}

/// Mean `|x_i − mean of its neighbours|` of a vector field over the vertices passing `keep`.
fn umbrella(pm: &ProgressiveMesh, x: &[DVec3], keep: impl Fn(DVec3) -> bool) -> f64 {
    let mesh = Mesh::from_triangles(pm.original_positions(), pm.finest_faces())
        .unwrap()
        .mesh;
    let (mut s, mut n) = (0.0, 0);
    for v in mesh.vertices() {
        let nb = mesh.neighbors(v);
        if nb.is_empty() || !keep(pm.original_positions()[v.slot()]) {
            continue;
        }
        let c: DVec3 = nb.iter().map(|u| x[u.slot()]).sum::<DVec3>() / nb.len() as f64;
        s += (x[v.slot()] - c).length();
        n += 1;
    }
    s / n as f64
}

#[test]
fn coarse_edit_moves_the_region_and_carries_the_details() {
    let (p, t) = noisy_height_field(30, 0.004);
    let (pm, pyr) = pyramid_of(&p, &t);
    let level = 80;
    // Grab the surface at the coarse vertex nearest the middle.
    let coarse = pyr.signal_at_level(level);
    let middle = DVec3::new(0.5, 0.5, 0.0);
    let centre = coarse[..level]
        .iter()
        .copied()
        .min_by(|a, b| (*a - middle).length().total_cmp(&(*b - middle).length()))
        .unwrap();
    // A gentle bend (slope ~0.15): the frames, and so the details, turn by ~9°, which adds
    // only ~15% of the noise to the displacement field.
    let lift = DVec3::new(0.0, 0.0, 0.05);
    let handle = MoveHandle {
        center: centre,
        displacement: lift,
        radius: 0.3,
    };
    let edited = pyr.edit(level, &[handle], &LevelGains::unit()).unwrap();
    let orig = pm.original_positions();
    let flat = |x: DVec3| DVec3::new(x.x, x.y, 0.0);
    let mut near = 0.0f64;
    let mut far = 0.0f64;
    for (x, y) in orig.iter().zip(&edited) {
        let d = (*y - *x).length();
        let r = (flat(*x) - flat(centre)).length();
        if r < 0.05 {
            near = near.max(d);
        } else if r > 0.7 {
            far = far.max(d);
        }
    }
    assert!(near > 0.5 * lift.z, "the handle region moves: {near}");
    // Predictions re-read neighbours at every finer level, so influence leaks a little beyond
    // the coarse support; far from the handle it is a fraction of a percent.
    assert!(far < 0.01 * lift.z, "far away almost nothing moves: {far}");
    // Details ride along: the displacement field of the edit is smooth — it does not contain
    // the noise (the details were re-added on top of the moved coarse surface, not lost or
    // left behind). Compare its umbrella with the noise's own.
    let region = |x: DVec3| (flat(x) - flat(centre)).length() < 0.3;
    let displacement: Vec<DVec3> = edited.iter().zip(orig).map(|(a, b)| *a - *b).collect();
    let noise: Vec<DVec3> = orig
        .iter()
        .map(|q| DVec3::new(0.0, 0.0, q.z - clean_height(*q)))
        .collect();
    let (u_edit, u_noise) = (
        umbrella(&pm, &displacement, region),
        umbrella(&pm, &noise, region),
    );
    assert!(
        u_edit < 0.5 * u_noise,
        "edit field {u_edit} vs noise {u_noise}"
    );
    // Without the details (coarse level only) the same comparison fails: the noise is gone.
    let smooth = pyr.synthesize(
        &Filter::default()
            .lowpass(LevelSpec::Vertices(level))
            .resolve(1.0),
    );
    let lost: Vec<DVec3> = smooth.iter().zip(orig).map(|(a, b)| *a - *b).collect();
    assert!(umbrella(&pm, &lost, region) > 0.8 * u_noise);

    assert_eq!(coarse.len(), pyr.signal_len());
    assert!(pyr.edit(0, &[handle], &LevelGains::unit()).is_err());
    let bad = MoveHandle {
        radius: 0.0,
        ..handle
    };
    assert!(pyr.edit(level, &[bad], &LevelGains::unit()).is_err());
}

/// A relaxation other than Guskov's drives the pyramid: unit gains reproduce the input exactly,
/// a low-pass still smooths, and the details differ from the second-difference pyramid's (the
/// operator really is used).
fn check_relaxation_drives_the_pyramid(op: &dyn meshpyr::relax::Relaxation, name: &str) {
    let (p, t) = noisy_height_field(30, 0.004);
    let mesh = Mesh::from_triangles(&p, &t).unwrap().mesh;
    let pm = ProgressiveMesh::build(&mesh, &PmOptions::default(), &NoProgress).unwrap();
    let pyr = DetailPyramid::analyze(&pm, op, &NoProgress).unwrap();
    assert_eq!(pyr.relaxation(), name);
    let out = pyr.synthesize(&LevelGains::unit());
    let err = max_dist(&out, pm.original_positions());
    assert!(err <= closed_loop_bound(&pyr), "{name}: {err:e}");
    let n = pyr.n_vertices();
    let low = pyr.synthesize(
        &Filter::default()
            .lowpass(LevelSpec::Vertices(n / 2))
            .resolve(1.0),
    );
    let everywhere = |_: DVec3| true;
    let (r0, r1) = (
        roughness(&pm, pm.original_positions(), everywhere),
        roughness(&pm, &low, everywhere),
    );
    assert!(r1 < 0.7 * r0, "{name}: roughness {r0} → {r1}");
    let (_, sd) = pyramid_of(&p, &t);
    assert!(!sd.split_details(0).1.eq(pyr.split_details(0).1), "{name}");
}

#[test]
fn mcm_relaxation_drives_the_pyramid() {
    // The MCM Jacobi step has a self weight; the pyramid starts each new vertex at its
    // survivor, so reconstruction stays exact.
    check_relaxation_drives_the_pyramid(&meshpyr::relax::MeanCurvatureStep::default(), "mcm");
}

#[test]
fn normal_adaptive_relaxation_drives_the_pyramid() {
    // A linear stencil without a self weight.
    check_relaxation_drives_the_pyramid(&meshpyr::relax::NormalAdaptive::default(), "normal");
}

#[test]
fn memory_is_compact_and_synthesis_deterministic() {
    let (p, t) = bumpy_sphere(3, 0.01);
    let (_, pyr) = pyramid_of(&p, &t);
    let per_vertex = pyr.memory_bytes() as f64 / pyr.n_vertices() as f64;
    // f64 weights (~10 per touched vertex) and details dominate; indices are 8-bit local
    // (the layout of ten parallel u32/f64 arrays before took about 1300 bytes per vertex).
    assert!(
        (300.0..1050.0).contains(&per_vertex),
        "{per_vertex} bytes/vertex"
    );
    let a = pyr.synthesize(&LevelGains::unit());
    let b = pyr.clone().synthesize(&LevelGains::unit());
    assert_eq!(a, b);
}

#[test]
fn analysis_gives_the_same_pyramid_on_any_thread_count() {
    // The records are cut into one range of splits per thread, each walked on its own (a flat
    // replay from the base for Guskov's operator, a half-edge cursor from the finest level
    // for the others), and large waves are downsampled in blocks on the pool; the pyramid
    // (storage order, base, every detail) must not depend on how many threads there are.
    let (p, t) = bumpy_sphere(4, 0.01);
    let (pm, _) = pyramid_of(&p, &t);
    // Two ranges of at least 1024 splits (the analysis' minimum) on 2 and 3 threads.
    assert!(pm.splits().len() >= 2 * 1024, "{}", pm.splits().len());
    let mcm = meshpyr::relax::MeanCurvatureStep::default();
    let second_difference = SecondDifference::default();
    let operators: [&dyn meshpyr::relax::Relaxation; 2] = [&second_difference, &mcm];
    for op in operators {
        let analyse = |threads: usize| {
            on_threads(threads, || DetailPyramid::analyze(&pm, op, &NoProgress)).unwrap()
        };
        let one = analyse(1);
        for threads in [2, 3] {
            let many = analyse(threads);
            let name = op.name();
            assert!(one.base() == many.base(), "{name}, {threads} threads: base");
            for k in 0..one.n_splits() {
                assert_eq!(
                    one.split_slot(k),
                    many.split_slot(k),
                    "{name}, {threads} threads"
                );
                assert!(
                    one.split_details(k).0 == many.split_details(k).0
                        && one.split_details(k).1.eq(many.split_details(k).1),
                    "{name}, {threads} threads: split {k}"
                );
            }
        }
    }
}

#[test]
fn parallel_synthesis_gives_the_bits_of_split_order() {
    // Synthesis runs waves of independent splits at once; split by split (one split per
    // call, which cannot reorder anything) must give the same bits, on 1 and 3 threads, for
    // the whole hierarchy and for a range starting mid-way (an edit's resynthesis).
    let (p, t) = bumpy_sphere(4, 0.01);
    let (_, pyr) = pyramid_of(&p, &t);
    assert!(pyr.n_splits() > 2000, "{}", pyr.n_splits());
    let gains = Filter::default()
        .gain(LevelSpec::Vertices(40), LevelSpec::Vertices(400), 2.0)
        .gain(LevelSpec::Vertices(1500), LevelSpec::Vertices(2200), 0.0)
        .resolve(pyr.surface_area());
    let (n0, n) = (pyr.n_base_vertices(), pyr.n_vertices());
    let one_by_one = |from: usize, f: &mut Vec<DVec3>| {
        for level in from..n {
            pyr.synthesize_range(f, level, level + 1, &gains);
        }
    };
    let mut reference = pyr.base_signal();
    one_by_one(n0, &mut reference);
    let mid = n0 + (n - n0) / 3;
    let mut partial_reference = pyr.signal_at_level(mid);
    one_by_one(mid, &mut partial_reference);
    for threads in [1, 3] {
        let (whole, partial) = on_threads(threads, || {
            let mut f = pyr.signal_at_level(mid);
            pyr.synthesize_range(&mut f, mid, n, &gains);
            (pyr.synthesize(&gains), f)
        });
        assert!(whole == reference, "{threads} threads");
        assert!(
            partial == partial_reference,
            "{threads} threads, from level {mid}"
        );
    }
}

#[test]
fn syntheses_running_side_by_side_on_the_pool_give_the_bits_of_one_thread() {
    // Each synthesis hands the waves to the pool's threads; when several run at once inside a
    // parallel loop, a synthesis may get no helper at all (the pool is busy with the others)
    // and must then run every block itself, with the same bits.
    let (p, t) = bumpy_sphere(4, 0.01);
    let (_, pyr) = pyramid_of(&p, &t);
    let gains: Vec<LevelGains> = (0..6)
        .map(|i| {
            Filter::default()
                .gain(
                    LevelSpec::Vertices(40 + 50 * i),
                    LevelSpec::Vertices(1500),
                    0.5 * i as f64,
                )
                .resolve(pyr.surface_area())
        })
        .collect();
    let expected: Vec<Vec<DVec3>> =
        on_threads(1, || gains.iter().map(|g| pyr.synthesize(g)).collect());
    let got: Vec<Vec<DVec3>> = on_threads(2, || {
        use rayon::prelude::*;
        gains.par_iter().map(|g| pyr.synthesize(g)).collect()
    });
    assert!(got == expected);
}

#[test]
fn band_warnings_name_bands_that_change_nothing_or_reach_below_the_base() {
    let (p, t) = bumpy_sphere(2, 0.01);
    let (_, pyramid) = pyramid_of(&p, &t);
    let (base, finest) = (pyramid.n_base_vertices(), pyramid.n_vertices());
    let inside = Filter::new().stopband(base + 1, finest - 1);
    assert!(pyramid.band_warnings(&inside).is_empty());
    let unit = Filter::new().gain(finest + 10, finest + 20, 1.0);
    assert!(pyramid.band_warnings(&unit).is_empty());
    let above = Filter::new().stopband(finest + 10, finest + 20);
    // Ends in either order are one band (sizes run the other way round); equal ends are empty.
    let empty = Filter::new().gain(30, 30, 2.0);
    let below = Filter::new().lowpass(base - 1);
    for (filter, says) in [
        (above, "changes nothing"),
        (empty, "is empty"),
        (below, "reaches below the pyramid's coarsest level"),
    ] {
        let warnings = pyramid.band_warnings(&filter);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains(says), "{warnings:?}");
    }
}

/// E_n of a low-pass of `name` to a quarter of its vertices against the mesh itself, with the
/// operator `kind`.
fn lowpass_normal_error(name: &str, kind: meshpyr::relax::RelaxKind) -> f64 {
    let input = meshpyr::io::read_mesh(common::data(name)).expect("readable");
    let options = meshpyr::PyramidOptions {
        relaxation: kind.spec(),
        ..Default::default()
    };
    let scan = meshpyr::Pyramid::build_with(input.clone(), &options, &NoProgress).expect("builds");
    let n = input.positions.len();
    let low = scan.filter(&Filter::default().lowpass(LevelSpec::Vertices(n / 4)));
    let mesh = |m: &meshpyr::PolygonMesh| Mesh::from_polygons(m).expect("valid").mesh;
    meshpyr::metrics::compare(&mesh(&low), &mesh(&input))
        .expect("comparable")
        .e_n
}

#[test]
fn normal_adaptive_low_passes_keep_cad_creases_better_than_guskovs() {
    use meshpyr::relax::RelaxKind;
    // The fandisk's creases are sharp: Guskov's operator rounds every one of them (its E_n is
    // several times the normal-adaptive one's); the cube has few creases against its faces.
    for (name, factor) in [("fandisk.ply", 0.3), ("cube_om.ply", 0.95)] {
        let guskov = lowpass_normal_error(name, RelaxKind::SecondDifference);
        let steered = lowpass_normal_error(name, RelaxKind::Normal);
        assert!(
            steered < factor * guskov,
            "{name}: E_n {steered} with the normal-adaptive operator, {guskov} with Guskov's"
        );
    }
}
