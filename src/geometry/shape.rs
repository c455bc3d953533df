//! The shapes an object can have, each in its own space: what the
//! intersection formulas of this folder are written for.
//!
//! This is the one list of them: [`Shape::ALL`], each with the element
//! name the scene format gives it ([`Shape::name`]), what the format's
//! documentation says of it ([`Shape::doc`]: editors show it, the schema
//! holds it), how POV-Ray spells it ([`Shape::pov`]) and whether it has
//! bounds. The loader, the schema and the
//! completion of `rayoflight lsp`, the save-back, `--add` and the panel's
//! buttons all read this list: a shape is named nowhere else. Its row also
//! says which function of its file makes the [`Primitive`](super::Primitive)
//! an object of it becomes ([`Shape::primitive`]): that answers where a
//! ray hits it and its normal there.

/// Declares the shapes, each once: the enum and the list of all of
/// them, with their element names and documentation.
macro_rules! shapes {
    ($($(#[doc = $what:literal])* $shape:ident = $name:literal, bounded: $bounded:literal, pov: $pov:literal, primitive: $primitive:path, $doc:literal;)*) => {
        /// What an object is in its own space.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum Shape {
            $($(#[doc = $what])* $shape,)*
        }

        impl Shape {
            /// Every shape, in the order the format lists them.
            pub const ALL: &'static [Shape] = &[$(Shape::$shape),*];

            /// The element name in the scene format (`<sphere>`).
            pub const fn name(self) -> &'static str {
                match self {
                    $(Shape::$shape => $name,)*
                }
            }

            /// What the scene format says of the element (the schema
            /// holds it, editors show it on hover).
            pub const fn doc(self) -> &'static str {
                match self {
                    $(Shape::$shape => concat!(
                        $doc,
                        " Its optional <color>, <material> and <transformation>, ",
                        "each at most once, in any order."
                    ),)*
                }
            }

            /// How POV-Ray 3.7 spells the same shape in its own space, up
            /// to its transformation and texture (`rayoflight export-pov`).
            pub const fn pov(self) -> &'static str {
                match self {
                    $(Shape::$shape => $pov,)*
                }
            }

            /// What an object of this shape placed by `transform` is to
            /// intersection (its file says: a sphere under a similarity is
            /// a ball, any other an ellipsoid).
            pub fn primitive(self, transform: &crate::math::Transform) -> super::Primitive {
                match self {
                    $(Shape::$shape => $primitive(transform),)*
                }
            }

            /// Whether it fits in a box (a bounding volume hierarchy holds
            /// it); an unbounded one is tested against every ray apart.
            pub const fn is_bounded(self) -> bool {
                match self {
                    $(Shape::$shape => $bounded,)*
                }
            }
        }
    };
}

shapes! {
    /// The unit sphere centred on the origin.
    Sphere = "sphere", bounded: true, pov: "sphere { 0, 1", primitive: super::sphere::primitive,
        "The unit sphere centred on the origin of its own space, placed by its transformation.";
    /// The plane z = 0, infinite and two-sided.
    Plane = "plane", bounded: false, pov: "plane { z, 0", primitive: super::plane::primitive,
        "The plane z = 0 of its own space (infinite, two-sided), placed by its transformation.";
}

impl Shape {
    /// The shape whose element is `name`, if one is.
    pub fn from_name(name: &str) -> Option<Shape> {
        Shape::ALL.iter().copied().find(|s| s.name() == name)
    }

    /// [`Shape::from_name`] for a name as the XML reader hands it.
    pub fn from_name_bytes(name: &[u8]) -> Option<Shape> {
        Shape::ALL
            .iter()
            .copied()
            .find(|s| s.name().as_bytes() == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shape_is_found_by_its_name_and_only_by_it() {
        for &shape in Shape::ALL {
            assert_eq!(Shape::from_name(shape.name()), Some(shape));
            assert_eq!(Shape::from_name_bytes(shape.name().as_bytes()), Some(shape));
        }
        assert_eq!(Shape::from_name("light"), None);
        assert_eq!(Shape::from_name("Sphere"), None);
    }
}
