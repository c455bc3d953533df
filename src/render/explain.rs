//! Why a pixel has its colour: the ray tree of one pixel, with every
//! number of the illumination formula at every bounce.
//!
//! The tree is recorded from the render's own trace loop (an observer of
//! [`Prepared::explain`]'s one-lane trace), not computed a second time:
//! the same kernel, the same formulas, the same early stop, so the
//! explained 8-bit value is the pixel of the image. A lane of a packet
//! computes what one ray alone does, bit for bit, so one lane explains
//! the packets' pixels too.
//!
//! Per bounce: the ray, the object hit, t, the hit point M and normal N,
//! each light's cos θ and cos α and what it added, and the terms ka C,
//! Σ I kd cos θ, Σ I ks cos^m α and ks I_r. The camera ray's reflection
//! is the renderer's own sum of the later bounces, so its four terms add
//! up to the pixel's unclamped colour bit for bit; a later bounce's
//! reflection is its ks times the next bounce's colour (the whitted formula
//! I = phong + ks I_r, docs/scene-format.md, Illumination).
//!
//! The trees of a pixel's rays can be large (256 rays of 10 000 bounces):
//! [`Prepared::explain_each`] hands them on one at a time, so that a
//! writer holds one tree, never all of them.
//!
//! [`Prepared::explain`]: super::Prepared::explain
//! [`Prepared::explain_each`]: super::Prepared::explain_each

pub use super::observer::Ended;
use super::observer::Observer;
use crate::geometry::{Lanes, Mask, Ray};
use crate::shading::{Illumination, LightObserver, SurfacePoint, Terms};
use glam::DVec3;

impl Ended {
    /// In words, for people.
    pub fn describe(&self) -> String {
        match self {
            Ended::Missed => "a miss".to_owned(),
            Ended::Depth => "the model's reflection depth".to_owned(),
            Ended::NoMirror => "ks = 0, nothing reflected".to_owned(),
            Ended::EarlyStop { bound } => format!(
                "early stop: the rest adds at most {} and changes no 8-bit value",
                vector(*bound)
            ),
        }
    }
}

/// Ray `k` of a chain in words: `camera ray from (…) along (…)` for the
/// first, `reflection k from …` after it.
pub fn describe_ray(k: usize, ray: &Ray) -> String {
    let which = if k == 0 {
        "camera ray".to_owned()
    } else {
        format!("reflection {k}")
    };
    format!(
        "{which} from {} along {}",
        vector(ray.origin),
        vector(ray.dir)
    )
}

/// A number for people: six significant digits at most, no trailing
/// zeros.
pub fn number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{}", if x == 0.0 { 0.0 } else { x });
    }
    let digits = (5 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let text = format!("{x:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text
    }
}

/// A vector for people: `(x, y, z)` with [`number`]s.
pub fn vector(v: DVec3) -> String {
    format!("({}, {}, {})", number(v.x), number(v.y), number(v.z))
}

/// What one light did at a hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightShare {
    /// Index of the light in the scene's list (0-based).
    pub light: usize,
    /// cos θ = N · L (the light is behind the surface where ≤ 0).
    pub cos_theta: f64,
    /// cos α = R · V, where the model has a specular term and the light
    /// is in front.
    pub cos_alpha: Option<f64>,
    /// I kd cos θ (zero where the light is behind).
    pub diffuse: DVec3,
    /// I ks cos^m α (zero where R faces away from V).
    pub specular: DVec3,
}

impl LightShare {
    /// In words: `light 1: cos θ = 0.6, cos α = 0.73`, or that it is
    /// behind the surface.
    pub fn describe(&self) -> String {
        let alpha = self
            .cos_alpha
            .map_or(String::new(), |a| format!(", cos α = {}", number(a)));
        let behind = if self.cos_theta > 0.0 {
            ""
        } else {
            " (behind: adds nothing)"
        };
        format!(
            "light {}: cos θ = {}{alpha}{behind}",
            self.light + 1,
            number(self.cos_theta)
        )
    }
}

/// One hit of the chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Bounce {
    /// The ray that arrived (f64; an f32 method's rays widened).
    pub ray: Ray,
    /// Index of the object hit in the scene's list (0-based).
    pub object: usize,
    /// Distance along the ray.
    pub t: f64,
    /// The hit point M.
    pub point: DVec3,
    /// The shading normal N (facing the ray).
    pub normal: DVec3,
    /// Each light's share, in the scene's order.
    pub lights: Vec<LightShare>,
    /// ka C, Σ I kd cos θ, Σ I ks cos^m α.
    pub terms: Terms,
    /// The surface's ks.
    pub ks: f64,
    /// The product of the ks met before this hit: the weight its own
    /// colour enters the pixel with.
    pub weight: f64,
    /// ks I_r: what the reflection brings.
    pub reflection: DVec3,
    /// ((ambient + diffuse) + specular) + reflection.
    pub color: DVec3,
}

/// The tree of one ray through the pixel (one of the aa × aa samples).
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// The image point the camera ray goes through, in pixels.
    pub at: (f64, f64),
    /// The hits, camera ray's first.
    pub bounces: Vec<Bounce>,
    /// The ray that hit nothing, where the chain ended on a miss.
    pub missed: Option<Ray>,
    pub ended: Ended,
    /// The ray's colour, unclamped: the first bounce's (black for a
    /// miss).
    pub color: DVec3,
}

/// Why pixel (x, y) has its colour.
#[derive(Debug, Clone, PartialEq)]
pub struct Explanation {
    pub x: u32,
    pub y: u32,
    /// The pixel whose rays were traced: (x, y) itself, or in a draft the
    /// top-left pixel of its 2×2 block (even x and y), whose colour the
    /// draft copies to the other three.
    pub traced: (u32, u32),
    pub illumination: Illumination,
    /// The rays through the pixel: one, or aa × aa in reading order.
    pub samples: Vec<Sample>,
    /// The unclamped colour: the one ray's, or the mean of the samples'.
    pub rgb: DVec3,
    /// The pixel of the image.
    pub rgb8: [u8; 3],
}

/// The pixel an explanation explains, as the render makes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelValue {
    /// The pixel whose rays were traced ([`Explanation::traced`]).
    pub traced: (u32, u32),
    /// The unclamped colour: the one ray's, or the mean of the samples'.
    pub rgb: DVec3,
    /// The pixel of the image.
    pub rgb8: [u8; 3],
    /// Rays through the pixel: 1, or aa × aa.
    pub samples: usize,
}

impl Explanation {
    /// In words, where the pixel is a draft's copy of another
    /// ([`draft_note`]).
    pub fn draft_note(&self) -> Option<String> {
        draft_note((self.x, self.y), self.traced, self.samples.len())
    }
}

/// In words, where pixel (x, y) is a draft's copy of the `traced` one:
/// `draft: pixel (7, 5) shows the ray of (6, 4)`; `rays`: its rays.
pub fn draft_note((x, y): (u32, u32), traced: (u32, u32), rays: usize) -> Option<String> {
    let (x0, y0) = traced;
    let rays = if rays > 1 { "rays" } else { "ray" };
    ((x0, y0) != (x, y))
        .then(|| format!("draft: pixel ({x}, {y}) shows the {rays} of ({x0}, {y0})"))
}

/// Records lane 0 of a trace (the explain traces one lane).
#[derive(Debug, Default)]
pub(super) struct Recorder {
    ray: Option<Ray>,
    lights: Vec<LightShare>,
    bounces: Vec<Bounce>,
    missed: Option<Ray>,
    ended: Option<Ended>,
}

impl<L: Lanes> LightObserver<L> for Recorder {
    fn light(
        &mut self,
        index: usize,
        cos_theta: L,
        cos_alpha: Option<L>,
        diffuse: L::Vector,
        specular: L::Vector,
    ) {
        self.lights.push(LightShare {
            light: index,
            cos_theta: cos_theta.lane(0),
            cos_alpha: cos_alpha.map(|c| c.lane(0)),
            diffuse: L::vector_lane(diffuse, 0),
            specular: L::vector_lane(specular, 0),
        });
    }
}

impl<L: Lanes> Observer<L> for Recorder {
    fn ray(&mut self, _: u32, rays: &Ray<L::Vector>) {
        self.ray = Some(Ray::new(
            L::vector_lane(rays.origin, 0),
            L::vector_lane(rays.dir, 0),
        ));
        self.lights.clear();
    }

    fn missed(&mut self, missed: L::Mask) {
        if missed.lane(0) {
            self.missed = self.ray;
            self.ended = Some(Ended::Missed);
        }
    }

    fn hit(
        &mut self,
        alive: L::Mask,
        object: L,
        t: L,
        point: &SurfacePoint<L::Vector>,
        terms: &Terms<L::Vector>,
        ks: L,
        weight: L,
    ) {
        let (Some(ray), true) = (self.ray, alive.lane(0)) else {
            return;
        };
        self.bounces.push(Bounce {
            ray,
            object: object.lane(0) as usize,
            t: t.lane(0),
            point: L::vector_lane(point.m, 0),
            normal: L::vector_lane(point.n, 0),
            lights: std::mem::take(&mut self.lights),
            terms: Terms {
                ambient: L::vector_lane(terms.ambient, 0),
                diffuse: L::vector_lane(terms.diffuse, 0),
                specular: L::vector_lane(terms.specular, 0),
            },
            ks: ks.lane(0),
            weight: weight.lane(0),
            reflection: DVec3::ZERO,
            color: DVec3::ZERO,
        });
    }

    fn ended(&mut self, lanes: L::Mask, why: Ended) {
        if lanes.lane(0) {
            self.ended = Some(why);
        }
    }
}

impl Recorder {
    /// The tree of the ray through image point `at`, whose trace gave
    /// `reflection` (the renderer's ks I_r of the camera ray) and `color`.
    pub(super) fn finish(self, at: (f64, f64), reflection: DVec3, color: DVec3) -> Sample {
        let mut bounces = self.bounces;
        // From the end of the chain back: each bounce's reflection is its
        // ks times the next one's colour; the camera ray's is the
        // renderer's own sum.
        let mut next: Option<DVec3> = None;
        for (k, bounce) in bounces.iter_mut().enumerate().rev() {
            bounce.reflection = match (k, next) {
                (0, _) => reflection,
                (_, Some(next)) => next * bounce.ks,
                (_, None) => DVec3::ZERO,
            };
            bounce.color = bounce.terms.local() + bounce.reflection;
            next = Some(bounce.color);
        }
        Sample {
            at,
            bounces,
            missed: self.missed,
            ended: self.ended.unwrap_or(Ended::Depth),
            color,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_well() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(-0.0), "0");
        assert_eq!(number(0.4), "0.4");
        assert_eq!(number(0.08000000000000002), "0.08");
        assert_eq!(number(21.108_123_4), "21.1081");
        assert_eq!(number(-0.000_416_666_7), "-0.000416667");
        assert_eq!(number(1234567.0), "1234567");
        assert_eq!(number(f64::INFINITY), "inf");
        assert_eq!(vector(DVec3::new(1.0, 0.5, -2.0)), "(1, 0.5, -2)");
    }
}
