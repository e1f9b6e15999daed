//! The fitted parameters of a model structure and the transforms that keep
//! them physical: the optimiser moves freely in `θ`, the model sees values
//! inside their bounds.

use model_core::{Extensions, MAX_SEGMENTS};

use super::effect::Effect;
use crate::model::predict::ModelSpec;

/// A fitted parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knob {
    /// `R1`, Ω.
    R1,
    /// `R2`, Ω.
    R2,
    /// `C`, F.
    C,
    /// `a`, the instant moment per charge, N·m/C (fitted as `|θ|` times the
    /// fixed model's DC moment per charge, `≥ 0`; as `ln a` with
    /// back-relaxation).
    A,
    /// `b = K z`, N·m/(C·s) (fitted as `b/p = θ²` times the fixed
    /// model's DC moment per charge, `≥ 0`; as `z/p = b/(a p)`, of either
    /// sign, with back-relaxation).
    B,
    /// `p`, 1/s.
    P,
    /// `EI`, N·m² (beam-stiffness).
    Ei,
    /// Constant modal damping ratio `ζ₀` (damping).
    Zeta,
    /// Rayleigh `β`, s (damping).
    Beta,
    /// Added mass per length, kg/m (hydrodynamic loading).
    AddedMass,
    /// Quadratic drag per length, `c₂` in `c₂ |v| v`, N·s²/m³
    /// (hydrodynamic loading). The water's linear part is a damping's.
    QuadraticDrag,
    /// `a` of `v (1 + a v²)`, 1/V² (electrochemical nonlinearity).
    ChargeCubic,
    /// `b` of `v/R2 (1 + b v²)`, 1/V² (electrochemical nonlinearity).
    LeakCubic,
    /// The reaction behind the double layer (electrochemical
    /// nonlinearity; [`model_core::Reaction`]): the layer's voltage at
    /// which its current equals the linear leak's, V (its ratio held at 1;
    /// fitted as the voltage's logarithm).
    ReactionRef,
    /// The reaction's Tafel voltage `b`, V (fitted as `ln b`).
    ReactionTafel,
    /// `κ` (segment crosstalk).
    Crosstalk,
    /// Dehydration rate, 1/s.
    Dehydration,
    /// Dehydration curvature (0: constant rate).
    DryingCurvature,
    /// Dehydration rate of the circuit's admittance, 1/s
    /// ([`crate::model::predict::circuit_gain`]): the currents and the
    /// charge fall with it, whatever the drive.
    CircuitDrying,
    /// Segment `i`'s (index from 0 at the clamp, never 0: the reference)
    /// relative departure of `R1` (segment variation).
    SegmentR1(usize),
    /// Segment `i`'s relative departure of `C` (segment variation).
    SegmentC(usize),
    /// Segment `i`'s relative departure of the moment gain `K` (segment
    /// variation).
    SegmentK(usize),
    /// The free strip's mode `k`'s (from 0) own damping ratio, the modes
    /// above taking the last freed one's (the form check's damping, see
    /// [`Space::with_each_modes_damping`]).
    FreeMode(usize),
    /// The held strip's mode `k`'s own damping ratio, as
    /// [`Knob::FreeMode`].
    BlockedMode(usize),
}

/// Modes of the free strip whose own damping ratio the form check frees:
/// the camera's 30 frames a second see the first alone.
pub const OWN_FREE_MODES: usize = 1;
/// Modes of the held strip whose own damping ratio the form check frees:
/// the load cell's thousand samples a second see a held tip ring in
/// several at once (the rig's soft strip: 2.2 times its noise with four
/// modes' own ratios against 23 with one for all, `tests/rig/tests/against_model.rs`).
pub const OWN_BLOCKED_MODES: usize = 4;
const FREE_MODE_NAMES: [&str; OWN_FREE_MODES] = ["modal_damping_free_1"];
const BLOCKED_MODE_NAMES: [&str; OWN_BLOCKED_MODES] = [
    "modal_damping_blocked_1",
    "modal_damping_blocked_2",
    "modal_damping_blocked_3",
    "modal_damping_blocked_4",
];

/// The per-segment knobs' names, by segment index.
const SEGMENT_R1_NAMES: [&str; MAX_SEGMENTS] = [
    "segment_1_r1_deviation",
    "segment_2_r1_deviation",
    "segment_3_r1_deviation",
    "segment_4_r1_deviation",
    "segment_5_r1_deviation",
    "segment_6_r1_deviation",
    "segment_7_r1_deviation",
    "segment_8_r1_deviation",
];
const SEGMENT_C_NAMES: [&str; MAX_SEGMENTS] = [
    "segment_1_c_deviation",
    "segment_2_c_deviation",
    "segment_3_c_deviation",
    "segment_4_c_deviation",
    "segment_5_c_deviation",
    "segment_6_c_deviation",
    "segment_7_c_deviation",
    "segment_8_c_deviation",
];
const SEGMENT_K_NAMES: [&str; MAX_SEGMENTS] = [
    "segment_1_k_deviation",
    "segment_2_k_deviation",
    "segment_3_k_deviation",
    "segment_4_k_deviation",
    "segment_5_k_deviation",
    "segment_6_k_deviation",
    "segment_7_k_deviation",
    "segment_8_k_deviation",
];

impl Knob {
    /// Whether the baseline fits it.
    pub fn is_baseline(&self) -> bool {
        BASELINE.contains(self)
    }

    /// Whether the parameter is positive by its nature (its interval is
    /// then reported on a log scale).
    pub fn positive(&self) -> bool {
        matches!(
            self,
            Knob::R1
                | Knob::R2
                | Knob::C
                | Knob::P
                | Knob::Ei
                | Knob::ReactionRef
                | Knob::ReactionTafel
        )
    }

    /// Whether the value is a ramp of `θ`, held at 0 for every `θ ≤ 0`
    /// ([`ramp`]): there the value does not move with `θ`, and its
    /// delta-method interval would be a point.
    pub fn floored(&self) -> bool {
        matches!(
            self,
            Knob::Zeta
                | Knob::Beta
                | Knob::AddedMass
                | Knob::QuadraticDrag
                | Knob::Dehydration
                | Knob::DryingCurvature
                | Knob::CircuitDrying
                | Knob::FreeMode(_)
                | Knob::BlockedMode(_)
        )
    }

    /// Name and unit, as reports and the TOML file say them.
    pub fn name(&self) -> &'static str {
        match self {
            Knob::R1 => "r1_ohm",
            Knob::R2 => "r2_ohm",
            Knob::C => "c_f",
            Knob::A => "a_nm_per_c",
            Knob::B => "b_nm_per_c_s",
            Knob::P => "p_per_s",
            Knob::Ei => "ei_nm2",
            Knob::Zeta => "damping_ratio",
            Knob::Beta => "damping_stiffness_s",
            Knob::AddedMass => "added_mass_kg_per_m",
            Knob::QuadraticDrag => "drag_quadratic_n_s2_per_m3",
            Knob::ChargeCubic => "charge_cubic_per_v2",
            Knob::LeakCubic => "leak_cubic_per_v2",
            Knob::ReactionRef => "reaction_ref_v",
            Knob::ReactionTafel => "reaction_tafel_v",
            Knob::Crosstalk => "crosstalk",
            Knob::Dehydration => "dehydration_per_s",
            Knob::DryingCurvature => "dehydration_curvature",
            Knob::CircuitDrying => "circuit_drying_per_s",
            Knob::SegmentR1(i) => SEGMENT_R1_NAMES[*i],
            Knob::SegmentC(i) => SEGMENT_C_NAMES[*i],
            Knob::SegmentK(i) => SEGMENT_K_NAMES[*i],
            Knob::FreeMode(k) => FREE_MODE_NAMES[*k],
            Knob::BlockedMode(k) => BLOCKED_MODE_NAMES[*k],
        }
    }

    /// Whether it is the circuit's: the currents depend on these knobs
    /// alone, and on nothing the beam does.
    pub fn is_circuit(&self) -> bool {
        matches!(
            self,
            Knob::R1
                | Knob::R2
                | Knob::C
                | Knob::ChargeCubic
                | Knob::LeakCubic
                | Knob::ReactionRef
                | Knob::ReactionTafel
                | Knob::CircuitDrying
                | Knob::SegmentR1(_)
                | Knob::SegmentC(_)
        )
    }

    /// Whether it is one of segment variation's deviations.
    pub fn is_segment_deviation(&self) -> bool {
        matches!(
            self,
            Knob::SegmentR1(_) | Knob::SegmentC(_) | Knob::SegmentK(_)
        )
    }
}

/// The knobs of the baseline: the seed's electrical and relaxation parameters.
pub const BASELINE: [Knob; 6] = [Knob::R1, Knob::R2, Knob::C, Knob::A, Knob::B, Knob::P];

/// Lowest value of the cubic terms: `v (1 + a v²)` must rise up to 4 V.
const CUBIC_MIN: f64 = -1.0 / 48.0;
/// The floor the fit's cubic terms are held to, just inside [`CUBIC_MIN`].
const CUBIC_FLOOR: f64 = CUBIC_MIN * 0.99;

// The effects' knobs are linear in θ, with θ = 0 the term switched off, so
// that an extended fit starts exactly where the model it extends stands
// (a logarithm could not start at zero, and any other start moves the
// undamped beam's ringing out of phase). Each scale is the term's typical
// size, so that θ is of order one.
/// Constant damping ratio (the rig's and real strips' 0.02 to 0.1).
const ZETA_SCALE: f64 = 1e-2;
/// Highest constant damping ratio: the model's terms are for an
/// underdamped strip.
const ZETA_MAX: f64 = 0.9;
/// Rayleigh `β`, s (`β ω₁²` is about 0.03/s at this scale).
const BETA_SCALE: f64 = 1e-6;
/// Added mass, kg/m (the strip itself is about 8e-3).
const ADDED_MASS_SCALE: f64 = 1e-2;
/// Quadratic drag, N·s²/m³ (`½ ρ C_d b`: about 10 for a 10 mm strip in
/// water).
const QUADRATIC_DRAG_SCALE: f64 = 10.0;
/// Cubic electrochemical terms, 1/V².
const CUBIC_SCALE: f64 = 1e-2;
/// The reaction's voltages (where its current equals the linear leak's)
/// a fit reaches, V: water's electrolysis sets in about 1.2 V, and a
/// reaction matching the leak below half a volt is a second leak, which
/// trades with `R2` (literature rig board session 52011 ran it to a
/// twentieth of a volt and a volt a Tafel voltage, and neither the leak
/// nor the reaction could then show); above ten, out of any drive's reach.
const REACTION_REF_MIN_V: f64 = 0.5;
const REACTION_REF_MAX_V: f64 = 10.0;
/// The reaction's Tafel voltage a fit starts from, V (water's
/// electrolysis on platinum: tens of millivolts a decade).
const TAFEL_START_V: f64 = 0.1;
/// The reaction's Tafel voltages a fit reaches, V: steeper than a tenth
/// of the start is a step; electrolysis's Tafel slopes are 30 to 120 mV
/// a decade (13 to 52 mV an `e`-fold), and one flatter than 0.2 V an
/// `e`-fold is a leak's, not a reaction's.
const TAFEL_MIN_V: f64 = 0.01;
const TAFEL_MAX_V: f64 = 0.2;
/// The session's highest drive a fit assumes where it was given none
/// ([`with_session_peak`]), V.
const PEAK_DRIVE_V: f64 = 3.0;
/// The reaction's grid of starts ([`Space::reaction_starts`]): voltages
/// from a volt (below water's 1.23 V, as overpotentials and a layer short
/// of the drive allow) to the session's peak in this many steps, each
/// with these Tafel voltages (electrolysis's slopes, steep to flat).
const REACTION_GRID_LOW_V: f64 = 1.0;
const REACTION_GRID_STEPS: usize = 5;
const REACTION_GRID_TAFEL_V: [f64; 3] = [0.025, 0.05, 0.1];
/// Crosstalk fraction.
const CROSSTALK_SCALE: f64 = 0.1;
/// Dehydration rate, 1/s.
const DEHYDRATION_SCALE: f64 = 1e-3;
/// Highest curvature of the drying law: at `c` the loss falls off as
/// `(1 + c r t)^(−1/c)`, and a curvature of hundreds puts the whole loss
/// in a step at the session's start, which is the baseline's transient,
/// not a strip losing water over minutes (unbounded, literature rig
/// sessions ran it to 100–1300 and the drying took the start-up).
const DRYING_CURVATURE_MAX: f64 = 3.0;
/// Segment deviations: the factor is `e^{s θ}`, so it stays positive and
/// is exactly 1 at `θ = 0`; a tenth is the rig's and the bench's typical
/// spread (5 to 15 %).
const SEGMENT_SCALE: f64 = 0.1;

/// Lowest `b/p` of the baseline's network, in units of the fixed model's
/// DC moment per charge: `b = 0` is back-relaxation's, not the baseline's.
const B_FLOOR: f64 = 1e-15;
/// Lowest `θ` a start gives `b/p` (`θ²` = 1e-6 of the unit): at `θ = 0`
/// its gradient vanishes.
const B_START_MIN: f64 = 1e-3;
/// Lowest relaxation rate `p` a fit reaches, 1/s: a relaxation slower
/// than the drift's scale (a minute) is the bench's drift, not the
/// strip's (`drift.rs`), and one the session cannot show beside it. Left
/// free, a fit turned a real strip's curl into an integrator (`p` =
/// 6.3e-6/s) and every relaxation parameter it reported was wrong. `p` is
/// `P_MIN + e^θ`, smooth through the bound.
pub const P_MIN: f64 = 1.0 / super::drift::DRIFT_SCALE_S;
/// Least `p − P_MIN` a fit starts from, 1/s: at the logarithm's floor
/// (1e-9) `p`'s gradient vanishes and a fit started there stays.
const P_START_MIN: f64 = 1e-3;
/// Highest `p` a fit starts from, 1/s. A pole far above every rate the
/// session shows (a camera's frames, the charging `1/(R1·C)`, 60/s for
/// the seed's strip) makes the lead network a gain `b/p`, and `p`'s
/// gradient falls as `1/p`: a fit started there stays. A baseline that
/// cannot bend back (a back-relaxing strip) runs off so (rig seed 107:
/// `p` 2.8e6/s), and every candidate started from it stayed, the
/// back-relaxation's too, were the currents' zero read at the rests.
/// Lowered to here, with the DC gain `b/p` kept, the model is the same
/// below 100/s.
const P_START_MAX: f64 = 100.0;
/// Lowest instant gain `a` a back-relaxed fit starts from, in units of
/// the fixed model's DC moment per charge: there `a` is a logarithm, and a
/// gain near zero moves the moment by next to nothing per step. A board
/// strip that relaxes back had its baseline collapse to no moment at all
/// (`a` 8e-6 of the unit), and the back-relaxation started there stopped
/// at once (rig seed 10084).
const A_START_MIN: f64 = 1e-3;

/// The forward-difference step for `θ`'s entry `t`: `θ` is a logarithm or
/// similar, so a fixed step is a relative one. Every derivative the fit
/// and the diagnosis take in `θ` (the Jacobian, the values' gradients, the
/// identifiability's Jacobian) steps by it.
pub fn difference_step(t: f64) -> f64 {
    1e-6 * t.abs().max(1.0)
}

/// A non-negative term: `s θ` above zero, zero below (the optimiser sees
/// a flat floor, and steps back from it).
fn ramp(t: f64, scale: f64) -> f64 {
    (t * scale).max(0.0)
}

/// A damping ratio (the law's constant one, or a mode's own) at `θ`:
/// [`ZETA_SCALE`] a unit, from 0 up to [`ZETA_MAX`].
fn damping_ratio(t: f64) -> f64 {
    ramp(t, ZETA_SCALE).min(ZETA_MAX)
}

/// The DC moment per charge `b/p`, N·m/C, floored above zero (a
/// back-relaxed start has none).
fn dc_per_charge(p: &model_core::Params) -> f64 {
    (p.b_nm_per_c_s / p.p_per_s.max(1e-9)).max(1e-15)
}

/// `a`, or for the pure lag (no instant part to scale `z` by) the DC
/// moment per charge, which starts the back-relaxed fit at `z = p`.
fn instant_or_gain(p: &model_core::Params) -> f64 {
    if p.a_nm_per_c > 0.0 {
        p.a_nm_per_c
    } else {
        dc_per_charge(p)
    }
}

/// The session's highest drive `fixed` carries, V (held in its
/// reaction's voltage, which a fixed model leaves off:
/// [`with_session_peak`]), or [`PEAK_DRIVE_V`].
pub fn session_peak_v(fixed: &ModelSpec) -> f64 {
    match fixed.ext.reaction_ref_v {
        v if v > 0.0 && fixed.ext.reaction_ratio == 0.0 => v,
        _ => PEAK_DRIVE_V,
    }
}

/// `fixed` carrying the session's highest drive `peak_v`, V: a reaction
/// starts with its voltage there (its current the linear leak's at a
/// voltage the layer never quite reaches: a few percent of the leak's at
/// most, and at a smaller drive next to nothing), and shows where the
/// fitted voltage lies below it beyond its interval.
pub fn with_session_peak(mut fixed: ModelSpec, peak_v: f64) -> ModelSpec {
    if fixed.ext.reaction_ratio == 0.0 && peak_v > 0.0 {
        fixed.ext.reaction_ref_v = peak_v.clamp(REACTION_REF_MIN_V, REACTION_REF_MAX_V);
    }
    fixed
}

/// A model structure (baseline plus effects) and its parameter space.
#[derive(Clone, Debug)]
pub struct Space {
    /// The fitted knobs, in `θ` order.
    pub knobs: Vec<Knob>,
    /// The effects on top of the baseline.
    pub effects: Vec<Effect>,
    /// Parameters held fixed (geometry, beam unless freed, a crosstalk
    /// or segments' deviations measured apart).
    pub fixed: ModelSpec,
}

impl Space {
    /// The space of the baseline plus `effects` for a strip of `segments`
    /// segments, around the fixed parts of `fixed`.
    pub fn new(effects: &[Effect], segments: usize, fixed: ModelSpec) -> Space {
        let mut knobs = BASELINE.to_vec();
        let mut effects = effects.to_vec();
        effects.sort();
        effects.dedup();
        for e in &effects {
            knobs.extend_from_slice(match e {
                Effect::LargeDeflection | Effect::BackRelaxation => &[],
                Effect::BeamStiffness => &[Knob::Ei],
                Effect::Damping => &[Knob::Zeta, Knob::Beta],
                Effect::HydrodynamicLoading => &[Knob::AddedMass, Knob::QuadraticDrag],
                Effect::ElectrochemicalNonlinearity => &[
                    Knob::ChargeCubic,
                    Knob::LeakCubic,
                    Knob::ReactionRef,
                    Knob::ReactionTafel,
                ],
                Effect::Dehydration => &[
                    Knob::CircuitDrying,
                    Knob::Dehydration,
                    Knob::DryingCurvature,
                ],
                Effect::SegmentCrosstalk => &[Knob::Crosstalk],
                Effect::SegmentVariation => &[],
            });
            if *e == Effect::SegmentVariation {
                // Segment 1 is the reference: its values are the shared ones.
                for i in 1..segments.min(MAX_SEGMENTS) {
                    knobs.extend([Knob::SegmentR1(i), Knob::SegmentC(i), Knob::SegmentK(i)]);
                }
            }
        }
        Space {
            knobs,
            effects,
            fixed,
        }
    }

    /// The same structure with each mode's own damping ratio in place of
    /// its law's constant one (`damping`'s `ζ₀`; its Rayleigh `β` stays):
    /// the first [`OWN_FREE_MODES`] modes of the free strip and
    /// [`OWN_BLOCKED_MODES`] of the held one, the modes above each taking
    /// the last one's. With every ratio at `ζ₀` it is the law, so the law's
    /// fit is one of its points. Not a catalogue effect: the fit's check
    /// of how far its estimates lean on the law's form ([`super::form`]).
    pub fn with_each_modes_damping(mut self) -> Space {
        self.knobs.retain(|k| !matches!(k, Knob::Zeta));
        self.knobs.extend((0..OWN_FREE_MODES).map(Knob::FreeMode));
        self.knobs
            .extend((0..OWN_BLOCKED_MODES).map(Knob::BlockedMode));
        self
    }

    /// Whether `theta` holds the charge's cubic term at its floor
    /// (`v (1 + a v²)` barely rising at 4 V): there it may be the currents
    /// leaning on the bound for a current the circuit's form lacks, at the
    /// moment's expense, so the fit also tries it held
    /// ([`super::Fitter`]'s descents). False without the term.
    pub fn charge_cubic_at_floor(&self, theta: &[f64]) -> bool {
        // A hair above the floor still counts: θ comes back from it scaled.
        self.knobs
            .iter()
            .position(|k| *k == Knob::ChargeCubic)
            .is_some_and(|j| theta[j] * CUBIC_SCALE <= CUBIC_FLOOR * (1.0 - 1e-9))
    }

    /// Starts for the reaction's two knobs around `theta`, the other
    /// knobs as there: its voltage on a geometric grid from
    /// [`REACTION_GRID_LOW_V`] to the session's peak, each with each of
    /// [`REACTION_GRID_TAFEL_V`]. The descent needs one: the reaction's
    /// current is exponential in both, so from the peak (where it starts,
    /// drawing next to nothing) the gradient flattens the Tafel voltage
    /// rather than lowering the onset (literature rig session 52002 ended
    /// at the flattest, ΔBIC −11,000, where `finrs fit` from an onset below
    /// the peak had found −41,000). Empty without the reaction.
    pub fn reaction_starts(&self, theta: &[f64]) -> Vec<Vec<f64>> {
        let at = |k: Knob| self.knobs.iter().position(|&x| x == k);
        let (Some(r), Some(b)) = (at(Knob::ReactionRef), at(Knob::ReactionTafel)) else {
            return Vec::new();
        };
        let peak = session_peak_v(&self.fixed).clamp(REACTION_REF_MIN_V, REACTION_REF_MAX_V);
        let low = REACTION_GRID_LOW_V.min(peak);
        let steps = REACTION_GRID_STEPS - 1;
        (0..=steps)
            .map(|k| low * (peak / low).powf(k as f64 / steps as f64))
            .flat_map(|ref_v| {
                REACTION_GRID_TAFEL_V.map(|tafel_v| {
                    let mut t = theta.to_vec();
                    t[r] = ref_v.ln();
                    t[b] = tafel_v.ln();
                    t
                })
            })
            .collect()
    }

    /// Whether the structure includes `e`.
    pub fn has(&self, e: Effect) -> bool {
        self.effects.contains(&e)
    }

    /// Whether knob `j`'s model is even in its `θ` (`θ` and `−θ` give one
    /// model), its bound at `θ = 0`: `a` (`|θ|`) and `b/p` (`θ²`) of a
    /// model without back-relaxation.
    pub fn even(&self, j: usize) -> bool {
        matches!(self.knobs[j], Knob::A | Knob::B) && !self.has(Effect::BackRelaxation)
    }

    /// Parameters the information criteria count: the knobs, plus one for
    /// back-relaxation, which frees `b`'s sign rather than adding a knob.
    pub fn counted_parameters(&self) -> usize {
        self.knobs.len() + usize::from(self.has(Effect::BackRelaxation))
    }

    /// The unit of the baseline's instant-moment knob: the fixed model's
    /// DC moment per charge, N·m/C.
    fn instant_unit(&self) -> f64 {
        dc_per_charge(&self.fixed.params)
    }

    /// The model at `θ`.
    pub fn spec(&self, theta: &[f64]) -> ModelSpec {
        let mut spec = self.fixed;
        spec.ext = Extensions {
            back_relaxation: self.has(Effect::BackRelaxation),
            large_deflection: self.has(Effect::LargeDeflection),
            // Held, not fitted, unless knobs here: a crosstalk measured
            // where it shows apart (the diagnosis's lone drives), and the
            // segments' deviations while that is measured.
            crosstalk: self.fixed.ext.crosstalk,
            segment_variation: self.fixed.ext.segment_variation,
            ..Extensions::NONE
        };
        spec.dehydration_per_s = 0.0;
        spec.dehydration_curvature = 0.0;
        spec.circuit_drying_per_s = 0.0;
        let p = &mut spec.params;
        // p first: a and b are relative to it (and to each other).
        let (mut a_theta, mut b_theta) = (None, None);
        for (knob, &t) in self.knobs.iter().zip(theta) {
            match knob {
                Knob::R1 => p.r1_ohm = t.exp(),
                Knob::R2 => p.r2_ohm = t.exp(),
                Knob::C => p.c_f = t.exp(),
                Knob::A => a_theta = Some(t),
                Knob::B => b_theta = Some(t),
                Knob::P => p.p_per_s = P_MIN + t.exp(),
                Knob::Ei => p.ei_nm2 = t.exp(),
                Knob::Zeta => spec.ext.damping_ratio = damping_ratio(t),
                Knob::Beta => spec.ext.damping_stiffness_s = ramp(t, BETA_SCALE),
                Knob::AddedMass => spec.ext.added_mass_kg_per_m = ramp(t, ADDED_MASS_SCALE),
                Knob::QuadraticDrag => {
                    spec.ext.drag_quadratic_n_s2_per_m3 = ramp(t, QUADRATIC_DRAG_SCALE)
                }
                Knob::ChargeCubic => {
                    spec.ext.charge_cubic_per_v2 = (t * CUBIC_SCALE).max(CUBIC_FLOOR)
                }
                Knob::LeakCubic => spec.ext.leak_cubic_per_v2 = (t * CUBIC_SCALE).max(CUBIC_FLOOR),
                Knob::ReactionRef => {
                    spec.ext.reaction_ratio = 1.0;
                    spec.ext.reaction_ref_v = t.exp().clamp(REACTION_REF_MIN_V, REACTION_REF_MAX_V);
                }
                Knob::ReactionTafel => {
                    spec.ext.reaction_tafel_v = t.exp().clamp(TAFEL_MIN_V, TAFEL_MAX_V)
                }
                Knob::Crosstalk => spec.ext.crosstalk = (t * CROSSTALK_SCALE).clamp(-0.95, 0.95),
                Knob::Dehydration => spec.dehydration_per_s = ramp(t, DEHYDRATION_SCALE),
                Knob::DryingCurvature => {
                    spec.dehydration_curvature = ramp(t, 1.0).min(DRYING_CURVATURE_MAX)
                }
                Knob::CircuitDrying => spec.circuit_drying_per_s = ramp(t, DEHYDRATION_SCALE),
                Knob::SegmentR1(i) => {
                    spec.ext.segment_variation.r1_deviation[*i] = (t * SEGMENT_SCALE).exp_m1()
                }
                Knob::SegmentC(i) => {
                    spec.ext.segment_variation.c_deviation[*i] = (t * SEGMENT_SCALE).exp_m1()
                }
                Knob::SegmentK(i) => {
                    spec.ext.segment_variation.k_deviation[*i] = (t * SEGMENT_SCALE).exp_m1()
                }
                // In ascending order: each sets its mode and those above,
                // until the next one's knob.
                Knob::FreeMode(k) => spec.ext.modal_damping.free[*k..].fill(damping_ratio(t)),
                Knob::BlockedMode(k) => spec.ext.modal_damping.blocked[*k..].fill(damping_ratio(t)),
            }
        }
        if let (Some(ta), Some(tb)) = (a_theta, b_theta) {
            if self.has(Effect::BackRelaxation) {
                // a > 0 and any z = b/a: through zero to the strip that
                // ends bent the other way.
                p.a_nm_per_c = ta.exp();
                p.b_nm_per_c_s = tb * p.a_nm_per_c * p.p_per_s;
            } else {
                // The DC moment per charge b/p and the instant part a, in
                // units of the fixed model's DC moment per charge: a = 0
                // is the pure lag, z = p an ordinary point, z = 0 (b = 0
                // with a held) one knob at zero. |θ| keeps a ≥ 0 without
                // a floor the optimiser could not climb back from. b/p is
                // θ², smooth through its bound: on a logarithm, once a
                // misfit drove b/p toward 0, ln(b/p) ran off to −∞ where
                // b's gradient vanishes, and every later fit that started
                // there kept b = 0 (measured: a soft strip's stiffness fit
                // left the tip at 4.5× its noise); on |θ| a fit whose best
                // b is 0 sat on the kink and stopped short in the others.
                // (The floor keeps b > 0, which the model without
                // back-relaxation requires.)
                p.b_nm_per_c_s = (tb * tb).max(B_FLOOR) * self.instant_unit() * p.p_per_s;
                p.a_nm_per_c = ta.abs() * self.instant_unit();
            }
        }
        spec
    }

    /// `θ` to start a fit from `spec`: [`Space::theta`], with a collapsed
    /// relaxation lifted to [`P_START_MIN`], one run off to a gain brought
    /// down to [`P_START_MAX`] (its `b/p` kept) and, back-relaxed,
    /// [`A_START_MIN`] (the lag's `z` kept).
    pub fn start_theta(&self, spec: &ModelSpec) -> Vec<f64> {
        let mut lifted = *spec;
        let p = &mut lifted.params;
        p.p_per_s = p.p_per_s.max(P_MIN + P_START_MIN);
        if p.p_per_s > P_START_MAX {
            p.b_nm_per_c_s *= P_START_MAX / p.p_per_s;
            p.p_per_s = P_START_MAX;
        }
        if self.has(Effect::BackRelaxation) {
            let a = p.a_nm_per_c.max(A_START_MIN * self.instant_unit());
            if p.a_nm_per_c > 0.0 {
                p.b_nm_per_c_s *= a / p.a_nm_per_c;
            }
            p.a_nm_per_c = a;
        }
        self.theta(&lifted)
    }

    /// `θ` for a model (values outside a knob's range are pulled inside).
    pub fn theta(&self, spec: &ModelSpec) -> Vec<f64> {
        let p = &spec.params;
        let ln = |x: f64, floor: f64| x.max(floor).ln();
        self.knobs
            .iter()
            .map(|knob| match knob {
                Knob::R1 => ln(p.r1_ohm, 1e-9),
                Knob::R2 => ln(p.r2_ohm, 1e-9),
                Knob::C => ln(p.c_f, 1e-15),
                Knob::A => {
                    if self.has(Effect::BackRelaxation) {
                        ln(instant_or_gain(p), 1e-15)
                    } else {
                        p.a_nm_per_c.max(0.0) / self.instant_unit()
                    }
                }
                Knob::B => {
                    if self.has(Effect::BackRelaxation) {
                        p.b_nm_per_c_s / (instant_or_gain(p) * p.p_per_s.max(1e-9))
                    } else {
                        // A start at b = 0, where θ²'s gradient vanishes, starts
                        // just inside instead.
                        (dc_per_charge(p) / self.instant_unit())
                            .sqrt()
                            .max(B_START_MIN)
                    }
                }
                Knob::P => ln(p.p_per_s - P_MIN, 1e-9),
                Knob::Ei => ln(p.ei_nm2, 1e-15),
                Knob::Zeta => spec.ext.damping_ratio / ZETA_SCALE,
                Knob::Beta => spec.ext.damping_stiffness_s / BETA_SCALE,
                Knob::AddedMass => spec.ext.added_mass_kg_per_m / ADDED_MASS_SCALE,
                Knob::QuadraticDrag => spec.ext.drag_quadratic_n_s2_per_m3 / QUADRATIC_DRAG_SCALE,
                Knob::ChargeCubic => spec.ext.charge_cubic_per_v2 / CUBIC_SCALE,
                Knob::LeakCubic => spec.ext.leak_cubic_per_v2 / CUBIC_SCALE,
                Knob::ReactionRef => {
                    // Off, it starts at the session's highest drive.
                    if spec.ext.reaction_ratio > 0.0 {
                        spec.ext
                            .reaction_ref_v
                            .clamp(REACTION_REF_MIN_V, REACTION_REF_MAX_V)
                            .ln()
                    } else {
                        session_peak_v(&self.fixed).ln()
                    }
                }
                Knob::ReactionTafel => {
                    // Off, its Tafel voltage is unset: the start's.
                    let b = spec.ext.reaction_tafel_v;
                    if spec.ext.reaction_ratio > 0.0 && b > 0.0 {
                        b.clamp(TAFEL_MIN_V, TAFEL_MAX_V).ln()
                    } else {
                        TAFEL_START_V.ln()
                    }
                }
                Knob::Crosstalk => spec.ext.crosstalk / CROSSTALK_SCALE,
                Knob::Dehydration => spec.dehydration_per_s / DEHYDRATION_SCALE,
                Knob::DryingCurvature => spec.dehydration_curvature,
                Knob::CircuitDrying => spec.circuit_drying_per_s / DEHYDRATION_SCALE,
                Knob::SegmentR1(_) | Knob::SegmentC(_) | Knob::SegmentK(_) => {
                    Space::value(*knob, spec).max(-1.0 + 1e-9).ln_1p() / SEGMENT_SCALE
                }
                Knob::FreeMode(_) | Knob::BlockedMode(_) => Space::value(*knob, spec) / ZETA_SCALE,
            })
            .collect()
    }

    /// The value of `knob` in a model, in its own unit.
    pub fn value(knob: Knob, spec: &ModelSpec) -> f64 {
        let p = &spec.params;
        match knob {
            Knob::R1 => p.r1_ohm,
            Knob::R2 => p.r2_ohm,
            Knob::C => p.c_f,
            Knob::A => p.a_nm_per_c,
            Knob::B => p.b_nm_per_c_s,
            Knob::P => p.p_per_s,
            Knob::Ei => p.ei_nm2,
            Knob::Zeta => spec.ext.damping_ratio,
            Knob::Beta => spec.ext.damping_stiffness_s,
            Knob::AddedMass => spec.ext.added_mass_kg_per_m,
            Knob::QuadraticDrag => spec.ext.drag_quadratic_n_s2_per_m3,
            Knob::ChargeCubic => spec.ext.charge_cubic_per_v2,
            Knob::LeakCubic => spec.ext.leak_cubic_per_v2,
            Knob::ReactionRef => spec.ext.reaction_ref_v,
            Knob::ReactionTafel => spec.ext.reaction_tafel_v,
            Knob::Crosstalk => spec.ext.crosstalk,
            Knob::Dehydration => spec.dehydration_per_s,
            Knob::DryingCurvature => spec.dehydration_curvature,
            Knob::CircuitDrying => spec.circuit_drying_per_s,
            Knob::SegmentR1(i) => spec.ext.segment_variation.r1_deviation[i],
            Knob::SegmentC(i) => spec.ext.segment_variation.c_deviation[i],
            Knob::SegmentK(i) => spec.ext.segment_variation.k_deviation[i],
            Knob::FreeMode(k) => spec.ext.modal_damping.free[k],
            Knob::BlockedMode(k) => spec.ext.modal_damping.blocked[k],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::Params;

    #[test]
    fn a_start_run_off_to_a_gain_comes_down_with_its_gain_kept() {
        let fixed = ModelSpec::baseline(Params::main_m_2006());
        let mut run_off = fixed;
        run_off.params.p_per_s = 2.8e6;
        run_off.params.b_nm_per_c_s = 6.9 * 2.8e6;
        for effects in [&[][..], &[Effect::BackRelaxation][..]] {
            let space = Space::new(effects, 3, fixed);
            let start = space.spec(&space.start_theta(&run_off));
            let p = &start.params;
            assert!(
                (p.p_per_s - P_START_MAX).abs() < 1e-9,
                "{effects:?}: {}",
                p.p_per_s
            );
            let gain = p.b_nm_per_c_s / p.p_per_s;
            assert!((gain - 6.9).abs() < 1e-9 * 6.9, "{effects:?}: {gain}");
        }
        // Below the cap, the start is the model.
        let space = Space::new(&[], 3, fixed);
        let start = space.spec(&space.start_theta(&fixed));
        assert!((start.params.p_per_s - fixed.params.p_per_s).abs() < 1e-12);
    }

    #[test]
    fn the_drying_law_bends_no_further_than_its_bound() {
        let fixed = ModelSpec::baseline(Params::main_m_2006());
        let space = Space::new(&[Effect::Dehydration], 3, fixed);
        let at = |c: f64| {
            let mut theta = space.theta(&fixed);
            let k = space
                .knobs
                .iter()
                .position(|&k| k == Knob::DryingCurvature)
                .unwrap();
            theta[k] = c;
            space.spec(&theta).dehydration_curvature
        };
        assert_eq!(at(-1.0), 0.0);
        assert_eq!(at(2.0), 2.0);
        assert_eq!(at(300.0), DRYING_CURVATURE_MAX);
    }

    #[test]
    fn the_reaction_starts_at_the_sessions_peak_and_stays_in_its_range() {
        let fixed = ModelSpec::baseline(Params::main_m_2006());
        let knob = |space: &Space, k: Knob| space.knobs.iter().position(|&x| x == k).unwrap();
        // Without a session's peak, the assumed one; with it, that.
        for (peak, want) in [(0.0, PEAK_DRIVE_V), (2.5, 2.5), (40.0, REACTION_REF_MAX_V)] {
            let fixed = with_session_peak(fixed, peak);
            let space = Space::new(&[Effect::ElectrochemicalNonlinearity], 3, fixed);
            let theta = space.theta(&fixed);
            let spec = space.spec(&theta);
            assert!((spec.ext.reaction_ref_v - want).abs() < 1e-12, "{peak}");
            assert_eq!(spec.ext.reaction_ratio, 1.0);
            assert!((spec.ext.reaction_tafel_v - TAFEL_START_V).abs() < 1e-12);
            // The carried peak is no reaction in a model without it.
            assert_eq!(Space::new(&[], 3, fixed).spec(&[]).ext.reaction_ratio, 0.0);
            // Far out, each value is held at its bound.
            let mut far = theta.clone();
            far[knob(&space, Knob::ReactionRef)] = -50.0;
            far[knob(&space, Knob::ReactionTafel)] = 50.0;
            let spec = space.spec(&far);
            assert_eq!(spec.ext.reaction_ref_v, REACTION_REF_MIN_V);
            assert_eq!(spec.ext.reaction_tafel_v, TAFEL_MAX_V);
            // And a fitted reaction's θ gives it back.
            let back = space.spec(&space.theta(&spec));
            assert!((back.ext.reaction_ref_v - REACTION_REF_MIN_V).abs() < 1e-12);
        }
    }

    #[test]
    fn the_reactions_starts_span_a_volt_to_the_peak_at_each_tafel_voltage() {
        let fixed = with_session_peak(ModelSpec::baseline(Params::main_m_2006()), 3.2);
        let space = Space::new(&[Effect::ElectrochemicalNonlinearity], 3, fixed);
        let theta = space.theta(&fixed);
        let starts = space.reaction_starts(&theta);
        assert_eq!(
            starts.len(),
            REACTION_GRID_STEPS * REACTION_GRID_TAFEL_V.len()
        );
        let specs: Vec<ModelSpec> = starts.iter().map(|t| space.spec(t)).collect();
        let refs: Vec<f64> = specs.iter().map(|s| s.ext.reaction_ref_v).collect();
        assert!((refs[0] - REACTION_GRID_LOW_V).abs() < 1e-12);
        assert!((refs[refs.len() - 1] - 3.2).abs() < 1e-12);
        for s in &specs {
            assert!(REACTION_GRID_TAFEL_V
                .iter()
                .any(|b| (s.ext.reaction_tafel_v - b).abs() < 1e-12));
            // Every other knob as it was.
            assert_eq!(
                s.params.r1_ohm.to_bits(),
                space.spec(&theta).params.r1_ohm.to_bits()
            );
        }
        // A session whose peak is below a volt starts at its peak alone.
        let low = Space::new(
            &[Effect::ElectrochemicalNonlinearity],
            3,
            with_session_peak(fixed, 0.8),
        );
        let starts = low.reaction_starts(&low.theta(&low.fixed));
        assert!(starts
            .iter()
            .all(|t| (low.spec(t).ext.reaction_ref_v - 0.8).abs() < 1e-12));
        // Without the reaction, none.
        assert!(Space::new(&[Effect::Damping], 3, fixed)
            .reaction_starts(&[])
            .is_empty());
    }

    #[test]
    fn the_charge_cubic_is_at_its_floor_only_where_the_spec_clamps_it() {
        let fixed = ModelSpec::baseline(Params::main_m_2006());
        let space = Space::new(&[Effect::ElectrochemicalNonlinearity], 3, fixed);
        let j = space
            .knobs
            .iter()
            .position(|&k| k == Knob::ChargeCubic)
            .unwrap();
        let mut theta = space.theta(&fixed);
        assert!(!space.charge_cubic_at_floor(&theta));
        // Just above the floor: an estimate.
        theta[j] = CUBIC_MIN * 0.98 / CUBIC_SCALE;
        assert!(!space.charge_cubic_at_floor(&theta));
        // At it, and below (where the spec clamps it to the floor).
        for below in [0.99, 1.5] {
            theta[j] = CUBIC_MIN * below / CUBIC_SCALE;
            assert!(space.charge_cubic_at_floor(&theta));
            let spec = space.spec(&theta);
            assert!((spec.ext.charge_cubic_per_v2 - CUBIC_FLOOR).abs() < 1e-15);
        }
        // Without the effect there is no such term.
        let bare = Space::new(&[], 3, fixed);
        assert!(!bare.charge_cubic_at_floor(&bare.theta(&fixed)));
    }
}
