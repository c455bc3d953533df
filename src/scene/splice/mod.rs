//! Save-back: writing an [`Edited`] scene into the XML text it was loaded
//! from.
//!
//! [`save`] splices the edits into the text by the origins the edit engine
//! kept ([`super::edit`]): an element is found again by where it came from,
//! never by matching elements up by position or name, and only what
//! differs changes ([`editor`]). Every other byte of the text is kept:
//! comments, whitespace, attribute order and quoting, the spelling of
//! unchanged numbers (`1.0` stays `1.0`), the XML declaration.
//!
//! [`plan_source`] does the same for a text held as a [`Source`]: one
//! held packed is read twice, a block at a time, never unpacked whole (its
//! [`Skeleton`] is scanned instead).
//!
//! How it works: the text is scanned again ([`super::layout`]) to find
//! each element's byte span, each attribute value's byte range and each
//! comment; the edits are collected as splices (byte range → replacement)
//! and applied in one pass ([`Rewrite`]). Before anything is returned, the
//! new text is parsed and compared with the edited scene: `save` never
//! returns a text that would load differently.
//!
//! A scene with no text yet is written by [`super::fresh::to_xml`].

use std::mem::discriminant;
use std::ops::Range;
use std::path::Path;

use super::edit::{EditError, Edited, ObjectOrigin};
use super::layout::skeleton::Skeleton;
use super::layout::{Doc, Keep, internal};
use super::source::Source;
use super::{LoadError, Object, Scene, parse};
use crate::math::TransformStep;

mod editor;

use editor::{Editor, Splice};

/// Writes `edited` into `text`, the source of a valid scene file that
/// `edited` was loaded from (`path` only names it in errors).
///
/// The result parses to `edited`'s scene; every part of `text` that did not
/// need to change is kept byte for byte.
pub fn save(text: &str, path: &Path, edited: &Edited) -> Result<String, EditError> {
    let rewrite = {
        let original = parse(text, path).map_err(|e| EditError::Parse(Box::new(e)))?;
        plan(text, &original, edited)?
    };
    let mut out = Vec::with_capacity(rewrite.len());
    rewrite
        .write_to(&mut out)
        .map_err(|e| internal(e.to_string()))?;
    let out = String::from_utf8(out).map_err(|_| internal("the rewritten text is not UTF-8"))?;
    check(&out, path, edited)?;
    Ok(out)
}

/// The splices that write `edited` into `text`, whose scene is `original`
/// (the scene `text` loads to, sharing its objects with `edited` where
/// they were not changed: the app keeps it rather than parse the text
/// again).
///
/// Only the elements of the objects that changed are scanned in full: on
/// a file of a million objects the others are only placed (16 bytes each).
pub fn plan<'t>(
    text: &'t str,
    original: &Scene,
    edited: &Edited,
) -> Result<Rewrite<'t>, EditError> {
    if edited.is_as_loaded(original) {
        return Ok(Rewrite {
            text: Text::Str(text),
            splices: Vec::new(),
        });
    }
    let changed = changed_objects(original, edited);
    let doc = Doc::scan(text, Keep::Objects(&changed))?;
    Rewrite::new(text, edit_splices(&doc, original, edited)?)
}

/// The splices that write `edited` into `doc`, scanned keeping the
/// elements of the objects `edited` changes ([`changed_objects`]).
fn edit_splices(
    doc: &Doc<'_>,
    original: &Scene,
    edited: &Edited,
) -> Result<Vec<Splice>, EditError> {
    let mut editor = Editor {
        doc,
        splices: Vec::new(),
    };
    editor.scene(original, edited)?;
    Ok(editor.splices)
}

/// Checks that `out`, a text written by a [`Rewrite`], loads as `edited`'s
/// scene: nothing is saved that would load differently.
pub fn check(out: &str, path: &Path, edited: &Edited) -> Result<(), EditError> {
    let scene = edited.scene();
    loads_as(super::parse_sharing(out, path, &scene.objects), scene)
}

/// [`check`] of the file `written`, a text written by a [`Rewrite`] for
/// `path` (which names it in errors): read a piece at a time where it is
/// big, its objects shared with `edited`'s, the text never held whole.
pub fn check_file(written: &Path, path: &Path, edited: &Edited) -> Result<(), EditError> {
    let scene = edited.scene();
    let loaded = super::load_like(written, &scene.objects).map_err(|e| LoadError {
        path: path.to_owned(),
        ..e
    });
    loads_as(loaded, scene)
}

fn loads_as(loaded: Result<Scene, LoadError>, scene: &Scene) -> Result<(), EditError> {
    match loaded {
        Ok(back) if &back == scene => Ok(()),
        Ok(_) => Err(internal(
            "the rewritten text does not load as the edited scene",
        )),
        Err(e) => Err(EditError::Invalid(Box::new(e))),
    }
}

/// A scene file's text with splices to apply: [`Rewrite::write_to`]
/// streams the new text without building it.
#[derive(Debug)]
pub struct Rewrite<'t> {
    text: Text<'t>,
    /// Sorted, not overlapping, inside the text ([`plan`] checked).
    splices: Vec<Splice>,
}

/// The text a [`Rewrite`] splices into.
#[derive(Debug)]
enum Text<'t> {
    Str(&'t str),
    /// Read back in order, a block at a time ([`plan_source`]).
    Source(&'t Source),
}

impl<'t> Rewrite<'t> {
    /// Orders the splices: insertions at one offset keep the order they
    /// were made in and come before a replacement starting there.
    /// Overlapping splices, or one outside the text, are an error.
    fn new(text: &'t str, mut splices: Vec<Splice>) -> Result<Rewrite<'t>, EditError> {
        splices.sort_by_key(|s| (s.range.start, !s.range.is_empty()));
        let mut cursor = 0;
        for splice in &splices {
            let Range { start, end } = splice.range;
            if start < cursor || end < start {
                return Err(internal("overlapping edits"));
            }
            if text.get(start..end).is_none() {
                return Err(internal("an edit outside the text"));
            }
            cursor = end;
        }
        Ok(Rewrite {
            text: Text::Str(text),
            splices,
        })
    }

    /// Nothing to change: the new text is the old one.
    pub fn is_empty(&self) -> bool {
        self.splices.is_empty()
    }

    /// The new text's length in bytes.
    pub fn len(&self) -> usize {
        let len = match self.text {
            Text::Str(text) => text.len(),
            Text::Source(source) => source.len(),
        };
        self.splices
            .iter()
            .fold(len, |n, s| n - (s.range.end - s.range.start) + s.text.len())
    }

    /// Writes the new text: the kept bytes and the splices in order.
    pub fn write_to(&self, w: &mut (impl std::io::Write + ?Sized)) -> std::io::Result<()> {
        use std::io::Read;
        match self.text {
            Text::Str(text) => {
                let mut cursor = 0;
                for splice in &self.splices {
                    w.write_all(&text.as_bytes()[cursor..splice.range.start])?;
                    w.write_all(splice.text.as_bytes())?;
                    cursor = splice.range.end;
                }
                w.write_all(&text.as_bytes()[cursor..])
            }
            Text::Source(source) => {
                let mut reader = source.reader();
                let mut cursor = 0;
                for splice in &self.splices {
                    let Range { start, end } = splice.range;
                    let kept = std::io::copy(&mut (&mut reader).take((start - cursor) as u64), w)?;
                    let skipped = std::io::copy(
                        &mut (&mut reader).take((end - start) as u64),
                        &mut std::io::sink(),
                    )?;
                    if kept + skipped != (end - cursor) as u64 {
                        return Err(std::io::Error::other("an edit past the end of the text"));
                    }
                    w.write_all(splice.text.as_bytes())?;
                    cursor = end;
                }
                std::io::copy(&mut reader, w).map(|_| ())
            }
        }
    }
}

/// [`plan`] for a text held as a [`Source`]. A packed one is never
/// unpacked whole: the save reads it once to find the changed objects'
/// elements ([`Skeleton`]) and once more to write the new text.
pub fn plan_source<'s>(
    source: &'s Source,
    original: &Scene,
    edited: &Edited,
) -> Result<Rewrite<'s>, EditError> {
    if edited.is_as_loaded(original) {
        return Ok(Rewrite {
            text: Text::Source(source),
            splices: Vec::new(),
        });
    }
    if let Some(text) = source.as_str() {
        return plan(text, original, edited);
    }
    let changed = changed_objects(original, edited);
    // Values edited in place: the runs of objects between the changed ones
    // are folded away.
    let fold = edited.objects_in_place() && edited.scene().objects.len() == original.objects.len();
    let skeleton = Skeleton::read(source, &changed, fold)?;
    let mut doc = match &skeleton.folded {
        Some(folded) => {
            let mut doc = Doc::scan(&skeleton.text, Keep::Folded(&folded.changed))?;
            doc.numbers = Some(&folded.numbers);
            doc
        }
        None => Doc::scan(&skeleton.text, Keep::Objects(&changed))?,
    };
    if skeleton.crlf {
        doc.nl = "\r\n";
    }
    let checked = Rewrite::new(&skeleton.text, edit_splices(&doc, original, edited)?)?;
    let splices = checked
        .splices
        .into_iter()
        .map(|s| Splice {
            range: skeleton.in_source(s.range.start)..skeleton.in_source(s.range.end),
            text: s.text,
        })
        .collect();
    Ok(Rewrite {
        text: Text::Source(source),
        splices,
    })
}

/// The objects of `original` (by index) that `edited` changes: only these
/// need their elements found in the text. An object kept as it was, with
/// its transformation steps where they were, needs nothing.
fn changed_objects(original: &Scene, edited: &Edited) -> std::collections::HashSet<usize> {
    (0..edited.scene().objects.len())
        .filter_map(|n| {
            let origin = edited.origin_of(n)?;
            let unchanged = original
                .objects
                .get(origin.index)
                .is_some_and(|o| unchanged(o, &edited.scene().objects[n], &origin.steps));
            (!unchanged).then_some(origin.index)
        })
        .collect()
}

/// `e`, whose steps came from `step_origins` of `o`'s, is `o` as it was.
fn unchanged(o: &Object, e: &Object, step_origins: &[Option<usize>]) -> bool {
    step_origins.len() == o.transform.steps().len()
        && step_origins
            .iter()
            .enumerate()
            .all(|(k, origin)| *origin == Some(k))
        && (std::ptr::eq(o, e) || o == e)
}

/// Writes `edited` into `text`, pairing the text's objects, lights and
/// transformation steps with `edited`'s by their index (and steps only when
/// of the same kind); the rest are removed or added.
///
/// For scenes changed outside the edit engine, which has no origins to go
/// by (tests, tools). The app and the command line save with [`save`].
pub fn rewrite_by_index(text: &str, path: &Path, edited: &Scene) -> Result<String, EditError> {
    let original = parse(text, path).map_err(|e| EditError::Parse(Box::new(e)))?;
    let steps = |o: &[TransformStep], e: &[TransformStep]| -> Vec<Option<usize>> {
        e.iter()
            .enumerate()
            .map(|(k, s)| {
                o.get(k)
                    .filter(|t| discriminant(*t) == discriminant(s))
                    .map(|_| k)
            })
            .collect()
    };
    let mut by_index = Edited::new(edited.clone());
    by_index.set_object_origins(
        edited
            .objects
            .iter()
            .enumerate()
            .map(|(i, e)| {
                original.objects.get(i).map(|o| ObjectOrigin {
                    index: i,
                    steps: steps(o.transform.steps(), e.transform.steps()),
                })
            })
            .collect(),
    );
    for (i, origin) in by_index.lights.iter_mut().enumerate() {
        *origin = (i < original.lights.len()).then_some(i);
    }
    by_index.camera_steps = steps(
        original.camera.transform.steps(),
        edited.camera.transform.steps(),
    );
    save(text, path, &by_index)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::edit::number_text as num;

    fn scene(text: &str) -> Scene {
        parse(text, Path::new("t.xml")).unwrap()
    }

    #[test]
    fn no_change_means_no_splice() {
        for text in [
            crate::EXAMPLE_SCENE,
            "\u{feff}<scene><!-- x --><camera width='2' height=\"3\" eyeDistance=\"1.0\"/></scene>",
        ] {
            let s = scene(text);
            let doc = Doc::scan(text, Keep::All).unwrap();
            let mut editor = Editor {
                doc: &doc,
                splices: Vec::new(),
            };
            editor.scene(&s, &Edited::new(s.clone())).unwrap();
            assert!(editor.splices.is_empty());
            assert_eq!(
                save(text, Path::new("t.xml"), &Edited::new(s)).unwrap(),
                text
            );
        }
    }

    #[test]
    fn numbers_read_back_exactly() {
        for v in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1.0 / 3.0,
            1e-7,
            1e-300,
            5e-324,
            1e16,
            1e300,
            f64::MAX,
            -2.5e-8,
            123456.789,
            0.000001,
        ] {
            let s = num(v);
            let back: f64 = s.parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v} -> {s}");
            assert!(s.len() < 30, "{s}");
        }
    }

    #[test]
    fn overlapping_splices_are_an_error() {
        let splices = vec![
            Splice {
                range: 0..3,
                text: "a".into(),
            },
            Splice {
                range: 2..4,
                text: "b".into(),
            },
        ];
        assert!(matches!(
            Rewrite::new("abcdef", splices),
            Err(EditError::Internal(_))
        ));
    }

    #[test]
    fn a_save_scans_only_the_objects_it_changes() {
        let text = "<scene>\n  <sphere><color red=\"1\" green=\"0\" blue=\"0\"/></sphere>\n  \
                    <sphere><color red=\"0\" green=\"1\" blue=\"0\"/></sphere>\n  \
                    <plane><color red=\"0\" green=\"0\" blue=\"1\"/></plane>\n  \
                    <camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>\n</scene>\n";
        fn count(text: &str, keep: Keep) -> usize {
            Doc::scan(text, keep).unwrap().nodes.len()
        }
        let (second, ends) = ([1].into(), [0, 2].into());
        // The root, three objects and the camera; then a colour each. An
        // object not asked for is only placed: no node.
        assert_eq!(count(text, Keep::TopLevel), 5);
        assert_eq!(count(text, Keep::All), 8);
        assert_eq!(count(text, Keep::Placed), 2);
        assert_eq!(count(text, Keep::Objects(&second)), 4);
        assert_eq!(count(text, Keep::Objects(&ends)), 6);
        // Every object placed, whichever are kept, at the same place.
        let places = |keep| Doc::scan(text, keep).unwrap().objects;
        let all = places(Keep::All);
        assert_eq!(all.len(), 3);
        assert_eq!(
            &text[all[1].start..all[1].end],
            "<sphere><color red=\"0\" green=\"1\" blue=\"0\"/></sphere>"
        );
        for keep in [
            Keep::TopLevel,
            Keep::Placed,
            Keep::Objects(&second),
            Keep::Objects(&ends),
        ] {
            assert_eq!(places(keep), all);
        }

        let original = scene(text);
        let mut edited = Edited::new(original.clone());
        edited
            .apply(&crate::scene::edit::Edit::Set(
                crate::scene::edit::Field::parse("object[2].color.blue").unwrap(),
                crate::scene::edit::Value::Number(0.5),
            ))
            .unwrap();
        assert_eq!(changed_objects(&original, &edited), [1].into());
        let saved = save(text, Path::new("t.xml"), &edited).unwrap();
        assert_eq!(
            saved,
            text.replacen("green=\"1\" blue=\"0\"", "green=\"1\" blue=\"0.5\"", 1)
        );
    }

    /// The text of `rewrite`.
    fn written(rewrite: &Rewrite<'_>) -> String {
        let mut out = Vec::new();
        rewrite.write_to(&mut out).unwrap();
        assert_eq!(out.len(), rewrite.len());
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn a_packed_text_is_saved_as_the_same_text_held_whole() {
        use crate::scene::edit::{Edit, Element, Field, Item, Owner, Value};
        // Comments above objects, objects on one line and on several, an
        // empty one, CRLF inside objects only, tabs.
        let mut text = String::from("\u{feff}<?xml version=\"1.0\"?>\n<!-- top -->\n<scene>\n");
        for i in 0..60 {
            text.push_str(&match i % 5 {
                0 => format!("  <!-- BALL {i} -->\n  <sphere><color red=\"0.{i}\" green=\"1\" blue=\"0\"/><material ka=\"0.1\"/></sphere>\n"),
                1 => format!("  <sphere>\r\n    <material kd=\"0.{i}\"/>\r\n    <transformation><translate x=\"{i}\"/></transformation>\r\n  </sphere>\n"),
                2 => "\t<sphere/>\n".to_owned(),
                3 => format!("  <plane><transformation><rotate-x angle=\"1.{i}\"/><translate y=\"{i}\"/></transformation></plane>\n"),
                _ => format!("  <sphere> <!-- inside {i} --> <color red=\"1\" green=\"0\" blue=\"0\"/> </sphere>\n"),
            });
        }
        text.push_str("  <light x=\"1\" y=\"2\" z=\"3\"/>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>\n");
        let original = scene(&text);
        let packed = Source::packed(&text);
        let mut edited = Edited::new(original.clone());
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: usize| {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng % n as u64) as usize
        };
        for round in 0..120 {
            let objects = edited.scene().objects.len();
            // An insertion first, before any object is kept whole.
            let kind = if round == 0 { 3 } else { next(8) };
            let edit = match kind {
                0 | 1 => Edit::Set(
                    Field::parse(&format!("object[{}].material.ka", next(objects) + 1)).unwrap(),
                    Value::Number(round as f64 / 100.0),
                ),
                2 => Edit::Remove(Item::Object(next(objects))),
                3 => {
                    let copy = edited.scene().objects[next(objects)].as_ref().clone();
                    Edit::Insert(
                        Item::Object(next(objects + 1)),
                        Element::Object(Box::new(copy)),
                    )
                }
                4 => Edit::add_step(
                    edited.scene(),
                    Owner::Object(next(objects)),
                    crate::math::TransformStep::UniformScale(1.5),
                )
                .unwrap(),
                5 => Edit::Set(
                    Field::parse("light[1].x").unwrap(),
                    Value::Number(round as f64),
                ),
                6 => Edit::Set(
                    Field::parse("camera.width").unwrap(),
                    Value::Integer(4 + round as u64 % 9),
                ),
                _ => Edit::Set(
                    Field::parse(&format!("object[{}].color.red", next(objects) + 1)).unwrap(),
                    Value::Number(0.5),
                ),
            };
            if edited.apply(&edit).is_err() {
                continue;
            }
            let whole = written(&plan(&text, &original, &edited).unwrap());
            let from_packed = written(&plan_source(&packed, &original, &edited).unwrap());
            assert_eq!(from_packed, whole, "round {round}: {edit:?}");
            assert_eq!(&scene(&whole), edited.scene());
        }
        // Nothing changed: the text as it is.
        let unchanged = Edited::new(original.clone());
        assert_eq!(
            written(&plan_source(&packed, &original, &unchanged).unwrap()),
            text
        );
    }

    /// Values edited in place, on texts laid out every which way: the
    /// save of a packed text folds the unchanged objects away (its
    /// skeleton a fraction of the text) and writes the text a text held
    /// whole would.
    #[test]
    fn a_skeleton_with_objects_folded_away_saves_as_the_whole_text() {
        use crate::scene::edit::{Edit, Field, Item, NewElement};
        let ball =
            |i: usize| format!("<sphere><color red=\"0.{i}\" green=\"1\" blue=\"0\"/></sphere>");
        let many = |each: &dyn Fn(usize) -> String| (0..40).map(each).collect::<String>();
        let texts = [
            // Comments between objects, a light among them, no model.
            format!(
                "<scene>\n{}  <light x=\"1\" y=\"2\" z=\"3\"/>\n{}  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>\n",
                many(&|i| format!("  <!-- ball {i} -->\n  {}\n", ball(i))),
                many(&|i| format!("  <plane/><!-- {i} -->\n  {}\n", ball(i))),
            ),
            // The root not on its own line, objects on its line.
            format!(
                "<?xml version=\"1.0\"?><scene>{}\n<light x=\"1\" y=\"2\" z=\"3\"/><camera width=\"8\" height=\"6\" eyeDistance=\"1\"/><model type=\"lambert\"/></scene>",
                many(&|i| ball(i)),
            ),
            // A byte order mark, CRLF, tabs; the first objects not on lines
            // of their own, then some less indented than the root.
            format!(
                "{}  <scene>\r\n  <sphere/> {}\r\n {}\r\n{}\t\t<light x=\"1\" y=\"2\" z=\"3\"/>\r\n\t\t<camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\r\n  </scene>\r\n",
                '\u{feff}',
                ball(0),
                ball(1),
                many(&|i| format!("  \t{}\r\n", ball(i))),
            ),
            // The first object sets the indentation unit (three spaces)
            // that an empty sphere given a colour indents it with.
            format!(
                "<scene>\n   <sphere/>\n{}  <light x=\"1\" y=\"2\" z=\"3\"/>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>\n",
                many(&|_| "  <sphere/>\n".to_owned()),
            ),
            // Every object on one line; lights last, one after the other.
            format!(
                "<scene>\n  {}<light x=\"1\" y=\"2\" z=\"3\"/><light x=\"4\" y=\"2\" z=\"3\"/>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>",
                many(&|i| ball(i)),
            ),
        ];
        for (t, text) in texts.iter().enumerate() {
            let original = scene(text);
            let packed = Source::packed(text);
            let mut edited = Edited::new(original.clone());
            let mut rng = 0x9e37_79b9_7f4a_7c15u64 + t as u64;
            let mut next = |n: usize| {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng % n.max(1) as u64) as usize
            };
            for round in 0..40 {
                let objects = original.objects.len();
                let lights = edited.scene().lights.len();
                let set = |path: String, value: &str| {
                    let field = Field::parse(&path).unwrap();
                    Edit::Set(field, field.parse_value(value).unwrap())
                };
                let edit = match next(8) {
                    0 | 1 => set(
                        format!("object[{}].material.ka", next(objects) + 1),
                        &format!("0.{round}"),
                    ),
                    2 => set(format!("object[{}].color.green", next(objects) + 1), "0.5"),
                    3 if lights > 0 => set(format!("light[{}].x", next(lights) + 1), "7"),
                    4 => Edit::add(edited.scene(), NewElement::Light),
                    5 if lights > 1 => Edit::Remove(Item::Light(next(lights))),
                    6 => set("camera.width".to_owned(), &format!("{}", 4 + round)),
                    _ => set("model.type".to_owned(), ["phong", "whitted"][round % 2]),
                };
                if edited.apply(&edit).is_err() {
                    continue;
                }
                assert!(edited.objects_in_place());
                let changed = changed_objects(&original, &edited);
                let skeleton = Skeleton::read(&packed, &changed, true).unwrap();
                let folded = skeleton.folded.as_ref().unwrap();
                assert!(
                    folded.numbers.len() <= 2 * changed.len() + 8,
                    "text {t}, round {round}: {} objects left of {objects}",
                    folded.numbers.len()
                );
                let whole = written(&plan(text, &original, &edited).unwrap());
                let from_packed = written(&plan_source(&packed, &original, &edited).unwrap());
                assert_eq!(from_packed, whole, "text {t}, round {round}: {edit:?}");
                assert_eq!(&scene(&whole), edited.scene());
            }
        }
    }
}
