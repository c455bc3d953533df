//! The trace loop and what it makes: a packet of camera rays followed
//! through whitted reflections and shaded at each hit ([`Prepared::trace`],
//! the same for every kernel), into the pixels of a tile, one pixel, the
//! rays a tile costs, or the recorded trees of an explained pixel; and the
//! app's pick. Each is a piece of work run with the method's kernel
//! ([`super::kernel`]).

use crate::geometry::{Lanes, MAX_LANES, Mask, Ray, Real, Vector};
use crate::render::explain::{Explanation, PixelValue, Recorder, Sample};
use crate::render::observer::{Ended, Observer};
use crate::render::{Cancel, Pass, Texel, Tile, in_f32, to_8bit};
use crate::scene::Object;
use crate::shading::{Color, Illumination, Material, Terms, local_color};
use glam::DVec3;
use std::ops::ControlFlow;

use super::kernel::{Alive, Kernel, Vectors, WithKernel};
use super::{Candidates, Prepared, TILE_CANDIDATES};

/// What tracing a packet gives back, per lane: the camera ray's hit (its
/// terms, normal, distance and object) and the reflected colour behind
/// it. Lanes that hit nothing hold zero terms, t = ∞ and object −1.
#[derive(Debug, Clone, Copy)]
pub(super) struct Traced<L: Lanes> {
    /// The camera ray's hit's own terms.
    pub terms: Terms<L::Vector>,
    /// ks I_r: the later bounces' colours, each weighted by the product
    /// of the ks before it.
    pub reflection: L::Vector,
    /// The shading normal N at the camera ray's hit.
    pub normal: L::Vector,
    pub t: L,
    /// Index of the object in the scene's object list, −1 for none.
    pub object: L,
}

impl<L: Lanes> Traced<L> {
    #[inline(always)]
    fn dark() -> Traced<L> {
        let zero = L::splat_vector(Color::ZERO);
        Traced {
            terms: Terms {
                ambient: zero,
                diffuse: zero,
                specular: zero,
            },
            reflection: zero,
            normal: zero,
            t: L::splat(f64::INFINITY),
            object: L::splat(-1.0),
        }
    }

    /// The colour: ((ambient + diffuse) + specular) + reflection.
    #[inline(always)]
    pub fn color(&self) -> L::Vector {
        self.terms.local() + self.reflection
    }

    /// The value of `pass` (unclamped), per lane.
    #[inline(always)]
    fn value(&self, pass: Pass) -> L::Vector {
        match pass {
            Pass::Final => self.color(),
            Pass::Ambient => self.terms.ambient,
            Pass::Diffuse => self.terms.diffuse,
            Pass::Specular => self.terms.specular,
            Pass::Reflection => self.reflection,
            Pass::Normal => self.normal,
            Pass::Depth => L::vector_from_fn(|i| DVec3::splat(self.t.lane(i))),
            Pass::Object => L::vector_from_fn(|i| DVec3::splat(self.object.lane(i) + 1.0)),
        }
    }

    /// Lane `k`'s four terms and colour in f32, as an EXR holds them
    /// ([`in_f32`]): the value of `pass` (a term or final).
    #[inline(always)]
    fn value_in_f32(&self, pass: Pass, k: usize) -> DVec3 {
        let lane = |v| L::vector_lane(v, k);
        let terms = [
            lane(self.terms.ambient),
            lane(self.terms.diffuse),
            lane(self.terms.specular),
            lane(self.reflection),
        ];
        let (terms, color) = in_f32(terms, lane(self.color()));
        match pass {
            Pass::Ambient => terms[0],
            Pass::Diffuse => terms[1],
            Pass::Specular => terms[2],
            Pass::Reflection => terms[3],
            _ => color,
        }
    }
}
/// [`Prepared::pixel`]'s work.
struct PixelAt {
    i: u32,
    j: u32,
}

impl WithKernel for PixelAt {
    type Output = [u8; 3];
    #[inline(always)]
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> [u8; 3] {
        let mut out = [[0; 3]; MAX_LANES];
        p.pixels::<K, u8>(
            kernel,
            &[(self.i, self.j)],
            Candidates::All,
            &mut 0,
            &mut out,
        );
        out[0]
    }
}

/// [`Prepared::explain_each`]'s work: each ray through the pixel traced
/// alone, in turn; with a visitor, its trace recorded and handed to it
/// (one tree held at a time), without one only its colour kept. Returns
/// the pixel, or `None` once the visitor stops.
struct ExplainAt<'a> {
    i: u32,
    j: u32,
    visit: Option<&'a mut dyn FnMut(Sample) -> ControlFlow<()>>,
}

impl WithKernel for ExplainAt<'_> {
    type Output = Option<PixelValue>;
    const ONE_LANE: bool = true;
    fn run<K: Kernel>(mut self, p: &Prepared, kernel: &K) -> Option<PixelValue> {
        // The early stop of one-ray pixels, as the render does.
        let exact_stop = p.aa == 1 && p.world.early_stop;
        let (mut sum, mut clamped_sum) = (DVec3::ZERO, DVec3::ZERO);
        let mut first = DVec3::ZERO;
        // In a draft, the pixel whose rays this one copies.
        let traced = p.traced_for(self.i, self.j);
        for k in 0..p.sample_count() {
            let at = p.sample_point(traced.0, traced.1, k);
            let packet = p.packet::<K>(&[at]);
            let color = match self.visit.as_deref_mut() {
                Some(visit) => {
                    let mut recorder = Recorder::default();
                    let traced = p.trace(
                        kernel,
                        packet,
                        Candidates::All,
                        exact_stop,
                        &mut 0,
                        &mut recorder,
                    );
                    let sample = recorder.finish(
                        at,
                        K::L::vector_lane(traced.reflection, 0),
                        K::L::vector_lane(traced.color(), 0),
                    );
                    let color = sample.color;
                    if visit(sample).is_break() {
                        return None;
                    }
                    color
                }
                None => {
                    let traced =
                        p.trace(kernel, packet, Candidates::All, exact_stop, &mut 0, &mut ());
                    K::L::vector_lane(traced.color(), 0)
                }
            };
            if k == 0 {
                first = color;
            }
            sum += color;
            clamped_sum += clamped(color);
        }
        // The pixel as [`Prepared::pixels`] makes it.
        let n = f64::from(p.aa);
        let (rgb, rgb8) = if p.aa == 1 {
            (first, u8::pixel(clamped(first)))
        } else {
            (sum / (n * n), u8::pixel(clamped_sum / (n * n)))
        };
        Some(PixelValue {
            traced,
            rgb,
            rgb8,
            samples: p.sample_count(),
        })
    }
}

/// [`Prepared::rays_through`]'s work: each ray traced alone among the
/// tile's candidates, as the render traces it, its rays counted.
struct RaysThrough<'a> {
    points: &'a [(f64, f64)],
    candidates: Candidates<'a>,
}

impl WithKernel for RaysThrough<'_> {
    type Output = u64;
    const ONE_LANE: bool = true;
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> u64 {
        let exact_stop = p.aa == 1 && p.world.early_stop;
        let mut rays = 0;
        for &at in self.points {
            p.trace(
                kernel,
                p.packet::<K>(&[at]),
                self.candidates,
                exact_stop,
                &mut rays,
                &mut (),
            );
        }
        rays
    }
}

/// [`Prepared::render_tile_into`]'s work.
struct TileInto<'a, T> {
    tile: &'a Tile,
    cancel: &'a Cancel,
    out: &'a mut Vec<T>,
}

impl<T: Texel> WithKernel for TileInto<'_, T> {
    type Output = Option<u64>;
    #[inline(always)]
    fn run<K: Kernel>(self, p: &Prepared, kernel: &K) -> Option<u64> {
        p.tile_into(kernel, self.tile, self.cancel, self.out)
    }
}
/// A colour clamped to [0, 1] per channel (NaN to 0), as pixels average
/// their samples.
#[inline(always)]
fn clamped(c: Color) -> Color {
    c.clamp(Color::ZERO, Color::ONE)
}
impl Prepared {
    /// The colours of a packet of primary rays (the `alive` lanes),
    /// following whitted reflections as a loop; a lane leaves the loop
    /// when its chain ends. `exact_stop`: end a chain once the rest cannot
    /// change the 8-bit value of its colour. `rays` counts the rays traced;
    /// `observer` sees each step (`()`: nothing, and costs nothing).
    ///
    /// The colour is the camera ray's hit's own terms, then the later
    /// bounces: ((ambient + diffuse) + specular) + reflection, where
    /// reflection = Σ_k w_k I_k over the later hits, w_k the product of
    /// the ks met before hit k: the whitted formula I = phong + ks I_r
    /// (docs/scene-format.md, Illumination) unrolled.
    #[inline(always)]
    fn trace<K: Kernel, O: Observer<K::L>>(
        &self,
        kernel: &K,
        (primary, alive): (Ray<Vectors<K>>, Alive<K>),
        candidates: Candidates,
        exact_stop: bool,
        rays: &mut u64,
        observer: &mut O,
    ) -> Traced<K::L> {
        let world = &*self.world;
        let zero = K::L::splat_vector(Color::ZERO);
        let mut traced = Traced::<K::L>::dark();
        // The camera ray's hit's own colour, once known.
        let mut first = zero;
        // Product of the ks of the surfaces met so far.
        let mut weight = K::L::ONE;
        let mut alive = alive;
        let mut ray = kernel.primary(primary);
        for bounce in 0..=world.depth {
            let among = if bounce == 0 {
                candidates
            } else {
                Candidates::All
            };
            *rays += u64::from(alive.count());
            observer.ray(bounce, &kernel.in_f64(&ray));
            let hits = kernel.nearest(self, &ray, alive, among);
            // A miss is black: its lane is done.
            observer.missed(alive & !hits.found);
            alive = alive & hits.found;
            if !alive.any() {
                break;
            }
            // The surface each lane hit.
            // (A plain loop: a closure here could be left out of line,
            // and the lanes' instructions in it with it.)
            let mut surfaces: [&Object; MAX_LANES] = [&world.objects[0]; MAX_LANES];
            for (i, surface) in surfaces.iter_mut().enumerate().take(K::L::WIDTH) {
                if alive.lane(i) {
                    *surface = &world.objects[hits.object.lane(i) as usize];
                }
            }
            let c = K::L::vector_from_fn(|i| surfaces[i].color);
            let material = Material {
                ka: K::L::from_fn(|i| surfaces[i].material.ka),
                kd: K::L::from_fn(|i| surfaces[i].material.kd),
                ks: K::L::from_fn(|i| surfaces[i].material.ks),
                m: K::L::from_fn(|i| surfaces[i].material.m),
            };
            let point = kernel.surface(self, &ray, &hits, alive);
            let terms = local_color(
                world.illumination,
                c,
                &material,
                &world.lights,
                &point,
                observer,
            );
            observer.hit(
                alive,
                hits.object,
                hits.t,
                &point,
                &terms,
                material.ks,
                weight,
            );
            let local = terms.local();
            if bounce == 0 {
                let pick = |v| <Vectors<K>>::select(alive, v, zero);
                traced.terms = Terms {
                    ambient: pick(terms.ambient),
                    diffuse: pick(terms.diffuse),
                    specular: pick(terms.specular),
                };
                traced.normal = pick(point.n);
                traced.t = K::L::select(alive, hits.t, traced.t);
                traced.object = K::L::select(alive, hits.object, traced.object);
                first = pick(local);
            } else {
                traced.reflection = <Vectors<K>>::select(
                    alive,
                    traced.reflection + local.scaled(weight),
                    traced.reflection,
                );
            }
            weight = K::L::select(alive, weight * material.ks, weight);
            if bounce == world.depth {
                observer.ended(alive, Ended::Depth);
                break;
            }
            let mirror = !weight.eq(K::L::ZERO);
            observer.ended(alive & !mirror, Ended::NoMirror);
            alive = alive & mirror;
            if exact_stop && alive.any() {
                let levels = world.depth - bounce;
                let color = first + traced.reflection;
                let mut invisible = [false; MAX_LANES];
                for (i, lane) in invisible.iter_mut().enumerate().take(K::L::WIDTH) {
                    if !alive.lane(i) {
                        continue;
                    }
                    let rest =
                        self.invisible_rest(K::L::vector_lane(color, i), weight.lane(i), levels);
                    if let Some(bound) = rest {
                        *lane = true;
                        let only = <Alive<K>>::from_fn(|k| k == i);
                        observer.ended(only, Ended::EarlyStop { bound });
                    }
                }
                alive = alive & !<Alive<K>>::from_fn(|i| invisible[i]);
            }
            if !alive.any() {
                break;
            }
            ray = kernel.reflected(&point);
        }
        traced
    }

    /// Whether `levels` more reflections, each adding at most
    /// `weight · max_ks^k · max_local`, leave every channel's 8-bit value
    /// where it is: the most they could add when they do not, `None` when
    /// they might. Every term is ≥ 0, so the final colour lies between
    /// `color` and `color + bound`; equal rounding at both ends settles it.
    #[inline(always)]
    fn invisible_rest(&self, color: Color, weight: f64, levels: u32) -> Option<Color> {
        let &series = self.world.tail.get(levels as usize)?;
        // A hair of margin covers the rounding of the sums themselves.
        let bound = weight * series * self.world.max_local * (1.0 + 1e-9) + DVec3::splat(1e-12);
        let high = color + bound;
        (0..3)
            .all(|c| to_8bit(color[c]) == to_8bit(high[c]))
            .then_some(bound)
    }
    /// The 8-bit colour of pixel (i, j): one ray through its centre, or the
    /// mean of `aa × aa` clamped samples on a regular grid.
    pub fn pixel(&self, i: u32, j: u32) -> [u8; 3] {
        self.with_kernel(PixelAt { i, j })
    }

    /// The rays a render of `tile` traces for one camera ray through each
    /// of `points` (image points in pixels, in the tile), reflections
    /// included: what the tile costs there, for one ray a pixel. None in
    /// a tile the render fills without tracing (nothing can be hit from
    /// it). `split`'s estimate of where the work is.
    pub fn rays_through(&self, tile: &Tile, points: &[(f64, f64)]) -> u64 {
        let culled = self.tile_candidates(tile);
        let candidates = match &culled {
            Some(list) if list.is_empty() && self.world.shapes.planes.is_empty() => return 0,
            Some(list) => Candidates::Only(list),
            None => Candidates::All,
        };
        self.with_kernel(RaysThrough { points, candidates })
    }

    /// Why pixel (i, j) has its colour: each of its rays' trees, recorded
    /// from the render's trace ([`crate::render::explain`]); `None`
    /// outside the image. All the trees at once: [`Prepared::explain_each`]
    /// hands them on one at a time. A draft's pixel is explained by the
    /// rays the draft traced for it: those of its 2×2 block's top-left
    /// pixel ([`Explanation::traced`]).
    pub fn explain(&self, i: u32, j: u32) -> Option<Explanation> {
        let mut samples = Vec::new();
        let pixel = self.explain_each(i, j, |sample| {
            samples.push(sample);
            ControlFlow::Continue(())
        })?;
        Some(Explanation {
            x: i,
            y: j,
            traced: pixel.traced,
            illumination: self.world.illumination,
            samples,
            rgb: pixel.rgb,
            rgb8: pixel.rgb8,
        })
    }

    /// [`Prepared::explain`] in bounded memory: each ray's tree in turn to
    /// `visit` (its aa × aa rays in reading order), one held at a time, so
    /// that 256 rays of 10 000 bounces never are in memory together. Then
    /// the pixel they make; `None` outside the image, or once `visit`
    /// stops (`ControlFlow::Break`).
    pub fn explain_each(
        &self,
        i: u32,
        j: u32,
        mut visit: impl FnMut(Sample) -> ControlFlow<()>,
    ) -> Option<PixelValue> {
        if i >= self.width() || j >= self.height() {
            return None;
        }
        self.with_kernel(ExplainAt {
            i,
            j,
            visit: Some(&mut visit),
        })
    }

    /// The pixel [`Prepared::explain`] explains, traced as it traces it
    /// but recording nothing: what a writer needs before the trees (the
    /// JSON's `rgb` comes before its samples). `None` outside the image.
    pub fn explained_pixel(&self, i: u32, j: u32) -> Option<PixelValue> {
        if i >= self.width() || j >= self.height() {
            return None;
        }
        self.with_kernel(ExplainAt { i, j, visit: None })
    }

    /// Rays through each pixel: 1, or aa × aa.
    pub fn samples_per_pixel(&self) -> usize {
        self.sample_count()
    }

    /// The illumination model of the prepared scene.
    pub fn illumination(&self) -> Illumination {
        self.world.illumination
    }

    /// The pixels (8-bit colours, or the values of the view's pass) of up
    /// to a packet's width of pixels into `out`: with one ray per pixel,
    /// one lane per pixel; supersampled, each pixel's samples in lanes,
    /// their clamped colours (or pass values) summed in the order of the
    /// grid.
    #[inline(always)]
    fn pixels<K: Kernel, T: Texel>(
        &self,
        kernel: &K,
        pixels: &[(u32, u32)],
        candidates: Candidates,
        rays: &mut u64,
        out: &mut [[T; 3]; MAX_LANES],
    ) {
        let width = K::L::WIDTH;
        debug_assert!(!pixels.is_empty() && pixels.len() <= width && width <= MAX_LANES);
        // 8-bit texels are the image (known at compile time: the trace
        // then keeps nothing of the passes).
        let pass = if T::UNCLAMPED { self.pass } else { Pass::Final };
        if self.aa == 1 {
            let mut points = [(0.0, 0.0); MAX_LANES];
            for (point, &(i, j)) in points.iter_mut().zip(pixels) {
                *point = (f64::from(i) + 0.5, f64::from(j) + 0.5);
            }
            let traced = self.trace(
                kernel,
                self.packet::<K>(&points[..pixels.len()]),
                candidates,
                self.world.early_stop,
                rays,
                &mut (),
            );
            // One ray: its value as it is (8-bit texels clamp themselves),
            // the terms and final of a pass in f32 (they add up there).
            let value = traced.value(pass);
            for (k, pixel) in out.iter_mut().take(pixels.len()).enumerate() {
                *pixel = T::pixel(if T::UNCLAMPED && pass.is_term_or_final() {
                    traced.value_in_f32(pass, k)
                } else {
                    K::L::vector_lane(value, k)
                });
            }
            return;
        }
        // Supersampled: a sample's own rounding says nothing about the
        // mean's, so every chain runs to its end.
        let n = f64::from(self.aa);
        let mut points = [(0.0, 0.0); MAX_LANES];
        for (pixel, &(i, j)) in out.iter_mut().zip(pixels) {
            let mut sum = DVec3::ZERO;
            for first in (0..self.sample_count()).step_by(width) {
                let count = width.min(self.sample_count() - first);
                for (k, point) in points.iter_mut().take(count).enumerate() {
                    *point = self.sample_point(i, j, first + k);
                }
                let packet = self.packet::<K>(&points[..count]);
                let traced = self.trace(kernel, packet, candidates, false, rays, &mut ());
                let value = traced.value(pass);
                for k in 0..count {
                    let v = K::L::vector_lane(value, k);
                    sum += if pass == Pass::Final { clamped(v) } else { v };
                }
            }
            *pixel = T::pixel(sum / (n * n));
        }
    }

    /// Rays per pixel: aa × aa.
    fn sample_count(&self) -> usize {
        (self.aa * self.aa) as usize
    }

    /// The image point of sample `k` of pixel (i, j): the pixel's centre
    /// with one ray per pixel, else the grid's cells in reading order.
    #[inline(always)]
    fn sample_point(&self, i: u32, j: u32, k: usize) -> (f64, f64) {
        let (aa, n) = (self.aa as usize, f64::from(self.aa));
        let (a, b) = (k % aa, k / aa);
        (
            f64::from(i) + (a as f64 + 0.5) / n,
            f64::from(j) + (b as f64 + 0.5) / n,
        )
    }

    /// A packet of camera rays through image points (at most a packet's
    /// width); lanes past the last point repeat it and stay dark.
    #[inline(always)]
    fn packet<K: Kernel>(&self, points: &[(f64, f64)]) -> (Ray<Vectors<K>>, Alive<K>) {
        let last = points.len() - 1;
        let rays = self.camera.rays(
            K::L::from_fn(|i| points[i.min(last)].0),
            K::L::from_fn(|i| points[i.min(last)].1),
        );
        (rays, <Alive<K>>::from_fn(|i| i <= last))
    }

    /// Renders one tile row-major into `out` (cleared first), three
    /// texels a pixel (RGB8, or the view's pass in f64), checking `cancel`
    /// before every packet of pixels. Returns the number of rays traced,
    /// or `None` when cancelled.
    pub fn render_tile_into<T: Texel>(
        &self,
        tile: &Tile,
        cancel: &Cancel,
        out: &mut Vec<T>,
    ) -> Option<u64> {
        debug_assert!(T::UNCLAMPED || self.pass == Pass::Final);
        self.with_kernel(TileInto { tile, cancel, out })
    }

    /// The side of the blocks one traced pixel stands for: 2 in a draft,
    /// else 1.
    fn draft_step(&self) -> u32 {
        if self.world.draft { 2 } else { 1 }
    }

    /// The pixel whose rays give pixel (i, j) its colour: itself, or in a
    /// draft the top-left of its 2×2 block, which [`Prepared::tile_into`]
    /// traces and copies to the other three.
    pub fn traced_for(&self, i: u32, j: u32) -> (u32, u32) {
        let step = self.draft_step();
        (i - i % step, j - j % step)
    }

    #[inline(always)]
    fn tile_into<K: Kernel, T: Texel>(
        &self,
        kernel: &K,
        tile: &Tile,
        cancel: &Cancel,
        out: &mut Vec<T>,
    ) -> Option<u64> {
        // Every pixel a miss until traced (what a tile that can hit
        // nothing keeps: black, no object, t = ∞).
        let [miss, ..] = T::pixel(f64::vector_lane(Traced::<f64>::dark().value(self.pass), 0));
        out.clear();
        out.resize(tile.width as usize * tile.height as usize * 3, miss);
        // Draft: one pixel in four is traced, the top-left of each 2×2
        // block of the image (even x and y); the other three copy it. A
        // tile of a region may start at an odd row or column: its first
        // pixels copy a block's corner outside it, traced all the same.
        let step = self.draft_step();
        let anchor = |v: u32| v - v % step;
        let traced_area = Tile {
            x: anchor(tile.x),
            y: anchor(tile.y),
            width: tile.width + tile.x % step,
            height: tile.height + tile.y % step,
        };
        let candidates = self.tile_candidates(&traced_area);
        let candidates = match &candidates {
            Some(list) => {
                if list.is_empty() && self.world.shapes.planes.is_empty() {
                    // Nothing can be hit from this tile: every ray misses.
                    return (!cancel.is_cancelled()).then_some(0);
                }
                Candidates::Only(list)
            }
            None => Candidates::All,
        };
        let mut rays = 0;
        let (x_end, row_bytes) = (tile.x + tile.width, tile.width as usize * 3);
        let mut traced = [[T::default(); 3]; MAX_LANES];
        let mut row: Vec<(u32, u32)> = Vec::with_capacity(tile.width as usize);
        for (dj, j) in (tile.y..tile.y + tile.height).enumerate() {
            let line = dj * row_bytes;
            if j != anchor(j) && j != tile.y {
                // A draft's odd row: the row above.
                out.copy_within(line - row_bytes..line, line);
                continue;
            }
            row.clear();
            row.extend(
                (traced_area.x..x_end)
                    .step_by(step as usize)
                    .map(|i| (i, anchor(j))),
            );
            for packet in row.chunks(K::L::WIDTH) {
                if cancel.is_cancelled() {
                    return None;
                }
                self.pixels(kernel, packet, candidates, &mut rays, &mut traced);
                for (&(a, _), rgb) in packet.iter().zip(&traced) {
                    // The traced pixel and, in a draft, the one on its
                    // right: those of them in the tile.
                    for i in (a..a + step).filter(|i| (tile.x..x_end).contains(i)) {
                        let at = line + (i - tile.x) as usize * 3;
                        out[at..at + 3].copy_from_slice(rgb);
                    }
                }
            }
        }
        Some(rays)
    }

    /// The bounded primitives whose bounding sphere reaches into the
    /// tile's frustum (the four planes through the eye and the tile's
    /// edges), or `None` when the scene has too many to cull or culling
    /// is off.
    fn tile_candidates(&self, tile: &Tile) -> Option<Vec<usize>> {
        if !self.world.shapes.cull {
            return None;
        }
        let (x0, y0) = (f64::from(tile.x), f64::from(tile.y));
        let (x1, y1) = (x0 + f64::from(tile.width), y0 + f64::from(tile.height));
        let eye = self.camera.ray(x0, y0).origin;
        let corner = |x, y| self.camera.ray(x, y).dir;
        let (a, b, c, d) = (
            corner(x0, y0),
            corner(x1, y0),
            corner(x1, y1),
            corner(x0, y1),
        );
        let centre = (a + b + c + d).normalize();
        // Side planes through the eye; the cross product of two unit corner
        // directions has length sin θ, θ the angle between them.
        let sides = [a.cross(b), b.cross(c), c.cross(d), d.cross(a)];
        let sin_min = sides
            .iter()
            .map(|n| n.length())
            .fold(f64::INFINITY, f64::min);
        if !(sin_min > 0.0 && sin_min.is_finite() && centre.is_finite()) {
            // A degenerate frustum (a camera squashed flat): no culling.
            return None;
        }
        // Inward unit normals. Their direction is only as good as the
        // corner directions' rounding (~1e-15) over sin θ: a hair of
        // relative slack per unit of distance covers that and the rounding
        // of the dot products.
        let planes = sides.map(|n| {
            let n = n / n.length();
            if n.dot(centre) < 0.0 { -n } else { n }
        });
        let relative = 1e-9 + 1e-13 / sin_min;
        if let Some(bvh) = &self.world.shapes.bvh
            && self.world.shapes.cull_spheres.is_empty()
        {
            let mut found = Vec::new();
            return bvh
                .collect_in_cone(eye, &planes, relative, TILE_CANDIDATES, &mut found)
                .then_some(found);
        }
        let inside = |(centre, radius): &(DVec3, f64)| {
            let to = *centre - eye;
            let slack = radius * (1.0 + 1e-9) + relative * to.length();
            planes.iter().all(|n| n.dot(to) >= -slack)
        };
        Some(
            self.world
                .shapes
                .cull_spheres
                .iter()
                .enumerate()
                .filter(|(_, s)| inside(s))
                .map(|(k, _)| k)
                .collect(),
        )
    }

    /// The object seen through image point (x, y) in pixels, if any: the
    /// app's pick ray.
    pub fn pick(&self, x: f64, y: f64) -> Option<usize> {
        self.nearest_hit(&self.camera.ray(x, y)).map(|h| h.object)
    }
}
