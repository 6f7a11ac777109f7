//! Spring forces and the implicit system's spring-form blocks on every core, with the serial loop's
//! bits.
//!
//! A spring network's force and system matrix are sums over springs that each add to two particles.
//! Written as one loop over the springs, the additions race when shared out; so the work is split in
//! two. First every spring's terms are computed on their own (its force, its unit direction and the two
//! coefficients of its block B = along · n nᵀ + across · I), in parallel over the springs, and the
//! system's per-spring outputs (the spring-form list, the pair blocks) are written. Then each particle
//! gathers its springs' terms in the springs' order ([`anima_ode::parallel::Scatter`]), so every
//! particle's force and diagonal block are added up exactly as the serial loop adds them.

use anima_geom::DVec3;
use anima_ode::SpringBlock;
use anima_ode::parallel::{self, Scatter};
use glam::DMat3;

/// What one spring contributes, computed on its own.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SpringTerm {
    /// The spring's unit direction, first end to second.
    pub n: DVec3,
    /// B = along · n nᵀ + across · I.
    pub along: f64,
    pub across: f64,
    /// The force on the first end (the second end gets its negative), N.
    pub force: DVec3,
    /// False for a spring of zero length: no force, no block.
    pub live: bool,
}

impl SpringTerm {
    /// B as a block, computed the same way wherever it is needed (the same bits on both ends).
    #[inline]
    pub fn block(&self) -> DMat3 {
        let (n, along) = (self.n, self.along);
        DMat3::from_cols(n * (n.x * along), n * (n.y * along), n * (n.z * along))
            + DMat3::from_diagonal(DVec3::splat(self.across))
    }
}

/// The per-spring terms and the particles' split, kept between evaluations.
#[derive(Debug, Clone, Default)]
pub(crate) struct SpringAssembly {
    terms: Vec<SpringTerm>,
    scatter: Scatter,
}

impl SpringAssembly {
    /// Forgets the split (the springs changed).
    pub fn invalidate(&mut self) {
        self.scatter.invalidate();
    }

    fn prepare(&mut self, n: usize, ends: &[(u32, u32)]) {
        if !self.scatter.ready_for(n, ends.len()) {
            self.scatter.prepare(n, ends.len(), |e| [ends[e].0, ends[e].1]);
        }
    }

    /// The force alone: f_i = base(i), then every live spring's force added to its first end and
    /// subtracted from its second, in the springs' order. `term(e)` gives spring e's terms (only its
    /// force and liveness are read).
    pub fn forces(
        &mut self,
        ends: &[(u32, u32)],
        base: impl Fn(usize) -> DVec3 + Sync + Send,
        term: impl Fn(usize) -> SpringTerm + Sync + Send,
        f: &mut [DVec3],
    ) {
        self.prepare(f.len(), ends);
        self.terms.resize(ends.len(), SpringTerm::default());
        parallel::for_chunks(&mut self.terms, |s, t| {
            for (k, t) in t.iter_mut().enumerate() {
                *t = term(s + k);
            }
        });
        let terms = &self.terms;
        self.scatter.run(f, |range, springs, f| {
            let s = range.start;
            for i in range.clone() {
                f[i - s] = base(i);
            }
            for &e in springs {
                let t = &terms[e as usize];
                if !t.live {
                    continue;
                }
                let (i, j) = (ends[e as usize].0 as usize, ends[e as usize].1 as usize);
                if range.contains(&i) {
                    f[i - s] += t.force;
                }
                if range.contains(&j) {
                    f[j - s] -= t.force;
                }
            }
        });
    }

    /// The force and the system's blocks in spring form: as [`SpringAssembly::forces`] for f; `diag`
    /// gets Σ B over each particle's live springs (from zero, in the springs' order), `off` (unless
    /// empty) −B per spring, and `springs` (when given) one [`SpringBlock`] per spring with
    /// u = n √along, a = across (zero for a dead spring), in the springs' order, its ends ordered as
    /// a pattern pair (i < j).
    #[expect(clippy::too_many_arguments, reason = "the springs, two rules and the system's four outputs")]
    pub fn force_and_system(
        &mut self,
        ends: &[(u32, u32)],
        base: impl Fn(usize) -> DVec3 + Sync + Send,
        term: impl Fn(usize) -> SpringTerm + Sync + Send,
        f: &mut [DVec3],
        diag: &mut [DMat3],
        off: &mut [DMat3],
        springs: Option<&mut Vec<SpringBlock<DVec3>>>,
    ) {
        self.forces(ends, base, term, f);
        let terms = &self.terms;
        if let Some(list) = springs {
            list.resize(ends.len(), SpringBlock { i: 0, j: 0, u: DVec3::ZERO, a: 0.0 });
            parallel::for_chunks(list, |s, list| {
                for (k, b) in list.iter_mut().enumerate() {
                    // As the pattern orders its pairs (B is symmetric, so u keeps its sign).
                    let (t, (a, b_)) = (&terms[s + k], ends[s + k]);
                    let (i, j) = (a.min(b_), a.max(b_));
                    *b = if t.live {
                        SpringBlock { i, j, u: t.n * t.along.sqrt(), a: t.across }
                    } else {
                        SpringBlock { i, j, u: DVec3::ZERO, a: 0.0 }
                    };
                }
            });
        }
        if !off.is_empty() {
            parallel::for_chunks(off, |s, off| {
                for (k, o) in off.iter_mut().enumerate() {
                    let t = &terms[s + k];
                    *o = if t.live { -t.block() } else { DMat3::ZERO };
                }
            });
        }
        self.scatter.run(diag, |range, springs, diag| {
            let s = range.start;
            for d in diag.iter_mut() {
                *d = DMat3::ZERO;
            }
            for &e in springs {
                let t = &terms[e as usize];
                if !t.live {
                    continue;
                }
                let block = t.block();
                let (i, j) = (ends[e as usize].0 as usize, ends[e as usize].1 as usize);
                if range.contains(&i) {
                    diag[i - s] += block;
                }
                if range.contains(&j) {
                    diag[j - s] += block;
                }
            }
        });
    }
}

/// Elements of four particles that add forces to them (bending stencils), shared out like the springs.
/// Each part computes the elements that touch it and keeps the forces on its own particles, so an
/// element on a part boundary is computed twice and nothing is buffered.
#[derive(Debug, Clone, Default)]
pub(crate) struct StencilAssembly {
    scatter: Scatter,
}

impl StencilAssembly {
    /// Forgets the split (the stencils changed).
    pub fn invalidate(&mut self) {
        self.scatter.invalidate();
    }

    /// Adds `element(e)`'s four forces to its particles `stencils[e]`, in the elements' order.
    pub fn add_forces(
        &mut self,
        stencils: &[[u32; 4]],
        element: impl Fn(usize) -> [DVec3; 4] + Sync + Send,
        f: &mut [DVec3],
    ) {
        self.prepare(f.len(), stencils);
        self.scatter.run(f, |range, elements, f| {
            let s = range.start;
            for &e in elements {
                let forces = element(e as usize);
                for (k, &i) in stencils[e as usize].iter().enumerate() {
                    let i = i as usize;
                    if range.contains(&i) {
                        f[i - s] += forces[k];
                    }
                }
            }
        });
    }

    fn prepare(&mut self, n: usize, stencils: &[[u32; 4]]) {
        if !self.scatter.ready_for(n, stencils.len()) {
            self.scatter.prepare(n, stencils.len(), |e| stencils[e]);
        }
    }
}
