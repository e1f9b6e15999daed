//! The catalogue of effects a diagnosis can name (`FORMAT.md`), each the
//! name of an optional term of the model.

use std::fmt;

/// An effect of `FORMAT.md`'s catalogue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Effect {
    /// Arc kinematics: the tip moves toward the clamp.
    LargeDeflection,
    /// `EI` differs from the laminate estimate.
    BeamStiffness,
    /// Viscoelastic and structural damping: a constant modal ratio `ζ₀`
    /// and the stiffness-proportional `β`.
    Damping,
    /// Added mass and drag of the surrounding water.
    HydrodynamicLoading,
    /// Charge and current not linear in voltage.
    ElectrochemicalNonlinearity,
    /// The bending relaxes back past the start under a held voltage.
    BackRelaxation,
    /// The response weakens over the session.
    Dehydration,
    /// Driving one segment bends its neighbours.
    SegmentCrosstalk,
    /// The segments differ in `R1`, `C` and moment gain.
    SegmentVariation,
}

impl Effect {
    /// Every effect, in the catalogue's order.
    pub const ALL: [Effect; 9] = [
        Effect::LargeDeflection,
        Effect::BeamStiffness,
        Effect::Damping,
        Effect::HydrodynamicLoading,
        Effect::ElectrochemicalNonlinearity,
        Effect::BackRelaxation,
        Effect::Dehydration,
        Effect::SegmentCrosstalk,
        Effect::SegmentVariation,
    ];

    /// The catalogue's name.
    pub fn name(&self) -> &'static str {
        match self {
            Effect::LargeDeflection => "large-deflection",
            Effect::BeamStiffness => "beam-stiffness",
            Effect::Damping => "damping",
            Effect::HydrodynamicLoading => "hydrodynamic-loading",
            Effect::ElectrochemicalNonlinearity => "electrochemical-nonlinearity",
            Effect::BackRelaxation => "back-relaxation",
            Effect::Dehydration => "dehydration",
            Effect::SegmentCrosstalk => "segment-crosstalk",
            Effect::SegmentVariation => "segment-variation",
        }
    }

    /// The effect a catalogue name denotes.
    pub fn parse(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
