//! A `.pyr` file's pyramid opened in two stages, for a viewer that should be usable long
//! before the whole pyramid is: most of opening a large file with stored details is recording
//! the layout (the relaxation weights and fans of every split, which the file does not hold),
//! while an editor showing a level of detail first needs only the levels it synthesises at
//! every move.
//!
//! 1. [`PyrData::into_pyramid_staged`] records the layout of the splits up to a level only
//!    ([`DetailPyramid::with_stored_details_up_to`]: the first splits' records are those of
//!    the whole layout, since a split's records depend only on the splits before it) and
//!    takes the spectrum straight from the stored details (their squares per octave, taken
//!    when the file was read, with the prefix's area and diagonal: nothing is decoded or
//!    summed twice);
//! 2. [`PendingLayout::record`] then makes the whole pyramid, as
//!    [`PyrData::into_pyramid`] would have, bit for bit, for the caller to swap in.
//!
//! Only operators with ring stencils are staged: they record a prefix by replaying the
//! splits before it, while the others walk down from the finest level whatever the prefix.

use super::{DetailPyramid, DetailSource, Pyramid, PyramidError, Spectrum};
use crate::format::{FileDetails, PyrData, StoredDetails};
use crate::pm::ProgressiveMesh;
use crate::progress::Progress;
use crate::relax::Relaxation;

/// A `.pyr` file's pyramid, whole or in two stages ([`PyrData::into_pyramid_staged`]).
pub enum Staged {
    /// The whole pyramid, and where its details came from: the file is staged only when it
    /// stores usable details, its operator has ring stencils and the level is below the
    /// finest.
    Whole(Pyramid, DetailSource),
    /// The pyramid up to the level asked for, and what records the rest.
    Prefix(StagedPyramid),
}

/// The first stage of a staged pyramid.
pub struct StagedPyramid {
    /// The input, its hierarchy and options, with the detail pyramid of the levels up to the
    /// level asked for (its synthesis there gives the whole pyramid's bits; beyond it, it has
    /// no splits).
    pub scan: Pyramid,
    /// The whole pyramid's spectrum, from the stored details.
    pub spectrum: Spectrum,
    /// What records the whole pyramid.
    pub rest: PendingLayout,
}

/// The second stage: the operator and the stored details, which make the whole pyramid.
pub struct PendingLayout {
    relaxation: Box<dyn Relaxation>,
    stored: StoredDetails,
}

impl PyrData {
    /// The scan with the pyramid of its levels up to `level` (from the stored details) and
    /// what records the rest ([`Staged::Prefix`]), or, when staging does not apply, the whole
    /// pyramid as [`Self::into_pyramid_with`] makes it with the file's relaxation.
    pub fn into_pyramid_staged(
        mut self,
        level: usize,
        progress: &dyn Progress,
    ) -> Result<Staged, PyramidError> {
        let spec = self.info.relaxation;
        let stored_fits = matches!(&self.details, FileDetails::Stored(s) if s.relaxation == spec);
        let has_rings = spec.operator().as_ring_stencils().is_some();
        if !stored_fits || !has_rings || level >= self.pm.n_vertices() {
            return self.whole(progress);
        }
        let share = super::guide_share(&spec);
        let relaxation =
            super::relaxation_for(&spec, &self.pm, &|x: f64| progress.update(share * x));
        let FileDetails::Stored(stored) = std::mem::replace(&mut self.details, FileDetails::Absent)
        else {
            return Err(PyramidError::Internal("stored details vanished".into()));
        };
        let rest = &|x: f64| progress.update(share + (1.0 - share) * x);
        let prefix = DetailPyramid::with_stored_details_up_to(
            &self.pm,
            relaxation.as_ref(),
            &stored,
            level,
            rest,
        )
        .and_then(|prefix| {
            // The prefix holds the whole hierarchy's area and diagonal already.
            let (area, diagonal) = (prefix.surface_area, prefix.bbox_diagonal);
            Ok((prefix, stored.spectrum_on(&self.pm, area, diagonal)?))
        });
        let (prefix, spectrum) = match prefix {
            Ok(staged) => staged,
            // Details that do not fit the hierarchy: the whole path says why and analyses.
            Err(PyramidError::Invalid(_)) => {
                self.details = FileDetails::Stored(stored);
                return self.whole(progress);
            }
            Err(e) => return Err(e),
        };
        let (input, source, pm, options) = self.into_scan_parts();
        let scan = Pyramid {
            input,
            source,
            pm,
            pyramid: prefix,
            options,
        };
        Ok(Staged::Prefix(StagedPyramid {
            scan,
            spectrum,
            rest: PendingLayout { relaxation, stored },
        }))
    }

    fn whole(self, progress: &dyn Progress) -> Result<Staged, PyramidError> {
        let (pyramid, from) = self.into_pyramid_with(None, progress)?;
        Ok(Staged::Whole(pyramid, from))
    }
}

impl PendingLayout {
    /// The whole detail pyramid of `pm` (the staged scan's hierarchy), what
    /// [`PyrData::into_pyramid`] makes, bit for bit: from the stored details, or analysed
    /// when a later split's details do not fit the hierarchy (and why).
    pub fn record(
        &self,
        pm: &ProgressiveMesh,
        progress: &dyn Progress,
    ) -> Result<(DetailPyramid, DetailSource), PyramidError> {
        let op = self.relaxation.as_ref();
        match DetailPyramid::with_stored_details(pm, op, &self.stored, progress) {
            Ok(pyramid) => Ok((pyramid, DetailSource::Stored)),
            Err(PyramidError::Invalid(why)) => {
                let pyramid = DetailPyramid::analyze(pm, op, progress)?;
                Ok((pyramid, DetailSource::Recomputed(why)))
            }
            Err(e) => Err(e),
        }
    }
}
