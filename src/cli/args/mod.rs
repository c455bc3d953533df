//! Command-line parsing with clap (derive), in two steps:
//!
//! 1. clap reads the arguments into [`Cli`]: the render's flags, or one
//!    subcommand's, each as its module defines them (the list of
//!    subcommands is [`super::command`]'s table);
//! 2. [`parse`] resolves them into one [`Command`], with every default
//!    applied and every rule across flags checked. That value is all the
//!    rest of the binary sees.
//!
//! The single-dash long options `-out` and `-time` (as the original command
//! line had them) are rewritten to `--out` and `--time` before clap sees
//! them: clap would read `-out` as `-o ut`. Any other single-dash word of
//! letters (`-frobnicate`, `-tme`) is refused whole, with the flag it is a
//! slip for, before clap would read it as short flags ([`spelling`]).
//! Numeric flags take negative numbers as values, so that their range
//! check says what is allowed.
//!
//! The whole definition ([`definition`]) is also what the usage
//! ([`usage`]: the render's line, then each subcommand's own), the man
//! pages and the shell completions are made from, and its list of
//! subcommand names is the one list ([`SUBCOMMANDS`]).

use super::command::{Command, Sub};
use super::generated::MAN_SUBCOMMAND;
use super::render::{RenderFlags, render_args};
use super::usage::UsageError;
use super::values::Named;
use clap::error::ErrorKind;
use clap::{CommandFactory, FromArgMatches, Parser};
use std::ffi::OsString;
use std::sync::LazyLock;

pub(super) mod spelling;

use spelling::{brief_spellings, clap_message, unknown_single_dash_word};

/// The render's usage: the first lines of the usage, before each
/// subcommand's.
const RENDER_USAGE: &str = "\
rayoflight [-time] scene.xml [-out image.png] [--set PATH=VALUE]…
                  [--pass NAME] [--region X0,Y0,X1,Y1] [--threads N] [--aa N]
                  [--method NAME] [--no-gui] [--quiet]";

/// What the top-level help says after the flags and subcommands.
const AFTER_HELP: &str = "\
The single-dash spellings -out and -time (as the original command line had
them) are the same flags as --out and --time. A scene file named like a
subcommand is given as a path: ./bench.

Exit status: 0 success, 1 scene, render or output error, 2 usage error.";

// ----- what clap reads -----

#[derive(Parser, Debug)]
#[command(
    name = "rayoflight",
    version,
    about = "A raytracer for XML scenes, with a live desktop previewer",
    long_about = "Renders an XML scene (spheres, planes, lights, one camera, an \
             illumination model) to an image. In the GUI build, the scene alone \
             opens the live previewer on it; any render flag or --no-gui renders \
             here instead.",
    // The usage first, as `rayoflight` alone prints it.
    help_template = "{usage-heading} {usage}\n\n{about-with-newline}\n{all-args}{after-help}",
    after_help = AFTER_HELP,
    // `rayoflight scene.xml` renders, `rayoflight bench` runs the bench: a
    // first argument that is not a subcommand's name is the scene.
    args_conflicts_with_subcommands = true,
    subcommand_value_name = "SUBCOMMAND",
    disable_help_subcommand = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Sub>,
    #[command(flatten)]
    render: RenderFlags,
}

/// The command line's definition, as clap reads it: what the help, the
/// usage, the shell completions and the man pages are made from. Built
/// from [`Cli`], with what needs the whole of it: the usage, which lists
/// every subcommand's, and the names `man` takes.
pub(super) fn definition() -> clap::Command {
    let cli = Cli::command();
    let usage = usage_of(&cli);
    cli.override_usage(usage).mut_subcommand("man", |man| {
        man.mut_arg(MAN_SUBCOMMAND, |arg| {
            arg.value_parser(Named::new(subcommand, subcommand_names))
        })
    })
}

/// The usage lines: the render's, then each subcommand's own usage as
/// its definition gives it, then help and version.
fn usage_of(cli: &clap::Command) -> String {
    let mut built = cli.clone();
    built.build();
    let mut lines = vec![RENDER_USAGE.to_owned()];
    for sub in built.get_subcommands_mut() {
        let usage = sub.render_usage().to_string();
        let usage = usage.trim_start_matches("Usage: ").trim_end();
        lines.push(usage.to_owned());
    }
    lines.push("rayoflight --help | --version".to_owned());
    lines.join("\n       ")
}

/// The usage, as `rayoflight` alone prints it (the headless build, no
/// scene) and as the help starts.
pub(super) fn usage() -> String {
    format!("Usage: {}", usage_of(&Cli::command()))
}

/// The subcommands' names, in the table's order, as clap derives them: the
/// one list, read from the definition (`man`'s argument, the subcommand
/// a usage error points to).
static SUBCOMMANDS: LazyLock<Vec<&'static str>> = LazyLock::new(|| {
    Cli::command()
        .get_subcommands()
        .map(|c| &*String::leak(c.get_name().to_owned()))
        .collect()
});

fn subcommand(text: &str) -> Result<String, String> {
    match SUBCOMMANDS.contains(&text) {
        true => Ok(text.to_owned()),
        false => Err(format!("expects one of {}", SUBCOMMANDS.join(", "))),
    }
}

fn subcommand_names() -> Vec<&'static str> {
    SUBCOMMANDS.clone()
}

/// The subcommand the arguments run, if any: only the first argument can
/// name one (`args_conflicts_with_subcommands`).
fn subcommand_named(args: &[OsString]) -> Option<&'static str> {
    let first = args.first()?.to_str()?;
    SUBCOMMANDS.iter().copied().find(|name| *name == first)
}

// ----- resolving -----

/// Parses the arguments after the program name.
pub(super) fn parse(args: impl IntoIterator<Item = OsString>) -> Result<Command, UsageError> {
    let args = brief_spellings(args);
    let subcommand = subcommand_named(&args);
    if let Some(word) = unknown_single_dash_word(&args, subcommand) {
        return Err(UsageError::Invalid {
            message: word,
            command: subcommand,
        });
    }
    let program = std::iter::once(OsString::from("rayoflight"));
    let clap_error = |e: clap::Error| match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            Ok(Command::Print(e.render().to_string()))
        }
        _ => Err(UsageError::Invalid {
            message: clap_message(&e),
            command: subcommand,
        }),
    };
    // The matches as well as the structs: the edits' order is in the
    // matches only.
    let matches = match definition().try_get_matches_from(program.chain(args)) {
        Ok(matches) => matches,
        Err(e) => return clap_error(e),
    };
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => return clap_error(e),
    };
    let Some(sub) = cli.command else {
        return Ok(Command::Render(render_args(cli.render)?));
    };
    // The subcommand's own matches (clap matched one: `sub` is it).
    let own = matches.subcommand().map_or(&matches, |(_, own)| own);
    Command::of(sub, own)
}

#[cfg(test)]
mod tests {
    use super::spelling::edit_distance;
    use super::*;
    use crate::cli::edit::EditArg;
    use crate::cli::plan::PlanFlags;
    use crate::cli::pov::ExportPovFlags;
    use std::path::PathBuf;

    fn p(args: &[&str]) -> Result<Command, UsageError> {
        parse(args.iter().map(OsString::from))
    }

    /// The message of a usage error.
    fn message(result: Result<Command, UsageError>) -> String {
        match result {
            Err(UsageError::Invalid { message, .. }) => message,
            other => panic!("expected a usage error, got {other:?}"),
        }
    }

    #[test]
    fn cli_is_well_formed() {
        definition().debug_assert();
        let names: Vec<_> = Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_owned())
            .collect();
        assert_eq!(names, *SUBCOMMANDS);
    }

    /// The usage has every subcommand's line, read from its definition
    /// (its own usage, or clap's for one that gives none).
    #[test]
    fn the_usage_names_every_subcommand() {
        let usage = usage();
        let lines: Vec<&str> = usage.lines().map(str::trim).collect();
        for name in SUBCOMMANDS.iter() {
            let line = format!("rayoflight {name}");
            assert!(
                lines.iter().any(|l| l
                    .strip_prefix(&line)
                    .is_some_and(|rest| rest.is_empty() || rest.starts_with(' '))),
                "the usage has no line for {name}:\n{usage}"
            );
        }
        assert!(usage.starts_with("Usage: rayoflight [-time] scene.xml"));
        assert!(usage.ends_with("rayoflight --help | --version"));
        let Ok(Command::Print(help)) = p(&["bench", "--help"]) else {
            panic!()
        };
        let bench = &usage[usage.find("rayoflight bench").unwrap()..];
        let bench = &bench[..bench.find("\n       rayoflight ").unwrap()];
        assert!(help.contains(&format!("Usage: {bench}\n")), "{help}");
    }

    #[test]
    fn brief_syntax_and_gnu_forms_agree() {
        let brief = p(&["-time", "s.xml", "-out", "x.png"]).unwrap();
        let gnu = p(&["--time", "s.xml", "--out=x.png"]).unwrap();
        assert_eq!(brief, gnu);
        let Command::Render(r) = brief else { panic!() };
        assert_eq!(r.scene, Some(PathBuf::from("s.xml")));
        assert_eq!(r.out, Some(PathBuf::from("x.png")));
        assert!(r.time && r.headless());
        assert_eq!(p(&["-time", "s.xml", "-out=x.png"]).unwrap(), gnu);
        assert_eq!(p(&["-time", "s.xml", "-o", "x.png"]).unwrap(), gnu);
    }

    #[test]
    fn numbers_are_checked() {
        assert_eq!(
            message(p(&["s.xml", "--threads", "0"])),
            format!(
                "--threads expects an integer from 1 to {} (four per core), not \"0\"",
                rayoflight::render::max_threads()
            )
        );
        assert_eq!(
            message(p(&["s.xml", "--aa", "17"])),
            "--aa expects an integer from 1 to 16, not \"17\""
        );
        assert_eq!(message(p(&["s.xml", "--aa"])), "--aa needs a value");
        let Ok(Command::Render(r)) = p(&["s.xml", "--aa", "4", "--threads=3"]) else {
            panic!()
        };
        assert_eq!((r.request.aa, r.request.threads), (Some(4), Some(3)));
    }

    #[test]
    fn unknown_flags_are_named() {
        assert_eq!(message(p(&["-x"])), "unknown flag '-x'");
        assert_eq!(
            message(p(&["--outt", "a"])),
            "unknown flag '--outt' (did you mean '--out'?)"
        );
        assert_eq!(
            message(p(&["a.xml", "b.xml"])),
            "unexpected argument 'b.xml'"
        );
        assert_eq!(
            message(p(&["s.xml", "-out", "a.png", "--out", "b.png"])),
            "--out given twice"
        );
    }

    #[test]
    fn single_dash_words_are_named_whole() {
        assert_eq!(
            message(p(&["-frobnicate", "s.xml"])),
            "unknown flag '-frobnicate'"
        );
        assert_eq!(
            message(p(&["-tme", "s.xml"])),
            "unknown flag '-tme' (did you mean '-time'?)"
        );
        assert_eq!(
            message(p(&["-outt", "x.png", "s.xml"])),
            "unknown flag '-outt' (did you mean '-out'?)"
        );
        assert_eq!(
            message(p(&["s.xml", "-threads", "2"])),
            "unknown flag '-threads' (did you mean '--threads'?)"
        );
        let Err(UsageError::Invalid {
            message: text,
            command,
        }) = p(&["assemble", "-outt", "a.png"])
        else {
            panic!()
        };
        assert_eq!(text, "unknown flag '-outt' (did you mean '-out'?)");
        assert_eq!(command, Some("assemble"));
        // clap's own forms still read: a value glued to a short flag, a
        // cluster of flags, a flag's value that starts with a dash.
        let Ok(Command::Render(r)) = p(&["s.xml", "-ox.png"]) else {
            panic!()
        };
        assert_eq!(r.out, Some(PathBuf::from("x.png")));
        assert!(matches!(
            p(&["split", "s.xml", "-n4"]),
            Ok(Command::Split(_))
        ));
        assert!(matches!(p(&["-qh"]), Ok(Command::Print(_))));
        assert!(message(p(&["s.xml", "--region", "-abc"])).starts_with("--region expects"));
        assert!(message(p(&["split", "s.xml", "-n", "-abc"])).starts_with("--tasks expects"));
        assert_eq!(edit_distance("tme", "time"), 1);
        assert_eq!(edit_distance("outt", "out"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn negative_numbers_are_values_and_the_range_is_said() {
        let max = rayoflight::render::max_threads();
        assert_eq!(
            message(p(&["s.xml", "--threads", "-1"])),
            format!("--threads expects an integer from 1 to {max} (four per core), not \"-1\"")
        );
        assert_eq!(
            message(p(&["s.xml", "--aa", "-1"])),
            "--aa expects an integer from 1 to 16, not \"-1\""
        );
        assert_eq!(
            message(p(&["bench", "--split-size", "-1"])),
            "--split-size expects 0 (skip the section) or a side from 8 to 16384 pixels, not \"-1\""
        );
        assert!(matches!(
            p(&["bench", "--split-size", "16384"]),
            Ok(Command::Bench(_))
        ));
        assert!(p(&["bench", "--split-size", "16385"]).is_err());
        assert!(message(p(&["bench", "--runs", "-1"])).starts_with("--runs expects an integer"));
        assert!(message(p(&["study", "--threads", "-2"])).starts_with("--threads expects"));
        assert_eq!(
            message(p(&["explain", "s.xml", "-1", "0"])),
            "<X> expects a pixel number: 0, 1, 2, … from the image's top left, not \"-1\""
        );
        assert!(message(p(&["explain", "s.xml", "0", "-3"])).starts_with("<Y> expects"));
    }

    #[test]
    fn usage_errors_point_to_the_subcommands_help() {
        let Err(UsageError::Invalid { command, .. }) = p(&["plan", "--frobnicate"]) else {
            panic!()
        };
        assert_eq!(command, Some("plan"));
        let Err(UsageError::Invalid { command, .. }) = p(&["s.xml", "--frobnicate"]) else {
            panic!()
        };
        assert_eq!(command, None);
    }

    #[test]
    fn help_and_version_are_printed() {
        let Ok(Command::Print(help)) = p(&["--help"]) else {
            panic!()
        };
        assert!(
            help.starts_with(&usage()) && help.contains("-o, --out <FILE>"),
            "{help}"
        );
        assert!(
            help.contains("also -out") && help.contains("Exit status"),
            "{help}"
        );
        let Ok(Command::Print(help)) = p(&["plan", "-h"]) else {
            panic!()
        };
        assert!(help.contains("Usage: rayoflight plan scene.xml"), "{help}");
        let Ok(Command::Print(version)) = p(&["-V"]) else {
            panic!()
        };
        assert_eq!(
            version.trim(),
            format!("rayoflight {}", env!("CARGO_PKG_VERSION"))
        );
    }

    #[test]
    fn export_pov_subcommand() {
        assert_eq!(
            p(&["export-pov", "s.xml", "-out", "s.pov"]).unwrap(),
            Command::ExportPov(ExportPovFlags {
                scene: "s.xml".into(),
                out: Some("s.pov".into())
            })
        );
        assert!(p(&["export-pov"]).is_err());
        assert!(p(&["export-pov", "s.xml", "--time"]).is_err());
    }

    #[test]
    fn a_scene_named_like_a_subcommand_is_given_as_a_path() {
        let Ok(Command::Render(r)) = p(&["./bench"]) else {
            panic!()
        };
        assert_eq!(r.scene, Some(PathBuf::from("./bench")));
    }

    #[test]
    fn bench_subcommand() {
        let Ok(Command::Bench(b)) = p(&["bench", "--threads", "3", "--runs", "7", "-out", "b.csv"])
        else {
            panic!()
        };
        assert_eq!((b.threads, b.runs, b.pov), (3, 7, true));
        assert_eq!(b.csv, Some(PathBuf::from("b.csv")));
        let Ok(Command::Bench(b)) = p(&["bench", "--no-pov"]) else {
            panic!()
        };
        assert!(!b.pov && b.runs == 3 && b.csv.is_none());
        assert!(p(&["bench", "--runs", "0"]).is_err());
        assert!(p(&["bench", "scene.xml"]).is_err());
        assert!(p(&["bench", "--aa", "2"]).is_err());
        assert!(p(&["bench", "--csv", "a.csv", "-out", "b.csv"]).is_err());
        assert!(
            p(&["s.xml", "--runs", "2"]).is_err(),
            "--runs belongs to bench"
        );
    }

    #[test]
    fn method_names_a_study_method() {
        let Ok(Command::Render(r)) = p(&["s.xml", "--method", "f32"]) else {
            panic!()
        };
        assert_eq!(r.request.method.as_ref().map(|m| m.name), Some("f32"));
        assert!(r.headless());
        assert!(message(p(&["s.xml", "--method", "fast"])).contains("auto"));
        assert!(p(&["s.xml", "--method"]).is_err());
        assert!(p(&["study", "--method", "auto"]).is_err());
    }

    #[test]
    fn plan_subcommand() {
        assert_eq!(
            p(&["plan", "s.xml"]).unwrap(),
            Command::Plan(PlanFlags {
                scene: PathBuf::from("s.xml")
            })
        );
        assert!(p(&["plan"]).is_err());
        assert!(p(&["plan", "a.xml", "b.xml"]).is_err());
        assert!(p(&["plan", "a.xml", "-out", "x.png"]).is_err());
    }

    #[test]
    fn study_subcommand() {
        let Ok(Command::Study(s)) = p(&["study", "--out", "d", "a.xml", "b.xml", "--runs=1"])
        else {
            panic!()
        };
        assert_eq!(s.out, PathBuf::from("d"));
        assert_eq!(s.scenes, [PathBuf::from("a.xml"), PathBuf::from("b.xml")]);
        assert_eq!((s.runs, s.threads), (1, None));
        let Ok(Command::Study(s)) = p(&["study"]) else {
            panic!()
        };
        assert_eq!((s.out, s.runs), (PathBuf::from("study"), 3));
        assert!(s.scenes.is_empty());
        assert!(p(&["study", "--aa", "2"]).is_err());
        assert!(p(&["study", "--csv", "x.csv"]).is_err());
    }

    #[test]
    fn set_on_a_render_is_read_and_makes_it_headless() {
        let Ok(Command::Render(r)) = p(&[
            "s.xml",
            "--set",
            "model.depth=3",
            "--set=light[1].x=-2",
            "--threads",
            "2",
        ]) else {
            panic!()
        };
        let expected = [
            EditArg::set("model.depth", "3"),
            EditArg::set("light[1].x", "-2"),
        ];
        assert_eq!(r.edits, expected.map(Result::unwrap));
        assert!(r.headless());
        assert_eq!(p(&["--set", "model.depth=3"]), Err(UsageError::NoScene));
        assert!(message(p(&["s.xml", "--set", "model.depth"])).starts_with("--set expects"));
        assert!(matches!(
            p(&["s.xml", "--set", "model.dept=3"]),
            Err(UsageError::Edit { .. })
        ));
        assert!(p(&["s.xml", "--remove", "light[1]"]).is_err(), "edit only");
    }

    #[test]
    fn edit_keeps_the_order_of_its_flags() {
        let Ok(Command::Edit(e)) = p(&[
            "edit",
            "s.xml",
            "--remove",
            "light[1]",
            "--set",
            "model.depth=3",
            "--add",
            "sphere",
            "--set=object[1].color.red=0.5",
            "-out",
            "o.xml",
        ]) else {
            panic!()
        };
        let expected = [
            EditArg::remove("light[1]"),
            EditArg::set("model.depth", "3"),
            EditArg::add("sphere"),
            EditArg::set("object[1].color.red", "0.5"),
        ];
        assert_eq!(e.edits, expected.map(Result::unwrap));
        assert_eq!((e.scene, e.out), ("s.xml".into(), Some("o.xml".into())));
    }

    #[test]
    fn edit_refuses_what_it_cannot_read() {
        assert!(message(p(&["edit", "s.xml"])).starts_with("nothing to do"));
        assert!(
            message(p(&["edit", "s.xml", "--set", "model.depth"])).starts_with("--set expects")
        );
        assert!(p(&["edit", "--set", "model.depth=3"]).is_err(), "no scene");
        let Err(UsageError::Edit { scene, error }) = p(&["edit", "s.xml", "--add", "cube"]) else {
            panic!()
        };
        assert_eq!(scene, PathBuf::from("s.xml"));
        assert_eq!(
            error.to_string(),
            "cube: not an element that can be added; those are sphere, plane and light"
        );
    }

    #[test]
    fn double_dash_ends_flags() {
        let Ok(Command::Render(r)) = p(&["--", "-weird.xml"]) else {
            panic!()
        };
        assert_eq!(r.scene, Some(PathBuf::from("-weird.xml")));
        let Ok(Command::Render(r)) = p(&["--", "-out"]) else {
            panic!()
        };
        assert_eq!(r.scene, Some(PathBuf::from("-out")));
    }
}
