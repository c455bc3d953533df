//! A progressive render, as the app shows one: the scene prepared once
//! (or the last render's preparation taken again when only the camera or
//! the anti-aliasing changed, and its geometry when only colours,
//! materials, lights or the model did, refitted when a few objects moved,
//! see [`LastPrepared`]), then traced coarse to
//! fine — 1/8, 1/4, then full size for a large image ([`passes`]) — each
//! pass through the one tile loop ([`trace_tiles`]) on the pool it is
//! called in, each finished tile handed on at once.
//!
//! [`crate::render::measure::progressive_timed`] times it (the one way time is
//! measured); the app's render worker runs that, and so does the bench's
//! "app ms" column, through the worker. The full-size pass is the
//! command line's image, pixel for pixel.

use super::{Cancel, Prepared, Progress, RenderError, RenderOptions, Tile, prepare, trace_tiles};
use crate::scene::Scene;
use std::sync::{Arc, Mutex};

/// Below this many pixels the image is rendered in one full-resolution pass.
const SINGLE_PASS_PIXELS: u64 = 256 * 256;

/// The passes for an image, as 1/scale of each side, coarsest first: full
/// resolution only when small, otherwise 1/8, 1/4 and full. Both previews
/// are coarse enough for the app to show at their own size: a 1/2 pass
/// painted at full size uploaded four screen pixels per pixel traced and
/// held a 4000×4000 render's window to 20 frames a second while it ran.
pub fn passes(width: u32, height: u32) -> Vec<u32> {
    if u64::from(width) * u64::from(height) <= SINGLE_PASS_PIXELS {
        vec![1]
    } else {
        vec![8, 4, 1]
    }
}

/// The scene prepared last, the options it was prepared with, and the
/// prepared scene. The next render reuses it when only the camera or the
/// anti-aliasing changed (orbiting a million spheres prepares them once),
/// and its geometry when only colours, materials, lights or the model
/// changed (an edit of a value on a million spheres builds no second
/// hierarchy beside the first), refitted when a few objects moved; a
/// viewer picks objects in it rather than preparing again.
#[derive(Default)]
pub struct LastPrepared {
    last: Mutex<Option<(Arc<Scene>, RenderOptions, Prepared)>>,
}

impl LastPrepared {
    /// `scene` prepared with `options`: the last preparation when it was
    /// of the same scene but for the camera, with the same options but
    /// for the anti-aliasing; over the last one's geometry when only
    /// colours, materials, lights or the model changed
    /// ([`Prepared::with_surfaces`]); else prepared now. Kept for the next.
    pub fn prepare(&self, scene: &Arc<Scene>, options: &RenderOptions) -> Prepared {
        let last = self.last.lock().ok().and_then(|last| {
            let (last, last_options, prepared) = last.as_ref()?;
            let same_options = RenderOptions {
                aa: options.aa,
                ..last_options.clone()
            } == *options;
            Some((
                same_options && last.same_but_camera(scene),
                prepared.clone(),
            ))
        });
        let surfaced = match last {
            Some((true, prepared)) => return prepared,
            Some((false, prepared)) => prepared.with_surfaces(scene, options),
            None => None,
        };
        // The last one goes first: both may be large.
        self.forget();
        let prepared = surfaced.unwrap_or_else(|| prepare(scene, options));
        if let Ok(mut last) = self.last.lock() {
            *last = Some((Arc::clone(scene), options.clone(), prepared.clone()));
        }
        prepared
    }

    /// `scene` prepared (with the options of the last render), seen
    /// through its own camera with their anti-aliasing (the full-size
    /// pass's view), if the last preparation was of it or of the same
    /// scene seen from another camera.
    pub fn seen_from(&self, scene: &Scene) -> Option<Prepared> {
        let last = self.last.lock().ok()?;
        let (prepared_scene, options, prepared) = last.as_ref()?;
        prepared_scene
            .same_but_camera(scene)
            .then(|| prepared.with_view(&scene.camera, options.aa))
    }

    /// Drops the last preparation.
    pub fn forget(&self) {
        if let Ok(mut last) = self.last.lock() {
            *last = None;
        }
    }
}

/// Where a progressive render is, reported on the thread that runs it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// The scene is prepared (or its last preparation taken again).
    Prepared,
    /// A pass at 1/`scale` of each side begins.
    Started { scale: u32 },
    /// That pass is done: `rays` traced, primary and reflected.
    Finished { scale: u32, rays: u64 },
}

/// Renders the whole of `scene`'s image in `passes` (1/scale of each side,
/// coarsest first; a scale of 0 counts as 1) on the current pool: the scene
/// prepared once through `last`, each pass a view of it, coarse passes with
/// one ray a pixel and the full-size one with the options' anti-aliasing.
/// `step` hears each pass begin and end; `tile` gets each finished tile
/// (the pass's scale, the tile of the pass's image, its row-major RGB8
/// pixels) on a render thread. `Ok(None)` once `cancel` is set (checked
/// before every pixel).
pub fn render_progressive(
    scene: &Arc<Scene>,
    options: &RenderOptions,
    passes: &[u32],
    last: &LastPrepared,
    cancel: &Cancel,
    step: &mut dyn FnMut(Step),
    tile: &(dyn Fn(u32, &Tile, &[u8]) + Sync),
) -> Result<Option<()>, RenderError> {
    options.validate()?;
    let prepared = last.prepare(scene, options);
    step(Step::Prepared);
    let (width, height) = (scene.camera.width, scene.camera.height);
    for &scale in passes {
        let scale = scale.max(1);
        if cancel.is_cancelled() {
            return Ok(None);
        }
        step(Step::Started { scale });
        let mut camera = scene.camera.clone();
        camera.width = width.div_ceil(scale);
        camera.height = height.div_ceil(scale);
        // Coarse passes are previews: one ray per pixel.
        let aa = if scale == 1 { options.aa } else { 1 };
        let view = prepared.with_view(&camera, aa);
        let traced = trace_tiles(
            &view,
            view.frame(),
            cancel,
            &Progress::default(),
            None,
            |t: &Tile, pixels: &[u8]| tile(scale, t, pixels),
        );
        let Some(rays) = traced else {
            return Ok(None);
        };
        step(Step::Finished { scale, rays });
    }
    Ok(Some(()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_full_pass_is_the_render_and_the_preparation_is_reused() {
        let mut scene = crate::scene::parse(crate::EXAMPLE_SCENE, std::path::Path::new("e.xml"))
            .expect("the example loads");
        (scene.camera.width, scene.camera.height) = (300, 250);
        let scene = Arc::new(scene);
        let options = RenderOptions::default();
        let last = LastPrepared::default();
        let image = Mutex::new(image::RgbImage::new(300, 250));
        let mut steps = Vec::new();
        let done = render_progressive(
            &scene,
            &options,
            &passes(300, 250),
            &last,
            &Cancel::never(),
            &mut |s| steps.push(s),
            &|scale, t: &Tile, pixels: &[u8]| {
                if scale == 1 {
                    let mut image = image.lock().unwrap();
                    for (k, p) in pixels.chunks_exact(3).enumerate() {
                        let (x, y) = (t.x + k as u32 % t.width, t.y + k as u32 / t.width);
                        image.put_pixel(x, y, image::Rgb([p[0], p[1], p[2]]));
                    }
                }
            },
        )
        .unwrap();
        assert_eq!(done, Some(()));
        assert_eq!(steps.len(), 1 + 2 * 3);
        assert_eq!(steps[0], Step::Prepared);
        assert_eq!(steps[1], Step::Started { scale: 8 });
        // The command line's image, with the rays it traces.
        let (expected, stats) = super::super::render_with_stats(&scene, &options).unwrap();
        assert_eq!(
            steps[6],
            Step::Finished {
                scale: 1,
                rays: stats.rays
            }
        );
        assert_eq!(image.into_inner().unwrap(), expected);
        // Another camera: the same preparation, seen from it.
        let first = last.seen_from(&scene).expect("kept");
        let mut moved = (*scene).clone();
        moved.camera.width = 40;
        let again = last.prepare(&Arc::new(moved.clone()), &options);
        assert!(again.same_world(&first));
        assert_eq!(last.seen_from(&moved).map(|p| p.width()), Some(40));
        // Cancelled: nothing more is traced.
        let newest = Arc::new(std::sync::atomic::AtomicU64::new(2));
        let cancelled = render_progressive(
            &scene,
            &options,
            &[1],
            &last,
            &Cancel::new(newest, 1),
            &mut |_| {},
            &|_, _: &Tile, _: &[u8]| panic!("no tile once cancelled"),
        );
        assert_eq!(cancelled.unwrap(), None);
        let bad = RenderOptions {
            aa: 0,
            ..RenderOptions::default()
        };
        assert!(
            render_progressive(
                &scene,
                &bad,
                &[1],
                &last,
                &Cancel::never(),
                &mut |_| {},
                &|_, _: &Tile, _: &[u8]| {}
            )
            .is_err()
        );
    }

    /// Renders `scene` through `last` and checks the image is the one a
    /// fresh preparation gives; returns the preparation used and the
    /// image.
    fn rendered_as_fresh(
        last: &LastPrepared,
        scene: &Scene,
        options: &RenderOptions,
    ) -> (Prepared, image::RgbImage) {
        let scene = Arc::new(scene.clone());
        let (width, height) = (scene.camera.width, scene.camera.height);
        let image = Mutex::new(image::RgbImage::new(width, height));
        render_progressive(
            &scene,
            options,
            &[1],
            last,
            &Cancel::never(),
            &mut |_| {},
            &|_, t: &Tile, pixels: &[u8]| {
                let mut image = image.lock().unwrap();
                for (k, p) in pixels.chunks_exact(3).enumerate() {
                    let (x, y) = (t.x + k as u32 % t.width, t.y + k as u32 / t.width);
                    image.put_pixel(x, y, image::Rgb([p[0], p[1], p[2]]));
                }
            },
        )
        .unwrap();
        let fresh = super::super::render(&scene, options).unwrap();
        assert!(
            image.into_inner().unwrap() == fresh,
            "the image of a fresh preparation"
        );
        (last.seen_from(&scene).expect("kept"), fresh)
    }

    /// A change to a scene, in the test below.
    type Edit = Box<dyn Fn(&mut Scene)>;

    #[test]
    fn an_edit_of_surfaces_keeps_the_geometry_and_the_image_is_the_same() {
        use crate::shading::Illumination;
        // Enough spheres for a hierarchy, a plane, reflections; few
        // enough for tiles to cull them one by one, and many more.
        for (spheres, options) in [40, 300].into_iter().flat_map(|n| {
            [
                RenderOptions::default(),
                RenderOptions {
                    accelerate: false,
                    ..RenderOptions::default()
                },
                RenderOptions {
                    precision: crate::render::Precision::F32,
                    ..RenderOptions::default()
                },
            ]
            .map(|o| (n, o))
        }) {
            let text = crate::scene::generated::spheres_on_floor(spheres, 64, 48);
            let mut scene = crate::scene::parse(&text, std::path::Path::new("s.xml")).unwrap();
            scene.model.illumination = Illumination::Whitted;
            let last = LastPrepared::default();
            let (mut before, mut picture) = rendered_as_fresh(&last, &scene, &options);
            let mut edits: Vec<(&str, Edit, bool)> = vec![
                (
                    "a material",
                    Box::new(|s| Arc::make_mut(&mut s.objects[3]).material.ks += 0.05),
                    true,
                ),
                (
                    "every material",
                    Box::new(|s| {
                        for o in &mut s.objects {
                            Arc::make_mut(o).material.ka *= 0.5;
                        }
                    }),
                    true,
                ),
                (
                    "a colour",
                    Box::new(|s| Arc::make_mut(&mut s.objects[0]).color.y += 0.1),
                    true,
                ),
                ("a light", Box::new(|s| s.lights[0].position.x += 1.0), true),
                (
                    "the model",
                    Box::new(|s| {
                        s.model.illumination = match s.model.illumination {
                            Illumination::Whitted => Illumination::Phong,
                            _ => Illumination::Whitted,
                        }
                    }),
                    true,
                ),
                (
                    "a move",
                    Box::new(|s| {
                        let o = Arc::make_mut(&mut s.objects[5]);
                        let mut steps = o.transform.steps().to_vec();
                        steps.push(crate::math::TransformStep::Translate(
                            crate::math::Vec3::new(0.5, 0.0, 0.0),
                        ));
                        o.transform = crate::math::Transform::from_steps(steps).unwrap();
                    }),
                    false,
                ),
                (
                    "two moves",
                    // Grown, across the picture, far from where they were
                    // (and from their leaves' other spheres).
                    Box::new(move |s| {
                        let half = 2.0 * (spheres as f64).sqrt();
                        let r = 0.1 * half;
                        for (n, x, z) in [(2, 0.0, 0.5 * half), (17, 0.5 * half, 0.3 * half)] {
                            use crate::math::TransformStep::{Translate, UniformScale};
                            let at = crate::math::Vec3::new(x, 1.0 - r, z);
                            Arc::make_mut(&mut s.objects[n]).transform =
                                crate::math::Transform::from_steps(vec![
                                    UniformScale(r),
                                    Translate(at),
                                ])
                                .unwrap();
                        }
                    }),
                    false,
                ),
                (
                    "one object fewer",
                    Box::new(|s| {
                        s.objects.pop();
                    }),
                    false,
                ),
            ];
            for (what, edit, kept) in edits.drain(..) {
                edit(&mut scene);
                let (after, image) = rendered_as_fresh(&last, &scene, &options);
                assert_eq!(after.same_shapes(&before), kept, "{what}");
                // A move refits the hierarchy; one object fewer builds it.
                let refitted = what == "a move" || what == "two moves";
                assert_eq!(after.same_hierarchy(&before), kept || refitted, "{what}");
                if what == "two moves" {
                    assert!(image != picture, "the moves are seen");
                }
                picture = image;
                assert!(!after.same_world(&before), "{what}");
                before = after;
            }
            // Other options than the geometry was made with: made again.
            let other = RenderOptions {
                accelerate: !options.accelerate,
                ..options.clone()
            };
            let (again, _) = rendered_as_fresh(&last, &scene, &other);
            assert!(!again.same_shapes(&before));
            rendered_as_fresh(&last, &scene, &options);
        }
    }
}
