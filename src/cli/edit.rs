//! Edits given on the command line: `rayoflight edit`'s `--set`,
//! `--remove` and `--add`. Each is read into an [`EditArg`] when the
//! arguments are parsed (its path and value checked), and turned into the
//! library's [`Edit`] only when it is applied, against the scene as the
//! edits before it left it: an added element's index depends on them.
//!
//! How any command's edit flags are put back in the order given
//! ([`in_order`]) and read ([`edit_args`]): the render's, `explain`'s and
//! `split`'s `--set` go through them as well. And the `edit` subcommand
//! itself: its flags ([`EditFlags`]) and its run, which writes the scene
//! back with only what the edits change changed.

use super::failure::{Failure, fail, refused};
use super::subcommand::Subcommand;
use super::usage::UsageError;
use super::values::{Named, path_value};
use clap::{ArgMatches, Args};
use rayoflight::scene::Scene;
use rayoflight::scene::edit::{Edit, EditError, Edited, Field, Item, NewElement, Value};
use rayoflight::scene::{self, merge, splice};
use rayoflight::system::{files, interrupt};
use std::path::{Path, PathBuf};

/// The paths `--set` and `--remove` take, for `rayoflight edit --help`
/// (the engine's errors list them too).
pub const PATHS: &str = "\
Paths count from 1, in file order; objects are spheres and planes together.

Values (--set PATH=VALUE):
  model.type, model.depth
  camera.width, camera.height, camera.eyeDistance
  camera.transformation[K].<x|y|z|angle|factor>
  object[N].color.<red|green|blue>
  object[N].material.<ka|kd|ks|m>
  object[N].transformation[K].<x|y|z|angle|factor>
  light[N].<x|y|z>
  light[N].color.<red|green|blue>

Elements (--remove PATH):
  object[N], light[N], object[N].transformation[K], camera.transformation[K]

Each value is checked as the loader checks the file: ka >= 0, model.type
one of ambient, lambert, phong, whitted, and so on.";

/// One `--set`, `--remove` or `--add`, its path and value read.
#[derive(Debug, Clone, PartialEq)]
pub enum EditArg {
    Set(Field, Value),
    Remove(Item),
    Add(NewElement),
}

impl EditArg {
    /// `--set PATH=VALUE`, split at the `=`.
    pub fn set(path: &str, value: &str) -> Result<EditArg, EditError> {
        let field = Field::parse(path)?;
        Ok(EditArg::Set(field, field.parse_value(value)?))
    }

    /// `--remove PATH`.
    pub fn remove(path: &str) -> Result<EditArg, EditError> {
        Item::parse(path).map(EditArg::Remove)
    }

    /// `--add sphere|plane|light`.
    pub fn add(kind: &str) -> Result<EditArg, EditError> {
        NewElement::parse(kind).map(EditArg::Add)
    }

    /// The engine's edit, for `scene` as it is now: an added element goes
    /// after the last of its kind.
    fn edit(&self, scene: &Scene) -> Edit {
        match *self {
            EditArg::Set(field, value) => Edit::Set(field, value),
            EditArg::Remove(item) => Edit::Remove(item),
            EditArg::Add(kind) => Edit::add(scene, kind),
        }
    }
}

/// Applies `edits` to `edited` in order. The first one the scene refuses
/// (a path naming nothing in it, a value out of range) stops there.
/// Returns the engine's edits, as applied (to replay them elsewhere with
/// [`rayoflight::scene::merge`]).
pub fn apply(edited: &mut Edited, edits: &[EditArg]) -> Result<Vec<Edit>, EditError> {
    let mut applied = Vec::with_capacity(edits.len());
    for arg in edits {
        let edit = arg.edit(edited.scene());
        edited.apply(&edit)?;
        applied.push(edit);
    }
    Ok(applied)
}

// ----- the command line -----

/// `rayoflight edit`: what to change in a scene file, and where to write it.
#[derive(Debug, Clone, PartialEq)]
pub struct EditArgs {
    pub scene: PathBuf,
    /// Where the edited scene goes; `None`: the scene file itself.
    pub out: Option<PathBuf>,
    /// The `--set`, `--remove` and `--add`, in the order given; never empty.
    pub edits: Vec<EditArg>,
}

/// Change values of a scene file, add or remove elements, and write it.
///
/// The edits apply in the order given, and the file keeps every byte
/// they do not change: comments, formatting, the spelling of other
/// numbers. It is rewritten in place (atomically, keeping its mode;
/// through a symbolic link, the file it points to), or written to
/// -out FILE. An edit that changes nothing leaves the file untouched.
#[derive(Args, Debug)]
#[command(
    override_usage = "rayoflight edit scene.xml [--set PATH=VALUE]… [--remove PATH]… \
                      [--add KIND]… [-out FILE]",
    after_help = PATHS
)]
pub(super) struct EditFlags {
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

impl Subcommand for EditFlags {
    type Args = EditArgs;

    /// The edits asked for, in the order given (`matches`: the
    /// subcommand's, which alone know that order), read against the
    /// scene's path; none is a usage error.
    fn resolve(self, matches: &ArgMatches) -> Result<EditArgs, UsageError> {
        let given = in_order(matches, self.set, self.remove, self.add);
        if given.is_empty() {
            return Err(UsageError::Invalid {
                message: "nothing to do: give at least one --set, --remove or --add".to_owned(),
                command: Some("edit"),
            });
        }
        Ok(EditArgs {
            edits: edit_args(given, &self.scene)?,
            scene: self.scene,
            out: self.out,
        })
    }

    fn prints(_: &EditArgs) -> bool {
        false
    }

    fn run(args: EditArgs, _: fn() -> clap::Command) -> Result<(), Failure> {
        edit_scene(&args)
    }
}

/// `--add`'s kind, read (and refused, naming the scene) with the edits.
fn kind(text: &str) -> Result<String, String> {
    Ok(text.to_owned())
}

fn kind_names() -> Vec<&'static str> {
    NewElement::ALL.iter().map(|k| k.name()).collect()
}

/// An edit flag as given, before its path is read.
pub(super) enum Given {
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
pub(super) fn edit_args(given: Vec<Given>, scene: &Path) -> Result<Vec<EditArg>, UsageError> {
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
    let edits = apply(&mut edited, &args.edits).map_err(refused(&args.scene))?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every path the help lists, with N = K = 1 and each `<a|b>` choice.
    fn listed(section: &str) -> Vec<String> {
        section
            .lines()
            .skip(1)
            .take_while(|l| l.starts_with("  "))
            .flat_map(|l| l.split(", "))
            .map(|p| p.trim().replace(['N', 'K'], "1"))
            .flat_map(|p| match p.split_once('<') {
                Some((head, choices)) => choices
                    .trim_end_matches('>')
                    .split('|')
                    .map(|c| format!("{head}{c}"))
                    .collect(),
                None => vec![p],
            })
            .collect()
    }

    #[test]
    fn the_help_lists_paths_the_engine_reads() {
        let (values, elements) = PATHS.split_once("Elements").unwrap();
        let values = listed(&values[values.find("Values").unwrap()..]);
        let elements = listed(elements);
        assert_eq!((values.len(), elements.len()), (28, 4));
        for path in values {
            Field::parse(&path).unwrap_or_else(|e| panic!("{e}"));
        }
        for path in elements {
            Item::parse(&path).unwrap_or_else(|e| panic!("{e}"));
        }
    }

    #[test]
    fn an_add_is_built_against_the_scene_as_the_edits_before_left_it() {
        let scene = rayoflight::scene::parse(
            rayoflight::EXAMPLE_SCENE,
            std::path::Path::new("example.xml"),
        )
        .unwrap();
        let mut edited = Edited::new(scene);
        let n = edited.scene().objects.len();
        let edits = [
            EditArg::add("sphere").unwrap(),
            EditArg::add("plane").unwrap(),
            EditArg::set(&format!("object[{}].color.red", n + 2), "0.5").unwrap(),
        ];
        apply(&mut edited, &edits).unwrap();
        let objects = &edited.scene().objects;
        assert_eq!(objects.len(), n + 2);
        assert_eq!(objects[n + 1].shape.name(), "plane");
        assert_eq!(objects[n + 1].color.x, 0.5);
    }
}
