//! What a render reads of every object — the largest `ks`, how many are
//! bounded and how many reflect, how far they reach, the brightest colour
//! a surface can give under the lights — worked out in one walk and kept
//! with the scene's list of objects ([`Objects::memo`]): a render after a
//! change of a light, the camera or the model walks no object. (On a
//! million spheres those walks, by `auto` and the preparation, took about
//! 100 ms a render, most of a keystroke's time in the app following an
//! editor.)

use rayon::prelude::*;
use std::sync::{Arc, Mutex, PoisonError};

use crate::geometry::Primitive;
use crate::scene::{Color, Illumination, Material, Object, Objects, Scene};

/// See the module's doc.
#[derive(Debug)]
pub(super) struct ObjectFacts {
    /// The largest `ks` (0 without objects).
    pub max_ks: f64,
    /// Objects with bounds (spheres; planes have none).
    pub bounded: usize,
    /// Objects with `ks` > 0.
    pub mirrors: usize,
    /// The largest coordinate, in absolute value, an object's bounds reach
    /// (a plane's: its origin's).
    pub reach: f64,
    /// The last [`ObjectFacts::max_local_color`] asked for: the model's
    /// illumination and the lights' summed colour it was for, and the
    /// colour.
    local: Mutex<Option<(Illumination, Color, Color)>>,
}

/// The facts of `objects`, worked out where this list has none yet.
pub(super) fn of(objects: &Objects) -> Arc<ObjectFacts> {
    objects.memo(walk)
}

/// The walk, on the cores (a sphere's bounds cost its matrices: a million
/// took 100 ms on one core). Maxima and counts: the same whatever the
/// order.
fn walk(objects: &[Arc<Object>]) -> ObjectFacts {
    let (max_ks, bounded, mirrors, reach) = objects
        .par_iter()
        .map(|o| {
            let reach = match Primitive::new(o.shape, &o.transform).bounds() {
                Some(b) => b.min.abs().max(b.max.abs()).max_element(),
                None => o.transform.to_world().translation.abs().max_element(),
            };
            let ks = o.material.ks;
            (
                ks,
                usize::from(o.shape.is_bounded()),
                usize::from(ks > 0.0),
                reach,
            )
        })
        .reduce(
            || (0.0, 0, 0, 0.0),
            |a, b| (a.0.max(b.0), a.1 + b.1, a.2 + b.2, a.3.max(b.3)),
        );
    ObjectFacts {
        max_ks,
        bounded,
        mirrors,
        reach,
        local: Mutex::new(None),
    }
}

impl ObjectFacts {
    /// Per channel, the most any one hit of `scene` (whose objects these
    /// are the facts of) can add before weighting: the largest
    /// ka C + Σ I (kd + ks) over the objects (the terms the model uses).
    /// Walked again only when the model's illumination or the lights'
    /// summed colour changed since the last asked for.
    pub fn max_local_color(&self, scene: &Scene) -> Color {
        let light_sum = scene.lights.iter().fold(Color::ZERO, |s, l| s + l.color);
        let illumination = scene.model.illumination;
        let mut local = self.local.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some((i, sum, color)) = *local
            && i == illumination
            && sum == light_sum
        {
            return color;
        }
        // On the cores, as the walk: a maximum, the same in any order.
        let color = scene
            .objects
            .par_iter()
            .map(|o| {
                let Material { ka, kd, ks, .. } = o.material;
                let direct = match illumination {
                    Illumination::Ambient => 0.0,
                    Illumination::Lambert => kd,
                    Illumination::Phong | Illumination::Whitted => kd + ks,
                };
                ka * o.color + direct * light_sum
            })
            .reduce(|| Color::ZERO, |a, b| a.max(b));
        *local = Some((illumination, light_sum, color));
        color
    }
}
