//! The save-back's editor: the splices (byte range → replacement) that
//! turn a scanned text ([`Doc`]) into the text of an edited scene. It
//! changes only what differs: an attribute value between its quotes, a
//! missing attribute appended to its element, a removed element with its
//! lines and the comment lines directly above it, an added element after
//! the last one of its kind with the indentation of its siblings. Elements
//! are paired with the edited scene's by where they came from
//! ([`Origins`]), never by position or name.

use std::ops::Range;

use super::unchanged;
use crate::math::{TransformStep, Vec3};
use crate::scene::edit::{Coef, EditError, Edited, number_text as num};
use crate::scene::fresh::{
    Lines, color_tag, light_lines, material_tag, model_tag, object_lines, step_tag,
    transformation_lines,
};
use crate::scene::layout::{Doc, Place, internal};
use crate::scene::{Camera, Color, Object, Scene};
use crate::shading::Light;

/// Where each element of a group came from ([`Editor::group`]): the
/// index among the text's elements of current element `i`, or `None` for
/// an element added since.
#[derive(Clone, Copy)]
enum Origins<'a> {
    List(&'a [Option<usize>]),
    /// `len` elements, each asked of `of` (the objects' origins are the
    /// edit engine's, asked for: a list of a million would be 16 MB).
    Asked {
        len: usize,
        of: &'a dyn Fn(usize) -> Option<usize>,
    },
}

impl Origins<'_> {
    fn len(&self) -> usize {
        match self {
            Origins::List(list) => list.len(),
            Origins::Asked { len, .. } => *len,
        }
    }

    fn of(&self, i: usize) -> Option<usize> {
        match self {
            Origins::List(list) => list.get(i).copied().flatten(),
            Origins::Asked { len, of } => (i < *len).then(|| of(i)).flatten(),
        }
    }
}

/// `items` as lines indented by `indent` plus their own levels.
fn block(doc: &Doc<'_>, indent: &str, items: &[Lines]) -> String {
    let mut text = String::new();
    for item in items {
        for (level, line) in item {
            text.push_str(indent);
            text.push_str(&doc.unit.repeat(*level));
            text.push_str(line);
            text.push_str(doc.nl);
        }
    }
    text
}

/// `items` written one after another on the current line.
fn inline(items: &[Lines]) -> String {
    items.iter().flatten().map(|(_, l)| l.as_str()).collect()
}

/// Replace `range` of the text with `text` (an insertion when empty).
#[derive(Debug)]
pub(super) struct Splice {
    pub(super) range: Range<usize>,
    pub(super) text: String,
}

/// Ranks of an object's children: where a new one goes among its siblings.
const OBJECT_RANKS: &[(&str, u8)] = &[("color", 0), ("material", 1), ("transformation", 2)];
const LIGHT_RANKS: &[(&str, u8)] = &[("color", 0)];
const CAMERA_RANKS: &[(&str, u8)] = &[("transformation", 0)];

pub(super) struct Editor<'d, 't> {
    pub(super) doc: &'d Doc<'t>,
    pub(super) splices: Vec<Splice>,
}

impl Editor<'_, '_> {
    fn splice(&mut self, range: Range<usize>, text: impl Into<String>) {
        self.splices.push(Splice {
            range,
            text: text.into(),
        });
    }

    pub(super) fn scene(&mut self, original: &Scene, edited: &Edited) -> Result<(), EditError> {
        let doc = self.doc;
        let scene = edited.scene();
        let root = doc.root;
        let objects = &doc.objects;
        let lights = doc.children_named(root, &["light"]);
        let cameras = doc.children_named(root, &["camera"]);
        let models = doc.children_named(root, &["model"]);
        let objects_here = doc.numbers.map_or(original.objects.len(), <[usize]>::len);
        if objects.len() != objects_here
            || lights.len() != original.lights.len()
            || cameras.len() != 1
            || models.len() > 1
        {
            return Err(internal("the text's elements do not match its scene"));
        }

        if let Some(numbers) = doc.numbers {
            // Every object where it was (a skeleton folds objects only
            // then): the changed ones are edited in place, as `group` would.
            for (k, &n) in numbers.iter().enumerate() {
                let (Some(o), Some(e), Some(origin)) = (
                    original.objects.get(n),
                    scene.objects.get(n),
                    edited.origin_of(n),
                ) else {
                    return Err(internal("the text's elements do not match its scene"));
                };
                if origin.index != n {
                    return Err(internal("an object moved in a folded skeleton"));
                }
                if unchanged(o, e, &origin.steps) {
                    continue;
                }
                let node = doc
                    .object_node(k)
                    .ok_or_else(|| internal("a changed object was not scanned"))?;
                self.object(node, o, e, &origin.steps)?;
            }
        } else {
            self.objects(original, edited, objects)?;
        }
        self.lights_camera_model(original, edited, lights, cameras, models)
    }

    /// The objects, brought to `edited`'s ([`Editor::group`]); `places`:
    /// the text's.
    fn objects(
        &mut self,
        original: &Scene,
        edited: &Edited,
        places: &[Place],
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let scene = edited.scene();
        let (root, objects) = (doc.root, places);
        let origins = Origins::Asked {
            len: scene.objects.len(),
            of: &|n| edited.object_origin(n),
        };
        self.group(
            root,
            objects,
            origins,
            |i| object_lines(&scene.objects[i]),
            |editor, k, i| {
                let origin = edited.origin_of(i);
                let steps = origin.as_ref().map_or(&[][..], |o| &o.steps[..]);
                // Its elements were not scanned (see `changed_objects`).
                if unchanged(&original.objects[k], &scene.objects[i], steps) {
                    return Ok(());
                }
                let node = doc
                    .object_node(k)
                    .ok_or_else(|| internal("a changed object was not scanned"))?;
                editor.object(node, &original.objects[k], &scene.objects[i], steps)
            },
        )
    }

    /// The lights, the camera and the model, brought to `edited`'s.
    fn lights_camera_model(
        &mut self,
        original: &Scene,
        edited: &Edited,
        lights: Vec<usize>,
        cameras: Vec<usize>,
        models: Vec<usize>,
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let scene = edited.scene();
        let root = doc.root;
        let light_places: Vec<Place> = lights.iter().map(|&id| doc.place(id)).collect();
        self.group(
            root,
            &light_places,
            Origins::List(&edited.lights),
            |i| light_lines(&scene.lights[i]),
            |editor, k, i| editor.light(lights[k], &original.lights[k], &scene.lights[i]),
        )?;

        self.camera(
            cameras[0],
            &original.camera,
            &scene.camera,
            &edited.camera_steps,
        )?;

        let (om, em) = (original.model, scene.model);
        if om != em {
            match models.first() {
                Some(&node) => {
                    if om.illumination != em.illumination {
                        self.set_attr(node, "type", em.illumination.name());
                    }
                    if om.depth != em.depth {
                        self.set_attr(node, "depth", &em.depth.to_string());
                    }
                }
                None => self.insert(root, "scene", None, &[vec![(0, model_tag(&em))]])?,
            }
        }
        Ok(())
    }

    /// Brings a group of sibling elements of `parent` (`nodes`, in text
    /// order: the objects, the lights, the steps of one transformation) to
    /// the current elements. `origins[i]` is the index in `nodes` that
    /// current element `i` came from, or `None` for a new one (written by
    /// `lines(i)`). Nodes no element came from are removed with the comment
    /// lines above them; kept ones are edited by `keep(self, k, i)`; new
    /// ones go before the next kept element, or after the group's last
    /// node, or at the end of `parent`.
    fn group(
        &mut self,
        parent: usize,
        nodes: &[Place],
        origins: Origins<'_>,
        lines: impl Fn(usize) -> Lines,
        mut keep: impl FnMut(&mut Self, usize, usize) -> Result<(), EditError>,
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let mut kept = vec![false; nodes.len()];
        let mut last = None;
        for i in 0..origins.len() {
            let Some(k) = origins.of(i) else { continue };
            if k >= nodes.len() || kept[k] || last.is_some_and(|l| l >= k) {
                return Err(internal("the elements' origins are not in text order"));
            }
            kept[k] = true;
            last = Some(k);
            keep(self, k, i)?;
        }
        for (k, &place) in nodes.iter().enumerate() {
            if !kept[k] {
                self.remove(place);
            }
        }
        let name = doc.node(parent).name;
        let mut i = 0;
        while i < origins.len() {
            if origins.of(i).is_some() {
                i += 1;
                continue;
            }
            let run_end = (i..origins.len())
                .find(|&j| origins.of(j).is_some())
                .unwrap_or(origins.len());
            let items: Vec<Lines> = (i..run_end).map(&lines).collect();
            match origins.of(run_end) {
                Some(k) => self.insert_before(nodes[k], &items),
                None => match nodes.last() {
                    Some(&place) => self.insert_after(place, &items),
                    None => self.insert(parent, name, None, &items)?,
                },
            }
            i = run_end;
        }
        Ok(())
    }

    fn object(
        &mut self,
        node: usize,
        o: &Object,
        e: &Object,
        step_origins: &[Option<usize>],
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let name = e.shape.name();
        if o.shape != e.shape {
            self.rename(node, name)?;
        }
        let mut new_items: Vec<(u8, Lines)> = Vec::new();
        if o.color != e.color {
            match doc.child(node, "color") {
                Some(c) => self.set_color(c, o.color, e.color),
                None => new_items.push((0, vec![(0, color_tag(e.color))])),
            }
        }
        if o.material != e.material {
            match doc.child(node, "material") {
                Some(m) => {
                    let (om, em) = (o.material, e.material);
                    let values = Coef::ALL.map(|c| (c.name(), c.of(&om), c.of(&em)));
                    self.set_numbers(m, &values);
                }
                None => new_items.push((1, vec![(0, material_tag(&e.material, true))])),
            }
        }
        self.transformation(
            node,
            o.transform.steps(),
            e.transform.steps(),
            step_origins,
            2,
            &mut new_items,
        )?;
        self.insert_ranked(node, name, OBJECT_RANKS, new_items)
    }

    fn light(&mut self, node: usize, o: &Light, e: &Light) -> Result<(), EditError> {
        self.set_vec3(node, ["x", "y", "z"], o.position, e.position);
        if o.color != e.color {
            match self.doc.child(node, "color") {
                Some(c) => self.set_color(c, o.color, e.color),
                None => {
                    let item = vec![(0, vec![(0, color_tag(e.color))])];
                    self.insert_ranked(node, "light", LIGHT_RANKS, item)?;
                }
            }
        }
        Ok(())
    }

    fn camera(
        &mut self,
        node: usize,
        o: &Camera,
        e: &Camera,
        step_origins: &[Option<usize>],
    ) -> Result<(), EditError> {
        if o.width != e.width {
            self.set_attr(node, "width", &e.width.to_string());
        }
        if o.height != e.height {
            self.set_attr(node, "height", &e.height.to_string());
        }
        if o.eye_distance != e.eye_distance {
            self.set_attr(node, "eyeDistance", &num(e.eye_distance));
        }
        let mut new_items = Vec::new();
        self.transformation(
            node,
            o.transform.steps(),
            e.transform.steps(),
            step_origins,
            0,
            &mut new_items,
        )?;
        self.insert_ranked(node, "camera", CAMERA_RANKS, new_items)
    }

    /// Brings the `<transformation>` of `parent` from steps `o` to `e`,
    /// step by step by their origins; queues a new `<transformation>` (at
    /// `rank`) in `new_items` when `parent` has none.
    fn transformation(
        &mut self,
        parent: usize,
        o: &[TransformStep],
        e: &[TransformStep],
        origins: &[Option<usize>],
        rank: u8,
        new_items: &mut Vec<(u8, Lines)>,
    ) -> Result<(), EditError> {
        let Some(node) = self.doc.child(parent, "transformation") else {
            if !e.is_empty() {
                new_items.push((rank, transformation_lines(e)));
            }
            return Ok(());
        };
        if o == e {
            // Back to the steps the text has (a camera moved and brought
            // back): its text says it already, whatever the origins.
            return Ok(());
        }
        let steps = self.doc.node(node).children.clone();
        if steps.len() != o.len() || origins.len() != e.len() {
            return Err(internal("a transformation's steps do not match its text"));
        }
        let places: Vec<Place> = steps.iter().map(|&id| self.doc.place(id)).collect();
        self.group(
            node,
            &places,
            Origins::List(origins),
            |i| vec![(0, step_tag(&e[i]))],
            |editor, k, i| editor.step(steps[k], &o[k], &e[i]),
        )
    }

    /// Edits the values of one step node from `a` to `b` (same kind).
    fn step(&mut self, node: usize, a: &TransformStep, b: &TransformStep) -> Result<(), EditError> {
        use TransformStep as S;
        match (*a, *b) {
            (S::Translate(u), S::Translate(v)) | (S::Scale(u), S::Scale(v)) => {
                self.set_vec3(node, ["x", "y", "z"], u, v);
            }
            (S::RotateX(u), S::RotateX(v))
            | (S::RotateY(u), S::RotateY(v))
            | (S::RotateZ(u), S::RotateZ(v)) => {
                if u != v {
                    self.set_attr(node, "angle", &num(v));
                }
            }
            (S::UniformScale(u), S::UniformScale(v)) => {
                if u != v {
                    self.set_attr(node, "factor", &num(v));
                }
            }
            _ => return Err(internal("a step changed its kind")),
        }
        Ok(())
    }

    fn set_color(&mut self, node: usize, o: Color, e: Color) {
        self.set_vec3(node, ["red", "green", "blue"], o, e);
    }

    /// Sets the three attributes `names` of `node` that changed from `o`
    /// to `e`.
    fn set_vec3(&mut self, node: usize, names: [&str; 3], o: Vec3, e: Vec3) {
        self.set_numbers(
            node,
            &[
                (names[0], o.x, e.x),
                (names[1], o.y, e.y),
                (names[2], o.z, e.z),
            ],
        );
    }

    /// Sets each attribute of `node` whose value changed, `(name, old,
    /// new)`; the others keep their text.
    fn set_numbers(&mut self, node: usize, values: &[(&str, f64, f64)]) {
        for &(attr, old, new) in values {
            if old != new {
                self.set_attr(node, attr, &num(new));
            }
        }
    }

    /// Sets attribute `name` of `node`: its value replaced between the
    /// quotes, or ` name="value"` appended after the last attribute.
    fn set_attr(&mut self, node: usize, name: &str, value: &str) {
        let n = self.doc.node(node);
        if let Some(attr) = n.attrs.iter().find(|a| a.name == name) {
            self.splice(attr.value.clone(), value);
            return;
        }
        let (at, quote) = match n.attrs.last() {
            Some(last) => {
                let quote = match self.doc.text.as_bytes().get(last.value.end) {
                    Some(b'\'') => '\'',
                    _ => '"',
                };
                (last.value.end + 1, quote)
            }
            None => (n.start + 1 + n.name.len(), '"'),
        };
        self.splice(at..at, format!(" {name}={quote}{value}{quote}"));
    }

    /// Renames the element `node` (start and end tags) to `name`.
    fn rename(&mut self, node: usize, name: &str) -> Result<(), EditError> {
        let n = self.doc.node(node);
        let old = n.name.len();
        let start = n.start + 1..n.start + 1 + old;
        let end = (!n.empty).then(|| n.end.start + 2..n.end.start + 2 + old);
        for range in std::iter::once(start).chain(end) {
            if self.doc.text.get(range.clone()) != Some(n.name) {
                return Err(internal("a tag name not where expected"));
            }
            self.splice(range, name);
        }
        Ok(())
    }

    /// Removes the element `node`: with its lines and the comment lines
    /// directly above it when it is alone on its lines, else just its text.
    fn remove(&mut self, place: Place) {
        let doc = self.doc;
        let Place { start, end } = place;
        let range = match (doc.block_start(start), doc.line_end_after(end)) {
            (Some(line), Some(after)) => line..after,
            _ => start..end,
        };
        self.splice(range, "");
    }

    /// Inserts `items` (siblings of `node`) just before it, with its
    /// indentation and before the comments above it.
    fn insert_before(&mut self, place: Place, items: &[Lines]) {
        let doc = self.doc;
        let at = place.start;
        match (doc.block_start(at), doc.own_indent(at)) {
            (Some(line), Some(indent)) => self.splice(line..line, block(doc, indent, items)),
            _ => self.splice(at..at, inline(items)),
        }
    }

    /// Inserts `items` (siblings of `node`) on the lines just after it, with
    /// its indentation.
    fn insert_after(&mut self, place: Place, items: &[Lines]) {
        let doc = self.doc;
        let Place { start, end } = place;
        match (doc.own_indent(start), doc.line_end_after(end)) {
            (Some(indent), Some(after)) => {
                let mut text = block(doc, indent, items);
                if !doc.text[..after].ends_with(['\n', '\r']) {
                    // The text ends on this line: start a new one.
                    text = format!("{}{}", doc.nl, text.trim_end_matches(['\r', '\n']));
                }
                self.splice(after..after, text);
            }
            _ => self.splice(end..end, inline(items)),
        }
    }

    /// Inserts new children of `parent` (named `name` in the edited scene),
    /// each before the first existing child of a higher rank, or at the end.
    /// `items` are in rank order; `removed` is a child being removed.
    fn insert_ranked(
        &mut self,
        parent: usize,
        name: &str,
        ranks: &[(&str, u8)],
        items: Vec<(u8, Lines)>,
    ) -> Result<(), EditError> {
        if items.is_empty() {
            return Ok(());
        }
        let doc = self.doc;
        let rank_of = |id: usize| {
            ranks
                .iter()
                .find(|(n, _)| *n == doc.node(id).name)
                .map_or(u8::MAX, |&(_, r)| r)
        };
        let existing: Vec<usize> = doc.node(parent).children.to_vec();
        let mut groups: Vec<(Option<usize>, Vec<Lines>)> = Vec::new();
        for (rank, lines) in items {
            let anchor = existing.iter().copied().find(|&c| rank_of(c) > rank);
            match groups.last_mut() {
                Some((a, group)) if *a == anchor => group.push(lines),
                _ => groups.push((anchor, vec![lines])),
            }
        }
        for (anchor, group) in groups {
            self.insert(parent, name, anchor, &group)?;
        }
        Ok(())
    }

    /// Inserts `items` as children of `parent` (named `name` once edited),
    /// before the child `anchor` or at the end, with the indentation of
    /// their siblings. An empty `<x/>` becomes `<x>…</x>`.
    fn insert(
        &mut self,
        parent: usize,
        name: &str,
        anchor: Option<usize>,
        items: &[Lines],
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let p = doc.node(parent);
        let block = |indent: &str| block(doc, indent, items);
        let inline = || inline(items);
        let parent_indent = doc.own_indent(p.start).unwrap_or("");

        if let Some(sibling) = anchor {
            let at = doc.node(sibling).start;
            match doc.own_indent(at) {
                Some(indent) => {
                    let line = doc.line_start(at);
                    self.splice(line..line, block(indent));
                }
                None => self.splice(at..at, inline()),
            }
            return Ok(());
        }

        if p.empty {
            // `<x .../>` (maybe `<x ... />`): replace from the end of the
            // attributes to the end of the tag.
            let slash = p
                .tag_end
                .checked_sub(2)
                .filter(|&s| doc.text.get(s..p.tag_end) == Some("/>"))
                .ok_or_else(|| internal("an empty element without '/>'"))?;
            let tag = doc.text.get(p.start..slash).unwrap_or_default();
            let from = p.start + tag.trim_end_matches([' ', '\t', '\r', '\n']).len();
            let child_indent = format!("{parent_indent}{}", doc.unit);
            let text = format!(
                ">{}{}{parent_indent}</{name}>",
                doc.nl,
                block(&child_indent)
            );
            self.splice(from..p.tag_end, text);
            return Ok(());
        }

        let end = p.end.start;
        if let Some(end_indent) = doc.own_indent(end) {
            // The last child: a node, or for the root maybe an object.
            let last_node = p.children.last().map(|&c| doc.node(c).start);
            let last_object = doc.objects.last().map(|o| o.start);
            let last = match (last_node, last_object) {
                (Some(n), Some(o)) if parent == doc.root => Some(n.max(o)),
                (n, o) if parent == doc.root => n.or(o),
                (n, _) => n,
            };
            let sibling_indent = last.and_then(|start| doc.own_indent(start));
            let indent = match sibling_indent {
                Some(indent) => indent.to_owned(),
                None => {
                    let outer = doc.own_indent(p.start).unwrap_or(end_indent);
                    format!("{outer}{}", doc.unit)
                }
            };
            let line = doc.line_start(end);
            self.splice(line..line, block(&indent));
        } else if doc
            .text
            .get(p.tag_end..end)
            .is_some_and(|s| s.trim_matches([' ', '\t']).is_empty())
        {
            let child_indent = format!("{parent_indent}{}", doc.unit);
            let text = format!("{}{}{parent_indent}", doc.nl, block(&child_indent));
            self.splice(p.tag_end..end, text);
        } else {
            self.splice(end..end, inline());
        }
        Ok(())
    }
}
