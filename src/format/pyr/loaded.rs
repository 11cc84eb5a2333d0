//! What a decoded file gives: its pyramid (from the stored details when they fit, else
//! analysed), its spectrum straight from the details, and the repaired mesh on demand.

use super::details::{ANALYSIS_VERSION, DetailSection};
use super::{BASE, PyrData, SPLT, corrupt};
use crate::format::FormatError;
use crate::format::container::Container;
use crate::mesh::{Built, Mesh, SourceMap};
use crate::progress::Progress;
use crate::pyramid::{DetailPyramid, Pyramid, PyramidError, StoredDetails};
use crate::relax::RelaxationSpec;

/// The details a `.pyr` file stores (section `DETL`).
#[derive(Clone, Debug)]
pub enum FileDetails {
    /// The file has none (format 2.0 or older, or written without details).
    Absent,
    /// Details analysed on this very hierarchy by this version of the analysis.
    Stored(StoredDetails),
    /// Details this reader cannot use, and why (analysed on another hierarchy, or by another
    /// version of the analysis).
    Unusable(String),
}

/// Where a loaded pyramid's details came from.
#[derive(Clone, Debug, PartialEq)]
pub enum DetailSource {
    /// Read from the file: only the relaxation weights and fans were computed.
    Stored,
    /// Recomputed by the analysis, and why the file's were not used.
    Recomputed(String),
}

impl PyrData {
    /// The whole scan with its detail pyramid: the file's details when it stores usable ones
    /// (only the relaxation weights and fans are computed), else the analysis' (bit-identical
    /// to the one the file was built with).
    pub fn into_pyramid(self, progress: &dyn Progress) -> Result<Pyramid, PyramidError> {
        Ok(self.into_pyramid_with(None, progress)?.0)
    }

    /// [`Self::into_pyramid`] with the relaxation `relaxation` (default: the file's): the
    /// stored details are used only when they were analysed with it; says where the details
    /// came from.
    pub fn into_pyramid_with(
        mut self,
        relaxation: Option<RelaxationSpec>,
        progress: &dyn Progress,
    ) -> Result<(Pyramid, DetailSource), PyramidError> {
        let spec = relaxation.unwrap_or(self.info.relaxation);
        let share = crate::pyramid::guide_share(&spec);
        let op =
            crate::pyramid::relaxation_for(&spec, &self.pm, &|x: f64| progress.update(share * x));
        let progress = &|x: f64| progress.update(share + (1.0 - share) * x);
        let details = std::mem::replace(&mut self.details, FileDetails::Absent);
        let (pyramid, from) = match stored_for(details, spec) {
            Ok(stored) => {
                match DetailPyramid::with_stored_details(&self.pm, op.as_ref(), &stored, progress) {
                    Ok(p) => (p, DetailSource::Stored),
                    Err(PyramidError::Invalid(why)) => (
                        DetailPyramid::analyze(&self.pm, op.as_ref(), progress)?,
                        DetailSource::Recomputed(why),
                    ),
                    Err(e) => return Err(e),
                }
            }
            Err(why) => (
                DetailPyramid::analyze(&self.pm, op.as_ref(), progress)?,
                DetailSource::Recomputed(why),
            ),
        };
        self.info.relaxation = spec;
        // A file whose input needed no repair was loaded without building the half-edge mesh
        // (see `clean_triangle_faces`): its mesh is the input itself, vertex for vertex and
        // face for face.
        let source = match self.built {
            Some(b) => b.source,
            None => SourceMap {
                vertex_source: (0..self.input.positions.len() as u32).collect(),
                face_source: (0..self.input.n_faces() as u32).collect(),
                input_vertices: self.input.positions.len(),
            },
        };
        let scan = Pyramid {
            input: self.input,
            source,
            pm: self.pm,
            pyramid,
            options: self.info,
        };
        Ok((scan, from))
    }

    /// The detail spectrum from the stored details, without any analysis; `None` (and why)
    /// when the file has no usable details analysed with `relaxation` (default: the file's).
    pub fn stored_spectrum(
        &self,
        relaxation: Option<RelaxationSpec>,
    ) -> Result<crate::pyramid::Spectrum, String> {
        let spec = relaxation.unwrap_or(self.info.relaxation);
        let stored = match &self.details {
            FileDetails::Stored(s) if s.relaxation == spec => s,
            other => return Err(stored_for(other.clone(), spec).err().unwrap_or_default()),
        };
        stored.spectrum(&self.pm).map_err(|e| e.to_string())
    }
}

/// Why a file without a `DETL` section has its details recomputed ([`DetailSource`]).
pub const NO_STORED_DETAILS: &str = "the file stores none";

/// The stored details if they were analysed with `spec`, else why not.
fn stored_for(details: FileDetails, spec: RelaxationSpec) -> Result<StoredDetails, String> {
    match details {
        FileDetails::Absent => Err(NO_STORED_DETAILS.into()),
        FileDetails::Unusable(why) => Err(why),
        FileDetails::Stored(s) if s.relaxation != spec => Err(format!(
            "the stored ones were analysed with --relax {}{}",
            s.relaxation.name(),
            if s.relaxation.name() == spec.name() {
                " with other options"
            } else {
                ""
            }
        )),
        FileDetails::Stored(s) => Ok(s),
    }
}

impl PyrData {
    /// The repaired half-edge mesh of [`Self::input`] and its map back (the one `build` made;
    /// deterministic). Built on demand unless loading already needed it.
    pub fn built(&self) -> Result<Built, FormatError> {
        match &self.built {
            Some(b) => Ok(b.clone()),
            None => Mesh::from_polygons(&self.input).map_err(|e| corrupt(0, e.to_string())),
        }
    }
}

/// Whether a decoded `DETL` section fits the file: analysed on its `BASE` and `SPLT` by this
/// version of the analysis.
pub(super) fn file_details(c: &Container<'_>, detl: Option<DetailSection>) -> FileDetails {
    let Some(d) = detl else {
        return FileDetails::Absent;
    };
    let crc = |tag| c.entry(tag).map_or(0, |e| e.crc);
    if d.analysis_version != ANALYSIS_VERSION {
        FileDetails::Unusable(format!(
            "the stored ones come from analysis version {} (this is {ANALYSIS_VERSION})",
            d.analysis_version
        ))
    } else if d.hierarchy_crcs != [crc(BASE), crc(SPLT)] {
        FileDetails::Unusable("the stored ones were analysed on another hierarchy".into())
    } else {
        FileDetails::Stored(d.stored)
    }
}
