//! Linear algebra on top of glam (double precision): the [`Transform`] that
//! places an object or the camera in the world.
//!
//! A transform keeps only the list of steps the scene file wrote (so it can
//! be shown, edited and written back), two of them in place: a sphere
//! placed by a scale and a translation is 72 bytes, not the 288 its three
//! matrices would take, which is most of a scene of a million spheres. The
//! object-to-world matrix, its inverse and the normal matrix (the inverse
//! transpose of the linear part) are composed from the steps when asked
//! for ([`Transform::matrices`]): in the same order every time, so they are
//! the same to the bit on every call. Their one heavy user, preparing a
//! scene for a render, asks once per object. Matrices are affine
//! (`DAffine3`): every step of the format is affine, and the implied last
//! row saves a quarter of the arithmetic of a `DMat4`.

use glam::{DAffine3, DMat3, DVec3};
use smallvec::SmallVec;

pub use glam::DVec3 as Vec3;

/// One child of a `<transformation>` element (docs/scene-format.md,
/// Transformations).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TransformStep {
    Translate(DVec3),
    /// Right-hand rotation about x, angle in radians.
    RotateX(f64),
    RotateY(f64),
    RotateZ(f64),
    /// `<scale factor="f"/>`.
    UniformScale(f64),
    /// `<scale x=".." y=".." z=".."/>`.
    Scale(DVec3),
}

impl TransformStep {
    /// The step as an affine matrix.
    pub fn matrix(&self) -> DAffine3 {
        match *self {
            TransformStep::Translate(t) => DAffine3::from_translation(t),
            TransformStep::RotateX(a) => DAffine3::from_rotation_x(a),
            TransformStep::RotateY(a) => DAffine3::from_rotation_y(a),
            TransformStep::RotateZ(a) => DAffine3::from_rotation_z(a),
            TransformStep::UniformScale(f) => DAffine3::from_scale(DVec3::splat(f)),
            TransformStep::Scale(s) => DAffine3::from_scale(s),
        }
    }

    /// The inverse step as a matrix: exact per step (negated translation
    /// and angle, reciprocal scale), so no determinant is ever formed.
    pub fn inverse_matrix(&self) -> DAffine3 {
        match *self {
            TransformStep::Translate(t) => DAffine3::from_translation(-t),
            TransformStep::RotateX(a) => DAffine3::from_rotation_x(-a),
            TransformStep::RotateY(a) => DAffine3::from_rotation_y(-a),
            TransformStep::RotateZ(a) => DAffine3::from_rotation_z(-a),
            TransformStep::UniformScale(f) => DAffine3::from_scale(DVec3::splat(f.recip())),
            TransformStep::Scale(s) => DAffine3::from_scale(s.recip()),
        }
    }
}

/// Why a list of steps makes no [`Transform`]; `step` counts from 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum TransformError {
    /// The step scales by zero: the matrix has no inverse.
    #[error("singular transformation (a zero scale)")]
    Singular { step: usize },
    /// Composing the steps up to this one made the matrix or its inverse
    /// non-finite (numbers too large, or a scale so small that its
    /// reciprocal is infinite).
    #[error("the composed transformation overflows")]
    Overflow { step: usize },
}

/// The steps of a transformation: up to two in place, more on the heap.
pub type Steps = SmallVec<[TransformStep; 2]>;

/// An object's (or the camera's) placement in the world: the steps the
/// file wrote, checked to compose to finite, invertible matrices.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Transform {
    steps: Steps,
}

/// The matrices of a [`Transform`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Matrices {
    /// Object (or camera) space to world space: M = T_n · … · T_1.
    pub to_world: DAffine3,
    /// World space to object space: M⁻¹.
    pub to_object: DAffine3,
    /// Object-space normals to world space: (M⁻¹)ᵀ, linear part only.
    pub normal: DMat3,
}

impl Transform {
    /// Composes the steps in document order: the first step is applied first.
    ///
    /// M = T_n · … · T_1, and its inverse is composed from the steps'
    /// exact inverses, M⁻¹ = T_1⁻¹ · … · T_n⁻¹, rather than by inverting M:
    /// a sphere of radius 1e-300 has a determinant that underflows to 0
    /// but a perfectly finite inverse.
    ///
    /// A zero scale is [`TransformError::Singular`]; any other non-finite
    /// result is [`TransformError::Overflow`] at the first step after
    /// which the product or its inverse is no longer finite (once
    /// non-finite, a product stays so: the check per step refuses exactly
    /// what a check of the result would).
    pub fn from_steps(steps: impl Into<Steps>) -> Result<Transform, TransformError> {
        let steps = steps.into();
        let mut to_world = DAffine3::IDENTITY;
        let mut to_object = DAffine3::IDENTITY;
        for (step, s) in steps.iter().enumerate() {
            let zero = match *s {
                TransformStep::UniformScale(f) => f == 0.0,
                TransformStep::Scale(v) => v.cmpeq(DVec3::ZERO).any(),
                _ => false,
            };
            if zero {
                return Err(TransformError::Singular { step });
            }
            to_world = s.matrix() * to_world;
            to_object *= s.inverse_matrix();
            if !to_world.is_finite() || !to_object.is_finite() {
                return Err(TransformError::Overflow { step });
            }
        }
        Ok(Transform { steps })
    }

    pub fn steps(&self) -> &[TransformStep] {
        &self.steps
    }

    /// All three matrices, composed as [`Transform::from_steps`] checked
    /// them.
    pub fn matrices(&self) -> Matrices {
        let to_world = self.to_world();
        let to_object = self.to_object();
        Matrices {
            to_world,
            to_object,
            normal: to_object.matrix3.transpose(),
        }
    }

    /// M = T_n · … · T_1.
    pub fn to_world(&self) -> DAffine3 {
        self.steps
            .iter()
            .fold(DAffine3::IDENTITY, |m, s| s.matrix() * m)
    }

    /// M⁻¹ = T_1⁻¹ · … · T_n⁻¹.
    pub fn to_object(&self) -> DAffine3 {
        self.steps
            .iter()
            .fold(DAffine3::IDENTITY, |m, s| m * s.inverse_matrix())
    }

    /// The normal matrix (M⁻¹)ᵀ: maps an object-space normal to a world-space
    /// normal (not normalised).
    pub fn normal_matrix(&self) -> DMat3 {
        self.to_object().matrix3.transpose()
    }

    pub fn is_identity(&self) -> bool {
        self.to_world() == DAffine3::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_apply_in_document_order() {
        // Translate then rotate 90° about z: (0,0,0) -> (1,0,0) -> (0,1,0).
        let t = Transform::from_steps(vec![
            TransformStep::Translate(DVec3::X),
            TransformStep::RotateZ(std::f64::consts::FRAC_PI_2),
        ])
        .unwrap();
        let p = t.to_world().transform_point3(DVec3::ZERO);
        assert!((p - DVec3::Y).length() < 1e-12, "{p}");
        // Rotate then translate: the origin stays put by the rotation.
        let t = Transform::from_steps(vec![
            TransformStep::RotateZ(std::f64::consts::FRAC_PI_2),
            TransformStep::Translate(DVec3::X),
        ])
        .unwrap();
        let p = t.to_world().transform_point3(DVec3::ZERO);
        assert!((p - DVec3::X).length() < 1e-12, "{p}");
    }

    #[test]
    fn inverse_undoes_the_matrix() {
        let t = Transform::from_steps(vec![
            TransformStep::Scale(DVec3::new(2.0, 3.0, -0.5)),
            TransformStep::RotateY(0.7),
            TransformStep::Translate(DVec3::new(1.0, -2.0, 5.0)),
        ])
        .unwrap();
        let p = DVec3::new(0.3, -1.7, 2.2);
        let q = t
            .to_object()
            .transform_point3(t.to_world().transform_point3(p));
        assert!((p - q).length() < 1e-12);
    }

    #[test]
    fn tiny_and_huge_scales_have_finite_inverses() {
        for f in [1e-300, 1e300, -1e-150] {
            let t = Transform::from_steps(vec![TransformStep::UniformScale(f)]).unwrap();
            let p = DVec3::new(1.0, 2.0, 3.0);
            let q = t
                .to_world()
                .transform_point3(t.to_object().transform_point3(p));
            assert!((p - q).length() < 1e-12 * p.length(), "{f}: {q}");
        }
    }

    #[test]
    fn zero_scale_is_singular() {
        assert_eq!(
            Transform::from_steps(vec![TransformStep::UniformScale(0.0)]),
            Err(TransformError::Singular { step: 0 })
        );
        assert_eq!(
            Transform::from_steps(vec![
                TransformStep::Translate(DVec3::X),
                TransformStep::Scale(DVec3::new(1.0, -0.0, 1.0))
            ]),
            Err(TransformError::Singular { step: 1 })
        );
    }

    #[test]
    fn a_non_finite_composition_overflows_at_the_step_that_made_it() {
        use TransformStep::*;
        let over = |steps: Vec<TransformStep>| Transform::from_steps(steps).map(|_| ());
        let x = DVec3::new(1e308, 0.0, 0.0);
        assert_eq!(
            over(vec![Translate(x), Translate(x)]),
            Err(TransformError::Overflow { step: 1 })
        );
        // The inverse overflows: 1 / 1e-320 is infinite.
        assert_eq!(
            over(vec![RotateX(1.0), UniformScale(1e-320)]),
            Err(TransformError::Overflow { step: 1 })
        );
        assert_eq!(
            over(vec![
                UniformScale(1e200),
                RotateZ(1.0),
                UniformScale(1e200),
                UniformScale(0.0)
            ]),
            Err(TransformError::Overflow { step: 2 })
        );
        // What undoes itself is fine.
        assert_eq!(
            over(vec![UniformScale(1e300), UniformScale(1e-300)]),
            Ok(())
        );
    }

    #[test]
    fn rotations_follow_the_contract_table() {
        let a = 0.3_f64;
        let (s, c) = a.sin_cos();
        let v = DVec3::new(1.0, 2.0, 3.0);
        let rx = TransformStep::RotateX(a).matrix().transform_vector3(v);
        assert!((rx - DVec3::new(1.0, 2.0 * c - 3.0 * s, 2.0 * s + 3.0 * c)).length() < 1e-15);
        let ry = TransformStep::RotateY(a).matrix().transform_vector3(v);
        // (z, x) -> (z cos a - x sin a, z sin a + x cos a)
        assert!((ry - DVec3::new(3.0 * s + 1.0 * c, 2.0, 3.0 * c - 1.0 * s)).length() < 1e-15);
        let rz = TransformStep::RotateZ(a).matrix().transform_vector3(v);
        assert!((rz - DVec3::new(1.0 * c - 2.0 * s, 1.0 * s + 2.0 * c, 3.0)).length() < 1e-15);
    }
}
