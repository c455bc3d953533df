//! Command-line parsing with clap (derive), in two steps:
//!
//! 1. clap reads the arguments into the `Cli` structs below, which mirror
//!    the flags one to one (and give each subcommand its `--help`);
//! 2. [`parse`] resolves them into one [`Command`], with every default
//!    applied and every rule across flags checked. That value is all the
//!    rest of the binary sees.
//!
//! The single-dash long options `-out` and `-time` (as the original command
//! line had them) are rewritten to `--out` and `--time` before clap sees
//! them: clap would read `-out` as `-o ut`. Any other single-dash word of
//! letters (`-frobnicate`, `-tme`) is refused whole, with the flag it is a
//! slip for, before clap would read it as short flags. Numeric flags take negative numbers as values,
//! so that their range check says what is allowed.
//!
//! Here: the top-level parser ([`Cli`], its list of subcommands [`Sub`]),
//! [`parse`] and what it returns ([`Command`], or a [`UsageError`], which
//! lives in [`error`]). Each subcommand's flags, as clap reads them, and
//! their resolving into the subcommand's own arguments live in the
//! subcommand's own module (`cluster`, `explain`, `edit`, `bench`,
//! `study`), which imports nothing of this file: [`parse`] wraps what they
//! give in a [`Command`]. The render's own flags are in [`render`]; the value parsers that
//! several commands share in [`values`]; the single-dash spellings and
//! clap's errors in one line in [`spelling`]. The list of subcommand names
//! is clap's own ([`SUBCOMMANDS`]).

use super::{bench, cluster, edit, explain, study};
use clap::error::ErrorKind;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand, ValueHint};
use std::ffi::OsString;
use std::path::PathBuf;
use std::sync::LazyLock;

pub(super) mod error;
pub(super) mod render;
mod spelling;
pub(super) mod values;

pub use error::UsageError;

pub use render::RenderArgs;
use render::{RenderFlags, render_args};
use spelling::{brief_spellings, clap_message, unknown_single_dash_word};
use values::Named;

pub const USAGE: &str = "\
Usage: rayoflight [-time] scene.xml [-out image.png] [--set PATH=VALUE]…
                  [--pass NAME] [--region X0,Y0,X1,Y1] [--threads N] [--aa N]
                  [--method NAME] [--no-gui] [--quiet]
       rayoflight explain scene.xml X Y [--json] [--set PATH=VALUE]… [--aa N] [--method NAME]
       rayoflight edit scene.xml [--set PATH=VALUE]… [--remove PATH]… [--add KIND]… [-out FILE]
       rayoflight split scene.xml --tasks N [--set PATH=VALUE]… [--aa N] [--method NAME]
       rayoflight assemble -out image.png PART.png…
       rayoflight sheet -out sheet.png [--columns N] IMAGE…
       rayoflight export-pov scene.xml [-out scene.pov]
       rayoflight plan scene.xml
       rayoflight bench [--threads N] [--runs K] [--csv FILE] [--no-pov] [--split-size PIXELS] [--big-spheres N]
                        [--quiet]
       rayoflight study [--out DIR] [--runs K] [--threads N] [--quiet] [scene.xml…]
       rayoflight new scene.xml
       rayoflight install-desktop [--uninstall]
       rayoflight schema | completions SHELL | man [SUBCOMMAND] | lsp
       rayoflight --help | --version";

/// What the top-level help says after the flags and subcommands.
const AFTER_HELP: &str = "\
The single-dash spellings -out and -time (as the original command line had
them) are the same flags as --out and --time. A scene file named like a
subcommand is given as a path: ./bench.

Exit status: 0 success, 1 scene, render or output error, 2 usage error.";

/// What the user asked for.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// `--help` or `--version`: print this text on stdout.
    Print(String),
    /// Render a scene (headless), or open the app on it (GUI build, no
    /// headless flag).
    Render(RenderArgs),
    /// `split scene.xml --tasks N`.
    Split(cluster::SplitArgs),
    /// `assemble -out image.png PART…`.
    Assemble { out: PathBuf, parts: Vec<PathBuf> },
    /// `sheet -out sheet.png [--columns N] IMAGE…`.
    Sheet {
        out: PathBuf,
        columns: Option<usize>,
        images: Vec<PathBuf>,
    },
    /// `export-pov scene.xml [-out scene.pov]`.
    ExportPov {
        scene: PathBuf,
        out: Option<PathBuf>,
    },
    /// `plan scene.xml`: print what `auto` decides for the scene.
    Plan { scene: PathBuf },
    /// `explain scene.xml X Y [--json]`.
    Explain(explain::ExplainArgs),
    /// `edit scene.xml [--set PATH=VALUE]… [--remove PATH]… [--add KIND]…`.
    Edit(edit::EditArgs),
    /// `bench [--threads N] [--runs K] [--csv FILE] [--no-pov]`.
    Bench(super::bench::BenchArgs),
    /// `study [--out DIR] [--runs K] [--threads N] [scene.xml…]`.
    Study(super::study::StudyArgs),
    /// `new scene.xml`: write the built-in example as a starting scene
    /// (`-`: on stdout).
    New { scene: PathBuf },
    /// `schema`: print the scene format's XML Schema.
    Schema,
    /// `completions SHELL`: print the shell's completion script.
    Completions(clap_complete::Shell),
    /// `man [SUBCOMMAND]`: print a man page (roff); `man --dir DIR`: write
    /// them all into DIR.
    Man {
        subcommand: Option<String>,
        dir: Option<PathBuf>,
    },
    /// `install-desktop [--uninstall]`.
    InstallDesktop { uninstall: bool },
    /// `lsp`: the language server on stdio.
    Lsp,
}

impl Command {
    /// Whether the command prints on stdout: help and version, `plan`,
    /// `split`, `explain`, `bench`, `study` and a render with `-time`.
    pub fn prints(&self) -> bool {
        match self {
            Command::Print(_)
            | Command::Plan { .. }
            | Command::Split(_)
            | Command::Explain(_)
            | Command::Bench(_)
            | Command::Study(_)
            | Command::Schema
            | Command::Completions(_)
            | Command::Man { dir: None, .. } => true,
            Command::Man { dir: Some(_), .. } => false,
            Command::New { scene } => scene.as_os_str() == "-",
            Command::InstallDesktop { .. } | Command::Lsp => false,
            Command::Render(r) => r.time,
            Command::Assemble { .. }
            | Command::Sheet { .. }
            | Command::ExportPov { .. }
            | Command::Edit(_) => false,
        }
    }
}

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
    override_usage = USAGE.trim_start_matches("Usage: "),
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

#[derive(Subcommand, Debug)]
enum Sub {
    /// N regions of the image, one a line, of even estimated cost.
    ///
    /// Each line is X0,Y0,X1,Y1 (pixels, X1 and Y1 excluded): give it to
    /// `rayoflight scene.xml --region X0,Y0,X1,Y1 -out part-I.png`, one
    /// task a line (a Slurm array, xargs -P, GNU parallel), then put the
    /// parts together with `rayoflight assemble`. The regions are balanced
    /// by cost, not area: a coarse pre-pass traces a few rays in each cell
    /// of a grid over the image and counts the rays each costs, reflections
    /// included; cuts follow the render's 32-pixel tiles where they can.
    /// Give the render's --set, --aa and --method: they change the cost.
    #[command(
        override_usage = "rayoflight split scene.xml --tasks N [--set PATH=VALUE]… [--aa N] \
                          [--method NAME]"
    )]
    Split(cluster::SplitFlags),
    /// Put the parts `--region` wrote together into the full image.
    ///
    /// The image is the same file a render of the whole writes, byte for
    /// byte. Every part's PNG records where it belongs, the full image's
    /// size and a fingerprint of the scene and render options: assemble
    /// refuses, naming the culprit, a file that is not a part, parts of
    /// other scenes, options or versions, overlapping parts, pixels no
    /// part holds (a missing part), a region outside the image. Rows are
    /// streamed: only the parts crossing a row are open, so memory holds a
    /// few rows, never the image.
    #[command(override_usage = "rayoflight assemble -out image.png PART.png…")]
    Assemble(cluster::AssembleFlags),
    /// A contact sheet: the images side by side in a grid, each named.
    ///
    /// Each picture sits in a cell as large as the largest, its file name
    /// (its end, when too long) under it: the renders of a --set sweep at
    /// a glance.
    #[command(override_usage = "rayoflight sheet -out sheet.png [--columns N] IMAGE…")]
    Sheet(cluster::SheetFlags),
    /// Write the scene as a POV-Ray 3.7 file, for cross-checking.
    ExportPov {
        /// The scene file.
        scene: PathBuf,
        /// The POV-Ray file to write [default: the scene's path with .pov]
        #[arg(short, long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// Print what 'auto' will do for the scene, and why.
    ///
    /// Precision, BVH and tile culling, early stop, zero terms: each
    /// decision with the scene's numbers. Renders use these options.
    Plan {
        /// The scene file.
        scene: PathBuf,
    },
    /// Why a pixel has its colour: its ray tree, term by term.
    ///
    /// For each bounce: the ray, the object hit (its number as in the
    /// app's panel), t, the hit point M and normal N, for each light
    /// cos θ and cos α, and the terms ka·C, Σ I·kd·cos θ, Σ I·ks·cos^m α
    /// and ks·Ir; then where the chain ended (a miss, the depth, ks = 0,
    /// or the early stop and its bound), the unclamped sum and the 8-bit
    /// value, which is the pixel of `rayoflight scene.xml` with the same
    /// --set, --aa and --method.
    #[command(
        override_usage = "rayoflight explain scene.xml X Y [--json] [--set PATH=VALUE]… \
                                [--aa N] [--method NAME]"
    )]
    Explain(explain::ExplainFlags),
    /// Time the bench scenes, against POV-Ray when it is installed.
    ///
    /// Also thread scaling, cost against object count and peak memory.
    Bench(bench::BenchFlags),
    /// Change values of a scene file, add or remove elements, and write it.
    ///
    /// The edits apply in the order given, and the file keeps every byte
    /// they do not change: comments, formatting, the spelling of other
    /// numbers. It is rewritten in place (atomically, keeping its mode;
    /// through a symbolic link, the file it points to), or written to
    /// -out FILE. An edit that changes nothing leaves the file untouched.
    #[command(
        override_usage = "rayoflight edit scene.xml [--set PATH=VALUE]… [--remove PATH]… \
                          [--add KIND]… [-out FILE]",
        after_help = edit::PATHS
    )]
    Edit(edit::EditFlags),
    /// Speed against accuracy: every render method on the study scenes.
    ///
    /// Measures each method (f32, textbook quadratic, offsets,
    /// anti-aliasing, depth cut, early stop, draft, auto) against the
    /// default image, on the built-in study scenes or on the scene files
    /// given. Prints a table on stdout and writes DIR/study.csv, the chart
    /// DIR/study.png and a picture of each failure. See docs/study.md.
    Study(study::StudyFlags),
    /// Write the built-in example scene to a new file, to start from.
    ///
    /// Never over an existing file. '-' prints it on stdout.
    New {
        /// The scene file to create.
        #[arg(value_name = "FILE", value_hint = ValueHint::FilePath)]
        scene: PathBuf,
    },
    /// Print the XML Schema (XSD 1.0) of the scene format.
    ///
    /// Generated from the loader's own tables: every element and
    /// attribute, which are required, the ranges and the numbers the
    /// loader reads, each documented (what editors show on hover). Save
    /// it as rayoflight.xsd and point the editor at it; see the README.
    Schema,
    /// Print the shell completion script for SHELL.
    ///
    /// Completes subcommands, flags, file names where a file goes and the
    /// names --method, --pass and --add take. For bash:
    /// rayoflight completions bash > ~/.local/share/bash-completion/completions/rayoflight
    Completions {
        /// The shell.
        #[arg(value_name = "SHELL")]
        shell: clap_complete::Shell,
    },
    /// Put the app in the desktop's menus and "Open with", for this user.
    ///
    /// Writes a desktop entry (that runs this binary, by its absolute
    /// path), the icons in the hicolor theme and the type of scenes that
    /// name rayoflight.xsd under $XDG_DATA_HOME (default ~/.local/share),
    /// and updates the desktop's databases when their tools are installed.
    /// RayOfLight is the default for its own type only, never for every
    /// XML file. Never over a file it did not write; --uninstall removes
    /// exactly what it wrote.
    InstallDesktop {
        /// Remove what install-desktop wrote.
        #[arg(long)]
        uninstall: bool,
    },
    /// A language server for scene files, on stdin and stdout (LSP).
    ///
    /// Errors as you type, at their line and column; completion of
    /// elements, attributes and the model's types; what a name means on
    /// hover; the objects, lights and camera as the document's symbols.
    /// Start it from the editor's LSP client; see the README.
    Lsp,
    /// Print a man page: rayoflight(1), or one subcommand's.
    ///
    /// For example: rayoflight man | man -l -, rayoflight man edit, or
    /// rayoflight man --dir ~/.local/share/man/man1 for every page.
    Man {
        /// The subcommand whose page to print [default: rayoflight(1)]
        #[arg(value_name = "SUBCOMMAND", value_parser = Named::new(subcommand, subcommand_names))]
        subcommand: Option<String>,
        /// Write every page into DIR (made if missing) instead:
        /// rayoflight.1 and rayoflight-SUBCOMMAND.1.
        #[arg(long, value_name = "DIR", value_hint = ValueHint::DirPath, conflicts_with = "subcommand")]
        dir: Option<PathBuf>,
    },
}

/// The subcommands' names, in `Sub`'s order, as clap derives them: the
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
pub fn parse(args: impl IntoIterator<Item = OsString>) -> Result<Command, UsageError> {
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
    let matches = match Cli::command().try_get_matches_from(program.chain(args)) {
        Ok(matches) => matches,
        Err(e) => return clap_error(e),
    };
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => return clap_error(e),
    };
    Ok(match cli.command {
        None => Command::Render(render_args(cli.render)?),
        Some(Sub::ExportPov { scene, out }) => Command::ExportPov { scene, out },
        Some(Sub::Split(f)) => Command::Split(f.resolve()?),
        Some(Sub::Assemble(f)) => {
            let (out, parts) = f.resolve();
            Command::Assemble { out, parts }
        }
        Some(Sub::Sheet(f)) => {
            let (out, columns, images) = f.resolve();
            Command::Sheet {
                out,
                columns,
                images,
            }
        }
        Some(Sub::Plan { scene }) => Command::Plan { scene },
        Some(Sub::Explain(f)) => Command::Explain(f.resolve()?),
        Some(Sub::Edit(f)) => {
            let matches = matches
                .subcommand_matches("edit")
                .expect("clap matched the edit subcommand");
            Command::Edit(f.resolve(matches, subcommand)?)
        }
        Some(Sub::Bench(f)) => Command::Bench(f.resolve()),
        Some(Sub::Study(f)) => Command::Study(f.resolve()),
        Some(Sub::New { scene }) => Command::New { scene },
        Some(Sub::Schema) => Command::Schema,
        Some(Sub::Completions { shell }) => Command::Completions(shell),
        Some(Sub::Man { subcommand, dir }) => Command::Man { subcommand, dir },
        Some(Sub::InstallDesktop { uninstall }) => Command::InstallDesktop { uninstall },
        Some(Sub::Lsp) => Command::Lsp,
    })
}

/// The command line's definition, as clap reads it: what the shell
/// completions and the man pages are generated from.
pub fn definition() -> clap::Command {
    Cli::command()
}

#[cfg(test)]
mod tests {
    use super::spelling::edit_distance;
    use super::*;
    use crate::cli::edit::EditArg;

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
        Cli::command().debug_assert();
        let names: Vec<_> = Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_owned())
            .collect();
        assert_eq!(names, *SUBCOMMANDS);
    }

    /// A new subcommand needs its line in the usage too: the one list
    /// the compiler does not check.
    #[test]
    fn the_usage_names_every_subcommand() {
        for name in SUBCOMMANDS.iter() {
            assert!(USAGE.contains(name), "the usage does not name {name}");
        }
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
            help.starts_with(USAGE) && help.contains("-o, --out <FILE>"),
            "{help}"
        );
        assert!(
            help.contains("also -out") && help.contains("Exit status"),
            "{help}"
        );
        let Ok(Command::Print(help)) = p(&["plan", "-h"]) else {
            panic!()
        };
        assert!(help.contains("Usage: rayoflight plan <SCENE>"), "{help}");
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
            Command::ExportPov {
                scene: "s.xml".into(),
                out: Some("s.pov".into())
            }
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
            Command::Plan {
                scene: PathBuf::from("s.xml")
            }
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
