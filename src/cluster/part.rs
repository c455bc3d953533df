//! A part of a render: the PNG `--region` writes records where it belongs
//! (its region, the full image's size) and what it is a part of (a
//! fingerprint of the scene and the render options, and the version of
//! the renderer), in one tEXt chunk. `assemble` reads it back to check
//! that parts fit together before it puts them together.
//!
//! The record is one line of `key=value` fields:
//!
//! ```text
//! region=0,0,400,300 image=800x600 render=5f0e3c2a91b7d408 version=0.1.0
//! ```

use crate::render::RenderOptions;
use crate::render::region::{Region, RegionError};
use crate::scene::Scene;
use std::fmt::{self, Write};

/// The tEXt chunk's keyword.
pub const KEYWORD: &str = "RayOfLight part";

/// Where a part belongs and what it is a part of.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Part {
    /// The pixels of the full image it holds.
    pub region: Region,
    /// The full image's width and height.
    pub image: (u32, u32),
    /// [`fingerprint`] of the scene and options it was rendered with.
    pub render: u64,
    /// The renderer's version (`CARGO_PKG_VERSION`).
    pub version: String,
}

/// Why a part's record cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PartError {
    #[error("its part record has no {0} field")]
    Missing(&'static str),
    #[error("its part record's {field} field {value:?} is not {expected}")]
    Field {
        field: &'static str,
        value: String,
        expected: &'static str,
    },
    #[error("its part record's region: {0}")]
    Region(RegionError),
}

impl Part {
    /// The part of `scene` rendered with `options` over `region`.
    pub fn new(scene: &Scene, options: &RenderOptions, region: Region) -> Part {
        Part {
            region,
            image: (scene.camera.width, scene.camera.height),
            render: fingerprint(scene, options),
            version: env!("CARGO_PKG_VERSION").to_owned(),
        }
    }

    /// Reads a record written by [`Part`]'s `Display`. Unknown fields are
    /// ignored (a later version may add some).
    pub fn parse(text: &str) -> Result<Part, PartError> {
        let field = |name: &'static str| {
            text.split_whitespace()
                .find_map(|f| f.strip_prefix(name)?.strip_prefix('='))
                .ok_or(PartError::Missing(name))
        };
        let bad = |field: &'static str, value: &str, expected: &'static str| PartError::Field {
            field,
            value: value.to_owned(),
            expected,
        };
        let region = Region::parse(field("region")?).map_err(PartError::Region)?;
        let image = field("image")?;
        let size = image
            .split_once('x')
            .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
            .ok_or_else(|| bad("image", image, "WIDTHxHEIGHT"))?;
        let render = field("render")?;
        let fingerprint = u64::from_str_radix(render, 16)
            .ok()
            .filter(|_| render.len() == 16)
            .ok_or_else(|| bad("render", render, "16 hexadecimal digits"))?;
        Ok(Part {
            region,
            image: size,
            render: fingerprint,
            version: field("version")?.to_owned(),
        })
    }
}

impl fmt::Display for Part {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (width, height) = self.image;
        write!(
            f,
            "region={} image={width}x{height} render={:016x} version={}",
            self.region, self.render, self.version
        )
    }
}

/// A fingerprint of what decides a render's pixels: the scene (every
/// value, as loaded and edited: two files that differ only in comments or
/// layout have one) and the options resolved for it, but not the thread
/// count or the region. 64-bit FNV-1a of their `Debug` text, streamed
/// (a million-object scene is never one string).
pub fn fingerprint(scene: &Scene, options: &RenderOptions) -> u64 {
    let options = RenderOptions {
        threads: None,
        region: None,
        ..options.clone()
    };
    let mut hash = Fnv1a(0xcbf2_9ce4_8422_2325);
    // Writing into the hash cannot fail.
    let _ = write!(hash, "{scene:?}\n{options:?}");
    hash.0
}

/// 64-bit FNV-1a over the bytes written.
struct Fnv1a(u64);

impl Write for Fnv1a {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        for byte in s.bytes() {
            self.0 = (self.0 ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
        Ok(())
    }
}

/// Writes a part of a render (`--region`) as a PNG whose record (a tEXt
/// chunk under [`KEYWORD`]) says where it belongs.
pub fn save(
    image: &image::RgbImage,
    part: &Part,
    path: &std::path::Path,
) -> Result<(), crate::output::OutputError> {
    crate::output::save_png(image, &[(KEYWORD, &part.to_string())], path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn example() -> Scene {
        crate::scene::parse(crate::EXAMPLE_SCENE, Path::new("e.xml")).expect("the example loads")
    }

    #[test]
    fn a_record_reads_back_as_written() {
        let scene = example();
        let region = Region::new(10, 20, 30, 40).unwrap();
        let part = Part::new(&scene, &RenderOptions::default(), region);
        let text = part.to_string();
        assert!(
            text.starts_with("region=10,20,30,40 image=600x600 render="),
            "{text}"
        );
        assert_eq!(Part::parse(&text), Ok(part.clone()));
        assert_eq!(Part::parse(&format!("extra=1 {text}")), Ok(part));
        assert_eq!(
            Part::parse("region=0,0,1,1 image=2x2 version=1"),
            Err(PartError::Missing("render"))
        );
        assert!(
            Part::parse("region=0,0,1,1 image=2by2 render=0000000000000001 version=1").is_err()
        );
        assert!(Part::parse("region=0,0,1,1 image=2x2 render=1 version=1").is_err());
    }

    #[test]
    fn the_fingerprint_follows_what_decides_the_pixels() {
        let scene = example();
        let options = RenderOptions::default();
        let base = fingerprint(&scene, &options);
        // Text the loader keeps nothing of: the same fingerprint.
        let spaced = crate::EXAMPLE_SCENE.replace("<scene>", "<!-- a comment -->\n<scene >");
        let respaced = crate::scene::parse(&spaced, Path::new("other/e.xml")).unwrap();
        assert_eq!(fingerprint(&respaced, &options), base);
        // Threads and region do not change a pixel.
        let elsewhere = RenderOptions {
            threads: Some(3),
            region: Some(Region::new(0, 0, 5, 5).unwrap()),
            ..options.clone()
        };
        assert_eq!(fingerprint(&scene, &elsewhere), base);
        // A value, the size, the anti-aliasing do.
        let mut moved = scene.clone();
        moved.camera.eye_distance += 1e-12;
        assert_ne!(fingerprint(&moved, &options), base);
        let mut wider = scene.clone();
        wider.camera.width += 1;
        assert_ne!(fingerprint(&wider, &options), base);
        let aa = RenderOptions { aa: 2, ..options };
        assert_ne!(fingerprint(&scene, &aa), base);
    }
}
