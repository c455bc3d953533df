//! The shapes an object can have, each in its own space: what the
//! intersection formulas of this folder are written for. The scene names
//! them in its file ([`Shape::name`]); geometry flattens them into
//! [`Primitive`](super::Primitive)s.

/// What an object is in its own space.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// The unit sphere centred on the origin.
    Sphere,
    /// The plane z = 0, infinite and two-sided.
    Plane,
}

impl Shape {
    /// The element name in the scene format (`<sphere>`, `<plane>`).
    pub fn name(self) -> &'static str {
        match self {
            Shape::Sphere => "sphere",
            Shape::Plane => "plane",
        }
    }
}
