//! Render passes: one term of the illumination formula, or one property
//! of the camera ray's hit, for every pixel — what compositors call AOVs.
//!
//! A pass is traced by the same tile loop and the same trace as the
//! image ([`trace_tiles`] with `f64` texels instead of 8-bit ones); the
//! trace keeps the camera ray's terms apart and adds them in one order,
//! so with one ray per pixel
//!
//! ```text
//! final = ((ambient + diffuse) + specular) + reflection
//! ```
//!
//! holds bit for bit in the renderer's f64 (what `explain` shows), and
//! `final` rounded to 8 bits is the image. A pass keeps its values as an
//! EXR holds them, in f32 ([`in_f32`]): each term the nearest f32, final
//! their f32 sum in the same order — so the files add up bit for bit too —
//! and still the image's 8-bit value (a term moves an ulp or two where a
//! value a hair from a rounding boundary would cross it).
//! With N×N rays per pixel a term pass is the mean of its samples' terms
//! and `final` the mean of the clamped samples (the image's value before
//! rounding): the terms then add up to the unclamped mean only within
//! rounding. `normal`, `depth` and `object` are properties of one ray
//! through the pixel's centre whatever the anti-aliasing (the same ray
//! as a click's pick, so `object` has the selection outline's ids).

use super::{
    Cancel, Progress, RenderError, RenderOptions, RenderStats, prepare, to_8bit, trace_tiles,
};
use crate::scene::Scene;
use glam::DVec3;
use image::{Rgb32FImage, RgbImage};

/// What a render computes for each pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum Pass {
    /// The image: the sum of the four terms.
    #[default]
    Final,
    /// ka C at the camera ray's hit.
    Ambient,
    /// Σ I kd cos θ at the camera ray's hit.
    Diffuse,
    /// Σ I ks cos^m α at the camera ray's hit.
    Specular,
    /// ks I_r: everything the camera ray's reflection brings, its whole
    /// chain.
    Reflection,
    /// The world shading normal N at the hit (facing the ray): −1 to 1,
    /// shown as (N + 1) / 2.
    Normal,
    /// t, the camera ray's distance to its hit (∞ for a miss), shown
    /// normalised over the image's range: near light, far dark.
    Depth,
    /// The object hit: its number (1-based, as in the panel; 0 for none),
    /// shown as a colour of its own.
    Object,
}

impl Pass {
    /// Every pass, in menu order.
    pub const ALL: [Pass; 8] = [
        Pass::Final,
        Pass::Ambient,
        Pass::Diffuse,
        Pass::Specular,
        Pass::Reflection,
        Pass::Normal,
        Pass::Depth,
        Pass::Object,
    ];

    /// The name on the command line and in the menu.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Final => "final",
            Pass::Ambient => "ambient",
            Pass::Diffuse => "diffuse",
            Pass::Specular => "specular",
            Pass::Reflection => "reflection",
            Pass::Normal => "normal",
            Pass::Depth => "depth",
            Pass::Object => "object",
        }
    }

    /// The pass named `name` (as [`Pass::name`] spells it).
    pub fn named(name: &str) -> Option<Pass> {
        Pass::ALL.into_iter().find(|p| p.name() == name)
    }

    /// One of the four terms, or final: they add up.
    pub fn is_term_or_final(self) -> bool {
        !self.is_geometric()
    }

    /// A property of the camera ray's hit, traced with one ray through
    /// each pixel's centre whatever the anti-aliasing.
    pub fn is_geometric(self) -> bool {
        matches!(self, Pass::Normal | Pass::Depth | Pass::Object)
    }
}

/// What a tile holds per channel: an 8-bit value of the image (`u8`), or
/// a pass's value (`f64`).
pub trait Texel: Copy + Default + Send + Sync + 'static {
    /// A one-ray pixel of the final pass keeps its colour unclamped (the
    /// passes' `final`, which the terms add up to); 8-bit pixels clamp.
    const UNCLAMPED: bool;
    /// The pixel of a value: one ray's, or the mean of its samples'.
    fn pixel(value: DVec3) -> [Self; 3];
}

impl Texel for u8 {
    const UNCLAMPED: bool = false;
    #[inline(always)]
    fn pixel(value: DVec3) -> [u8; 3] {
        [to_8bit(value.x), to_8bit(value.y), to_8bit(value.z)]
    }
}

impl Texel for f64 {
    const UNCLAMPED: bool = true;
    #[inline(always)]
    fn pixel(value: DVec3) -> [f64; 3] {
        value.to_array()
    }
}

/// One pass of a whole image: three f64 values a pixel, row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct PassImage {
    pub pass: Pass,
    pub width: u32,
    pub height: u32,
    pub values: Vec<f64>,
}

impl PassImage {
    /// The value at pixel (x, y).
    pub fn at(&self, x: u32, y: u32) -> Option<DVec3> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y as usize * self.width as usize + x as usize) * 3;
        Some(DVec3::from_slice(&self.values[i..i + 3]))
    }

    /// The nearest and farthest hit (the depth pass's range), if any
    /// pixel's ray hits something.
    pub fn depth_range(&self) -> Option<(f64, f64)> {
        if self.pass != Pass::Depth {
            return None;
        }
        let (near, far) = self
            .values
            .iter()
            .step_by(3)
            .filter(|t| t.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(n, f), &t| {
                (n.min(t), f.max(t))
            });
        (near <= far).then_some((near, far))
    }

    /// The pass as an 8-bit picture: terms and `final` clamped and
    /// rounded as the image is, N as (N + 1) / 2 (misses black), depth from 1 at the
    /// nearest hit to 0.2 at the farthest (misses black), each object a
    /// colour of its own (misses black).
    pub fn to_rgb8(&self) -> RgbImage {
        let range = self.depth_range();
        let mut image = RgbImage::new(self.width, self.height);
        for (pixel, v) in image.pixels_mut().zip(self.values.chunks_exact(3)) {
            pixel.0 = shown(self.pass, DVec3::from_slice(v), range);
        }
        image
    }

    /// The pass in 32-bit floats, unclamped (what an EXR holds). One ray
    /// per pixel, the values are f32 already ([`in_f32`]); the means of
    /// supersampled pixels are rounded to the nearest f32 that keeps
    /// their 8-bit value ([`f32_keeping_level`]).
    pub fn to_rgb32f(&self) -> Rgb32FImage {
        let values = self.values.iter().map(|&v| in_exr(self.pass, v)).collect();
        Rgb32FImage::from_raw(self.width, self.height, values)
            .expect("three values a pixel, width × height pixels")
    }
}

/// A pass's value `v` as its 8-bit picture shows it ([`PassImage::to_rgb8`]);
/// `range` is the depth pass's nearest and farthest hit.
#[inline]
pub fn shown(pass: Pass, v: DVec3, range: Option<(f64, f64)>) -> [u8; 3] {
    let shown = match pass {
        // A hit's N is unit: zero is a miss, black.
        Pass::Normal if v == DVec3::ZERO => v,
        Pass::Normal => (v + DVec3::ONE) * 0.5,
        Pass::Depth => match range {
            Some((near, far)) if v.x.is_finite() => {
                let span = far - near;
                let along = if span > 0.0 { (v.x - near) / span } else { 0.0 };
                DVec3::splat(1.0 - 0.8 * along)
            }
            _ => DVec3::ZERO,
        },
        Pass::Object => object_color(v.x),
        _ => v,
    };
    u8::pixel(shown)
}

/// A pass's value in the f32 an EXR holds ([`PassImage::to_rgb32f`]).
#[inline]
pub fn in_exr(pass: Pass, v: f64) -> f32 {
    if pass.is_geometric() {
        v as f32
    } else {
        f32_keeping_level(v)
    }
}

/// One ray's four terms (ambient, diffuse, specular, reflection) and its
/// colour (their f64 sum) in f32, as the EXR passes hold them: each term
/// the nearest f32, and the colour their f32 sum in the renderer's order,
/// ((a + d) + s) + r, so that the files add up bit for bit. Where that
/// sum would round to another 8-bit level than the f64 colour (a value a
/// hair from (k + ½)/255), the largest term moves by an ulp or two until
/// it does not: final.exr rounds to the PNG everywhere. (The values come
/// back in f64, each an f32 exactly.)
pub fn in_f32(terms: [DVec3; 4], color: DVec3) -> ([DVec3; 4], DVec3) {
    let mut out = [DVec3::ZERO; 4];
    let mut sum = DVec3::ZERO;
    for c in 0..3 {
        let (t, s) = channel_in_f32(terms.map(|t| t[c]), color[c]);
        for (o, t) in out.iter_mut().zip(t) {
            o[c] = f64::from(t);
        }
        sum[c] = f64::from(s);
    }
    (out, sum)
}

fn channel_in_f32(terms: [f64; 4], color: f64) -> ([f32; 4], f32) {
    let mut t = terms.map(|x| x as f32);
    let add = |t: &[f32; 4]| ((t[0] + t[1]) + t[2]) + t[3];
    let level = to_8bit(color);
    let largest = (0..4)
        .max_by(|&i, &j| terms[i].abs().total_cmp(&terms[j].abs()))
        .unwrap_or(0);
    // A few steps at most: the f32 sum is within ulps of the f64 one.
    for _ in 0..64 {
        let sum = add(&t);
        let got = to_8bit(f64::from(sum));
        if got == level {
            return (t, sum);
        }
        t[largest] = if got > level {
            t[largest].next_down()
        } else {
            t[largest].next_up()
        };
    }
    (t, add(&t))
}

/// `v` in f32 with the same 8-bit value: the nearest f32, or where that
/// one lies across a rounding boundary (v a hair below (k + ½)/255, the
/// f32 above it), its neighbour on v's side, one ulp further. An EXR's
/// `final` then rounds to the PNG's pixels, every one of them (on the
/// golden scenes about one channel in 10⁵ needs the neighbour).
pub fn f32_keeping_level(v: f64) -> f32 {
    let nearest = v as f32;
    if to_8bit(f64::from(nearest)) == to_8bit(v) {
        return nearest;
    }
    if f64::from(nearest) > v {
        nearest.next_down()
    } else {
        nearest.next_up()
    }
}

/// The colour of object number `id` (1-based; 0: none, black): hues
/// spread by the golden angle, so neighbours in the list differ.
pub fn object_color(id: f64) -> DVec3 {
    if id.is_nan() || id < 1.0 {
        return DVec3::ZERO;
    }
    let hue = ((id - 1.0) * 0.618_033_988_749_895).fract() * 6.0;
    let sector = hue.floor();
    let f = hue - sector;
    let (v, s) = (0.95, 0.7);
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match sector as u32 {
        0 => DVec3::new(v, t, p),
        1 => DVec3::new(q, v, p),
        2 => DVec3::new(p, v, t),
        3 => DVec3::new(p, q, v),
        4 => DVec3::new(t, p, v),
        _ => DVec3::new(v, p, q),
    }
}

/// Renders one pass of `scene` with `options` (what [`super::render`]
/// does for the image), stopping once `cancel` is set (`Ok(None)`).
pub fn render_pass(
    scene: &Scene,
    options: &RenderOptions,
    pass: Pass,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<Option<(PassImage, RenderStats)>, RenderError> {
    let region = options.region_of(scene)?;
    super::in_pool(options, || {
        let prepared = prepare(scene, options);
        let prepared = if pass.is_geometric() {
            prepared.with_view(&scene.camera, 1)
        } else {
            prepared
        }
        .for_pass(pass);
        let (width, height) = (region.width(), region.height());
        let mut values = pass_buffer::<f64>(width, height, 3, pass, "its f64 values")?;
        let Some(rays) = trace_tiles(
            &prepared,
            region,
            cancel,
            progress,
            Some(&mut values),
            |_, _| {},
        ) else {
            return Ok(None);
        };
        Ok(Some((
            PassImage {
                pass,
                width,
                height,
                values,
            },
            RenderStats { rays },
        )))
    })?
}

/// A buffer of `per_pixel` values a pixel for a pass, or the error that
/// names what it would have taken.
fn pass_buffer<T: bytemuck::Zeroable>(
    width: u32,
    height: u32,
    per_pixel: usize,
    pass: Pass,
    what: &str,
) -> Result<Vec<T>, RenderError> {
    let len = (width as usize)
        .saturating_mul(height as usize)
        .saturating_mul(per_pixel);
    crate::system::resources::buffer(len).map_err(|source| RenderError::Memory {
        what: format!("the {width}×{height} {} pass ({what})", pass.name()),
        source,
    })
}

/// The form a pass is kept in while it renders, for the file it goes
/// to: the 8-bit picture an image format holds, or the f32 values an EXR
/// holds. Either is made tile by tile as the tiles finish, never the f64
/// values of the whole image ([`PassImage`]: 24 bytes a pixel).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassForm {
    /// [`PassImage::to_rgb8`]'s picture.
    Picture,
    /// [`PassImage::to_rgb32f`]'s values.
    Floats,
}

impl PassForm {
    /// Bytes a pixel that rendering `pass` in this form holds at most: 3
    /// for a picture (the image's own), 8 for the depth pass's (t in f64
    /// until the range is known, then its picture in the same bytes), 12
    /// for floats.
    pub fn bytes_per_pixel(self, pass: Pass) -> u64 {
        match (self, pass) {
            (PassForm::Floats, _) => 12,
            (PassForm::Picture, Pass::Depth) => 8,
            (PassForm::Picture, _) => 3,
        }
    }
}

/// A pass in its [`PassForm`].
#[derive(Debug, Clone, PartialEq)]
pub enum PassPixels {
    Picture(RgbImage),
    Floats(Rgb32FImage),
}

/// A pass rendered in the form of its file ([`render_pass_as`]).
#[derive(Debug, Clone, PartialEq)]
pub struct KeptPass {
    pub pass: Pass,
    pub pixels: PassPixels,
    /// The depth pass's nearest and farthest hit ([`PassImage::depth_range`]).
    pub depth_range: Option<(f64, f64)>,
}

/// [`render_pass`] kept in `form` as the tiles finish: what
/// [`PassImage::to_rgb8`] or [`PassImage::to_rgb32f`] of its image gives,
/// the same bytes, in [`PassForm::bytes_per_pixel`] bytes a pixel instead
/// of 24 and then a copy. The buffer is allocated before the first ray: a
/// size the system cannot give is an error ([`RenderError::Memory`]),
/// not an abort.
pub fn render_pass_as(
    scene: &Scene,
    options: &RenderOptions,
    pass: Pass,
    form: PassForm,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<Option<(KeptPass, RenderStats)>, RenderError> {
    let region = options.region_of(scene)?;
    super::in_pool(options, || {
        // Prepared once its buffer is had (see `render_all`).
        let view = || {
            let prepared = prepare(scene, options);
            if pass.is_geometric() {
                prepared.with_view(&scene.camera, 1)
            } else {
                prepared
            }
            .for_pass(pass)
        };
        let (width, height) = (region.width(), region.height());
        let done = match form {
            PassForm::Floats => {
                let buffer = pass_buffer::<f32>(width, height, 3, pass, "its f32 values")?;
                keep_tiles(&view(), region, cancel, progress, buffer, 3, |v, out| {
                    for c in 0..3 {
                        out[c] = in_exr(pass, v[c]);
                    }
                })
                .map(|(values, range, rays)| {
                    let image =
                        Rgb32FImage::from_raw(width, height, values).expect("three values a pixel");
                    (PassPixels::Floats(image), range, rays)
                })
            }
            PassForm::Picture if pass == Pass::Depth => {
                // t in f64, little-endian, 8 bytes a pixel: the range is
                // known only at the end.
                let buffer = pass_buffer::<u8>(width, height, 8, pass, "t in f64")?;
                keep_tiles(&view(), region, cancel, progress, buffer, 8, |v, out| {
                    out.copy_from_slice(&v.x.to_le_bytes());
                })
                .map(|(mut bytes, range, rays)| {
                    // Each pixel's 3 bytes where its t began, in order: a
                    // pixel's picture never reaches a t not yet read
                    // (3k + 3 ≤ 8k for k ≥ 1, and pixel 0 reads first).
                    let pixels = bytes.len() / 8;
                    for k in 0..pixels {
                        let mut t = [0; 8];
                        t.copy_from_slice(&bytes[8 * k..8 * k + 8]);
                        let t = f64::from_le_bytes(t);
                        let rgb = shown(pass, DVec3::splat(t), range);
                        bytes[3 * k..3 * k + 3].copy_from_slice(&rgb);
                    }
                    bytes.truncate(3 * pixels);
                    bytes.shrink_to_fit();
                    let image = RgbImage::from_raw(width, height, bytes).expect("3 bytes a pixel");
                    (PassPixels::Picture(image), range, rays)
                })
            }
            PassForm::Picture => {
                let buffer = pass_buffer::<u8>(width, height, 3, pass, "its 8-bit picture")?;
                keep_tiles(&view(), region, cancel, progress, buffer, 3, |v, out| {
                    out.copy_from_slice(&shown(pass, v, None));
                })
                .map(|(bytes, range, rays)| {
                    let image = RgbImage::from_raw(width, height, bytes).expect("3 bytes a pixel");
                    (PassPixels::Picture(image), range, rays)
                })
            }
        };
        Ok(done.map(|(pixels, depth_range, rays)| {
            (
                KeptPass {
                    pass,
                    pixels,
                    depth_range: depth_range.filter(|_| pass == Pass::Depth),
                },
                RenderStats { rays },
            )
        }))
    })?
}

/// What [`keep_tiles`] kept: the buffer, the depth range, the rays traced.
type Kept<U> = (Vec<U>, Option<(f64, f64)>, u64);

/// Traces `region` of the prepared pass ([`trace_tiles`]) and keeps each
/// finished tile's values in `buffer`, `per_pixel` elements a pixel
/// written by `keep`, under a lock taken once a tile; also the nearest
/// and farthest finite first channel (the depth pass's range). `None`
/// once `cancel` is set.
fn keep_tiles<U: Copy + Default + Send>(
    prepared: &super::Prepared,
    region: crate::render::region::Region,
    cancel: &Cancel,
    progress: &Progress,
    mut buffer: Vec<U>,
    per_pixel: usize,
    keep: impl Fn(DVec3, &mut [U]) + Sync,
) -> Option<Kept<U>> {
    let row = region.width() as usize * per_pixel;
    let range = (f64::INFINITY, f64::NEG_INFINITY);
    let shared = std::sync::Mutex::new((&mut buffer[..], range));
    let rays = trace_tiles::<f64>(prepared, region, cancel, progress, None, |tile, values| {
        let tile_row = tile.width as usize * per_pixel;
        let mut kept = vec![U::default(); tile_row * tile.height as usize];
        let (mut near, mut far) = range;
        for (v, out) in values.chunks_exact(3).zip(kept.chunks_exact_mut(per_pixel)) {
            let v = DVec3::from_slice(v);
            if v.x.is_finite() {
                (near, far) = (near.min(v.x), far.max(v.x));
            }
            keep(v, out);
        }
        let mut shared = shared
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let (image, (n, f)) = &mut *shared;
        (*n, *f) = (n.min(near), f.max(far));
        for (r, src) in kept.chunks_exact(tile_row).enumerate() {
            let y = (tile.y - region.y0) as usize + r;
            let start = y * row + (tile.x - region.x0) as usize * per_pixel;
            image[start..start + tile_row].copy_from_slice(src);
        }
    })?;
    let (_, (near, far)) = shared
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    Some((buffer, (near <= far).then_some((near, far)), rays))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A colour a hair below 121.5/255 (met on coloured-lights): its
    /// nearest f32 rounds to 122, the f64 to 121.
    const NEAR_BOUNDARY: f64 = 4.764_705_779_513_642_7e-1;

    #[test]
    fn f32_terms_add_up_and_keep_the_level() {
        assert_eq!(to_8bit(NEAR_BOUNDARY), 121);
        assert_eq!(to_8bit(f64::from(NEAR_BOUNDARY as f32)), 122);
        let terms = [0.1, NEAR_BOUNDARY - 0.1 - 0.05, 0.05, 0.0].map(DVec3::splat);
        let color = ((terms[0] + terms[1]) + terms[2]) + terms[3];
        let (t, sum) = in_f32(terms, color);
        for c in 0..3 {
            let t32 = t.map(|t| t[c] as f32);
            assert_eq!(((t32[0] + t32[1]) + t32[2]) + t32[3], sum[c] as f32);
            assert_eq!(to_8bit(sum[c]), to_8bit(color[c]));
            // Each term within two ulps of its nearest f32.
            for (k, t) in t32.iter().enumerate() {
                let nearest = terms[k][c] as f32;
                assert!((t.to_bits() as i64 - nearest.to_bits() as i64).abs() <= 2);
            }
        }
        // All of it in one term: that term moves an ulp, below.
        let alone = [NEAR_BOUNDARY, 0.0, 0.0, 0.0].map(DVec3::splat);
        let (t, sum) = in_f32(alone, DVec3::splat(NEAR_BOUNDARY));
        assert_eq!(t[0].x as f32, (NEAR_BOUNDARY as f32).next_down());
        assert_eq!((t[0].x, to_8bit(sum.x)), (sum.x, 121));
        assert_eq!(
            f32_keeping_level(NEAR_BOUNDARY),
            (NEAR_BOUNDARY as f32).next_down()
        );
        assert_eq!(f32_keeping_level(0.25), 0.25);
    }
}
