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

use super::edit::{self, EditArg};
use clap::builder::{PossibleValue, TypedValueParser};
use clap::error::{ContextKind, ContextValue, ErrorKind};
use clap::{ArgMatches, Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueHint};
use rayoflight::render::region::Region;
use rayoflight::render::request::RenderRequest;
use rayoflight::render::{self, Method, Pass};
use rayoflight::scene::edit::{EditError, NewElement};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

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
    Split(SplitArgs),
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
    Explain(ExplainArgs),
    /// `edit scene.xml [--set PATH=VALUE]… [--remove PATH]… [--add KIND]…`.
    Edit(EditArgs),
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

#[derive(Debug, Clone, PartialEq, Default)]
pub struct RenderArgs {
    /// The scene file; `None` means the built-in example (app only).
    pub scene: Option<PathBuf>,
    pub out: Option<PathBuf>,
    pub time: bool,
    pub no_gui: bool,
    /// `--method`, `--aa`, `--threads` and `--region`.
    pub request: RenderRequest,
    /// `--set`: values changed in memory before rendering, in order.
    pub edits: Vec<EditArg>,
    /// `--quiet`: no progress bar.
    pub quiet: bool,
    /// `--pass`: what to write (default: the image).
    pub pass: Pass,
}

/// `rayoflight explain`: which pixel of which render.
#[derive(Debug, Clone, PartialEq)]
pub struct ExplainArgs {
    pub scene: PathBuf,
    pub x: u32,
    pub y: u32,
    pub json: bool,
    /// The render's method and anti-aliasing (threads do not matter).
    pub request: RenderRequest,
    /// `--set`: values changed in memory first, in order.
    pub edits: Vec<EditArg>,
}

/// `rayoflight split`: which render to split, into how many regions.
#[derive(Debug, Clone, PartialEq)]
pub struct SplitArgs {
    pub scene: PathBuf,
    pub tasks: usize,
    /// The render's method and anti-aliasing (they change the cost).
    pub request: RenderRequest,
    /// `--set`: values changed in memory first, in order.
    pub edits: Vec<EditArg>,
}

/// `rayoflight edit`: what to change in a scene file, and where to write it.
#[derive(Debug, Clone, PartialEq)]
pub struct EditArgs {
    pub scene: PathBuf,
    /// Where the edited scene goes; `None`: the scene file itself.
    pub out: Option<PathBuf>,
    /// The `--set`, `--remove` and `--add`, in the order given; never empty.
    pub edits: Vec<EditArg>,
}

impl RenderArgs {
    /// Whether the command asks for headless work: any of `-out`, `-time`,
    /// `--no-gui`, `--quiet`, `--threads`, `--aa`, `--method`, `--region`,
    /// `--set`, `--pass`: every flag but the scene is the command line's.
    /// In the GUI build, anything else opens the app (the headless build
    /// never asks).
    #[cfg_attr(not(feature = "gui"), allow(dead_code))]
    pub fn headless(&self) -> bool {
        self.out.is_some()
            || self.time
            || self.no_gui
            || self.quiet
            || self.request != RenderRequest::default()
            || !self.edits.is_empty()
            || self.pass != Pass::Final
    }
}

/// A command line that does not parse, or an edit the scene refuses: exit
/// status 2.
#[derive(Debug, Clone, PartialEq)]
pub enum UsageError {
    /// No scene where the command needs one: the usage is printed.
    NoScene,
    /// Arguments that do not fit the command. `command` is the subcommand
    /// whose `--help` to point to (`None`: the top-level one).
    Invalid {
        message: String,
        command: Option<&'static str>,
    },
    /// A `--set`, `--remove` or `--add` whose path or value the edit engine
    /// refuses, for this scene (`object[5]: the scene has 3 objects`).
    Edit { scene: PathBuf, error: EditError },
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

/// The render's flags: `rayoflight [-time] scene.xml [-out image.png] …`.
#[derive(Args, Debug)]
struct RenderFlags {
    /// The scene file (none: the app opens on the built-in example).
    scene: Option<PathBuf>,
    /// The image to write (also -out); the extension picks the format.
    ///
    /// png, jpg, jpeg, gif, bmp, tga, ppm, tif, tiff, qoi, webp, or exr
    /// (32-bit floats, unclamped). Default: the scene's path with the
    /// extension .png.
    #[arg(short, long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print the render time (prepare + trace) as 'render: N ns' (also
    /// -time).
    #[arg(long)]
    time: bool,
    /// Render threads [default: one per core]
    #[arg(long, value_name = "N", value_parser = threads, allow_negative_numbers = true)]
    threads: Option<usize>,
    /// N×N rays per pixel, 1 to 16 [default: 1, the pixel centre]
    #[arg(long, value_name = "N", value_parser = aa, allow_negative_numbers = true)]
    aa: Option<u32>,
    /// Render with this method instead of auto (see docs/study.md).
    #[arg(long, value_name = "NAME", value_parser = Named::new(method, method_names))]
    method: Option<Method>,
    /// Never open a window (the headless build never does).
    #[arg(long)]
    no_gui: bool,
    /// Render with a value changed (object[2].material.ka=0.5), in memory
    /// only: the scene file is not written.
    ///
    /// Repeatable; the paths are listed by 'rayoflight edit --help'.
    #[arg(long, value_name = "PATH=VALUE", value_parser = path_value)]
    set: Vec<(String, String)>,
    /// No progress bar on stderr.
    ///
    /// One shows on a terminal for renders over a second: percentage,
    /// rays/s, time left.
    #[arg(short, long)]
    quiet: bool,
    /// Write one render pass instead of the image.
    ///
    /// final (default), ambient, diffuse, specular, reflection (the camera
    /// ray's terms; in .exr they add up to final), normal, depth, object.
    #[arg(long, value_name = "NAME", value_parser = Named::new(pass, pass_names))]
    pass: Option<Pass>,
    /// Render only this rectangle of the image, into the PNG part -out
    /// names.
    ///
    /// Pixels from the top left, X1 and Y1 excluded; -out is required.
    /// The part's pixels are the whole render's, and it records where it
    /// belongs: 'rayoflight assemble' puts parts together.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = region, allow_hyphen_values = true)]
    region: Option<Region>,
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
    Split(SplitFlags),
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
    Assemble(AssembleFlags),
    /// A contact sheet: the images side by side in a grid, each named.
    ///
    /// Each picture sits in a cell as large as the largest, its file name
    /// (its end, when too long) under it: the renders of a --set sweep at
    /// a glance.
    #[command(override_usage = "rayoflight sheet -out sheet.png [--columns N] IMAGE…")]
    Sheet(SheetFlags),
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
    Explain(ExplainFlags),
    /// Time the bench scenes, against POV-Ray when it is installed.
    ///
    /// Also thread scaling, cost against object count and peak memory.
    Bench(BenchFlags),
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
    Edit(EditFlags),
    /// Speed against accuracy: every render method on the study scenes.
    ///
    /// Measures each method (f32, textbook quadratic, offsets,
    /// anti-aliasing, depth cut, early stop, draft, auto) against the
    /// default image, on the built-in study scenes or on the scene files
    /// given. Prints a table on stdout and writes DIR/study.csv, the chart
    /// DIR/study.png and a picture of each failure. See docs/study.md.
    Study(StudyFlags),
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

#[derive(Args, Debug)]
struct ExplainFlags {
    /// The scene file.
    scene: PathBuf,
    /// The pixel's column, 0 at the left.
    #[arg(value_name = "X", value_parser = pixel, allow_negative_numbers = true)]
    x: u32,
    /// The pixel's row, 0 at the top.
    #[arg(value_name = "Y", value_parser = pixel, allow_negative_numbers = true)]
    y: u32,
    /// Print one JSON object: "rgb8", "rgb", "hits" (each with "object",
    /// 1-based or null for a miss, "t", "point", "normal", "terms").
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    render: RenderOf,
}

/// Which render a subcommand speaks of (`explain`, `split`): the scene's
/// values changed, the anti-aliasing and the method.
#[derive(Args, Debug)]
struct RenderOf {
    /// The render with this value changed, in memory only.
    #[arg(long, value_name = "PATH=VALUE", value_parser = path_value)]
    set: Vec<(String, String)>,
    /// N×N rays per pixel, 1 to 16.
    #[arg(long, value_name = "N", value_parser = aa, allow_negative_numbers = true)]
    aa: Option<u32>,
    /// The study method the render uses instead of auto.
    #[arg(long, value_name = "NAME", value_parser = Named::new(method, method_names))]
    method: Option<Method>,
}

impl RenderOf {
    /// The request and the edits, read against `scene`'s path.
    fn resolve(self, scene: &Path) -> Result<(RenderRequest, Vec<EditArg>), UsageError> {
        let given = self.set.into_iter().map(|(p, v)| Given::Set(p, v));
        let request = RenderRequest {
            method: self.method,
            aa: self.aa,
            ..RenderRequest::default()
        };
        Ok((request, edit_args(given.collect(), scene)?))
    }
}

#[derive(Args, Debug)]
struct SplitFlags {
    /// The scene file.
    scene: PathBuf,
    /// How many regions (tasks), at least 1.
    #[arg(
        long,
        short = 'n',
        value_name = "N",
        value_parser = tasks,
        required = true,
        allow_hyphen_values = true
    )]
    tasks: usize,
    #[command(flatten)]
    render: RenderOf,
}

#[derive(Args, Debug)]
struct AssembleFlags {
    /// The image to write (PNG).
    #[arg(short, long, value_name = "FILE", required = true)]
    out: PathBuf,
    /// The parts, in any order.
    #[arg(value_name = "PART", required = true)]
    parts: Vec<PathBuf>,
}

#[derive(Args, Debug)]
struct SheetFlags {
    /// The sheet to write; its extension picks the format.
    #[arg(short, long, value_name = "FILE", required = true)]
    out: PathBuf,
    /// Pictures a row [default: as square a grid as the count allows]
    #[arg(long, value_name = "N", value_parser = columns, allow_hyphen_values = true)]
    columns: Option<usize>,
    /// The images, in the order to show them.
    #[arg(value_name = "IMAGE", required = true)]
    images: Vec<PathBuf>,
}

#[derive(Args, Debug)]
struct EditFlags {
    /// The scene file.
    scene: PathBuf,
    /// Set a value: object[2].material.ka=0.5, model.type=phong.
    #[arg(long, value_name = "PATH=VALUE", value_parser = path_value)]
    set: Vec<(String, String)>,
    /// Remove an element: object[2], light[1], object[1].transformation[2].
    #[arg(long, value_name = "PATH")]
    remove: Vec<String>,
    /// Add an element with default values, after the last of its kind:
    /// sphere, plane or light.
    #[arg(long, value_name = "KIND", value_parser = Named::new(kind, kind_names))]
    add: Vec<String>,
    /// Write the edited scene to FILE instead of the scene file.
    #[arg(short, long, value_name = "FILE")]
    out: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct BenchFlags {
    /// Render threads [default: one per core]
    #[arg(long, value_name = "N", value_parser = threads, allow_negative_numbers = true)]
    threads: Option<usize>,
    /// Runs per measurement; the median is reported.
    #[arg(long, value_name = "K", default_value_t = 3, value_parser = runs, allow_negative_numbers = true)]
    runs: usize,
    /// Also write the results as CSV to FILE (also --out).
    #[arg(long, short = 'o', visible_alias = "out", value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Do not render with POV-Ray, even where it is installed.
    #[arg(long)]
    no_pov: bool,
    /// No progress bar on stderr.
    #[arg(short, long)]
    quiet: bool,
    /// The side of the image split into 64 regions and assembled, in
    /// pixels (0: skip that section).
    #[arg(
        long,
        value_name = "PIXELS",
        default_value_t = 16000,
        value_parser = split_size,
        allow_negative_numbers = true
    )]
    split_size: u32,
    /// Spheres in the big scene loaded, checked and prepared against
    /// xmllint's streaming parse of the same file (0: skip that section).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1_000_000,
        value_parser = big_spheres,
        allow_negative_numbers = true
    )]
    big_spheres: usize,
    /// The big section's own child: the app without its window on FILE,
    /// printing its peak memory after each stage.
    #[arg(long, value_name = "FILE", hide = true)]
    app_document: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct StudyFlags {
    /// Where study.csv, study.png and the failure pictures go (created).
    #[arg(short, long, value_name = "DIR", default_value = "study")]
    out: PathBuf,
    /// Runs per measurement; the median is reported.
    #[arg(long, value_name = "K", default_value_t = 3, value_parser = runs, allow_negative_numbers = true)]
    runs: usize,
    /// Render threads [default: one per core]
    #[arg(long, value_name = "N", value_parser = threads, allow_negative_numbers = true)]
    threads: Option<usize>,
    /// Scene files to study [default: the built-in study scenes]
    #[arg(value_name = "SCENE")]
    scenes: Vec<PathBuf>,
    /// No progress bar on stderr.
    #[arg(short, long)]
    quiet: bool,
}

// Value parsers. Their messages complete "--flag …, not "value"" (see
// `clap_message`).

fn threads(text: &str) -> Result<usize, String> {
    let max = rayoflight::render::max_threads();
    text.parse()
        .ok()
        .filter(|n| (1..=max).contains(n))
        .ok_or_else(|| format!("expects an integer from 1 to {max} (four per core)"))
}

fn runs(text: &str) -> Result<usize, String> {
    text.parse()
        .ok()
        .filter(|n| (1..=1000).contains(n))
        .ok_or_else(|| "expects an integer from 1 to 1000".to_owned())
}

/// The bench's split section: 0 (skipped), or a square image of at least
/// a pixel per task and at most the render's limit of pixels.
fn split_size(text: &str) -> Result<u32, String> {
    let tasks = super::bench::SPLIT_TASKS as u64;
    let (min, max) = (
        tasks.isqrt() + u64::from(tasks.isqrt().pow(2) < tasks),
        rayoflight::scene::MAX_PIXELS.isqrt(),
    );
    text.parse::<u64>()
        .ok()
        .filter(|&n| n == 0 || (min..=max).contains(&n))
        .and_then(|n| u32::try_from(n).ok())
        .ok_or_else(|| format!("expects 0 (skip the section) or a side from {min} to {max} pixels"))
}

/// The bench's big scene: 0 (skipped), or up to four million spheres
/// (about 930 MB of XML, under the 1 GiB a scene file may take).
fn big_spheres(text: &str) -> Result<usize, String> {
    text.parse::<usize>()
        .ok()
        .filter(|&n| n <= super::bench::MAX_BIG_SPHERES)
        .ok_or_else(|| {
            format!(
                "expects 0 (skip the section) or a count up to {}",
                super::bench::MAX_BIG_SPHERES
            )
        })
}

fn tasks(text: &str) -> Result<usize, String> {
    text.trim()
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| "expects a whole number of tasks, at least 1".to_owned())
}

fn columns(text: &str) -> Result<usize, String> {
    text.trim()
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| "expects a whole number, at least 1".to_owned())
}

fn aa(text: &str) -> Result<u32, String> {
    let max = rayoflight::render::MAX_AA;
    text.parse()
        .ok()
        .filter(|n| (1..=max).contains(n))
        .ok_or_else(|| format!("expects an integer from 1 to {max}"))
}

fn path_value(text: &str) -> Result<(String, String), String> {
    text.split_once('=')
        .map(|(path, value)| (path.to_owned(), value.to_owned()))
        .ok_or_else(|| "expects PATH=VALUE, such as object[1].material.ka=0.5".to_owned())
}

fn region(text: &str) -> Result<Region, String> {
    Region::parse(text).map_err(|e| e.to_string())
}

fn pixel(text: &str) -> Result<u32, String> {
    text.parse()
        .map_err(|_| "expects a pixel number: 0, 1, 2, … from the image's top left".to_owned())
}

fn pass(text: &str) -> Result<Pass, String> {
    Pass::named(text).ok_or_else(|| {
        let names: Vec<_> = Pass::ALL.iter().map(|p| p.name()).collect();
        format!("expects one of {}", names.join(", "))
    })
}

fn pass_names() -> Vec<&'static str> {
    Pass::ALL.iter().map(|p| p.name()).collect()
}

fn method(text: &str) -> Result<Method, String> {
    render::method(text).ok_or_else(|| format!("expects one of {}", method_names().join(", ")))
}

fn method_names() -> Vec<&'static str> {
    render::methods().iter().map(|m| m.name).collect()
}

/// `--add`'s kind, read (and refused, naming the scene) with the edits.
fn kind(text: &str) -> Result<String, String> {
    Ok(text.to_owned())
}

fn kind_names() -> Vec<&'static str> {
    NewElement::ALL.iter().map(|k| k.name()).collect()
}

fn subcommand(text: &str) -> Result<String, String> {
    match SUBCOMMANDS.contains(&text) {
        true => Ok(text.to_owned()),
        false => Err(format!("expects one of {}", SUBCOMMANDS.join(", "))),
    }
}

fn subcommand_names() -> Vec<&'static str> {
    SUBCOMMANDS.to_vec()
}

/// A value parser that also names the values it takes, for the shell
/// completions, the help and the man pages; parsing (and its message)
/// stays the function's.
#[derive(Clone)]
struct Named<T> {
    parse: fn(&str) -> Result<T, String>,
    names: fn() -> Vec<&'static str>,
}

impl<T> Named<T> {
    fn new(parse: fn(&str) -> Result<T, String>, names: fn() -> Vec<&'static str>) -> Named<T> {
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
        Some(Sub::Split(f)) => {
            let (request, edits) = f.render.resolve(&f.scene)?;
            Command::Split(SplitArgs {
                scene: f.scene,
                tasks: f.tasks,
                request,
                edits,
            })
        }
        Some(Sub::Assemble(f)) => Command::Assemble {
            out: f.out,
            parts: f.parts,
        },
        Some(Sub::Sheet(f)) => Command::Sheet {
            out: f.out,
            columns: f.columns,
            images: f.images,
        },
        Some(Sub::Plan { scene }) => Command::Plan { scene },
        Some(Sub::Explain(e)) => {
            let (request, edits) = e.render.resolve(&e.scene)?;
            Command::Explain(ExplainArgs {
                scene: e.scene,
                x: e.x,
                y: e.y,
                json: e.json,
                request,
                edits,
            })
        }
        Some(Sub::Edit(e)) => {
            let matches = matches
                .subcommand_matches("edit")
                .expect("clap matched the edit subcommand");
            let given = in_order(matches, e.set, e.remove, e.add);
            if given.is_empty() {
                return Err(UsageError::Invalid {
                    message: "nothing to do: give at least one --set, --remove or --add".to_owned(),
                    command: subcommand,
                });
            }
            Command::Edit(EditArgs {
                edits: edit_args(given, &e.scene)?,
                scene: e.scene,
                out: e.out,
            })
        }
        Some(Sub::Bench(b)) => Command::Bench(super::bench::BenchArgs {
            threads: b.threads.unwrap_or_else(rayoflight::render::all_cores),
            runs: b.runs,
            csv: b.csv,
            pov: !b.no_pov,
            quiet: b.quiet,
            split_size: b.split_size,
            big_spheres: b.big_spheres,
            app_document: b.app_document,
        }),
        Some(Sub::Study(s)) => Command::Study(super::study::StudyArgs {
            out: s.out,
            runs: s.runs,
            threads: s.threads,
            scenes: s.scenes,
            quiet: s.quiet,
        }),
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

fn render_args(r: RenderFlags) -> Result<RenderArgs, UsageError> {
    let edits = match &r.scene {
        Some(scene) => {
            let given = r.set.into_iter().map(|(p, v)| Given::Set(p, v));
            edit_args(given.collect(), scene)?
        }
        // --set makes the render headless, which needs a scene.
        None if !r.set.is_empty() => return Err(UsageError::NoScene),
        None => Vec::new(),
    };
    if r.region.is_some() {
        let invalid = |message: &str| UsageError::Invalid {
            message: message.to_owned(),
            command: None,
        };
        if r.pass.is_some_and(|p| p != Pass::Final) {
            return Err(invalid(
                "--region renders the image: it cannot be used with --pass",
            ));
        }
        let png = |out: &Path| {
            out.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("png"))
        };
        match r.out.as_deref() {
            None => {
                return Err(invalid(
                    "--region needs -out PART.png: written to the scene's own image \
                     path, a part would replace its whole render",
                ));
            }
            Some(out) if !png(out) => {
                return Err(invalid(
                    "--region writes a PNG part, which records where it belongs for \
                     'rayoflight assemble': -out must end in .png",
                ));
            }
            Some(_) => {}
        }
    }
    Ok(RenderArgs {
        scene: r.scene,
        out: r.out,
        time: r.time,
        no_gui: r.no_gui,
        request: RenderRequest {
            method: r.method,
            aa: r.aa,
            threads: r.threads,
            region: r.region,
        },
        edits,
        quiet: r.quiet,
        pass: r.pass.unwrap_or_default(),
    })
}

/// An edit flag as given, before its path is read.
enum Given {
    Set(String, String),
    Remove(String),
    Add(String),
}

/// The `--set`, `--remove` and `--add` of `matches`, in the order given on
/// the command line: clap collects each flag's values apart, and their
/// indices put them back in order.
fn in_order(
    matches: &ArgMatches,
    set: Vec<(String, String)>,
    remove: Vec<String>,
    add: Vec<String>,
) -> Vec<Given> {
    let indices = |id: &str| matches.indices_of(id).into_iter().flatten();
    let mut given: Vec<(usize, Given)> = Vec::new();
    given.extend(
        indices("set")
            .zip(set)
            .map(|(i, (p, v))| (i, Given::Set(p, v))),
    );
    given.extend(
        indices("remove")
            .zip(remove)
            .map(|(i, p)| (i, Given::Remove(p))),
    );
    given.extend(indices("add").zip(add).map(|(i, k)| (i, Given::Add(k))));
    given.sort_by_key(|(i, _)| *i);
    given.into_iter().map(|(_, g)| g).collect()
}

/// The edits read: their paths, values and kinds checked (not yet against
/// the scene).
fn edit_args(given: Vec<Given>, scene: &Path) -> Result<Vec<EditArg>, UsageError> {
    given
        .into_iter()
        .map(|g| match g {
            Given::Set(path, value) => EditArg::set(&path, &value),
            Given::Remove(path) => EditArg::remove(&path),
            Given::Add(kind) => EditArg::add(&kind),
        })
        .collect::<Result<_, _>>()
        .map_err(|error| UsageError::Edit {
            scene: scene.to_owned(),
            error,
        })
}

/// The arguments with the single-dash `-out` and `-time` spelled `--out` and
/// `--time` (up to a `--`, after which every argument is a file).
fn brief_spellings(args: impl IntoIterator<Item = OsString>) -> Vec<OsString> {
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
fn unknown_single_dash_word(args: &[OsString], subcommand: Option<&str>) -> Option<String> {
    let mut root = Cli::command();
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
fn edit_distance(a: &str, b: &str) -> usize {
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

/// The subcommands' names, as clap derives them from `Sub`.
const SUBCOMMANDS: [&str; 15] = [
    "split",
    "assemble",
    "sheet",
    "export-pov",
    "plan",
    "explain",
    "bench",
    "edit",
    "study",
    "new",
    "schema",
    "completions",
    "install-desktop",
    "lsp",
    "man",
];

/// The subcommand the arguments run, if any: only the first argument can
/// name one (`args_conflicts_with_subcommands`).
fn subcommand_named(args: &[OsString]) -> Option<&'static str> {
    let first = args.first()?.to_str()?;
    SUBCOMMANDS.into_iter().find(|name| *name == first)
}

/// One line for a clap error, in the words the hand-written parser used
/// ("unknown flag '--frobnicate'", "--aa expects an integer from 1 to 16,
/// not \"17\""); clap's own text spans several lines.
fn clap_message(e: &clap::Error) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(names, SUBCOMMANDS);
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
