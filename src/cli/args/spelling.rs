//! The command line as typed, around clap: the single-dash long flags
//! `-out` and `-time` spelled as clap reads them ([`brief_spellings`]),
//! a single-dash word clap would misread as short flags refused whole
//! ([`unknown_single_dash_word`], with the flag it is a slip for), and
//! clap's errors said in one line ([`clap_message`]).

use super::definition;
use clap::error::{ContextKind, ContextValue, ErrorKind};
use std::ffi::OsString;

/// The arguments with the single-dash `-out` and `-time` spelled `--out` and
/// `--time` (up to a `--`, after which every argument is a file).
pub(super) fn brief_spellings(args: impl IntoIterator<Item = OsString>) -> Vec<OsString> {
    let mut files_only = false;
    args.into_iter()
        .map(|arg| {
            if files_only {
                return arg;
            }
            match arg.to_str() {
                Some("--") => {
                    files_only = true;
                    arg
                }
                Some(flag @ ("-out" | "-time")) => format!("-{flag}").into(),
                Some(text) if text.starts_with("-out=") => format!("-{text}").into(),
                _ => arg,
            }
        })
        .collect()
}

/// The first single-dash word of several letters that is neither a
/// single-dash long flag (`-out`, `-time`, already `--out` and `--time`
/// here) nor a cluster of short flags (`-qh`), as a message: `unknown flag
/// '-frobnicate'`, `unknown flag '-tme' (did you mean '-time'?)`. clap
/// would read `-frobnicate` as `-f …` and `-outt x.png` as `-o utt` then
/// a stray `x.png`. A word with a digit, a dot or a slash (`-n4`,
/// `-ox.png`, `-1`) is clap's to read, as are the values of the flags
/// that take one.
pub(super) fn unknown_single_dash_word(
    args: &[OsString],
    subcommand: Option<&str>,
) -> Option<String> {
    let mut root = definition();
    root.build();
    let command = match subcommand {
        Some(name) => root.find_subcommand(name)?.clone(),
        None => root,
    };
    let takes_value = |arg: &clap::Arg| arg.get_action().takes_values();
    let short = |c: char| command.get_arguments().find(|a| a.get_short() == Some(c));
    let mut value_next = false;
    for arg in &args[usize::from(subcommand.is_some())..] {
        if std::mem::take(&mut value_next) {
            continue;
        }
        let Some(text) = arg.to_str() else { continue };
        if text == "--" {
            break;
        }
        if let Some(long) = text.strip_prefix("--") {
            value_next = !long.contains('=')
                && command
                    .get_arguments()
                    .any(|a| a.get_long() == Some(long) && takes_value(a));
            continue;
        }
        let Some(word) = text.strip_prefix('-') else {
            continue;
        };
        let mut letters = word.chars();
        if let (Some(c), None) = (letters.next(), letters.next()) {
            value_next = short(c).is_some_and(takes_value);
            continue;
        }
        let whole = !word.is_empty()
            && word.chars().all(|c| c.is_ascii_alphabetic() || c == '-')
            && !word
                .chars()
                .all(|c| short(c).is_some_and(|a| !takes_value(a)));
        if whole {
            return Some(match suggestion(word, &command) {
                Some(flag) => format!("unknown flag '-{word}' (did you mean '{flag}'?)"),
                None => format!("unknown flag '-{word}'"),
            });
        }
    }
    None
}

/// The flag of `command` closest to `word` (a flag's name as typed,
/// without its dash), spelled as the help spells it (`-out`, `-time`,
/// `--threads`), where it is close enough to be a slip: at most two
/// letters apart, and fewer than half the word's.
fn suggestion(word: &str, command: &clap::Command) -> Option<String> {
    command
        .get_arguments()
        .flat_map(|a| {
            a.get_long()
                .into_iter()
                .chain(a.get_all_aliases().into_iter().flatten())
        })
        .map(|long| (edit_distance(word, long), long))
        .filter(|&(d, _)| d <= 2 && d < word.len().div_ceil(2))
        .min_by_key(|&(d, _)| d)
        .map(|(_, long)| match long {
            "out" | "time" => format!("-{long}"),
            _ => format!("--{long}"),
        })
}

/// Levenshtein's distance: the fewest letters inserted, removed or
/// replaced that turn `a` into `b`.
pub(super) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let replaced = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = replaced.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

/// One line for a clap error, in the words the hand-written parser used
/// ("unknown flag '--frobnicate'", "--aa expects an integer from 1 to 16,
/// not \"17\""); clap's own text spans several lines.
pub(super) fn clap_message(e: &clap::Error) -> String {
    let text = |kind| match e.get(kind) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        Some(ContextValue::Strings(s)) => Some(s.join(", ")),
        Some(ContextValue::StyledStr(s)) => Some(s.to_string()),
        _ => None,
    };
    // "--threads <N>" → "--threads".
    let flag = text(ContextKind::InvalidArg)
        .map(|a| a.split(' ').next().unwrap_or_default().to_owned())
        .unwrap_or_default();
    let value = text(ContextKind::InvalidValue).unwrap_or_default();
    match e.kind() {
        ErrorKind::UnknownArgument if flag.starts_with('-') => {
            match text(ContextKind::SuggestedArg) {
                Some(s) => format!("unknown flag '{flag}' (did you mean '{s}'?)"),
                None => format!("unknown flag '{flag}'"),
            }
        }
        ErrorKind::UnknownArgument => format!("unexpected argument '{flag}'"),
        ErrorKind::InvalidValue if value.is_empty() => format!("{flag} needs a value"),
        ErrorKind::InvalidValue => match text(ContextKind::ValidValue) {
            Some(valid) => format!("{flag} expects one of {valid}, not {value:?}"),
            None => format!("{flag}: invalid value {value:?}"),
        },
        ErrorKind::ValueValidation => match std::error::Error::source(e) {
            Some(why) => format!("{flag} {why}, not {value:?}"),
            None => format!("{flag}: invalid value {value:?}"),
        },
        ErrorKind::ArgumentConflict => {
            let prior = text(ContextKind::PriorArg).unwrap_or_default();
            match text(ContextKind::InvalidSubcommand) {
                // A second positional where there is room for one: clap
                // takes it for a subcommand's name.
                Some(extra) => format!("unexpected argument '{extra}'"),
                None if prior.split(' ').next() == Some(flag.as_str()) => {
                    format!("{flag} given twice")
                }
                None => format!("{flag} cannot be used with {prior}"),
            }
        }
        ErrorKind::MissingRequiredArgument => {
            format!(
                "missing argument {}",
                text(ContextKind::InvalidArg).unwrap_or_default()
            )
        }
        // Anything else: clap's first line, without its "error: ".
        _ => {
            let rendered = e.render().to_string();
            let first = rendered.lines().next().unwrap_or_default();
            first.strip_prefix("error: ").unwrap_or(first).to_owned()
        }
    }
}
