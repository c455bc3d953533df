//! The generic formulas against frozen copies of the code they replaced
//! (the f64 functions and the f32 study's own quadratic and plane test),
//! bit for bit, on a few thousand random rays: a changed operation or a
//! changed order fails here, before it can move a pixel.

use super::Primitive32;
use super::precision::{F64x4, Lanes, Mask};
use super::single::Ray32;
use super::sphere::stable_roots;
use super::{
    Ray, Receding, intersect_ball, intersect_ball_textbook, intersect_plane_world,
    intersect_sphere, intersect_sphere_textbook,
};
use glam::{DVec3, Vec3};

mod old {
    //! Verbatim copies of the replaced functions (doc comments trimmed).
    use super::{DVec3, Ray, Vec3};

    pub fn nearest_positive<T: PartialOrd + Copy + Default>(t0: T, t1: T) -> Option<T> {
        let zero = T::default();
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if near > zero {
            Some(near)
        } else if far > zero {
            Some(far)
        } else {
            None
        }
    }

    pub fn intersect_sphere(ray: &Ray) -> Option<f64> {
        let (o, d) = (ray.origin, ray.dir);
        let a = d.length_squared();
        let b = o.dot(d);
        let c = o.length_squared() - 1.0;
        let l = o - (b / a) * d;
        let quarter_disc = a * (1.0 - l.length_squared());
        if quarter_disc.is_nan() || quarter_disc < 0.0 {
            return None;
        }
        let q = -(b + quarter_disc.sqrt().copysign(b));
        if q == 0.0 {
            return None;
        }
        let (t0, t1) = (q / a, c / q);
        nearest_positive(t0, t1)
    }

    pub fn intersect_ball(ray: &Ray, center: DVec3, radius: f64) -> Option<f64> {
        let f = ray.origin - center;
        let d = ray.dir;
        let b = f.dot(d);
        let r2 = radius * radius;
        let c = f.length_squared() - r2;
        if c > 0.0 && b > 0.0 {
            return None;
        }
        let l = f - b * d;
        let quarter_disc = r2 - l.length_squared();
        if quarter_disc.is_nan() || quarter_disc < 0.0 {
            return None;
        }
        let q = -(b + quarter_disc.sqrt().copysign(b));
        if q == 0.0 {
            return None;
        }
        nearest_positive(q, c / q)
    }

    pub fn intersect_sphere_textbook(ray: &Ray) -> Option<f64> {
        let (o, d) = (ray.origin, ray.dir);
        let a = d.length_squared();
        let b = 2.0 * o.dot(d);
        let c = o.length_squared() - 1.0;
        let disc = b * b - 4.0 * a * c;
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        nearest_positive((-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a))
    }

    pub fn intersect_ball_textbook(ray: &Ray, center: DVec3, radius: f64) -> Option<f64> {
        let f = ray.origin - center;
        let b = 2.0 * f.dot(ray.dir);
        let c = f.length_squared() - radius * radius;
        let disc = b * b - 4.0 * c;
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        nearest_positive((-b - sq) / 2.0, (-b + sq) / 2.0)
    }

    pub fn intersect_plane_world(ray: &Ray, point: DVec3, normal: DVec3) -> Option<f64> {
        let denom = normal.dot(ray.dir);
        let num = normal.dot(point - ray.origin);
        if denom == 0.0 || (num > 0.0) != (denom > 0.0) {
            return None;
        }
        let t = num / denom;
        (t > 0.0 && t.is_finite()).then_some(t)
    }

    pub fn quadratic<const TEXTBOOK: bool>(f: Vec3, d: Vec3, r2: f32) -> Option<f32> {
        let a = d.length_squared();
        let c = f.length_squared() - r2;
        let (t0, t1) = if TEXTBOOK {
            let b = 2.0 * f.dot(d);
            let disc = b * b - 4.0 * a * c;
            if disc.is_nan() || disc < 0.0 {
                return None;
            }
            let sq = disc.sqrt();
            ((-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a))
        } else {
            let b = f.dot(d);
            let l = f - (b / a) * d;
            let quarter_disc = a * (r2 - l.length_squared());
            if quarter_disc.is_nan() || quarter_disc < 0.0 {
                return None;
            }
            let q = -(b + quarter_disc.sqrt().copysign(b));
            if q == 0.0 {
                return None;
            }
            (q / a, c / q)
        };
        nearest_positive(t0, t1)
    }

    pub fn plane32(ray_origin: Vec3, ray_dir: Vec3, point: Vec3, normal: Vec3) -> Option<f32> {
        let denom = normal.dot(ray_dir);
        let num = normal.dot(point - ray_origin);
        if denom == 0.0 || (num > 0.0) != (denom > 0.0) {
            return None;
        }
        let t = num / denom;
        (t > 0.0 && t.is_finite()).then_some(t)
    }
}

/// SplitMix64: a fixed, dependency-free stream of random numbers.
struct Random(u64);

impl Random {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [−1, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// A number of any scale from 1e-6 to 1e9, either sign; now and then
    /// zero, so that tangents, parallels and degenerate rays come up.
    fn scalar(&mut self) -> f64 {
        match self.next() % 16 {
            0 => 0.0,
            1 => self.unit().round(),
            _ => self.unit() * 10f64.powf(15.0 * (self.unit() + 1.0) / 2.0 - 6.0),
        }
    }

    fn vector(&mut self) -> DVec3 {
        match self.next() % 8 {
            // Near the origin, where most hits are.
            0..=3 => DVec3::new(self.unit(), self.unit(), self.unit()) * 4.0,
            // An axis, for exact zeros in the products.
            4 => [DVec3::X, DVec3::Y, -DVec3::Z][(self.next() % 3) as usize] * self.scalar(),
            _ => DVec3::new(self.scalar(), self.scalar(), self.scalar()),
        }
    }

    /// A unit direction, mostly; now and then a scaled one (an object-space
    /// ray) or zero.
    fn direction(&mut self) -> DVec3 {
        let d = self.vector().normalize_or_zero();
        match self.next() % 8 {
            0 => d * self.scalar().abs(),
            _ => d,
        }
    }
}

/// Both `None`, or both `Some` with the same bits.
fn same<T: Copy>(new: Option<T>, old: Option<T>, bits: impl Fn(T) -> u64) -> bool {
    new.map(&bits) == old.map(&bits)
}

/// Hits and misses seen, so that a test shows it reached both.
#[derive(Default)]
struct Tally {
    hits: usize,
    misses: usize,
}

impl Tally {
    /// Asserts that each (new, old) pair agrees bit for bit; `context`
    /// describes the case.
    fn check<T: Copy + std::fmt::Debug, const N: usize>(
        &mut self,
        pairs: [(Option<T>, Option<T>); N],
        bits: impl Fn(T) -> u64,
        context: impl Fn() -> String,
    ) {
        for (k, (new, old)) in pairs.into_iter().enumerate() {
            assert!(
                same(new, old, &bits),
                "formula {k}: {new:?} != {old:?} ({})",
                context()
            );
            if new.is_some() {
                self.hits += 1;
            } else {
                self.misses += 1;
            }
        }
    }

    /// Both outcomes came up often.
    fn assert_both(&self) {
        let Tally { hits, misses } = *self;
        assert!(hits > CASES && misses > CASES, "{hits} {misses}");
    }
}

const CASES: usize = 20_000;

#[test]
fn f64_formulas_match_the_replaced_code_bit_for_bit() {
    let mut random = Random(0x5eed_0001);
    let (mut tally, mut moved) = (Tally::default(), 0);
    for case in 0..CASES {
        let ray = Ray::new(random.vector(), random.direction());
        // Aim at the sphere now and then, so that roots come up often.
        let center = if case % 3 == 0 {
            ray.at(random.scalar().abs()) + random.vector() * 0.25
        } else {
            random.vector()
        };
        let radius = random.scalar().abs();
        let (point, normal) = (random.vector(), random.direction());
        let bits = f64::to_bits;
        // The comparison sees a change of arithmetic: a = |d|² computed
        // (≈ 1, not 1) instead of the unit direction's a = 1 moves roots.
        let computed_a = stable_roots(
            ray.origin - center,
            ray.dir,
            ray.dir.length_squared(),
            radius * radius,
            Receding::Dismiss,
        )
        .get();
        if !same(computed_a, old::intersect_ball(&ray, center, radius), bits) {
            moved += 1;
        }
        let pairs = [
            (intersect_sphere(&ray).get(), old::intersect_sphere(&ray)),
            (
                intersect_sphere_textbook(&ray).get(),
                old::intersect_sphere_textbook(&ray),
            ),
            (
                intersect_ball(&ray, center, radius * radius).get(),
                old::intersect_ball(&ray, center, radius),
            ),
            (
                intersect_ball_textbook(&ray, center, radius * radius).get(),
                old::intersect_ball_textbook(&ray, center, radius),
            ),
            (
                intersect_plane_world(&ray, point, normal).get(),
                old::intersect_plane_world(&ray, point, normal),
            ),
        ];
        tally.check(pairs, bits, || {
            format!("case {case}: {ray:?} {center} {radius} {point} {normal}")
        });
    }
    // The cases reach both outcomes often, and would catch a change.
    tally.assert_both();
    assert!(moved > 100, "{moved}");
}

#[test]
fn f32_formulas_match_the_replaced_code_bit_for_bit() {
    let mut random = Random(0x5eed_0002);
    let mut tally = Tally::default();
    for case in 0..CASES {
        let ray = Ray32::from_f64(&Ray::new(random.vector(), random.direction()));
        let center = if case % 3 == 0 {
            ray.at(random.scalar().abs() as f32) + random.vector().as_vec3() * 0.25
        } else {
            random.vector().as_vec3()
        };
        let radius = random.scalar().abs() as f32;
        // An ellipsoid through a random affine map (world to object).
        let to_object =
            glam::Affine3A::from_cols_array(&std::array::from_fn(|_| random.unit() as f32 * 3.0));
        let (point, normal) = (random.vector().as_vec3(), random.direction().as_vec3());
        let ball = Primitive32::Ball(super::Ball32 { center, radius });
        let ellipsoid = Primitive32::Ellipsoid(super::Ellipsoid32 {
            to_object,
            normal: glam::Mat3::IDENTITY,
        });
        let plane = Primitive32::Plane(super::Plane32 { point, normal });
        let (f, r2) = (ray.origin - center, radius * radius);
        let (o, d) = (
            to_object.transform_point3(ray.origin),
            to_object.transform_vector3(ray.dir),
        );
        let bits = |t: f32| u64::from(t.to_bits());
        let pairs = [
            (
                ball.intersect::<false>(&ray),
                old::quadratic::<false>(f, ray.dir, r2),
            ),
            (
                ball.intersect::<true>(&ray),
                old::quadratic::<true>(f, ray.dir, r2),
            ),
            (
                ellipsoid.intersect::<false>(&ray),
                old::quadratic::<false>(o, d, 1.0),
            ),
            (
                ellipsoid.intersect::<true>(&ray),
                old::quadratic::<true>(o, d, 1.0),
            ),
            (
                plane.intersect::<false>(&ray),
                old::plane32(ray.origin, ray.dir, point, normal),
            ),
        ];
        tally.check(pairs, bits, || {
            format!("case {case}: {ray:?} {center} {radius} {point} {normal}")
        });
    }
    tally.assert_both();
}

/// Four rays in lanes give, lane by lane, what each gives alone: the same
/// root bit for bit, found in the same lanes (the lanes' early outs drop
/// only the lanes they concern).
#[test]
fn lanes_match_one_ray_at_a_time() {
    let mut random = Random(0x5eed_0003);
    let mut found = [0u32; 2];
    for case in 0..CASES / 4 {
        let rays: [Ray; 4] = std::array::from_fn(|_| Ray::new(random.vector(), random.direction()));
        let centers: [DVec3; 4] = std::array::from_fn(|i| {
            if (case + i) % 3 == 0 {
                rays[i].at(random.scalar().abs()) + random.vector() * 0.25
            } else {
                random.vector()
            }
        });
        let r2 = random.scalar().powi(2);
        let (point, normal) = (random.vector(), random.direction());
        let lanes = Ray::new(
            F64x4::vector_from_fn(|i| rays[i].origin),
            F64x4::vector_from_fn(|i| rays[i].dir),
        );
        let center = F64x4::vector_from_fn(|i| centers[i]);
        let (splat_r2, splat_point, splat_normal) = (
            F64x4::splat(r2),
            F64x4::splat_vector(point),
            F64x4::splat_vector(normal),
        );
        for i in 0..4 {
            let ray = &rays[i];
            let pairs = [
                (intersect_sphere(&lanes), intersect_sphere(ray)),
                (
                    intersect_sphere_textbook(&lanes),
                    intersect_sphere_textbook(ray),
                ),
                (
                    intersect_ball(&lanes, center, splat_r2),
                    intersect_ball(ray, centers[i], r2),
                ),
                (
                    intersect_ball_textbook(&lanes, center, splat_r2),
                    intersect_ball_textbook(ray, centers[i], r2),
                ),
                (
                    intersect_plane_world(&lanes, splat_point, splat_normal),
                    intersect_plane_world(ray, point, normal),
                ),
            ];
            for (k, (lane, one)) in pairs.into_iter().enumerate() {
                let lane = lane.found.lane(i).then(|| lane.t.lane(i));
                assert_eq!(
                    lane.map(f64::to_bits),
                    one.get().map(f64::to_bits),
                    "case {case} lane {i} formula {k}: {ray:?}"
                );
                found[usize::from(lane.is_some())] += 1;
            }
        }
    }
    assert!(found[0] > 1000 && found[1] > 1000, "{found:?}");
}
