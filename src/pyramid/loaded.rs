//! A decoded `.pyr` file turned into a [`Pyramid`]: from the stored details when they fit
//! (only the relaxation weights and fans computed), else analysed; and its spectrum straight
//! from the details.

use super::{DetailPyramid, Pyramid, PyramidError, Spectrum, StoredDetails};
use crate::format::{FileDetails, PyrData};
use crate::progress::Progress;
use crate::relax::RelaxationSpec;

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
        let share = super::guide_share(&spec);
        let op = super::relaxation_for(&spec, &self.pm, &|x: f64| progress.update(share * x));
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
        let (input, source, pm, options) = self.into_scan_parts();
        let scan = Pyramid {
            input,
            source,
            pm,
            pyramid,
            options,
        };
        Ok((scan, from))
    }

    /// The detail spectrum from the stored details, without any analysis; `None` (and why)
    /// when the file has no usable details analysed with `relaxation` (default: the file's).
    pub fn stored_spectrum(&self, relaxation: Option<RelaxationSpec>) -> Result<Spectrum, String> {
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
