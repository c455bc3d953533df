//! Following the user's editor: its unsaved text of the file, on screen
//! instead of the document while it holds one ([`Document::follow`]), kept
//! up to date an edit at a time ([`Document::follow_edit`]).
//!
//! The text is held whole (an edit splices it in place) with a
//! [`Reading`] that keeps its scene: an edit reads again only the root's
//! children it touches, and the scene shares every other object and the
//! list itself where no object was read again, so the renderer sees at
//! once what stayed (an edit of a light on a million spheres prepares no
//! geometry). The objects' labels are read again only where an edit can
//! have changed them: a comment, or objects more or fewer.
//!
//! The editor's first text starts from the file's: the bytes where the
//! two differ ([`Source::difference`]) are an edit of the file's text,
//! read from where the file's load placed its children (its
//! [`Layout`]), the rest of the scene the file's own
//! (a million spheres: 70 ms, where reading the text whole took 2.6 s).
//!
//! An editor's text that is not on screen because it is the file's (handed
//! whole, or an edit took it back there) or one it saved is kept whole, as
//! it was when followed ([`EditorBase`]): its next change is applied there,
//! not asked for whole again nor unpacked from the file's packed text, and
//! where that text is known to be the file's, the change is read where it
//! falls without comparing the two ([`Document::text_from`]).

use std::ops::Range;
use std::sync::Arc;

use super::disk::fingerprint;
use super::{Document, Version, next_generation};
use crate::desktop::editor_link::apply_change;
use crate::scene::source::Source;
use crate::scene::{Layout, LoadError, Reading, Reread, names};

/// The editor's text being followed, and what shows from it.
#[derive(Debug, Clone)]
pub(super) struct Following {
    /// The editor's newest text.
    text: String,
    /// What is known of `text` (its scene as last read without error).
    reading: Reading,
    /// The objects' labels of the text the reading last read without
    /// error (or of the file's text it starts from)...
    labels: Arc<names::Labels>,
    /// ...unless a comment's marker was edited since.
    labels_stale: bool,
    /// The scene of the last text that loaded, on screen.
    pub(super) version: Version,
}

impl Following {
    /// The editor's newest text.
    pub(super) fn text(&self) -> &str {
        &self.text
    }
}

/// An edit that does not fit the text it is said to change: the app
/// missed a change (it asks for the whole text again).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("an edit of the editor's text that does not fit the text held")]
pub struct Unfit;

/// An editor's text that is not on screen, held whole so that its next
/// change is applied to it (not asked for whole again, nor unpacked from
/// the file's), with what tells whether it is the file's text: then the
/// change is read where it falls, without comparing the two.
#[derive(Debug)]
pub struct EditorBase {
    text: String,
    of: BaseOf,
}

/// What an [`EditorBase`]'s text is known to be.
#[derive(Debug)]
enum BaseOf {
    /// The text of this [`Source`] (the file's, when the editor's text
    /// was found equal to it).
    Source(Source),
    /// A text the editor saved, by its fingerprint: the file's once the
    /// file is read back with it.
    Saved(u64),
}

/// An editor's text made from what the app knew of it
/// ([`Document::text_from`]).
#[derive(Debug)]
pub struct Rebuilt {
    text: String,
    /// The bytes of the file's text it replaced, and how many replace
    /// them, where it is an edit of the file's text that changes it.
    of_file: Option<(Range<usize>, usize)>,
}

impl From<String> for Rebuilt {
    /// A text handed whole: where it differs from the file's is not known.
    fn from(text: String) -> Rebuilt {
        Rebuilt {
            text,
            of_file: None,
        }
    }
}

/// What following an editor's text came to ([`Document::follow`]).
#[derive(Debug)]
pub enum Followed {
    /// Its text is on screen.
    Shown,
    /// It is the file's text: the document is on screen, and this is
    /// what the editor's next change is of.
    File(EditorBase),
}

impl Followed {
    /// Whether the editor's text is on screen.
    pub fn is_shown(&self) -> bool {
        matches!(self, Followed::Shown)
    }
}

impl EditorBase {
    /// A text the editor saved (its fingerprint made here, once).
    pub fn saved(text: String) -> EditorBase {
        let of = BaseOf::Saved(fingerprint(text.as_bytes()));
        EditorBase { text, of }
    }
}

impl Document {
    /// An editor's `text`, which is the file's (its whole text was, or an
    /// edit took it back there): what its next edit is of.
    fn file_base(&self, text: String) -> EditorBase {
        let of = BaseOf::Source(self.file.source.clone());
        EditorBase { text, of }
    }

    /// The editor's text on screen, which it saved, taken (the document
    /// goes on following it, empty, until told otherwise): what its next
    /// edit is of. `None` while not following.
    pub fn take_saved_base(&mut self) -> Option<EditorBase> {
        self.take_editor_text().map(EditorBase::saved)
    }

    /// An editor's text, `base`'s with a change (the bytes `range`
    /// replaced by `inserted`, making `length` bytes), to follow
    /// ([`Document::follow_rebuilt`]); `None` where the change does not
    /// fit. Where `base` is known to be the file's text, the change is
    /// said to be an edit of it.
    pub fn text_from(
        &self,
        base: EditorBase,
        range: Range<usize>,
        inserted: &str,
        length: usize,
    ) -> Option<Rebuilt> {
        let EditorBase { mut text, of } = base;
        let is_file = match of {
            BaseOf::Source(source) => source.same(&self.file.source),
            BaseOf::Saved(saved) => self.file.fingerprint == Some(saved),
        };
        let same = text.get(range.clone()) == Some(inserted);
        let of_file = (is_file && !same).then(|| (range.clone(), inserted.len()));
        apply_change(&mut text, range, inserted, length).then_some(Rebuilt { text, of_file })
    }

    /// Shows the user's editor's unsaved `text` of this file instead of the
    /// document (which waits, unsaved edits and all): what `rayoflight lsp`
    /// hands over, read where it differs from the file's text. A text
    /// that does not load keeps the last one that did on screen, with its
    /// error; the file's own text ends the following. Nothing is written.
    pub fn follow(&mut self, text: String) -> Followed {
        let difference = self.file.source.difference(&text);
        self.follow_differing(text, difference)
    }

    /// [`Document::follow`], the editor's text made from what the app
    /// knew of it ([`Document::text_from`]) or handed whole: where it is
    /// an edit of the file's text, that edit is where it differs, not
    /// compared again.
    pub fn follow_rebuilt(&mut self, rebuilt: Rebuilt) -> Followed {
        match rebuilt.of_file {
            Some(edit) => self.follow_differing(rebuilt.text, Some(edit)),
            None => self.follow(rebuilt.text),
        }
    }

    /// [`Document::follow`], `difference` the bytes of the file's text
    /// that `text` replaces and how many replace them (`None`: none, it
    /// is the file's text).
    fn follow_differing(
        &mut self,
        text: String,
        difference: Option<(Range<usize>, usize)>,
    ) -> Followed {
        // What differs from the file's text (the editor opened the file,
        // then typed): read from the file's layout, only there.
        let Some((range, inserted)) = difference else {
            self.unfollow();
            return Followed::File(self.file_base(text));
        };
        let version = match self.editor.take() {
            Some(was) => was.version,
            None => self.shown.clone(),
        };
        // Where the file's layout is not known, the text is read whole,
        // sharing the objects of the file's scene that it has the same.
        let layout = self.file.layout.as_deref();
        let mut reading = Reading::keeping_from(
            layout.unwrap_or(&Layout::default()),
            self.file.source_scene.clone(),
        );
        // The file's labels, unless the file's bytes it replaces touch a
        // comment's marker.
        let near = range.start.saturating_sub(3)..range.end + 3;
        let replaced = self.file.source.bytes(near);
        let labels_stale =
            has_marker(&replaced) || has_marker(&text.as_bytes()[range.start..][..inserted]);
        reading.edited(range, inserted);
        let mut following = Following {
            text,
            reading,
            labels: Arc::clone(&self.file.labels),
            labels_stale,
            version,
        };
        self.read_following(&mut following);
        self.editor = Some(following);
        Followed::Shown
    }

    /// The editor's text changed: the bytes `range` of the text followed
    /// are now `inserted`, making it `length` bytes long. Reads again only
    /// what the edit touches ([`Followed::File`]: the text is the file's
    /// again); [`Unfit`] where the edit does not fit the text held, which
    /// is left as it was.
    pub fn follow_edit(
        &mut self,
        range: Range<usize>,
        inserted: &str,
        length: usize,
    ) -> Result<Followed, Unfit> {
        let Some(mut following) = self.editor.take() else {
            return Err(Unfit);
        };
        // A comment's marker the edit cuts into or out of: labels change.
        let bytes = following.text.as_bytes();
        let window = bytes
            .get(range.start.saturating_sub(3)..(range.end + 3).min(bytes.len()))
            .unwrap_or_default();
        let cut_marker = has_marker(window) || has_marker(inserted.as_bytes());
        if !apply_change(&mut following.text, range.clone(), inserted, length) {
            self.editor = Some(following);
            return Err(Unfit);
        }
        if self.file.source.is_near(&following.text, range.start) {
            // Back to the document (its error, if the last text had one,
            // goes with the text).
            let text = std::mem::take(&mut following.text);
            self.editor = Some(following);
            self.unfollow();
            return Ok(Followed::File(self.file_base(text)));
        }
        following.reading.edited(range, inserted.len());
        following.labels_stale |= cut_marker;
        self.read_following(&mut following);
        self.editor = Some(following);
        Ok(Followed::Shown)
    }

    /// Reads `following`'s text where its reading needs (whole, or where
    /// the edits since fall), and puts its scene on screen, or its error
    /// in the banner over the last scene that loaded.
    fn read_following(&mut self, following: &mut Following) {
        let reading = &mut following.reading;
        let found = reading.check(&following.text, None);
        // (A text read without error has its scene kept.)
        match found.map(|()| reading.scene().cloned()) {
            Ok(Some(scene)) => {
                let stale = following.labels_stale
                    || match reading.reread() {
                        Some(Reread::Children {
                            text,
                            objects_were,
                            objects_now,
                            ..
                        }) => {
                            objects_were != objects_now
                                || following.text[text.clone()].contains("<!--")
                        }
                        _ => true,
                    };
                if stale {
                    following.labels = Arc::new(names::object_labels(&following.text));
                    following.labels_stale = false;
                }
                let labels = Arc::clone(&following.labels);
                following.version = Version::new(Source::default(), scene, labels);
                self.editor_error = None;
            }
            Ok(None) => {}
            Err(e) => {
                let path = self.path.clone().unwrap_or_default();
                self.editor_error = Some(LoadError { path, ..e }.to_string());
            }
        }
        self.generation = next_generation();
    }

    /// The editor's newest text, while it is followed: taken, for a caller
    /// that shows another editor's text and may show this one again.
    pub fn take_editor_text(&mut self) -> Option<String> {
        self.editor.as_mut().map(|f| std::mem::take(&mut f.text))
    }

    /// Back to the document: the editor saved or closed the file.
    pub fn unfollow(&mut self) {
        if self.editor.take().is_some() {
            self.editor_error = None;
            self.generation = next_generation();
        }
    }

    /// Whether the editor's unsaved text is on screen
    /// ([`Document::follow`]): the panel is read-only, saving waits.
    pub fn is_following(&self) -> bool {
        self.editor.is_some()
    }
}

/// Whether `bytes` hold a comment's marker, opening or closing.
fn has_marker(bytes: &[u8]) -> bool {
    bytes.windows(4).any(|w| w == b"<!--") || bytes.windows(3).any(|w| w == b"-->")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two spheres after a byte-order mark, a comment with a letter of two
    /// bytes naming the second.
    const TEXT: &str = "\u{feff}<scene>\n  <sphere><material ka=\"0.2\"/></sphere>\n  <!-- é ball -->\n  <sphere><material ka=\"0.3\"/></sphere>\n  <light x=\"1\" y=\"2\" z=\"3\"/>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"2\"/>\n</scene>\n";

    fn open() -> (tempfile::TempDir, Document) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.xml");
        std::fs::write(&path, TEXT).unwrap();
        let doc = Document::open(&path).unwrap();
        (dir, doc)
    }

    /// Edits after a byte-order mark, one into a comment's label: the
    /// scene and the labels are those of the text read whole.
    #[test]
    fn edits_give_the_scene_and_labels_of_the_text() {
        let (_dir, mut doc) = open();
        let mut text = TEXT.replace("ka=\"0.2\"", "ka=\"0.25\"");
        assert!(doc.follow(text.clone()).is_shown());
        assert_eq!(doc.scene().objects[0].material.ka, 0.25);
        let mut edit = |doc: &mut Document, from: &str, to: &str| {
            let at = text.find(from).unwrap();
            text.replace_range(at..at + from.len(), to);
            doc.follow_edit(at..at + from.len(), to, text.len())
                .unwrap()
                .is_shown()
        };
        assert!(edit(&mut doc, "ka=\"0.3\"", "ka=\"0.35\""));
        assert_eq!(doc.scene().objects[1].material.ka, 0.35);
        assert_eq!(doc.object_label(1), "#2 é ball sphere");
        assert!(edit(&mut doc, "é ball", "é red ball"));
        assert_eq!(doc.object_label(1), "#2 é red ball sphere");
        assert!(edit(&mut doc, "x=\"1\"", "x=\"9\""));
        assert_eq!(doc.scene().lights[0].position.x, 9.0);
        assert_eq!(doc.error(), None);
    }

    /// A comment cut by an edit whose text has an error: once an edit
    /// elsewhere fixes the error, the labels are read again, the comment
    /// gone. A first text that cuts the file's comment likewise.
    #[test]
    fn a_comment_cut_while_the_text_has_an_error_still_changes_the_labels() {
        let (_dir, mut doc) = open();
        let mut text = TEXT.to_owned();
        let cut = "<!-- é ball -->\n  <sphere><material ka=\"0.3\"";
        let at = text.find(cut).unwrap();
        let put = "<sphere><material ka=\"0.3x\"";
        text.replace_range(at..at + cut.len(), put);
        // The first text: the file's, with the comment cut and an error.
        assert!(doc.follow(text.clone()).is_shown());
        assert!(doc.error().is_some());
        assert_eq!(doc.object_label(1), "#2 é ball sphere");
        let x = at + put.find('x').unwrap();
        let fixed = doc.follow_edit(x..x + 1, "", text.len() - 1);
        assert!(fixed.unwrap().is_shown());
        assert_eq!(doc.error(), None);
        assert_eq!(doc.scene().objects[1].material.ka, 0.3);
        assert!(
            !doc.object_label(1).contains("ball"),
            "{}",
            doc.object_label(1)
        );
        // Followed from the file's text again, the comment cut and no
        // error: the labels without it at once.
        doc.unfollow();
        text.replace_range(x..x + 1, "");
        assert!(doc.follow(text).is_shown());
        assert!(
            !doc.object_label(1).contains("ball"),
            "{}",
            doc.object_label(1)
        );
    }

    /// The editor's first text, the file's with an edit, is read from
    /// where the file's load placed its children, only where it differs:
    /// the other objects are the file's own. A text that differs from
    /// its first byte (its byte-order mark gone) is read whole, and is
    /// the same scene.
    #[test]
    fn the_first_text_is_read_where_it_differs_from_the_files() {
        let (_dir, mut doc) = open();
        assert!(doc.file.layout.as_ref().is_some_and(|l| l.children() == 4));
        let text = TEXT.replace("ka=\"0.3\"", "ka=\"0.35\"");
        assert!(doc.follow(text.clone()).is_shown());
        let reading = &doc.editor.as_ref().unwrap().reading;
        assert!(matches!(
            reading.reread(),
            Some(Reread::Children {
                first_object: 1,
                objects_were: 1,
                objects_now: 1,
                ..
            })
        ));
        let parsed = crate::scene::parse(&text, std::path::Path::new("s.xml")).unwrap();
        assert_eq!(doc.scene(), &parsed);
        let file = doc.file.source_scene.objects.clone();
        assert!(Arc::ptr_eq(&doc.scene().objects[0], &file[0]));
        assert_eq!(doc.object_label(1), "#2 é ball sphere");
        // Whole, without the mark.
        let bare = text.strip_prefix('\u{feff}').unwrap().to_owned();
        assert!(doc.follow(bare).is_shown());
        let reading = &doc.editor.as_ref().unwrap().reading;
        assert_eq!(reading.reread(), Some(&Reread::Whole));
        assert_eq!(doc.scene(), &parsed);
        assert!(Arc::ptr_eq(&doc.scene().objects[0], &file[0]));
    }

    /// An edit of a text the editor saved is applied to the text kept:
    /// compared with the file's before the file is read back with it,
    /// read where it falls after; so is an edit of the file's own text.
    #[test]
    fn an_edit_of_a_saved_text_is_the_files_once_read_back() {
        let (_dir, mut doc) = open();
        let saved = TEXT.replace("ka=\"0.2\"", "ka=\"0.25\"");
        assert!(doc.follow(saved.clone()).is_shown());
        let at = saved.find("0.25").unwrap();
        let edited = saved.replace("0.25", "0.5");
        let edit = |doc: &Document, base| {
            let rebuilt = doc.text_from(base, at..at + 4, "0.5", saved.len() - 1);
            rebuilt.map(|r: Rebuilt| (r.text, r.of_file))
        };
        // Not read back yet: where it differs is not known.
        let base = doc.take_saved_base().expect("following");
        assert_eq!(edit(&doc, base), Some((edited.clone(), None)));
        doc.unfollow();
        let scene = crate::scene::parse(&saved, std::path::Path::new("s.xml")).unwrap();
        doc.file_loaded(saved.clone(), scene);
        let base = EditorBase::saved(saved.clone());
        assert_eq!(
            edit(&doc, base),
            Some((edited.clone(), Some((at..at + 4, 3))))
        );
        let base = doc.file_base(saved.clone());
        assert_eq!(edit(&doc, base), Some((edited, Some((at..at + 4, 3)))));
        // A change that does not fit is refused.
        let base = doc.file_base(saved.clone());
        assert!(doc.text_from(base, at..at + 4, "0.5", 7).is_none());
        // Followed where the edit falls, not compared whole.
        let base = doc.file_base(saved.clone());
        let rebuilt = doc.text_from(base, at..at + 4, "0.5", saved.len() - 1);
        assert!(doc.follow_rebuilt(rebuilt.unwrap()).is_shown());
        assert_eq!(doc.scene().objects[0].material.ka, 0.5);
        // A change that changes nothing: the file's text, kept for the
        // next change.
        let base = doc.file_base(saved.clone());
        let same = doc.text_from(base, at..at + 4, "0.25", saved.len());
        assert_eq!(same.as_ref().map(|r| &r.of_file), Some(&None));
        match doc.follow_rebuilt(same.unwrap()) {
            Followed::File(base) => assert_eq!(base.text, saved),
            Followed::Shown => panic!("the file's own text is not followed"),
        }
        assert!(!doc.is_following());
    }

    /// A text with an error keeps the last good scene with the error; the
    /// editor's text back to the file's ends the following, and the
    /// error with it.
    #[test]
    fn back_to_the_files_text_ends_the_following_and_its_error() {
        let (_dir, mut doc) = open();
        let changed = TEXT.replace("ka=\"0.2\"", "ka=\"0.25\"");
        assert!(doc.follow(changed.clone()).is_shown());
        let at = changed.find("ka=\"0.25\"").unwrap() + 4;
        // `0.25` → `0.25x`: not a number.
        assert_eq!(
            doc.follow_edit(at + 4..at + 4, "x", changed.len() + 1)
                .map(|f| f.is_shown()),
            Ok(true)
        );
        assert!(doc.error().is_some());
        assert_eq!(doc.scene().objects[0].material.ka, 0.25);
        let generation = doc.generation();
        // `0.25x` → `0.2`: the file's text.
        let back = doc.follow_edit(at..at + 5, "0.2", TEXT.len());
        assert!(matches!(back, Ok(Followed::File(base)) if base.text == TEXT));
        assert!(!doc.is_following());
        assert_eq!(doc.error(), None);
        assert_ne!(doc.generation(), generation);
        // An edit that does not fit what is held is refused.
        assert!(doc.follow(changed.clone()).is_shown());
        assert!(matches!(doc.follow_edit(0..1, "x", 5), Err(Unfit)));
    }
}
