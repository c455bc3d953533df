//! The command line: `rayoflight [-time] scene.xml [-out image.png]` and its
//! subcommands. This is the binary's edge: it turns typed library errors into
//! one-line messages on stderr and exit statuses (0 success, 1 a scene,
//! render or output error, 2 a usage error).

mod args;
mod bench;
mod cluster;
mod edit;
mod explain;
mod generated;
mod lsp;
mod progress;
mod stdout;
mod study;

use args::{Command, RenderArgs, USAGE, UsageError};
use edit::EditArgs;
use rayoflight::cluster::part::Part;
use rayoflight::render::measure;
use rayoflight::scene::edit::{EditError, Edited};
use rayoflight::scene::{merge, splice};
use rayoflight::system::{files, interrupt, resources};
use rayoflight::{output, pov, render, scene};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// A failure at the edge: what to print and which status to exit with.
enum Failure {
    /// Exit status 2.
    Usage(UsageError),
    /// A scene, render or output error, as printed: exit status 1.
    Error(String),
}

impl From<UsageError> for Failure {
    fn from(e: UsageError) -> Failure {
        Failure::Usage(e)
    }
}

fn fail(e: impl std::fmt::Display) -> Failure {
    Failure::Error(e.to_string())
}

/// A usage error (exit 2) found once the scene is read.
fn usage(message: String) -> Failure {
    Failure::Usage(UsageError::Invalid {
        message,
        command: None,
    })
}

pub fn main() -> ExitCode {
    rayoflight::system::allocator::tune();
    let code = report(run(std::env::args_os().skip(1)));
    // A signal that stopped the work: the status a shell gives a process
    // the signal ended (130 for Ctrl+C, 143 for SIGTERM).
    match interrupt::caught() {
        Some(signal) => ExitCode::from(128u8.saturating_add(signal as u8)),
        None => code,
    }
}

/// Prints what failed, and gives the exit status.
fn report(result: Result<(), Failure>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(UsageError::NoScene)) => {
            eprintln!("{USAGE}");
            ExitCode::from(2)
        }
        Err(Failure::Usage(UsageError::Invalid { message, command })) => {
            let help = match command {
                Some(name) => format!("rayoflight {name} --help"),
                None => "rayoflight --help".to_owned(),
            };
            error_line(&format!("rayoflight: {message}; see '{help}'"));
            ExitCode::from(2)
        }
        Err(Failure::Usage(UsageError::Edit { scene, error })) => {
            error_line(&format!("rayoflight: {}: {error}", scene.display()));
            ExitCode::from(2)
        }
        Err(Failure::Error(msg)) => {
            error_line(&msg);
            ExitCode::from(1)
        }
    }
}

fn run(args: impl IntoIterator<Item = std::ffi::OsString>) -> Result<(), Failure> {
    let command = args::parse(args)?;
    interrupt::writes_past_the_size_limit_fail().map_err(fail)?;
    // SIGINT, SIGTERM and SIGHUP stop a render or a write cleanly (the
    // app, which saves unsaved edits on them, has its own handlers).
    if !matches!(&command, Command::Render(r) if opens_app(r)) {
        interrupt::install().map_err(fail)?;
    }
    // What prints on stdout finds it closed before any work, not after.
    if command.prints() && stdout::closed_at_start() {
        return Err(Failure::Error(stdout::CLOSED.to_owned()));
    }
    match command {
        Command::Print(text) => print_line(text.trim_end()),
        Command::ExportPov { scene, out } => export_pov(&scene, out),
        Command::Edit(args) => edit_scene(&args),
        Command::Explain(args) => explain::run(&args),
        Command::Split(args) => cluster::split(&args),
        Command::Assemble { out, parts } => cluster::assemble(&out, &parts),
        Command::Sheet {
            out,
            columns,
            images,
        } => cluster::sheet(&out, columns, &images),
        Command::Plan { scene } => {
            let scene = scene::load(&scene).map_err(fail)?;
            for d in render::auto(&scene).decisions {
                print_line(&format!("{}: {}\n  {}", d.topic, d.choice, d.reason))?;
            }
            Ok(())
        }
        Command::Bench(args) => {
            let steps = progress::Steps::new(progress::wanted(args.quiet));
            bench::run(&args, &steps).map_err(Failure::Error)
        }
        Command::Study(args) => {
            let steps = progress::Steps::new(progress::wanted(args.quiet));
            study::run(&args, &steps).map_err(Failure::Error)
        }
        Command::Render(r) => render_scene(r),
        Command::New { scene } => new_scene(&scene),
        Command::InstallDesktop { uninstall } => install_desktop(uninstall),
        Command::Lsp => lsp::run().map_err(Failure::Error),
        Command::Schema => print_line(rayoflight::scene::schema::xsd().trim_end()),
        Command::Completions(shell) => {
            stdout::write(&generated::completions(shell)).map_err(Failure::Error)
        }
        Command::Man {
            subcommand,
            dir: None,
        } => {
            let page = generated::man_page(subcommand.as_deref()).map_err(usage)?;
            stdout::write(&page).map_err(Failure::Error)
        }
        Command::Man { dir: Some(dir), .. } => {
            files::make_folders(&dir)
                .map_err(|e| Failure::Error(format!("{}: {e}", dir.display())))?;
            for (name, page) in generated::man_pages().map_err(Failure::Error)? {
                files::write_atomic(&dir.join(name), page.as_bytes()).map_err(fail)?;
            }
            Ok(())
        }
    }
}

/// `rayoflight install-desktop [--uninstall]`: what was done, on stderr.
fn install_desktop(uninstall: bool) -> Result<(), Failure> {
    use rayoflight::desktop;
    if !cfg!(feature = "gui") {
        return Err(Failure::Error(
            "rayoflight: this build has no desktop app (built without the gui feature): \
             nothing to install"
                .to_owned(),
        ));
    }
    let home = desktop::data_home().map_err(fail)?;
    let done = match uninstall {
        false => {
            let exec = std::env::current_exe()
                .and_then(std::fs::canonicalize)
                .map_err(|e| Failure::Error(format!("rayoflight: where is this binary? {e}")))?;
            let done = desktop::install(&home, &exec).map_err(fail)?;
            eprintln!(
                "installed under {}: the desktop entry (running {}), {} icons and the scene type",
                home.display(),
                exec.display(),
                desktop::ICON_PNGS.len() + 1
            );
            done
        }
        true => {
            let done = desktop::uninstall(&home).map_err(fail)?;
            match done.files.len() {
                0 => eprintln!(
                    "nothing to remove: install-desktop wrote nothing under {}",
                    home.display()
                ),
                n => eprintln!(
                    "removed the {n} files install-desktop wrote under {}",
                    home.display()
                ),
            }
            for kept in &done.kept {
                eprintln!(
                    "left {}: it changed since install-desktop wrote it",
                    rayoflight::system::escape::visible(&kept.display().to_string(), false)
                );
            }
            done
        }
    };
    for ran in &done.ran {
        eprintln!("ran {ran}");
    }
    for tool in &done.missing {
        eprintln!(
            "{tool} is not installed: the desktop may see the change only after its next login"
        );
    }
    Ok(())
}

/// `rayoflight new scene.xml`: the built-in example, to start from, in a
/// file that did not exist (never over one: its text was not read), or on
/// stdout for `-`.
fn new_scene(path: &Path) -> Result<(), Failure> {
    if path.as_os_str() == "-" {
        return stdout::write(rayoflight::EXAMPLE_SCENE).map_err(Failure::Error);
    }
    files::write_new(path, rayoflight::EXAMPLE_SCENE.as_bytes()).map_err(fail)
}

/// Prints a line to stdout ([`stdout::write`]).
fn print_line(text: &str) -> Result<(), Failure> {
    stdout::write(&format!("{text}\n")).map_err(Failure::Error)
}

/// Whether `r` opens the desktop app rather than rendering here.
fn opens_app(r: &RenderArgs) -> bool {
    #[cfg(feature = "gui")]
    return !r.headless();
    #[cfg(not(feature = "gui"))]
    {
        let _ = r;
        false
    }
}

/// What the edge says when a signal stopped a render before any file
/// was written.
fn interrupted() -> Failure {
    Failure::Error("rayoflight: interrupted: nothing was written".to_owned())
}

/// An error on stderr: one line, whatever the file names in it hold.
fn error_line(message: &str) {
    eprintln!("{}", rayoflight::system::escape::visible(message, false));
}

fn render_scene(r: RenderArgs) -> Result<(), Failure> {
    if opens_app(&r) {
        #[cfg(feature = "gui")]
        return open_app(r.scene.as_deref());
    }
    // No scene: the headless CLI prints its usage.
    let Some(scene_path) = r.scene.clone() else {
        return Err(Failure::Usage(UsageError::NoScene));
    };
    let out = r
        .out
        .clone()
        .unwrap_or_else(|| scene_path.with_extension("png"));
    // Everything that can be checked before work is checked first.
    refuse_same_file(&scene_path, &out)?;
    output::format_for(&out).map_err(fail)?;

    let loaded = scene::load(&scene_path).map_err(fail)?;
    // --set: in memory only, the scene file is never written. The edit
    // engine's record of where each element came from is made only for
    // them (a million objects' origins are 80 MB).
    let edited;
    let scene = if r.edits.is_empty() {
        &loaded
    } else {
        let mut engine = Edited::new(loaded);
        edit::apply(&mut engine, &r.edits).map_err(refused(&scene_path))?;
        edited = engine;
        edited.scene()
    };
    let request = &r.request;
    let (width, height) = match request.region {
        Some(region) => {
            let region = region
                .check_in(scene.camera.width, scene.camera.height)
                .map_err(|e| usage(format!("{}: --region {e}", scene_path.display())))?;
            (region.width(), region.height())
        }
        None => (scene.camera.width, scene.camera.height),
    };
    // The output can take this image: a folder that exists and is
    // writable, a format that holds its size, no special file in the way.
    let format = output::check_target(&out, width, height).map_err(fail)?;
    let pass = output::takes_pass(r.pass, &out).then_some(r.pass);
    // The memory the render and its file take, asked for before the
    // first ray: a one-line refusal, not an abort after minutes of work.
    let needed = output::bytes_to_render(format, pass, width, height);
    resources::check_memory(needed).map_err(|e| {
        let what = match pass {
            Some(pass) => format!("the {} pass", pass.name()),
            None => "the image".to_owned(),
        };
        Failure::Error(format!(
            "{}: rendering {what} at {width}×{height} {e}",
            out.display()
        ))
    })?;
    // Render time as the bench and the study measure it (rayoflight::render::measure).
    let pool = measure::RenderPool::new(request.threads).map_err(fail)?;
    let counted = render::Progress::default();
    // A signal stops the render at its next tile, or the write.
    let _cleanly = interrupt::cleanly();
    let never = render::Cancel::on_signal();
    let cancelled = interrupted;
    let elapsed = if let Some(pass) = pass {
        let form = output::pixel_form(format);
        let rendered = progress::render(&counted, progress::wanted(r.quiet), || {
            measure::kept_pass_timed(scene, request, pass, form, &pool, &never, &counted)
        });
        let timed = rendered.map_err(fail)?.ok_or_else(cancelled)?;
        output::save_kept_pass(&timed.image, &out).map_err(fail)?;
        if let Some((near, far)) = timed.image.depth_range {
            eprintln!("depth: t from {near} to {far}");
        }
        timed.elapsed
    } else {
        let rendered = progress::render(&counted, progress::wanted(r.quiet), || {
            measure::render_timed(scene, request, &pool, &never, &counted)
        });
        let timed = rendered.map_err(fail)?.ok_or_else(cancelled)?;
        match request.region {
            // A part records where it belongs, for `assemble`.
            Some(region) => {
                let part = Part::new(scene, &request.options(scene), region);
                rayoflight::cluster::part::save(&timed.image, &part, &out).map_err(fail)?
            }
            None => output::save(&timed.image, &out).map_err(fail)?,
        }
        timed.elapsed
    };
    if r.time {
        print_line(&format!("render: {} ns", elapsed.as_nanos()))?;
    }
    Ok(())
}

/// Opens the desktop app (GUI build). No display is a usage problem: the
/// message names `--no-gui` and the exit status is 2.
#[cfg(feature = "gui")]
fn open_app(scene: Option<&Path>) -> Result<(), Failure> {
    use rayoflight::gui::{self, GuiError};
    match gui::run(scene) {
        Ok(()) => Ok(()),
        Err(e @ (GuiError::NoDisplay | GuiError::Window(_))) => {
            Err(Failure::Usage(UsageError::Invalid {
                message: e.to_string(),
                command: None,
            }))
        }
        Err(e) => Err(fail(e)),
    }
}

/// `rayoflight edit`: applies the edits and writes the scene's text back
/// with only what they change changed, in place or to `-out`.
///
/// In place, the scene is locked ([`files::lock_for_update`]) from the
/// read to the rename, so that concurrent `edit`s and the app's saves take
/// turns and none loses another's changes. A program that takes no lock
/// (an editor) is caught by reading the file again just before the rename:
/// the edits are then merged onto its text by the app's engine
/// ([`merge`]) and written again; a conflict writes nothing.
fn edit_scene(args: &EditArgs) -> Result<(), Failure> {
    if let Some(out) = &args.out {
        files::check_file_target(out).map_err(fail)?;
    }
    let out = args.out.as_deref().unwrap_or(&args.scene);
    let in_place = files::same_file(&args.scene, out);
    // Waiting for the lock, a signal still ends the process at once.
    let _lock = match in_place {
        true => files::lock_for_update(&args.scene).map_err(|e| {
            Failure::Error(format!("{}: cannot lock it: {e}", args.scene.display()))
        })?,
        false => None,
    };
    let _cleanly = interrupt::cleanly();
    let (mut text, loaded) = scene::load_with_text(&args.scene).map_err(fail)?;
    let base = loaded.clone();
    let mut edited = Edited::new(loaded);
    let edits = edit::apply(&mut edited, &args.edits).map_err(refused(&args.scene))?;
    for _ in 0..MAX_REREADS {
        let new_text = splice::save(&text, &args.scene, &edited)
            .map_err(|e| Failure::Error(format!("{}: {e}", args.scene.display())))?;
        // Edits that change nothing (a value set to the one it has) leave
        // the scene file untouched, its modification time included.
        if new_text == text && in_place {
            return Ok(());
        }
        let written = files::write_atomic_with(
            out,
            |w| w.write_all(new_text.as_bytes()),
            |_| {
                if !in_place {
                    return Ok(());
                }
                // A file that cannot be read again (no descriptor left) is
                // not one another program changed: say why, write nothing.
                match std::fs::read(&args.scene) {
                    Ok(now) if now == text.as_bytes() => Ok(()),
                    Ok(_) => Err(Rewrite::Changed),
                    Err(e) => Err(Rewrite::Unreadable(e)),
                }
            },
        );
        match written {
            Ok(()) => return Ok(()),
            // Another file put at the name meanwhile: read it and merge.
            Err(Rewrite::Write(files::WriteError::Moved { .. })) => {}
            Err(Rewrite::Write(e)) => return Err(fail(e)),
            Err(Rewrite::Unreadable(e)) => {
                return Err(Failure::Error(format!(
                    "{}: cannot read the file again before writing it: {e}; nothing was written",
                    args.scene.display()
                )));
            }
            Err(Rewrite::Changed) => {}
        }
        // Another program wrote the file since it was read: replay the
        // edits onto its version.
        let (their_text, theirs) = scene::load_with_text(&args.scene).map_err(fail)?;
        let merged = merge::merge(&base, &theirs, &edits, &Default::default());
        if let Some(c) = merged.conflicts.first() {
            return Err(Failure::Error(format!(
                "{}: another program changed the file meanwhile: {}: yours {}, the file's {}; nothing was written",
                args.scene.display(),
                c.path,
                c.yours,
                c.theirs
            )));
        }
        text = their_text;
        edited = merged.edited;
    }
    Err(Failure::Error(format!(
        "{}: another program keeps changing the file ({MAX_REREADS} times while it was edited); nothing was written",
        args.scene.display()
    )))
}

/// How many times `edit` merges onto a file that another program keeps
/// writing before it gives up.
const MAX_REREADS: usize = 8;

/// Why `edit`'s write did not happen.
enum Rewrite {
    Write(files::WriteError),
    /// The scene is not the text that was read any more.
    Changed,
    /// The scene could not be read again to find out.
    Unreadable(std::io::Error),
}

impl From<files::WriteError> for Rewrite {
    fn from(e: files::WriteError) -> Rewrite {
        Rewrite::Write(e)
    }
}

/// An edit `scene` refuses: a usage error (exit 2) that names the scene.
fn refused(scene: &Path) -> impl FnOnce(EditError) -> Failure {
    let scene = scene.to_owned();
    |error| Failure::Usage(UsageError::Edit { scene, error })
}

fn export_pov(scene_path: &Path, out: Option<PathBuf>) -> Result<(), Failure> {
    let out = out.unwrap_or_else(|| scene_path.with_extension("pov"));
    refuse_same_file(scene_path, &out)?;
    files::check_file_target(&out).map_err(fail)?;
    let scene = scene::load(scene_path).map_err(fail)?;
    let header = pov::Header {
        scene: scene_path,
        written_to: &out,
    };
    let text = pov::export_named(&scene, Some(header));
    files::write_atomic(&out, text.as_bytes()).map_err(fail)
}

/// The output must never replace the scene: not by another spelling of
/// its path (`./a/../s.xml`), a symbolic link or a hard link.
fn refuse_same_file(scene: &Path, out: &Path) -> Result<(), Failure> {
    if files::same_file(scene, out) {
        return Err(Failure::Error(format!(
            "{}: refusing to overwrite the scene file with the output",
            out.display()
        )));
    }
    Ok(())
}
