//! Cutting an image into regions of even cost, one per task of a batch
//! job (`rayoflight split scene.xml --tasks N`).
//!
//! Equal areas are not equal work: a pixel of sky costs one ray, a pixel
//! between two mirrors as many as the reflection depth allows. So the
//! split first estimates where the work is ([`CostMap::estimate`]): a
//! coarse pre-pass traces a few rays in each cell of a grid over the
//! image (at most [`CELLS_ACROSS`] cells a side, a few thousandths of
//! the render's rays on a large image) and counts the rays each one
//! costs, reflections included, as the render would trace them. Then
//! [`split`] cuts the image in two again and again (a k-d split): each
//! cut, along either axis, on the image's tile grid where it can, is the
//! one whose two sides, each given its share of the tasks, leave the
//! dearest task the least work.

use crate::render::region::Region;
use crate::render::{RenderOptions, TILE_SIZE, Tile, prepare};
use crate::scene::Scene;
use rayon::prelude::*;

/// Cells of the cost map across the longer side of the image, at most.
pub const CELLS_ACROSS: u32 = 128;

/// Rays traced per cell of the cost map, at most (a 4×4 grid).
const SAMPLES_ACROSS: u32 = 4;

/// What a pixel costs beside its rays, in rays: filling and copying it
/// (all a pixel costs in a tile from which nothing can be hit).
const FILL: f64 = 0.02;

/// An estimate of the render's cost over the image: rays per cell of a
/// grid, a cell a multiple of the tile size; between grid lines the cost
/// of a cell is spread evenly over its pixels.
#[derive(Debug, Clone)]
pub struct CostMap {
    width: u32,
    height: u32,
    /// A cell's edge, in pixels.
    cell: u32,
    columns: u32,
    rows: u32,
    /// Sums of the cells' costs above and left of each grid point:
    /// `(columns + 1) × (rows + 1)`, row by row.
    sums: Vec<f64>,
}

/// Why an image cannot be split.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SplitError {
    #[error("cannot split into {tasks} tasks: the {width}×{height} image has fewer pixels")]
    TooManyTasks {
        tasks: usize,
        width: u32,
        height: u32,
    },
    #[error("cannot split into 0 tasks")]
    NoTasks,
}

impl CostMap {
    /// The coarse pre-pass: rays through a grid of points in each cell,
    /// traced as `options` render them (early stop, depth), counted.
    pub fn estimate(scene: &Scene, options: &RenderOptions) -> CostMap {
        let (width, height) = (scene.camera.width, scene.camera.height);
        let tiles = width.max(height).div_ceil(CELLS_ACROSS * TILE_SIZE);
        let cell = TILE_SIZE * tiles.max(1);
        let (columns, rows) = (width.div_ceil(cell), height.div_ceil(cell));
        // About one ray per 256 pixels (a 16×16 square), 1 to 16 a cell.
        let across = (cell / 16).clamp(1, SAMPLES_ACROSS);
        let cells: Vec<Region> = (0..rows)
            .flat_map(|r| (0..columns).map(move |c| (c, r)))
            .map(|(c, r)| Region {
                x0: c * cell,
                y0: r * cell,
                x1: ((c + 1) * cell).min(width),
                y1: ((r + 1) * cell).min(height),
            })
            .collect();
        let prepared = prepare(scene, options);
        let costs: Vec<f64> = cells
            .par_iter()
            .map(|cell| {
                // Sample points spread evenly over the cell as it is (an
                // edge cell may be narrower).
                let at = |start: u32, size: u32, k: u32| {
                    f64::from(start) + (f64::from(k) + 0.5) * f64::from(size) / f64::from(across)
                };
                let points: Vec<(f64, f64)> = (0..across)
                    .flat_map(|b| (0..across).map(move |a| (a, b)))
                    .map(|(a, b)| (at(cell.x0, cell.width(), a), at(cell.y0, cell.height(), b)))
                    .collect();
                let tile = Tile {
                    x: cell.x0,
                    y: cell.y0,
                    width: cell.width(),
                    height: cell.height(),
                };
                let rays = prepared.rays_through(&tile, &points);
                (rays as f64 / points.len() as f64 + FILL) * cell.area() as f64
            })
            .collect();
        let mut sums = vec![0.0; (columns as usize + 1) * (rows as usize + 1)];
        let stride = columns as usize + 1;
        for r in 0..rows as usize {
            for c in 0..columns as usize {
                sums[(r + 1) * stride + c + 1] = costs[r * columns as usize + c]
                    + sums[r * stride + c + 1]
                    + sums[(r + 1) * stride + c]
                    - sums[r * stride + c];
            }
        }
        CostMap {
            width,
            height,
            cell,
            columns,
            rows,
            sums,
        }
    }

    /// The whole image's region.
    pub fn frame(&self) -> Region {
        Region::whole(self.width, self.height)
    }

    /// The estimated cost of `region`, in rays.
    pub fn cost(&self, region: &Region) -> f64 {
        let Region { x0, y0, x1, y1 } = *region;
        self.above_left(x1, y1) - self.above_left(x0, y1) - self.above_left(x1, y0)
            + self.above_left(x0, y0)
    }

    /// The cost of the pixels left of x and above y.
    fn above_left(&self, x: u32, y: u32) -> f64 {
        // Whole cells before (i, j), and the share of cell i (j) that lies
        // before x (y).
        let (i, j) = (x / self.cell, y / self.cell);
        let share = |v: u32, k: u32, count: u32, size: u32| {
            if k >= count {
                return 0.0;
            }
            let edge = (self.cell).min(size - k * self.cell);
            f64::from(v - k * self.cell) / f64::from(edge)
        };
        let (fx, fy) = (
            share(x, i, self.columns, self.width),
            share(y, j, self.rows, self.height),
        );
        let stride = self.columns as usize + 1;
        let sum = |c: u32, r: u32| {
            let (c, r) = (c.min(self.columns) as usize, r.min(self.rows) as usize);
            self.sums[r * stride + c]
        };
        let whole = sum(i, j);
        let column = sum(i + 1, j) - whole;
        let row = sum(i, j + 1) - whole;
        let corner = sum(i + 1, j + 1) - sum(i + 1, j) - sum(i, j + 1) + whole;
        whole + fx * column + fy * row + fx * fy * corner
    }
}

/// Estimates the cost of rendering `scene` with `options`
/// ([`CostMap::estimate`]) and splits its image into `tasks` regions
/// ([`split`]).
pub fn plan(
    scene: &Scene,
    options: &RenderOptions,
    tasks: usize,
) -> Result<Vec<Region>, SplitError> {
    split(&CostMap::estimate(scene, options), tasks)
}

/// `tasks` regions that cover the image once, of estimated costs as even
/// as the cuts allow, in reading order (by top edge, then left).
pub fn split(map: &CostMap, tasks: usize) -> Result<Vec<Region>, SplitError> {
    let frame = map.frame();
    if tasks == 0 {
        return Err(SplitError::NoTasks);
    }
    if tasks as u64 > frame.area() {
        return Err(SplitError::TooManyTasks {
            tasks,
            width: map.width,
            height: map.height,
        });
    }
    let mut regions = Vec::with_capacity(tasks);
    cut(map, frame, tasks, &mut regions);
    regions.sort_by_key(|r| (r.y0, r.x0));
    Ok(regions)
}

/// A cut of a region in two, with each side's share of the tasks.
#[derive(Debug, Clone, Copy)]
struct Cut {
    sides: [(Region, usize); 2],
    /// The dearest task's estimated cost if this cut is taken.
    dearest: f64,
}

/// Splits `region` into `tasks` regions (at least one pixel each) into
/// `out`.
fn cut(map: &CostMap, region: Region, tasks: usize, out: &mut Vec<Region>) {
    if tasks == 1 {
        out.push(region);
        return;
    }
    // Cuts on the tile grid first (every pixel is then traced in a tile
    // of the same size as in the whole render); a region too small for
    // those is cut anywhere.
    let best = best_cut(map, region, tasks, true).or_else(|| best_cut(map, region, tasks, false));
    let Some(best) = best else {
        // Unreachable while a region holds at least as many pixels as
        // tasks (any 1-pixel-wide cut then fits); keep the region whole
        // rather than lose it.
        out.push(region);
        return;
    };
    for (side, share) in best.sides {
        cut(map, side, share, out);
    }
}

/// The best cut of `region` for `tasks` (see [`Cut`]), through the longer
/// side first so that even cuts keep regions squarish; `on_grid`: only at
/// multiples of the tile size.
fn best_cut(map: &CostMap, region: Region, tasks: usize, on_grid: bool) -> Option<Cut> {
    let total = map.cost(&region);
    let vertical_first = region.width() >= region.height();
    let mut best: Option<Cut> = None;
    for vertical in [vertical_first, !vertical_first] {
        let (start, end) = if vertical {
            (region.x0, region.x1)
        } else {
            (region.y0, region.y1)
        };
        let step = if on_grid { TILE_SIZE } else { 1 };
        let first = (start / step + 1) * step;
        for at in (first..end).step_by(step as usize) {
            let (a, b) = if vertical {
                (Region { x1: at, ..region }, Region { x0: at, ..region })
            } else {
                (Region { y1: at, ..region }, Region { y0: at, ..region })
            };
            let (cost_a, cost_b) = (map.cost(&a), total - map.cost(&a));
            // Tasks in proportion to cost, each side at least one and at
            // most one a pixel.
            let wanted = (tasks as f64 * cost_a / total.max(f64::MIN_POSITIVE)).round() as usize;
            let low = 1.max(tasks.saturating_sub(usize::try_from(b.area()).unwrap_or(usize::MAX)));
            let high = (tasks - 1).min(usize::try_from(a.area()).unwrap_or(usize::MAX));
            if low > high {
                continue;
            }
            let share = wanted.clamp(low, high);
            let dearest = (cost_a / share as f64).max(cost_b / (tasks - share) as f64);
            // Strictly better only: among equals the first (longer side,
            // nearer the start) stays.
            if best.is_none_or(|b| dearest < b.dearest * (1.0 - 1e-12)) {
                best = Some(Cut {
                    sides: [(a, share), (b, tasks - share)],
                    dearest,
                });
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map of a uniform cost over `width × height` (an empty scene).
    fn uniform(width: u32, height: u32) -> CostMap {
        let scene_text = format!(
            r#"<scene><camera width="{width}" height="{height}" eyeDistance="1"/><model type="ambient"/></scene>"#
        );
        let scene = crate::scene::parse(&scene_text, std::path::Path::new("u.xml")).unwrap();
        CostMap::estimate(&scene, &RenderOptions::default())
    }

    fn covers_once(regions: &[Region], width: u32, height: u32) {
        let mut count = vec![0u8; (width * height) as usize];
        for r in regions {
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    count[(y * width + x) as usize] += 1;
                }
            }
        }
        assert!(count.iter().all(|&c| c == 1), "{regions:?}");
    }

    #[test]
    fn costs_add_up_over_any_cut() {
        let map = uniform(300, 170);
        // An empty scene: every tile is filled without a ray.
        let per_pixel = FILL;
        let whole = map.cost(&map.frame());
        assert!((whole - 300.0 * 170.0 * per_pixel).abs() < 1e-6, "{whole}");
        let a = Region::new(0, 0, 77, 170).unwrap();
        let b = Region::new(77, 0, 300, 170).unwrap();
        assert!((map.cost(&a) + map.cost(&b) - whole).abs() < 1e-6);
        assert!((map.cost(&a) - 77.0 * 170.0 * per_pixel).abs() < 1e-6);
        let c = Region::new(5, 9, 6, 10).unwrap();
        assert!((map.cost(&c) - per_pixel).abs() < 1e-9);
    }

    #[test]
    fn a_split_covers_the_image_once_with_as_many_regions_as_tasks() {
        for (w, h, tasks) in [
            (300, 170, 1),
            (300, 170, 7),
            (64, 64, 64),
            (5, 3, 15),
            (1, 9, 4),
        ] {
            let map = uniform(w, h);
            let regions = split(&map, tasks).unwrap();
            assert_eq!(regions.len(), tasks);
            covers_once(&regions, w, h);
        }
        let map = uniform(5, 3);
        assert_eq!(
            split(&map, 16),
            Err(SplitError::TooManyTasks {
                tasks: 16,
                width: 5,
                height: 3
            })
        );
        assert_eq!(split(&map, 0), Err(SplitError::NoTasks));
    }

    #[test]
    fn uniform_cost_gives_even_areas_on_the_tile_grid() {
        let map = uniform(512, 256);
        let regions = split(&map, 8).unwrap();
        for r in &regions {
            assert_eq!(r.area(), 512 * 256 / 8, "{r}");
            assert!([r.x0, r.y0].iter().all(|v| v % TILE_SIZE == 0), "{r}");
        }
    }
}
