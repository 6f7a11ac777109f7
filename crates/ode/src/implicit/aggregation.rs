//! A two-level preconditioner for A = M − β_v D − β_x K whose coarse level is the rigid motions of small
//! patches, projected with the current A (a Galerkin coarse level, as in smoothed-aggregation multigrid
//! for cloth, Tamstorf, Jones & McCormick 2015, here without the prolongation smoothing).
//!
//! Why not a scalar "mass plus spring Laplacian" Ŝ ([`super::two_level`]): measured on the standard
//! sheet (N = 64, 1/60 s), the errors that conjugate gradients with that preconditioner leave longest
//! are low-energy modes, A e ≈ (1.5 … 3) M e: locally rigid in-plane motions while the sheet is flat,
//! motions across a sheet under tension later. An isotropic Laplacian charges a local rotation the
//! stiffness of a stretch (it has no direction to tell them apart), 30 to 50 times its true energy,
//! and block Jacobi sees each particle as stiff in its springs' directions; both correct such a mode by
//! 2–3 % per application. The rigid motions of a patch — three translations and three rotations about
//! its centre, u_i = t + ω × (x_i − c) — contain exactly those modes at the patch's scale, and a coarse
//! matrix Rᵀ A R built from the current A (its real, anisotropic, rotated stiffness) weighs them right.
//!
//! Patches ("aggregates") are grown greedily by breadth-first search over the coupling pattern, `radius`
//! hops from a seed, once per pattern. The coarse matrix (six unknowns per aggregate) is assembled and
//! factorised (faer's sparse Cholesky, symbolic part kept) at every Newton iteration, since A's
//! directions turn with the cloth; reusing it for a few steps was measured to triple the iterations.
//! One application is the symmetric cycle
//!
//! z ← ω J⁻¹ r (`sweeps` times, on the residual),  z ← z + R (Rᵀ A R)⁻¹ Rᵀ (r − A z),
//! then the smoothing sweeps again,
//!
//! J the diagonal blocks of A, everything filtered. Coordinates of dimension one get one unknown per
//! aggregate (its translation); three-dimensional ones six.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;
use crate::parallel;

use super::SpringBlock;
use super::cg::Preconditioner;
use super::cholesky::SparseSolver;
use super::system::{Filter, SystemMatrix};

/// The damping ω of the block-Jacobi smoothing sweeps (as in [`super::two_level`]), unless the system
/// needs less ([`SMOOTHING_BOUND`]).
const SMOOTHING: f64 = 0.7;

/// The most ω λ̂ may be with ω = [`SMOOTHING`], λ̂ the estimated largest eigenvalue of J⁻¹A; above it ω
/// is [`SMOOTHING_TARGET`]/λ̂. Why: a sweep z ← z + ω J⁻¹ (r − A z) multiplies the error's component
/// along an eigenvector of J⁻¹A by 1 − ω λ, so it grows once ω λ > 2, and the two-level cycle around it
/// is then worse than no coarse level at all. With springs of positive weight only λ ≤ 2 (the standard
/// sheet); the bending elements' negative weights lift it: λ̂ reached 1.96–1.98 on the theses' 17²
/// drapes at 1/60 s, 2.71 on Test III's sphere with contact after the step, 2.30 on the 33² membrane
/// sheet, 2.62 on the 65² drapes, 2.80 on the 129² ones and 2.82 on the 257² Bunny's first 0.5 s
/// (`anima run` on the shipped scenes), where 0.7 contracts. Later in their 3 s the 129² Bunny and the
/// 257² drapes pass 2.86 (the 257² Bunny 3.44 at most). A mesh graded by remeshing reaches 3.3, where
/// 0.7 amplifies. Measured on the Bunny drape at 1/60 s (contact
/// in the solve, modern self-collision) started at 17² and remeshed after every step by the sizing
/// field (1.56 cm, about 2 250 particles), CG iterations a solve from 0.5 to 0.75 s: ω = 0.7 23.2, more
/// than block Jacobi without a coarse level (8.9); ω λ̂ = 1.9 6.1, 1.6 3.3, 1.4 4.1; ω = 0.5 3.9 (the
/// uniform 65² drape: 3.5 with 0.7, 3.7 with 0.5). The bound is the hard one, 2: a lower one (1.9 was
/// tried) would also change runs on which 0.7 still contracts.
///
/// The bound is on by default ([`crate::Stepper::set_bounded_smoothing`] turns it off). Of the shipped
/// scenes it binds on remeshed cloth and on the 129² Bunny and 257² drapes of
/// `docs/benchmarks-scale.md` (regenerated with it: 20.4 CG iterations a step on the 129² Bunny, 21.6
/// on the 257² one). With the bound off, `scale_probe` measured 20.3 and 23.5 on the same drapes. The
/// theses' scenes, the standard sheet, the 65² drapes and the 129² sphere keep the bits they had with
/// ω = 0.7.
const SMOOTHING_BOUND: f64 = 2.0;

/// ω λ̂ where [`SMOOTHING_BOUND`] lowers ω (the best of 1.9, 1.6 and 1.4 measured, see there).
const SMOOTHING_TARGET: f64 = 1.6;

/// Power iterations for λ̂ from a fixed start (a new pattern, or the first set-up), and from the last
/// estimate's vector every [`ESTIMATE_EVERY`] set-ups after, so that λ̂ follows a cloth that folds and
/// touches.
const FRESH_ITERATIONS: usize = 12;
const WARM_ITERATIONS: usize = 2;
const ESTIMATE_EVERY: usize = 8;

/// Breadth-first hops that grow an aggregate. On the standard sheet (N = 64, whose pattern includes the
/// skip-one bend springs) radius 3 makes 163 aggregates of about 25 particles (978 coarse unknowns),
/// radius 2 304 and radius 1 704. Measured there at 1/60 s (generalised-α's defaults, spring-form
/// Galerkin product, ms per step): radius 3 needs 8.9 CG iterations per step and 1.03 ms of coarse set-up
/// (4.8 ms in all), radius 4 10.1 and 0.71 (4.6 ms), radius 5 11.0 and 0.56 (4.7 ms), radius 6 12.9
/// and 0.47 (5.1 ms). Oliveira's three drapes at 1/60 s (contact in the solve) ran 3–9 % faster with
/// 4 than with 3. (Measured earlier, before the spring-form products and the line search's end
/// rule: radius 1 needed 7.9 iterations and 6 ms per factorisation, radius 2 10.8 and 2.5 ms, radius
/// 3 13.6 and 1.7 ms.)
///
/// On a graded mesh radius 4 serves as well, once the smoothing is damped enough for it
/// ([`SMOOTHING_BOUND`]): 3.3 CG iterations a solve on the remeshed Bunny drape below, as on the
/// uniform one. Before that, with ω = 0.7 amplifying that mesh's stiffest modes, the aggregations below
/// were tried in search of the cause, and none kept CG's count as low as on a uniform mesh without a
/// coarse level nearly as large as the fine one. Measured on the
/// Bunny drape at 1/60 s (contact in the solve, modern self-collision) started at 17² and remeshed after
/// every step by the sizing field down to the 65² drape's spacing (about 2 200 particles by 0.7 s), CG
/// iterations per solve over the steps to 0.75 s, against the uniform 65² drape (4 225 particles) at
/// the same time; one run each, throwaway switches, and the remeshed runs differ from each other
/// chaotically, so the counts are indicative:
///
/// | aggregation | remeshed: aggregates (largest) | CG / solve | uniform: aggregates | CG / solve |
/// |---|---|---|---|---|
/// | radius 4 (this) | 39–41 (233) | 26.1 | 100 (59) | 3.6 |
/// | radius 3 | 72 (114) | 31.7 | – | – |
/// | radius 2 | 127 (51) | 12.9 | – | – |
/// | radius 1 | 373 (19) | 2.6 | – | – |
/// | radius 4, growth within 4 cm of the seed | 340 (20) | 5.0 | 484 (9) | 2.2 |
/// | radius 4, growth within 7 cm of the seed | 128 (80) | 15.1 | 180 (27) | 2.5 |
/// | radius 4, 2, 3, seeds whose neighbours are all free, leftovers joined to a neighbour | 25, 62, 36 | 28.3, 14.5, 26.8 | – | – |
/// | radius 4, at most 60, 40, 25 particles an aggregate | 58, 66, 118–123 | 24.9, 18.3, 20.2 | – | – |
/// | radius 4, strong pairs only, θ = 0.02, 0.05, 0.1 | 80–96 | 19.2, 28.3, 28.4 | 169–193 | 3.1, 3.1, 2.6 |
///
/// Strength of connection there was ‖B_e‖ ≥ θ √(d_i d_j), d the spring-form diagonal's norm; about half
/// the pairs were weak on either mesh. The remeshed system is not stiffer per particle (d_i/m_i median
/// 3 231, largest 15 307, against 8 009 and 26 835 on the uniform mesh). Only radius 1 matched the
/// uniform count, with a coarse level of 2 238 unknowns for 6 800 fine ones, and its step was no cheaper
/// (213 against 188 ms a step, one run each on a loaded machine). The grading alone is not the cause:
/// with contact answered after the step instead of in the solve, the same remeshed drape (radius 4)
/// needs 3.6–4.2 iterations a solve from 0.5 to 0.75 s (2 400–2 800 particles), the uniform one 3.1–3.7.
/// Nor was it the remeshing (the mesh of 0.45 s kept to 0.75 s: 15.3 a solve), friction's sticking
/// (frictionless: 10.7), or aggregates that straddle contact and free particles (grown within one kind:
/// 23.4). Block Jacobi alone took 8.9, fewer than with the coarse level: the smoothing, not the
/// aggregates, was at fault.
pub(crate) const RADIUS: usize = 4;

/// Block-Jacobi sweeps before and after the coarse correction. Two sweeps cut the CG iterations by a
/// third (13.6 → 9.7 per step, measured with radius 3 before the spring-form products) but cost two
/// more products with A per iteration, and were measured slower per step.
pub(crate) const SWEEPS: usize = 1;

/// Coarse unknowns per aggregate, at most.
const MAX_PER: usize = 6;

type Block6 = [[f64; MAX_PER]; MAX_PER];

/// The aggregates, the coarse matrix and its factor, kept between solves.
#[derive(Debug)]
pub(crate) struct RigidAggregation<C: Coord> {
    /// Breadth-first hops that grow an aggregate.
    radius: usize,
    /// Smoothing sweeps before and after the coarse correction.
    sweeps: usize,
    /// What the aggregation was built for.
    pattern: Vec<(u32, u32)>,
    fixed: Vec<bool>,
    /// Aggregate of each coordinate (`NONE` for prescribed ones).
    agg: Vec<u32>,
    /// The coordinates of aggregate g, increasing: `members[member_start[g]..member_start[g + 1]]`.
    members: Vec<u32>,
    member_start: Vec<u32>,
    /// Rᵀ r per aggregate (the restriction, before it is laid out for the coarse solve).
    restricted: Vec<[f64; MAX_PER]>,
    n_agg: usize,
    /// Coarse unknowns per aggregate: 6 for 3-D coordinates, 1 for scalars.
    per: usize,
    /// Per coordinate, x_i − c of its aggregate.
    lever: Vec<[f64; 3]>,
    /// Per pattern pair: its coarse pair (`NONE` inside one aggregate), and whether (agg i, agg j) is
    /// reversed.
    pair_of: Vec<u32>,
    flip: Vec<bool>,
    n_pairs: usize,
    /// The pattern's pairs, increasing, with an end in aggregate g
    /// (`agg_springs[agg_spring_start[g]..agg_spring_start[g + 1]]`), between the two aggregates of
    /// coarse pair p (`pair_springs`), and at coordinate i (`incident`): the coarse blocks are summed
    /// from them, one block a thread.
    agg_springs: Vec<u32>,
    agg_spring_start: Vec<u32>,
    pair_springs: Vec<u32>,
    pair_spring_start: Vec<u32>,
    incident: Vec<u32>,
    incident_start: Vec<u32>,
    d_blocks: Vec<Block6>,
    o_blocks: Vec<Block6>,
    s_diag: Vec<f64>,
    s_off: Vec<f64>,
    solver: Option<SparseSolver>,
    y: Vec<f64>,
    az: Vec<C>,
    /// Per aggregate, Σ m x and Σ m (scratch of the levers).
    centres: Vec<[f64; 4]>,
    /// Per coordinate, Σ B_e over its springs to other aggregates (scratch of the spring-form Galerkin
    /// product, symmetric: xx, yy, zz, xy, xz, yz).
    across: Vec<[f64; 6]>,
    /// Per coordinate, the solve's projector S_i onto its free directions when it is not the identity
    /// (a contact constrains it), and whether it is: the coarse matrix is (S R)ᵀ A (S R), the Galerkin
    /// matrix of the filtered system the solve sees.
    projector: Vec<[[f64; 3]; 3]>,
    projected: Vec<bool>,
    /// Coarse factorisations so far.
    pub factorizations: usize,
    /// Whether ω follows λ̂ ([`SMOOTHING_BOUND`]); otherwise it is [`SMOOTHING`] and nothing is
    /// estimated ([`crate::Stepper::set_bounded_smoothing`]).
    pub(crate) bounded: bool,
    /// The smoothing sweeps' damping ω.
    omega: f64,
    /// The power iteration's vector (the dominant eigenvector of J⁻¹A as last estimated) and the
    /// set-ups since that estimate.
    power: Vec<C>,
    since_estimate: usize,
}

const NONE: u32 = u32::MAX;

/// The cross-product matrix columns e_k × d (k = x, y, z) as rows of S = [e_x × d, e_y × d, e_z × d].
#[inline]
fn skew(d: [f64; 3]) -> [[f64; 3]; 3] {
    [[0.0, d[2], -d[1]], [-d[2], 0.0, d[0]], [d[1], -d[0], 0.0]]
}

/// Rᵀu = [S(l)ᵀ u; u] for R = [S(l) | I] (rotations first).
#[inline]
fn modes_of(l: [f64; 3], u: [f64; 3]) -> [f64; MAX_PER] {
    let s = skew(l);
    let r: [f64; 3] = std::array::from_fn(|p| s[0][p] * u[0] + s[1][p] * u[1] + s[2][p] * u[2]);
    [r[0], r[1], r[2], u[0], u[1], u[2]]
}

/// out += sign · Rᵢᵀ (u uᵀ + s I) R_j = sign · (vᵢ v_jᵀ + s [[SᵢᵀS_j, Sᵢᵀ], [S_j, I]]) with vᵢ = Rᵢᵀu
/// ([`modes_of`]) and SᵢᵀS_j = (lᵢ·l_j) I − l_j lᵢᵀ.
#[inline]
fn add_galerkin(
    out: &mut Block6,
    li: [f64; 3],
    lj: [f64; 3],
    vi: &[f64; MAX_PER],
    vj: &[f64; MAX_PER],
    s: f64,
    sign: f64,
) {
    for p in 0..MAX_PER {
        let a = sign * vi[p];
        for q in 0..MAX_PER {
            out[p][q] += a * vj[q];
        }
    }
    let ss = sign * s;
    let (si, sj) = (skew(li), skew(lj));
    let dot = li[0] * lj[0] + li[1] * lj[1] + li[2] * lj[2];
    for p in 0..3 {
        for q in 0..3 {
            out[p][q] -= ss * lj[p] * li[q];
            out[p][q + 3] += ss * si[q][p];
            out[p + 3][q] += ss * sj[p][q];
        }
        out[p][p] += ss * dot;
        out[p + 3][p + 3] += ss;
    }
}

/// Rᵢᵀ B R_j for R = [S(l) | I] (rotations first) with levers lᵢ, l_j: [[SᵢᵀBS_j, SᵢᵀB], [BS_j, B]].
#[inline]
fn galerkin3(li: [f64; 3], b: &[[f64; 3]; 3], lj: [f64; 3]) -> Block6 {
    let mut out = [[0.0; MAX_PER]; MAX_PER];
    let (si, sj) = (skew(li), skew(lj));
    let mut bs = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            bs[r][c] = b[r][0] * sj[0][c] + b[r][1] * sj[1][c] + b[r][2] * sj[2][c];
        }
    }
    for p in 0..3 {
        for q in 0..3 {
            out[p][q] = si[0][p] * bs[0][q] + si[1][p] * bs[1][q] + si[2][p] * bs[2][q];
            out[p][q + 3] = si[0][p] * b[0][q] + si[1][p] * b[1][q] + si[2][p] * b[2][q];
            out[p + 3][q] = bs[p][q];
            out[p + 3][q + 3] = b[p][q];
        }
    }
    out
}

/// A B for 3 × 3 matrices.
#[inline]
fn mat3_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| {
        std::array::from_fn(|c| a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c])
    })
}

/// out += Rᵀ B R for one coordinate's R = [S(l) | I] and a symmetric B.
#[inline]
fn add_galerkin_block(out: &mut Block6, l: [f64; 3], b: &[[f64; 3]; 3]) {
    let m = galerkin3(l, b, l);
    for p in 0..MAX_PER {
        for q in 0..MAX_PER {
            out[p][q] += m[p][q];
        }
    }
}

/// What the spring-form coarse blocks are summed from, borrowed from a [`RigidAggregation`] while its
/// blocks are written ([`RigidAggregation::galerkin_springs`]).
struct GalerkinTerms<'a, C: Coord> {
    per: usize,
    agg: &'a [u32],
    lever: &'a [[f64; 3]],
    projected: &'a [bool],
    projector: &'a [[[f64; 3]; 3]],
    flip: &'a [bool],
    springs: &'a [SpringBlock<C>],
    masses: &'a [f64],
    /// Per coordinate, Σ B over its springs to other aggregates (empty while it is summed).
    across: &'a [[f64; 6]],
}

impl<C: Coord> GalerkinTerms<'_, C> {
    /// Spring e's ends, their aggregates, u (padded to three components) and a.
    #[inline]
    fn spring(&self, e: usize) -> (usize, usize, u32, u32, [f64; 3], f64) {
        let SpringBlock { i, j, u, a } = self.springs[e];
        let (i, j) = (i as usize, j as usize);
        let u = std::array::from_fn(|k| if k < C::DIM { u.component(k) } else { 0.0 });
        (i, j, self.agg[i], self.agg[j], u, a)
    }

    /// Sᵢ B S_j, S the identity where the coordinate is not projected.
    #[inline]
    fn projected_pair(&self, i: usize, b: &[[f64; 3]; 3], j: usize) -> [[f64; 3]; 3] {
        let identity: [[f64; 3]; 3] =
            std::array::from_fn(|r| std::array::from_fn(|c| if r == c { 1.0 } else { 0.0 }));
        let si = if self.projected[i] { self.projector[i] } else { identity };
        let sj = if self.projected[j] { self.projector[j] } else { identity };
        mat3_mul(&mat3_mul(&si, b), &sj)
    }

    /// Scalar projectors (0 or 1) of i and j.
    #[inline]
    fn scalar_projectors(&self, i: usize, j: usize) -> (f64, f64) {
        let p = |k: usize| if self.projected[k] { self.projector[k][0][0] } else { 1.0 };
        (p(i), p(j))
    }

    /// m_i Rᵢᵀ Sᵢ Rᵢ. The levers are taken from the aggregate's mass centre, so Σ m_i S(l_i) = 0 over
    /// it and only the inertia tensor Σ m (|l|² I − l lᵀ) and the mass Σ m I remain; a projector adds
    /// m Rᵢᵀ (Sᵢ − I) Rᵢ on top (it is idempotent), which keeps its rotation–translation terms.
    fn add_mass(&self, i: usize, d: &mut Block6) {
        let m = self.masses[i];
        if self.projected[i] {
            if self.per == 1 {
                d[0][0] += m * (self.projector[i][0][0] - 1.0);
            } else {
                let sm: [[f64; 3]; 3] = std::array::from_fn(|r| {
                    std::array::from_fn(|c| m * (self.projector[i][r][c] - if r == c { 1.0 } else { 0.0 }))
                });
                add_galerkin_block(d, self.lever[i], &sm);
            }
        }
        if self.per == 1 {
            d[0][0] += m;
        } else {
            let l = self.lever[i];
            let l2 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
            for p in 0..3 {
                for q in 0..3 {
                    d[p][q] -= m * l[p] * l[q];
                }
                d[p][p] += m * l2;
                d[p + 3][p + 3] += m;
            }
        }
    }

    /// What spring e adds to the diagonal block of aggregate g, one of its ends' (3-D springs between
    /// unprojected coordinates of two aggregates go through [`Self::add_across_to_diagonal`]).
    fn add_spring_to_diagonal(&self, g: u32, e: usize, d: &mut Block6) {
        let (i, j, gi, gj, u, s) = self.spring(e);
        if self.per == 1 {
            let (pi, pj) = self.scalar_projectors(i, j);
            let b = u[0] * u[0] + s;
            if gi != gj {
                let p = if gi == g { pi } else { pj };
                d[0][0] += p * b * p;
            } else if pi != 1.0 || pj != 1.0 {
                d[0][0] += (pi - pj) * b * (pi - pj);
            }
            return;
        }
        let (li, lj) = (self.lever[i], self.lever[j]);
        if self.projected[i] || self.projected[j] {
            // (Sᵢ Rᵢ − S_j R_j)ᵀ B (Sᵢ Rᵢ − S_j R_j) inside one aggregate; Rᵢᵀ Sᵢ B Sᵢ Rᵢ on i's side.
            let b = spring_matrix(u, s);
            if gi == g {
                add_galerkin_block(d, li, &self.projected_pair(i, &b, i));
            }
            if gj == g {
                add_galerkin_block(d, lj, &self.projected_pair(j, &b, j));
            }
            if gi == gj {
                let m = galerkin3(li, &self.projected_pair(i, &b, j), lj);
                for p in 0..MAX_PER {
                    for q in 0..MAX_PER {
                        d[p][q] -= m[p][q] + m[q][p];
                    }
                }
            }
            return;
        }
        if gi == gj {
            // (Rᵢ − R_j)ᵀ B (Rᵢ − R_j) with Rᵢ − R_j = [K | 0], K = S(x_i − x_j): rotations only.
            let k = skew(std::array::from_fn(|c| li[c] - lj[c]));
            let w: [f64; 3] = std::array::from_fn(|p| k[0][p] * u[0] + k[1][p] * u[1] + k[2][p] * u[2]);
            for p in 0..3 {
                for q in 0..3 {
                    d[p][q] += w[p] * w[q] + s * (k[0][p] * k[0][q] + k[1][p] * k[1][q] + k[2][p] * k[2][q]);
                }
            }
        }
    }

    /// −Rᵢᵀ Sᵢ B S_j R_j of spring e between two aggregates, to their coarse pair's block (stored as
    /// (lower aggregate, higher aggregate)).
    fn add_spring_between(&self, e: usize, o: &mut Block6) {
        let (i, j, _, _, u, s) = self.spring(e);
        if self.per == 1 {
            let (pi, pj) = self.scalar_projectors(i, j);
            o[0][0] -= pi * (u[0] * u[0] + s) * pj;
            return;
        }
        let (li, lj) = (self.lever[i], self.lever[j]);
        if self.projected[i] || self.projected[j] {
            let m = galerkin3(li, &self.projected_pair(i, &spring_matrix(u, s), j), lj);
            for p in 0..MAX_PER {
                for q in 0..MAX_PER {
                    if self.flip[e] {
                        o[q][p] -= m[p][q];
                    } else {
                        o[p][q] -= m[p][q];
                    }
                }
            }
        } else {
            let (vi, vj) = (modes_of(li, u), modes_of(lj, u));
            if self.flip[e] {
                add_galerkin(o, lj, li, &vj, &vi, s, -1.0);
            } else {
                add_galerkin(o, li, lj, &vi, &vj, s, -1.0);
            }
        }
    }

    /// Σ B (xx, yy, zz, xy, xz, yz) over `springs`, a coordinate's, in their order, of those between
    /// unprojected coordinates of two aggregates (3-D).
    fn add_across(&self, springs: &[u32], sum: &mut [f64; 6]) {
        for &e in springs {
            let (i, j, gi, gj, u, s) = self.spring(e as usize);
            if gi == gj || self.projected[i] || self.projected[j] {
                continue;
            }
            let b =
                [u[0] * u[0] + s, u[1] * u[1] + s, u[2] * u[2] + s, u[0] * u[1], u[0] * u[2], u[1] * u[2]];
            for c in 0..6 {
                sum[c] += b[c];
            }
        }
    }

    /// Rᵢᵀ Sᵢ (Σ B) Sᵢ Rᵢ of coordinate i's springs to other aggregates.
    fn add_across_to_diagonal(&self, i: usize, d: &mut Block6) {
        let c = self.across[i];
        if c.iter().all(|&v| v == 0.0) {
            return;
        }
        let mut b = [[c[0], c[3], c[4]], [c[3], c[1], c[5]], [c[4], c[5], c[2]]];
        if self.projected[i] {
            let p = &self.projector[i];
            b = mat3_mul(&mat3_mul(p, &b), p);
        }
        add_galerkin_block(d, self.lever[i], &b);
    }
}

/// Lists the items of `(row, item)` pairs (rows `NONE` left out) by row, each row's items in the order
/// given: row r's are `items[start[r]..start[r + 1]]`.
fn group(
    rows: usize,
    pairs: impl Iterator<Item = (u32, usize)> + Clone,
    items: &mut Vec<u32>,
    start: &mut Vec<u32>,
) {
    start.clear();
    start.resize(rows + 1, 0);
    for (r, _) in pairs.clone() {
        if r != NONE {
            start[r as usize + 1] += 1;
        }
    }
    for r in 0..rows {
        start[r + 1] += start[r];
    }
    let mut fill: Vec<u32> = start[..rows].to_vec();
    items.clear();
    items.resize(start[rows] as usize, 0);
    for (r, e) in pairs {
        if r != NONE {
            items[fill[r as usize] as usize] = e as u32;
            fill[r as usize] += 1;
        }
    }
}

/// B = u uᵀ + s I.
#[inline]
fn spring_matrix(u: [f64; 3], s: f64) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| u[r] * u[c] + if r == c { s } else { 0.0 }))
}

impl<C: Coord> Clone for RigidAggregation<C> {
    /// A clone starts unbuilt (faer's factor cannot be cloned): its first solve builds the coarse
    /// matrix from the A of that moment, where the original may still use the one of the step's first
    /// Newton iteration, so a clone taken between a step's Newton iterations can differ in round-off.
    /// Clones taken between steps step exactly as the original.
    fn clone(&self) -> Self {
        let mut clone = Self::new(self.radius, self.sweeps);
        // What the smoothing's estimate depends on, so that the clone's ω follows the original's.
        clone.pattern.clone_from(&self.pattern);
        clone.fixed.clone_from(&self.fixed);
        clone.bounded = self.bounded;
        clone.omega = self.omega;
        clone.power.clone_from(&self.power);
        clone.since_estimate = self.since_estimate;
        clone
    }
}

impl<C: Coord> Default for RigidAggregation<C> {
    fn default() -> Self {
        Self::new(RADIUS, SWEEPS)
    }
}

impl<C: Coord> RigidAggregation<C> {
    pub fn new(radius: usize, sweeps: usize) -> Self {
        Self {
            radius,
            sweeps: sweeps.max(1),
            pattern: Vec::new(),
            fixed: Vec::new(),
            agg: Vec::new(),
            members: Vec::new(),
            member_start: Vec::new(),
            restricted: Vec::new(),
            n_agg: 0,
            per: 0,
            lever: Vec::new(),
            pair_of: Vec::new(),
            flip: Vec::new(),
            n_pairs: 0,
            agg_springs: Vec::new(),
            agg_spring_start: Vec::new(),
            pair_springs: Vec::new(),
            pair_spring_start: Vec::new(),
            incident: Vec::new(),
            incident_start: Vec::new(),
            d_blocks: Vec::new(),
            o_blocks: Vec::new(),
            s_diag: Vec::new(),
            s_off: Vec::new(),
            solver: None,
            y: Vec::new(),
            az: Vec::new(),
            centres: Vec::new(),
            across: Vec::new(),
            projector: Vec::new(),
            projected: Vec::new(),
            factorizations: 0,
            bounded: false,
            omega: SMOOTHING,
            power: Vec::new(),
            since_estimate: 0,
        }
    }

    /// Whether `filter` constrains other coordinates or directions than the filter the coarse matrix
    /// was built with: its Galerkin matrix (S R)ᵀ A (S R) is then not the solve's, and a coarse level
    /// that misses a direction the solve has freed over-corrects it.
    pub fn filter_changed(&self, filter: Filter<'_, C>) -> bool {
        let Filter::Projected(blocks) = filter else {
            return self.projected.iter().any(|&p| p);
        };
        if blocks.len() != self.projected.len() {
            return true;
        }
        let identity = C::block_identity(1.0);
        blocks.iter().enumerate().any(|(i, &b)| {
            let entry =
                |r: usize, c: usize| if r < C::DIM && c < C::DIM { C::block_entry(b, r, c) } else { 0.0 };
            if self.projected[i] {
                (0..3).any(|r| (0..3).any(|c| entry(r, c) != self.projector[i][r][c]))
            } else {
                (0..C::DIM).any(|r| (0..C::DIM).any(|c| entry(r, c) != C::block_entry(identity, r, c)))
            }
        })
    }

    /// Whether a coarse matrix has been factorised.
    pub fn is_built(&self) -> bool {
        self.factorizations > 0 && self.solver.is_some()
    }

    /// Aggregates grown by breadth-first search; the coarse pattern and its symbolic factorisation.
    fn aggregate(&mut self, pattern: &[(u32, u32)], prescribed: &[bool]) -> Result<(), String> {
        let n = prescribed.len();
        self.pattern.clear();
        self.pattern.extend_from_slice(pattern);
        self.fixed.clear();
        self.fixed.extend_from_slice(prescribed);
        self.per = if C::DIM == 3 { 6 } else { 1 };
        let per = self.per;
        // Adjacency in compressed rows.
        let mut start = vec![0u32; n + 1];
        for &(i, j) in pattern {
            start[i as usize + 1] += 1;
            start[j as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut adj = vec![0u32; 2 * pattern.len()];
        for &(i, j) in pattern {
            adj[fill[i as usize] as usize] = j;
            fill[i as usize] += 1;
            adj[fill[j as usize] as usize] = i;
            fill[j as usize] += 1;
        }
        self.agg.clear();
        self.agg.resize(n, NONE);
        let (mut frontier, mut next) = (Vec::new(), Vec::new());
        let mut count = 0u32;
        for seed in 0..n {
            if self.agg[seed] != NONE || prescribed[seed] {
                continue;
            }
            self.agg[seed] = count;
            frontier.clear();
            frontier.push(seed as u32);
            for _ in 0..self.radius {
                next.clear();
                for &p in &frontier {
                    for &q in &adj[start[p as usize] as usize..start[p as usize + 1] as usize] {
                        if self.agg[q as usize] == NONE && !prescribed[q as usize] {
                            self.agg[q as usize] = count;
                            next.push(q);
                        }
                    }
                }
                std::mem::swap(&mut frontier, &mut next);
            }
            count += 1;
        }
        self.n_agg = count as usize;
        // Members of each aggregate in increasing order, for the restriction's per-aggregate sums.
        group(
            self.n_agg,
            self.agg.iter().enumerate().map(|(i, &g)| (g, i)),
            &mut self.members,
            &mut self.member_start,
        );
        // Coarse pairs in order of first appearance.
        let mut index = std::collections::HashMap::new();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        self.pair_of.clear();
        self.flip.clear();
        for &(i, j) in pattern {
            let (gi, gj) = (self.agg[i as usize], self.agg[j as usize]);
            if gi == NONE || gj == NONE || gi == gj {
                self.pair_of.push(NONE);
                self.flip.push(false);
                continue;
            }
            let key = (gi.min(gj), gi.max(gj));
            let e = *index.entry(key).or_insert_with(|| {
                pairs.push(key);
                pairs.len() as u32 - 1
            });
            self.pair_of.push(e);
            self.flip.push(gi > gj);
        }
        self.n_pairs = pairs.len();
        let ends = |e: usize| [pattern[e].0 as usize, pattern[e].1 as usize];
        group(
            self.n_agg,
            (0..pattern.len()).flat_map(|e| {
                let [gi, gj] = ends(e).map(|i| self.agg[i]);
                [(gi, e), (if gj == gi { NONE } else { gj }, e)]
            }),
            &mut self.agg_springs,
            &mut self.agg_spring_start,
        );
        group(
            self.n_pairs,
            self.pair_of.iter().enumerate().map(|(e, &p)| (p, e)),
            &mut self.pair_springs,
            &mut self.pair_spring_start,
        );
        group(
            n,
            (0..pattern.len()).flat_map(|e| ends(e).map(|i| (i as u32, e))),
            &mut self.incident,
            &mut self.incident_start,
        );
        // The scalar pattern: inside each aggregate (upper triangle), then every coarse pair.
        let mut scalar = Vec::with_capacity(self.n_agg * per * (per - 1) / 2 + pairs.len() * per * per);
        for g in 0..self.n_agg {
            for p in 0..per {
                for q in p + 1..per {
                    scalar.push(((g * per + p) as u32, (g * per + q) as u32));
                }
            }
        }
        for &(gi, gj) in &pairs {
            for p in 0..per {
                for q in 0..per {
                    scalar.push(((gi as usize * per + p) as u32, (gj as usize * per + q) as u32));
                }
            }
        }
        self.solver = Some(SparseSolver::new::<f64>(self.n_agg * per, &scalar).map_err(|e| e.to_string())?);
        self.d_blocks = vec![[[0.0; MAX_PER]; MAX_PER]; self.n_agg];
        self.o_blocks = vec![[[0.0; MAX_PER]; MAX_PER]; self.n_pairs];
        self.s_diag = vec![0.0; self.n_agg * per];
        self.s_off = vec![0.0; scalar.len()];
        self.y = vec![0.0; self.n_agg * per];
        self.az.resize(n, C::default());
        self.lever.resize(n, [0.0; 3]);
        Ok(())
    }

    /// Rᵢᵀ B R_j for the modes of coordinates i and j (R = [S | I], rotations first, in 3-D).
    #[inline]
    fn galerkin(&self, i: usize, b: C::Block, j: usize) -> Block6 {
        if self.per == 1 {
            let mut out = [[0.0; MAX_PER]; MAX_PER];
            out[0][0] = C::block_entry(b, 0, 0);
            return out;
        }
        let b: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| C::block_entry(b, r, c)));
        galerkin3(self.lever[i], &b, self.lever[j])
    }

    /// Builds the coarse matrix Rᵀ A R for the current A and positions `x`, and factorises it (the
    /// aggregation itself is redone only when the pattern or the prescribed set changed). The caller
    /// calls this once per step: a coarse matrix kept over the step's later Newton iterations was
    /// measured to cost nothing in iterations (A turns little within a step) and saves its rebuild,
    /// while one kept for two steps raised the iterations by a fifth and for three by three fifths.
    pub fn update(
        &mut self,
        a: &SystemMatrix<C>,
        pattern: &[(u32, u32)],
        masses: &[f64],
        prescribed: &[bool],
        x: &[C],
        filter: Filter<'_, C>,
    ) -> Result<(), String> {
        let n = masses.len();
        let new_pattern = self.pattern != pattern || self.fixed != prescribed;
        if self.solver.is_none() || new_pattern {
            self.aggregate(pattern, prescribed)?;
        }
        self.estimate_smoothing(a, pattern, filter, new_pattern);
        // In spring form the diagonal's scalar part (the mass, and what the system adds to it) is what
        // the coarse level weighs, and the levers are taken about its centres.
        let masses = if a.spring_form { &a.masses[..] } else { masses };
        let per = self.per;
        // The projectors of the coordinates the filter constrains (prescribed ones are in no aggregate).
        self.projected.resize(n, false);
        self.projector.resize(n, [[0.0; 3]; 3]);
        let blocks = if let Filter::Projected(blocks) = filter { Some(blocks) } else { None };
        parallel::for_chunks2(&mut self.projected, &mut self.projector, |s, projected, projector| {
            let identity = C::block_identity(1.0);
            for (k, (projected, projector)) in projected.iter_mut().zip(projector).enumerate() {
                *projected = false;
                let Some(blocks) = blocks else { continue };
                let b = blocks[s + k];
                let entries: [[f64; 3]; 3] = std::array::from_fn(|r| {
                    std::array::from_fn(
                        |c| if r < C::DIM && c < C::DIM { C::block_entry(b, r, c) } else { 0.0 },
                    )
                });
                let same =
                    (0..C::DIM).all(|r| (0..C::DIM).all(|c| C::block_entry(identity, r, c) == entries[r][c]));
                if !same {
                    *projected = true;
                    *projector = entries;
                }
            }
        });
        // Levers from the aggregates' mass centres (each summed over its members in increasing order).
        if per == MAX_PER {
            let (members, member_start) = (&self.members, &self.member_start);
            self.centres.resize(self.n_agg, [0.0; 4]);
            parallel::for_chunks_min(&mut self.centres, 64, |s, out| {
                for (k, c) in out.iter_mut().enumerate() {
                    let g = s + k;
                    *c = [0.0; 4];
                    for &i in &members[member_start[g] as usize..member_start[g + 1] as usize] {
                        let i = i as usize;
                        for k in 0..3 {
                            c[k] += masses[i] * x[i].component(k);
                        }
                        c[3] += masses[i];
                    }
                }
            });
            let (agg, centre) = (&self.agg, &self.centres);
            parallel::for_chunks(&mut self.lever, |s, out| {
                for (k, lever) in out.iter_mut().enumerate() {
                    let i = s + k;
                    let g = agg[i];
                    *lever = if g == NONE {
                        [0.0; 3]
                    } else {
                        let c = centre[g as usize];
                        std::array::from_fn(|k| x[i].component(k) - c[k] / c[3])
                    };
                }
            });
        }
        if a.spring_form {
            self.galerkin_springs(a, masses);
        } else {
            for b in self.d_blocks.iter_mut().chain(self.o_blocks.iter_mut()) {
                *b = [[0.0; MAX_PER]; MAX_PER];
            }
            self.galerkin_blocks(a, pattern);
        }
        self.factorize_coarse()
    }

    /// Sets ω from λ̂, the largest eigenvalue of S J⁻¹ A (J the filtered diagonal blocks the smoothing
    /// uses), by power iteration: afresh for a new pattern, warm every [`ESTIMATE_EVERY`] set-ups
    /// otherwise. Serial sums and the product's own bits: the same ω on any thread count.
    fn estimate_smoothing(
        &mut self,
        a: &SystemMatrix<C>,
        pattern: &[(u32, u32)],
        filter: Filter<'_, C>,
        new_pattern: bool,
    ) {
        if !self.bounded {
            self.omega = SMOOTHING;
            return;
        }
        let n = a.jacobi.len();
        let fresh = new_pattern || self.power.len() != n;
        self.since_estimate += 1;
        if !fresh && self.since_estimate < ESTIMATE_EVERY {
            return;
        }
        self.since_estimate = 0;
        if fresh {
            self.power.clear();
            self.power.extend((0..n).map(|i| {
                let mut v = C::default();
                for k in 0..C::DIM {
                    v.set_component(k, (1.0 + (7 * i + 3 * k) as f64).sin());
                }
                filter.one(i, v)
            }));
        }
        let norm = |v: &[C]| v.iter().map(|c| c.dot(*c)).sum::<f64>().sqrt();
        let mut w = std::mem::take(&mut self.az);
        w.resize(n, C::default());
        let mut lambda = 0.0;
        for _ in 0..if fresh { FRESH_ITERATIONS } else { WARM_ITERATIONS } {
            let nv = norm(&self.power);
            if !(nv > 0.0 && nv.is_finite()) {
                break;
            }
            a.mul(pattern, filter, &self.power, &mut w);
            for (i, w) in w.iter_mut().enumerate() {
                *w = filter.one(i, C::block_mul(a.jacobi[i], *w));
            }
            let nw = norm(&w);
            if !(nw > 0.0 && nw.is_finite()) {
                break;
            }
            lambda = nw / nv;
            for (v, w) in self.power.iter_mut().zip(&w) {
                *v = *w * (1.0 / nw);
            }
        }
        self.az = w;
        self.omega = if SMOOTHING * lambda > SMOOTHING_BOUND { SMOOTHING_TARGET / lambda } else { SMOOTHING };
    }

    /// S B S' as a block, for the projectors of coordinates `i` and `j` (identity where not projected).
    fn projected_block(&self, i: usize, b: C::Block, j: usize) -> C::Block {
        let mut b = b;
        if self.projected[i] {
            b = C::block_mul_blocks(C::block_from_entries(self.projector[i]), b);
        }
        if self.projected[j] {
            b = C::block_mul_blocks(b, C::block_from_entries(self.projector[j]));
        }
        b
    }

    /// Rᵀ A R from A's blocks: Rᵢᵀ A_ii Rᵢ for every coordinate, Rᵢᵀ A_ij R_j for every pair (each with
    /// its coordinates' projectors).
    fn galerkin_blocks(&mut self, a: &SystemMatrix<C>, pattern: &[(u32, u32)]) {
        let (n, per) = (a.diag.len(), self.per);
        for i in 0..n {
            let g = self.agg[i];
            if g != NONE {
                let m = self.galerkin(i, self.projected_block(i, a.diag[i], i), i);
                let d = &mut self.d_blocks[g as usize];
                for p in 0..per {
                    for q in 0..per {
                        d[p][q] += m[p][q];
                    }
                }
            }
        }
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let (gi, gj) = (self.agg[i], self.agg[j]);
            if gi == NONE || gj == NONE {
                continue;
            }
            let m = self.galerkin(i, self.projected_block(i, a.off[e], j), j);
            if gi == gj {
                // A_ij and A_ji = A_ijᵀ both fall inside the aggregate.
                let d = &mut self.d_blocks[gi as usize];
                for p in 0..per {
                    for q in 0..per {
                        d[p][q] += m[p][q] + m[q][p];
                    }
                }
            } else {
                let o = &mut self.o_blocks[self.pair_of[e] as usize];
                if self.flip[e] {
                    for p in 0..per {
                        for q in 0..per {
                            o[q][p] += m[p][q];
                        }
                    }
                } else {
                    for p in 0..per {
                        for q in 0..per {
                            o[p][q] += m[p][q];
                        }
                    }
                }
            }
        }
    }

    /// Rᵀ A R from a spring-form A = M + Σ_e B_e (e_i − e_j)(e_i − e_j)ᵀ, B_e = u uᵀ + a I: the masses
    /// give m_i Rᵢᵀ Rᵢ; a spring inside one aggregate (Rᵢ − R_j)ᵀ B (Rᵢ − R_j), which moves only the
    /// rotations (Rᵢ − R_j = [S(x_i − x_j) | 0]); a spring between two aggregates Rᵢᵀ B Rᵢ and R_jᵀ B R_j
    /// on their diagonals and −Rᵢᵀ B R_j between them. The same matrix as [`Self::galerkin_blocks`] up
    /// to round-off, in about half the time (no 3 × 3 block products, and none of the cancellation
    /// between a spring's diagonal and pair terms inside an aggregate). A spring between aggregates adds
    /// its B to a per-coordinate sum, and each coordinate's Rᵢᵀ (Σ B) Rᵢ is added once: a sixth less
    /// set-up on the standard sheet than one Rᵢᵀ B Rᵢ per spring end.
    ///
    /// On every core, with the same bits on any thread count: each coarse block is summed by one
    /// thread from the lists of [`Self::aggregate`] (an aggregate's members and the springs that touch
    /// it, a coarse pair's springs, a coordinate's springs), in the order of one serial pass — the masses,
    /// then the springs in pattern order, then the per-coordinate sums.
    fn galerkin_springs(&mut self, a: &SystemMatrix<C>, masses: &[f64]) {
        let per = self.per;
        let terms = GalerkinTerms {
            per,
            agg: &self.agg,
            lever: &self.lever,
            projected: &self.projected,
            projector: &self.projector,
            flip: &self.flip,
            springs: &a.springs,
            masses,
            across: &[],
        };
        if per == MAX_PER {
            self.across.resize(masses.len(), [0.0; 6]);
            let (incident, start) = (&self.incident, &self.incident_start);
            parallel::for_chunks_min(&mut self.across, 1024, |s, out| {
                for (k, sum) in out.iter_mut().enumerate() {
                    let i = s + k;
                    *sum = [0.0; 6];
                    if terms.agg[i] != NONE {
                        terms.add_across(&incident[start[i] as usize..start[i + 1] as usize], sum);
                    }
                }
            });
        }
        let terms = GalerkinTerms { across: &self.across, ..terms };
        let (members, member_start) = (&self.members, &self.member_start);
        let (touching, touching_start) = (&self.agg_springs, &self.agg_spring_start);
        parallel::for_chunks_min(&mut self.d_blocks, 8, |s, out| {
            for (k, d) in out.iter_mut().enumerate() {
                let g = s + k;
                *d = [[0.0; MAX_PER]; MAX_PER];
                let members = &members[member_start[g] as usize..member_start[g + 1] as usize];
                for &i in members {
                    terms.add_mass(i as usize, d);
                }
                for &e in &touching[touching_start[g] as usize..touching_start[g + 1] as usize] {
                    terms.add_spring_to_diagonal(g as u32, e as usize, d);
                }
                if per == MAX_PER {
                    for &i in members {
                        terms.add_across_to_diagonal(i as usize, d);
                    }
                }
            }
        });
        let (between, between_start) = (&self.pair_springs, &self.pair_spring_start);
        parallel::for_chunks_min(&mut self.o_blocks, 32, |s, out| {
            for (k, o) in out.iter_mut().enumerate() {
                let p = s + k;
                *o = [[0.0; MAX_PER]; MAX_PER];
                for &e in &between[between_start[p] as usize..between_start[p + 1] as usize] {
                    terms.add_spring_between(e as usize, o);
                }
            }
        });
    }

    /// Assembles the coarse blocks into the scalar matrix and factorises it.
    fn factorize_coarse(&mut self) -> Result<(), String> {
        let per = self.per;
        // A one- or two-particle aggregate has rotations that move nothing (a zero row): a relative
        // 10⁻¹⁰ on the diagonal keeps the factorisation positive definite and leaves such modes inert.
        // When every coordinate is held (all pinned or sticking) the coarse matrix is zero: its identity
        // then serves, since the filtered residuals it is given are zero too.
        let scale = self.d_blocks.iter().flat_map(|d| (0..per).map(move |p| d[p][p])).fold(0.0, f64::max);
        let scale = if scale > 0.0 { scale } else { 1e10 };
        let mut e = 0;
        for (g, d) in self.d_blocks.iter().enumerate() {
            for p in 0..per {
                self.s_diag[g * per + p] = d[p][p] + 1e-10 * scale;
                for q in p + 1..per {
                    self.s_off[e] = d[p][q];
                    e += 1;
                }
            }
        }
        for o in &self.o_blocks {
            for p in 0..per {
                for q in 0..per {
                    self.s_off[e] = o[p][q];
                    e += 1;
                }
            }
        }
        let solver = self.solver.as_mut().expect("aggregated above");
        solver.factorize::<f64>(&self.s_diag, &self.s_off, Filter::None).map_err(|e| e.to_string())?;
        self.factorizations += 1;
        Ok(())
    }

    /// z += S R (Rᵀ A R)⁻¹ Rᵀ r (r already filtered). The restriction sums each aggregate's members in
    /// increasing order and the prolongation is per coordinate, so both run on every core with the
    /// serial loop's bits.
    fn coarse(&mut self, filter: Filter<'_, C>, r: &[C], z: &mut [C]) {
        let per = self.per;
        self.restricted.resize(self.n_agg, [0.0; MAX_PER]);
        let (members, start, lever) = (&self.members, &self.member_start, &self.lever);
        parallel::for_chunks(&mut self.restricted, |s, out| {
            for (k, y) in out.iter_mut().enumerate() {
                let g = s + k;
                *y = [0.0; MAX_PER];
                for &i in &members[start[g] as usize..start[g + 1] as usize] {
                    let i = i as usize;
                    if per == 1 {
                        y[0] += r[i].component(0);
                    } else {
                        let (d, ri) = (lever[i], [r[i].component(0), r[i].component(1), r[i].component(2)]);
                        // Rotations: (e_k × d)·r = e_k·(d × r); translations: r.
                        y[0] += d[1] * ri[2] - d[2] * ri[1];
                        y[1] += d[2] * ri[0] - d[0] * ri[2];
                        y[2] += d[0] * ri[1] - d[1] * ri[0];
                        y[3] += ri[0];
                        y[4] += ri[1];
                        y[5] += ri[2];
                    }
                }
            }
        });
        for (g, y) in self.restricted.iter().enumerate() {
            self.y[g * per..(g + 1) * per].copy_from_slice(&y[..per]);
        }
        self.solver.as_mut().expect("updated before use").solve_in_place(&mut self.y, 1);
        let (agg, y) = (&self.agg, &self.y);
        parallel::for_chunks(z, |s, z| {
            for (k, z) in z.iter_mut().enumerate() {
                let i = s + k;
                let g = agg[i];
                if g == NONE {
                    continue;
                }
                let y = &y[g as usize * per..(g as usize + 1) * per];
                let mut v = C::default();
                if per == 1 {
                    v.set_component(0, y[0]);
                } else {
                    // ω × d + t.
                    let d = lever[i];
                    v.set_component(0, y[1] * d[2] - y[2] * d[1] + y[3]);
                    v.set_component(1, y[2] * d[0] - y[0] * d[2] + y[4]);
                    v.set_component(2, y[0] * d[1] - y[1] * d[0] + y[5]);
                }
                *z += filter.one(i, v);
            }
        });
    }
}

impl<C: Coord> Preconditioner<C> for RigidAggregation<C> {
    fn apply(
        &mut self,
        a: &SystemMatrix<C>,
        pattern: &[(u32, u32)],
        filter: Filter<'_, C>,
        r: &[C],
        z: &mut [C],
    ) {
        let mut az = std::mem::take(&mut self.az);
        let omega = self.omega;
        // z += ω S J⁻¹ (r − A z), or z = ω S J⁻¹ r from z = 0 (`first`).
        let smooth = |z: &mut [C], az: &[C], first: bool| {
            parallel::for_chunks(z, |s, z| {
                for (k, z) in z.iter_mut().enumerate() {
                    let i = s + k;
                    let residual = if first { r[i] } else { r[i] - az[i] };
                    let step = filter.one(i, C::block_mul(a.jacobi[i], residual)) * omega;
                    *z = if first { step } else { *z + step };
                }
            });
        };
        // Pre-smoothing (damped block Jacobi from z = 0).
        smooth(z, &az, true);
        for _ in 1..self.sweeps {
            a.mul(pattern, filter, z, &mut az);
            smooth(z, &az, false);
        }
        // Coarse correction of the remaining residual.
        a.mul(pattern, filter, z, &mut az);
        parallel::for_chunks(&mut az, |s, az| {
            for (k, az) in az.iter_mut().enumerate() {
                *az = r[s + k] - *az;
            }
        });
        self.coarse(filter, &az, z);
        // Post-smoothing.
        for _ in 0..self.sweeps {
            a.mul(pattern, filter, z, &mut az);
            smooth(z, &az, false);
        }
        self.az = az;
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    /// A system matrix, its pattern, masses, prescribed flags and positions.
    type System = (SystemMatrix<DVec3>, Vec<(u32, u32)>, Vec<f64>, Vec<bool>, Vec<DVec3>);

    /// A spring-form matrix on a jittered 6 × 6 grid with row, column and skip-one springs and one
    /// prescribed corner, held both as blocks and as springs.
    fn spring_system() -> System {
        spring_system_of(6)
    }

    /// [`spring_system`] on an n × n grid.
    fn spring_system_of(n: usize) -> System {
        let id = |i: usize, j: usize| (j * n + i) as u32;
        let mut pattern = Vec::new();
        for j in 0..n {
            for i in 0..n {
                if i + 1 < n {
                    pattern.push((id(i, j), id(i + 1, j)));
                }
                if j + 1 < n {
                    pattern.push((id(i, j), id(i, j + 1)));
                }
                if i + 2 < n {
                    pattern.push((id(i, j), id(i + 2, j)));
                }
            }
        }
        let wobble = |k: usize, s: f64| ((k as f64 + 1.0) * s).sin();
        let x: Vec<DVec3> = (0..n * n)
            .map(|k| DVec3::new((k % n) as f64 + 0.1 * wobble(k, 1.3), (k / n) as f64, 0.2 * wobble(k, 0.7)))
            .collect();
        let masses: Vec<f64> = (0..n * n).map(|k| 1.0 + 0.5 * wobble(k, 2.1)).collect();
        let prescribed: Vec<bool> = (0..n * n).map(|k| k == 0).collect();
        let mut a = SystemMatrix::<DVec3>::new();
        a.resize(n * n, &pattern);
        a.spring_form = true;
        a.springs.clear();
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let d = (x[j as usize] - x[i as usize]).normalize();
            let (u, s) = (d * (3.0 + wobble(e, 0.9)), 0.4 + 0.3 * wobble(e, 1.7));
            a.springs.push(super::super::SpringBlock { i, j, u, a: s });
            let b = DVec3::block_combine(DVec3::block_outer(u, u), 1.0, DVec3::block_identity(s), 1.0);
            a.off[e] = DVec3::block_combine(b, -1.0, b, 0.0);
            a.diag[i as usize] = DVec3::block_combine(a.diag[i as usize], 1.0, b, 1.0);
            a.diag[j as usize] = DVec3::block_combine(a.diag[j as usize], 1.0, b, 1.0);
        }
        a.add_masses(&masses, &vec![0.0; masses.len()]);
        (a, pattern, masses, prescribed, x)
    }

    #[test]
    fn the_spring_form_galerkin_matrix_equals_the_block_one() {
        let (mut a, pattern, masses, prescribed, x) = spring_system();
        let mut from_springs = RigidAggregation::<DVec3>::new(1, 1);
        from_springs.update(&a, &pattern, &masses, &prescribed, &x, Filter::None).unwrap();
        a.spring_form = false;
        let mut from_blocks = RigidAggregation::<DVec3>::new(1, 1);
        from_blocks.update(&a, &pattern, &masses, &prescribed, &x, Filter::None).unwrap();
        assert!(from_blocks.n_agg > 3 && from_blocks.n_pairs > 3, "aggregates {}", from_blocks.n_agg);
        let scale = from_blocks.s_diag.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let close = |p: &[f64], q: &[f64]| p.iter().zip(q).all(|(p, q)| (p - q).abs() <= 1e-12 * scale);
        assert!(close(&from_springs.s_diag, &from_blocks.s_diag), "diagonal");
        assert!(close(&from_springs.s_off, &from_blocks.s_off), "off-diagonal");
        assert!(from_blocks.s_off.iter().any(|v| v.abs() > 1e-3 * scale), "a coarse matrix with couplings");
    }

    /// The coarse blocks are summed one a thread from fixed lists: the same bits on one thread and on
    /// four, with contacts projecting some coordinates (a grid large enough for every loop of the
    /// set-up to split).
    #[test]
    fn the_coarse_matrix_is_the_same_bits_on_any_thread_count() {
        let (a, pattern, masses, prescribed, x) = spring_system_of(48);
        let n = masses.len();
        let identity = DVec3::block_identity(1.0);
        let normal = DVec3::new(0.3, -0.2, 0.9).normalize();
        let sliding = DVec3::block_combine(identity, 1.0, DVec3::block_outer(normal, normal), -1.0);
        let proj: Vec<_> = (0..n)
            .map(|i| match (i % 7, i % 11) {
                (0, _) => sliding,
                (_, 0) => DVec3::block_identity(0.0),
                _ => identity,
            })
            .collect();
        let coarse = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut agg = RigidAggregation::<DVec3>::new(1, 1);
                agg.update(&a, &pattern, &masses, &prescribed, &x, Filter::Projected(&proj)).unwrap();
                assert!(agg.n_agg >= 64 && n >= 2048, "too small to split: {} aggregates", agg.n_agg);
                let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                (bits(&agg.s_diag), bits(&agg.s_off))
            })
        };
        let one = coarse(1);
        assert!(one == coarse(4), "the coarse matrix depends on the thread count");
        assert!(one == coarse(3), "the coarse matrix depends on the thread count");
    }

    #[test]
    fn the_spring_form_product_equals_the_block_one() {
        let (mut a, pattern, ..) = spring_system();
        let x: Vec<DVec3> =
            (0..36).map(|k| DVec3::new((k as f64).cos(), (k as f64 * 0.3).sin(), 0.5)).collect();
        let (mut y1, mut y2) = (vec![DVec3::ZERO; 36], vec![DVec3::ZERO; 36]);
        a.mul(&pattern, Filter::None, &x, &mut y1);
        a.spring_form = false;
        a.mul(&pattern, Filter::None, &x, &mut y2);
        for (p, q) in y1.iter().zip(&y2) {
            assert!((*p - *q).length() < 1e-12 * (1.0 + q.length()), "{p} {q}");
        }
    }

    /// Where damped block Jacobi at ω = 0.7 would amplify the stiffest modes (ω λ > 2, λ the largest
    /// eigenvalue of J⁻¹A), ω is lowered to 1.6/λ̂, and CG with the two-level cycle needs fewer
    /// iterations than with block Jacobi alone, where at 0.7 it needed more (as on the remeshed drape
    /// of [`SMOOTHING_BOUND`]). The system is a bending energy's, M + (L²) ⊗ I with L the grid's
    /// Laplacian: its pairs two apart have negative weight, which lifts λ to 3.15 (with positive weights
    /// alone λ ≤ 2). On the plain spring grid ω stays 0.7.
    #[test]
    fn the_smoothing_is_damped_where_block_jacobi_would_amplify() {
        let (a, pattern, masses, prescribed, x) = spring_system_of(10);
        let plain_lambda = largest_eigenvalue(&a, &pattern);
        let mut plain = RigidAggregation::<DVec3>::new(1, 1);
        plain.bounded = true;
        plain.update(&a, &pattern, &masses, &prescribed, &x, Filter::None).unwrap();
        assert!(SMOOTHING * plain_lambda < SMOOTHING_BOUND, "the plain grid's λ is {plain_lambda}");
        assert_eq!(plain.omega, SMOOTHING);
        let masses: Vec<f64> = masses.iter().map(|m| 0.01 * m).collect();
        let (a, pattern) = bending_system(10, &masses);
        let n = masses.len();
        let lambda = largest_eigenvalue(&a, &pattern);
        assert!(SMOOTHING * lambda > 2.0, "the test needs ω = 0.7 to amplify: λ = {lambda}");
        let mut unbounded = RigidAggregation::<DVec3>::new(2, 1);
        unbounded.update(&a, &pattern, &masses, &prescribed, &x, Filter::Prescribed(&prescribed)).unwrap();
        assert_eq!(unbounded.omega, SMOOTHING, "unbounded, the damping is the fixed one");
        let mut agg = RigidAggregation::<DVec3>::new(2, 1);
        agg.bounded = true;
        agg.update(&a, &pattern, &masses, &prescribed, &x, Filter::Prescribed(&prescribed)).unwrap();
        // A sweep that contracts every mode, with its stiffest near the target (the power iteration's
        // λ̂ falls short of λ by a few per cent).
        let damping = agg.omega * lambda;
        assert!(damping > 0.95 * SMOOTHING_TARGET && damping < SMOOTHING_BOUND, "ω λ = {damping}");
        // Conjugate gradients to a relative residual of 10⁻⁸ with the cycle, and with block Jacobi.
        let filter = Filter::Prescribed(&prescribed);
        let mut b: Vec<DVec3> = (0..n).map(|i| DVec3::new(1.0, -0.5, 0.25) * (i as f64).cos()).collect();
        filter.apply(&mut b);
        let solve = |precond: &mut dyn Preconditioner<DVec3>| {
            let mut x = vec![DVec3::ZERO; n];
            let mut buffers = super::super::cg::CgBuffers::default();
            let outcome =
                super::super::cg::pcg(&a, &pattern, filter, precond, &b, &mut x, &mut buffers, 1e-8, 1000);
            assert!(outcome.converged);
            outcome.iterations
        };
        let damped = solve(&mut agg);
        let jacobi = solve(&mut super::super::cg::BlockJacobi);
        agg.omega = SMOOTHING;
        let undamped = solve(&mut agg);
        assert!(
            damped < jacobi && jacobi < undamped,
            "CG iterations: {damped} with ω = 1.6/λ̂, {undamped} with 0.7, {jacobi} without a coarse level"
        );
    }

    /// M + (L²) ⊗ I in spring form on an n × n grid, L the Laplacian of its rows and columns: pairs
    /// one apart weigh 8 (fewer at the border), pairs two apart along a row or column −1 and diagonal
    /// pairs −2.
    fn bending_system(n: usize, masses: &[f64]) -> (SystemMatrix<DVec3>, Vec<(u32, u32)>) {
        let count = n * n;
        let mut l = vec![vec![0.0f64; count]; count];
        for j in 0..n {
            for i in 0..n {
                let p = j * n + i;
                for (q, ok) in [(p + 1, i + 1 < n), (p + n, j + 1 < n)] {
                    if ok {
                        l[p][q] -= 1.0;
                        l[q][p] -= 1.0;
                        l[p][p] += 1.0;
                        l[q][q] += 1.0;
                    }
                }
            }
        }
        let mut pattern = Vec::new();
        let mut a = SystemMatrix::<DVec3>::new();
        a.springs.clear();
        for p in 0..count {
            for q in p + 1..count {
                let entry: f64 = (0..count).map(|k| l[p][k] * l[k][q]).sum();
                if entry != 0.0 {
                    pattern.push((p as u32, q as u32));
                    a.springs.push(super::super::SpringBlock {
                        i: p as u32,
                        j: q as u32,
                        u: DVec3::ZERO,
                        a: -entry,
                    });
                }
            }
        }
        a.resize(count, &pattern);
        a.spring_form = true;
        for (e, s) in a.springs.clone().iter().enumerate() {
            let b = DVec3::block_identity(s.a);
            a.off[e] = DVec3::block_combine(b, -1.0, b, 0.0);
            for k in [s.i, s.j] {
                a.diag[k as usize] = DVec3::block_combine(a.diag[k as usize], 1.0, b, 1.0);
            }
        }
        a.add_masses(masses, &vec![0.0; count]);
        (a, pattern)
    }

    /// λ_max(J⁻¹A) by 300 power iterations.
    fn largest_eigenvalue(a: &SystemMatrix<DVec3>, pattern: &[(u32, u32)]) -> f64 {
        let n = a.jacobi.len();
        let mut v: Vec<DVec3> =
            (0..n).map(|i| DVec3::new(1.0, (i as f64).sin(), (2.0 * i as f64).cos())).collect();
        let mut w = vec![DVec3::ZERO; n];
        let mut lambda = 0.0;
        for _ in 0..300 {
            a.mul(pattern, Filter::None, &v, &mut w);
            for i in 0..n {
                w[i] = DVec3::block_mul(a.jacobi[i], w[i]);
            }
            let (nv, nw) = (
                v.iter().map(|c| c.length_squared()).sum::<f64>().sqrt(),
                w.iter().map(|c| c.length_squared()).sum::<f64>().sqrt(),
            );
            lambda = nw / nv;
            for i in 0..n {
                v[i] = w[i] / nw;
            }
        }
        lambda
    }

    /// The coarse matrix equals (S R)ᵀ A (S R) computed column by column from products with A: with
    /// springs, isotropic pairs of negative weight (the bending elements' form), extra diagonal terms
    /// and contact projectors (a sliding and a sticking coordinate).
    #[test]
    fn the_coarse_matrix_is_the_galerkin_product_of_the_filtered_system() {
        for (with_pairs, with_projectors, extra) in [
            (false, false, 0.0),
            (false, false, 0.25),
            (false, true, 0.0),
            (true, false, 0.0),
            (true, true, 0.25),
        ] {
            galerkin_case(with_pairs, with_projectors, extra);
        }
    }

    fn galerkin_case(with_pairs: bool, with_projectors: bool, extra: f64) {
        let (mut a, mut pattern, masses, prescribed, x) = spring_system();
        let n = masses.len();
        if with_pairs {
            // Pairs across cells, a multiple of the identity of either sign.
            for (k, (i, j)) in
                [(1u32, 8u32), (7, 2), (14, 21), (20, 15), (27, 34), (33, 28)].into_iter().enumerate()
            {
                pattern.push((i.min(j), i.max(j)));
                let weight = if k % 2 == 0 { -0.3 } else { 0.45 };
                a.springs.push(super::super::SpringBlock {
                    i: i.min(j),
                    j: i.max(j),
                    u: DVec3::ZERO,
                    a: weight,
                });
            }
        }
        a.resize(n, &pattern);
        a.spring_form = true;
        a.masses = masses.iter().map(|m| m + extra).collect();
        // Projectors: coordinate 9 slides on a plane, 22 sticks.
        let identity = DVec3::block_identity(1.0);
        let mut proj = vec![identity; n];
        let normal = DVec3::new(0.3, -0.2, 0.9).normalize();
        if with_projectors {
            proj[9] = DVec3::block_combine(identity, 1.0, DVec3::block_outer(normal, normal), -1.0);
            proj[22] = DVec3::block_identity(0.0);
        }
        let filter = Filter::Projected(&proj);
        let mut agg = RigidAggregation::<DVec3>::new(1, 1);
        agg.update(&a, &pattern, &masses, &prescribed, &x, filter).unwrap();
        // Columns of S R: aggregate g, mode p.
        let column = |g: usize, p: usize| -> Vec<DVec3> {
            (0..n)
                .map(|i| {
                    if agg.agg[i] == NONE || agg.agg[i] as usize != g {
                        return DVec3::ZERO;
                    }
                    let l = agg.lever[i];
                    let v = if p < 3 {
                        DVec3::AXES[p].cross(DVec3::new(l[0], l[1], l[2]))
                    } else {
                        DVec3::AXES[p - 3]
                    };
                    filter.one(i, v)
                })
                .collect()
        };
        // The coarse pair of two aggregates, stored as (lower, higher).
        let coarse_pair = |g: u32, h: u32| {
            pattern.iter().enumerate().find_map(|(e, &(i, j))| {
                let (gi, gj) = (agg.agg[i as usize], agg.agg[j as usize]);
                ((gi.min(gj), gi.max(gj)) == (g.min(h), g.max(h)) && gi != gj)
                    .then(|| agg.pair_of[e] as usize)
            })
        };
        let mut y = vec![DVec3::ZERO; n];
        let mut worst = 0.0f64;
        let scale = agg.d_blocks.iter().flat_map(|d| (0..6).map(move |p| d[p][p].abs())).fold(0.0, f64::max);
        for g in 0..agg.n_agg {
            for p in 0..6 {
                let c = column(g, p);
                a.mul(&pattern, Filter::None, &c, &mut y);
                for h in 0..agg.n_agg {
                    for q in 0..6 {
                        let r = column(h, q);
                        let entry: f64 = r.iter().zip(&y).map(|(r, y)| r.dot(*y)).sum();
                        let stored = if g == h {
                            agg.d_blocks[g][q][p]
                        } else {
                            match coarse_pair(g as u32, h as u32) {
                                Some(e) if h < g => agg.o_blocks[e][q][p],
                                Some(e) => agg.o_blocks[e][p][q],
                                None => 0.0,
                            }
                        };
                        worst = worst.max((entry - stored).abs());
                    }
                }
            }
        }
        assert!(
            worst <= 1e-10 * scale,
            "pairs {with_pairs}, projectors {with_projectors}, extra {extra}: largest difference {worst} (scale {scale})"
        );
    }
}
