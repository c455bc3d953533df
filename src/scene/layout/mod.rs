//! Where things sit in a scene file's text: each element's bytes, each
//! attribute value's range, each comment, where each object (sphere or
//! plane) is, and how the file indents and ends its lines. Save-back
//! ([`super::splice`]) edits the text by these places; the panel's object
//! names ([`super::names`]) read the comments above the objects; the
//! language server ([`super::language`]) outlines the root's children; the
//! app opens an editor at an object ([`object_position`]).
//!
//! [`Doc::scan`] scans a text with quick-xml, keeping as nodes only the
//! elements it is asked for ([`Keep`]): a million objects are placed
//! (16 bytes each), not kept as a million nodes. A text held packed is
//! read through its [`skeleton`], the text with the insides of the objects
//! left out.

use std::borrow::Cow;
use std::ops::Range;

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

use super::Shape;
use super::edit::EditError;
use super::source::Source;

pub(super) mod skeleton;

use skeleton::Skeleton;

/// An error of the text's scan that a valid scene's text never gives.
pub(in crate::scene) fn internal(message: impl Into<String>) -> EditError {
    EditError::Internal(message.into())
}

/// The line ending new lines get in `text`: CRLF where it has one, LF
/// where it has one, a lone CR where it has only those (a file of classic
/// Mac OS), else LF.
fn line_ending(text: &str) -> &'static str {
    if text.contains("\r\n") {
        "\r\n"
    } else if text.contains('\n') || !text.contains('\r') {
        "\n"
    } else {
        "\r"
    }
}

/// The comment directly above each object that has one (spheres and
/// planes numbered in file order from 0), between its `<!--` and `-->`.
/// [`super::names`] makes the panel's labels of them.
pub(in crate::scene) fn object_comments(text: &str) -> impl Iterator<Item = (usize, &str)> {
    // Where the objects are is all it needs: they are not kept as nodes
    // (a million objects would be a million nodes, and five million with
    // their elements).
    let doc = text
        .contains("<!--")
        .then(|| Doc::scan(text, Keep::Placed).ok())
        .flatten();
    // Without a comment in the text, no object has one.
    let places = doc
        .as_ref()
        .filter(|d| !d.comments.is_empty())
        .map_or(0, |d| d.objects.len());
    (0..places).filter_map(move |k| {
        let doc = doc.as_ref()?;
        let comment = doc.comments_above(doc.objects[k].start).last()?.clone();
        Some((k, text.get(comment.start + 4..comment.end - 3)?))
    })
}

/// [`object_comments`] of a text held as a [`Source`]: of its skeleton
/// with every object's inside left out (a packed text is never unpacked
/// whole). The comments above the objects are all outside them, and so is
/// every line an object starts on, up to its start: what is found is what
/// the whole text gives.
pub(in crate::scene) fn source_object_comments(source: &Source) -> Vec<(usize, String)> {
    if let Some(text) = source.as_str() {
        return object_comments(text)
            .map(|(k, c)| (k, c.to_owned()))
            .collect();
    }
    let Ok(skeleton) = Skeleton::read(source, &std::collections::HashSet::new(), false) else {
        return Vec::new();
    };
    object_comments(&skeleton.text)
        .map(|(k, c)| (k, c.to_owned()))
        .collect()
}

/// The elements directly inside `<scene>`, in file order: each one's name,
/// its bytes (`<` to the end of its end tag) and its start tag's bytes.
/// Empty when the text is not well-formed XML.
pub fn top_level(text: &str) -> Vec<(&str, Range<usize>, Range<usize>)> {
    let mut children = Vec::new();
    match each_top_level(text, |name, element, tag| {
        children.push((name, element, tag))
    }) {
        true => children,
        false => Vec::new(),
    }
}

/// [`top_level`] one child at a time, none kept: `f` has each root's
/// child's name, element bytes and start tag bytes, in file order; false
/// (after the children before the fault) when the text is not
/// well-formed XML. An outline of a million objects lists a few hundred,
/// and holds no more.
pub fn each_top_level<'t>(
    text: &'t str,
    mut f: impl FnMut(&'t str, Range<usize>, Range<usize>),
) -> bool {
    let body = text.strip_prefix('\u{feff}').unwrap_or(text);
    let base = text.len() - body.len();
    let mut reader = Reader::from_str(body);
    let config = reader.config_mut();
    config.check_end_names = true;
    config.expand_empty_elements = false;
    config.trim_text(false);
    let mut depth = 0usize;
    let mut root_seen = false;
    // The open child of the root: its name, start and start tag's end.
    let mut open: Option<(&'t str, usize, usize)> = None;
    loop {
        let before = base + reader.buffer_position() as usize;
        let Ok(event) = reader.read_event() else {
            return false;
        };
        let after = base + reader.buffer_position() as usize;
        let (start, empty) = match event {
            Event::Start(start) => (start, false),
            Event::Empty(start) => (start, true),
            Event::End(_) => {
                depth = depth.saturating_sub(1);
                if depth == 1
                    && let Some((name, at, tag_end)) = open.take()
                {
                    f(name, at..after, at..tag_end);
                }
                continue;
            }
            Event::Eof => return depth == 0 && root_seen,
            _ => continue,
        };
        if depth == 0 {
            if root_seen {
                return false;
            }
            root_seen = true;
        } else if depth == 1 {
            let name_len = start.name().as_ref().len();
            let Some(name) = text.get(before + 1..before + 1 + name_len) else {
                return false;
            };
            match empty {
                true => f(name, before..after, before..after),
                false => open = Some((name, before, after)),
            }
        }
        if !empty {
            depth += 1;
        }
    }
}

/// Where the element of object `index` (spheres and planes in file order)
/// starts in `text`: its line and column, for an editor to open at.
pub fn object_position(text: &str, index: usize) -> Option<super::Position> {
    let doc = Doc::scan(text, Keep::Placed).ok()?;
    let place = doc.objects.get(index)?;
    Some(super::Position::at_offset(text, place.start))
}

/// One attribute: its name and the byte range of its raw value, between the
/// quotes.
pub(super) struct AttrSpan<'t> {
    pub(super) name: &'t str,
    pub(super) value: Range<usize>,
}

/// One element of the text, with byte offsets into the whole text.
pub(super) struct Node<'t> {
    pub(super) name: &'t str,
    /// Offset of the `<` of the start tag.
    pub(super) start: usize,
    /// Offset just past the `>` of the start tag.
    pub(super) tag_end: usize,
    /// `<x/>`: no content and no end tag.
    pub(super) empty: bool,
    /// The end tag `</x>`; `tag_end..tag_end` for an empty element.
    pub(super) end: Range<usize>,
    pub(super) attrs: Vec<AttrSpan<'t>>,
    pub(super) children: Vec<usize>,
}

impl Node<'_> {
    /// Offset just past the whole element.
    pub(super) fn elem_end(&self) -> usize {
        if self.empty {
            self.tag_end
        } else {
            self.end.end
        }
    }
}

pub(super) struct Doc<'t> {
    pub(super) text: &'t str,
    /// Offset of the text after a byte-order mark (0 without one).
    pub(super) base: usize,
    /// The file's line ending.
    pub(super) nl: &'static str,
    /// One level of indentation, as the file writes it.
    pub(super) unit: String,
    pub(super) nodes: Vec<Node<'t>>,
    pub(super) root: usize,
    /// Every comment, `<!--` to `-->`, in text order.
    pub(super) comments: Vec<Range<usize>>,
    /// Where each object (the root's spheres and planes, in text order)
    /// is, whether or not it is kept as a node: a million objects need a
    /// million places (16 bytes each), not a million nodes (over 100).
    pub(super) objects: Vec<Place>,
    /// The node of each object kept as one: (object number, node).
    pub(super) object_nodes: Vec<(usize, usize)>,
    /// In a skeleton with objects folded away, each object's number in
    /// the whole text ([`Folded::numbers`](skeleton::Folded::numbers));
    /// `None`: the objects are all here.
    pub(super) numbers: Option<&'t [usize]>,
}

/// Where an element is: the offset of its `<` and the offset just past
/// the whole element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Place {
    pub(super) start: usize,
    pub(super) end: usize,
}

/// Which elements [`Doc::scan`] keeps; the others are only checked.
#[derive(Clone, Copy)]
pub(super) enum Keep<'a> {
    #[cfg(test)]
    All,
    /// The root and its children (as nodes: [`each_top_level`] reads
    /// them keeping none).
    #[cfg(test)]
    TopLevel,
    /// The root and its children but the objects (spheres and planes),
    /// which are only placed (`Doc::objects`).
    Placed,
    /// Every element but the objects (spheres and planes, numbered in
    /// text order) not in the set, which are only placed.
    Objects(&'a std::collections::HashSet<usize>),
    /// As `Objects`, in a skeleton with objects folded away
    /// ([`Folded`](skeleton::Folded)): its folds are not elements.
    Folded(&'a std::collections::HashSet<usize>),
}

impl<'t> Doc<'t> {
    /// Scans `text`, keeping the elements `keep` asks for.
    pub(super) fn scan(text: &'t str, keep: Keep) -> Result<Doc<'t>, EditError> {
        let body = text.strip_prefix('\u{feff}').unwrap_or(text);
        let base = text.len() - body.len();
        let offset = |slice: &[u8]| -> Result<usize, EditError> {
            (slice.as_ptr() as usize)
                .checked_sub(body.as_ptr() as usize)
                .filter(|&o| o.saturating_add(slice.len()) <= body.len())
                .map(|o| o + base)
                .ok_or_else(|| internal("a slice outside the text"))
        };

        let mut reader = Reader::from_str(body);
        let config = reader.config_mut();
        config.check_end_names = true;
        config.expand_empty_elements = false;
        config.trim_text(false);

        let mut nodes: Vec<Node<'t>> = Vec::new();
        // The open elements, `None` for those not kept.
        let mut stack: Vec<Option<usize>> = Vec::new();
        // While inside an object whose elements are not kept: the depth of
        // the stack at its start.
        let mut skip_below: Option<usize> = None;
        let mut root = None;
        let mut comments = Vec::new();
        let mut objects: Vec<Place> = Vec::new();
        let mut object_nodes = Vec::new();
        // Inside an object that is only placed: its end is not known yet.
        let mut placing = false;
        loop {
            let event = reader
                .read_event()
                .map_err(|e| internal(format!("XML: {e}")))?;
            let position = usize::try_from(reader.buffer_position())
                .map_err(|_| internal("position out of range"))?
                .saturating_add(base);
            let (start, empty) = match event {
                Event::Start(start) => (start, false),
                Event::Empty(start) => (start, true),
                Event::End(_) => {
                    let at = text
                        .get(..position)
                        .and_then(|before| before.rfind('<'))
                        .ok_or_else(|| internal("end tag without '<'"))?;
                    let id = stack.pop().ok_or_else(|| internal("unbalanced end tag"))?;
                    if let Some(id) = id {
                        nodes[id].end = at..position;
                    }
                    if skip_below.is_some_and(|d| stack.len() <= d) {
                        skip_below = None;
                        if placing && let Some(place) = objects.last_mut() {
                            place.end = position;
                            placing = false;
                        }
                    }
                    continue;
                }
                Event::Eof => break,
                Event::Comment(content) => {
                    let from = offset(&content)?;
                    comments.push(from - 4..from + content.len() + 3);
                    continue;
                }
                _ => continue,
            };
            // A fold of a skeleton's objects ([`Folded`]) is nothing.
            if matches!(keep, Keep::Folded(_)) && stack.len() == 1 && start.name().as_ref() == b"_"
            {
                match empty {
                    true => continue,
                    false => return Err(internal("a fold with an inside")),
                }
            }
            let object = stack.len() == 1
                && skip_below.is_none()
                && Shape::from_name_bytes(start.name().as_ref()).is_some();
            // An object only placed, or kept with or without its elements.
            let (placed, deep) = match keep {
                _ if !object => (false, true),
                #[cfg(test)]
                Keep::All => (false, true),
                #[cfg(test)]
                Keep::TopLevel => (false, false),
                Keep::Placed => (true, false),
                Keep::Objects(deep) | Keep::Folded(deep) => {
                    let deep = deep.contains(&objects.len());
                    (!deep, deep)
                }
            };
            if object {
                let at = offset(start.name().as_ref())?
                    .checked_sub(1)
                    .ok_or_else(|| internal("start tag without '<'"))?;
                objects.push(Place {
                    start: at,
                    end: position,
                });
            }
            let kept = match keep {
                _ if placed => false,
                #[cfg(test)]
                Keep::All => true,
                #[cfg(test)]
                Keep::TopLevel => stack.len() <= 1,
                Keep::Placed => stack.len() <= 1,
                Keep::Objects(_) | Keep::Folded(_) => skip_below.is_none_or(|d| stack.len() <= d),
            };
            if !kept {
                if !empty {
                    if placed {
                        // Up to its end tag (this one's depth): not kept.
                        skip_below = Some(stack.len());
                        placing = true;
                    }
                    stack.push(None);
                }
                continue;
            }
            let id = nodes.len();
            nodes.push(element(text, &start, empty, position, &offset)?);
            if object {
                object_nodes.push((objects.len() - 1, id));
                if !deep && !empty {
                    skip_below = Some(stack.len());
                }
            }
            match stack.last() {
                Some(&Some(parent)) => nodes[parent].children.push(id),
                Some(None) => return Err(internal("an element inside one not kept")),
                None if root.is_none() => root = Some(id),
                None => return Err(internal("a second root element")),
            }
            if !empty {
                stack.push(Some(id));
            }
        }
        let root = match (root, stack.is_empty()) {
            (Some(root), true) => root,
            _ => return Err(internal("unbalanced elements")),
        };
        let nl = line_ending(text);
        let mut doc = Doc {
            text,
            base,
            nl,
            unit: String::new(),
            nodes,
            root,
            comments,
            objects,
            object_nodes,
            numbers: None,
        };
        // A kept object ends where its node does.
        for &(k, id) in &doc.object_nodes {
            doc.objects[k].end = doc.nodes[id].elem_end();
        }
        doc.unit = doc.indent_unit();
        Ok(doc)
    }

    /// The extra indentation of the first child, on its own line, of a
    /// parent on its own line; two spaces when the file shows none.
    fn indent_unit(&self) -> String {
        for node in &self.nodes {
            let Some(parent) = self.own_indent(node.start) else {
                continue;
            };
            let unit_at = |start: usize| {
                self.own_indent(start)
                    .filter(|indent| indent.len() > parent.len())
                    .and_then(|indent| indent.strip_prefix(parent))
            };
            let first_at = |start: usize| unit_at(start).map(|unit| (start, unit));
            let child = node
                .children
                .iter()
                .find_map(|&c| first_at(self.nodes[c].start));
            // The root's children are its kept nodes and its placed objects.
            let object = match std::ptr::eq(node, &self.nodes[self.root]) {
                true => self.objects.iter().find_map(|p| first_at(p.start)),
                false => None,
            };
            let earliest = match (child, object) {
                (Some(c), Some(o)) => Some(if o.0 < c.0 { o } else { c }),
                (c, o) => c.or(o),
            };
            if let Some((_, unit)) = earliest {
                return unit.to_owned();
            }
        }
        "  ".to_owned()
    }

    /// Where node `id` is.
    pub(super) fn place(&self, id: usize) -> Place {
        let node = self.node(id);
        Place {
            start: node.start,
            end: node.elem_end(),
        }
    }

    /// The node of object `k` (in text order), if it was kept as one.
    pub(super) fn object_node(&self, k: usize) -> Option<usize> {
        let i = self
            .object_nodes
            .binary_search_by_key(&k, |&(k, _)| k)
            .ok()?;
        Some(self.object_nodes[i].1)
    }

    /// Offset of the start of the line holding `pos`.
    pub(super) fn line_start(&self, pos: usize) -> usize {
        let before = self.text.get(..pos).unwrap_or_default();
        // A lone CR (classic Mac OS) ends a line too.
        before
            .rfind(['\n', '\r'])
            .map_or(0, |i| i + 1)
            .max(self.base)
    }

    /// The indentation before `pos` when only spaces and tabs precede it on
    /// its line.
    pub(super) fn own_indent(&self, pos: usize) -> Option<&'t str> {
        let indent = self.text.get(self.line_start(pos)..pos)?;
        indent
            .bytes()
            .all(|b| b == b' ' || b == b'\t')
            .then_some(indent)
    }

    /// The offset just past the line ending that follows `pos`, when only
    /// spaces and tabs come between (or the end of the text).
    pub(super) fn line_end_after(&self, pos: usize) -> Option<usize> {
        let rest = self.text.get(pos..)?;
        let spaces = rest.len() - rest.trim_start_matches([' ', '\t']).len();
        let after = &rest[spaces..];
        let ending = if after.starts_with("\r\n") {
            2
        } else if after.starts_with(['\n', '\r']) {
            1
        } else if after.is_empty() {
            0
        } else {
            return None;
        };
        Some(pos + spaces + ending)
    }

    /// The comments directly above the line holding `pos`, in text order:
    /// each alone on its lines, with no blank line between them and `pos`.
    pub(super) fn comments_above(&self, pos: usize) -> Vec<Range<usize>> {
        let mut found = Vec::new();
        if self.own_indent(pos).is_none() {
            return found;
        }
        let mut line = self.line_start(pos);
        let mut next = self.comments.partition_point(|c| c.end <= line);
        while let Some(c) = next.checked_sub(1).and_then(|i| self.comments.get(i)) {
            let alone =
                self.own_indent(c.start).is_some() && self.line_end_after(c.end) == Some(line);
            if !alone {
                break;
            }
            found.push(c.clone());
            line = self.line_start(c.start);
            next -= 1;
        }
        found.reverse();
        found
    }

    /// Where the lines of the element starting at `start` begin: the
    /// first comment directly above it, or its own line; `None` when it
    /// shares its line.
    pub(super) fn block_start(&self, start: usize) -> Option<usize> {
        self.own_indent(start)?;
        let first = self
            .comments_above(start)
            .first()
            .map_or(start, |c| c.start);
        Some(self.line_start(first))
    }

    pub(super) fn node(&self, id: usize) -> &Node<'t> {
        &self.nodes[id]
    }

    /// The only child of `id` named `name`, if any.
    pub(super) fn child(&self, id: usize, name: &str) -> Option<usize> {
        self.node(id)
            .children
            .iter()
            .copied()
            .find(|&c| self.node(c).name == name)
    }

    pub(super) fn children_named(&self, id: usize, names: &[&str]) -> Vec<usize> {
        self.node(id)
            .children
            .iter()
            .copied()
            .filter(|&c| names.contains(&self.node(c).name))
            .collect()
    }
}

/// A node for a start tag read at `tag_end` (the offset past its `>`).
fn element<'t>(
    text: &'t str,
    start: &BytesStart<'_>,
    empty: bool,
    tag_end: usize,
    offset: &impl Fn(&[u8]) -> Result<usize, EditError>,
) -> Result<Node<'t>, EditError> {
    // Names as slices of the text: no allocation per element.
    let slice = |bytes: &[u8]| -> Result<&'t str, EditError> {
        let from = offset(bytes)?;
        text.get(from..from + bytes.len())
            .ok_or_else(|| internal("a name outside the text"))
    };
    let name = start.name();
    let name_text = slice(name.as_ref())?;
    let at = offset(name.as_ref())?
        .checked_sub(1)
        .ok_or_else(|| internal("start tag without '<'"))?;
    let mut attrs = Vec::new();
    let mut iter = start.attributes();
    iter.with_checks(false);
    for attr in iter {
        let attr = attr.map_err(|e| internal(format!("attribute: {e}")))?;
        let Cow::Borrowed(value) = attr.value else {
            return Err(internal("an attribute value not borrowed from the text"));
        };
        let from = offset(value)?;
        attrs.push(AttrSpan {
            name: slice(attr.key.as_ref())?,
            value: from..from + value.len(),
        });
    }
    Ok(Node {
        name: name_text,
        start: at,
        tag_end,
        empty,
        end: tag_end..tag_end,
        attrs,
        children: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indentation_unit_is_detected() {
        assert_eq!(
            Doc::scan(crate::EXAMPLE_SCENE, Keep::All).unwrap().unit,
            " "
        );
        let tabs = "<scene>\n\t<camera width=\"1\" height=\"1\" eyeDistance=\"1\"/>\n</scene>\n";
        assert_eq!(Doc::scan(tabs, Keep::All).unwrap().unit, "\t");
        let flat = "<scene><camera width=\"1\" height=\"1\" eyeDistance=\"1\"/></scene>";
        assert_eq!(Doc::scan(flat, Keep::All).unwrap().unit, "  ");
        // Only the objects show it (the rest on one line): the same unit
        // when they are only placed as when they are nodes (without their
        // elements, as in a save: see `Keep::TopLevel`).
        let objects = "<scene>\n   <sphere/>\n   <plane>\n      <color red=\"1\" green=\"1\" blue=\"1\"/>\n   </plane>\n<camera width=\"1\" height=\"1\" eyeDistance=\"1\"/></scene>";
        let none = std::collections::HashSet::new();
        for text in [crate::EXAMPLE_SCENE, tabs, flat, objects] {
            let unit = Doc::scan(text, Keep::TopLevel).unwrap().unit;
            assert_eq!(Doc::scan(text, Keep::Placed).unwrap().unit, unit, "{text}");
        }
        for keep in [Keep::Placed, Keep::Objects(&none)] {
            assert_eq!(Doc::scan(objects, keep).unwrap().unit, "   ");
        }
    }
}
