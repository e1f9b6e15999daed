//! The strip's geometry, as a recording's metadata states it.

/// Geometry of a strip, as a recording's metadata states it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Free length, m.
    pub length_m: f64,
    /// Width, m.
    pub width_m: f64,
    /// Total thickness (core and both films), m.
    pub thickness_m: f64,
}

impl Geometry {
    /// The seed's 50 mm strip.
    pub const THESIS_2006: Geometry = Geometry {
        length_m: 0.05,
        width_m: 0.01,
        thickness_m: 0.000_285_8,
    };
}
