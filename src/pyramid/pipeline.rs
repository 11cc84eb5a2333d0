//! File-level glue: a polygon mesh as read from a file → half-edge mesh (repaired) →
//! progressive mesh → detail pyramid, and back to a polygon mesh with **exactly the input's
//! vertices and faces in the same order** (attributes untouched), so per-vertex data still
//! lines up after filtering.

use super::{DetailPyramid, MoveHandle, PyramidError, Spectrum, StoredDetails};
use crate::fairing::{DenoiseOptions, denoise};
use crate::format::{self, FormatError, PyramidOptions, SizeReport};
use crate::io::IoError;
use crate::mesh::{Mesh, PolygonMesh, SourceMap};
use crate::pm::ProgressiveMesh;
use crate::progress::{NoProgress, Progress};
use crate::pyramid::Filter;
use crate::relax::{NormalAdaptive, Relaxation, RelaxationSpec};
use glam::DVec3;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

/// What a `.pyr` file keeps besides the hierarchy and the exact input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PyrContent {
    /// Also the pyramid's details, quantised (format 2.1, section `DETL`): the file opens
    /// without the detail pass, and its spectrum without any analysis.
    #[default]
    WithDetails,
    /// The hierarchy and the exact input only (as format 2.0): smaller; readers recompute the
    /// details.
    HierarchyOnly,
}

/// A scan with its progressive mesh and detail pyramid: the library's front door for
/// filtering, editing and saving (see the [crate docs](crate)).
///
/// Every mesh it returns is the input mesh with new positions: the same vertices and faces in
/// the same order, attributes untouched.
pub struct Pyramid {
    /// The mesh as read.
    pub input: PolygonMesh,
    /// Where each vertex of the repaired mesh came from in the input. The hierarchy is built
    /// from the builder's corner table: a half-edge mesh of the input is never made (filters
    /// never read it, and it is about 430 B per vertex).
    pub source: SourceMap,
    /// The hierarchy.
    pub pm: ProgressiveMesh,
    /// The pyramid of the input's positions. Filters, edits, spectra and saving go through
    /// the methods of `Pyramid` (with [`Pyramid::filter_reporting`] and
    /// [`Pyramid::edit_reporting`] for their warnings); the field is public for callers that
    /// work on the detail pyramid itself, such as the editor's server (a [`SynthesisCache`](super::SynthesisCache)
    /// over it, signals of intermediate levels).
    pub pyramid: DetailPyramid,
    /// What it was built with.
    pub options: PyramidOptions,
}

/// Why a `.pyr` file could not be saved or opened as a [`Pyramid`]. Errors of
/// [`Pyramid::load`] and [`Pyramid::save`] name the file.
#[derive(Debug, thiserror::Error)]
pub enum PyrFileError {
    /// Reading or writing the file failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The bytes are not a valid `.pyr` file, or the hierarchy cannot be encoded.
    #[error("{}{error}", file_prefix(path))]
    Format {
        /// The file, when there is one.
        path: Option<PathBuf>,
        /// What is wrong.
        error: FormatError,
    },
    /// The pyramid could not be rebuilt from the file's hierarchy.
    #[error("{}{error}", file_prefix(path))]
    Pyramid {
        /// The file, when there is one.
        path: Option<PathBuf>,
        /// What is wrong.
        error: PyramidError,
    },
}

fn file_prefix(path: &Option<PathBuf>) -> String {
    path.as_ref()
        .map(|p| format!("{}: ", p.display()))
        .unwrap_or_default()
}

impl PyrFileError {
    pub(super) fn in_file(self, file: &Path) -> PyrFileError {
        match self {
            PyrFileError::Format { error, .. } => PyrFileError::Format {
                path: Some(file.to_path_buf()),
                error,
            },
            PyrFileError::Pyramid { error, .. } => PyrFileError::Pyramid {
                path: Some(file.to_path_buf()),
                error,
            },
            io => io,
        }
    }
}

impl From<FormatError> for PyrFileError {
    fn from(error: FormatError) -> Self {
        PyrFileError::Format { path: None, error }
    }
}

impl From<PyramidError> for PyrFileError {
    fn from(error: PyramidError) -> Self {
        PyrFileError::Pyramid { path: None, error }
    }
}

impl Pyramid {
    /// The pyramid of `input` with the default options: the progressive mesh collapsed as far
    /// as legal, details predicted with Guskov's second differences.
    pub fn build(input: &PolygonMesh) -> Result<Pyramid, PyramidError> {
        Pyramid::build_with(input.clone(), &PyramidOptions::default(), &NoProgress)
    }

    /// Builds everything with `options`; `progress` runs 0 → 0.5 for the PM and 0.5 → 1 for
    /// the analysis.
    pub fn build_with(
        input: PolygonMesh,
        options: &PyramidOptions,
        progress: &dyn Progress,
    ) -> Result<Pyramid, PyramidError> {
        Pyramid::build_staged(input, options, progress, &mut |_| {})
    }

    /// [`Self::build_with`], handing the progressive mesh to `hierarchy_built` as soon as it
    /// is made, before the analysis that takes most of the rest: a viewer can show the
    /// hierarchy's levels (at the input's positions) while the details are computed.
    pub fn build_staged(
        input: PolygonMesh,
        options: &PyramidOptions,
        progress: &dyn Progress,
        hierarchy_built: &mut dyn FnMut(&ProgressiveMesh),
    ) -> Result<Pyramid, PyramidError> {
        input.check_surface()?;
        let (pm, source) = ProgressiveMesh::from_polygons(&input, &options.pm, &|x: f64| {
            progress.update(0.5 * x)
        })?;
        hierarchy_built(&pm);
        let (_, pyramid) = analyze_with(&options.relaxation, &pm, &|x: f64| {
            progress.update(0.5 + 0.5 * x)
        })?;
        Ok(Pyramid {
            input,
            source,
            pm,
            pyramid,
            options: options.clone(),
        })
    }

    /// The levels, as vertex counts: from the base mesh's to the input's (repaired) vertices.
    pub fn levels(&self) -> RangeInclusive<usize> {
        self.pyramid.n_base_vertices()..=self.pyramid.n_vertices()
    }

    /// Level `level` (clamped to [`Self::levels`]) of the hierarchy at the input's positions,
    /// with its per-vertex attributes, its faces' attributes, materials and groups and, for a
    /// textured input, its corners' texture coordinates and other per-corner data, each face
    /// keeping one chart (`crate::pm::level_mesh`; a `.pyr` file of this pyramid gives the same
    /// mesh through [`format::PyrData::level_mesh`]).
    pub fn level_mesh(&self, level: usize) -> Result<PolygonMesh, crate::pm::SeamBreak> {
        crate::pm::level_mesh(&self.pm, &self.input, &self.source, level)
    }

    /// The input with `filter` applied to its details (unit gains give the input back
    /// exactly; synthesis with them would be within `√3/2` of a detail step, about 4e-7 of the
    /// bounding-box diagonal, because details are quantised). Bands beyond the levels act on
    /// the levels they cover.
    pub fn filter(&self, filter: &Filter) -> PolygonMesh {
        let gains = filter.resolve(self.pyramid.surface_area());
        if gains.is_unit() {
            return self.input.clone();
        }
        self.output_mesh(&self.pyramid.synthesize(&gains))
    }

    /// A multiresolution edit: moves the vertices of level `level` by `handles` (each with a
    /// smooth falloff over its radius), then resynthesises the finest level with `filter`'s
    /// gains, so the details ride along in their local frames.
    pub fn edit(
        &self,
        level: usize,
        handles: &[MoveHandle],
        filter: &Filter,
    ) -> Result<PolygonMesh, PyramidError> {
        Ok(self.edit_reporting(level, handles, filter)?.mesh)
    }

    /// The detail energy per band of levels.
    pub fn spectrum(&self) -> Spectrum {
        self.pyramid.spectrum()
    }

    /// The `.pyr` file of this pyramid: its hierarchy with the exact input, the options to
    /// rebuild it and its details (formats/pyr.md), with its size by section.
    pub fn to_pyr_bytes(&self) -> Result<(Vec<u8>, SizeReport), FormatError> {
        self.to_pyr_bytes_as(PyrContent::WithDetails)
    }

    /// [`Self::to_pyr_bytes`], with or without the details.
    pub fn to_pyr_bytes_as(
        &self,
        content: PyrContent,
    ) -> Result<(Vec<u8>, SizeReport), FormatError> {
        let encoded = self.encode_as(content)?;
        let sizes = encoded.sizes;
        Ok((encoded.into_bytes(), sizes))
    }

    /// [`Self::encode_as`], consuming the pyramid: its details are coded first and the
    /// detail pyramid dropped before the hierarchy is encoded (whose replay is most of the
    /// encoder's memory), so that saving a large scan's pyramid peaks no higher than making
    /// it. Gives the hierarchy back with the file.
    pub fn into_encoded(
        self,
        content: PyrContent,
    ) -> Result<(format::EncodedPyr, ProgressiveMesh), FormatError> {
        let Pyramid {
            input,
            pm,
            pyramid,
            options,
            ..
        } = self;
        let details = (content == PyrContent::WithDetails)
            .then(|| StoredDetails::of(&pyramid, options.relaxation));
        drop(pyramid);
        let encoded = format::encode_sections(&input, &pm, &options, details.as_ref())?;
        Ok((encoded, pm))
    }

    /// The `.pyr` file of this pyramid, with or without the details, section by section:
    /// [`format::EncodedPyr::write_to`] writes it without gathering it in memory.
    pub fn encode_as(&self, content: PyrContent) -> Result<format::EncodedPyr, FormatError> {
        let details = (content == PyrContent::WithDetails)
            .then(|| StoredDetails::of(&self.pyramid, self.options.relaxation));
        format::encode_sections(&self.input, &self.pm, &self.options, details.as_ref())
    }

    /// The `.pyr` file of an edit: this hierarchy and options with `positions` (one per input
    /// vertex, as [`Pyramid::to_input_positions`] gives them) as its new original positions,
    /// with their details (analysed here).
    pub fn to_pyr_bytes_with_positions(
        &self,
        positions: Vec<DVec3>,
    ) -> Result<(Vec<u8>, SizeReport), PyrFileError> {
        self.to_pyr_bytes_with_positions_as(positions, PyrContent::WithDetails)
    }

    /// [`Self::to_pyr_bytes_with_positions`], with or without the details (which take an
    /// analysis of the new positions).
    pub fn to_pyr_bytes_with_positions_as(
        &self,
        positions: Vec<DVec3>,
        content: PyrContent,
    ) -> Result<(Vec<u8>, SizeReport), PyrFileError> {
        let (input, pm) = format::with_positions(&self.input, &self.source, &self.pm, positions)?;
        let details = match content {
            PyrContent::WithDetails => {
                let (_, pyramid) = analyze_with(&self.options.relaxation, &pm, &NoProgress)?;
                Some(StoredDetails::of(&pyramid, self.options.relaxation))
            }
            PyrContent::HierarchyOnly => None,
        };
        Ok(format::encode_with_details(
            &input,
            &pm,
            &self.options,
            details.as_ref(),
        )?)
    }

    /// Opens a `.pyr` file's bytes: the hierarchy as saved, and the pyramid with the file's
    /// details (only the relaxation weights and fans computed) or, for a file without usable
    /// ones, recomputed bit-identical to the one that was saved.
    pub fn from_pyr_bytes(bytes: &[u8], progress: &dyn Progress) -> Result<Self, PyrFileError> {
        Ok(Self::from_pyr_bytes_with(bytes, None, progress)?.0)
    }

    /// Saves [`Self::to_pyr_bytes`] to `path`, atomically (an existing file is replaced only
    /// once the new one is complete).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), PyrFileError> {
        self.save_as(path, PyrContent::WithDetails)
    }

    /// [`Self::save`], with or without the details.
    pub fn save_as(&self, path: impl AsRef<Path>, content: PyrContent) -> Result<(), PyrFileError> {
        let path = path.as_ref();
        let encoded = self
            .encode_as(content)
            .map_err(|e| PyrFileError::from(e).in_file(path))?;
        crate::io::write_atomic_with(path, |w| encoded.write_to(w))?;
        Ok(())
    }

    /// Opens the `.pyr` file at `path` ([`Self::from_pyr_bytes`]; [`Self::load_with`] chooses
    /// the relaxation and says whether the stored details were used).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, PyrFileError> {
        Ok(Self::load_with(path, None, &NoProgress)?.0)
    }

    /// Maps a signal in PM order onto the input's vertices (split copies averaged, vertices
    /// outside the hierarchy keep their input positions): the positions [`Pyramid::filter`]
    /// writes, without copying the rest of the mesh.
    pub fn to_input_positions(&self, pm_signal: &[DVec3]) -> Vec<DVec3> {
        input_positions(&self.pm, &self.source, pm_signal, &self.input.positions)
    }

    /// The input mesh with its positions replaced by `pm_signal` (PM order), its stored
    /// normals recomputed where the surface moved ([`PolygonMesh::refresh_normals`]).
    pub fn output_mesh(&self, pm_signal: &[DVec3]) -> PolygonMesh {
        let mut out = self.input.clone();
        out.positions = self.to_input_positions(pm_signal);
        out.refresh_normals(&self.input.positions);
        out
    }

    /// [`Self::output_mesh`], consuming the pyramid: the input's arrays become the output's,
    /// and the hierarchy and details are freed before the positions are mapped, so the peak
    /// of a one-shot filter does not hold a copy of the input beside them.
    pub fn into_output_mesh(self, pm_signal: &[DVec3]) -> PolygonMesh {
        let Pyramid {
            mut input,
            source,
            pm,
            pyramid,
            ..
        } = self;
        drop(pyramid);
        let moved = input_positions(&pm, &source, pm_signal, &input.positions);
        let before = std::mem::replace(&mut input.positions, moved);
        input.refresh_normals(&before);
        input
    }

    /// The input's positions and triangles (the repaired mesh) for previews and metrics.
    pub fn triangles(&self, pm_signal: &[DVec3]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let n = pm_signal.len().min(self.pm.original_positions().len());
        (pm_signal[..n].to_vec(), self.pm.finest_faces().to_vec())
    }
}

/// [`Pyramid::to_input_positions`] from the parts it reads.
fn input_positions(
    pm: &ProgressiveMesh,
    source: &SourceMap,
    pm_signal: &[DVec3],
    input: &[DVec3],
) -> Vec<DVec3> {
    // The PM covers every vertex of the repaired mesh (`pm_to_mesh` is a permutation of its
    // slots), and its original positions are the mesh's; entries `pm_signal` lacks keep them.
    let original = pm.original_positions();
    let mut mesh_values = vec![DVec3::ZERO; source.vertex_source.len()];
    for (i, &slot) in pm.pm_to_mesh().iter().enumerate() {
        if let Some(m) = mesh_values.get_mut(slot as usize) {
            *m = pm_signal.get(i).copied().unwrap_or(original[i]);
        }
    }
    source.to_input_positions(&mesh_values, input)
}

/// The operator `spec` names, ready to analyse `pm`: the normal-adaptive operator takes its
/// normals from the finest level denoised by Ohtake's filter with its automatic preset (what
/// `smooth --method auto` runs today; it keeps creases and removes the noise that would steer
/// the operator at random; `relax::normal_adaptive`).
/// Deterministic, so a `.pyr` loader rebuilds the same operator from the stored input.
/// `progress` goes 0 → 1 while the guide is made (see [`guide_share`]).
pub(crate) fn relaxation_for(
    spec: &RelaxationSpec,
    pm: &ProgressiveMesh,
    progress: &dyn Progress,
) -> Box<dyn Relaxation> {
    match *spec {
        RelaxationSpec::NormalAdaptive {
            normal_scale,
            degenerate_area_ratio,
        } => {
            let op = NormalAdaptive {
                normal_scale,
                degenerate_area_ratio,
                ..NormalAdaptive::default()
            };
            Box::new(match denoised_guide(pm, progress) {
                Some(guide) => op.with_guide(guide),
                None => op,
            })
        }
        _ => spec.operator(),
    }
}

/// The operator `spec` names for `pm` ([`relaxation_for`]) and the analysis of `pm`'s original
/// positions with it; `progress` goes 0 → 1 over both (the guide takes [`guide_share`]).
pub(crate) fn analyze_with(
    spec: &RelaxationSpec,
    pm: &ProgressiveMesh,
    progress: &dyn Progress,
) -> Result<(Box<dyn Relaxation>, DetailPyramid), PyramidError> {
    let share = guide_share(spec);
    let op = relaxation_for(spec, pm, &|x: f64| progress.update(share * x));
    let pyramid = DetailPyramid::analyze(pm, op.as_ref(), &|x: f64| {
        progress.update(share + (1.0 - share) * x)
    })?;
    Ok((op, pyramid))
}

/// The share of a progress bar that [`relaxation_for`] takes before the analysis, so the bar
/// moves while the guide is made: smoothing the finest level costs about what analysing it
/// does.
pub(crate) fn guide_share(spec: &RelaxationSpec) -> f64 {
    match spec {
        RelaxationSpec::NormalAdaptive { .. } => 0.4,
        _ => 0.0,
    }
}

/// The PM's vertices (in PM order) at their positions after Ohtake's filter with its
/// automatic preset ([`DenoiseOptions::automatic`]) on the finest level, its neighbourhoods
/// reaching the kernel's whole 4σ support; vertices without faces keep theirs. `None` when the
/// smoother refuses the mesh, and the operator then reads the normals of the positions
/// themselves.
fn denoised_guide(pm: &ProgressiveMesh, progress: &dyn Progress) -> Option<Vec<DVec3>> {
    let positions = pm.original_positions();
    let built = Mesh::from_triangles(positions, pm.finest_faces()).ok()?;
    // The whole support, not the preset's faster 3σ cut: the normal operator and
    // `smooth --method pyramid` were tuned and measured on this guide, and the 3σ guide moves
    // the pyramid denoiser's noise estimate off its finest octave.
    let options = DenoiseOptions {
        reach: 4.0,
        ..DenoiseOptions::automatic()
    };
    let smoothed = denoise(&built.mesh, &options, progress).ok()?;
    let mut guide = positions.to_vec();
    for (&source, &p) in built.source.vertex_source.iter().zip(&smoothed.positions) {
        if let Some(g) = guide.get_mut(source as usize) {
            *g = p;
        }
    }
    Some(guide)
}
