//! How objects are named for people: `#2 RED sphere` in the panel and the
//! explain output, `#2 sphere` in an undo step's label. The number counts
//! from 1 in file order (as paths do); the words are the first ones of the
//! comment directly above the object in the file ([`object_labels`]).

use super::layout;
use super::source::Source;

/// The first words of the comment directly above each object (spheres and
/// planes in file order), for naming it in the panel: up to three, before
/// any punctuation ("RED sphere" for `<!-- RED sphere, left -->`).
///
/// Only the objects that have some are held: a million spheres without a
/// comment hold nothing (a list of a million `None`s was 24 MB).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Labels(
    /// (object number, its words), by object number.
    Vec<(usize, Box<str>)>,
);

impl Labels {
    /// The words of object `k` (0-based, in file order), if a comment
    /// touches it.
    pub fn get(&self, k: usize) -> Option<&str> {
        let i = self.0.binary_search_by_key(&k, |(n, _)| *n).ok()?;
        Some(&self.0[i].1)
    }
}

/// The [`Labels`] of `text`'s objects.
pub fn object_labels(text: &str) -> Labels {
    labels_of(layout::object_comments(text))
}

/// The [`Labels`] of the objects of a text held as a [`Source`] (a packed
/// one is read a block at a time).
pub fn source_labels(source: &Source) -> Labels {
    let comments = layout::source_object_comments(source);
    labels_of(comments.iter().map(|(k, c)| (*k, c.as_str())))
}

/// The labels made of the comments above objects: (object number, the
/// comment between its `<!--` and `-->`), by object number.
fn labels_of<'a>(comments: impl Iterator<Item = (usize, &'a str)>) -> Labels {
    Labels(
        comments
            .filter_map(|(k, comment)| {
                // Up to the first punctuation, at most three words.
                let phrase = comment
                    .split([',', '.', ':', ';', '(', '-', '\n'])
                    .find(|p| !p.trim().is_empty())?;
                let label = phrase
                    .split_whitespace()
                    .take(3)
                    .collect::<Vec<_>>()
                    .join(" ");
                (!label.is_empty()).then(|| (k, label.into_boxed_str()))
            })
            .collect(),
    )
}

/// The name of object `n` (0-based) of shape `shape`, given the first
/// words of the comment above it ([`object_labels`]): `#2 RED sphere`,
/// `#2 sphere` without a comment.
pub fn object_name(n: usize, shape: &str, words: Option<&str>) -> String {
    match words {
        Some(w) if w.to_lowercase().ends_with(shape) => format!("#{} {w}", n + 1),
        Some(w) => format!("#{} {w} {shape}", n + 1),
        None => format!("#{} {shape}", n + 1),
    }
}
