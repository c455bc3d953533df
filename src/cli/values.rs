//! The value parsers of the flags more than one command takes (`--threads`,
//! `--runs`, `--aa`, `--method`, `--set`, `--region`, `--pass`), and
//! [`Named`], which gives a parser the names the completions, the help and
//! the man pages list. A flag of one subcommand only has its parser in that
//! subcommand's module.
//!
//! Their messages complete "--flag …, not "value"" (see
//! [`super::args::spelling::clap_message`]).

use clap::builder::{PossibleValue, TypedValueParser};
use rayoflight::render::region::Region;
use rayoflight::render::{self, Method, Pass};

pub(in crate::cli) fn threads(text: &str) -> Result<usize, String> {
    let max = rayoflight::render::max_threads();
    text.parse()
        .ok()
        .filter(|n| (1..=max).contains(n))
        .ok_or_else(|| format!("expects an integer from 1 to {max} (four per core)"))
}

pub(in crate::cli) fn runs(text: &str) -> Result<usize, String> {
    text.parse()
        .ok()
        .filter(|n| (1..=1000).contains(n))
        .ok_or_else(|| "expects an integer from 1 to 1000".to_owned())
}

pub(in crate::cli) fn aa(text: &str) -> Result<u32, String> {
    let max = rayoflight::render::MAX_AA;
    text.parse()
        .ok()
        .filter(|n| (1..=max).contains(n))
        .ok_or_else(|| format!("expects an integer from 1 to {max}"))
}

pub(in crate::cli) fn path_value(text: &str) -> Result<(String, String), String> {
    text.split_once('=')
        .map(|(path, value)| (path.to_owned(), value.to_owned()))
        .ok_or_else(|| "expects PATH=VALUE, such as object[1].material.ka=0.5".to_owned())
}

pub(in crate::cli) fn region(text: &str) -> Result<Region, String> {
    Region::parse(text).map_err(|e| e.to_string())
}

pub(in crate::cli) fn pass(text: &str) -> Result<Pass, String> {
    Pass::named(text).ok_or_else(|| {
        let names: Vec<_> = Pass::ALL.iter().map(|p| p.name()).collect();
        format!("expects one of {}", names.join(", "))
    })
}

pub(in crate::cli) fn pass_names() -> Vec<&'static str> {
    Pass::ALL.iter().map(|p| p.name()).collect()
}

pub(in crate::cli) fn method(text: &str) -> Result<Method, String> {
    render::method(text).ok_or_else(|| format!("expects one of {}", method_names().join(", ")))
}

pub(in crate::cli) fn method_names() -> Vec<&'static str> {
    render::methods().iter().map(|m| m.name).collect()
}

/// A value parser that also names the values it takes, for the shell
/// completions, the help and the man pages; parsing (and its message)
/// stays the function's.
#[derive(Clone)]
pub(in crate::cli) struct Named<T> {
    parse: fn(&str) -> Result<T, String>,
    names: fn() -> Vec<&'static str>,
}

impl<T> Named<T> {
    pub(in crate::cli) fn new(
        parse: fn(&str) -> Result<T, String>,
        names: fn() -> Vec<&'static str>,
    ) -> Named<T> {
        Named { parse, names }
    }
}

impl<T: Clone + Send + Sync + 'static> TypedValueParser for Named<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        self.parse.parse_ref(cmd, arg, value)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new((self.names)().into_iter().map(PossibleValue::new)))
    }
}
