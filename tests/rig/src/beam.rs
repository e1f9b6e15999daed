//! The rig's cantilever: a finer Hermite-cubic mesh than any fitted model,
//! its modes, and the shape it takes.
//!
//! Freedoms are `(w, θ)` of nodes 1..=n (node 0 is clamped). A rigid load
//! cell ([`Tip::Pinned`]) pins the tip's deflection and reads the support's
//! reaction, from the pinned freedom's row of the full matrices; a load
//! cell that gives ([`Tip::Spring`]) is a spring on the tip's deflection
//! and reads its own extension.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// How the tip is held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tip {
    /// Free: the camera watches the strip.
    Free,
    /// Held at rest by a rigid load cell.
    Pinned,
    /// Held by a load cell that gives: a spring of this stiffness, N/m.
    Spring(f64),
}

impl Tip {
    /// Whether a load cell holds the tip (and the camera sees nothing).
    pub fn is_held(self) -> bool {
        self != Tip::Free
    }
}

/// Mesh, matrices and modes.
pub struct Beam {
    /// Elements along the strip.
    pub elements: usize,
    /// Element length, m.
    pub le_m: f64,
    /// Mass-normalised mode shapes, one per column.
    pub shapes: DMatrix<f64>,
    /// Angular frequency of each mode, rad/s.
    pub omega: Vec<f64>,
    /// `forcing[(k, i)]`: modal force of mode `k` per unit moment of segment `i`.
    pub forcing: DMatrix<f64>,
    /// Pinned tip: the full stiffness and mass rows of the tip's deflection
    /// over the remaining freedoms, and its load per unit moment of each
    /// segment (`None` unless pinned).
    pub reaction: Option<Reaction>,
    /// The load cell's spring at the tip, N/m ([`Tip::Spring`]).
    pub spring_n_per_m: Option<f64>,
}

/// What the pinned tip's support carries.
pub struct Reaction {
    /// Stiffness row over the free freedoms.
    pub k_row: DVector<f64>,
    /// Mass row over the free freedoms.
    pub m_row: DVector<f64>,
    /// Load on the pinned freedom per unit moment of each segment.
    pub f_row: DVector<f64>,
}

impl Beam {
    /// Builds the beam of `segments` segments, `per_segment` elements each,
    /// bending stiffness `ei`, mass per length `mass` (the fluid's added mass
    /// included), its tip held as `tip` says.
    pub fn new(
        length_m: f64,
        segments: usize,
        per_segment: usize,
        ei_nm2: f64,
        mass_kg_per_m: f64,
        tip: Tip,
    ) -> Beam {
        let blocked = tip == Tip::Pinned;
        let elements = segments * per_segment;
        let le = length_m / elements as f64;
        let n = 2 * elements;
        let mut k = DMatrix::<f64>::zeros(n, n);
        let mut m = DMatrix::<f64>::zeros(n, n);
        let ke = [
            [12.0, 6.0 * le, -12.0, 6.0 * le],
            [6.0 * le, 4.0 * le * le, -6.0 * le, 2.0 * le * le],
            [-12.0, -6.0 * le, 12.0, -6.0 * le],
            [6.0 * le, 2.0 * le * le, -6.0 * le, 4.0 * le * le],
        ];
        let me = [
            [156.0, 22.0 * le, 54.0, -13.0 * le],
            [22.0 * le, 4.0 * le * le, 13.0 * le, -3.0 * le * le],
            [54.0, 13.0 * le, 156.0, -22.0 * le],
            [-13.0 * le, -3.0 * le * le, -22.0 * le, 4.0 * le * le],
        ];
        let (kf, mf) = (ei_nm2 / le.powi(3), mass_kg_per_m * le / 420.0);
        let mut forcing_dof = DMatrix::<f64>::zeros(n, segments);
        for e in 0..elements {
            // Element e joins nodes e and e + 1; node 0's freedoms are clamped.
            let dof = |local: usize| -> Option<usize> {
                let node = e + local / 2;
                (node > 0).then(|| 2 * (node - 1) + local % 2)
            };
            for a in 0..4 {
                let Some(da) = dof(a) else { continue };
                for b in 0..4 {
                    let Some(db) = dof(b) else { continue };
                    k[(da, db)] += kf * ke[a][b];
                    m[(da, db)] += mf * me[a][b];
                }
            }
            // A uniform moment on the element: couples at its two ends.
            let seg = e / per_segment;
            if let Some(d) = dof(1) {
                forcing_dof[(d, seg)] -= 1.0;
            }
            forcing_dof[(dof(3).expect("end node is free"), seg)] += 1.0;
        }
        let spring_n_per_m = match tip {
            Tip::Spring(k_s) => {
                k[(n - 2, n - 2)] += k_s;
                Some(k_s)
            }
            _ => None,
        };
        // Pinned: the tip's deflection (freedom n − 2) leaves the system;
        // its rows stay to give the reaction.
        let keep: Vec<usize> = (0..n).filter(|&d| !(blocked && d == n - 2)).collect();
        let reaction = blocked.then(|| Reaction {
            k_row: DVector::from_iterator(keep.len(), keep.iter().map(|&d| k[(n - 2, d)])),
            m_row: DVector::from_iterator(keep.len(), keep.iter().map(|&d| m[(n - 2, d)])),
            f_row: forcing_dof.row(n - 2).transpose(),
        });
        let k = k.select_rows(&keep).select_columns(&keep);
        let m = m.select_rows(&keep).select_columns(&keep);
        let forcing_dof = forcing_dof.select_rows(&keep);
        let n = keep.len();
        // K φ = ω² M φ through M = L Lᵀ: a symmetric standard problem.
        let l = m
            .clone()
            .cholesky()
            .expect("mass matrix is positive definite")
            .l();
        let l_inv = l.clone().try_inverse().expect("triangular factor inverts");
        let a = &l_inv * &k * l_inv.transpose();
        let a = (&a + a.transpose()) * 0.5;
        let eig = SymmetricEigen::new(a);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let lt_inv = l_inv.transpose();
        let mut shapes = DMatrix::<f64>::zeros(n, n);
        let mut omega = Vec::with_capacity(n);
        for (col, &i) in order.iter().enumerate() {
            shapes.set_column(col, &(&lt_inv * eig.eigenvectors.column(i)));
            omega.push(eig.eigenvalues[i].max(0.0).sqrt());
        }
        let forcing = shapes.transpose() * forcing_dof;
        Beam {
            elements,
            le_m: le,
            shapes,
            omega,
            forcing,
            reaction,
            spring_n_per_m,
        }
    }

    /// The spring that puts the first mode of this beam, its tip on a
    /// spring, at `f_hz`, N/m, by bisection on the logarithm of the
    /// stiffness: the first mode rises from the free cantilever's towards
    /// the pinned beam's as the spring stiffens. `None` unless `f_hz` lies
    /// strictly between those two.
    pub fn spring_for_first_mode(
        length_m: f64,
        segments: usize,
        per_segment: usize,
        ei_nm2: f64,
        mass_kg_per_m: f64,
        f_hz: f64,
    ) -> Option<f64> {
        let first = |tip: Tip| {
            Beam::new(length_m, segments, per_segment, ei_nm2, mass_kg_per_m, tip).omega[0]
                / (2.0 * std::f64::consts::PI)
        };
        if !(first(Tip::Free) < f_hz && f_hz < first(Tip::Pinned)) {
            return None;
        }
        // Bracket: the tip's own bending stiffness 3EI/L³ is the scale.
        let scale = 3.0 * ei_nm2 / length_m.powi(3);
        let (mut lo, mut hi) = ((scale * 1e-6).ln(), (scale * 1e6).ln());
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if first(Tip::Spring(mid.exp())) < f_hz {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some((0.5 * (lo + hi)).exp())
    }

    /// Nodal freedoms `q` from modal coordinates `η`, the pinned tip's
    /// deflection put back as zero so that indices are the same either way.
    pub fn nodal(&self, eta: &DVector<f64>) -> DVector<f64> {
        let q = &self.shapes * eta;
        if self.reaction.is_none() {
            return q;
        }
        let n = q.len() + 1;
        DVector::from_iterator(
            n,
            (0..n).map(|d| match d.cmp(&(n - 2)) {
                std::cmp::Ordering::Less => q[d],
                std::cmp::Ordering::Equal => 0.0,
                std::cmp::Ordering::Greater => q[d - 1],
            }),
        )
    }

    /// Force on the load cell, N: the tip's load minus what its row of the
    /// beam takes elastically and inertially, from modal coordinates `η`,
    /// accelerations `η̈` and the moments `u`.
    pub fn reaction_n(&self, eta: &DVector<f64>, eta_dd: &DVector<f64>, u: &[f64]) -> f64 {
        let Some(r) = &self.reaction else {
            return 0.0;
        };
        let q = &self.shapes * eta;
        let q_dd = &self.shapes * eta_dd;
        let load: f64 = r.f_row.iter().zip(u).map(|(f, u)| f * u).sum();
        load - r.k_row.dot(&q) - r.m_row.dot(&q_dd)
    }

    /// Deflection `w` and slope `θ` at arc length `s` (small-deflection
    /// field, Hermite interpolation).
    fn field(&self, q: &DVector<f64>, s_m: f64) -> (f64, f64) {
        let le = self.le_m;
        let e = ((s_m / le).floor() as usize).min(self.elements - 1);
        let xi = (s_m / le - e as f64).clamp(0.0, 1.0);
        let node = |j: usize| {
            if j == 0 {
                (0.0, 0.0)
            } else {
                (q[2 * (j - 1)], q[2 * (j - 1) + 1])
            }
        };
        let ((w0, t0), (w1, t1)) = (node(e), node(e + 1));
        let (x2, x3) = (xi * xi, xi * xi * xi);
        let w = (1.0 - 3.0 * x2 + 2.0 * x3) * w0
            + (xi - 2.0 * x2 + x3) * le * t0
            + (3.0 * x2 - 2.0 * x3) * w1
            + (x3 - x2) * le * t1;
        let theta = (-6.0 * xi + 6.0 * x2) / le * (w0 - w1)
            + (1.0 - 4.0 * xi + 3.0 * x2) * t0
            + (3.0 * x2 - 2.0 * xi) * t1;
        (w, theta)
    }

    /// Slope `θ` at arc length `s` of the small-deflection field.
    pub fn slope(&self, q: &DVector<f64>, s_m: f64) -> f64 {
        self.field(q, s_m).1
    }

    /// Position of the point at arc length `s` relative to where it rests:
    /// `(along, across)`. Small deflection: `(0, w)`. Arcs: the slope field
    /// integrated as `x' = cos θ`, `y' = sin θ` (Simpson, 16 panels an
    /// element), so the strip keeps its length.
    pub fn position_m(&self, q: &DVector<f64>, s_m: f64, arcs: bool) -> (f64, f64) {
        if !arcs {
            return (0.0, self.field(q, s_m).0);
        }
        let panels = 16
            * self.elements.max(1)
            * ((s_m / (self.le_m * self.elements as f64)).ceil() as usize).max(1);
        let panels = panels + panels % 2;
        let h = s_m / panels as f64;
        let (mut x, mut y) = (0.0, 0.0);
        for p in 0..=panels {
            let weight = if p == 0 || p == panels {
                1.0
            } else if p % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let theta = self.field(q, p as f64 * h).1;
            x += weight * (theta.cos() - 1.0);
            y += weight * theta.sin();
        }
        (x * h / 3.0, y * h / 3.0)
    }

    /// Tip deflection, m.
    pub fn tip_m(&self, q: &DVector<f64>) -> f64 {
        q[2 * self.elements - 2]
    }
}
