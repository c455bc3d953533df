//! `rayoflight study [--out DIR] [--runs K] [--threads N] [scene.xml…]`:
//! every study method on every scene (the built-in study scenes when none
//! are given), a table on stdout, DIR/study.csv, the chart DIR/study.png
//! and, for each failing case, DIR/fail-<scene>-<method>.png (method |
//! reference | difference ×8).
//!
//! Its flags, as clap reads them, are here too ([`StudyFlags`]), resolved
//! into the [`StudyArgs`] it runs with.

use super::failure::Failure;
use super::progress::{self, Steps};
use super::subcommand::Subcommand;
use super::usage::UsageError;
use super::values::{runs, threads};
use clap::Args;
use rayoflight::study::chart;
use rayoflight::system::escape::visible;
use rayoflight::system::files;
use rayoflight::{output, study};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StudyArgs {
    /// Where study.csv, study.png and the failure pictures go (created);
    /// default `study/`.
    pub out: PathBuf,
    pub runs: usize,
    pub threads: Option<usize>,
    /// User scenes; empty means the built-in ones.
    pub scenes: Vec<PathBuf>,
    /// No progress bar.
    pub quiet: bool,
}

/// Runs the study; the report goes to stdout as it comes, a progress bar
/// (`steps`: one step per scene and method) to stderr.
fn run_study(args: &StudyArgs, steps: &Steps) -> Result<(), String> {
    let out = |text: &str| steps.print(text);
    let scenes = if args.scenes.is_empty() {
        study::builtin_scenes()
    } else {
        study::load_scenes(&args.scenes)
    }
    .map_err(|e| e.to_string())?;
    // Every scene fits in memory, asked before anything is printed.
    for scene in &scenes {
        study::check_memory(scene).map_err(|e| e.to_string())?;
    }
    // Fail on an unusable output folder before the long part.
    rayoflight::system::files::make_folders(&args.out)
        .map_err(|e| format!("{}: cannot create the folder: {e}", args.out.display()))?;
    let (csv, png) = (args.out.join("study.csv"), args.out.join("study.png"));
    for file in [&csv, &png] {
        files::check_file_target(file).map_err(|e| e.to_string())?;
    }
    let methods = rayoflight::render::methods();
    out(&format!(
        "RayOfLight study: {} methods × {} scenes, median of {} runs; reference: the default \
         image (aa methods: the default supersampled 16×16); failed: within 1 < {}\n\n",
        methods.len(),
        scenes.len(),
        args.runs,
        study::FAIL_BELOW
    ))?;
    out(&format!(
        "{:<18} {:<15} {:>10} {:>11} {:>4} {:>9} {:>9}  {}\n",
        "scene", "method", "time ms", "rays", "max", "mean", "within 1", "failed"
    ))?;
    let start = Instant::now();
    // The first picture or line that could not be written, reported once
    // the study returns (its callback cannot stop it).
    let mut picture_error = None;
    let mut print_error = None;
    steps.set_total((scenes.len() * methods.len()) as u64);
    let mut done = 0;
    let rows = study::run(
        &scenes,
        &methods,
        args.runs,
        args.threads,
        &rayoflight::render::Cancel::never(),
        &study::StudyProgress::default(),
        &mut |r, image, reference| {
            if r.failed && picture_error.is_none() {
                let path = args.out.join(chart::failure_file_name(r));
                if let Err(e) = output::save(&chart::side_by_side(image, reference), &path) {
                    picture_error = Some(e.to_string());
                }
            }
            // A scene's name is a file's: one line whatever it holds.
            let line = out(&format!(
                "{:<18} {:<15} {:>10.2} {:>11} {:>4} {:>9.4} {:>9.4}  {}\n",
                visible(&r.scene, false),
                r.method,
                r.time.as_secs_f64() * 1e3,
                r.rays,
                r.max_diff,
                r.mean_diff,
                r.within1,
                if r.failed { "FAILED" } else { "" }
            ));
            if let Err(e) = line {
                print_error.get_or_insert(e);
            }
            done += 1;
            steps.step(done, &format!("{} {}", r.scene, r.method));
        },
    )
    .map_err(|e| e.to_string())?;
    if let Some(e) = print_error.or(picture_error) {
        return Err(e);
    }
    files::write_atomic(&csv, study::csv(&rows).as_bytes()).map_err(|e| e.to_string())?;
    let picture = chart::chart(&rows).map_err(|e| e.to_string())?;
    output::save(&picture, &png).map_err(|e| e.to_string())?;
    let failed: Vec<String> = rows
        .iter()
        .filter(|r| r.failed)
        .map(|r| {
            format!(
                "{} on {} ({:.4})",
                r.method,
                visible(&r.scene, false),
                r.within1
            )
        })
        .collect();
    out(&format!(
        "\n{} failures{}{}\nwrote {}, {} and {} failure pictures in {:.1} s\n",
        failed.len(),
        if failed.is_empty() { "" } else { ": " },
        failed.join(", "),
        visible(&csv.display().to_string(), false),
        visible(&png.display().to_string(), false),
        failed.len(),
        start.elapsed().as_secs_f64()
    ))
}

// ----- the command line -----

/// Speed against accuracy: every render method on the study scenes.
///
/// Measures each method (f32, textbook quadratic, offsets,
/// anti-aliasing, depth cut, early stop, draft, auto) against the
/// default image, on the built-in study scenes or on the scene files
/// given. Prints a table on stdout and writes DIR/study.csv, the chart
/// DIR/study.png and a picture of each failure. See docs/study.md.
#[derive(Args, Debug)]
#[command(
    override_usage = "rayoflight study [--out DIR] [--runs K] [--threads N] [--quiet] [scene.xml…]"
)]
pub(super) struct StudyFlags {
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

impl Subcommand for StudyFlags {
    type Args = StudyArgs;

    fn resolve(self, _: &clap::ArgMatches) -> Result<StudyArgs, UsageError> {
        Ok(StudyArgs {
            out: self.out,
            runs: self.runs,
            threads: self.threads,
            scenes: self.scenes,
            quiet: self.quiet,
        })
    }

    fn prints(_: &StudyArgs) -> bool {
        true
    }

    fn run(args: StudyArgs, _: fn() -> clap::Command) -> Result<(), Failure> {
        let steps = Steps::new(progress::wanted(args.quiet));
        run_study(&args, &steps).map_err(Failure::Error)
    }
}
