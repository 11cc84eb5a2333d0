//! # meshpyr
//!
//! Multiresolution editing of triangle meshes, built on a progressive-mesh hierarchy.
//!
//! The data flow:
//!
//! 1. A [`PolygonMesh`] is a mesh as a file holds it ([`read_mesh`], [`write_mesh`]: OBJ, PLY,
//!    OFF, STL, optionally gzipped).
//! 2. Its [`ProgressiveMesh`] is a hierarchy of quadric-error half-edge collapses whose vertex
//!    splits undo them exactly. [`simplify()`] cuts it at a face count, a ratio or an error.
//! 3. Its [`Pyramid`] keeps, for every level, the details that a relaxation operator fails to
//!    predict from the coarser level (Guskov, Sweldens and Schröder 1999). Scaling the details
//!    per level gives low-pass, stop-band and enhancement [`Filter`]s. Moving a coarse level
//!    and resynthesising is a multiresolution [edit](Pyramid::edit).
//! 4. A `.pyr` file ([`Pyramid::save`], [`Pyramid::load`]) keeps the hierarchy with the exact
//!    input and the pyramid's details (quantised, so a load skips the detail pass;
//!    [`PyrContent`] leaves them out), compact, versioned and checksummed.
//!    [`Pyramid::load_with`] chooses the relaxation and says whether the stored details were
//!    used.
//!
//! [`Pyramid::filter_reporting`] and [`Pyramid::edit_reporting`] give the same meshes with what
//! a user should be told: bands that change nothing, handles that reach no vertex.
//!
//! Every mesh a [`Pyramid`] returns is its input with new positions: the same vertices and
//! faces in the same order, and the same attributes.
//!
//! ## Quick start
//!
//! Low-pass a scan to its 500 coarsest levels:
//!
//! ```
//! use meshpyr::{Filter, Pyramid};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scan = meshpyr::read_mesh("tests/data/mc/mc_bunny_vox40.ply")?;
//! let pyramid = Pyramid::build(&scan)?;
//! let smooth = pyramid.filter(&Filter::new().lowpass(500));
//! meshpyr::write_mesh(std::env::temp_dir().join("bunny-lowpass.ply"), &smooth)?;
//! # assert_eq!(smooth.n_vertices(), scan.n_vertices());
//! # Ok(()) }
//! ```
//!
//! The other jobs, one line each, with `scan` and `pyramid` as above:
//!
//! ```
//! # use meshpyr::{Filter, MoveHandle, Pyramid, SimplifyTarget};
//! # use meshpyr::mesh::{Attribute, AttributeData};
//! # use glam::DVec3;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! # let scan = meshpyr::read_mesh("tests/data/mc/mc_bunny_vox40.ply")?;
//! # let pyramid = Pyramid::build(&scan)?;
//! # let dir = std::env::temp_dir();
//! // Simplify to 1 % of the triangles (or to the floor of the topology; `stop` says which).
//! let coarse = meshpyr::simplify(&scan, SimplifyTarget::Ratio(0.01), &Default::default(), &meshpyr::NoProgress)?;
//! // Enhance the details of levels 200 to 2000 twofold, normal components only.
//! let sharp = pyramid.filter(&Filter::new().gain(200, 2000, 2.0).normal_only());
//! // Pull level 200 up around a point; the finer details ride along.
//! let handle = MoveHandle { center: scan.positions[0], displacement: DVec3::Y * 0.01, radius: 0.05 };
//! let edited = pyramid.edit(200, &[handle], &Filter::new())?;
//! // The detail energy per band of levels.
//! let spectrum = pyramid.spectrum();
//! // Save the hierarchy with the exact input, and open it again.
//! pyramid.save(dir.join("bunny.pyr"))?;
//! let again = Pyramid::load(dir.join("bunny.pyr"))?;
//! // The same as bytes, to ship a pyramid between processes.
//! let (bytes, _sizes) = pyramid.to_pyr_bytes()?;
//! let shipped = Pyramid::from_pyr_bytes(&bytes, &meshpyr::NoProgress)?;
//! // Denoise, keeping creases (Ohtake, Belyaev and Seidel 2002).
//! let denoised = meshpyr::smooth_mesh(&scan, &meshpyr::SmoothMethod::default(), &meshpyr::NoProgress)?.mesh;
//! // Subdivide twice by cascadic mean-curvature motion (Diewald, Morigi and Rumpf 2001).
//! let fine = meshpyr::subdivide_mesh(&coarse.mesh, &meshpyr::SubdivOptions { levels: 2, ..Default::default() })?;
//! // How far the enhancement moved each vertex off the scan, and a picture coloured by it.
//! let reference = meshpyr::metrics::Reference::from_mesh(&meshpyr::mesh::Mesh::from_polygons(&scan)?.mesh)?;
//! let moved = meshpyr::metrics::vertex_distances(&sharp.positions, &reference);
//! let mut shown = sharp.clone();
//! shown.set_vertex_attribute(Attribute { name: "distance".into(), data: AttributeData::F64(moved) })?;
//! let options = meshpyr::RenderOptions { color_by: Some("distance".into()), ..Default::default() };
//! let png = meshpyr::render_meshes(&[("scan", &scan), ("enhanced", &shown)], &options)?.encode_png()?;
//! # assert!(coarse.mesh.n_faces() < scan.n_faces() && fine.n_faces() > coarse.mesh.n_faces());
//! # assert_eq!((sharp.n_vertices(), edited.n_vertices(), denoised.n_vertices()), (scan.n_vertices(), scan.n_vertices(), scan.n_vertices()));
//! # assert!(!spectrum.bands.is_empty() && again.levels() == pyramid.levels());
//! # assert!(png.starts_with(b"\x89PNG"));
//! # assert_eq!(shipped.filter(&Filter::new()).positions, again.filter(&Filter::new()).positions);
//! # Ok(()) }
//! ```
//!
//! ## Modules
//!
//! The front door above is re-exported here. The modules hold the rest, for callers who need
//! more control:
//!
//! | module | what it holds |
//! |---|---|
//! | [`choice`] | the named values of options, and the message for an unknown name |
//! | [`memory`] | whether a job fits in the memory this process may use, told before the work |
//! | [`mesh`] | the file-level [`PolygonMesh`], the half-edge [`mesh::Mesh`] and its repairs |
//! | [`io`] | the mesh file formats |
//! | [`pm`] | the progressive mesh, its levels (a textured scan's with their texture) and simplification |
//! | [`pyramid`] | the detail pyramid, filters, edits and spectra |
//! | [`relax`] | the relaxation operators that predict one level from the next |
//! | [`format`](mod@format) | the `.pyr` file |
//! | [`smooth`] | denoising and smoothing |
//! | [`subdiv`] | subdivision of coarse meshes |
//! | [`metrics`] | distances (summaries and per-vertex fields) and curvature |
//! | [`numerics`] | the finite elements and solvers that subdivision and smoothing share |
//! | [`render`] | PNG pictures of meshes, coloured by a per-vertex value if asked or by their texture |
//! | [`machine`] | the memory the machine offers this process (available, cgroup limit) |
//! | [`progress`] | progress reporting |
//! | [`wording`] | counts with their nouns, as messages show them |
//!
//! The `meshpyr` command line and its browser editor are a crate of their own (`cli/` in the
//! repository) that uses this library through the door above like any other caller. Without
//! default features (`meshpyr = { version = "…", default-features = false }`) the exact sparse
//! solver of subdivision is left out.
#![warn(missing_docs)]

pub mod choice;
pub(crate) mod fairing;
pub mod format;
#[doc(hidden)]
pub mod fuzzing;
pub mod io;
pub mod machine;
pub mod memory;
pub mod mesh;
pub mod metrics;
pub mod numerics;
pub mod pm;
pub mod progress;
pub mod pyramid;
pub mod relax;
pub mod render;
pub mod smooth;
pub mod subdiv;
pub mod wording;

pub use io::{read_mesh, write_mesh};
pub use mesh::{MeshInfo, PolygonMesh};
pub use pm::{ProgressiveMesh, Simplified, SimplifyTarget, simplify};
pub use progress::NoProgress;
pub use pyramid::{
    Filter, LevelMove, MoveHandle, PyrContent, PyrFileError, Pyramid, PyramidDenoise,
    PyramidOptions, Spectrum, StoredDetails, SynthesisCache,
};
pub use relax::RelaxationSpec;
pub use render::{
    RenderError, RenderOptions, Shading, Textures, View, render_mesh, render_meshes,
    render_textured_meshes,
};
pub use smooth::{DenoiseOptions, SmoothMethod, Smoothed, smooth_mesh};
pub use subdiv::{SubdivOptions, subdivide_mesh};
