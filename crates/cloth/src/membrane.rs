//! A continuum cloth model whose refinement converges: constant-strain triangles for the membrane and
//! a quadratic discrete-shell element for bending, beside the theses' springs.
//!
//! Why. A spring network's response depends on its mesh: its stretch stiffness follows from the
//! springs' layout and its bending stiffness from springs of fixed k across two cells, so two uniform
//! meshes of one sheet do not approach one another as they are refined (13 × 13 and 17 × 17 springs
//! differ by centimetres), and "error against the fine mesh" measures the mesh, not the method. The
//! model here is a discretisation of one continuum: the membrane energy and the bending energy of a
//! sheet with given E·t, ν and bending rigidity, so that uniform meshes 9 × 9 … 65 × 65 approach one
//! another (`cargo xtask reproduce membrane` measures it) and adaptive meshes can be compared with
//! uniform ones fairly.
//!
//! **Membrane: co-rotational constant-strain triangles** (Etzmuss, Keckeisen & Straßer 2003). Each
//! triangle keeps its rest shape in a 2-D frame, D_m (its two edges there). The deformation gradient
//! F = D_s D_m⁻¹ (3 × 2, D_s the current edges) is split by the polar decomposition F = R S (R with
//! orthonormal columns, S symmetric 2 × 2), the strain is ε = S − I and the energy
//!
//! W = A (μ ε:ε + ½ λ (tr ε)²),   μ = Y / (2 (1 + ν)),   λ = Y ν / (1 − ν²)   (plane stress),
//!
//! Y = E·t in N/m and A the rest area. Its exact gradient is P = R (2μ ε + λ tr ε I) (the rotation's
//! derivative drops out of this energy), so f_a = −A P g_a with F = Σ_a x_a g_aᵀ. The stiffness keeps R
//! fixed (the usual co-rotational linearisation):
//!
//! ∂f_a/∂x_b = −A [μ ((g_a·g_b) R Rᵀ + w_b w_aᵀ) + λ w_a w_bᵀ],   w_a = R g_a,
//!
//! symmetric and negative semi-definite, which the implicit integrators need. It leaves out the
//! stress's own stiffness (the geometric term), as the clamped spring Jacobians leave out compression.
//!
//! **Bending: the quadratic model of Bergou, Wardetzky, Harmon, Zorin & Grinspun** ("A quadratic
//! bending model for inextensible surfaces", 2006): the discrete-shell energy of an initially flat
//! sheet at isometric deformation, per interior edge (x₀, x₁) with opposite vertices x₂, x₃,
//!
//! E_e = ½ k_b / (A₁ + A₂) · |Σ_r K_r x_r|²,   K = (c₀₃ + c₀₄, c₀₁ + c₀₂, −c₀₁ − c₀₃, −c₀₂ − c₀₄),
//!
//! the c the cotangents of the rest angles at the edge and A₁, A₂ the rest areas of its triangles (the
//! paper's weight carries another constant factor; this one is fixed so that Σ_e converges to
//! ½ k_b ∫ |Δx|² dA, the bending energy of a plate of rigidity k_b = E t³ / (12 (1 − ν²)) (N·m) bent
//! without stretching: the test `a_cylinder_has_the_continuum_bending_energy` checks it). Its Hessian is
//! constant, −k_b/(A₁ + A₂) K Kᵀ per edge (times I₃).
//!
//! **Damping** is stiffness-proportional (Rayleigh): f_d = c_d K v, the viscous stress of a material
//! whose stress relaxes in c_d seconds, the same on every mesh. A mode of frequency ω is damped with ratio
//! c_d ω / 2: the unresolved stretch modes of a fine mesh are overdamped, the folds hardly.
//!
//! Masses are lumped (a third of each triangle's mass to each corner). Everything is f64; the model
//! implements [`OdeSystem`] and [`Linearized`], so every integrator of `anima_ode` steps it.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk the corners of an element and the pattern slots in step"
)]

use std::collections::HashMap;

use anima_geom::DVec3;
use anima_ode::{Integrator, Jacobians, Linearized, OdeSystem, State, Stepper};
use glam::DMat3;

use crate::bounds::{BoundsWatch, Defaults};
use crate::error::{NonFinite, StepError};

/// The material of a [`Membrane`], in the units of its field names.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MembraneMaterial {
    /// Stretch stiffness Y = E·t, N/m.
    #[serde(rename = "young_thickness_n_m")]
    pub young_thickness: f64,
    /// Poisson's ratio ν, in [0, 0.5).
    pub poisson: f64,
    /// Bending rigidity k_b, N·m (E t³ / (12 (1 − ν²)) for a plate).
    #[serde(rename = "bending_n_m")]
    pub bending: f64,
    /// Stiffness-proportional damping c_d, s.
    #[serde(rename = "damping_s")]
    pub damping: f64,
}

impl MembraneMaterial {
    /// The material that stands beside the standard sheet's springs: Y = 1000 N/m (the structural
    /// springs' 1000 N/m on a square grid), ν = 0.3, k_b = 10⁻³ N·m, c_d = 10⁻³ s.
    pub const STANDARD: Self = Self { young_thickness: 1000.0, poisson: 0.3, bending: 1e-3, damping: 1e-3 };

    /// Lamé's μ and λ of plane stress.
    pub fn lame(&self) -> (f64, f64) {
        let (y, nu) = (self.young_thickness, self.poisson);
        (y / (2.0 * (1.0 + nu)), y * nu / (1.0 - nu * nu))
    }
}

/// Why a membrane was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MembraneError {
    #[error("triangle {triangle} names vertex {index}, but there are {n} vertices")]
    BadIndex { triangle: usize, index: u32, n: usize },
    #[error("triangle {0} has no area at rest")]
    Degenerate(usize),
    #[error("the material is not usable: {0}")]
    BadMaterial(&'static str),
    #[error("the surface density must be positive and finite")]
    BadDensity,
    #[error("the sheet: {0}")]
    Sheet(String),
    #[error("expected one {what} per vertex ({n}), found {found}")]
    Count { what: &'static str, n: usize, found: usize },
    #[error("the time step must be positive and finite, found {0} s")]
    Step(f64),
}

/// One triangle's rest shape: the gradient weights g₁, g₂ (rows of D_m⁻¹; g₀ = −g₁ − g₂), its rest area
/// and its pattern slots for the corner pairs (0, 1), (0, 2), (1, 2).
#[derive(Debug, Clone, Copy)]
struct Element {
    v: [u32; 3],
    g: [[f64; 2]; 3],
    area: f64,
    slots: [u32; 3],
}

/// One interior edge's bending stencil: its four vertices, the weights K, k_b/(A₁ + A₂) and the pattern
/// slots of its six vertex pairs in the order (0,1), (0,2), (0,3), (1,2), (1,3), (2,3).
#[derive(Debug, Clone, Copy)]
struct Hinge {
    v: [u32; 4],
    k: [f64; 4],
    scale: f64,
    slots: [u32; 6],
}

impl Hinge {
    /// Σ_r K_r y_r.
    #[inline]
    fn curvature(&self, y: &[DVec3]) -> DVec3 {
        let v = self.v.map(|i| y[i as usize]);
        v[0] * self.k[0] + v[1] * self.k[1] + v[2] * self.k[2] + v[3] * self.k[3]
    }
}

const PAIRS4: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
const PAIRS3: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// A triangle-mesh sheet of co-rotational membrane elements and quadratic bending hinges, with pins and
/// gravity. Pinned vertices keep their velocity.
#[derive(Debug, Clone)]
pub struct Membrane {
    material: MembraneMaterial,
    masses: Vec<f64>,
    inv_masses: Vec<f64>,
    pinned: Vec<bool>,
    pub gravity: DVec3,
    elements: Vec<Element>,
    hinges: Vec<Hinge>,
    pattern: Vec<(u32, u32)>,
}

impl Membrane {
    /// Builds the model on `triangles` over the rest positions `rest` (each triangle's rest shape is its
    /// shape there; the bending model takes the rest surface to be flat), with surface density `density`
    /// (kg/m²).
    pub fn new(
        rest: &[DVec3],
        triangles: &[[u32; 3]],
        material: MembraneMaterial,
        density: f64,
        pinned: Vec<bool>,
        gravity: DVec3,
    ) -> Result<Self, MembraneError> {
        let n = rest.len();
        if pinned.len() != n {
            return Err(MembraneError::Count { what: "pin flag", n, found: pinned.len() });
        }
        let m = material;
        if !(m.young_thickness.is_finite() && m.young_thickness >= 0.0) {
            return Err(MembraneError::BadMaterial("E·t must be finite and non-negative"));
        }
        if !(m.poisson.is_finite() && (0.0..0.5).contains(&m.poisson)) {
            return Err(MembraneError::BadMaterial("Poisson's ratio must lie in [0, 0.5)"));
        }
        if !(m.bending.is_finite() && m.bending >= 0.0 && m.damping.is_finite() && m.damping >= 0.0) {
            return Err(MembraneError::BadMaterial("bending and damping must be finite and non-negative"));
        }
        if !(density.is_finite() && density > 0.0) {
            return Err(MembraneError::BadDensity);
        }
        let mut slot_of: HashMap<(u32, u32), u32> = HashMap::new();
        let mut pattern = Vec::new();
        let mut slot = |a: u32, b: u32| -> u32 {
            let key = (a.min(b), a.max(b));
            *slot_of.entry(key).or_insert_with(|| {
                pattern.push(key);
                pattern.len() as u32 - 1
            })
        };
        let mut masses = vec![0.0; n];
        let mut elements = Vec::with_capacity(triangles.len());
        // Interior edges: the triangles on each side and their third vertices.
        let mut edge_sides: HashMap<(u32, u32), Vec<(usize, u32)>> = HashMap::new();
        for (t, tri) in triangles.iter().enumerate() {
            for &index in tri {
                if index as usize >= n {
                    return Err(MembraneError::BadIndex { triangle: t, index, n });
                }
            }
            let [p0, p1, p2] = tri.map(|k| rest[k as usize]);
            let (e1, e2) = (p1 - p0, p2 - p0);
            let normal = e1.cross(e2);
            let area = 0.5 * normal.length();
            if !(area > 0.0 && area.is_finite()) || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return Err(MembraneError::Degenerate(t));
            }
            // D_m in the frame (u, n × u) of the triangle's plane; its inverse's rows are g₁ and g₂.
            let u = e1.normalize();
            let w = normal.normalize().cross(u);
            let (a, b, c, d) = (e1.length(), e2.dot(u), 0.0, e2.dot(w));
            let det = a * d - b * c;
            let inv = [[d / det, -b / det], [-c / det, a / det]];
            let g1 = inv[0];
            let g2 = inv[1];
            let g0 = [-g1[0] - g2[0], -g1[1] - g2[1]];
            for &k in tri {
                masses[k as usize] += density * area / 3.0;
            }
            let slots = PAIRS3.map(|(p, q)| slot(tri[p], tri[q]));
            elements.push(Element { v: *tri, g: [g0, g1, g2], area, slots });
            for (p, q, r) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
                let key = (tri[p].min(tri[q]), tri[p].max(tri[q]));
                edge_sides.entry(key).or_default().push((t, tri[r]));
            }
        }
        // A vertex no triangle uses is a free particle: it gets the smallest mass of the others.
        let least = masses.iter().copied().filter(|&m| m > 0.0).fold(f64::INFINITY, f64::min);
        for m in masses.iter_mut().filter(|m| **m <= 0.0) {
            *m = if least.is_finite() { least } else { density };
        }
        let mut edges: Vec<_> = edge_sides.into_iter().filter(|(_, s)| s.len() == 2).collect();
        edges.sort_unstable_by_key(|(e, _)| *e);
        let mut hinges = Vec::with_capacity(edges.len());
        for ((i0, i1), sides) in edges {
            let v = [i0, i1, sides[0].1, sides[1].1];
            let [x0, x1, x2, x3] = v.map(|k| rest[k as usize]);
            let cot = |a: DVec3, b: DVec3| a.dot(b) / a.cross(b).length();
            let (e0, e1, e2, e3, e4) = (x1 - x0, x2 - x0, x3 - x0, x2 - x1, x3 - x1);
            let (c01, c02, c03, c04) = (cot(e0, e1), cot(e0, e2), cot(-e0, e3), cot(-e0, e4));
            let k = [c03 + c04, c01 + c02, -c01 - c03, -c02 - c04];
            let areas = elements[sides[0].0].area + elements[sides[1].0].area;
            let scale = material.bending / areas;
            let slots = PAIRS4.map(|(p, q)| slot(v[p], v[q]));
            hinges.push(Hinge { v, k, scale, slots });
        }
        Ok(Self {
            material,
            inv_masses: masses.iter().map(|m| 1.0 / m).collect(),
            masses,
            pinned,
            gravity,
            elements,
            hinges,
            pattern,
        })
    }

    pub fn n_vertices(&self) -> usize {
        self.masses.len()
    }

    pub fn n_triangles(&self) -> usize {
        self.elements.len()
    }

    /// Interior edges, each one bending hinge.
    pub fn n_hinges(&self) -> usize {
        self.hinges.len()
    }

    pub fn material(&self) -> MembraneMaterial {
        self.material
    }

    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// Elastic energy at x: membrane and bending, J.
    pub fn elastic_energy(&self, x: &[DVec3]) -> (f64, f64) {
        let (mu, lambda) = self.material.lame();
        let mut membrane = 0.0;
        for e in &self.elements {
            if let Some((_, strain)) = rotation_and_strain(e, x) {
                let tr = strain[0][0] + strain[1][1];
                let dd = strain[0][0].powi(2) + 2.0 * strain[0][1].powi(2) + strain[1][1].powi(2);
                membrane += e.area * (mu * dd + 0.5 * lambda * tr * tr);
            }
        }
        let mut bending = 0.0;
        for h in &self.hinges {
            bending += 0.5 * h.scale * h.curvature(x).length_squared();
        }
        (membrane, bending)
    }

    /// Mass-weighted centre of the vertices at x.
    pub fn centre_of_mass(&self, x: &[DVec3]) -> DVec3 {
        let total: f64 = self.masses.iter().sum();
        x.iter().zip(&self.masses).map(|(p, m)| *p * *m).sum::<DVec3>() / total
    }

    /// The largest principal strain of any triangle at x (its largest singular value of F less one).
    pub fn max_strain(&self, x: &[DVec3]) -> f64 {
        let mut worst = 0.0f64;
        for e in &self.elements {
            if let Some((_, eps)) = rotation_and_strain(e, x) {
                // The larger eigenvalue of the symmetric 2 × 2 ε.
                let (a, b, c) = (eps[0][0], eps[0][1], eps[1][1]);
                let largest = 0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt();
                worst = worst.max(largest);
            }
        }
        worst
    }

    /// Kinetic energy at v, J.
    pub fn kinetic_energy(&self, v: &[DVec3]) -> f64 {
        v.iter().zip(&self.masses).map(|(v, m)| 0.5 * m * v.length_squared()).sum()
    }

    /// Adds the elastic and damping forces at (x, v) to `f`; with `jac`, also their Jacobians (K to
    /// `k_*`, D = c_d K to `d_*`).
    pub(crate) fn add_forces(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        mut jac: Option<&mut Jacobians<DVec3>>,
    ) {
        let (mu, lambda) = self.material.lame();
        let cd = self.material.damping;
        // The element's stiffness blocks are needed for its damping force and for the Jacobians only.
        let with_blocks = cd > 0.0 || jac.is_some();
        let mut blocks = [[DMat3::ZERO; 3]; 3];
        for e in &self.elements {
            let Some((r, strain)) = rotation_and_strain(e, x) else {
                continue;
            };
            let tr = strain[0][0] + strain[1][1];
            // σ = 2μ ε + λ tr ε I, P = R σ (3 × 2, columns r·σ).
            let sigma = [
                [2.0 * mu * strain[0][0] + lambda * tr, 2.0 * mu * strain[0][1]],
                [2.0 * mu * strain[1][0], 2.0 * mu * strain[1][1] + lambda * tr],
            ];
            let p = [r[0] * sigma[0][0] + r[1] * sigma[1][0], r[0] * sigma[0][1] + r[1] * sigma[1][1]];
            if with_blocks {
                let w = e.g.map(|g| r[0] * g[0] + r[1] * g[1]);
                let rrt = outer(r[0], r[0]) + outer(r[1], r[1]);
                for a in 0..3 {
                    for b in 0..3 {
                        let gg = e.g[a][0] * e.g[b][0] + e.g[a][1] * e.g[b][1];
                        blocks[a][b] =
                            (rrt * (mu * gg) + outer(w[b], w[a]) * mu + outer(w[a], w[b]) * lambda)
                                * (-e.area);
                    }
                }
            }
            for a in 0..3 {
                let ia = e.v[a] as usize;
                let mut fa = -(p[0] * e.g[a][0] + p[1] * e.g[a][1]) * e.area;
                if cd > 0.0 {
                    for b in 0..3 {
                        fa += blocks[a][b] * v[e.v[b] as usize] * cd;
                    }
                }
                f[ia] += fa;
            }
            if let Some(jac) = jac.as_deref_mut() {
                for a in 0..3 {
                    let ia = e.v[a] as usize;
                    jac.k_diag[ia] += blocks[a][a];
                    jac.d_diag[ia] += blocks[a][a] * cd;
                }
                for (s, &(a, b)) in PAIRS3.iter().enumerate() {
                    // The pattern pair is (min, max): ∂f_min/∂x_max.
                    let block = if e.v[a] < e.v[b] { blocks[a][b] } else { blocks[b][a] };
                    let slot = e.slots[s] as usize;
                    jac.k_off[slot] += block;
                    jac.d_off[slot] += block * cd;
                }
            }
        }
        for h in &self.hinges {
            // f_r = −(k_b/(A₁ + A₂)) K_r Σ_c K_c (x_c + c_d v_c).
            let kx = (h.curvature(x) + h.curvature(v) * cd) * h.scale;
            for r in 0..4 {
                f[h.v[r] as usize] -= kx * h.k[r];
            }
            if let Some(jac) = jac.as_deref_mut() {
                for r in 0..4 {
                    let k = DMat3::from_diagonal(DVec3::splat(-h.scale * h.k[r] * h.k[r]));
                    jac.k_diag[h.v[r] as usize] += k;
                    jac.d_diag[h.v[r] as usize] += k * cd;
                }
                for (s, &(r, c)) in PAIRS4.iter().enumerate() {
                    let k = DMat3::from_diagonal(DVec3::splat(-h.scale * h.k[r] * h.k[c]));
                    let slot = h.slots[s] as usize;
                    jac.k_off[slot] += k;
                    jac.d_off[slot] += k * cd;
                }
            }
        }
    }

    fn gravity_forces(&self, f: &mut [DVec3]) {
        for (fi, m) in f.iter_mut().zip(&self.masses) {
            *fi = self.gravity * *m;
        }
    }
}

/// a bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// The polar decomposition of a triangle's F = R S at x: R's two columns and ε = S − I; `None` for a
/// triangle collapsed to a point.
fn rotation_and_strain(e: &Element, x: &[DVec3]) -> Option<([DVec3; 2], [[f64; 2]; 2])> {
    let [x0, x1, x2] = e.v.map(|k| x[k as usize]);
    let (d1, d2) = (x1 - x0, x2 - x0);
    // F's columns: F = D_s D_m⁻¹ = d1 g₁ᵀ + d2 g₂ᵀ.
    let f = [d1 * e.g[1][0] + d2 * e.g[2][0], d1 * e.g[1][1] + d2 * e.g[2][1]];
    let c = [[f[0].dot(f[0]), f[0].dot(f[1])], [f[0].dot(f[1]), f[1].dot(f[1])]];
    // S = √C = (C + √det C I) / √(tr C + 2 √det C) for a symmetric positive semi-definite 2 × 2 C.
    let s_det = (c[0][0] * c[1][1] - c[0][1] * c[0][1]).max(0.0).sqrt();
    let denom = (c[0][0] + c[1][1] + 2.0 * s_det).sqrt();
    if denom.is_nan() || denom <= 0.0 {
        return None;
    }
    let s = [[(c[0][0] + s_det) / denom, c[0][1] / denom], [c[0][1] / denom, (c[1][1] + s_det) / denom]];
    let det_s = s[0][0] * s[1][1] - s[0][1] * s[1][0];
    // R = F S⁻¹; a triangle squashed onto a line (det S = 0) keeps the stretch along it and no rotation
    // out of it: its force still pulls it back.
    let r = if det_s > 1e-300 {
        let inv = [[s[1][1] / det_s, -s[0][1] / det_s], [-s[1][0] / det_s, s[0][0] / det_s]];
        [f[0] * inv[0][0] + f[1] * inv[1][0], f[0] * inv[0][1] + f[1] * inv[1][1]]
    } else {
        let u = if f[0].length_squared() >= f[1].length_squared() { f[0] } else { f[1] }.normalize();
        let w = u.any_orthonormal_vector();
        [u, w]
    };
    let strain = [[s[0][0] - 1.0, s[0][1]], [s[1][0], s[1][1] - 1.0]];
    Some((r, strain))
}

impl OdeSystem for Membrane {
    type Coord = DVec3;

    fn n_coords(&self) -> usize {
        self.masses.len()
    }

    fn acceleration(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], a: &mut [DVec3]) {
        self.gravity_forces(a);
        self.add_forces(x, v, a, None);
        for ((ai, inv_m), &pin) in a.iter_mut().zip(&self.inv_masses).zip(&self.pinned) {
            *ai = if pin { DVec3::ZERO } else { *ai * *inv_m };
        }
    }

    fn linearized(&mut self) -> Option<&mut dyn Linearized<DVec3>> {
        Some(self)
    }
}

impl Linearized<DVec3> for Membrane {
    fn masses(&self) -> &[f64] {
        &self.masses
    }

    fn prescribed(&self) -> &[bool] {
        &self.pinned
    }

    fn pattern(&self) -> &[(u32, u32)] {
        &self.pattern
    }

    fn force_and_jacobians(
        &mut self,
        _t: f64,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        jac: &mut Jacobians<DVec3>,
    ) {
        self.gravity_forces(f);
        self.add_forces(x, v, f, Some(jac));
    }

    fn force(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], _scratch: &mut Jacobians<DVec3>) {
        self.gravity_forces(f);
        self.add_forces(x, v, f, None);
    }
}

/// A membrane stepped at a constant step by one of `anima_ode`'s fixed-step integrators, checked for
/// non-finite values after every step.
#[derive(Debug)]
pub struct MembraneSim {
    pub membrane: Membrane,
    stepper: Stepper<DVec3>,
    pub state: State<DVec3>,
    next: State<DVec3>,
    dt: f64,
    step: u64,
    /// Linear-solver iterations of the implicit steps so far.
    pub solver_iterations: usize,
    /// The physical bounds the run is checked against ([`crate::bounds`]: speed and energy; a
    /// membrane has no springs whose strain to bound).
    pub bounds: BoundsWatch,
}

impl MembraneSim {
    /// At rest at `x`; a position count other than the membrane's, or a step that is not positive and
    /// finite, is an error.
    pub fn new(
        membrane: Membrane,
        x: Vec<DVec3>,
        integrator: Integrator,
        dt: f64,
    ) -> Result<Self, MembraneError> {
        let n = x.len();
        if n != membrane.n_vertices() {
            return Err(MembraneError::Count { what: "position", n: membrane.n_vertices(), found: n });
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(MembraneError::Step(dt));
        }
        let state = State::new(x, vec![DVec3::ZERO; n]);
        let defaults = Defaults::passive(membrane.gravity);
        let bounds = BoundsWatch::new(defaults, &state.x, &state.v, membrane.masses(), membrane.gravity, 0.0);
        Ok(Self {
            bounds,
            membrane,
            stepper: Stepper::new(integrator, n),
            next: state.clone(),
            state,
            dt,
            step: 0,
            solver_iterations: 0,
        })
    }

    pub fn stepper_mut(&mut self) -> &mut Stepper<DVec3> {
        &mut self.stepper
    }

    pub fn time(&self) -> f64 {
        self.step as f64 * self.dt
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.step
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Every vertex's position.
    pub fn positions(&self) -> &[DVec3] {
        &self.state.x
    }

    pub fn velocities(&self) -> &[DVec3] {
        &self.state.v
    }

    /// Replaces every vertex's position and velocity; a multistep or implicit integrator starts its
    /// history again, the step count and time go on.
    ///
    /// # Panics
    /// If `x` or `v` does not hold one value per vertex.
    pub fn set_state(&mut self, x: &[DVec3], v: &[DVec3]) {
        assert!(x.len() == self.state.x.len() && v.len() == x.len(), "one position and velocity per vertex");
        self.state.x.copy_from_slice(x);
        self.state.v.copy_from_slice(v);
        self.stepper.reset_history();
    }

    /// Takes the bounds from the state as it is now (what the first step of [`MembraneSim::run`] does).
    pub fn restart_bounds(&mut self) {
        let (x, v, m) = (&self.state.x, &self.state.v, self.membrane.masses());
        self.bounds.restart(x, v, m, self.membrane.gravity, 0.0);
    }

    /// Checks the state as it is now against the bounds, for a caller that integrates the membrane's
    /// system itself (an adaptive integrator under its step controller, after
    /// [`MembraneSim::restart_bounds`]): `step` and `time` are the caller's count and clock, for the
    /// error.
    pub fn check_bounds_at(&self, step: u64, time: f64) -> Result<(), StepError> {
        let (x, v, m) = (&self.state.x, &self.state.v, self.membrane.masses());
        Ok(self.bounds.check(step, time, x, v, m, self.membrane.gravity, std::iter::empty())?)
    }

    /// Takes `n` steps; stops at the first that fails, leaves a non-finite value or leaves the bounds
    /// (checked every step for implicit integrators, every few dozen for explicit ones).
    pub fn run(&mut self, n: usize) -> Result<(), StepError> {
        let every =
            if self.stepper.integrator().is_implicit() { 1 } else { crate::bounds::EXPLICIT_CHECK_EVERY };
        if self.step == 0 {
            self.restart_bounds();
        }
        for k in 0..n {
            let t = self.time();
            let step = self.step + 1;
            let stats = self
                .stepper
                .step(&mut self.membrane, t, self.dt, &self.state, &mut self.next)
                .map_err(|source| StepError::Solver { step, time: step as f64 * self.dt, source })?;
            std::mem::swap(&mut self.state, &mut self.next);
            self.step += 1;
            self.solver_iterations += stats.solver_iterations;
            if let Some(particle) = self.state.first_non_finite() {
                let (step, time) = (self.step, self.time());
                return Err(NonFinite { step, time, particle, place: None }.into());
            }
            if (k + 1) % every == 0 || k + 1 == n {
                let (x, v, m) = (&self.state.x, &self.state.v, self.membrane.masses());
                self.bounds.check(
                    self.step,
                    self.time(),
                    x,
                    v,
                    m,
                    self.membrane.gravity,
                    std::iter::empty(),
                )?;
            }
        }
        Ok(())
    }
}

/// A square sheet of membrane elements on an N × N grid, with the spring sheet's size, height, mass, pins
/// and gravity. Its cells' diagonals alternate like a chequerboard: with one diagonal direction
/// everywhere (the spring sheet's frames) the mesh, and so its discrete stiffness, is not symmetric
/// under the sheet's reflections. Measured on the standard sheet with generalised-α (`cargo xtask
/// reproduce membrane`'s set-up), one direction against alternating: 65 × 65 at 1/1000 s against
/// 1/2000 s erred 2.2 against 0.7 mm at 0.5 s, and the 9, 17 and 33 meshes lay 17.4, 14.7 and 7.4 mm
/// against 15.9, 12.8 and 6.0 mm from the 65 × 65 one.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MembraneSheetSpec {
    /// Vertices per side.
    pub n: usize,
    #[serde(rename = "size_m")]
    pub size: f64,
    #[serde(rename = "height_m")]
    pub height: f64,
    #[serde(rename = "total_mass_kg")]
    pub total_mass: f64,
    pub material: MembraneMaterial,
    /// Pinned vertices as (i, j), vertex (i, j) at (i·h, j·h, height) with index j·N + i.
    pub pinned: Vec<(usize, usize)>,
    #[serde(rename = "gravity_m_s2")]
    pub gravity: DVec3,
}

impl MembraneSheetSpec {
    /// The standard sheet (1 m, 0.2 kg, pinned at the two corners of its first row, 1.5 m up) in
    /// [`MembraneMaterial::STANDARD`].
    pub fn standard(n: usize) -> Self {
        Self {
            n,
            size: 1.0,
            height: 1.5,
            total_mass: 0.2,
            material: MembraneMaterial::STANDARD,
            pinned: vec![(0, 0), (n - 1, 0)],
            gravity: DVec3::new(0.0, 0.0, -9.81),
        }
    }

    pub fn positions(&self) -> Vec<DVec3> {
        crate::spring_net::grid_positions(self.n, self.size, self.height)
    }

    /// Two triangles per cell, the diagonal of cell (i, j) from its (0, 0) corner when i + j is even and
    /// from its (1, 0) corner when odd.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let n = self.n;
        let mut out = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let p = (i * n + j) as u32;
                let (b, q) = (p + n as u32, p + 1);
                if (i + j) % 2 == 0 {
                    out.push([p, b, b + 1]);
                    out.push([p, b + 1, q]);
                } else {
                    out.push([p, b, q]);
                    out.push([q, b, b + 1]);
                }
            }
        }
        out
    }

    /// The membrane; a grid of fewer than 2 × 2 or more than anima's particles, or a pin off the grid,
    /// is an error.
    pub fn build(&self) -> Result<Membrane, MembraneError> {
        let n = self.n;
        let max = anima_format::limits::MAX_PARTICLES;
        if n < 2 || n.checked_mul(n).is_none_or(|p| p > max) {
            return Err(MembraneError::Sheet(format!(
                "expected 2 to {} vertices a side, found {n}",
                max.isqrt()
            )));
        }
        if let Some((i, j)) = self.pinned.iter().find(|&&(i, j)| i >= n || j >= n) {
            return Err(MembraneError::Sheet(format!("pin ({i}, {j}) lies outside the {n} × {n} grid")));
        }
        let mut pinned = vec![false; self.n * self.n];
        for &(i, j) in &self.pinned {
            pinned[j * self.n + i] = true;
        }
        let density = self.total_mass / (self.size * self.size);
        Membrane::new(&self.positions(), &self.triangles(), self.material, density, pinned, self.gravity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sheet(n: usize, material: MembraneMaterial) -> (Membrane, Vec<DVec3>) {
        let spec = MembraneSheetSpec { material, pinned: vec![], ..MembraneSheetSpec::standard(n) };
        (spec.build().unwrap(), spec.positions())
    }

    fn jittered(x: &[DVec3], amount: f64) -> Vec<DVec3> {
        x.iter()
            .enumerate()
            .map(|(k, p)| {
                let s = |a: f64| ((k as f64 + 1.0) * a).sin() * amount;
                *p + DVec3::new(s(1.3), s(2.9), s(0.7))
            })
            .collect()
    }

    fn forces(m: &mut Membrane, x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
        let mut f = vec![DVec3::ZERO; x.len()];
        m.add_forces(x, v, &mut f, None);
        f
    }

    #[test]
    fn rest_and_rigid_motions_have_no_force() {
        let (mut m, x) = sheet(5, MembraneMaterial::STANDARD);
        let rot = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.9);
        let moved: Vec<DVec3> = x.iter().map(|p| rot * *p + DVec3::new(0.3, -2.0, 5.0)).collect();
        let zero = vec![DVec3::ZERO; x.len()];
        for y in [&x, &moved] {
            let f = forces(&mut m, y, &zero);
            let worst = f.iter().map(|f| f.length()).fold(0.0, f64::max);
            assert!(worst < 1e-9, "largest force {worst} N at a rigid placement");
        }
        let (membrane, bending) = m.elastic_energy(&moved);
        assert!(membrane.abs() < 1e-18 && bending.abs() < 1e-20, "{membrane} {bending}");
    }

    #[test]
    fn a_uniform_stretch_has_the_continuum_energy() {
        // x ↦ (1 + s) x: ε = diag(s, 0), W = A (μ s² + ½ λ s²), whatever the mesh.
        let s = 0.05;
        for n in [3, 6] {
            let (m, x) = sheet(n, MembraneMaterial::STANDARD);
            let y: Vec<DVec3> = x.iter().map(|p| DVec3::new(p.x * (1.0 + s), p.y, p.z)).collect();
            let (mu, lambda) = MembraneMaterial::STANDARD.lame();
            let expected = 1.0 * (mu * s * s + 0.5 * lambda * s * s);
            let (membrane, bending) = m.elastic_energy(&y);
            assert!((membrane - expected).abs() < 1e-12 * expected, "n = {n}: {membrane} against {expected}");
            assert!(bending.abs() < 1e-15, "a flat stretch does not bend: {bending}");
        }
    }

    #[test]
    fn a_cylinder_has_the_continuum_bending_energy() {
        // A unit square rolled onto a cylinder of radius ρ: ½ k_b ∫ |Δx|² dA = ½ k_b / ρ². The hinges cover
        // the interior edges only, so the energy approaches it as the mesh is refined (border error O(h)).
        let rho = 0.8;
        let material = MembraneMaterial { bending: 1.0, ..MembraneMaterial::STANDARD };
        let mut errors = Vec::new();
        for n in [9, 17, 33, 65] {
            let (m, x) = sheet(n, material);
            let y: Vec<DVec3> = x
                .iter()
                .map(|p| {
                    let phi = p.x / rho;
                    DVec3::new(rho * phi.sin(), p.y, rho * (1.0 - phi.cos()))
                })
                .collect();
            let (_, bending) = m.elastic_energy(&y);
            let expected = 0.5 / (rho * rho);
            errors.push((bending - expected).abs() / expected);
        }
        assert!(errors[3] < 0.05, "relative errors {errors:?}");
        assert!(errors.windows(2).all(|w| w[1] < 0.6 * w[0]), "refinement converges: {errors:?}");
    }

    #[test]
    fn the_force_is_the_energy_gradient_and_the_jacobian_its_derivative() {
        let material = MembraneMaterial { damping: 0.0, ..MembraneMaterial::STANDARD };
        let (mut m, x) = sheet(4, material);
        let x = jittered(&x, 0.05);
        let zero = vec![DVec3::ZERO; x.len()];
        let f = forces(&mut m, &x, &zero);
        let energy = |y: &[DVec3]| {
            let (a, b) = m.elastic_energy(y);
            a + b
        };
        let eps = 1e-6;
        let mut worst = 0.0f64;
        let scale = f.iter().map(|f| f.length()).fold(0.0, f64::max);
        for i in 0..x.len() {
            for c in 0..3 {
                let (mut p, mut q) = (x.clone(), x.clone());
                p[i][c] += eps;
                q[i][c] -= eps;
                let g = (energy(&p) - energy(&q)) / (2.0 * eps);
                worst = worst.max((f[i][c] + g).abs());
            }
        }
        assert!(worst < 1e-6 * scale, "force against −∇E: {worst} (scale {scale})");

        // The co-rotational stiffness is exact for small motions about a rotated rest state.
        let rot = glam::DQuat::from_axis_angle(DVec3::new(0.2, 1.0, 0.4).normalize(), 0.7);
        let (_, x0) = sheet(4, material);
        let turned: Vec<DVec3> = x0.iter().map(|p| rot * *p).collect();
        let mut jac = Jacobians::new(x.len(), m.pattern().len());
        let mut f0 = vec![DVec3::ZERO; x.len()];
        m.force_and_jacobians(0.0, &turned, &zero, &mut f0, &mut jac);
        let dx = jittered(&vec![DVec3::ZERO; x.len()], 1.0);
        let h = 1e-7;
        let y: Vec<DVec3> = turned.iter().zip(&dx).map(|(p, d)| *p + *d * h).collect();
        let mut f1 = vec![DVec3::ZERO; x.len()];
        m.force(0.0, &y, &zero, &mut f1, &mut jac.clone());
        let mut kdx: Vec<DVec3> = (0..x.len()).map(|i| jac.k_diag[i] * dx[i]).collect();
        for (e, &(i, j)) in m.pattern().iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            kdx[i] += jac.k_off[e] * dx[j];
            kdx[j] += jac.k_off[e].transpose() * dx[i];
        }
        let scale = kdx.iter().map(|v| v.length()).fold(0.0, f64::max);
        for i in 0..x.len() {
            let fd = (f1[i] - f0[i]) / h;
            assert!((fd - kdx[i]).length() < 1e-5 * scale, "vertex {i}: {fd} against K dx {}", kdx[i]);
        }
    }

    #[test]
    fn the_jacobian_is_symmetric_negative_semidefinite_and_damping_dissipates() {
        let (mut m, x) = sheet(5, MembraneMaterial::STANDARD);
        let x = jittered(&x, 0.08);
        let v = jittered(&vec![DVec3::ZERO; x.len()], 2.0);
        let mut jac = Jacobians::new(x.len(), m.pattern().len());
        let mut f = vec![DVec3::ZERO; x.len()];
        m.force_and_jacobians(0.0, &x, &v, &mut f, &mut jac);
        for d in &jac.k_diag {
            let scale = d.to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!((*d - d.transpose()).abs_diff_eq(DMat3::ZERO, 1e-12 * scale), "{d}");
        }
        // uᵀ K u ≤ 0 for several u.
        for s in [1.0, 2.0, 3.5] {
            let u = jittered(&vec![DVec3::ZERO; x.len()], s);
            let mut q = 0.0;
            for i in 0..x.len() {
                q += u[i].dot(jac.k_diag[i] * u[i]);
            }
            for (e, &(i, j)) in m.pattern().iter().enumerate() {
                q += 2.0 * u[i as usize].dot(jac.k_off[e] * u[j as usize]);
            }
            assert!(q <= 1e-9, "uᵀKu = {q}");
        }
        // The damping force alone does negative work.
        let f_elastic = forces(&mut m, &x, &vec![DVec3::ZERO; x.len()]);
        let f_total = forces(&mut m, &x, &v);
        let power: f64 = f_total.iter().zip(&f_elastic).zip(&v).map(|((a, b), v)| (*a - *b).dot(*v)).sum();
        assert!(power < 0.0, "damping power {power}");
    }

    #[test]
    fn a_hanging_curtain_stretches_as_the_continuum_does() {
        // A 1 m square hanging in the plane y = 0 from its whole top edge, at rest under gravity. Each
        // horizontal line carries the weight below it, σ(z) = ρ g (z − z_bottom) per metre, so the
        // bottom edge drops ρ g L² / (2Y) (1D, free lateral contraction): 0.98 mm here. The clamped top
        // edge holds the contraction back over a band about as deep as the sheet is wide, where the
        // material is stiffer by up to 1/(1 − ν²) = 1.10, so the drop lies a little below.
        let n = 17;
        let h = 1.0 / (n - 1) as f64;
        let rest: Vec<DVec3> =
            (0..n * n).map(|p| DVec3::new((p % n) as f64 * h, 0.0, 1.0 - (p / n) as f64 * h)).collect();
        let triangles = MembraneSheetSpec::standard(n).triangles();
        let pinned: Vec<bool> = (0..n * n).map(|p| p < n).collect();
        let (rho, g) = (0.2, 9.81);
        let m = Membrane::new(
            &rest,
            &triangles,
            MembraneMaterial::STANDARD,
            rho,
            pinned,
            DVec3::new(0.0, 0.0, -g),
        )
        .unwrap();
        let mut sim = MembraneSim::new(m, rest.clone(), Integrator::ImplicitEuler, 0.02).unwrap();
        sim.stepper_mut().set_linear_solver(anima_ode::LinearSolver::SparseCholesky);
        sim.run(300).unwrap();
        let drop: f64 = (n * (n - 1)..n * n).map(|p| rest[p].z - sim.state.x[p].z).sum::<f64>() / n as f64;
        let expected = rho * g / (2.0 * MembraneMaterial::STANDARD.young_thickness);
        let speed = sim.state.v.iter().map(|v| v.length()).fold(0.0, f64::max);
        assert!(speed < 1e-6, "at rest: {speed} m/s");
        assert!(
            (0.9 * expected..=1.0 * expected).contains(&drop),
            "bottom edge dropped {:.4} mm, the 1D continuum {:.4} mm",
            drop * 1e3,
            expected * 1e3
        );
    }

    #[test]
    fn bad_input_is_refused() {
        let x = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let ok = |t: &[[u32; 3]], mat: MembraneMaterial, rho: f64| {
            Membrane::new(&x, t, mat, rho, vec![false; 3], DVec3::ZERO).err()
        };
        let mat = MembraneMaterial::STANDARD;
        assert!(ok(&[[0, 1, 2]], mat, 1.0).is_none());
        assert_eq!(ok(&[[0, 1, 3]], mat, 1.0), Some(MembraneError::BadIndex { triangle: 0, index: 3, n: 3 }));
        assert_eq!(ok(&[[0, 1, 1]], mat, 1.0), Some(MembraneError::Degenerate(0)));
        assert!(matches!(
            ok(&[[0, 1, 2]], MembraneMaterial { poisson: 0.5, ..mat }, 1.0),
            Some(MembraneError::BadMaterial(_))
        ));
        assert_eq!(ok(&[[0, 1, 2]], mat, 0.0), Some(MembraneError::BadDensity));
    }
}
