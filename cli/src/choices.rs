//! The clap value parser of the library's named choices ([`Choice`]): the names, their help
//! and the message for an unknown name all come from the library, so the command line and the
//! Python bindings accept the same words and refuse the others alike.

use clap::builder::{PossibleValue, TypedValueParser};
use meshpyr::choice::Choice;
use std::marker::PhantomData;

/// Parses a [`Choice`] by its library name.
#[derive(Clone, Copy)]
pub(crate) struct ChoiceParser<T>(PhantomData<T>);

/// The parser of `T`'s values, for `#[arg(value_parser = named::<T>())]`.
pub(crate) fn named<T: Choice + Send + Sync>() -> ChoiceParser<T> {
    ChoiceParser(PhantomData)
}

impl<T: Choice + Send + Sync> TypedValueParser for ChoiceParser<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        let name = value.to_string_lossy();
        T::parse(&name).map_err(|unknown| {
            let option = arg.map_or_else(String::new, |a| format!("--{}: ", a.get_id()));
            clap::Error::raw(
                clap::error::ErrorKind::InvalidValue,
                format!("{option}{unknown}\n"),
            )
            .with_cmd(cmd)
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(T::ALL.iter().map(|value| {
            PossibleValue::new(value.name()).help(value.about())
        })))
    }
}
