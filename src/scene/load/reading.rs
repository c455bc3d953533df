//! A text checked again after edits, read only where they fall: what the
//! language server does at each keystroke, in time that follows the edit,
//! not the file.
//!
//! A [`Reading`] knows, of the text as last found without error, where
//! each of the root's children starts and what it is. The edits since are
//! one span of that text ([`Reading::edited`]). [`Reading::check`] reads
//! the new text from the child the span starts in, as a parse in one reads
//! it (the reader holding the root open, the counts of what came before
//! given: [`Parser::document_from`]), and stops at the first child past
//! the span, where the rest of the text is the old one, in the same state:
//! so an error is the one a parse in one gives, at its line and column,
//! and a text without one is known for the next edit. What only the whole
//! can tell (a camera or model more or less, a count past its limit)
//! reads the whole text, as does a text never read without error.
//!
//! A reading can also start from a text it never read: the file the app
//! loaded, whose [`Layout`] (where its children sit, recorded by the
//! loader, on every core) and scene make what a whole reading knows
//! ([`Reading::keeping_from`]); the editor's first text of that file is
//! then read only where it differs from the file's.
//!
//! A check ([`Reading::default`], the language server's) keeps objects
//! and lights checked, not kept: a million spheres cost their places (16
//! bytes each), not a scene. A reading that keeps the scene
//! ([`Reading::keeping`], the app's, following an editor) replaces only
//! the objects and lights of the children read again, the others shared
//! with the scene before ([`Reading::scene`]): an edit of one light leaves
//! the list of a million objects the same list, and the renderer sees that
//! at once.

use std::ops::Range;
use std::path::Path;

use super::parser::{Child, Gathered, Parser};
use super::{MAX_LIGHTS, MAX_OBJECTS};
use crate::scene::error::LoadError;
use crate::scene::{Camera, Scene};
use crate::shading::Model;

/// What is known of a text between checks ([`Reading::check`]).
#[derive(Debug, Clone, Default)]
pub struct Reading {
    known: Option<Known>,
    /// The edits since `known` was read, as one span of that text.
    dirty: Option<Span>,
    /// The scene is kept ([`Reading::keeping`]).
    keep: bool,
    /// What the last check read, where it found no error.
    last: Option<Reread>,
}

/// What a check read of the text ([`Reading::reread`]), to bring up to
/// date what follows the text's children (an app's labels of its
/// objects).
#[derive(Debug, Clone, PartialEq)]
pub enum Reread {
    /// The whole text.
    Whole,
    /// The bytes `text` of the new text (its byte-order mark counted), from
    /// the start of a child of the root to the start of the first child
    /// after the edits (or the root's end), which held `objects_were`
    /// objects and now hold `objects_now`, the first of them object
    /// number `first_object`.
    Children {
        text: Range<usize>,
        first_object: usize,
        objects_were: usize,
        objects_now: usize,
    },
}

/// Where each of the root's children sits in a text that loaded, as the
/// loader found it ([`super::load_counting`], [`super::load_packed`]): a
/// reading of the text starts from it ([`Reading::keeping_from`]) without
/// reading the text again. 16 bytes a child.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Layout {
    /// The text's byte-order mark's length: places are in the text after it.
    pub(super) bom: usize,
    /// Where each child of the root starts, and what it is.
    pub(super) places: Vec<(usize, Child)>,
    /// The root's content, from after its start tag to its end tag's `<`.
    pub(super) content: Range<usize>,
}

impl Layout {
    /// The layout `gathered` recorded ([`Parser::record`]) of a text
    /// without a byte-order mark, its places taken; none (a reading
    /// starting from it reads the text whole) where it has not read the
    /// whole root.
    pub(super) fn take(gathered: &mut Gathered) -> Layout {
        let places = std::mem::take(&mut gathered.places);
        match (gathered.content_start, gathered.content_end) {
            (Some(start), Some(end)) => Layout {
                bom: 0,
                places,
                content: start..end,
            },
            _ => Layout::default(),
        }
    }

    /// How many children of the root it places.
    pub fn children(&self) -> usize {
        self.places.len()
    }
}

/// The text as last found without error.
#[derive(Debug, Clone)]
struct Known {
    /// Its byte-order mark's length: places are in the text after it.
    bom: usize,
    /// Where each child of the root starts, and what it is.
    places: Vec<(usize, Child)>,
    /// The root's content, from after its start tag to its end tag's `<`.
    content: Range<usize>,
    /// A camera and a model it has, if any: what a parse in one has seen
    /// when it reads on past them.
    camera: Option<Camera>,
    model: Option<Model>,
    /// The scene it loads to, where the reading keeps it.
    scene: Option<Scene>,
}

/// Edits of a text, one after another, as one span of it: the bytes
/// `start..end` of the text before them are now the bytes
/// [`Span::now`], the text `delta` bytes longer. What a reading reads
/// again, and what the language server sends an app ([`Span::then`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    pub start: usize,
    pub end: usize,
    pub delta: isize,
}

impl Span {
    /// `span` (none: no edit yet), then the bytes `range` of the text as
    /// it then is replaced by `inserted` bytes.
    pub fn then(span: Option<Span>, range: Range<usize>, inserted: usize) -> Span {
        let (a, b) = (range.start, range.end);
        let grown = inserted as isize - (b as isize - a as isize);
        match span {
            None => Span {
                start: a,
                end: b,
                delta: grown,
            },
            Some(d) => {
                // `a` and `b` in the text before: before the span as they
                // are, after it moved back, inside it the span's ends.
                let now_end = (d.end as isize + d.delta) as usize;
                let old = |x: usize, inside: usize| match x {
                    x if x <= d.start => x,
                    x if x >= now_end => (x as isize - d.delta) as usize,
                    _ => inside,
                };
                Span {
                    start: d.start.min(old(a, d.start)),
                    end: d.end.max(old(b, d.end)),
                    delta: d.delta + grown,
                }
            }
        }
    }

    /// Where the span's bytes are in the text after the edits.
    pub fn now(&self) -> Range<usize> {
        self.start..(self.end as isize + self.delta) as usize
    }
}

impl Reading {
    /// A reading that keeps the scene of the text ([`Reading::scene`]),
    /// each check replacing only the objects and lights it reads again.
    pub fn keeping() -> Reading {
        Reading {
            keep: true,
            ..Reading::default()
        }
    }

    /// A reading that keeps the scene, of the text that `layout` places
    /// and that loads to `scene`: as if it had read that text whole.
    pub fn keeping_from(layout: &Layout, scene: Scene) -> Reading {
        let has_model = layout.places.iter().any(|(_, c)| *c == Child::Model);
        Reading {
            known: Some(Known {
                bom: layout.bom,
                places: layout.places.clone(),
                content: layout.content.clone(),
                camera: Some(scene.camera.clone()),
                model: has_model.then_some(scene.model),
                scene: Some(scene),
            }),
            dirty: None,
            keep: true,
            last: None,
        }
    }

    /// The scene of the text as last found without error, where the
    /// reading keeps it ([`Reading::keeping`]).
    pub fn scene(&self) -> Option<&Scene> {
        self.known.as_ref()?.scene.as_ref()
    }

    /// What the last check read, where it found no error.
    pub fn reread(&self) -> Option<&Reread> {
        self.last.as_ref()
    }

    /// The bytes `range` of the text (as it is now) were replaced by
    /// `inserted` bytes.
    pub fn edited(&mut self, range: Range<usize>, inserted: usize) {
        let Some(known) = &self.known else {
            return;
        };
        if range.start < known.bom {
            self.forget();
            return;
        }
        let range = range.start - known.bom..range.end - known.bom;
        self.dirty = Some(Span::then(self.dirty, range, inserted));
    }

    /// The text changed in ways not told: it is read whole next time.
    pub fn forget(&mut self) {
        // A kept scene stays, for its objects to be shared with the next.
        if let Some(known) = &mut self.known {
            known.places = Vec::new();
            known.content = 0..0;
        }
        self.dirty = None;
    }

    /// The first error of `text` (the text as edited), as a parse in one
    /// gives it; read from the edits on where it can be. `lines`: where
    /// the lines of `text` start, where the caller keeps them (an error is
    /// placed by a search instead of a count of the lines before it).
    pub fn check(&mut self, text: &str, lines: Option<&[usize]>) -> Result<(), LoadError> {
        let path = Path::new("");
        self.last = None;
        if let (Some(known), Some(dirty)) = (&mut self.known, self.dirty)
            && !known.places.is_empty()
            && let Some(found) = again(known, dirty, text, lines, path, self.keep)
        {
            if let Ok(reread) = found {
                self.dirty = None;
                self.last = Some(reread);
                return Ok(());
            }
            return found.map(|_| ());
        }
        self.dirty = None;
        let like = self
            .known
            .as_mut()
            .and_then(|k| k.scene.take())
            .map(|scene| scene.objects);
        let (known, found) = whole(
            text,
            lines,
            path,
            self.keep,
            like.as_ref().map(|o| o.as_slice()),
        );
        match found {
            Ok(()) => {
                self.known = known;
                self.last = Some(Reread::Whole);
                Ok(())
            }
            Err(e) => {
                // Nothing known of this text: read whole next time.
                self.known = None;
                Err(e)
            }
        }
    }
}

/// The text read whole: what is known of it where it has no error (its
/// scene too, where `keep`, sharing the objects of `like` that are equal).
fn whole(
    text: &str,
    lines: Option<&[usize]>,
    path: &Path,
    keep: bool,
    like: Option<&[std::sync::Arc<crate::scene::Object>]>,
) -> (Option<Known>, Result<(), LoadError>) {
    let body = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut parser = Parser::new(body, path);
    parser.lines = lines.map(|l| (l, text.len() - body.len()));
    parser.check_only = !keep;
    parser.record = true;
    if let Some(like) = like {
        parser.like = like;
    }
    match parser.gathered() {
        Ok(mut g) => {
            // (A text read without error has its camera.)
            let scene = g.camera.clone().filter(|_| keep).map(|camera| Scene {
                objects: std::mem::take(&mut g.objects).into(),
                lights: std::mem::take(&mut g.lights),
                camera,
                model: g.model.unwrap_or_default(),
            });
            let known = g
                .content_start
                .zip(g.content_end)
                .map(|(start, end)| Known {
                    bom: text.len() - body.len(),
                    places: g.places,
                    content: start..end,
                    camera: g.camera,
                    model: g.model,
                    scene,
                });
            (known, Ok(()))
        }
        Err(e) => (None, Err(e)),
    }
}

/// The text read again from the edits `dirty` on, where `known` allows
/// (`None`: read it whole), `known` brought up to date where it has no
/// error.
fn again(
    known: &mut Known,
    dirty: Span,
    text: &str,
    lines: Option<&[usize]>,
    path: &Path,
    keep: bool,
) -> Option<Result<Reread, LoadError>> {
    let body = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.len() - body.len() != known.bom
        || dirty.start < known.content.start
        || dirty.end > known.content.end
    {
        return None;
    }
    // The children read again: from the one the edits start in (or the
    // root's content) to the first that starts past them.
    let (first, from) = match known.places.partition_point(|(at, _)| *at <= dirty.start) {
        0 => (0, known.content.start),
        n => (n - 1, known.places[n - 1].0),
    };
    let past = known.places.partition_point(|(at, _)| *at < dirty.end);
    let past = past.max(first);
    let stop = known
        .places
        .get(past)
        .map_or(known.content.end, |(at, _)| *at);
    let stop = usize::try_from(stop as isize + dirty.delta).ok()?;
    // What a parse in one has gathered at `from`.
    let mut before = Gathered::default();
    let seen = counts(&known.places[..first]);
    before.unkept_objects = seen[Child::Object as usize];
    before.unkept_lights = seen[Child::Light as usize];
    if seen[Child::Camera as usize] > 0 {
        before.camera = Some(known.camera.clone()?);
    }
    if seen[Child::Model as usize] > 0 {
        before.model = Some(known.model?);
    }
    let first_object = before.unkept_objects;
    let first_light = before.unkept_lights;
    let mut parser = Parser::new(body, path);
    parser.check_only = !keep;
    parser.record = true;
    parser.stop = Some(stop);
    parser.lines = lines.map(|l| (l, known.bom));
    if let Some(scene) = &known.scene {
        parser.like = scene.objects.get(first_object..).unwrap_or_default();
    }
    let (mut read, stopped) = match parser.document_from(from, before)? {
        Ok(read) => read,
        Err(e) => return Some(Err(e)),
    };
    if !stopped {
        // Read to the end: all of it is known anew.
        let (Some(camera), Some(end)) = (read.camera.clone(), read.content_end) else {
            return None;
        };
        let objects_were = counts(&known.places[first..])[Child::Object as usize];
        let objects_now = read.objects.len() + read.unkept_objects - first_object;
        if let Some(scene) = &mut known.scene {
            let objects = std::mem::take(&mut read.objects);
            if objects_were > 0 || !objects.is_empty() {
                scene.objects.truncate(first_object);
                scene.objects.extend(objects);
            }
            scene.lights.truncate(first_light);
            scene.lights.append(&mut read.lights);
            scene.camera = camera.clone();
            scene.model = read.model.unwrap_or_default();
        }
        known.places.truncate(first);
        known.places.extend(read.places);
        known.content.end = end;
        known.camera = Some(camera);
        known.model = read.model;
        return Some(Ok(Reread::Children {
            text: known.bom + from..known.bom + end,
            first_object,
            objects_were,
            objects_now,
        }));
    }
    // Stopped where the old text goes on: what only the whole can tell
    // is read whole.
    let (old, new) = (counts(&known.places[first..past]), counts(&read.places));
    let (camera, model) = (Child::Camera as usize, Child::Model as usize);
    if old[camera] != new[camera] || old[model] != new[model] {
        return None;
    }
    let rest = counts(&known.places[past..]);
    if read.object_count() + rest[Child::Object as usize] > MAX_OBJECTS
        || read.light_count() + rest[Child::Light as usize] > MAX_LIGHTS
    {
        return None;
    }
    if new[camera] > 0 {
        known.camera = read.camera.clone();
    }
    if new[model] > 0 {
        known.model = read.model;
    }
    let (objects_were, objects_now) = (old[Child::Object as usize], new[Child::Object as usize]);
    let lights_were = old[Child::Light as usize];
    if let Some(scene) = &mut known.scene {
        // The list is touched (and so copied, where shared) only where
        // objects were read again.
        if objects_were > 0 || objects_now > 0 {
            scene.objects.splice(
                first_object..first_object + objects_were,
                std::mem::take(&mut read.objects),
            );
        }
        scene
            .lights
            .splice(first_light..first_light + lights_were, read.lights);
        if let (true, Some(camera)) = (new[camera] > 0, read.camera) {
            scene.camera = camera;
        }
        if let (true, Some(model)) = (new[model] > 0, read.model) {
            scene.model = model;
        }
    }
    known.places.splice(first..past, read.places);
    let moved = first + new.iter().sum::<usize>();
    for (at, _) in &mut known.places[moved..] {
        *at = (*at as isize + dirty.delta) as usize;
    }
    known.content.end = (known.content.end as isize + dirty.delta) as usize;
    Some(Ok(Reread::Children {
        text: known.bom + from..known.bom + stop,
        first_object,
        objects_were,
        objects_now,
    }))
}

/// How many of `places` are of each kind (by [`Child`] as an index).
fn counts(places: &[(usize, Child)]) -> [usize; 4] {
    let mut counts = [0; 4];
    for (_, child) in places {
        counts[*child as usize] += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::super::tests::{below, in_one, varied};
    use super::*;
    use std::sync::Arc;

    /// Where the lines of `text` start, as an editor's server keeps them.
    fn starts(text: &str) -> Vec<usize> {
        crate::scene::language::Lines::new(text).starts().to_vec()
    }

    /// The error as a check gives it (a check names no file).
    fn pathless(e: LoadError) -> LoadError {
        LoadError {
            path: Default::default(),
            ..e
        }
    }

    /// What a parse in one says of `text`, as a check says it.
    fn one(text: &str) -> String {
        let body = text.strip_prefix('\u{feff}').unwrap_or(text);
        format!("{:?}", in_one(body).map(|_| ()).map_err(pathless))
    }

    /// Edits of every kind, one after another, each checked again from
    /// the edits on: each check says what a parse in one of the whole text
    /// says, error, line and column included.
    #[test]
    fn a_check_after_edits_says_what_a_parse_in_one_says() {
        let snippets = [
            "<sphere/>",
            "<light x=\"1\" y=\"2\" z=\"3\"/>",
            "<camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>",
            "<model type=\"lambert\"/>",
            "<!-- a -->",
            "<!--",
            "-->",
            "<",
            ">",
            "x",
            "\"",
            "</sphere>",
            "<sphere>",
            " ",
            "\n",
            "-",
            "é",
        ];
        let mut next = below(0x9E37_79B9_7F4A_7C15u64);
        let base = varied(200);
        let (mut incremental, mut valid) = (0, 0);
        for round in 0..60 {
            // Some texts start with a byte-order mark (not counted in
            // columns).
            let mut text = match round % 4 {
                1 => format!("\u{feff}{base}"),
                _ => base.clone(),
            };
            let mut reading = Reading::default();
            assert_eq!(
                format!("{:?}", reading.check(&text, Some(&starts(&text)))),
                one(&text)
            );
            // The app's reading, keeping the scene, told the same edits.
            let mut keeping = Reading::keeping();
            let _ = keeping.check(&text, None);
            for step in 0..12 {
                let mut at = next(text.len() + 1);
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                // A third of the rounds keep the text valid.
                let kind = if round % 3 == 0 { 3 } else { next(4) };
                let (range, insert) = match kind {
                    // Before a child: an element that keeps the text valid.
                    3 if text[at..].contains("\n  <sphere") => {
                        let at = at + text[at..].find("\n  <sphere").unwrap_or(0) + 3;
                        (at..at, snippets[next(2)].to_owned())
                    }
                    0 => {
                        let mut to = (at + next(30)).min(text.len());
                        while !text.is_char_boundary(to) {
                            to -= 1;
                        }
                        (at..to, String::new())
                    }
                    _ => (at..at, snippets[next(snippets.len())].to_owned()),
                };
                text.replace_range(range.clone(), &insert);
                reading.edited(range.clone(), insert.len());
                keeping.edited(range, insert.len());
                let knew = reading.known.is_some() && reading.dirty.is_some();
                let checked = format!("{:?}", reading.check(&text, Some(&starts(&text))));
                assert_eq!(checked, one(&text), "round {round}, step {step}:\n{text}");
                // The kept scene is the one a parse in one gives.
                let kept = keeping.check(&text, None).map(|()| keeping.scene());
                let body = text.strip_prefix('\u{feff}').unwrap_or(&text);
                match (kept, in_one(body)) {
                    (Ok(kept), Ok(scene)) => assert_eq!(
                        format!("{:?}", kept.expect("a kept scene")),
                        format!("{scene:?}"),
                        "round {round}, step {step}:\n{text}"
                    ),
                    (Err(_), Err(_)) => {}
                    (kept, parsed) => panic!("{kept:?} against {parsed:?}"),
                }
                incremental += usize::from(knew);
                valid += usize::from(checked == "Ok(())");
            }
        }
        // Most checks read from the edits on; some texts stay valid.
        assert!(
            incremental > 300 && valid > 150,
            "{incremental} from the edits, {valid} valid"
        );
    }

    /// An edit in the middle of a long text reads a few children, not the
    /// text: its places move, and a fix is known without a whole reading.
    #[test]
    fn an_edit_reads_only_the_children_it_touches() {
        let text = varied(2000);
        let mut reading = Reading::default();
        assert!(reading.check(&text, Some(&starts(&text))).is_ok());
        let places = reading.known.as_ref().unwrap().places.clone();
        let at = text.len() / 2 + text[text.len() / 2..].find("<sphere/>").unwrap();
        let mut broken = text.clone();
        broken.insert(at + 1, 'x');
        reading.edited(at + 1..at + 1, 1);
        let e = reading.check(&broken, Some(&starts(&broken))).unwrap_err();
        assert_eq!(Some(e.clone()), in_one(&broken).err().map(pathless));
        // The fix: known again, the places as before.
        reading.edited(at + 1..at + 2, 0);
        assert!(reading.check(&text, Some(&starts(&text))).is_ok());
        assert_eq!(reading.known.as_ref().unwrap().places, places);
        assert!(reading.dirty.is_none());
        // A sphere more: the places after it move.
        let mut more = text.clone();
        more.insert_str(at, "<sphere/>");
        reading.edited(at..at, 9);
        assert!(reading.check(&more, Some(&starts(&more))).is_ok());
        let moved = &reading.known.as_ref().unwrap().places;
        assert_eq!(moved.len(), places.len() + 1);
        assert_eq!(moved.last().unwrap().0, places.last().unwrap().0 + 9);
    }

    /// A reading that keeps the scene replaces only what it read again:
    /// a light's edit leaves the objects' list the same list, a sphere's
    /// shares every other sphere, and says which children it read.
    #[test]
    fn a_kept_scene_changes_only_where_the_edit_falls() {
        let text = varied(2000);
        let mut reading = Reading::keeping();
        reading.check(&text, None).unwrap();
        assert_eq!(reading.reread(), Some(&Reread::Whole));
        let before = reading.scene().unwrap().clone();

        let at = text.rfind("<light").unwrap() + "<light".len();
        let x = at + text[at..].find("x=\"").unwrap() + 3;
        let mut lit = text.clone();
        lit.insert(x, '7');
        reading.edited(x..x, 1);
        reading.check(&lit, None).unwrap();
        let after = reading.scene().unwrap();
        assert!(after.objects.same_list(&before.objects));
        assert_ne!(after.lights, before.lights);
        assert!(matches!(
            reading.reread(),
            Some(Reread::Children {
                objects_were: 0,
                objects_now: 0,
                ..
            })
        ));

        let at = text.len() / 2 + text[text.len() / 2..].find("\n  <sphere").unwrap() + 3;
        let mut grown = lit.clone();
        grown.insert_str(at, "<sphere/>");
        reading.edited(at..at, 9);
        reading.check(&grown, None).unwrap();
        let after = reading.scene().unwrap();
        assert_eq!(after.objects.len(), before.objects.len() + 1);
        let Some(Reread::Children {
            first_object,
            objects_were,
            objects_now,
            ..
        }) = reading.reread().cloned()
        else {
            panic!("read whole")
        };
        // Every object outside the children read again is shared.
        let same = |a: &[Arc<crate::scene::Object>], b: &[Arc<crate::scene::Object>]| {
            a.len() == b.len() && a.iter().zip(b).all(|(a, b)| Arc::ptr_eq(a, b))
        };
        assert!(same(
            &after.objects[..first_object],
            &before.objects[..first_object]
        ));
        assert!(same(
            &after.objects[first_object + objects_now..],
            &before.objects[first_object + objects_were..]
        ));
        assert_eq!(objects_now, objects_were + 1);
        assert_eq!(
            format!("{:?}", after.objects[first_object]),
            format!("{:?}", in_one(&grown).unwrap().objects[first_object])
        );
    }
}
