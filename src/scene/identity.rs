//! Which element of one version of a scene is which in another: what lets
//! an edit made on one version of the file go to the same element in a
//! version another program saved, and a reload be undone element by
//! element.
//!
//! The two lists of objects (and of lights) are diffed as a three-way merge
//! diffs lines: elements equal in both are matched along their longest
//! common subsequence (Myers' diff, with a deadline for huge rewrites).
//! Within a run of elements that differ, an old one is matched with a new
//! one that is *like* it ([`alike_objects`], [`alike_lights`]), keeping
//! their order; a run whose old and new sides are left with as many
//! elements each is matched in order (another program changed them in
//! place). Last, an element left over on the old side that is equal to
//! one left over on the new side was moved there (a reordering). What is
//! left then was removed on the one side, added on the other.

use std::ops::Range;
use std::time::{Duration, Instant};

use similar::DiffOp;
use similar::algorithms::{Capture, Replace, myers};

use super::{Light, Object};

/// For each element of the old list, the index of the same element in the
/// new list, or `None` when it is gone. Matched indices rise with the old
/// index, but for elements another program moved.
pub type Matching = Vec<Option<usize>>;

/// How long the diff may search before settling for a longer edit script:
/// a file rewritten whole still opens at once.
const DEADLINE: Duration = Duration::from_millis(500);

/// The matching of two lists of objects.
pub fn objects<O: AsRef<Object>>(old: &[O], new: &[O]) -> Matching {
    matching(
        old,
        new,
        |a, b| std::ptr::eq(a.as_ref(), b.as_ref()) || a.as_ref() == b.as_ref(),
        |a, b| alike_objects(a.as_ref(), b.as_ref()),
    )
}

/// The matching of two lists of lights.
pub fn lights(old: &[Light], new: &[Light]) -> Matching {
    matching(old, new, |a, b| a == b, alike_lights)
}

/// Two versions of one object: the same shape, and either the same place
/// and size (its colour or material changed) or the same look (it moved).
pub fn alike_objects(a: &Object, b: &Object) -> bool {
    a.shape == b.shape
        && (a.transform == b.transform || (a.color == b.color && a.material == b.material))
}

/// Two versions of one light: the same place or the same colour.
pub fn alike_lights(a: &Light, b: &Light) -> bool {
    a.position == b.position || a.color == b.color
}

/// An element compared by `same`: for Myers' diff, which wants
/// `PartialEq`.
struct Item<'a, T, F> {
    item: &'a T,
    same: &'a F,
}

impl<T, F: Fn(&T, &T) -> bool> PartialEq for Item<'_, T, F> {
    fn eq(&self, other: &Self) -> bool {
        (self.same)(self.item, other.item)
    }
}

fn items<'a, T, F>(items: &'a [T], same: &'a F) -> Vec<Item<'a, T, F>> {
    items.iter().map(|item| Item { item, same }).collect()
}

fn matching<T>(
    old: &[T],
    new: &[T],
    same: impl Fn(&T, &T) -> bool,
    alike: impl Fn(&T, &T) -> bool,
) -> Matching {
    let mut matched = vec![None; old.len()];
    // The runs equal at both ends are matched at once (Myers' diff would
    // trim them too): an edit in a million elements wraps and diffs only
    // what lies between.
    let prefix = old.iter().zip(new).take_while(|(a, b)| same(a, b)).count();
    let suffix = old[prefix..]
        .iter()
        .rev()
        .zip(new[prefix..].iter().rev())
        .take_while(|(a, b)| same(a, b))
        .count();
    for (k, slot) in matched.iter_mut().enumerate().take(prefix) {
        *slot = Some(k);
    }
    for k in 1..=suffix {
        matched[old.len() - k] = Some(new.len() - k);
    }
    let a = items(&old[prefix..old.len() - suffix], &same);
    let b = items(&new[prefix..new.len() - suffix], &same);
    let mut hook = Replace::new(Capture::new());
    let deadline = Instant::now() + DEADLINE;
    // Capture never fails.
    let _ = myers::diff_deadline_raw(&mut hook, &a, 0..a.len(), &b, 0..b.len(), Some(deadline));
    // The ops count from the start of the middle.
    for op in hook.into_inner().into_ops() {
        match op {
            DiffOp::Equal {
                old_index,
                new_index,
                len,
            } => {
                for k in 0..len {
                    matched[prefix + old_index + k] = Some(prefix + new_index + k);
                }
            }
            DiffOp::Replace {
                old_index,
                old_len,
                new_index,
                new_len,
            } => {
                let (old_index, new_index) = (prefix + old_index, prefix + new_index);
                match_changed(
                    old,
                    new,
                    old_index..old_index + old_len,
                    new_index..new_index + new_len,
                    &alike,
                    &mut matched,
                )
            }
            DiffOp::Delete { .. } | DiffOp::Insert { .. } => {}
        }
    }
    match_moved(old, new, &same, &mut matched);
    matched
}

/// Matches the elements left over on the old side with equal ones left
/// over on the new side, first with first: they were moved.
fn match_moved<T>(old: &[T], new: &[T], same: &impl Fn(&T, &T) -> bool, matched: &mut Matching) {
    let mut taken = vec![false; new.len()];
    for j in matched.iter().flatten() {
        taken[*j] = true;
    }
    let mut left: Vec<usize> = (0..new.len()).filter(|&j| !taken[j]).collect();
    if left.is_empty() || left.len() > MAX_RUN {
        return;
    }
    for (i, slot) in matched.iter_mut().enumerate() {
        if slot.is_none()
            && let Some(k) = left.iter().position(|&j| same(&old[i], &new[j]))
        {
            *slot = Some(left.remove(k));
        }
    }
}

/// The largest run of changed elements matched by likeness (longest common
/// subsequence, quadratic); longer runs are matched in order when they are
/// as long on both sides.
const MAX_RUN: usize = 2000;

/// Matches the changed elements `old[olds]` with `new[news]`: alike ones
/// along their longest common subsequence, and between two such pairs, the
/// elements left in order when as many are left on each side.
fn match_changed<T>(
    old: &[T],
    new: &[T],
    olds: Range<usize>,
    news: Range<usize>,
    alike: &impl Fn(&T, &T) -> bool,
    matched: &mut Matching,
) {
    let (n, m) = (olds.len(), news.len());
    let mut pairs = Vec::new();
    if n <= MAX_RUN && m <= MAX_RUN {
        // lcs[i][j]: the longest alike subsequence of old[i..] and new[j..].
        let mut lcs = vec![0u32; (n + 1) * (m + 1)];
        let at = |i: usize, j: usize| i * (m + 1) + j;
        for i in (0..n).rev() {
            for j in (0..m).rev() {
                lcs[at(i, j)] = if alike(&old[olds.start + i], &new[news.start + j]) {
                    lcs[at(i + 1, j + 1)] + 1
                } else {
                    lcs[at(i + 1, j)].max(lcs[at(i, j + 1)])
                };
            }
        }
        let (mut i, mut j) = (0, 0);
        while i < n && j < m {
            if alike(&old[olds.start + i], &new[news.start + j])
                && lcs[at(i, j)] == lcs[at(i + 1, j + 1)] + 1
            {
                pairs.push((i, j));
                i += 1;
                j += 1;
            } else if lcs[at(i + 1, j)] >= lcs[at(i, j + 1)] {
                i += 1;
            } else {
                j += 1;
            }
        }
    }
    // The gaps between the alike pairs (and before the first, after the
    // last): as many on each side are matched in order.
    let mut from = (0, 0);
    for &(i, j) in pairs.iter().chain(std::iter::once(&(n, m))) {
        if i - from.0 == j - from.1 {
            for k in 0..i - from.0 {
                matched[olds.start + from.0 + k] = Some(news.start + from.1 + k);
            }
        }
        if i < n {
            matched[olds.start + i] = Some(news.start + j);
        }
        from = (i + 1, j + 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn objects_of(text: &str) -> Vec<std::sync::Arc<Object>> {
        crate::scene::parse(text, Path::new("t.xml"))
            .unwrap()
            .objects
            .to_vec()
    }

    fn sphere(x: f64, red: f64) -> String {
        format!(
            "<sphere><color red=\"{red}\" green=\"0\" blue=\"0\"/><transformation><translate x=\"{x}\"/></transformation></sphere>"
        )
    }

    fn scene(spheres: &[String]) -> String {
        format!(
            "<scene>{}<camera width=\"4\" height=\"4\" eyeDistance=\"1\"/></scene>",
            spheres.concat()
        )
    }

    #[test]
    fn an_insertion_above_keeps_every_element_its_own() {
        let old = objects_of(&scene(&[sphere(0.0, 1.0), sphere(1.0, 1.0)]));
        let new = objects_of(&scene(&[
            sphere(5.0, 0.5),
            sphere(0.0, 1.0),
            sphere(1.0, 1.0),
        ]));
        assert_eq!(objects(&old, &new), vec![Some(1), Some(2)]);
    }

    #[test]
    fn a_removal_and_a_change_beside_it_are_told_apart() {
        let old = objects_of(&scene(&[
            sphere(0.0, 1.0),
            sphere(1.0, 1.0),
            sphere(2.0, 1.0),
        ]));
        // The first removed, the second recoloured.
        let new = objects_of(&scene(&[sphere(1.0, 0.3), sphere(2.0, 1.0)]));
        assert_eq!(objects(&old, &new), vec![None, Some(0), Some(1)]);
    }

    #[test]
    fn elements_changed_in_place_are_matched_in_order() {
        let old = objects_of(&scene(&[sphere(0.0, 1.0), sphere(1.0, 1.0)]));
        let new = objects_of(&scene(&[sphere(7.0, 0.1), sphere(8.0, 0.2)]));
        assert_eq!(objects(&old, &new), vec![Some(0), Some(1)]);
    }

    #[test]
    fn a_reordering_keeps_the_moved_element() {
        let a = sphere(0.0, 1.0);
        let b = sphere(1.0, 0.5);
        let c = sphere(2.0, 0.25);
        let old = objects_of(&scene(&[a.clone(), b.clone(), c.clone()]));
        let new = objects_of(&scene(&[c, a, b]));
        // c moved to the front.
        assert_eq!(objects(&old, &new), vec![Some(1), Some(2), Some(0)]);
    }
}
