//! Level of detail for scans larger than the display budget: the page shows level `shown` of
//! the progressive mesh (the most vertices whose triangles fit the budget), its vertices where
//! the full-resolution result puts them, and a slider move computes only those vertices.
//!
//! The preview of a state splits the octaves at level `exact` (an octave start, at most
//! [`EXACT_LEVELS`]):
//!
//! * the coarse octaves are synthesised exactly, up to level `exact` only
//!   ([`SynthesisCache::up_to`]): their effect is far from linear in the gain, but they hold
//!   few splits;
//! * every shown vertex hangs off its ancestor at level `exact` (the vertex it collapses into):
//!   its offset from the ancestor's unit-gain position follows the local linear map of the
//!   coarse surface's change at the ancestor (fitted to the ancestor's edges and normal), so it
//!   rides along when the coarse surface bends, stretches or shrinks;
//! * each fine octave adds `(g − 1)` times its displacement at the shown vertices, measured
//!   once as the full-resolution result at unit gains minus the one with that octave at gain
//!   0 (in the background: [`super::background`]). Fine octaves' effect is nearly linear in
//!   the gain, and exactly so at gains 0 and 1.
//!
//! The exact full-resolution result is computed in the background and replaces the preview
//! when it arrives; exports use it.

use super::state::{EditorState, ms_between};
use glam::{DMat3, DVec3};
use meshpyr::pyramid::{LevelGains, LevelMove, MoveHandle, Pyramid, SynthesisCache};
use rayon::prelude::*;
use std::borrow::Cow;
use std::ops::RangeInclusive;

/// The finest level synthesised exactly at every move: the splits up to it take a few tens of
/// milliseconds on two cores.
pub const EXACT_LEVELS: usize = 32_768;

/// Default display budget in triangles: enough to show a scan's features on a screen of a few
/// million pixels, few enough to draw and to move quickly.
pub const DEFAULT_BUDGET: usize = 400_000;

/// The displacement of one fine octave at the shown vertices, once measured.
struct FineOctave {
    /// Index of the octave (its slider).
    octave: usize,
    displacement: Option<Vec<[f32; 3]>>,
}

/// The level-of-detail view of a scan and the data its previews combine (see the module docs).
pub(crate) struct Preview {
    /// The level shown (vertices `0..shown` in PM order).
    pub shown: usize,
    /// The level up to which previews synthesise exactly.
    pub exact: usize,
    /// Whether `exact` is lower than the whole pyramid's would be (made on a staged
    /// pyramid's first stage that ends below it).
    pub capped: bool,
    /// The triangles of level `shown`, PM indices.
    pub triangles: Vec<[u32; 3]>,
    exact_triangles: Vec<[u32; 3]>,
    /// Per shown vertex, its ancestor at level `exact`.
    anchor: Vec<u32>,
    /// `f^(exact)` at unit gains, and the normal equations' matrix of each vertex's fit
    /// (see [`local_maps`]), inverted.
    reference: Vec<DVec3>,
    reference_fits: Vec<DMat3>,
    /// Per shown vertex, its input position minus its ancestor's reference position.
    offsets: Vec<[f32; 3]>,
    /// Per shown vertex, the unit normal of level `shown` at the input positions.
    normals: Vec<[f32; 3]>,
    fine: Vec<FineOctave>,
    cache: SynthesisCache,
}

/// Where a preview's time went, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PreviewTiming {
    /// Exact synthesis of the coarse octaves up to level `exact`.
    pub synthesis: f64,
    /// Frames at level `exact` and the combination at the shown vertices.
    pub combine: f64,
}

/// The last octave start at most [`EXACT_LEVELS`] and `top` (at least the base level).
fn exact_level(octaves: &[(usize, usize)], levels: RangeInclusive<usize>, top: usize) -> usize {
    octaves
        .iter()
        .map(|o| o.0)
        .filter(|&lo| lo <= EXACT_LEVELS.min(top))
        .max()
        .unwrap_or(*levels.start())
        .max(*levels.start())
}

/// The most vertices whose level has at most `budget` triangles (at least the base level).
pub(crate) fn shown_level(pyramid: &Pyramid, budget: usize) -> usize {
    pyramid
        .pm
        .level_for_faces(budget)
        .min(*hierarchy_levels(pyramid).end())
}

impl Preview {
    /// The preview of `pyramid` at level `shown`, its octaves `octaves` (coarse to fine).
    /// `pyramid` may be a staged pyramid's first stage: it synthesises up to the exact level.
    pub fn new(pyramid: &Pyramid, octaves: &[(usize, usize)], shown: usize) -> Preview {
        let p = &pyramid.pyramid;
        let levels = hierarchy_levels(pyramid);
        let shown = shown.clamp(*levels.start(), *levels.end());
        // A staged pyramid's first stage synthesises up to its own finest level only.
        let exact = exact_level(octaves, levels.clone(), shown.min(p.n_vertices()));
        let capped = exact != exact_level(octaves, levels.clone(), shown);
        let pm = &pyramid.pm;
        let n0 = pm.n_base_vertices();
        let mut anchor: Vec<u32> = (0..shown as u32).collect();
        for x in exact..shown {
            anchor[x] = anchor[pm.splits()[x - n0].survivor as usize];
        }
        let mut cache = SynthesisCache::up_to(p, exact);
        let reference = cache.synthesize(p, &LevelGains::unit()).to_vec();
        let exact_triangles = pm.level_triangles(exact);
        let triangles = pm.level_triangles(shown);
        let reference_fits = edge_moments(&reference, &reference, &exact_triangles)
            .into_iter()
            .map(|m| {
                let inverse = m.inverse();
                if m.determinant().abs() > 0.0 && inverse.is_finite() {
                    inverse
                } else {
                    DMat3::ZERO
                }
            })
            .collect();
        let input = &pm.original_positions()[..shown];
        let offsets = input
            .iter()
            .zip(&anchor)
            .map(|(&x, &a)| f32s(x - reference[a as usize]))
            .collect();
        let normals = vertex_normals(input, &triangles)
            .into_iter()
            .map(f32s)
            .collect();
        let fine = octaves
            .iter()
            .enumerate()
            .filter(|(_, o)| o.0 >= exact)
            .map(|(octave, _)| FineOctave {
                octave,
                displacement: None,
            })
            .collect();
        Preview {
            shown,
            exact,
            capped,
            triangles,
            exact_triangles,
            anchor,
            reference,
            reference_fits,
            offsets,
            normals,
            fine,
            cache,
        }
    }

    /// The octaves whose displacements previews need and do not have yet, coarse to fine.
    pub fn missing_octaves(&self) -> Vec<usize> {
        self.fine
            .iter()
            .filter(|f| f.displacement.is_none())
            .map(|f| f.octave)
            .collect()
    }

    /// Takes in the measured displacement of octave `octave` at the shown vertices.
    pub fn set_displacement(&mut self, octave: usize, displacement: Vec<[f32; 3]>) {
        if let Some(f) = self.fine.iter_mut().find(|f| f.octave == octave)
            && displacement.len() == self.shown
        {
            f.displacement = Some(displacement);
        }
    }

    /// The preview of `state` at the shown vertices (PM order), where it went, and whether it
    /// is complete: false when a fine octave away from gain 1 has no displacement yet (it is
    /// then left out).
    pub fn positions(
        &mut self,
        pyramid: &Pyramid,
        state: &EditorState,
        gains: &LevelGains,
    ) -> (Vec<DVec3>, PreviewTiming, bool) {
        let start = std::time::Instant::now();
        let p = &pyramid.pyramid;
        let mut moves: Vec<&LevelMove> = state.moves.iter().collect();
        moves.sort_by_key(|m| m.level);
        let (coarse_moves, fine_moves) =
            moves.split_at(moves.partition_point(|m| m.level <= self.exact));
        let coarse: Cow<[DVec3]> = if coarse_moves.is_empty() {
            Cow::Borrowed(self.cache.synthesize(p, gains))
        } else {
            Cow::Owned(edited_prefix(pyramid, coarse_moves, gains, self.exact))
        };
        let synthesized = std::time::Instant::now();
        let turns = local_maps(
            &self.reference,
            &coarse,
            &self.reference_fits,
            &self.exact_triangles,
        );
        let mut complete = true;
        let mut active: Vec<(f64, &[[f32; 3]])> = Vec::new();
        for f in &self.fine {
            let g = state.gains[f.octave];
            match (&f.displacement, g != 1.0) {
                (Some(d), true) => active.push((g - 1.0, d)),
                (None, true) => complete = false,
                _ => {}
            }
        }
        let normal_only = state.normal_only;
        let mut out = vec![DVec3::ZERO; self.shown];
        out.par_chunks_mut(4096)
            .enumerate()
            .for_each(|(chunk, out)| {
                for (i, o) in out.iter_mut().enumerate() {
                    let v = chunk * 4096 + i;
                    let mut local = dvec(self.offsets[v]);
                    let n = dvec(self.normals[v]);
                    for &(g, d) in &active {
                        let d = dvec(d[v]);
                        local += g * if normal_only { d.dot(n) * n } else { d };
                    }
                    let a = self.anchor[v] as usize;
                    *o = coarse[a] + turns[a] * local;
                }
            });
        for m in fine_moves {
            MoveHandle::apply(std::slice::from_ref(&m.handle), &mut out);
        }
        let timing = PreviewTiming {
            synthesis: ms_between(start, synthesized),
            combine: ms_between(synthesized, std::time::Instant::now()),
        };
        (out, timing, complete)
    }
}

/// `f^(top)` on vertices `0..top` with `moves` (levels at most `top`, sorted) applied as
/// [`meshpyr::pyramid::DetailPyramid::edit_levels`] applies them.
fn edited_prefix(
    pyramid: &Pyramid,
    moves: &[&LevelMove],
    gains: &LevelGains,
    top: usize,
) -> Vec<DVec3> {
    let p = &pyramid.pyramid;
    let mut f = vec![DVec3::ZERO; top];
    f[..p.n_base_vertices()].copy_from_slice(p.base());
    let mut reached = p.n_base_vertices();
    for m in moves {
        p.synthesize_range(&mut f, reached, m.level, gains);
        reached = m.level;
        MoveHandle::apply(std::slice::from_ref(&m.handle), &mut f[..m.level]);
    }
    p.synthesize_range(&mut f, reached, top, gains);
    f
}

/// Unit area-weighted vertex normals of `positions` over `triangles` (zero where undefined).
pub(crate) fn vertex_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let area = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += area;
        }
    }
    for x in &mut n {
        *x = x.normalize_or_zero();
    }
    n
}

/// Per vertex, `Σ e' eᵀ` over its edges `e` in `before` and `e'` in `after` (both over
/// `triangles`), plus the same of its normals scaled by the edges' mean length: the two sides
/// of the least-squares fit of the linear map taking the one neighbourhood to the other.
fn edge_moments(before: &[DVec3], after: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DMat3> {
    let outer = |a: DVec3, b: DVec3| DMat3::from_cols(a * b.x, a * b.y, a * b.z);
    let mut m = vec![DMat3::ZERO; before.len()];
    let mut length = vec![(0.0f64, 0u32); before.len()];
    for t in triangles {
        for k in 0..3 {
            let a = t[k] as usize;
            for b in [t[(k + 1) % 3] as usize, t[(k + 2) % 3] as usize] {
                let e = before[b] - before[a];
                m[a] += outer(after[b] - after[a], e);
                length[a].0 += e.length();
                length[a].1 += 1;
            }
        }
    }
    let normals_before = vertex_normals(before, triangles);
    let normals_after = vertex_normals(after, triangles);
    for (i, m) in m.iter_mut().enumerate() {
        // The normal weighs as much as one mean edge: it fixes the map across the surface,
        // where the edges say nothing.
        let (sum, count) = length[i];
        let mean = if count > 0 {
            sum / f64::from(count)
        } else {
            0.0
        };
        let scale = mean * mean;
        *m += outer(normals_after[i], normals_before[i]) * scale;
    }
    m
}

/// Per vertex of `before`, the linear map that best takes its edges and normal to those in
/// `after` (`fits`: the inverted moments of `before` with itself, [`edge_moments`]); the
/// identity where the fit is undefined.
fn local_maps(
    before: &[DVec3],
    after: &[DVec3],
    fits: &[DMat3],
    triangles: &[[u32; 3]],
) -> Vec<DMat3> {
    edge_moments(before, after, triangles)
        .into_iter()
        .zip(fits)
        .map(|(m, &fit)| {
            let map = m * fit;
            if fit == DMat3::ZERO || !map.is_finite() {
                DMat3::IDENTITY
            } else {
                map
            }
        })
        .collect()
}

fn f32s(v: DVec3) -> [f32; 3] {
    v.to_array().map(|x| x as f32)
}

fn dvec(v: [f32; 3]) -> DVec3 {
    DVec3::new(v[0].into(), v[1].into(), v[2].into())
}

/// The hierarchy's levels, from the base to the finest: those of the whole pyramid, also
/// while a staged pyramid's first stage is in hand.
pub(crate) fn hierarchy_levels(pyramid: &Pyramid) -> RangeInclusive<usize> {
    pyramid.pm.n_base_vertices()..=pyramid.pm.n_vertices()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed octahedron.
    fn octahedron() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = vec![
            DVec3::X,
            DVec3::Y,
            -DVec3::X,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        let t = vec![
            [0, 1, 4],
            [1, 2, 4],
            [2, 3, 4],
            [3, 0, 4],
            [1, 0, 5],
            [2, 1, 5],
            [3, 2, 5],
            [0, 3, 5],
        ];
        (p, t)
    }

    #[test]
    fn local_maps_recover_a_rotation_and_stretch_of_the_whole_surface() {
        let (p, t) = octahedron();
        let map = DMat3::from_rotation_z(0.7) * DMat3::from_diagonal(DVec3::new(1.0, 1.0, 1.0));
        let moved: Vec<DVec3> = p.iter().map(|&x| map * x + DVec3::splat(3.0)).collect();
        let fits: Vec<DMat3> = edge_moments(&p, &p, &t)
            .iter()
            .map(|m| m.inverse())
            .collect();
        for m in local_maps(&p, &moved, &fits, &t) {
            assert!(
                (m - map).abs().to_cols_array().iter().all(|&x| x < 1e-12),
                "{m}"
            );
        }
        // A uniform scale maps normals to themselves while edges grow: the fit blends them.
        let grown: Vec<DVec3> = p.iter().map(|&x| 2.0 * x).collect();
        for (m, &x) in local_maps(&p, &grown, &fits, &t).iter().zip(&p) {
            assert!((*m * x - 2.0 * x).length() < 0.6, "{}", *m * x);
        }
        let unchanged = local_maps(&p, &p, &fits, &t);
        assert!(unchanged.iter().all(|m| {
            (*m - DMat3::IDENTITY)
                .abs()
                .to_cols_array()
                .iter()
                .all(|&x| x < 1e-12)
        }));
    }
}
