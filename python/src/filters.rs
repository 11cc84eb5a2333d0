//! The filter keywords of `Pyramid.filter` and `Pyramid.edit`, as the command line's `--lowpass`,
//! `--stopband`, `--enhance`, `--gain` and `--normal-only` (same order of bands, so the same
//! gains and the same bits).

use crate::errors::{input_error, value_error};
use meshpyr::Filter;
use meshpyr::pyramid::{GainBand, LevelSpec};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyInt, PyString};

/// The filter keywords as given.
pub(crate) struct FilterArgs<'a, 'py> {
    pub(crate) lowpass: Option<&'a Bound<'py, PyAny>>,
    pub(crate) stopband: Option<&'a Bound<'py, PyAny>>,
    pub(crate) enhance: Option<&'a Bound<'py, PyAny>>,
    pub(crate) gains: Option<&'a Bound<'py, PyAny>>,
    pub(crate) normal_only: bool,
}

/// A level: an int is a vertex count, a string such as "0.02u" a feature size in model units
/// (or a count, "1000").
fn level(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<LevelSpec> {
    if obj.is_instance_of::<PyBool>() {
        return Err(value_error(format!(
            "{what}: a level is an int vertex count or a feature size such as \"0.02u\", not a bool"
        )));
    }
    if obj.is_instance_of::<PyInt>() {
        let n: i64 = obj
            .extract()
            .map_err(|_| value_error(format!("{what}: the level {obj} is out of range")))?;
        return usize::try_from(n).map(LevelSpec::Vertices).map_err(|_| {
            value_error(format!(
                "{what}: a level is a vertex count (>= 0) or a feature size such as \"0.02u\", \
                 got {n}"
            ))
        });
    }
    if let Ok(text) = obj.cast::<PyString>() {
        let text = text.to_cow()?;
        return text
            .parse::<LevelSpec>()
            .map_err(|e| value_error(format!("{what}: {e}")));
    }
    Err(value_error(format!(
        "{what}: a level is an int vertex count or a feature size string such as \"0.02u\", got \
         {}",
        obj.get_type().name()?
    )))
}

/// A finite gain.
fn gain(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<f64> {
    let g: f64 = obj
        .extract()
        .map_err(|_| value_error(format!("{what}: the gain must be a number")))?;
    if !g.is_finite() {
        return Err(value_error(format!(
            "{what}: the gain must be finite, got {g}"
        )));
    }
    Ok(g)
}

/// The items of a list of tuples, each of length `arity`.
fn tuples<'py>(
    obj: Option<&Bound<'py, PyAny>>,
    name: &str,
    arity: usize,
    form: &str,
) -> PyResult<Vec<Vec<Bound<'py, PyAny>>>> {
    let Some(obj) = obj else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    let items = obj
        .try_iter()
        .map_err(|_| value_error(format!("{name} must be a list of {form} tuples")))?;
    for (i, item) in items.enumerate() {
        let item = item?;
        let parts: Vec<Bound<'py, PyAny>> = item
            .try_iter()
            .and_then(|it| it.collect::<PyResult<Vec<_>>>())
            .map_err(|_| value_error(format!("{name}[{i}] must be a tuple {form}")))?;
        if parts.len() != arity {
            return Err(value_error(format!(
                "{name}[{i}] must be a tuple {form}, got {} values",
                parts.len()
            )));
        }
        out.push(parts);
    }
    Ok(out)
}

/// Bands `(a, b, g)`.
fn gain_bands(obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Vec<GainBand>> {
    tuples(obj, name, 3, "(a, b, gain)")?
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let what = format!("{name}[{i}]");
            Ok(GainBand {
                from: level(&p[0], &what)?,
                to: Some(level(&p[1], &what)?),
                gain: gain(&p[2], &what)?,
            })
        })
        .collect()
}

impl FilterArgs<'_, '_> {
    /// The filter, bands in the command line's order: low-pass, stop-bands, enhancements,
    /// generic gains.
    pub(crate) fn filter(&self) -> PyResult<Filter> {
        let mut filter = Filter {
            normal_only: self.normal_only,
            ..Filter::default()
        };
        if let Some(obj) = self.lowpass.filter(|o| !o.is_none()) {
            let n = level(obj, "lowpass")?
                .for_lowpass(&obj.to_string())
                .map_err(input_error)?;
            filter = filter.lowpass(n);
        }
        for (i, p) in tuples(self.stopband, "stopband", 2, "(a, b)")?
            .iter()
            .enumerate()
        {
            let what = format!("stopband[{i}]");
            filter = filter.stopband(level(&p[0], &what)?, level(&p[1], &what)?);
        }
        filter.bands.extend(gain_bands(self.enhance, "enhance")?);
        filter.bands.extend(gain_bands(self.gains, "gains")?);
        Ok(filter)
    }
}
