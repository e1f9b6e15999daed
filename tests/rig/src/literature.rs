//! A strip from the IPMC literature rather than from the fit's own
//! equations (#49): what [`crate::strip`] runs when [`Hidden::literature`]
//! is set.
//!
//! - **Electrodes as a resistive line.** Each segment's electrode is a
//!   ladder of [`CELLS`] cells: the drive enters through a contact
//!   resistance at the segment's clamp end, runs along the platinum's
//!   surface resistance, and charges each cell's double layer through the
//!   polymer's ionic resistance; the charge (and the moment) arrives later
//!   at the segment's far end than at its contact (Shahinpoor and Kim's
//!   equivalent circuit, Chen and Tan's distributed model). The fit lumps
//!   it into one `R1`–`C`.
//! - **Electrolysis.** Behind each double layer, beside a linear leak, a
//!   Tafel reaction: nothing below its onset (water's 1.23 V), an
//!   exponential current above it. Not `sinh` about zero, not a cubic.
//! - **Viscoelastic damping.** The polymer's modulus relaxes as a Prony
//!   series of [`SPECTRUM`] terms (a generalised Maxwell solid): every
//!   mode's damping follows from one spectrum, frequency-dependent, and the
//!   strip is stiffer to a quick load than to a held one.
//! - **Drying by water content.** As the strip loses water, `C` and the
//!   moment per charge fall with it and the ionic resistance and the leak's
//!   resistance rise; not one gain on the moment.
//! - **A ruler and a balance.** The metadata's length, width and thickness
//!   are measured a few percent off, and the true mass per length is the
//!   laminate formula's only to a few percent.
//!
//! Each departure's strength is drawn from below the diagnosis's own
//! detectable level to above its plausible one ([`Strengths`]), so that a
//! sweep gives detection against strength.

use rand::Rng;

use crate::sample::{Hidden, Sample};

/// Cells along each segment's electrode line. The rig's meshes (8 and 4
/// elements a segment) give each cell whole elements.
pub const CELLS: usize = 4;

/// Terms of the modulus's relaxation spectrum.
pub const SPECTRUM: usize = 3;

/// Water's electrolysis potential, V: the reaction's onset is drawn about
/// it.
pub const WATER_SPLIT_V: f64 = 1.23;

/// The drive at which the reaction's strength is stated, V
/// (`real-benches.md`: "the steady current at 3 V can be several times a
/// linear leak's").
pub const STRENGTH_AT_V: f64 = 3.0;

/// The parts of the literature strip's base that an ablation can leave out
/// ([`Literature::without`]): `line` (each segment's electrode a lumped
/// `R1`–`C`, as the fit's), `spectrum` (no relaxing modulus: an undamped,
/// elastic beam), `ruler` (the metadata's geometry and the laminate's mass
/// per length exact).
pub const BASE_PARTS: [&str; 3] = ["line", "spectrum", "ruler"];

/// The literature strip's physics beyond [`Sample`].
#[derive(Clone, Debug, PartialEq)]
pub struct Literature {
    /// The contact's share of the series resistance `R1`; the rest is the
    /// polymer's ionic resistance, shared by the cells.
    pub contact_share: f64,
    /// The electrode's surface resistance along one segment, over `R1`.
    pub sheet_over_r1: f64,
    /// The modulus's relaxation spectrum: `(g, τ_s)` per term, `g` the
    /// term's share of the instantaneous modulus.
    pub spectrum: Vec<(f64, f64)>,
    /// `electrochemical-nonlinearity`: electrolysis behind the double
    /// layer.
    pub reaction: Option<Reaction>,
    /// `dehydration`: the strip's water content falls over the session.
    pub drying: Option<Drying>,
    /// What the metadata say over the truth: length, width, thickness.
    pub measured: [f64; 3],
    /// True mass per length over the laminate formula's.
    pub mass_factor: f64,
}

/// A Tafel reaction behind each double layer: `i = i₀ (e^{(|v| − E₀)/b} −
/// 1)` above the onset `E₀`, nothing below, the sign of `v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reaction {
    /// Onset `E₀`, V.
    pub onset_v: f64,
    /// Tafel slope over ln 10, `b`, V.
    pub tafel_v: f64,
    /// Scale `i₀`, A, for the whole segment.
    pub scale_a: f64,
    /// The strength it was drawn at: the steady current at
    /// [`STRENGTH_AT_V`] over the linear leak's, less one.
    pub extra_current: f64,
}

impl Reaction {
    /// The reaction's current at double-layer voltage `v`, A.
    pub fn current_a(&self, v: f64) -> f64 {
        let over = v.abs() - self.onset_v;
        if over <= 0.0 {
            return 0.0;
        }
        // Capped where the exponential would outrun any drive: a cell at
        // 2 V beyond the onset is never reached with a 4 V limit.
        v.signum() * self.scale_a * ((over / self.tafel_v).min(60.0).exp() - 1.0)
    }
}

/// The strip's water content `w(t)`: from 1 at the session's start down
/// to `1 − loss` at `span_s`, exponentially with time constant `tau_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drying {
    /// Water lost by `span_s`, as a fraction.
    pub loss: f64,
    /// Time constant, s.
    pub tau_s: f64,
    /// The session's span the loss is stated at, s.
    pub span_s: f64,
}

impl Drying {
    /// The loss of moment per volt over the session, `1 − (1 − loss)²`:
    /// `C` and the moment per charge both follow the water.
    pub fn moment_loss(&self) -> f64 {
        1.0 - (1.0 - self.loss).powi(2)
    }

    /// Water content at session time `t_s` (1: as wet as at the start).
    pub fn water(&self, t_s: f64) -> f64 {
        let shape = |t: f64| 1.0 - (-t / self.tau_s).exp();
        1.0 - self.loss * shape(t_s.max(0.0)) / shape(self.span_s)
    }
}

/// The true strip's first undamped angular frequencies, rad/s, with its
/// tip free and held (clamped–free and clamped–pinned Euler–Bernoulli
/// roots 1.8751 and 3.9266), on the true section and mass per length with
/// the water's added mass ([`crate::strip::section`]).
pub fn first_modes_rad_s(sample: &Sample, hidden: &Hidden) -> [f64; 2] {
    let (ei, mass) = crate::strip::section(sample, hidden);
    let scale = (ei / (mass * sample.length_m.powi(4))).sqrt();
    [1.875_104_068_7_f64, 3.926_602_312_f64].map(|beta_l| beta_l * beta_l * scale)
}

/// The departures' strengths, each in the unit of the diagnosis's own
/// probe (`identify.rs`), for power curves.
pub type Strengths = Vec<(&'static str, f64)>;

impl Literature {
    /// The base strip's own physics: the line, the spectrum, the ruler's
    /// and the balance's errors; no departure.
    pub fn draw_base(rng: &mut impl Rng) -> Literature {
        // A total relaxing share split over three terms whose times span
        // a millisecond to half a second: damping ratios of a few percent
        // over the first modes, as per-mode fits of real strips find.
        let total = rng.gen_range(0.1..0.45);
        let weights: Vec<f64> = (0..SPECTRUM).map(|_| rng.gen_range(0.2..1.0)).collect();
        let sum: f64 = weights.iter().sum();
        let spectrum = weights
            .iter()
            .map(|w| (total * w / sum, 10f64.powf(rng.gen_range(-3.0..-0.3))))
            .collect();
        let ruler = |rng: &mut dyn rand::RngCore, spread: f64| 1.0 + rng.gen_range(-spread..spread);
        Literature {
            contact_share: rng.gen_range(0.1..0.3),
            sheet_over_r1: rng.gen_range(0.15..1.0),
            spectrum,
            reaction: None,
            drying: None,
            measured: [ruler(rng, 0.01), ruler(rng, 0.02), ruler(rng, 0.04)],
            mass_factor: ruler(rng, 0.05),
        }
    }

    /// The base without `parts` (of [`BASE_PARTS`]), everything drawn as
    /// it would be with them: an ablation that tells which part of the
    /// base a diagnosis's false names come from. An unknown part is
    /// refused, naming the known ones.
    pub fn without(&mut self, parts: &[String]) -> Result<(), String> {
        for part in parts {
            match part.as_str() {
                "line" => self.sheet_over_r1 = 0.0,
                "spectrum" => self.spectrum.iter_mut().for_each(|(g, _)| *g = 0.0),
                "ruler" => {
                    self.measured = [1.0; 3];
                    self.mass_factor = 1.0;
                }
                other => {
                    return Err(format!(
                        "`{other}` is no part of the literature strip's base: {BASE_PARTS:?}"
                    ))
                }
            }
        }
        Ok(())
    }

    /// The relaxing share of the modulus, `Σ g`.
    pub fn relaxing(&self) -> f64 {
        self.spectrum.iter().map(|(g, _)| g).sum()
    }

    /// The damping ratio the spectrum gives a mode whose undamped
    /// (instantaneous-modulus) frequency is `omega0` rad/s: half the loss
    /// tangent `E''/E'` at the mode's own frequency `ω = ω₀ √E'(ω)`, with
    /// `E*/E₀ = 1 − Σ g_k / (1 + iωτ_k)`. A light damping's modal ratio
    /// (the correspondence principle); the frequency found by iteration,
    /// which settles since `E'` changes slowly with `ω`.
    pub fn mode_damping(&self, omega0: f64) -> f64 {
        let parts = |w: f64| {
            self.spectrum
                .iter()
                .fold((1.0, 0.0), |(re, im), &(g, tau)| {
                    let x = w * tau;
                    let d = 1.0 + x * x;
                    (re - g / d, im + g * x / d)
                })
        };
        let mut w = omega0;
        for _ in 0..50 {
            w = omega0 * parts(w).0.sqrt();
        }
        let (re, im) = parts(w);
        0.5 * im / re
    }

    /// The spectrum's damping ratio of the strip's first mode, free or
    /// with its tip held (the load cell's ringing), whichever is larger
    /// ([`first_modes_rad_s`]): what the diagnosis's `damping` probe
    /// measures (a constant modal ratio) at the mode that shows it best.
    pub fn first_mode_damping(&self, sample: &Sample, hidden: &Hidden) -> f64 {
        first_modes_rad_s(sample, hidden)
            .iter()
            .map(|&omega| self.mode_damping(omega))
            .fold(0.0, f64::max)
    }

    /// A reaction whose steady current at [`STRENGTH_AT_V`] is `1 + extra`
    /// times the linear leak's on the lumped strip (`R1` in series with
    /// `C` and `R2` in parallel), `extra` capped where the double layer
    /// would sit less than 0.1 V above the onset.
    pub fn reaction_for(sample: &Sample, extra: f64, onset_v: f64, tafel_v: f64) -> Reaction {
        let (r1, r2, v) = (sample.r1_ohm, sample.r2_ohm, STRENGTH_AT_V);
        let linear = v / (r1 + r2);
        let most = (v - onset_v - 0.1) / r1 / linear - 1.0;
        let extra = extra.min(most);
        let current = (1.0 + extra) * linear;
        let layer = v - r1 * current;
        let reaction = current - layer / r2;
        Reaction {
            onset_v,
            tafel_v,
            scale_a: reaction / (((layer - onset_v) / tafel_v).exp() - 1.0),
            extra_current: extra,
        }
    }

    /// Draws the literature departures among `names` on top of the base:
    /// the reaction (`electrochemical-nonlinearity`) and the drying
    /// (`dehydration`) in the forms above; the others as the off-class
    /// rig's, their strengths widened from below the diagnosis's detectable
    /// level to above its plausible one. `span_s` is the session's length.
    pub fn draw(
        names: &[&str],
        sample: &Sample,
        span_s: f64,
        rng: &mut impl Rng,
    ) -> Result<Hidden, String> {
        let base = Literature::draw_base(rng);
        let log_uniform =
            |rng: &mut dyn rand::RngCore, lo: f64, hi: f64| (rng.gen_range(lo.ln()..hi.ln())).exp();
        let others: Vec<&str> = names
            .iter()
            .copied()
            .filter(|n| !matches!(*n, "electrochemical-nonlinearity" | "dehydration"))
            .collect();
        let mut h = Hidden::draw_off_class(&others, rng)?;
        // The spectrum is the damping; no per-mode ratio besides.
        h.modal_damping = None;
        let mut lit = base;
        if names.contains(&"electrochemical-nonlinearity") {
            let extra = log_uniform(rng, 0.02, 3.0);
            let onset = WATER_SPLIT_V + rng.gen_range(-0.08..0.15);
            let tafel = rng.gen_range(0.04..0.09);
            lit.reaction = Some(Literature::reaction_for(sample, extra, onset, tafel));
        }
        if names.contains(&"dehydration") {
            // Drawn as the moment's loss s ([`Drying::moment_loss`]), the
            // water's follows.
            let s: f64 = log_uniform(rng, 0.01, 0.5);
            lit.drying = Some(Drying {
                loss: 1.0 - (1.0 - s).sqrt(),
                tau_s: rng.gen_range(60.0..600.0),
                span_s,
            });
        }
        if let Some((beta, _)) = h.back_branch.as_mut() {
            // Drawn in the probe's unit ([`back_relaxation`]), the branch's
            // β following: a β of 1 or less relaxes the strip only part
            // way, which the catalogue calls the baseline (FORMAT.md).
            let s = log_uniform(rng, 0.02, 1.0);
            *beta = 1.0 + s * sample.p_per_s / sample.z_per_s;
        }
        if let Some(k) = h.crosstalk.as_mut() {
            *k = log_uniform(rng, 0.005, 0.35);
        }
        if let Some(f) = h.segment_factors.as_mut() {
            let scale = log_uniform(rng, 0.1, 1.5);
            for s in f.iter_mut() {
                for x in [&mut s.r1, &mut s.c, &mut s.k] {
                    *x = 1.0 + (*x - 1.0) * scale;
                }
            }
        }
        h.literature = Some(lit);
        Ok(h)
    }
}

/// The strengths of what `hidden` holds on `sample`, in the diagnosis's
/// probe units (`identify.rs`): the spectrum's first-mode damping ratio,
/// the reaction's extra steady current at 3 V, the drying's loss of
/// moment per volt over the session, the back branch's `β`, the
/// crosstalk's fraction, the segments' largest departure.
pub fn strengths(sample: &Sample, hidden: &Hidden) -> Strengths {
    let mut out = Strengths::new();
    if let Some(lit) = &hidden.literature {
        if lit.relaxing() > 0.0 {
            out.push(("damping", lit.first_mode_damping(sample, hidden)));
        }
        if let Some(r) = lit.reaction {
            out.push(("electrochemical-nonlinearity", r.extra_current));
        }
        if let Some(d) = lit.drying {
            out.push(("dehydration", d.moment_loss()));
        }
    }
    if let Some((beta, _)) = hidden.back_branch {
        out.push(("back-relaxation", back_relaxation(sample, beta)));
    }
    if let Some(k) = hidden.crosstalk {
        out.push(("segment-crosstalk", k));
    }
    if let Some(f) = &hidden.segment_factors {
        let most = f
            .iter()
            .flat_map(|s| [s.r1, s.c, s.k])
            .map(|x| (x - 1.0).abs())
            .fold(0.0, f64::max);
        out.push((crate::sample::SEGMENT_VARIATION, most));
    }
    out
}

/// A back branch's strength in the diagnosis's probe unit (`identify.rs`:
/// the steady moment against the instant one, below zero, `−b/(a p)`):
/// the lead network `K (q + (z − p) r)` less the branch's `β K (z/p) b`,
/// with `r → q/p` and `b → q` held, bends `K (z/p)(1 − β) q` against the
/// instant `K q`, so `(z/p)(β − 1)`. Below zero where `β < 1`: a strip that
/// relaxes only part way, no back-relaxation.
pub fn back_relaxation(sample: &Sample, beta: f64) -> f64 {
    sample.z_per_s / sample.p_per_s * (beta - 1.0)
}

/// The diagnosis's plausible strength of each effect (`identify.rs`'s
/// probes): above it a right diagnosis must name the effect, below it
/// may.
pub fn plausible(name: &str) -> f64 {
    match name {
        "electrochemical-nonlinearity" | "dehydration" | crate::sample::SEGMENT_VARIATION => 0.1,
        "back-relaxation" => 0.2,
        "segment-crosstalk" | "damping" => 0.05,
        _ => 0.0,
    }
}

/// The literature strip's electrics: each segment a line of [`CELLS`]
/// cells (module docs).
pub(crate) struct Lines<'a> {
    pub s: &'a Sample,
    pub h: &'a Hidden,
    pub lit: &'a Literature,
}

/// Per cell: charge, the lead network's state, the back branch's; per
/// segment after its cells: the lagged charge its neighbours feel.
pub(crate) const PER_SEGMENT: usize = 3 * CELLS + 1;

/// One segment's cells at a water content.
struct Cell {
    /// Each cell's double-layer capacitance, F.
    c_f: f64,
    /// Each cell's ionic resistance, Ω.
    ionic_ohm: f64,
    /// Each cell's linear leak, Ω.
    leak_ohm: f64,
    /// The contact, Ω.
    contact_ohm: f64,
    /// The sheet between neighbouring cells, Ω.
    gap_ohm: f64,
}

impl Lines<'_> {
    fn water(&self, t_s: f64) -> f64 {
        self.lit.drying.map_or(1.0, |d| d.water(t_s))
    }

    /// Segment `i`'s cells at water content `w`.
    fn cell(&self, i: usize, w: f64) -> Cell {
        let f = self.h.segment(i);
        let n = CELLS as f64;
        let r1 = self.s.r1_ohm * f.r1;
        Cell {
            c_f: self.s.c_f * f.c * w / n,
            ionic_ohm: (1.0 - self.lit.contact_share) * r1 * n / w.powf(1.5),
            leak_ohm: self.s.r2_ohm * n / w,
            contact_ohm: self.lit.contact_share * r1,
            gap_ohm: self.lit.sheet_over_r1 * self.s.r1_ohm / n,
        }
    }

    /// The line's node potentials, V, for cell voltages `v`: a tridiagonal
    /// system (Thomas's algorithm); `drive` is `None` when the contact is
    /// open. Without a sheet resistance (an ablation) the nodes are one:
    /// the lumped circuit.
    fn nodes(cell: &Cell, v: &[f64; CELLS], drive: Option<f64>) -> [f64; CELLS] {
        if cell.gap_ohm == 0.0 {
            let g_ion = 1.0 / cell.ionic_ohm;
            let (g_c, into) = drive.map_or((0.0, 0.0), |d| {
                (1.0 / cell.contact_ohm, d / cell.contact_ohm)
            });
            let phi = (into + g_ion * v.iter().sum::<f64>()) / (g_c + CELLS as f64 * g_ion);
            return [phi; CELLS];
        }
        let (g_ion, g_s, g_c) = (
            1.0 / cell.ionic_ohm,
            1.0 / cell.gap_ohm,
            1.0 / cell.contact_ohm,
        );
        let mut diag = [0.0; CELLS];
        let mut rhs = [0.0; CELLS];
        for j in 0..CELLS {
            diag[j] = g_ion + if j > 0 { g_s } else { 0.0 } + if j + 1 < CELLS { g_s } else { 0.0 };
            rhs[j] = g_ion * v[j];
        }
        if let Some(d) = drive {
            diag[0] += g_c;
            rhs[0] += g_c * d;
        }
        // Forward sweep with off-diagonals −g_s, then back substitution.
        let mut c = [0.0; CELLS];
        let mut phi = [0.0; CELLS];
        c[0] = -g_s / diag[0];
        phi[0] = rhs[0] / diag[0];
        for j in 1..CELLS {
            let m = diag[j] + g_s * c[j - 1];
            c[j] = -g_s / m;
            phi[j] = (rhs[j] + g_s * phi[j - 1]) / m;
        }
        for j in (0..CELLS - 1).rev() {
            phi[j] -= c[j] * phi[j + 1];
        }
        phi
    }

    /// Each cell's double-layer voltage, V, from segment state `x`.
    fn voltages(cell: &Cell, x: &[f64]) -> [f64; CELLS] {
        std::array::from_fn(|j| x[3 * j] / cell.c_f)
    }

    fn derivative(
        &self,
        x: &[f64],
        volts: &[f64],
        open: Option<&[bool]>,
        t_s: f64,
        dx: &mut [f64],
    ) {
        let w = self.water(t_s);
        let p = self.s.p_per_s;
        for (i, (seg, d)) in x
            .chunks(PER_SEGMENT)
            .zip(dx.chunks_mut(PER_SEGMENT))
            .enumerate()
        {
            let cell = self.cell(i, w);
            let (r_ion, r2) = (cell.ionic_ohm, cell.leak_ohm);
            let v = Lines::voltages(&cell, seg);
            let drive = (!open.is_some_and(|o| o[i])).then(|| volts[i]);
            let phi = Lines::nodes(&cell, &v, drive);
            let mut total = 0.0;
            for j in 0..CELLS {
                let (q, r, b) = (seg[3 * j], seg[3 * j + 1], seg[3 * j + 2]);
                let reaction = self
                    .lit
                    .reaction
                    .map_or(0.0, |re| re.current_a(v[j]) / CELLS as f64);
                d[3 * j] = (phi[j] - v[j]) / r_ion - v[j] / r2 - reaction;
                d[3 * j + 1] = -p * r + q;
                d[3 * j + 2] = self.h.back_branch.map_or(0.0, |(_, tau)| (q - b) / tau);
                total += q;
            }
            d[3 * CELLS] = self
                .h
                .crosstalk_lag_s
                .map_or(0.0, |tau| (total - seg[3 * CELLS]) / tau);
        }
    }
}

impl crate::strip::Electrical for Lines<'_> {
    type X = Vec<f64>;

    fn patches(&self) -> usize {
        CELLS
    }

    fn rest(&self, segments: usize) -> Vec<f64> {
        vec![0.0; segments * PER_SEGMENT]
    }

    fn moments(&self, x: &Vec<f64>, t_s: f64, out: &mut [f64]) {
        let s = self.s;
        let w = self.water(t_s);
        let kappa = self.h.crosstalk.unwrap_or(0.0);
        // A neighbour passes on its whole charge, through the lag if any.
        let felt = |seg: &[f64]| {
            if self.h.crosstalk_lag_s.is_some() {
                seg[3 * CELLS]
            } else {
                (0..CELLS).map(|j| seg[3 * j]).sum()
            }
        };
        let segment = |i: usize| x.get(i * PER_SEGMENT..(i + 1) * PER_SEGMENT);
        for (i, seg) in x.chunks(PER_SEGMENT).enumerate() {
            let k = s.k_nm_per_c * self.h.segment(i).k * w;
            let before = i.checked_sub(1).and_then(segment).map_or(0.0, felt);
            let after = segment(i + 1).map_or(0.0, felt);
            let cross = kappa * s.k_nm_per_c * w * (before + after);
            for j in 0..CELLS {
                let (q, r, b) = (seg[3 * j], seg[3 * j + 1], seg[3 * j + 2]);
                // A cell holds 1/CELLS of the segment's charge when even:
                // its local moment is the segment's at that charge.
                let n = CELLS as f64;
                let lead = k * n * (q + (s.z_per_s - s.p_per_s) * r);
                let own = match self.h.back_branch {
                    Some((beta, _)) => lead - beta * k * n * s.z_per_s / s.p_per_s * b,
                    None => lead,
                };
                out[i * CELLS + j] = own + cross;
            }
        }
    }

    fn currents(
        &self,
        x: &Vec<f64>,
        volts: &[f64],
        open: Option<&[bool]>,
        t_s: f64,
        out: &mut [f64],
    ) {
        let w = self.water(t_s);
        for (i, seg) in x.chunks(PER_SEGMENT).enumerate() {
            if open.is_some_and(|o| o[i]) {
                out[i] = 0.0;
                continue;
            }
            let cell = self.cell(i, w);
            let phi = Lines::nodes(&cell, &Lines::voltages(&cell, seg), Some(volts[i]));
            out[i] = (volts[i] - phi[0]) / cell.contact_ohm;
        }
    }

    fn step(&self, x: &mut Vec<f64>, volts: &[f64], open: Option<&[bool]>, t_s: f64, h: f64) {
        let n = x.len();
        let mut k = [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut y = vec![0.0; n];
        self.derivative(x, volts, open, t_s, &mut k[0]);
        for stage in 1..4 {
            let f = if stage == 3 { h } else { 0.5 * h };
            for ((y, x), k) in y.iter_mut().zip(x.iter()).zip(&k[stage - 1]) {
                *y = x + f * k;
            }
            self.derivative(&y, volts, open, t_s + f, &mut k[stage]);
        }
        for (m, x) in x.iter_mut().enumerate() {
            *x += h / 6.0 * (k[0][m] + 2.0 * k[1][m] + 2.0 * k[2][m] + k[3][m]);
        }
    }
}

/// One mode's exact sub-step on the viscoelastic beam: the state
/// `[η, η̇/ω, s₁..s_K]` from itself, the modal force at the step's start
/// and its slope across it. With the modulus `E₀ (1 − Σg) + Σ` Maxwell
/// terms, the mode obeys `η̈ = f − ω₀² ((1 − Σg) η + Σ s_k)` and
/// `ṡ_k = −s_k/τ_k + g_k η̇`: `s_k` jumps with `η` on a quick load and
/// relaxes to zero under a held one.
pub(crate) struct ViscoStep {
    /// Rows of the step for each state, over `[state.., f0, slope]`.
    m: Vec<Vec<f64>>,
    /// `1 − Σg`: the relaxed share.
    relaxed: f64,
}

impl ViscoStep {
    pub(crate) fn new(omega: f64, spectrum: &[(f64, f64)], h: f64) -> ViscoStep {
        let k = spectrum.len();
        assert!(k <= SPECTRUM, "at most {SPECTRUM} terms, got {k}");
        let n = 2 + k + 2;
        let relaxed = 1.0 - spectrum.iter().map(|(g, _)| g).sum::<f64>();
        let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
        // η' = ω z; z' = f/ω − ω((1 − Σg) η + Σ s); s_k' = −s_k/τ_k + g_k ω z.
        a[(0, 1)] = omega;
        a[(1, 0)] = -omega * relaxed;
        a[(1, 2 + k)] = 1.0 / omega;
        for (m, &(g, tau)) in spectrum.iter().enumerate() {
            a[(1, 2 + m)] = -omega;
            a[(2 + m, 2 + m)] = -1.0 / tau;
            a[(2 + m, 1)] = g * omega;
        }
        a[(2 + k, 3 + k)] = 1.0;
        let e = (a * h).exp();
        let m = (0..2 + k)
            .map(|r| {
                (0..n)
                    .map(|c| if c == n - 1 { e[(r, c)] / h } else { e[(r, c)] })
                    .collect()
            })
            .collect();
        ViscoStep { m, relaxed }
    }

    /// Advances `[η, z, s..]` by one sub-step under force `f0` rising by
    /// `slope` across it.
    pub(crate) fn advance(&self, state: &mut [f64], f0: f64, slope: f64) {
        let k = state.len();
        // On the stack: this runs for every mode on every sub-step.
        let mut old = [0.0; 2 + SPECTRUM];
        old[..k].copy_from_slice(state);
        for (r, row) in self.m.iter().enumerate() {
            state[r] = row[..k]
                .iter()
                .zip(&old[..k])
                .map(|(a, x)| a * x)
                .sum::<f64>()
                + row[k] * f0
                + row[k + 1] * slope;
        }
    }

    /// The elastic coordinate `(1 − Σg) η + Σ s`: what the stiffness sees.
    pub(crate) fn elastic(&self, state: &[f64]) -> f64 {
        self.relaxed * state[0] + state[2..].iter().sum::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn sample() -> Sample {
        Sample::draw(&mut rand::rngs::StdRng::seed_from_u64(3))
    }

    #[test]
    fn a_mode_rings_down_at_the_spectrums_damping_ratio() {
        // One mode of the viscoelastic beam let go from rest at η = 1: its
        // swings shrink by e^{−ζ ω t}, to first order in the relaxing
        // share (8 % here, at Σg up to 0.3). Spectra with a term near the mode,
        // one well below it and one far above.
        let omega0 = 2.0 * std::f64::consts::PI * 40.0;
        for spectrum in [
            vec![(0.1, 1.0 / omega0)],
            vec![
                (0.05, 0.3 / omega0),
                (0.1, 3.0 / omega0),
                (0.1, 50.0 / omega0),
            ],
            vec![(0.3, 0.05 / omega0)],
        ] {
            let lit = Literature {
                spectrum: spectrum.clone(),
                ..Literature::draw_base(&mut rand::rngs::StdRng::seed_from_u64(1))
            };
            let zeta = lit.mode_damping(omega0);
            let h = 1e-5;
            let step = ViscoStep::new(omega0, &spectrum, h);
            let mut x = vec![0.0; 2 + spectrum.len()];
            x[0] = 1.0;
            // Peaks and troughs; the swing between them is free of the
            // slow terms' drifting centre.
            let mut turns = Vec::new();
            let (mut before, mut prev) = (0.0, x[0]);
            let n = (80.0 * 2.0 * std::f64::consts::PI / omega0 / h) as usize;
            for k in 0..n {
                step.advance(&mut x, 0.0, 0.0);
                let now = x[0];
                if k > 0 && (prev - before) * (now - prev) <= 0.0 {
                    turns.push((k as f64 * h, prev));
                }
                before = prev;
                prev = now;
            }
            let swing = |i: usize| (turns[i].1 - turns[i + 1].1).abs();
            // From the fortieth half-cycle to the last: by then the slow
            // terms' own transients are gone.
            let (i, j) = (40, turns.len() - 2);
            let rate = (swing(i) / swing(j)).ln() / (turns[j].0 - turns[i].0);
            let omega = std::f64::consts::PI * (j - i) as f64 / (turns[j].0 - turns[i].0);
            let measured = rate / omega;
            assert!(
                (measured - zeta).abs() < 0.08 * zeta,
                "{spectrum:?}: rings at {measured:.5}, the loss tangent says {zeta:.5}"
            );
        }
    }

    #[test]
    fn the_reaction_gives_the_drawn_extra_current_on_the_lumped_strip() {
        let s = sample();
        for extra in [0.05, 0.5, 1.5] {
            let r = Literature::reaction_for(&s, extra, 1.25, 0.06);
            assert!(
                (r.extra_current - extra).abs() < 1e-12,
                "not capped at {extra}"
            );
            // The steady state's double layer, by bisection on its balance.
            let balance = |v: f64| (STRENGTH_AT_V - v) / s.r1_ohm - v / s.r2_ohm - r.current_a(v);
            let (mut lo, mut hi) = (0.0, STRENGTH_AT_V);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if balance(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let current = (STRENGTH_AT_V - lo) / s.r1_ohm;
            let linear = STRENGTH_AT_V / (s.r1_ohm + s.r2_ohm);
            assert!(
                (current / linear - 1.0 - extra).abs() < 1e-6,
                "{extra}: {}",
                current / linear - 1.0
            );
            // Nothing flows below the onset.
            assert_eq!(r.current_a(1.2), 0.0);
            assert!(r.current_a(-2.0) < 0.0);
        }
    }

    #[test]
    fn the_line_settles_to_the_lumped_circuits_current() {
        use crate::strip::Electrical;
        let s = sample();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let h = Hidden {
            literature: Some(Literature::draw_base(&mut rng)),
            ..Hidden::default()
        };
        let lit = h.literature.as_ref().unwrap();
        let lines = Lines { s: &s, h: &h, lit };
        let mut x = lines.rest(1);
        let dt = 1e-4;
        let mut i = [0.0];
        // The first instant: the contact, then the cells in parallel but
        // the far ones behind the sheet: less than the lumped R1's current,
        // more than with the whole sheet in series.
        lines.currents(&x, &[2.0], None, 0.0, &mut i);
        let r_sheet = lit.sheet_over_r1 * s.r1_ohm;
        assert!(
            i[0] < 2.0 / s.r1_ohm && i[0] > 2.0 / (s.r1_ohm + r_sheet),
            "{} against {} and {}",
            i[0],
            2.0 / s.r1_ohm,
            2.0 / (s.r1_ohm + r_sheet)
        );
        for _ in 0..(5.0 / dt) as usize {
            lines.step(&mut x, &[2.0], None, 0.0, dt);
        }
        lines.currents(&x, &[2.0], None, 0.0, &mut i);
        let lumped = 2.0 / (s.r1_ohm + s.r2_ohm);
        // At rest the sheet carries the leak: within its own drop.
        assert!(
            (i[0] / lumped - 1.0).abs() < 0.05,
            "{} against {lumped}",
            i[0]
        );
        // The far cell holds less charge than the near one on the way.
        let mut y = lines.rest(1);
        for _ in 0..20 {
            lines.step(&mut y, &[2.0], None, 0.0, dt);
        }
        assert!(y[0] > y[3 * (CELLS - 1)]);
    }

    #[test]
    fn without_its_line_the_strip_charges_as_the_lumped_circuit() {
        use crate::strip::Electrical;
        let s = sample();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut lit = Literature::draw_base(&mut rng);
        let drawn = lit.clone();
        lit.without(&["line".to_string()]).unwrap();
        assert_eq!(lit.sheet_over_r1, 0.0);
        assert_eq!(
            (&lit.spectrum, lit.measured),
            (&drawn.spectrum, drawn.measured)
        );
        let h = Hidden {
            literature: Some(lit),
            ..Hidden::default()
        };
        let lines = Lines {
            s: &s,
            h: &h,
            lit: h.literature.as_ref().unwrap(),
        };
        // R1 in series with C and R2 across C: i(t) = V/(R1+R2) + V R2/(R1 (R1+R2)) e^{−t/τ},
        // τ = C R1 R2/(R1+R2).
        let (r1, r2, c) = (s.r1_ohm, s.r2_ohm, s.c_f);
        let tau = c * r1 * r2 / (r1 + r2);
        let want = |t: f64| 2.0 / (r1 + r2) + 2.0 * r2 / (r1 * (r1 + r2)) * (-t / tau).exp();
        let (mut x, dt, mut i) = (lines.rest(1), tau / 400.0, [0.0]);
        for k in 0..2000 {
            let t = k as f64 * dt;
            lines.currents(&x, &[2.0], None, 0.0, &mut i);
            assert!(
                (i[0] / want(t) - 1.0).abs() < 1e-6,
                "t = {t}: {} against {}",
                i[0],
                want(t)
            );
            lines.step(&mut x, &[2.0], None, 0.0, dt);
        }
        // The other parts, and a name that is none.
        let mut lit = drawn.clone();
        lit.without(&["spectrum".to_string(), "ruler".to_string()])
            .unwrap();
        assert_eq!(lit.relaxing(), 0.0);
        assert_eq!((lit.measured, lit.mass_factor), ([1.0; 3], 1.0));
        assert_eq!(lit.sheet_over_r1, drawn.sheet_over_r1);
        let e = lit.without(&["sheet".to_string()]).unwrap_err();
        assert!(e.contains("`sheet`") && e.contains("line"), "{e}");
    }

    #[test]
    fn a_viscoelastic_mode_is_stiffer_to_a_quick_load_than_to_a_held_one() {
        let omega = 2.0 * std::f64::consts::PI * 10.0;
        let spectrum = [(0.1, 0.01), (0.1, 0.1), (0.1, 1.0)];
        let h = 1e-4;
        let step = ViscoStep::new(omega, &spectrum, h);
        let mut x = vec![0.0; 2 + spectrum.len()];
        let f = 1.0;
        let mut peak: f64 = 0.0;
        for _ in 0..(20.0 / h) as usize {
            step.advance(&mut x, f, 0.0);
            peak = peak.max(x[0]);
        }
        // Held for 20 τ of the slowest term: the relaxed modulus's static
        // deflection, and the internal terms gone.
        let held = f / (omega * omega * 0.7);
        assert!((x[0] / held - 1.0).abs() < 1e-3, "{} against {held}", x[0]);
        assert!(x[2..].iter().all(|s| s.abs() < 1e-3 * held));
        // Damped: the first overshoot is below an undamped one's (twice
        // the instantaneous modulus's static deflection from rest).
        assert!(peak < 2.0 * held);
        assert!(step.elastic(&x) > 0.0);
    }

    #[test]
    fn drying_reaches_its_loss_at_the_span() {
        let d = Drying {
            loss: 0.2,
            tau_s: 100.0,
            span_s: 300.0,
        };
        assert_eq!(d.water(0.0), 1.0);
        assert!((d.water(300.0) - 0.8).abs() < 1e-12);
        assert!(d.water(150.0) < 0.9);
    }
}
