//! `meshpyr.Pyramid`: a mesh with its progressive mesh and detail pyramid; filters, edits,
//! spectra, and the `.pyr` file as a file, as bytes and as a pickle.

use crate::arrays::{mesh_arrays, positions_array, triangles_array};
use crate::corners::corners_dict;
use crate::errors::{input_error, pyr_error, pyramid_error, value_error};
use crate::filters::FilterArgs;
use crate::functions::{mesh_pair, mesh_with_corners};
use glam::DVec3;
use meshpyr::pm::PmOptions;
use meshpyr::relax::RelaxKind;
use meshpyr::{MoveHandle, NoProgress, PyramidOptions};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyRange, PyTuple, PyType};
use std::ops::RangeInclusive;
use std::path::PathBuf;
use std::sync::Arc;

/// A mesh with its progressive mesh and Burt-Adelson detail pyramid (Guskov, Sweldens and
/// Schröder 1999): every level of the hierarchy keeps the details that the relaxation operator
/// fails to predict from the coarser level. Scaling the details per level gives low-pass,
/// stop-band and enhancement filters; moving a coarse level and resynthesising is a
/// multiresolution edit.
///
/// ``Pyramid(V, F, relax="second-difference")`` builds it; ``relax`` is the operator that
/// predicts each level from the coarser one: "second-difference" (Guskov's), "mcm" (one step
/// of implicit mean-curvature motion) or "normal" (second differences that stop at creases,
/// so low-passes keep sharp edges).
///
/// ``corners=C`` (the dict of ``read(path, corners=True)``) builds the hierarchy of a textured
/// scan as the command line does for its file: collapses keep the texture seams and weigh the
/// texture shift by ``uv_weight`` (as ``meshpyr build --uv-weight``), so filters give the
/// positions ``meshpyr filter`` writes, and ``level(n, corners=True)`` gives each level's
/// corners.
///
/// Every array it returns holds the input's vertices in the input's order. A Pyramid is
/// immutable, safe to share between threads, and pickles as its .pyr bytes (so
/// multiprocessing, Ray and Dask can ship it).
#[pyclass(module = "meshpyr", frozen)]
pub(crate) struct Pyramid {
    inner: Arc<meshpyr::Pyramid>,
}

impl Pyramid {
    /// The library's pyramid, shared (the notebook editor keeps it).
    pub(crate) fn shared(&self) -> Arc<meshpyr::Pyramid> {
        Arc::clone(&self.inner)
    }
}

/// Moves `[(point, delta), ...]` with one radius.
/// What ``to_bytes`` and ``save`` write.
fn content(details: bool) -> meshpyr::PyrContent {
    if details {
        meshpyr::PyrContent::WithDetails
    } else {
        meshpyr::PyrContent::HierarchyOnly
    }
}

fn move_handles(moves: &Bound<'_, PyAny>, radius: f64) -> PyResult<Vec<MoveHandle>> {
    let form = "moves must be a list of (point, delta) pairs of 3 numbers each";
    let mut handles = Vec::new();
    for (i, item) in moves.try_iter().map_err(|_| value_error(form))?.enumerate() {
        let (point, delta): (Vec<f64>, Vec<f64>) = item?
            .extract()
            .map_err(|_| value_error(format!("moves[{i}]: {form}")))?;
        let (Ok(point), Ok(delta)) = (<[f64; 3]>::try_from(point), <[f64; 3]>::try_from(delta))
        else {
            return Err(value_error(format!("moves[{i}]: {form}")));
        };
        let (center, displacement) = (DVec3::from_array(point), DVec3::from_array(delta));
        if !(center.is_finite() && displacement.is_finite()) {
            return Err(value_error(format!(
                "moves[{i}]: coordinates must be finite"
            )));
        }
        handles.push(MoveHandle {
            center,
            displacement,
            radius,
        });
    }
    if handles.is_empty() {
        return Err(value_error(
            "moves is empty: give at least one (point, delta) pair",
        ));
    }
    Ok(handles)
}

/// `n` as a level of `levels`, else a `ValueError` naming them.
pub(crate) fn level_in(n: i64, levels: &RangeInclusive<usize>) -> PyResult<usize> {
    match usize::try_from(n) {
        Ok(n) if levels.contains(&n) => Ok(n),
        _ => Err(value_error(format!(
            "level {n} is outside this mesh's levels {}..={}",
            levels.start(),
            levels.end()
        ))),
    }
}

/// `(V, F)` of `mesh`, with its corners dict when `corners` (as `read(path, corners=True)`).
pub(crate) fn mesh_tuple<'py>(
    py: Python<'py>,
    mesh: &meshpyr::PolygonMesh,
    corners: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let (v, f) = mesh_pair(py, mesh);
    let mut items = vec![v.into_any(), f.into_any()];
    if corners {
        items.push(corners_dict(py, mesh)?.into_any());
    }
    PyTuple::new(py, items)
}

#[pymethods]
impl Pyramid {
    #[new]
    #[pyo3(signature = (v, f, /, *, relax="second-difference", corners=None, uv_weight=PmOptions::default().uv_weight))]
    fn new(
        py: Python<'_>,
        v: &Bound<'_, PyAny>,
        f: &Bound<'_, PyAny>,
        relax: &str,
        corners: Option<&Bound<'_, PyAny>>,
        uv_weight: f64,
    ) -> PyResult<Self> {
        let kind: RelaxKind = relax.parse().map_err(input_error)?;
        let mesh = mesh_with_corners(v, f, corners)?;
        let options = PyramidOptions {
            relaxation: kind.spec(),
            pm: PmOptions {
                uv_weight,
                ..PmOptions::default()
            },
        };
        let inner = py
            .detach(|| meshpyr::Pyramid::build_with(mesh, &options, &NoProgress))
            .map_err(pyramid_error)?;
        Ok(Pyramid {
            inner: Arc::new(inner),
        })
    }

    /// The levels as vertex counts, ``range(base, finest + 1)``: from the coarsest mesh's
    /// vertex count to the (repaired) input's.
    #[getter]
    fn levels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyRange>> {
        let levels = self.inner.levels();
        PyRange::new(py, *levels.start() as isize, *levels.end() as isize + 1)
    }

    /// The input's vertex positions, float64 (n, 3), as given (or as stored in the .pyr file).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        positions_array(py, &self.inner.input.positions)
    }

    /// The input's triangles, int64 (m, 3) (polygons of a .pyr file built by the command line
    /// fan-triangulated from their first corner).
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let (_, f) = mesh_arrays(&self.inner.input);
        triangles_array(py, &f)
    }

    /// The input's corners dict (as ``read(path, corners=True)`` gives it): empty for a
    /// pyramid built without corners from an untextured mesh.
    #[getter]
    fn corners<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        corners_dict(py, &self.inner.input)
    }

    /// Level ``n`` (a vertex count in ``levels``) of the hierarchy at the input's positions,
    /// as ``(V_n, F_n)``, or with ``corners=True`` ``(V_n, F_n, C_n)``: C_n is the corners
    /// dict of the level, each triangle keeping the material and the texture coordinates of
    /// its vertices on its own side of every seam (empty for an untextured mesh). A pyramid
    /// whose hierarchy was built without the seams (a .pyr of a partitioned build) has no
    /// texture coordinates below the finest level.
    #[pyo3(signature = (n, /, *, corners=false))]
    fn level<'py>(&self, py: Python<'py>, n: i64, corners: bool) -> PyResult<Bound<'py, PyTuple>> {
        let levels = self.inner.levels();
        let n = level_in(n, &levels)?;
        let mesh = py
            .detach(|| self.inner.level_mesh(n))
            .map_err(|e| value_error(e.to_string()))?;
        mesh_tuple(py, &mesh, corners)
    }

    /// The relaxation operator's name: "second-difference", "mcm" or "normal".
    #[getter]
    fn relax(&self) -> &'static str {
        self.inner.options.relaxation.name()
    }

    /// The input with its details scaled per level: the same vertices in the same order with
    /// new positions, float64 (n, 3), the same bits as ``meshpyr filter`` writes.
    ///
    /// Levels are vertex counts (ints) or feature sizes in model units as strings with a
    /// ``u`` suffix ("0.02u"). ``lowpass=N`` zeroes the details of every level above N;
    /// ``stopband=[(a, b), ...]`` zeroes the levels in (a, b]; ``enhance=[(a, b, g), ...]`` and
    /// ``gains=[(a, b, g), ...]`` multiply them by g (gains of overlapping bands multiply);
    /// ``normal_only=True`` scales only the normal component of the details, so vertices do
    /// not drift sideways. At least one band is required. A band that selects none of the
    /// levels, or reaches below the coarsest, gives a UserWarning.
    #[pyo3(signature = (*, lowpass=None, stopband=None, enhance=None, gains=None, normal_only=false))]
    fn filter<'py>(
        &self,
        py: Python<'py>,
        lowpass: Option<&Bound<'py, PyAny>>,
        stopband: Option<&Bound<'py, PyAny>>,
        enhance: Option<&Bound<'py, PyAny>>,
        gains: Option<&Bound<'py, PyAny>>,
        normal_only: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let filter = FilterArgs {
            lowpass,
            stopband,
            enhance,
            gains,
            normal_only,
        }
        .filter()?;
        if filter.bands.is_empty() {
            return Err(value_error(
                "no filter given: use lowpass=N, stopband=[(a, b)], enhance=[(a, b, g)] or \
                 gains=[(a, b, g)]",
            ));
        }
        let filtered = py.detach(|| self.inner.filter_reporting(&filter));
        for warning in &filtered.warnings {
            crate::warn(py, warning)?;
        }
        Ok(positions_array(py, &filtered.mesh.positions))
    }

    /// A multiresolution edit, as ``meshpyr edit``: moves the vertices of level ``level`` (a
    /// vertex count in ``levels``; coarser levels give broader edits) near each point by its
    /// delta, with a smooth falloff over ``radius`` (model units), then resynthesises the
    /// finest level so that the details ride along. ``moves`` is a list of ``(point,
    /// delta)`` pairs of 3 numbers each. The filter keywords of ``filter`` apply while
    /// resynthesising. Returns the new positions, float64 (n, 3), in the input's order.
    #[pyo3(signature = (level, moves, radius, *, lowpass=None, stopband=None, enhance=None, gains=None, normal_only=false))]
    #[allow(clippy::too_many_arguments)]
    fn edit<'py>(
        &self,
        py: Python<'py>,
        level: i64,
        moves: &Bound<'py, PyAny>,
        radius: f64,
        lowpass: Option<&Bound<'py, PyAny>>,
        stopband: Option<&Bound<'py, PyAny>>,
        enhance: Option<&Bound<'py, PyAny>>,
        gains: Option<&Bound<'py, PyAny>>,
        normal_only: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(value_error(format!(
                "radius must be a positive number, got {radius}"
            )));
        }
        let level = level_in(level, &self.inner.levels())?;
        let handles = move_handles(moves, radius)?;
        let filter = FilterArgs {
            lowpass,
            stopband,
            enhance,
            gains,
            normal_only,
        }
        .filter()?;
        let edited = py
            .detach(|| self.inner.edit_reporting(level, &handles, &filter))
            .map_err(pyramid_error)?;
        for warning in &edited.warnings {
            crate::warn(py, warning)?;
        }
        // A move that reaches no vertex of the level changes nothing: say so, as the CLI does.
        for (handle, reach) in handles.iter().zip(&edited.reach) {
            if reach.points == 0 {
                let c = handle.center;
                crate::warn(
                    py,
                    &format!(
                        "the move at {},{},{} reaches no vertex of level {level} (the nearest is \
                         {:.6} away, the radius is {radius}); it changes nothing",
                        c.x, c.y, c.z, reach.nearest
                    ),
                )?;
            }
        }
        Ok(positions_array(py, &edited.mesh.positions))
    }

    /// The detail energy per band of levels (octaves of vertex counts), as ``meshpyr spectrum
    /// --csv``: a dict of equal-length numpy arrays ``lo`` and ``hi`` (each band covers the
    /// levels (lo, hi]), ``levels`` and ``details`` (counts in the band), ``energy`` (sum of
    /// squared detail lengths), ``rms`` and ``feature_size`` (typical edge length at ``hi``).
    fn spectrum<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let spectrum = py.detach(|| self.inner.spectrum());
        let bands = &spectrum.bands;
        let ints = |f: fn(&meshpyr::pyramid::BandEnergy) -> usize| {
            PyArray1::from_vec(py, bands.iter().map(|b| f(b) as i64).collect())
        };
        let floats = |f: fn(&meshpyr::pyramid::BandEnergy) -> f64| {
            PyArray1::from_vec(py, bands.iter().map(f).collect())
        };
        let dict = PyDict::new(py);
        dict.set_item("lo", ints(|b| b.lo))?;
        dict.set_item("hi", ints(|b| b.hi))?;
        dict.set_item("levels", ints(|b| b.levels))?;
        dict.set_item("details", ints(|b| b.details))?;
        dict.set_item("energy", floats(|b| b.energy))?;
        dict.set_item("rms", floats(|b| b.rms))?;
        dict.set_item("feature_size", floats(|b| b.feature_size))?;
        Ok(dict)
    }

    /// The .pyr file's bytes: the hierarchy with the exact input, the build options and
    /// (unless ``details=False``) the quantised details (compact, versioned, checksummed), the
    /// same bytes ``meshpyr build`` (``--no-details``) writes for the same input and relaxation.
    #[pyo3(signature = (*, details=true))]
    fn to_bytes<'py>(&self, py: Python<'py>, details: bool) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = py
            .detach(|| self.inner.to_pyr_bytes_as(content(details)))
            .map_err(|e| pyr_error(e.into()))?;
        Ok(PyBytes::new(py, &bytes.0))
    }

    /// Opens .pyr bytes (from ``to_bytes``, a file, or the network): the hierarchy as saved,
    /// with the stored details (the detail pass skipped, the relaxation weights computed;
    /// filters agree with the saved pyramid's to about 1e-10 of the bounding-box diagonal) or,
    /// without them, the pyramid recomputed bit-identical to the one that was saved. Raises
    /// FormatError for damaged or foreign bytes.
    #[classmethod]
    fn from_bytes(_cls: &Bound<'_, PyType>, py: Python<'_>, data: &[u8]) -> PyResult<Self> {
        let inner = py
            .detach(|| meshpyr::Pyramid::from_pyr_bytes(data, &NoProgress))
            .map_err(pyr_error)?;
        Ok(Pyramid {
            inner: Arc::new(inner),
        })
    }

    /// Saves the .pyr file at ``path`` (``to_bytes``), atomically (an existing file is replaced
    /// only once the new one is complete). Raises OSError when it cannot be written.
    #[pyo3(signature = (path, *, details=true))]
    fn save(&self, py: Python<'_>, path: PathBuf, details: bool) -> PyResult<()> {
        py.detach(|| self.inner.save_as(&path, content(details)))
            .map_err(pyr_error)
    }

    /// Opens the .pyr file at ``path`` (written by ``save`` or ``meshpyr build``), as
    /// ``from_bytes``. Raises OSError when it cannot be read,
    /// FormatError when it is damaged or not a .pyr file.
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = py
            .detach(|| meshpyr::Pyramid::load(&path))
            .map_err(pyr_error)?;
        Ok(Pyramid {
            inner: Arc::new(inner),
        })
    }

    /// Pickles as ``Pyramid.from_bytes(self.to_bytes(details=False))``: the unpickled pyramid
    /// recomputes its details, so its filters give the very bits of this one's.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let from_bytes = slf.get_type().getattr("from_bytes")?;
        let bytes = slf.get().to_bytes(py, false)?;
        PyTuple::new(py, [from_bytes, PyTuple::new(py, [bytes])?.into_any()])
    }

    fn __repr__(&self) -> String {
        let levels = self.inner.levels();
        format!(
            "<meshpyr.Pyramid: {} vertices, {} faces, levels {}..={}, relax={:?}>",
            self.inner.input.n_vertices(),
            self.inner.input.n_triangles(),
            levels.start(),
            levels.end(),
            self.relax()
        )
    }
}
