//! The preview's picture on the GPU: one texture kept in step with the
//! [`Preview`](super::preview::Preview) by uploading only what changed.
//!
//! The worker's tiles are recorded as [`Dirty`] regions and only those are
//! uploaded. When the whole picture changes (a new size, or a coarse pass
//! written out at full size) it goes up in bands of rows over several
//! frames, at most [`BAND_PIXELS`] a frame, so that a 4000×4000 picture
//! (64 MB as texels) never holds a frame up; until the last band is up the
//! texture is not [`complete`](PictureTexture::complete) and the app keeps
//! showing the coarse picture it had.

use egui::{Color32, ColorImage, TextureHandle, TextureId, TextureOptions};
use image::RgbImage;

/// A rectangle of the image, in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Region {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// What of the image changed since the texture was last uploaded.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Dirty {
    #[default]
    Nothing,
    /// These tiles: only they are uploaded (a 4000×4000 image is 48 MB; a
    /// tile is 3 KB to 50 KB).
    Regions(Vec<Region>),
    /// Everything (a new size, or a coarse picture written at full size).
    Whole,
}

impl Region {
    pub fn area(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// The smallest region holding both.
    fn union(self, other: Region) -> Region {
        let x = self.x.min(other.x);
        let y = self.y.min(other.y);
        let right = (self.x + self.width).max(other.x + other.width);
        let bottom = (self.y + self.height).max(other.y + other.height);
        Region {
            x,
            y,
            width: right - x,
            height: bottom - y,
        }
    }
}

impl Dirty {
    /// Past this many regions in one frame, a new one joins the region it
    /// grows least (tiles come in bands: neighbours join into a band, and
    /// a band at the top never joins one at the bottom into the whole
    /// image).
    const MAX_REGIONS: usize = 64;

    pub fn add(&mut self, region: Region) {
        if region.width == 0 || region.height == 0 {
            return;
        }
        match self {
            Dirty::Whole => {}
            Dirty::Nothing => *self = Dirty::Regions(vec![region]),
            Dirty::Regions(list) if list.len() >= Dirty::MAX_REGIONS => {
                let growth = |r: &Region| r.union(region).area() - r.area();
                if let Some(nearest) = list.iter_mut().min_by_key(|r| growth(r)) {
                    *nearest = nearest.union(region);
                }
            }
            Dirty::Regions(list) => list.push(region),
        }
    }

    /// Pixels to upload.
    pub fn area(&self, whole: u64) -> u64 {
        match self {
            Dirty::Nothing => 0,
            Dirty::Regions(list) => list.iter().map(Region::area).sum(),
            Dirty::Whole => whole,
        }
    }
}

/// Pixels converted and uploaded per frame while the whole picture goes up
/// band by band: a few milliseconds of work on the development machine.
pub const BAND_PIXELS: usize = 1 << 20;

/// The texture of the full-size picture.
#[derive(Default)]
pub struct PictureTexture {
    handle: Option<TextureHandle>,
    /// First row of the next band to upload, while the whole picture is
    /// going up.
    next_band: Option<u32>,
}

impl PictureTexture {
    /// The texture to paint, once one exists.
    pub fn id(&self) -> Option<TextureId> {
        self.handle.as_ref().map(TextureHandle::id)
    }

    /// Whether every pixel of the picture has been uploaded.
    pub fn complete(&self) -> bool {
        self.handle.is_some() && self.next_band.is_none()
    }

    /// Uploads what changed in `image` and, while the whole picture is
    /// going up, its next band. `cleared`: the image is a new black one
    /// (but for `dirty`), and the texture a new black one with it. A
    /// texture of another size is otherwise replaced by a black one filled
    /// band by band.
    pub fn update(&mut self, ctx: &egui::Context, image: &RgbImage, cleared: bool, dirty: Dirty) {
        let (w, h) = image.dimensions();
        let size = [w as usize, h as usize];
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
                    upload(handle, image, r);
                }
            }
        }
        if let Some(y) = self.next_band {
            let rows = (BAND_PIXELS / size[0].max(1)).max(1) as u32;
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
            );
            self.next_band = (y + height < h).then_some(y + height);
            // The next band goes up in the next frame.
            ctx.request_repaint();
        }
    }
}

/// Uploads one region of `image` into the texture.
fn upload(texture: &mut TextureHandle, image: &RgbImage, r: Region) {
    if r.width == 0 || r.height == 0 {
        return;
    }
    let raw = image.as_raw();
    let row = image.width() as usize * 3;
    let (x, y) = (r.x as usize, r.y as usize);
    let (w, h) = (r.width as usize, r.height as usize);
    let mut rgb = Vec::with_capacity(w * h * 3);
    for line in y..y + h {
        let start = line * row + x * 3;
        rgb.extend_from_slice(raw.get(start..start + w * 3).unwrap_or_default());
    }
    if rgb.len() != w * h * 3 {
        return;
    }
    let part = ColorImage::from_rgb([w, h], &rgb);
    texture.set_partial([x, y], part, TextureOptions::NEAREST);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(x: u32, y: u32) -> Region {
        Region {
            x,
            y,
            width: 32,
            height: 32,
        }
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
        texture.update(&ctx, &image, false, Dirty::Whole);
        frames += 1;
        assert!(!texture.complete(), "one band is not the whole picture");
        while !texture.complete() {
            texture.update(&ctx, &image, false, Dirty::Nothing);
            frames += 1;
        }
        assert_eq!(frames, 3);
        // A small picture goes up at once.
        texture.update(&ctx, &RgbImage::new(100, 60), false, Dirty::Whole);
        assert!(texture.complete());
        // A new black picture needs no upload at all.
        texture.update(&ctx, &RgbImage::new(4000, 4000), true, Dirty::Nothing);
        assert!(texture.complete());
    }
}
