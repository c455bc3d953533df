//! A bounding volume hierarchy over bounded primitives: binned surface-area
//! heuristic build, nearest-hit traversal front to back.
//!
//! Nodes live in one flat array; an interior node's children are adjacent
//! (`first`, `first + 1`), a leaf holds `count` primitives from `first` in
//! leaf order: the build puts the caller's items in that order, in place
//! ([`Bvh::build_over`]).

use super::{Lanes, Mask, Ray};
use glam::DVec3;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn centroid(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Half the surface area (the SAH only compares areas).
    fn half_area(&self) -> f64 {
        let d = (self.max - self.min).max(DVec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// Entry distance of each lane's ray into the box, and the lanes that
    /// enter it before their `t_max` (the slab test, in glam's min/max).
    #[inline(always)]
    fn entry<L: Lanes>(&self, origin: &[L; 3], inv_dir: &[L; 3], t_max: L) -> (L, L::Mask) {
        let (mut near, mut far) = (L::ZERO, L::ZERO);
        for axis in 0..3 {
            let t1 = (L::splat(self.min[axis]) - origin[axis]) * inv_dir[axis];
            let t2 = (L::splat(self.max[axis]) - origin[axis]) * inv_dir[axis];
            let (low, high) = (min(t1, t2), max(t1, t2));
            (near, far) = if axis == 0 {
                (low, high)
            } else {
                (max(near, low), min(far, high))
            };
        }
        // Not behind the origin, not past t_max (a NaN gives way, as
        // f64::max and f64::min do).
        let near = L::select(near.gt(L::ZERO), near, L::ZERO);
        let far = L::select(far.lt(t_max), far, t_max);
        (near, near.le(far))
    }
}

/// glam's min: `a` where `a < b`, else `b` (per lane).
#[inline(always)]
fn min<L: Lanes>(a: L, b: L) -> L {
    L::select(a.lt(b), a, b)
}

/// glam's max: `a` where `a > b`, else `b` (per lane).
#[inline(always)]
fn max<L: Lanes>(a: L, b: L) -> L {
    L::select(a.gt(b), a, b)
}

/// What [`Bvh::nearest`] asks of the search it serves: the distance each
/// lane must beat, and to test a primitive for some lanes.
pub trait Search<L: Lanes> {
    /// Per lane, the nearest hit so far (infinity before any).
    fn t_max(&self) -> L;
    /// Tests the primitive at position `k` in leaf order (where
    /// [`Bvh::build_over`] left the items) for `lanes`.
    fn test(&mut self, k: usize, lanes: L::Mask);
}

#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    /// Leaf: first primitive; interior: index of the left child.
    first: u32,
    /// Primitives in a leaf; 0 for an interior node.
    count: u32,
}

/// The hierarchy. Build it with [`Bvh::build_over`] over the primitives,
/// then ask [`Bvh::nearest`].
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
}

/// Primitives in a leaf at most, unless they cannot be told apart.
const MAX_LEAF: usize = 4;
/// SAH bins per split.
const BINS: usize = 16;
/// Below this depth splits follow the SAH; deeper, the median, which keeps
/// the depth (and the traversal stack) bounded whatever the input.
const SAH_DEPTH: usize = 48;
/// A big build splits on the cores ([`rayon::join`]) this many times along
/// each path (16 subtrees at most, each node copied as many times into
/// its parent's list), never into halves of fewer items than
/// `PARALLEL_ITEMS`.
const FORKS: usize = 4;
const PARALLEL_ITEMS: usize = 1 << 14;
/// Traversal stack size: at most one pending node per level.
const STACK: usize = 128;

/// The box the hierarchy holds for an item whose own box is `b`: padded
/// by a relative hair so rounding in the slab test never loses a grazing
/// hit on the primitive's own extent. Computed from the own box each time
/// it is read, never kept (the build's list is the caller's items).
#[inline(always)]
fn padded(b: &Aabb) -> Aabb {
    let pad = 1e-9
        * (b.max - b.min)
            .max_element()
            .max(b.centroid().abs().max_element())
        + 1e-300;
    Aabb {
        min: b.min - DVec3::splat(pad),
        max: b.max + DVec3::splat(pad),
    }
}

impl Bvh {
    /// Builds the hierarchy over `items`, `own(item)` the item's box, on
    /// every core, and puts the items in leaf order, in place: leaf ranges
    /// index into them. The items carry what the caller needs in that
    /// order (the primitives themselves, with their object numbers), so
    /// nothing is looked up again in another order and no second list is
    /// made.
    pub fn build_over<T: Send>(items: &mut [T], own: impl Fn(&T) -> Aabb + Sync) -> Bvh {
        Bvh::build_split(items, &own, FORKS)
    }

    /// [`Bvh::build_over`], forking `forks` times at most ([`FORKS`]).
    fn build_split<T: Send, F: Fn(&T) -> Aabb + Sync>(
        items: &mut [T],
        own: &F,
        forks: usize,
    ) -> Bvh {
        let mut nodes = Vec::with_capacity(2 * items.len().max(1));
        nodes.push(Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        build_node(&mut nodes, 0, items, own, 0, 0, forks);
        // Fewer than the 2n reserved: leaves hold up to MAX_LEAF items.
        nodes.shrink_to_fit();
        Bvh { nodes }
    }

    /// The items at `slots` (leaf order, ascending) have new boxes
    /// (`own`, as at the build): the leaves holding them and every node
    /// above take their new bounds, the tree's shape kept. The bounds are
    /// what a build of this shape gives over the items as they are now,
    /// so a search finds what it finds in a new build (the nearest hit,
    /// ties to the smaller rank), in a tree that may be looser where an
    /// item moved far. The work follows the nodes (a look at each, to
    /// know parents) and the depth, not the items.
    pub fn refit<T>(&mut self, items: &[T], slots: &[usize], own: impl Fn(&T) -> Aabb) {
        let nodes = &mut self.nodes;
        if nodes.len() < 2 || slots.is_empty() {
            if let Some(root) = nodes.first_mut() {
                root.bounds = items
                    .iter()
                    .fold(Aabb::EMPTY, |b, i| b.union(&padded(&own(i))));
            }
            return;
        }
        let mut parent = vec![u32::MAX; nodes.len()];
        let mut leaves = Vec::new();
        for (at, node) in nodes.iter().enumerate() {
            let (first, count) = (node.first as usize, node.count as usize);
            if count == 0 {
                parent[first] = at as u32;
                parent[first + 1] = at as u32;
            } else {
                let held = slots.partition_point(|&s| s < first);
                if slots.get(held).is_some_and(|&s| s < first + count) {
                    leaves.push(at);
                }
            }
        }
        for leaf in leaves {
            let node = &mut nodes[leaf];
            let (first, count) = (node.first as usize, node.count as usize);
            node.bounds = items[first..first + count]
                .iter()
                .fold(Aabb::EMPTY, |b, i| b.union(&padded(&own(i))));
            let mut at = leaf;
            while parent[at] != u32::MAX {
                at = parent[at] as usize;
                let left = nodes[at].first as usize;
                nodes[at].bounds = nodes[left].bounds.union(&nodes[left + 1].bounds);
            }
        }
    }

    /// Walks the hierarchy front to back for the `alive` lanes of `ray`,
    /// handing `search` each primitive whose box a lane enters before its
    /// nearest hit so far. A node is entered by the lanes that reach it;
    /// the primitives are tested for those lanes only, so each lane finds
    /// what it would find alone.
    #[inline(always)]
    pub fn nearest<L: Lanes>(
        &self,
        ray: &Ray<L::Vector>,
        alive: L::Mask,
        search: &mut impl Search<L>,
    ) {
        let origin = L::components(ray.origin);
        let [dx, dy, dz] = L::components(ray.dir);
        let inv_dir = [L::ONE / dx, L::ONE / dy, L::ONE / dz];
        // Pending nodes, each with the lanes that reached it (as bits: the
        // stack stays 1 KiB whatever the lanes' registers).
        let mut stack = [(0u32, 0u32); STACK];
        let mut top = 0;
        let mut node = &self.nodes[0];
        let mut lanes = alive & node.bounds.entry(&origin, &inv_dir, search.t_max()).1;
        if !lanes.any() {
            return;
        }
        loop {
            if node.count > 0 {
                let start = node.first as usize;
                for k in start..start + node.count as usize {
                    search.test(k, lanes);
                }
            } else {
                let (l, r) = (node.first as usize, node.first as usize + 1);
                let t_max = search.t_max();
                let (el, in_l) = self.nodes[l].bounds.entry(&origin, &inv_dir, t_max);
                let (er, in_r) = self.nodes[r].bounds.entry(&origin, &inv_dir, t_max);
                let (in_l, in_r) = (lanes & in_l, lanes & in_r);
                match (in_l.any(), in_r.any()) {
                    (true, true) => {
                        // Nearer child first (for most of the lanes in
                        // both); the other waits on the stack.
                        let both = in_l & in_r;
                        let left_first = 2 * (both & el.le(er)).count() >= both.count();
                        let (near, far) = if left_first {
                            ((l, in_l), (r, in_r))
                        } else {
                            ((r, in_r), (l, in_l))
                        };
                        stack[top] = (far.0 as u32, far.1.bits());
                        top += 1;
                        (node, lanes) = (&self.nodes[near.0], near.1);
                        continue;
                    }
                    (true, false) => {
                        (node, lanes) = (&self.nodes[l], in_l);
                        continue;
                    }
                    (false, true) => {
                        (node, lanes) = (&self.nodes[r], in_r);
                        continue;
                    }
                    (false, false) => {}
                }
            }
            // Next pending node still worth entering, for the lanes that
            // still reach it.
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let (index, waiting) = stack[top];
                let candidate = &self.nodes[index as usize];
                let enter = L::Mask::from_bits(waiting)
                    & candidate.bounds.entry(&origin, &inv_dir, search.t_max()).1;
                if enter.any() {
                    (node, lanes) = (candidate, enter);
                    break;
                }
            }
        }
    }
}

impl Bvh {
    /// Collects into `out` the positions (in leaf order) of the
    /// primitives whose boxes reach into the convex cone from `apex`
    /// bounded by the planes through it with inward unit `normals`, with a
    /// slack of `relative` per unit of distance for the normals' own
    /// error. Gives up and returns false once more than `limit` are found.
    pub fn collect_in_cone(
        &self,
        apex: DVec3,
        normals: &[DVec3; 4],
        relative: f64,
        limit: usize,
        out: &mut Vec<usize>,
    ) -> bool {
        out.clear();
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let b = &node.bounds;
            // The box corner farthest along each normal (the "p-vertex"):
            // if even it is outside a plane, the whole box is.
            let reach = b
                .centroid()
                .abs()
                .max_element()
                .max(apex.abs().max_element());
            let slack = relative * (reach + (b.max - b.min).max_element());
            let outside = normals.iter().any(|n| {
                let p = DVec3::select(n.cmpge(DVec3::ZERO), b.max, b.min);
                n.dot(p - apex) < -slack
            });
            if outside {
                continue;
            }
            if node.count > 0 {
                let start = node.first as usize;
                out.extend(start..start + node.count as usize);
                if out.len() > limit {
                    return false;
                }
            } else {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
        true
    }
}

/// Builds the subtree of `items` at `nodes[at]`; `forks` more times along
/// each path down, a split of two big halves builds them on two cores.
fn build_node<T: Send, F: Fn(&T) -> Aabb + Sync>(
    nodes: &mut Vec<Node>,
    at: usize,
    items: &mut [T],
    own: &F,
    offset: usize,
    depth: usize,
    forks: usize,
) {
    let bounds = items
        .iter()
        .fold(Aabb::EMPTY, |b, i| b.union(&padded(&own(i))));
    let leaf = Node {
        bounds,
        first: offset as u32,
        count: items.len() as u32,
    };
    if items.len() <= MAX_LEAF {
        nodes[at] = leaf;
        return;
    }
    let centroids = items.iter().fold(Aabb::EMPTY, |b, i| Aabb {
        min: b.min.min(own(i).centroid()),
        max: b.max.max(own(i).centroid()),
    });
    let extent = centroids.max - centroids.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let split = if extent[axis] > 0.0 && depth < SAH_DEPTH {
        sah_split(items, own, axis, centroids.min[axis], extent[axis], &bounds)
    } else {
        None
    };
    let mid = match split {
        Some(SahSplit::Leaf) => {
            nodes[at] = leaf;
            return;
        }
        Some(SahSplit::At(mid)) => mid,
        None => {
            // Centroids all equal (or too deep): halve by the median.
            let mid = items.len() / 2;
            items.select_nth_unstable_by(mid, |a, b| {
                own(a).centroid()[axis].total_cmp(&own(b).centroid()[axis])
            });
            mid
        }
    };
    let left = nodes.len();
    let placeholder = Node {
        bounds: Aabb::EMPTY,
        first: 0,
        count: 0,
    };
    nodes.push(placeholder);
    nodes.push(placeholder);
    nodes[at] = Node {
        bounds,
        first: left as u32,
        count: 0,
    };
    let (a, b) = items.split_at_mut(mid);
    if forks > 0 && a.len().min(b.len()) >= PARALLEL_ITEMS {
        // The two halves on two cores, each in a list of its own (its
        // root first), appended after: the list one core would write.
        let subtree = |items: &mut [T], offset| {
            let mut tree = vec![placeholder];
            build_node(&mut tree, 0, items, own, offset, depth + 1, forks - 1);
            tree
        };
        let (left_tree, right_tree) =
            rayon::join(|| subtree(a, offset), || subtree(b, offset + mid));
        for (slot, tree) in [(left, left_tree), (left + 1, right_tree)] {
            // Node k ≥ 1 of `tree` goes to `base + k - 1`.
            let base = nodes.len();
            let moved = |node: Node| match node.count {
                0 => Node {
                    first: (base + node.first as usize - 1) as u32,
                    ..node
                },
                _ => node,
            };
            nodes[slot] = moved(tree[0]);
            nodes.extend(tree[1..].iter().map(|&node| moved(node)));
        }
        return;
    }
    build_node(nodes, left, a, own, offset, depth + 1, forks);
    build_node(nodes, left + 1, b, own, offset + mid, depth + 1, forks);
}

enum SahSplit {
    /// Splitting costs more than testing every primitive.
    Leaf,
    /// Items partitioned; the left part has this many.
    At(usize),
}

fn sah_split<T>(
    items: &mut [T],
    own: &impl Fn(&T) -> Aabb,
    axis: usize,
    lo: f64,
    extent: f64,
    bounds: &Aabb,
) -> Option<SahSplit> {
    let scale = BINS as f64 / extent;
    let bin_of = |c: DVec3| (((c[axis] - lo) * scale) as usize).min(BINS - 1);
    let mut bins = [(Aabb::EMPTY, 0usize); BINS];
    for item in items.iter() {
        let item = own(item);
        let b = &mut bins[bin_of(item.centroid())];
        b.0 = b.0.union(&padded(&item));
        b.1 += 1;
    }
    // Sweep from the right, then from the left: cost of each of the
    // BINS − 1 planes.
    let mut right_area = [0.0; BINS];
    let mut acc = (Aabb::EMPTY, 0usize);
    for i in (1..BINS).rev() {
        acc.0 = acc.0.union(&bins[i].0);
        acc.1 += bins[i].1;
        right_area[i] = acc.0.half_area() * acc.1 as f64;
    }
    let mut best: Option<(f64, usize)> = None;
    let mut acc = (Aabb::EMPTY, 0usize);
    for i in 0..BINS - 1 {
        acc.0 = acc.0.union(&bins[i].0);
        acc.1 += bins[i].1;
        if acc.1 == 0 || acc.1 == items.len() {
            continue;
        }
        let cost = acc.0.half_area() * acc.1 as f64 + right_area[i + 1];
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, i));
        }
    }
    let (cost, plane) = best?;
    // Leaf cost: every primitive tested; a split also pays a box test.
    let leaf_cost = bounds.half_area() * items.len() as f64;
    if items.len() <= 2 * MAX_LEAF && cost >= leaf_cost {
        return Some(SahSplit::Leaf);
    }
    let mut mid = 0;
    for i in 0..items.len() {
        if bin_of(own(&items[i]).centroid()) <= plane {
            items.swap(i, mid);
            mid += 1;
        }
    }
    Some(SahSplit::At(mid))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{F64x4, Mask4};

    fn indices(n: usize) -> Vec<u32> {
        (0..n as u32).collect()
    }

    /// The hierarchy over `boxes` (primitive i has box i), and the
    /// primitives' indices in leaf order.
    fn build(boxes: &[Aabb]) -> (Bvh, Vec<u32>) {
        let mut order = indices(boxes.len());
        let bvh = Bvh::build_over(&mut order, |&i| boxes[i as usize]);
        (bvh, order)
    }

    /// Unit boxes along a diagonal; "hit" is the box's entry distance.
    fn boxes(n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let c = DVec3::new((i * 7 % 13) as f64, (i * 3 % 11) as f64, i as f64 * 0.5);
                Aabb {
                    min: c - 0.25,
                    max: c + 0.25,
                }
            })
            .collect()
    }

    /// A refit after items moved has the bounds a build of the same shape
    /// gives over the moved items, and finds what brute force finds.
    #[test]
    fn a_refit_holds_the_moved_items() {
        let boxes = boxes(3000);
        let (mut bvh, order) = build(&boxes);
        // Leaf order, then three items moved far and near.
        let mut placed: Vec<Aabb> = order.iter().map(|&i| boxes[i as usize]).collect();
        let slots = [5, 1700, 2999];
        for (k, &slot) in slots.iter().enumerate() {
            let shift = DVec3::splat([40.0, -3.0, 0.5][k]);
            placed[slot].min += shift;
            placed[slot].max += shift;
        }
        bvh.refit(&placed, &slots, |b| *b);
        // Every node holds its items, as a build's nodes do.
        fn check(bvh: &Bvh, at: usize, items: &[Aabb]) -> Aabb {
            let node = bvh.nodes[at];
            let held = if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                items[range]
                    .iter()
                    .fold(Aabb::EMPTY, |b, i| b.union(&padded(i)))
            } else {
                let left = node.first as usize;
                check(bvh, left, items).union(&check(bvh, left + 1, items))
            };
            assert_eq!(node.bounds, held);
            held
        }
        check(&bvh, 0, &placed);
        for k in 0..200 {
            let ray = diagonal_ray(k);
            let mut scan = Scan::new(|_, j| entry(&placed[j], &ray), |j| j);
            bvh.nearest::<f64>(&ray, true, &mut scan);
            let brute = (0..placed.len())
                .filter_map(|j| entry(&placed[j], &ray).map(|t| (t, j)))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(scan.best[0], brute, "ray {k}");
        }
    }

    #[test]
    fn a_build_on_the_cores_makes_the_tree_of_one_core() {
        // Scattered boxes of varied sizes, some equal, many of them.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let boxes: Vec<Aabb> = (0..200_000)
            .map(|i| {
                let c = DVec3::new(next() * 100.0, next() * 10.0, (i % 1000) as f64);
                let r = 0.01 + next();
                Aabb {
                    min: c - r,
                    max: c + r,
                }
            })
            .collect();
        let own = |&i: &u32| boxes[i as usize];
        let (mut one_order, mut many_order) = (indices(boxes.len()), indices(boxes.len()));
        let one = Bvh::build_split(&mut one_order, &own, 0);
        let many = Bvh::build_split(&mut many_order, &own, FORKS);
        // Each subtree's list is in the order one core writes it: the
        // whole list is the same, node for node.
        assert!(one_order == many_order, "primitives in another order");
        assert!(
            format!("{:?}", one.nodes) == format!("{:?}", many.nodes),
            "another tree"
        );
    }

    /// A search by "hit" functions, one per lane: the nearest t, ties to
    /// the smaller rank, as the renderer's search keeps them.
    struct Scan<H: Fn(usize, usize) -> Option<f64>, R: Fn(usize) -> usize> {
        hit: H,
        rank: R,
        best: [Option<(f64, usize)>; 4],
        tested: usize,
    }

    impl<H: Fn(usize, usize) -> Option<f64>, R: Fn(usize) -> usize> Scan<H, R> {
        fn new(hit: H, rank: R) -> Self {
            Scan {
                hit,
                rank,
                best: [None; 4],
                tested: 0,
            }
        }

        fn consider(&mut self, lane: usize, k: usize) {
            self.tested += 1;
            if let Some(t) = (self.hit)(lane, k) {
                let better = self.best[lane]
                    .is_none_or(|(b, j)| t < b || (t == b && (self.rank)(k) < (self.rank)(j)));
                if better {
                    self.best[lane] = Some((t, k));
                }
            }
        }

        fn t(&self, lane: usize) -> f64 {
            self.best[lane].map_or(f64::INFINITY, |b| b.0)
        }
    }

    impl<H: Fn(usize, usize) -> Option<f64>, R: Fn(usize) -> usize> Search<f64> for Scan<H, R> {
        fn t_max(&self) -> f64 {
            self.t(0)
        }
        fn test(&mut self, k: usize, lanes: bool) {
            if lanes {
                self.consider(0, k);
            }
        }
    }

    impl<H: Fn(usize, usize) -> Option<f64>, R: Fn(usize) -> usize> Search<F64x4> for Scan<H, R> {
        fn t_max(&self) -> F64x4 {
            F64x4::from_fn(|i| self.t(i))
        }
        fn test(&mut self, k: usize, lanes: Mask4) {
            for i in 0..4 {
                if lanes.lane(i) {
                    self.consider(i, k);
                }
            }
        }
    }

    fn diagonal_ray(k: u32) -> Ray {
        let f = f64::from(k);
        Ray::new(
            DVec3::new(-5.0, -5.0, -5.0),
            DVec3::new(
                1.0 + (f * 0.37).sin(),
                1.0 + (f * 0.71).cos(),
                1.0 + 0.01 * f,
            )
            .normalize(),
        )
    }

    fn entry(b: &Aabb, ray: &Ray) -> Option<f64> {
        let (t, enters) = b.entry::<f64>(
            &ray.origin.to_array(),
            &ray.dir.recip().to_array(),
            f64::INFINITY,
        );
        enters.then_some(t)
    }

    #[test]
    fn nearest_equals_brute_force() {
        let b = boxes(500);
        let (bvh, order) = build(&b);
        let mut sorted = order.clone();
        sorted.sort();
        assert_eq!(sorted, (0..500).collect::<Vec<u32>>());
        for k in 0..200 {
            let ray = diagonal_ray(k);
            let brute = (0..b.len())
                .filter_map(|i| entry(&b[i], &ray).map(|t| (t, i)))
                .min_by(|x, y| x.0.total_cmp(&y.0));
            let mut scan = Scan::new(|_, k| entry(&b[order[k] as usize], &ray), |k| k);
            bvh.nearest::<f64>(&ray, true, &mut scan);
            let fast = scan.best[0].map(|(t, k)| (t, order[k] as usize));
            assert_eq!(brute.map(|x| x.0), fast.map(|x| x.0), "ray {k}");
        }
    }

    /// Four rays walked together find, lane by lane, what each finds alone;
    /// a lane left out finds nothing.
    #[test]
    fn lanes_find_what_each_ray_finds_alone() {
        let b = boxes(500);
        let (bvh, order) = build(&b);
        for k in 0..100 {
            let rays: [Ray; 4] = std::array::from_fn(|i| diagonal_ray(4 * k + i as u32));
            let lanes = Ray::new(
                F64x4::vector_from_fn(|i| rays[i].origin),
                F64x4::vector_from_fn(|i| rays[i].dir),
            );
            let hit = |lane: usize, k: usize| entry(&b[order[k] as usize], &rays[lane]);
            let mut together = Scan::new(hit, |k| k);
            let alive = Mask4::from_fn(|i| i != 2);
            bvh.nearest::<F64x4>(&lanes, alive, &mut together);
            for (i, ray) in rays.iter().enumerate() {
                let mut alone = Scan::new(|_, k| entry(&b[order[k] as usize], ray), |k| k);
                bvh.nearest::<f64>(ray, true, &mut alone);
                let expected = if i == 2 { None } else { alone.best[0] };
                assert_eq!(together.best[i], expected, "rays {k}, lane {i}");
            }
        }
    }

    #[test]
    fn identical_boxes_still_build_a_shallow_tree() {
        let b = vec![
            Aabb {
                min: DVec3::ZERO,
                max: DVec3::ONE
            };
            10_000
        ];
        let (bvh, order) = build(&b);
        assert!(bvh.nodes.iter().all(|n| n.count as usize <= MAX_LEAF));
        let ray = Ray::new(DVec3::splat(-1.0), DVec3::ONE.normalize());
        // Every primitive "hit" beyond the boxes: nothing can be pruned.
        let mut scan = Scan::new(|_, _| Some(100.0), |k| order[k] as usize);
        bvh.nearest::<f64>(&ray, true, &mut scan);
        // The tie goes to the smallest rank: primitive 0, wherever the
        // build put it.
        let at = order.iter().position(|&i| i == 0);
        assert_eq!(scan.best[0], Some((100.0, at.unwrap())));
        assert_eq!(scan.tested, 10_000, "all overlap, so all are tested");
    }
}
