//! Which object each pixel shows: an object-id buffer, the same pick as a
//! click in the app ([`Prepared::pick`]) for every pixel, for outlining the
//! selected object.

use rayon::prelude::*;

use super::Prepared;
use crate::scene::Camera;

/// The object seen at each pixel of a `width` × `height` picture, row by
/// row: its index in the scene's object list, or `None` where the ray hits
/// nothing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjectIds {
    pub width: u32,
    pub height: u32,
    pub ids: Vec<Option<u32>>,
}

impl ObjectIds {
    /// The object at pixel (x, y), if any.
    pub fn at(&self, x: u32, y: u32) -> Option<u32> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.ids
            .get(y as usize * self.width as usize + x as usize)
            .copied()
            .flatten()
    }

    /// Whether pixel (x, y) shows `object` and touches a pixel that does
    /// not (or the picture's edge): the object's outline.
    pub fn is_outline(&self, x: u32, y: u32, object: u32) -> bool {
        if self.at(x, y) != Some(object) {
            return false;
        }
        let (w, h) = (self.width, self.height);
        x == 0
            || y == 0
            || x + 1 == w
            || y + 1 == h
            || [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
                .iter()
                .any(|&(nx, ny)| self.at(nx, ny) != Some(object))
    }
}

/// The object-id buffer of a prepared scene seen through `camera`, at
/// 1/`scale` of its size on each side (the same view; 1 is full size),
/// computed on rayon's pool.
pub fn object_ids(prepared: &Prepared, camera: &Camera, scale: u32) -> ObjectIds {
    let scale = scale.max(1);
    let mut small = camera.clone();
    small.width = camera.width.div_ceil(scale);
    small.height = camera.height.div_ceil(scale);
    let prepared = prepared.with_view(&small, 1);
    let (width, height) = (small.width, small.height);
    let ids = (0..u64::from(width) * u64::from(height))
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % u64::from(width), i / u64::from(width));
            prepared
                .pick(x as f64 + 0.5, y as f64 + 0.5)
                .and_then(|o| u32::try_from(o).ok())
        })
        .collect();
    ObjectIds { width, height, ids }
}

#[cfg(test)]
mod tests {
    use super::super::{RenderOptions, prepare};
    use super::*;
    use std::path::Path;

    #[test]
    fn each_pixel_holds_the_object_a_click_there_picks() {
        let scene = crate::scene::parse(crate::EXAMPLE_SCENE, Path::new("e.xml")).unwrap();
        let ids = object_ids(
            &prepare(&scene, &RenderOptions::default()),
            &scene.camera,
            4,
        );
        assert_eq!((ids.width, ids.height), (150, 150));
        let mut small = scene.clone();
        small.camera.width = 150;
        small.camera.height = 150;
        let prepared = prepare(&small, &RenderOptions::default());
        for (x, y) in [(0, 0), (75, 75), (40, 75), (110, 75), (149, 149)] {
            let pick = prepared.pick(f64::from(x) + 0.5, f64::from(y) + 0.5);
            assert_eq!(ids.at(x, y), pick.map(|o| o as u32), "({x}, {y})");
        }
        // The two spheres show, and the background.
        for object in [Some(0), Some(1), None] {
            assert!(ids.ids.contains(&object));
        }
        // An outline pixel touches another id; an inner one does not.
        let (x, y) = (40, 75);
        let object = ids.at(x, y).unwrap();
        assert!(!ids.is_outline(x, y, object));
        let edge = (0..150).find(|&x| ids.at(x, 75) == Some(object)).unwrap();
        assert!(ids.is_outline(edge, 75, object));
    }
}
