//! The preview's picture on the GPU: one texture kept in step with the
//! [`Preview`](crate::session::preview::Preview) by uploading only what changed.
//!
//! The worker's tiles are recorded as [`Dirty`] regions and only those are
//! uploaded. When the whole picture changes (a new size, or a coarse pass
//! written out at full size) it goes up in bands of rows over several
//! frames, at most [`BAND_PIXELS`] a frame, so that a 4000×4000 picture
//! (64 MB as texels) never holds a frame up; until the last band is up the
//! texture is not [`complete`](PictureTexture::complete) and the app keeps
//! showing the coarse picture it had.
//!
//! A picture shown smaller than 1:1 is also kept reduced: averaged over
//! blocks of `factor × factor` pixels (a power of two, the largest that
//! keeps the reduced picture at least as large as it is shown), and that
//! is the texture painted. Sampling a 2880×2160 texture for a picture
//! shown at 850×640 reads a new cache line for every screen pixel: with
//! Mesa's software renderer (Xvfb, remote desktops) that cost 12 ms of
//! CPU a frame, a sixth of a core at 20 frames a second taken from the
//! render. The averaged picture is also the truer one (nearest sampling
//! drops most pixels).

use crate::session::preview::{Dirty, Region};
use egui::{Color32, ColorImage, Pos2, Rect, TextureHandle, TextureId, TextureOptions};
use image::RgbImage;

/// Pixels converted and uploaded per frame while the whole picture goes up
/// band by band: a few milliseconds of work on the development machine.
pub const BAND_PIXELS: usize = 1 << 20;

/// All of a texture, as texture coordinates.
pub const WHOLE: Rect = Rect {
    min: Pos2::ZERO,
    max: Pos2::new(1.0, 1.0),
};

/// The texture of the picture: at full size, and reduced while it is
/// shown smaller.
pub struct PictureTexture {
    full: Level,
    /// The picture averaged over blocks, while it is shown at most half
    /// its size.
    reduced: Option<Level>,
}

impl Default for PictureTexture {
    fn default() -> Self {
        PictureTexture {
            full: Level::new(1),
            reduced: None,
        }
    }
}

/// One texture of the picture, `factor` image pixels a side to a texel.
struct Level {
    handle: Option<TextureHandle>,
    factor: u32,
    /// The size of the image it holds.
    image_size: (u32, u32),
    /// First image row of the next band to upload, while the whole picture
    /// is going up.
    next_band: Option<u32>,
}

impl PictureTexture {
    /// The full-size texture, once one exists.
    pub fn id(&self) -> Option<TextureId> {
        self.full.handle.as_ref().map(TextureHandle::id)
    }

    /// The texture to paint and the part of it that is the picture: the
    /// reduced one once it is wholly up, else the full-size one.
    pub fn shown(&self) -> Option<(TextureId, Rect)> {
        match &self.reduced {
            Some(reduced) if reduced.complete() => reduced.handle.as_ref().map(|t| {
                // The last column and row of blocks may be partial: the
                // picture ends inside them.
                let [tw, th] = t.size();
                let (w, h) = reduced.image_size;
                let uv = Pos2::new(
                    w as f32 / (tw as f32 * reduced.factor as f32),
                    h as f32 / (th as f32 * reduced.factor as f32),
                );
                (t.id(), Rect::from_min_max(Pos2::ZERO, uv))
            }),
            _ => self.id().map(|id| (id, WHOLE)),
        }
    }

    /// Whether every pixel of the picture has been uploaded at full size.
    pub fn complete(&self) -> bool {
        self.full.complete()
    }

    /// Uploads what changed in `image` and, while the whole picture is
    /// going up, its next band; `zoom` is screen pixels per image pixel,
    /// which picks the reduced texture's factor. `cleared`: the image is a
    /// new black one (but for `dirty`), and the texture a new black one
    /// with it. A texture of another size is otherwise replaced by a black
    /// one filled band by band.
    pub fn update(
        &mut self,
        ctx: &egui::Context,
        image: &RgbImage,
        cleared: bool,
        dirty: Dirty,
        zoom: f32,
    ) {
        let factor = reduction(zoom);
        if factor == 1 {
            self.reduced = None;
        } else {
            // Built band by band when the factor changes; the full-size
            // texture is painted meanwhile.
            let reduced = match &mut self.reduced {
                Some(reduced) if reduced.factor == factor => reduced,
                _ => self.reduced.insert(Level::new(factor)),
            };
            reduced.update(ctx, image, cleared, &dirty);
        }
        self.full.update(ctx, image, cleared, &dirty);
    }
}

/// The reduced texture's factor for a picture shown at `zoom` screen
/// pixels per image pixel: the largest power of two whose blocks are at
/// most a screen pixel (1: not reduced).
pub fn reduction(zoom: f32) -> u32 {
    let mut factor = 1u32;
    while factor < 64 && zoom * (factor * 2) as f32 <= 1.0 {
        factor *= 2;
    }
    factor
}

impl Level {
    /// A level with no texture yet.
    fn new(factor: u32) -> Level {
        Level {
            handle: None,
            factor,
            image_size: (0, 0),
            next_band: None,
        }
    }

    fn complete(&self) -> bool {
        self.handle.is_some() && self.next_band.is_none()
    }

    /// The texture's size for an image of `w × h`.
    fn texels(&self, w: u32, h: u32) -> [usize; 2] {
        [
            w.div_ceil(self.factor) as usize,
            h.div_ceil(self.factor) as usize,
        ]
    }

    fn update(&mut self, ctx: &egui::Context, image: &RgbImage, cleared: bool, dirty: &Dirty) {
        let (w, h) = image.dimensions();
        self.image_size = (w, h);
        let size = self.texels(w, h);
        let factor = self.factor;
        let handle = match &mut self.handle {
            Some(t) if t.size() == size && !cleared => t,
            _ => {
                self.next_band = (!cleared).then_some(0);
                let blank = ColorImage::filled(size, Color32::BLACK);
                self.handle
                    .insert(ctx.load_texture("render", blank, TextureOptions::NEAREST))
            }
        };
        match dirty {
            Dirty::Nothing => {}
            Dirty::Whole => self.next_band = Some(0),
            Dirty::Regions(regions) => {
                for r in regions {
                    upload(handle, image, *r, factor);
                }
            }
        }
        if let Some(y) = self.next_band {
            // BAND_PIXELS of the image (a reduced band holds fewer texels
            // but averages as many pixels), in whole blocks.
            let rows = (BAND_PIXELS / (w as usize).max(1)).max(1) as u32;
            let rows = rows.div_ceil(factor) * factor;
            let height = rows.min(h - y.min(h));
            upload(
                handle,
                image,
                Region {
                    x: 0,
                    y,
                    width: w,
                    height,
                },
                factor,
            );
            self.next_band = (y + height < h).then_some(y + height);
            // The next band goes up in the next frame.
            ctx.request_repaint();
        }
    }
}

/// Uploads region `r` of `image` into a texture of `factor` image pixels
/// a side to a texel.
fn upload(texture: &mut TextureHandle, image: &RgbImage, r: Region, factor: u32) {
    if r.width == 0 || r.height == 0 {
        return;
    }
    let (origin, size, rgb) = reduce(image, r, factor);
    if rgb.len() != size[0] * size[1] * 3 {
        return;
    }
    let part = ColorImage::from_rgb(size, &rgb);
    texture.set_partial(origin, part, TextureOptions::NEAREST);
}

/// The texels of a texture of `factor` image pixels a side that region
/// `r` of `image` touches: their first texel, their size and their RGB
/// bytes, each the mean of its block's pixels (the blocks of the last
/// column and row hold what of the image is left).
fn reduce(image: &RgbImage, r: Region, factor: u32) -> ([usize; 2], [usize; 2], Vec<u8>) {
    let (w, h) = image.dimensions();
    let (x0, y0) = (r.x / factor, r.y / factor);
    let x1 = (r.x + r.width).min(w).div_ceil(factor);
    let y1 = (r.y + r.height).min(h).div_ceil(factor);
    let size = [
        (x1.saturating_sub(x0)) as usize,
        (y1.saturating_sub(y0)) as usize,
    ];
    let raw = image.as_raw();
    let row = w as usize * 3;
    let mut rgb = Vec::with_capacity(size[0] * size[1] * 3);
    if factor == 1 {
        for line in y0..y1 {
            let start = line as usize * row + x0 as usize * 3;
            rgb.extend_from_slice(raw.get(start..start + size[0] * 3).unwrap_or_default());
        }
        return ([x0 as usize, y0 as usize], size, rgb);
    }
    let mut sums = vec![0u32; size[0] * 3];
    for ty in y0..y1 {
        sums.fill(0);
        let (top, bottom) = (ty * factor, ((ty + 1) * factor).min(h));
        let (left, right) = (x0 * factor, (x1 * factor).min(w));
        for line in top..bottom {
            let start = line as usize * row;
            let pixels = raw.get(start + left as usize * 3..start + right as usize * 3);
            for (i, p) in pixels.unwrap_or_default().chunks_exact(3).enumerate() {
                let texel = i / factor as usize;
                for c in 0..3 {
                    sums[texel * 3 + c] += u32::from(p[c]);
                }
            }
        }
        for tx in 0..size[0] as u32 {
            let x = x0 + tx;
            let across = ((x + 1) * factor).min(w) - x * factor;
            let count = across * (bottom - top);
            for c in 0..3 {
                let sum = sums[tx as usize * 3 + c];
                // Rounded to nearest.
                rgb.push(((sum + count / 2) / count.max(1)) as u8);
            }
        }
    }
    ([x0 as usize, y0 as usize], size, rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region(x: u32, y: u32, width: u32, height: u32) -> Region {
        Region {
            x,
            y,
            width,
            height,
        }
    }

    fn tile(x: u32, y: u32) -> Region {
        region(x, y, 32, 32)
    }

    #[test]
    fn many_tiles_join_their_neighbours_not_the_whole_image() {
        // A frame's worth of tiles of two passes, far apart: the end of
        // one at the bottom of a 4000² image, the start of the next at
        // the top.
        let mut dirty = Dirty::Nothing;
        let mut painted = 0;
        for k in 0..100 {
            dirty.add(tile(k * 32, 3968));
            dirty.add(tile(k * 32, 0));
            painted += 2 * 32 * 32;
        }
        let Dirty::Regions(list) = &dirty else {
            panic!("regions")
        };
        assert_eq!(list.len(), 64);
        // Not one rectangle from the top to the bottom: about what was
        // painted.
        assert!(dirty.area(4000 * 4000) <= 2 * painted, "{}", dirty.area(0));
    }

    #[test]
    fn a_whole_picture_goes_up_in_bands() {
        let ctx = egui::Context::default();
        let mut texture = PictureTexture::default();
        // 1024 wide: 1024 rows a band, three bands for 2500 rows.
        let image = RgbImage::new(1024, 2500);
        let mut frames = 0;
        texture.update(&ctx, &image, false, Dirty::Whole, 1.0);
        frames += 1;
        assert!(!texture.complete(), "one band is not the whole picture");
        while !texture.complete() {
            texture.update(&ctx, &image, false, Dirty::Nothing, 1.0);
            frames += 1;
        }
        assert_eq!(frames, 3);
        // A small picture goes up at once.
        texture.update(&ctx, &RgbImage::new(100, 60), false, Dirty::Whole, 1.0);
        assert!(texture.complete());
        // A new black picture needs no upload at all.
        texture.update(&ctx, &RgbImage::new(4000, 4000), true, Dirty::Nothing, 1.0);
        assert!(texture.complete());
    }

    #[test]
    fn the_reduction_is_the_largest_power_of_two_within_a_screen_pixel() {
        assert_eq!(reduction(2.0), 1);
        assert_eq!(reduction(1.0), 1);
        assert_eq!(reduction(0.9), 1);
        assert_eq!(reduction(0.5), 2);
        assert_eq!(reduction(0.3), 2);
        assert_eq!(reduction(0.25), 4);
        assert_eq!(reduction(0.2), 4);
        assert_eq!(reduction(1e-6), 64);
    }

    #[test]
    fn a_reduced_texel_is_the_mean_of_its_block_and_edge_blocks_are_partial() {
        // 5 × 3 pixels by blocks of 2: texels of 2×2, 2×1, 1×2 and 1×1
        // pixels.
        let image = RgbImage::from_fn(5, 3, |x, y| image::Rgb([(10 * x + y) as u8, 200, x as u8]));
        let all = region(0, 0, 5, 3);
        let (origin, size, rgb) = reduce(&image, all, 2);
        assert_eq!((origin, size), ([0, 0], [3, 2]));
        let texel = |tx: usize, ty: usize| &rgb[(ty * 3 + tx) * 3..(ty * 3 + tx) * 3 + 3];
        // Pixels (0..2, 0..2): red 0, 1, 10, 11; mean 5.5, rounded to 6.
        assert_eq!(texel(0, 0), [6, 200, 1]);
        // (4, 0..2): red 40, 41.
        assert_eq!(texel(2, 0), [41, 200, 4]);
        // (2..4, 2): red 22, 32.
        assert_eq!(texel(1, 1), [27, 200, 3]);
        // (4, 2) alone.
        assert_eq!(texel(2, 1), [42, 200, 4]);
        // A region inside one block updates that block, read whole.
        let one = region(3, 1, 1, 1);
        let (origin, size, part) = reduce(&image, one, 2);
        assert_eq!((origin, size), ([1, 0], [1, 1]));
        assert_eq!(part, rgb[3..6]);
        // Factor 1 is the region itself.
        let (origin, size, raw) = reduce(&image, all, 1);
        assert_eq!((origin, size), ([0, 0], [5, 3]));
        assert_eq!(raw, image.as_raw().as_slice());
    }

    #[test]
    fn a_picture_shown_small_paints_its_reduced_texture_once_it_is_up() {
        let ctx = egui::Context::default();
        let mut texture = PictureTexture::default();
        let image = RgbImage::new(2880, 2160);
        // Shown at 1:1 while the full-size picture goes up.
        texture.update(&ctx, &image, false, Dirty::Whole, 1.0);
        while !texture.complete() {
            texture.update(&ctx, &image, false, Dirty::Nothing, 1.0);
        }
        let full = texture.id().unwrap();
        assert_eq!(texture.shown().unwrap().0, full);
        // At 0.3: blocks of 2, 1440 × 1080 texels, built band by band
        // (the full-size texture painted meanwhile).
        texture.update(&ctx, &image, false, Dirty::Nothing, 0.3);
        assert_eq!(texture.shown().unwrap().0, full, "not up yet");
        let mut frames = 1;
        while texture.shown().unwrap().0 == full {
            texture.update(&ctx, &image, false, Dirty::Nothing, 0.3);
            frames += 1;
        }
        assert_eq!(frames, 6, "BAND_PIXELS of the image a frame");
        let (id, uv) = texture.shown().unwrap();
        let size = ctx.tex_manager().read().meta(id).unwrap().size;
        assert_eq!(size, [1440, 1080]);
        assert_eq!(uv.max, Pos2::new(1.0, 1.0));
        // 999 × 999 at 0.2: blocks of 4, 250 texels of which the last
        // holds 3 pixels: the picture ends at 999/1000 of the texture.
        let odd = RgbImage::new(999, 999);
        texture.update(&ctx, &odd, false, Dirty::Whole, 0.2);
        let (_, uv) = texture.shown().unwrap();
        assert_eq!(
            ctx.tex_manager()
                .read()
                .meta(texture.shown().unwrap().0)
                .unwrap()
                .size,
            [250, 250]
        );
        assert_eq!(uv.max, Pos2::new(0.999, 0.999));
        // Back to 1:1: the full-size texture alone.
        texture.update(&ctx, &odd, false, Dirty::Nothing, 1.0);
        assert_eq!(texture.shown().unwrap().0, texture.id().unwrap());
    }
}
