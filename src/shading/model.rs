/// The illumination model's formula (docs/scene-format.md, Illumination).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Illumination {
    Ambient,
    Lambert,
    Phong,
    Whitted,
}

impl Illumination {
    pub const ALL: [Illumination; 4] = [
        Illumination::Ambient,
        Illumination::Lambert,
        Illumination::Phong,
        Illumination::Whitted,
    ];

    /// The `type` attribute value.
    pub const fn name(self) -> &'static str {
        match self {
            Illumination::Ambient => "ambient",
            Illumination::Lambert => "lambert",
            Illumination::Phong => "phong",
            Illumination::Whitted => "whitted",
        }
    }

    pub fn from_name(name: &str) -> Option<Illumination> {
        Illumination::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The `<model>` element: a formula and the whitted reflection depth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Model {
    pub illumination: Illumination,
    /// Reflected rays followed from one primary ray; used by `whitted` only.
    pub depth: u32,
}

impl Model {
    /// Largest accepted `depth`.
    pub const MAX_DEPTH: u32 = 10_000;

    /// Reflection rays actually followed: `depth` for whitted, 0 otherwise.
    pub fn reflection_depth(&self) -> u32 {
        match self.illumination {
            Illumination::Whitted => self.depth,
            _ => 0,
        }
    }
}

impl Default for Model {
    fn default() -> Self {
        Model {
            illumination: Illumination::Phong,
            depth: 1,
        }
    }
}
