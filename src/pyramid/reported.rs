//! Front-door results that carry what a caller should tell its user: the warnings of a
//! filter's bands, what each handle of an edit reached, and where a loaded file's details came
//! from. The command line and the Python package report from these instead of reaching into
//! the [`DetailPyramid`](super::DetailPyramid).

use super::pipeline::PyrFileError;
use super::{DetailSource, Filter, HandleReach, MoveHandle, Pyramid, PyramidError};
use crate::format::{self, PyrData};
use crate::io::IoError;
use crate::mesh::PolygonMesh;
use crate::progress::Progress;
use crate::relax::RelaxationSpec;
use std::path::Path;

/// What [`Pyramid::filter_reporting`] returns.
#[derive(Clone, Debug)]
pub struct Filtered {
    /// The input with the filter applied, as [`Pyramid::filter`] gives it.
    pub mesh: PolygonMesh,
    /// One sentence per band that changes nothing or less than it says
    /// ([`Pyramid::band_warnings`]).
    pub warnings: Vec<String>,
}

/// What [`Pyramid::edit_reporting`] returns.
#[derive(Clone, Debug)]
pub struct Edited {
    /// The input with the edit applied, as [`Pyramid::edit`] gives it.
    pub mesh: PolygonMesh,
    /// Per handle, in the order given, what it reached on the edited level: a handle that
    /// reaches no vertex changes nothing.
    pub reach: Vec<HandleReach>,
    /// The warnings of the filter applied while resynthesising ([`Pyramid::band_warnings`]).
    pub warnings: Vec<String>,
}

impl Pyramid {
    /// One sentence per band of `filter` that changes nothing on this pyramid (empty, or
    /// outside its levels) or less than it says (partly outside them). Below a textured scan's
    /// base it names the seam floor (`docs/seams.md`).
    pub fn band_warnings(&self, filter: &Filter) -> Vec<String> {
        let floor = if self.pm.keeps_seams() {
            "the seam floor: vertices where texture seams meet or end on a boundary never move, \
             docs/seams.md"
        } else {
            "no legal collapse goes further"
        };
        self.pyramid.band_warnings_below(filter, floor)
    }

    /// [`Pyramid::filter`], with the warnings of `filter`'s bands.
    pub fn filter_reporting(&self, filter: &Filter) -> Filtered {
        Filtered {
            warnings: self.band_warnings(filter),
            mesh: self.filter(filter),
        }
    }

    /// [`Self::filter_reporting`], consuming the pyramid: the hierarchy and details are freed
    /// before the output is made from the input's own arrays (see
    /// [`Pyramid::into_output_mesh`]), so a one-shot filter's peak holds no second copy.
    pub fn into_filtered(self, filter: &Filter) -> Filtered {
        let warnings = self.band_warnings(filter);
        let gains = filter.resolve(self.pyramid.surface_area());
        let mesh = if gains.is_unit() {
            self.input
        } else {
            let signal = self.pyramid.synthesize(&gains);
            self.into_output_mesh(&signal)
        };
        Filtered { mesh, warnings }
    }

    /// [`Pyramid::edit`], with what each handle reached on level `level` and the warnings of
    /// `filter`'s bands.
    pub fn edit_reporting(
        &self,
        level: usize,
        handles: &[MoveHandle],
        filter: &Filter,
    ) -> Result<Edited, PyramidError> {
        let gains = filter.resolve(self.pyramid.surface_area());
        let (signal, reach) = self.pyramid.edit_reporting(level, handles, &gains)?;
        Ok(Edited {
            mesh: self.output_mesh(&signal),
            reach,
            warnings: self.band_warnings(filter),
        })
    }

    /// [`Pyramid::from_pyr_bytes`] with the relaxation `relaxation` (default: the file's): the
    /// file's stored details are used only when they were analysed with it, and the result
    /// says whether they were. `progress` goes 0 → 1 over the weights and fans (and the
    /// analysis when it runs).
    pub fn from_pyr_bytes_with(
        bytes: &[u8],
        relaxation: Option<RelaxationSpec>,
        progress: &dyn Progress,
    ) -> Result<(Pyramid, DetailSource), PyrFileError> {
        let data: PyrData = format::decode(bytes)?;
        Ok(data.into_pyramid_with(relaxation, progress)?)
    }

    /// Opens the `.pyr` file at `path` with the relaxation `relaxation` (default: the file's)
    /// and says whether its stored details were used ([`Self::from_pyr_bytes_with`]). The file
    /// is read in place ([`format::PyrFile`]), not copied into memory first.
    pub fn load_with(
        path: impl AsRef<Path>,
        relaxation: Option<RelaxationSpec>,
        progress: &dyn Progress,
    ) -> Result<(Pyramid, DetailSource), PyrFileError> {
        let path = path.as_ref();
        let file = format::PyrFile::open(path).map_err(|error| IoError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        let data = file
            .decode()
            .map_err(|e| PyrFileError::from(e).in_file(path))?;
        drop(file);
        data.into_pyramid_with(relaxation, progress)
            .map_err(|e| PyrFileError::from(e).in_file(path))
    }
}
