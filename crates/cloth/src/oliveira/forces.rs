//! The equations of motion integrated by RK4 (Oliveira 2013 §4.4, Eq. 4.7): springs and dampers,
//! bending, gravity and air drag. Contact is not among them: it is answered after the step (§4.4.2.1).
//!
//! For the implicit integrators the model is also [`Linearized`]: the springs' exact Jacobians (the
//! geometric term clamped at zero so the system stays definite, as for every anima spring), the drag's
//! −C_i I on the velocity diagonal, and the bending elements' Jacobians in their mode
//! ([`super::bending::BendingMode::jacobian_coefficients`]), taken along the element's mean normal and
//! applied alike in every direction (below). Bending must be implicit
//! at the sizes users simulate: its stiffness over a particle's mass grows as 1/L⁴ with the edge
//! length L, so on the 17 × 17 meshes of the thesis its highest frequency is far below any step a user
//! would choose (h·ω ≈ 0.2 at 1/60 s), while on a 65 × 65 mesh it is about 10 at 1/60 s and an
//! explicit bending force inside the implicit step made the drape stretch its springs to several times
//! their length (measured: 716 % on the Bunny at step 10; 3–25 % with bending off).
//!
//! The system is written in spring form ([`Linearized::spring_form`]): one B = along · n nᵀ +
//! across · I per pattern pair and the drag on the diagonal, so the solvers multiply by it from four
//! numbers a pair, on every core. A bending element's Jacobian −k (Σ u_a)(Σ u_b)ᵀ over its four
//! particles is rank one; with s_a = u_a·n̄ (n̄ the mean of its two face normals: on a flat element
//! u_a = s_a n̄ exactly) it becomes −k (s sᵀ) ⊗ I, which, since Σ s_a = 0, is a sum over the element's
//! six pairs of −k s_a s_b times (e_a − e_b)(e_a − e_b)ᵀ ⊗ I: an isotropic term on each pair, added to
//! its `across`. That is the Hessian of a quadratic bending energy in the manner of Bergou et al.
//! (2006), exact at a flat element in the normal direction; it adds stiffness of the bending scale
//! in the plane, where the springs are thousands of times stiffer. Measured on the Bunny drape
//! (65 × 65, 1/60 s) against the rank-one form: the same CG and Newton iterations (17.97 against 17.72
//! a step) and a quarter less solve time, with no product over four-particle stencils.

use anima_geom::DVec3;
use anima_ode::parallel;
use anima_ode::{Coord, Jacobians, Linearized, OdeSystem, SystemOut};
use glam::DMat3;

use crate::assembly::{SpringAssembly, SpringTerm, StencilAssembly};

use super::bending::BendingElements;
use super::scene::{DamperLaw, SpringLaw};
use super::springs::Springs;
use crate::membrane::Membrane;

/// Everything the acceleration depends on, as flat arrays over particles, springs and elements.
#[derive(Debug, Clone)]
pub struct ClothModel {
    pub springs: Springs,
    pub bending: BendingElements,
    pub mass: Vec<f64>,
    pub inv_mass: Vec<f64>,
    /// m_i·g, N.
    pub weight: Vec<DVec3>,
    /// C_i = A_i·κ, kg/s.
    pub drag: Vec<f64>,
    pub bending_stiffness: f64,
    pub bending_damping: f64,
    /// η of [`super::Options::bending_height_floor`].
    pub bending_height_floor: f64,
    pub spring_law: SpringLaw,
    pub damper_law: DamperLaw,
    /// The continuum model of [`super::Options::membrane`]: when present its elastic, bending and damping
    /// forces replace the springs' and the bending elements'.
    pub membrane: Option<Membrane>,
    /// The spring pattern and (empty) prescribed set the implicit integrators need, built on first use.
    pub(crate) implicit: ImplicitParts,
}

/// What [`Linearized`] hands out besides the masses, kept so the step loop does not rebuild it, and
/// the assemblies that share the forces out over the threads.
#[derive(Debug, Clone, Default)]
pub(crate) struct ImplicitParts {
    /// Per spring its ends ordered (i < j), then the pairs of the bending elements' outer particles
    /// (x₁, x₂) that no spring joins: every pair a bending element couples.
    pattern: Vec<(u32, u32)>,
    prescribed: Vec<bool>,
    /// Per pattern pair, as a spring is oriented (its force acts on `.0`); the bending pairs carry no
    /// spring.
    ends: Vec<(u32, u32)>,
    /// The bending elements in the system (empty when bending is off), and for each the pattern pairs
    /// of its particles (0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3).
    stencils: Vec<[u32; 4]>,
    stencil_pairs: Vec<[u32; 6]>,
    /// Per pattern pair, the (element, pair slot) of the bending elements that couple it, in element
    /// order: `pair_elements[pair_start[p]..pair_start[p + 1]]`.
    pair_elements: Vec<(u32, u8)>,
    pair_start: Vec<u32>,
    /// Per bending element at the last evaluation: its forces, and t_a = √γ s_a (the pair (a, b) gains
    /// −t_a t_b I).
    bending_terms: Vec<([DVec3; 4], [f64; 4])>,
    springs: SpringAssembly,
    bending: StencilAssembly,
}

/// The pairs of a four-particle stencil, in the order of [`ImplicitParts::stencil_pairs`].
const STENCIL_PAIRS: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

impl ClothModel {
    /// Forgets the implicit pattern (after the springs changed: a remesh).
    pub fn invalidate_implicit(&mut self) {
        self.implicit = ImplicitParts::default();
    }

    /// Whether the bending elements act (and so go into the implicit system).
    fn bending_acts(&self) -> bool {
        self.membrane.is_none() && (self.bending_stiffness != 0.0 || self.bending_damping != 0.0)
    }

    fn ensure_implicit(&mut self) {
        let n_stencils = if self.bending_acts() { self.bending.len() } else { 0 };
        let parts = &mut self.implicit;
        let ready = match &self.membrane {
            Some(m) => parts.pattern.len() == Linearized::pattern(m).len(),
            None => parts.ends.len() == parts.pattern.len() && parts.stencils.len() == n_stencils,
        };
        if ready && parts.prescribed.len() == self.mass.len() && parts.pattern.len() >= self.springs.len() {
            return;
        }
        parts.springs.invalidate();
        parts.bending.invalidate();
        parts.prescribed = vec![false; self.mass.len()];
        parts.stencils.clear();
        parts.stencil_pairs.clear();
        parts.pair_elements.clear();
        parts.pair_start.clear();
        if let Some(m) = &self.membrane {
            parts.pattern = Linearized::pattern(m).to_vec();
            parts.ends.clear();
            return;
        }
        parts.ends = self.springs.ends.iter().map(|&[i, j]| (i, j)).collect();
        parts.pattern = self.springs.ends.iter().map(|&[i, j]| (i.min(j), i.max(j))).collect();
        if n_stencils == 0 {
            return;
        }
        let mut index: std::collections::HashMap<(u32, u32), u32> =
            parts.pattern.iter().enumerate().map(|(e, &p)| (p, e as u32)).collect();
        for s in &self.bending.stencils {
            let pairs = STENCIL_PAIRS.map(|(a, b)| {
                let key = (s[a].min(s[b]), s[a].max(s[b]));
                *index.entry(key).or_insert_with(|| {
                    parts.pattern.push(key);
                    parts.ends.push(key);
                    parts.pattern.len() as u32 - 1
                })
            });
            parts.stencils.push(*s);
            parts.stencil_pairs.push(pairs);
        }
        parts.pair_start.clear();
        parts.pair_start.resize(parts.pattern.len() + 1, 0);
        for pairs in &parts.stencil_pairs {
            for &p in pairs {
                parts.pair_start[p as usize + 1] += 1;
            }
        }
        for p in 0..parts.pattern.len() {
            parts.pair_start[p + 1] += parts.pair_start[p];
        }
        let mut fill: Vec<u32> = parts.pair_start[..parts.pattern.len()].to_vec();
        parts.pair_elements.clear();
        parts.pair_elements.resize(parts.pair_start[parts.pattern.len()] as usize, (0, 0));
        for (e, pairs) in parts.stencil_pairs.iter().enumerate() {
            for (q, &p) in pairs.iter().enumerate() {
                parts.pair_elements[fill[p as usize] as usize] = (e as u32, q as u8);
                fill[p as usize] += 1;
            }
        }
    }
}

impl ClothModel {
    /// f_i = m_i g − C_i v_i: the forces every model shares.
    fn weight_and_drag(&self, v: &[DVec3], f: &mut [DVec3]) {
        for ((fi, (w, c)), vi) in f.iter_mut().zip(self.weight.iter().zip(&self.drag)).zip(v) {
            *fi = *w - *vi * *c;
        }
    }

    /// The total force on every particle, N: f_i = m_i g − C_i v_i + springs + bending (Eq. 4.7), or
    /// the membrane's forces in place of the springs and bending. On every core for large meshes, with
    /// the serial sums' bits (springs in their order, then the bending elements in theirs).
    pub fn forces(&mut self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        if let Some(m) = &self.membrane {
            self.weight_and_drag(v, f);
            m.add_forces(x, v, f, None);
            return;
        }
        self.ensure_implicit();
        let (springs, law, damper) = (&self.springs, self.spring_law, self.damper_law);
        let (weight, drag) = (&self.weight, &self.drag);
        let parts = &mut self.implicit;
        parts.springs.forces(
            &parts.ends,
            |i| weight[i] - v[i] * drag[i],
            |e| {
                if e >= springs.len() {
                    return SpringTerm::default();
                }
                let [i, j] = springs.ends[e].map(|i| i as usize);
                let force = super::springs::spring_force(
                    x[i],
                    x[j],
                    v[i],
                    v[j],
                    springs.rest_length[e],
                    springs.stiffness[e],
                    springs.damping[e],
                    law,
                    damper,
                );
                SpringTerm { force, live: true, ..SpringTerm::default() }
            },
            f,
        );
        if !self.bending_acts() {
            return;
        }
        let (k, c, floor) = (self.bending_stiffness, self.bending_damping, self.bending_height_floor);
        let stencils = &self.bending.stencils;
        self.implicit.bending.add_forces(
            stencils,
            |e| {
                let idx = stencils[e].map(|i| i as usize);
                super::bending::bending_forces(idx.map(|i| x[i]), idx.map(|i| v[i]), k, c, floor)
            },
            f,
        );
    }

    /// The bending elements' forces and Jacobian weights t_a = √γ s_a, γ = β_x k_x + β_v k_v (module
    /// docs), in one pass over the elements, in parallel.
    fn bending_terms(&mut self, x: &[DVec3], v: &[DVec3], beta_v: f64, beta_x: f64) {
        let (k, c, floor) = (self.bending_stiffness, self.bending_damping, self.bending_height_floor);
        let parts = &mut self.implicit;
        let stencils = &parts.stencils;
        parts.bending_terms.resize(stencils.len(), ([DVec3::ZERO; 4], [0.0; 4]));
        parallel::for_chunks(&mut parts.bending_terms, |s, terms| {
            for (q, t) in terms.iter_mut().enumerate() {
                let idx = stencils[s + q].map(|i| i as usize);
                *t = ([DVec3::ZERO; 4], [0.0; 4]);
                if let Some(m) = super::bending::bending_mode(idx.map(|i| x[i]), floor) {
                    let (kx, kv) = m.jacobian_coefficients(k, c);
                    let root = (beta_x * kx + beta_v * kv).sqrt();
                    let normal = m.mean_normal();
                    *t = (m.forces(idx.map(|i| v[i]), k, c), m.u.map(|u| root * u.dot(normal)));
                }
            }
        });
    }
}

impl OdeSystem for ClothModel {
    type Coord = DVec3;

    fn n_coords(&self) -> usize {
        self.mass.len()
    }

    fn acceleration(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], a: &mut [DVec3]) {
        self.forces(x, v, a);
        for (ai, m) in a.iter_mut().zip(&self.inv_mass) {
            *ai *= *m;
        }
    }

    fn linearized(&mut self) -> Option<&mut dyn Linearized<DVec3>> {
        self.ensure_implicit();
        Some(self)
    }
}

impl Linearized<DVec3> for ClothModel {
    fn masses(&self) -> &[f64] {
        &self.mass
    }

    fn prescribed(&self) -> &[bool] {
        &self.implicit.prescribed
    }

    fn pattern(&self) -> &[(u32, u32)] {
        &self.implicit.pattern
    }

    fn force(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], _scratch: &mut Jacobians<DVec3>) {
        self.forces(x, v, f);
    }

    /// The springs' pair blocks B = β_x K + β_v D = along · u uᵀ + across · I (K and D of
    /// [`super::springs::definite_spring_jacobians`]), so the solvers multiply from four numbers a
    /// spring; the drag's β_v C_i I goes on the diagonal ([`Linearized::spring_form_diagonal`]). Not
    /// with the membrane, whose elements couple more than two particles.
    fn spring_form(&self) -> bool {
        self.membrane.is_none()
    }

    fn spring_form_diagonal(&self, beta_v: f64, _beta_x: f64, out: &mut [f64]) {
        for (o, &c) in out.iter_mut().zip(&self.drag) {
            *o = beta_v * c;
        }
    }

    /// The force of [`ClothModel::forces`] to the bit, and in spring form the system's blocks from one
    /// pass over the bending elements and one over the pattern's pairs. With the membrane, the
    /// Jacobians' way.
    fn force_and_system(
        &mut self,
        t: f64,
        x: &[DVec3],
        v: &[DVec3],
        beta_v: f64,
        beta_x: f64,
        out: SystemOut<'_, DVec3>,
        scratch: &mut Jacobians<DVec3>,
    ) {
        if self.membrane.is_some() {
            scratch.resize(x.len(), self.implicit.pattern.len());
            scratch.clear();
            self.force_and_jacobians(t, x, v, out.f, scratch);
            for (a, (&d, &k)) in out.diag.iter_mut().zip(scratch.d_diag.iter().zip(&scratch.k_diag)) {
                *a = <DVec3 as Coord>::block_combine(d, -beta_v, k, -beta_x);
            }
            for (a, (&d, &k)) in out.off.iter_mut().zip(scratch.d_off.iter().zip(&scratch.k_off)) {
                *a = <DVec3 as Coord>::block_combine(d, -beta_v, k, -beta_x);
            }
            return;
        }
        self.ensure_implicit();
        let bending = self.bending_acts();
        if bending {
            self.bending_terms(x, v, beta_v, beta_x);
        }
        let SystemOut { f, diag, off, springs: springs_out } = out;
        let (springs, law, damper) = (&self.springs, self.spring_law, self.damper_law);
        let (weight, drag) = (&self.weight, &self.drag);
        let parts = &mut self.implicit;
        let (pair_start, pair_elements, terms) =
            (&parts.pair_start, &parts.pair_elements, &parts.bending_terms);
        // The bending elements' isotropic −t_a t_b on pair p (module docs), in element order.
        let bent = |p: usize| -> f64 {
            if !bending {
                return 0.0;
            }
            let mut sum = 0.0;
            for &(e, q) in &pair_elements[pair_start[p] as usize..pair_start[p + 1] as usize] {
                let (a, b) = STENCIL_PAIRS[q as usize];
                let t = &terms[e as usize].1;
                sum -= t[a] * t[b];
            }
            sum
        };
        parts.springs.force_and_system(
            &parts.ends,
            |i| weight[i] - v[i] * drag[i],
            |e| {
                if e >= springs.len() {
                    // A pair only the bending elements couple: no force, their term alone.
                    let across = bent(e);
                    return SpringTerm { across, live: across != 0.0, ..SpringTerm::default() };
                }
                let [i, j] = springs.ends[e].map(|i| i as usize);
                let (rest, k, c) = (springs.rest_length[e], springs.stiffness[e], springs.damping[e]);
                let force = super::springs::spring_force(x[i], x[j], v[i], v[j], rest, k, c, law, damper);
                let d = x[j] - x[i];
                let len = d.length();
                if len == 0.0 {
                    let across = bent(e);
                    return SpringTerm { force, across, live: across != 0.0, ..SpringTerm::default() };
                }
                let stretched = len > rest;
                let elastic = stretched || law == SpringLaw::TwoSided;
                let viscous = stretched || damper == DamperLaw::Always;
                // K = k [u uᵀ + g (I − u uᵀ)] while the elastic force acts, g = 1 − L⁰/|d| clamped at
                // zero (definite); D = c u uᵀ while the damper acts.
                let (k, g) = if elastic { (k, (1.0 - rest / len).max(0.0)) } else { (0.0, 0.0) };
                let c = if viscous { c } else { 0.0 };
                SpringTerm {
                    n: d / len,
                    along: beta_x * k * (1.0 - g) + beta_v * c,
                    across: beta_x * k * g + bent(e),
                    force,
                    live: true,
                }
            },
            f,
            diag,
            off,
            springs_out,
        );
        // The drag's −C_i v_i: β_v C_i on the diagonal.
        parallel::for_chunks(diag, |s, diag| {
            for (k, d) in diag.iter_mut().enumerate() {
                *d += DMat3::from_diagonal(DVec3::splat(beta_v * drag[s + k]));
            }
        });
        if bending {
            let parts = &mut self.implicit;
            let terms = &parts.bending_terms;
            parts.bending.add_forces(&parts.stencils, |e| terms[e].0, f);
        }
    }

    fn force_and_jacobians(
        &mut self,
        _t: f64,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        jac: &mut Jacobians<DVec3>,
    ) {
        for (d, &c) in jac.d_diag.iter_mut().zip(&self.drag) {
            *d -= DMat3::from_diagonal(DVec3::splat(c));
        }
        if let Some(m) = &self.membrane {
            self.weight_and_drag(v, f);
            m.add_forces(x, v, f, Some(jac));
            return;
        }
        self.forces(x, v, f);
        let s = &self.springs;
        for (e, &[i, j]) in s.ends.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let (k, c) = super::springs::definite_spring_jacobians(
                x[i],
                x[j],
                s.rest_length[e],
                s.stiffness[e],
                s.damping[e],
                self.spring_law,
                self.damper_law,
            );
            jac.k_diag[i] -= k;
            jac.k_diag[j] -= k;
            jac.k_off[e] += k;
            jac.d_diag[i] -= c;
            jac.d_diag[j] -= c;
            jac.d_off[e] += c;
        }
        if !self.bending_acts() {
            return;
        }
        // ∂f_a/∂x_b ≈ −k_x s_a s_b I and ∂f_a/∂v_b ≈ −k_v s_a s_b I over the element's pairs, each as
        // −(e_a − e_b)(e_a − e_b)ᵀ ⊗ (−k s_a s_b I) (module docs).
        let (kb, cb, floor) = (self.bending_stiffness, self.bending_damping, self.bending_height_floor);
        let parts = &self.implicit;
        for (e, st) in parts.stencils.iter().enumerate() {
            let Some(m) = super::bending::bending_mode(st.map(|i| x[i as usize]), floor) else { continue };
            let (kx, kv) = m.jacobian_coefficients(kb, cb);
            let normal = m.mean_normal();
            let s = m.u.map(|u| u.dot(normal));
            for (q, &(a, b)) in STENCIL_PAIRS.iter().enumerate() {
                let p = parts.stencil_pairs[e][q] as usize;
                let w = -s[a] * s[b];
                let (i, j) = (st[a] as usize, st[b] as usize);
                // A pair term c (e_i − e_j)(e_i − e_j)ᵀ ⊗ I in the force Jacobian: −c on the diagonals.
                for (jac_diag, jac_off, coeff) in
                    [(&mut jac.k_diag, &mut jac.k_off, kx), (&mut jac.d_diag, &mut jac.d_off, kv)]
                {
                    let block = DMat3::from_diagonal(DVec3::splat(coeff * w));
                    jac_diag[i] -= block;
                    jac_diag[j] -= block;
                    jac_off[p] += block;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use anima_geom::{DiagonalPattern, MaterialMesh};
    use anima_ode::SpringBlock;

    use super::*;
    use crate::oliveira::Material;

    /// The cloth model of a small wrinkled, moving mesh with stretched and compressed springs.
    fn model() -> (ClothModel, Vec<DVec3>, Vec<DVec3>) {
        let mesh = MaterialMesh::grid(6, 0.5, DiagonalPattern::Uniform).unwrap();
        let material = Material::table_5_5();
        let areas = mesh.vertex_areas();
        let mass: Vec<f64> = areas.iter().map(|&a| material.particle_mass(a)).collect();
        let rest_length = mesh.edge_rest_lengths();
        let model = ClothModel {
            springs: Springs {
                ends: mesh.topology().edges().iter().map(|e| e.vertices).collect(),
                stiffness: rest_length.iter().map(|&l| material.spring_stiffness(l)).collect(),
                damping: rest_length.iter().map(|&l| material.spring_damping(l)).collect(),
                rest_length,
            },
            bending: BendingElements {
                stencils: mesh.topology().interior_stencils().iter().map(|s| s.vertices).collect(),
            },
            inv_mass: mass.iter().map(|m| 1.0 / m).collect(),
            weight: mass.iter().map(|&m| DVec3::new(0.0, 0.0, -9.81) * m).collect(),
            drag: areas.iter().map(|&a| material.particle_drag(a)).collect(),
            mass,
            bending_stiffness: material.bending_stiffness,
            bending_damping: material.bending_damping,
            bending_height_floor: 0.05,
            spring_law: SpringLaw::TensionOnly,
            damper_law: DamperLaw::Always,
            membrane: None,
            implicit: Default::default(),
        };
        let x: Vec<DVec3> = mesh
            .place(DVec3::ZERO, DVec3::X, DVec3::Y)
            .iter()
            .enumerate()
            .map(|(k, p)| {
                *p * (1.0 + 0.04 * (k as f64 * 1.3).sin()) + DVec3::Z * 0.03 * (k as f64 * 0.7).cos()
            })
            .collect();
        let v: Vec<DVec3> =
            (0..x.len()).map(|k| DVec3::new((k as f64).sin(), 0.2, (k as f64 * 0.4).cos())).collect();
        (model, x, v)
    }

    /// The spring form (springs, bending pairs, drag on the diagonal) multiplies a vector as the
    /// blocks of the Jacobians do, A = M − β_v D − β_x K; and its force is the model's to the bit.
    #[test]
    fn the_spring_form_is_the_jacobians_system() {
        let (mut model, x, v) = model();
        let n = x.len();
        let lin = model.linearized().unwrap();
        let pattern = lin.pattern().to_vec();
        assert!(pattern.len() > model.springs.len(), "the bending elements' outer pairs join the pattern");
        let (bv, bx) = (0.013, 0.0021);
        let (mut f, mut diag) = (vec![DVec3::ZERO; n], vec![DMat3::ZERO; n]);
        let mut springs = Vec::<SpringBlock<DVec3>>::new();
        let mut scratch = Jacobians::new(n, pattern.len());
        let out = SystemOut { f: &mut f, diag: &mut diag, off: &mut [], springs: Some(&mut springs) };
        model.force_and_system(0.0, &x, &v, bv, bx, out, &mut scratch);
        let mut extra = vec![0.0; n];
        model.spring_form_diagonal(bv, bx, &mut extra);
        let mut jac = Jacobians::new(n, pattern.len());
        let mut f2 = vec![DVec3::ZERO; n];
        model.force_and_jacobians(0.0, &x, &v, &mut f2, &mut jac);
        let mut f3 = vec![DVec3::ZERO; n];
        model.forces(&x, &v, &mut f3);
        assert!(
            f.iter().zip(&f3).all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits))
        );
        let y: Vec<DVec3> =
            (0..n).map(|k| DVec3::new((k as f64 * 0.9).cos(), 1.0, (k as f64).sin())).collect();
        // From the spring form.
        let mut a = vec![DVec3::ZERO; n];
        for i in 0..n {
            a[i] = y[i] * (model.mass[i] + extra[i]);
        }
        for s in &springs {
            let (i, j) = (s.i as usize, s.j as usize);
            let d = y[i] - y[j];
            let b = s.u * s.u.dot(d) + d * s.a;
            a[i] += b;
            a[j] -= b;
        }
        // From the blocks.
        let mut b = vec![DVec3::ZERO; n];
        for i in 0..n {
            let block =
                DMat3::from_diagonal(DVec3::splat(model.mass[i])) - jac.d_diag[i] * bv - jac.k_diag[i] * bx;
            b[i] = block * y[i];
            assert!(
                (diag[i] + DMat3::from_diagonal(DVec3::splat(model.mass[i])) - block)
                    .abs()
                    .to_cols_array()
                    .iter()
                    .all(|e| *e < 1e-9),
                "diagonal {i}"
            );
        }
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let block = -(jac.d_off[e] * bv) - jac.k_off[e] * bx;
            b[i as usize] += block * y[j as usize];
            b[j as usize] += block.transpose() * y[i as usize];
        }
        let scale = b.iter().map(|p| p.length()).fold(0.0, f64::max);
        for i in 0..n {
            assert!((a[i] - b[i]).length() < 1e-9 * scale, "row {i}: {} vs {}", a[i], b[i]);
        }
    }
}
