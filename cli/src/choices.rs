//! clap value parsers for the library's named choices: the names, their help and the message
//! for an unknown name all come from the library, so the command line and the Python bindings
//! accept the same words.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use meshpyr::relax::RelaxKind;

/// `--relax`: the relaxation operators by [`RelaxKind`]'s names.
pub(crate) fn relax_kind() -> impl TypedValueParser<Value = RelaxKind> {
    let values =
        RelaxKind::ALL.map(|kind| PossibleValue::new(kind.spec().name()).help(kind.about()));
    PossibleValuesParser::new(values).try_map(|name| name.parse::<RelaxKind>())
}
