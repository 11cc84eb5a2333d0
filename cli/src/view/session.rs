//! The editor's state on the server: the pyramid, the synthesis cache behind the equalizer, the
//! level of detail of a scan larger than the display budget (with its background work), and
//! the last result a client asked for (what a bare `GET /api/export` exports).

use super::background::{Background, StateKey};
use super::layout::LayoutWait;
use super::preview::{self, Preview, PreviewTiming};
use super::state::{EditorState, ms_between};
use super::texture::ViewTexture;
use glam::DVec3;
use meshpyr::io::{MeshFormat, WriteOptions};
use meshpyr::mesh::PolygonMesh;
use meshpyr::pyramid::{Filter, LevelGains, Pyramid, Spectrum, SynthesisCache};
use serde_json::json;
use std::ops::RangeInclusive;
use std::sync::Arc;
use std::time::Instant;

/// Where the time of [`Session::positions_timed`] went, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Timing {
    /// Synthesis in PM order (resumed by the cache, or an edit's full synthesis).
    pub synthesis: f64,
    /// From PM order to the input's vertices and order.
    pub reorder: f64,
}

/// The level of detail of a scan over the display budget: the preview and the background work.
pub(crate) struct Lod {
    pub preview: Preview,
    /// The exact results and fine octaves; `None` while the whole pyramid is pending.
    background: Option<Background>,
    /// Number of the latest previewed state.
    version: u64,
    /// The latest previewed state, for the background once it starts.
    wanted: Option<(u64, StateKey)>,
}

/// A preview: positions of the shown vertices, the state's number, where the time went, and
/// whether every octave away from gain 1 is in it.
pub(crate) struct Previewed {
    pub positions: Vec<DVec3>,
    pub version: u64,
    pub timing: PreviewTiming,
    pub complete: bool,
}

pub(crate) struct Session {
    /// The scan and its pyramid: the whole pyramid, or while `layout` is pending the pyramid
    /// of the levels up to the previews' exact level ([`meshpyr::pyramid::Staged`]).
    pub pyramid: Arc<Pyramid>,
    /// The hierarchy's levels (those of the whole pyramid).
    pub levels: RangeInclusive<usize>,
    /// The spectrum, once asked for (or given with a staged pyramid).
    spectrum: Option<Spectrum>,
    /// The recording of the whole pyramid, while it is pending.
    layout: Option<LayoutWait>,
    /// Why the whole pyramid could not be made, if it could not.
    layout_failed: Option<String>,
    pub name: String,
    /// The octave bands `(lo, hi]`, one slider each.
    pub octaves: Vec<(usize, usize)>,
    cache: SynthesisCache,
    pub last: EditorState,
    /// The display budget in triangles.
    pub budget: usize,
    /// The level of detail, once made (only for scans over the budget).
    lod: Option<Lod>,
    /// The images and materials of a textured scan (`None` for an untextured one).
    pub texture: Option<ViewTexture>,
}

impl Session {
    pub fn new(pyramid: impl Into<Arc<Pyramid>>) -> Session {
        let pyramid = pyramid.into();
        let octaves = pyramid.pyramid.levels_of_octaves();
        Session::with_octaves(pyramid, octaves, None, None)
    }

    /// The session of a staged pyramid (`scan`: its first stage, `spectrum`: the whole
    /// pyramid's) whose whole pyramid `layout` records.
    pub fn staged(scan: Arc<Pyramid>, spectrum: Spectrum, layout: LayoutWait) -> Session {
        let octaves = spectrum.bands.iter().map(|b| (b.lo, b.hi)).collect();
        Session::with_octaves(scan, octaves, Some(spectrum), Some(layout))
    }

    fn with_octaves(
        pyramid: Arc<Pyramid>,
        octaves: Vec<(usize, usize)>,
        spectrum: Option<Spectrum>,
        layout: Option<LayoutWait>,
    ) -> Session {
        let cache = SynthesisCache::octaves(&pyramid.pyramid);
        let texture = ViewTexture::of(&pyramid.input);
        let last = EditorState {
            gains: vec![1.0; octaves.len()],
            ..Default::default()
        };
        Session {
            levels: preview::hierarchy_levels(&pyramid),
            pyramid,
            spectrum,
            layout,
            layout_failed: None,
            name: "mesh".into(),
            octaves,
            cache,
            last,
            budget: preview::DEFAULT_BUDGET,
            lod: None,
            texture,
        }
    }

    /// True when the finest level has more triangles than the budget: the page then shows a
    /// level of detail.
    pub fn over_budget(&self) -> bool {
        self.pyramid.pm.finest_faces().len() > self.budget
    }

    /// Changes the display budget; the level of detail is made again on next use (its
    /// background work stops).
    pub fn set_budget(&mut self, triangles: usize) {
        if triangles != self.budget {
            self.budget = triangles;
            self.lod = None;
        }
    }

    /// The level of detail (made on first use), or `None` for a scan within the budget. Its
    /// background work starts once the whole pyramid is in.
    pub fn lod(&mut self) -> Option<&mut Lod> {
        if self.lod.is_none() && self.over_budget() {
            let shown = preview::shown_level(&self.pyramid, self.budget);
            let preview = Preview::new(&self.pyramid, &self.octaves, shown);
            let background = self.whole().then(|| self.background_of(&preview));
            self.lod = Some(Lod {
                preview,
                background,
                version: 0,
                wanted: None,
            });
        }
        let lod = self.lod.as_mut()?;
        if let Some(background) = &lod.background {
            for (octave, d) in background.take_measured() {
                lod.preview.set_displacement(octave, d);
            }
        }
        Some(lod)
    }

    /// The background work of `preview`: exact results, and the fine octaves it misses.
    fn background_of(&self, preview: &Preview) -> Background {
        let octaves = preview
            .missing_octaves()
            .into_iter()
            .map(|i| (i, self.octaves[i].0, self.octaves[i].1))
            .collect();
        Background::start(Arc::clone(&self.pyramid), octaves, preview.shown)
    }

    /// True when the session has the whole pyramid (not a staged one's first stage).
    pub fn whole(&self) -> bool {
        self.layout.is_none() && self.layout_failed.is_none()
    }

    /// Why a call that needs the whole pyramid cannot be answered yet (it is being recorded,
    /// or could not be made); `None` when it can.
    pub fn pending(&self) -> Option<String> {
        if let Some(why) = &self.layout_failed {
            return Some(format!("the whole pyramid could not be made: {why}"));
        }
        let layout = self.layout.as_ref()?;
        Some(format!(
            "the whole pyramid is still being recorded ({:.0} % done; /api/status says when)",
            100.0 * layout.done()
        ))
    }

    /// The finest level the pyramid in hand synthesises: the finest, or a staged pyramid's
    /// first stage.
    pub fn synthesised_levels(&self) -> usize {
        self.pyramid.pyramid.n_vertices()
    }

    /// Swaps the whole pyramid in when its recording has ended, and starts the level of
    /// detail's background work with the latest previewed state. The previews stay: up to
    /// their exact level the first stage synthesises the whole pyramid's bits.
    pub fn poll_layout(&mut self) {
        let Some(result) = self.layout.as_ref().and_then(LayoutWait::take) else {
            return;
        };
        self.layout = None;
        let whole = match result {
            Ok(whole) => whole,
            Err(why) => {
                self.layout_failed = Some(why);
                return;
            }
        };
        let Some(scan) = Arc::get_mut(&mut self.pyramid) else {
            self.layout_failed = Some("internal error: the first stage is still in use".into());
            return;
        };
        scan.pyramid = whole;
        self.cache = SynthesisCache::octaves(&scan.pyramid);
        // A preview capped by the first stage is made again; the others stay.
        if let Some(mut lod) = self.lod.take() {
            if lod.preview.capped {
                let (version, wanted) = (lod.version, lod.wanted.take());
                if let Some(new) = self.lod() {
                    new.version = version;
                    if let (Some(b), Some((v, key))) = (&new.background, wanted) {
                        b.want(v, key);
                    }
                }
                return;
            }
            let background = self.background_of(&lod.preview);
            if let Some((version, key)) = lod.wanted.take() {
                background.want(version, key);
            }
            lod.background = Some(background);
            self.lod = Some(lod);
        }
    }

    /// The preview of `state` at the shown vertices; asks the background for its exact result
    /// and remembers `state` as the last result. `None` for a scan within the budget.
    pub fn preview(&mut self, state: EditorState) -> Option<Previewed> {
        let gains = self.gains_of(&state);
        let pyramid = Arc::clone(&self.pyramid);
        let lod = self.lod()?;
        let (positions, timing, complete) = lod.preview.positions(&pyramid, &state, &gains);
        lod.version += 1;
        let version = lod.version;
        let key = StateKey {
            gains,
            moves: state.moves.clone(),
        };
        match &lod.background {
            Some(background) => background.want(version, key),
            None => lod.wanted = Some((version, key)),
        }
        self.last = state;
        Some(Previewed {
            positions,
            version,
            timing,
            complete,
        })
    }

    /// The exact result's positions at the shown vertices (PM order) when the background has
    /// it for state number `version`.
    pub fn exact_shown(&mut self, version: u64) -> Option<Vec<DVec3>> {
        let lod = self.lod()?;
        let exact = lod
            .background
            .as_ref()?
            .exact()
            .filter(|e| e.version == version)?;
        Some(exact.signal[..lod.preview.shown].to_vec())
    }

    /// `/api/status`: the latest state's number, the exact result's, the fine octaves
    /// measured, and whether the whole pyramid is in.
    pub fn status(&mut self) -> serde_json::Value {
        let layout = self.layout_status();
        let Some(lod) = self.lod() else {
            return json!({"lod": false, "layout": layout});
        };
        let missing = lod.preview.missing_octaves();
        let (measured, total, busy, exact) = match &lod.background {
            Some(b) => {
                let (measured, total, busy) = b.progress();
                (measured, total, busy, b.exact().map(|e| e.version))
            }
            None => (0, missing.len(), None, None),
        };
        json!({
            "lod": true,
            "version": lod.version,
            "exact": exact,
            "octaves": {"measured": measured, "total": total, "missing": missing},
            "busy": busy,
            "layout": layout,
        })
    }

    /// `/api/status`'s `layout`: whether the whole pyramid is in, how far its recording is,
    /// and why it failed if it did.
    fn layout_status(&self) -> serde_json::Value {
        json!({
            "whole": self.whole(),
            "done": self.layout.as_ref().map_or(1.0, LayoutWait::done),
            "levels": self.synthesised_levels(),
            "error": self.layout_failed,
        })
    }

    /// The finest signal of `state` (PM order): the background's exact result when it has this
    /// state, else synthesised here, without the equalizer's cache.
    pub fn exact_signal(&mut self, state: &EditorState) -> Result<Arc<Vec<DVec3>>, String> {
        let gains = self.gains_of(state);
        if let Some(lod) = self.lod.as_ref()
            && let Some(exact) = lod.background.as_ref().and_then(Background::exact)
            && exact.key.gains == gains
            && exact.key.moves == state.moves
        {
            return Ok(exact.signal);
        }
        let p = &self.pyramid.pyramid;
        let signal = if state.moves.is_empty() {
            p.synthesize(&gains)
        } else {
            p.edit_levels(&state.moves, &gains)
                .map_err(|e| e.to_string())?
        };
        Ok(Arc::new(signal))
    }

    /// The filter the equalizer's gains stand for (bands at gain 1 left out).
    pub fn filter_of(&self, state: &EditorState) -> Filter {
        let mut filter = Filter::new();
        for (&(lo, hi), &g) in self.octaves.iter().zip(&state.gains) {
            if g != 1.0 {
                filter = filter.gain(lo, hi, g);
            }
        }
        filter.normal_only = state.normal_only;
        filter
    }

    fn gains_of(&self, state: &EditorState) -> LevelGains {
        self.filter_of(state)
            .resolve(self.pyramid.pyramid.surface_area())
    }

    /// The input's positions for `state` (what `meshpyr filter`/`edit` would write), and
    /// remembers `state` as the last result.
    pub fn positions(&mut self, state: EditorState) -> Result<Vec<DVec3>, String> {
        self.positions_timed(state).map(|(positions, _)| positions)
    }

    /// [`Session::positions`] and where its time went.
    pub fn positions_timed(&mut self, state: EditorState) -> Result<(Vec<DVec3>, Timing), String> {
        let start = Instant::now();
        let gains = self.gains_of(&state);
        let p = &self.pyramid.pyramid;
        let edited;
        let signal = if state.moves.is_empty() {
            self.cache.synthesize(p, &gains)
        } else {
            edited = p
                .edit_levels(&state.moves, &gains)
                .map_err(|e| e.to_string())?;
            &edited
        };
        let synthesized = Instant::now();
        let input_positions = self.pyramid.to_input_positions(signal);
        let timing = Timing {
            synthesis: ms_between(start, synthesized),
            reorder: ms_between(synthesized, Instant::now()),
        };
        self.last = state;
        Ok((input_positions, timing))
    }

    /// `/api/info`: counts, levels, octaves with feature sizes and energies, bounds.
    pub fn info(&mut self) -> serde_json::Value {
        self.lod();
        let pyramid = &self.pyramid;
        let spectrum = self.spectrum.get_or_insert_with(|| pyramid.spectrum());
        let octaves: Vec<_> = spectrum
            .bands
            .iter()
            .map(|b| json!({"from": b.lo, "to": b.hi, "feature_size": b.feature_size, "energy": b.energy}))
            .collect();
        let input = &self.pyramid.input;
        let (lo, hi) = input.positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let levels = self.levels.clone();
        let display = match &self.lod {
            Some(lod) => json!({
                "budget": self.budget, "lod": true, "shown": lod.preview.shown,
                "exact": lod.preview.exact, "triangles": lod.preview.triangles.len(),
            }),
            None => json!({"budget": self.budget, "lod": false, "shown": levels.end()}),
        };
        json!({
            "name": self.name,
            "vertices": input.n_vertices(),
            "triangles": input.n_triangles(),
            "levels": {"min": levels.start(), "max": levels.end()},
            "octaves": octaves,
            "bbox": {"min": lo.to_array(), "max": hi.to_array()},
            "diagonal": self.pyramid.pyramid.bbox_diagonal(),
            "area": self.pyramid.pyramid.surface_area(),
            "max_gain": super::limits::MAX_GAIN,
            "max_moves": super::limits::MAX_MOVES,
            "display": display,
            "texture": self.texture.as_ref().map(ViewTexture::info),
        })
    }

    /// `/api/faces`: the input's polygons as fan triangles, u32 triples.
    pub fn faces(&self) -> Vec<u8> {
        let input = &self.pyramid.input;
        let mut out = Vec::with_capacity(12 * input.n_triangles());
        for f in input.faces() {
            for k in 1..f.len().saturating_sub(1) {
                for i in [f[0], f[k], f[k + 1]] {
                    out.extend_from_slice(&i.to_le_bytes());
                }
            }
        }
        out
    }

    /// `/api/texcoords`: the drawing layout of a textured scan's texture coordinates
    /// ([`ViewTexture::layout`]) on the triangles the page shows: the input's, or over the
    /// budget the shown level's (its drawn vertices are then PM indices, as `/api/display`'s
    /// triangles), whose corners follow from the finest ones ([`Pyramid::level_mesh`]). With
    /// `level`, that of the scrubber's level `level` (`/api/level`'s triangles) instead.
    /// `None` for an untextured scan; an error when the hierarchy has no texture below the
    /// finest level (a partitioned build of a `.pyr` file written before it kept the seams) or
    /// a collapse breaks a seam.
    pub fn texcoords(&mut self, level: Option<usize>) -> Option<Result<Vec<u8>, String>> {
        self.texture.as_ref()?;
        let shown = match level {
            Some(n) => Some(n),
            None => self.lod().map(|lod| lod.preview.shown),
        };
        let texture = self.texture.as_ref()?;
        let Some(shown) = shown else {
            return Some(Ok(texture.layout(&self.pyramid.input)));
        };
        if !self.pyramid.pm.keeps_seams() {
            return Some(Err(format!(
                "the hierarchy was built without the texture seams: level {shown} has no \
                 texture coordinates"
            )));
        }
        Some(
            self.pyramid
                .level_mesh(shown)
                .map(|level| texture.layout(&level))
                .map_err(|e| e.to_string()),
        )
    }

    /// `/api/level`: vertex and triangle counts (u32), positions (f32 triples, PM order) and
    /// triangles (u32 triples) of the progressive mesh at `n` vertices.
    pub fn level(&self, n: usize) -> Vec<u8> {
        let signal = self.pyramid.pyramid.signal_at_level(n);
        let triangles = self.pyramid.pm.level_triangles(n);
        let mut out = Vec::with_capacity(8 + 12 * (n + triangles.len()));
        out.extend_from_slice(&(n as u32).to_le_bytes());
        out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
        push_f32_bytes(&mut out, &signal[..n]);
        push_u32_triples(&mut out, &triangles);
        out
    }

    /// `/api/display`: u32 vertex and triangle counts of the shown level, then its triangles
    /// (u32 triples, PM indices); `None` for a scan within the budget.
    pub fn display(&mut self) -> Option<Vec<u8>> {
        let preview = &self.lod()?.preview;
        let (shown, triangles) = (preview.shown, &preview.triangles);
        let mut out = Vec::with_capacity(8 + 12 * triangles.len());
        out.extend_from_slice(&(shown as u32).to_le_bytes());
        out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
        push_u32_triples(&mut out, triangles);
        Some(out)
    }

    /// A download of `state`'s result: `format` is `ply`, `obj` or `pyr`; returns the bytes and
    /// a file name.
    pub fn export(
        &mut self,
        state: EditorState,
        format: &str,
    ) -> Result<(Vec<u8>, String), String> {
        let positions = if self.over_budget() {
            let signal = self.exact_signal(&state)?;
            self.last = state;
            self.pyramid.to_input_positions(&signal)
        } else {
            self.positions(state)?
        };
        let bytes = match format {
            "pyr" => {
                self.pyramid
                    .to_pyr_bytes_with_positions(positions)
                    .map_err(|e| e.to_string())?
                    .0
            }
            "ply" => self.mesh_bytes(positions, MeshFormat::Ply)?,
            "obj" => self.mesh_bytes(positions, MeshFormat::Obj)?,
            other => return Err(format!("unknown export format {other:?} (ply, obj or pyr)")),
        };
        Ok((bytes, format!("{}-view.{format}", safe_stem(&self.name))))
    }

    /// The input with `positions` (stored normals following them); when the format cannot
    /// carry the input's other data (PLY properties in an OBJ, say), the geometry alone. A
    /// download may be saved in any folder, so its references to material libraries and
    /// images are absolute ([`meshpyr::io::write_mesh_bytes_detached`]).
    fn mesh_bytes(&self, positions: Vec<DVec3>, format: MeshFormat) -> Result<Vec<u8>, String> {
        let mut mesh = self.pyramid.input.clone();
        mesh.positions = positions;
        mesh.refresh_normals(&self.pyramid.input.positions);
        let opts = WriteOptions::default();
        meshpyr::io::write_mesh_bytes_detached(&mesh, format, &opts).or_else(|_| {
            let mut bare = PolygonMesh::new();
            bare.positions = mesh.positions;
            for f in self.pyramid.input.faces() {
                bare.push_face(f);
            }
            meshpyr::io::write_mesh_bytes(&bare, format, &opts).map_err(|e| e.to_string())
        })
    }
}

/// Appends `positions` to `out` as little-endian f32 triples.
pub(crate) fn push_f32_bytes(out: &mut Vec<u8>, positions: &[DVec3]) {
    out.reserve(12 * positions.len());
    for p in positions {
        for x in p.to_array() {
            out.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
}

/// Appends `triangles` to `out` as little-endian u32 triples.
pub(crate) fn push_u32_triples(out: &mut Vec<u8>, triangles: &[[u32; 3]]) {
    out.reserve(12 * triangles.len());
    for i in triangles.iter().flatten() {
        out.extend_from_slice(&i.to_le_bytes());
    }
}

/// The input's file stem reduced to characters safe in a header and a file name.
fn safe_stem(name: &str) -> String {
    let stem = std::path::Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh");
    let safe: String = stem
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || "-_.".contains(*c))
        .take(64)
        .collect();
    if safe.is_empty() { "mesh".into() } else { safe }
}
