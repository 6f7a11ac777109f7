//! CMA-ES: the (μ/μ_w, λ) covariance matrix adaptation evolution strategy with rank-one and rank-μ
//! updates and cumulative step-size adaptation, with IPOP restarts (the population doubles at each
//! restart). Written from Hansen's tutorial ("The CMA Evolution Strategy: A Tutorial", 2016) and
//! Auger & Hansen 2005 (IPOP); the formulas are quoted at the update.
//!
//! The search runs in scaled coordinates u = x / s with s the width of each bounded dimension (1 for
//! an unbounded one), so `sigma0` is a fraction of every interval. Bounds are met by mirroring a
//! sample back into the box; the mirrored point is what is evaluated and what the update learns
//! from. Whole-number dimensions are rounded for evaluation only.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::eigen::symmetric_eigen;
use super::{MAX_POPULATION, Normal, OptimiseError, Optimiser, Space, check_population, reflect, uniform};

/// CMA-ES settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CmaesConfig {
    /// The initial mean.
    pub x0: Vec<f64>,
    /// Initial step size, in units of each bounded dimension's width (absolute for an unbounded one).
    pub sigma0: f64,
    /// Population size λ, at most [`MAX_POPULATION`]; `None` for 4 + ⌊3 ln n⌋.
    pub lambda: Option<usize>,
    /// IPOP restarts after a stop criterion (0: plain CMA-ES, which then finishes). A restart starts
    /// from a uniform point of the box (x0 for unbounded dimensions) with λ multiplied by `increase`,
    /// up to [`MAX_POPULATION`].
    pub restarts: usize,
    pub increase: f64,
    /// Finish as soon as a fitness ≥ target is seen.
    pub target: Option<f64>,
    /// Stop a run when the best fitnesses of the last 10 + ⌈30n/λ⌉ generations, and all of the
    /// current one, lie within `tol_fun`.
    pub tol_fun: f64,
    /// Stop a run when σ · max(p_c,i, √C_ii) < tol_x · sigma0 in every coordinate.
    pub tol_x: f64,
}

impl CmaesConfig {
    /// Defaults: λ from n, 9 IPOP restarts, tolerances 1e-12.
    pub fn new(x0: Vec<f64>, sigma0: f64) -> Self {
        Self {
            x0,
            sigma0,
            lambda: None,
            restarts: 9,
            increase: 2.0,
            target: None,
            tol_fun: 1e-12,
            tol_x: 1e-12,
        }
    }
}

/// Strategy parameters that depend on n and λ (tutorial Table 1).
#[derive(Debug, Clone)]
struct Strategy {
    lambda: usize,
    mu: usize,
    weights: Vec<f64>,
    mueff: f64,
    cc: f64,
    cs: f64,
    c1: f64,
    cmu: f64,
    damps: f64,
}

impl Strategy {
    fn new(n: usize, lambda: usize) -> Self {
        let nf = n as f64;
        let mu = lambda / 2;
        let raw: Vec<f64> =
            (0..mu).map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - ((i + 1) as f64).ln()).collect();
        let sum: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / sum).collect();
        let mueff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();
        let cc = (4.0 + mueff / nf) / (nf + 4.0 + 2.0 * mueff / nf);
        let cs = (mueff + 2.0) / (nf + mueff + 5.0);
        let c1 = 2.0 / ((nf + 1.3).powi(2) + mueff);
        let cmu = (1.0 - c1).min(2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nf + 2.0).powi(2) + mueff));
        let damps = 1.0 + 2.0 * (((mueff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + cs;
        Self { lambda, mu, weights, mueff, cc, cs, c1, cmu, damps }
    }
}

/// CMA-ES with IPOP restarts, as an ask/tell [`Optimiser`].
#[derive(Debug, Clone)]
pub struct Cmaes {
    space: Space,
    cfg: CmaesConfig,
    rng: ChaCha8Rng,
    normal: Normal,
    n: usize,
    scale: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    st: Strategy,
    chi_n: f64,
    mean: Vec<f64>,
    sigma: f64,
    pc: Vec<f64>,
    ps: Vec<f64>,
    /// Covariance C, row-major.
    c: Vec<f64>,
    /// Eigenvectors of C as columns (row-major) and the square roots of its eigenvalues.
    b: Vec<f64>,
    d: Vec<f64>,
    eigen_generation: usize,
    generation: usize,
    restart: usize,
    history: Vec<f64>,
    pending: Vec<Vec<f64>>,
    best: Option<(Vec<f64>, f64)>,
    evaluations: usize,
    finished: bool,
}

impl Cmaes {
    pub fn new(space: Space, cfg: CmaesConfig, seed: u64) -> Result<Self, OptimiseError> {
        let n = space.len();
        if n == 0 || cfg.x0.len() != n {
            return Err(OptimiseError::Config(format!("x0 has {} values for {n} dimensions", cfg.x0.len())));
        }
        if !(cfg.sigma0 > 0.0 && cfg.sigma0.is_finite()) {
            return Err(OptimiseError::Config(format!("sigma0 must be positive, found {}", cfg.sigma0)));
        }
        if cfg.lambda.is_some_and(|l| l < 2) || cfg.increase.is_nan() || cfg.increase < 1.0 {
            return Err(OptimiseError::Config("λ must be ≥ 2 and the IPOP increase ≥ 1".into()));
        }
        let scale: Vec<f64> =
            space.dims.iter().map(|d| if d.bounded() && d.max > d.min { d.width() } else { 1.0 }).collect();
        let lo: Vec<f64> = space.dims.iter().zip(&scale).map(|(d, s)| d.min / s).collect();
        let hi: Vec<f64> = space.dims.iter().zip(&scale).map(|(d, s)| d.max / s).collect();
        let nf = n as f64;
        let lambda = cfg.lambda.unwrap_or(4 + (3.0 * nf.ln()).floor() as usize);
        check_population("λ", lambda)?;
        let mean: Vec<f64> = (0..n).map(|i| reflect(cfg.x0[i] / scale[i], lo[i], hi[i])).collect();
        let mut me = Self {
            st: Strategy::new(n, lambda),
            chi_n: nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf)),
            sigma: cfg.sigma0,
            rng: ChaCha8Rng::seed_from_u64(seed),
            normal: Normal::default(),
            n,
            scale,
            lo,
            hi,
            mean,
            pc: vec![0.0; n],
            ps: vec![0.0; n],
            c: vec![0.0; n * n],
            b: vec![0.0; n * n],
            d: vec![1.0; n],
            eigen_generation: 0,
            generation: 0,
            restart: 0,
            history: Vec::new(),
            pending: Vec::new(),
            best: None,
            evaluations: 0,
            finished: false,
            space,
            cfg,
        };
        me.reset_distribution();
        Ok(me)
    }

    fn reset_distribution(&mut self) {
        let n = self.n;
        self.sigma = self.cfg.sigma0;
        self.pc.fill(0.0);
        self.ps.fill(0.0);
        self.c.fill(0.0);
        self.b.fill(0.0);
        for i in 0..n {
            self.c[i * n + i] = 1.0;
            self.b[i * n + i] = 1.0;
        }
        self.d.fill(1.0);
        self.generation = 0;
        self.eigen_generation = 0;
        self.history.clear();
    }

    /// Restarts run so far (IPOP).
    pub fn restarts(&self) -> usize {
        self.restart
    }

    /// The current population size.
    pub fn lambda(&self) -> usize {
        self.st.lambda
    }

    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Evaluations told so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    pub fn finished(&self) -> bool {
        self.finished
    }

    fn to_x(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(&self.scale)
            .zip(&self.space.dims)
            .map(|((u, s), d)| if d.integer { d.admit(u * s) } else { u * s })
            .collect()
    }

    /// Should this run stop (tutorial, Appendix B)?
    fn stop_run(&self, fitness: &[f64]) -> bool {
        let n = self.n;
        let (sigma, d) = (self.sigma, &self.d);
        if !sigma.is_finite() || self.mean.iter().any(|m| !m.is_finite()) {
            return true;
        }
        // TolFun.
        let window = 10 + (30 * n).div_ceil(self.st.lambda);
        if self.history.len() >= window {
            let h = &self.history[self.history.len() - window..];
            let range = |v: &[f64]| {
                let (mn, mx) =
                    v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
                mx - mn
            };
            if range(h) < self.cfg.tol_fun && range(fitness) < self.cfg.tol_fun {
                return true;
            }
        }
        // TolX.
        if (0..n).all(|i| {
            sigma * self.pc[i].abs().max(self.c[i * n + i].sqrt()) < self.cfg.tol_x * self.cfg.sigma0
        }) {
            return true;
        }
        // ConditionCov.
        let (dmin, dmax) = d.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        if dmax * dmax > 1e14 * dmin * dmin {
            return true;
        }
        // NoEffectAxis: a tenth of a standard deviation along one principal axis leaves m unchanged.
        let k = self.generation % n;
        if (0..n).all(|i| self.mean[i] == self.mean[i] + 0.1 * sigma * d[k] * self.b[i * n + k]) {
            return true;
        }
        // NoEffectCoord.
        if (0..n).any(|i| self.mean[i] == self.mean[i] + 0.2 * sigma * self.c[i * n + i].sqrt()) {
            return true;
        }
        // TolUpSigma: σ grew absurdly compared with the largest axis of C.
        sigma * dmax > 1e20 * self.cfg.sigma0
    }

    fn start_restart(&mut self) {
        self.restart += 1;
        // `as` saturates, so even an infinite increase stops at the limit.
        let lambda = ((self.st.lambda as f64) * self.cfg.increase).round() as usize;
        self.st = Strategy::new(self.n, lambda.max(self.st.lambda).min(MAX_POPULATION));
        for i in 0..self.n {
            self.mean[i] = if self.lo[i].is_finite() && self.hi[i].is_finite() {
                uniform(&mut self.rng, self.lo[i], self.hi[i])
            } else {
                reflect(self.cfg.x0[i] / self.scale[i], self.lo[i], self.hi[i])
            };
        }
        self.normal = Normal::default();
        self.reset_distribution();
    }
}

impl Optimiser for Cmaes {
    fn name(&self) -> &'static str {
        "cma-es"
    }

    fn dimension(&self) -> usize {
        self.n
    }

    fn stage(&self) -> usize {
        self.restart
    }

    fn ask(&mut self) -> Vec<Vec<f64>> {
        if self.finished {
            return Vec::new();
        }
        let n = self.n;
        self.pending.clear();
        let mut z = vec![0.0; n];
        for _ in 0..self.st.lambda {
            for zi in &mut z {
                *zi = self.normal.sample(&mut self.rng);
            }
            // u = m + σ B D z, mirrored into the box.
            let u: Vec<f64> = (0..n)
                .map(|i| {
                    let y: f64 = (0..n).map(|k| self.b[i * n + k] * self.d[k] * z[k]).sum();
                    reflect(self.mean[i] + self.sigma * y, self.lo[i], self.hi[i])
                })
                .collect();
            self.pending.push(u);
        }
        self.pending.iter().map(|u| self.to_x(u)).collect()
    }

    fn tell(&mut self, candidates: &[Vec<f64>], fitness: &[f64]) -> Vec<bool> {
        assert_eq!(candidates.len(), self.pending.len(), "tell the generation just asked");
        assert_eq!(fitness.len(), candidates.len(), "one fitness per candidate");
        let n = self.n;
        let st = self.st.clone();
        self.evaluations += fitness.len();
        let fit: Vec<f64> = fitness.iter().map(|&f| if f.is_nan() { f64::NEG_INFINITY } else { f }).collect();

        let mut accepted = vec![false; fit.len()];
        for (k, &f) in fit.iter().enumerate() {
            if self.best.as_ref().is_none_or(|(_, b)| f > *b) {
                self.best = Some((candidates[k].clone(), f));
                accepted[k] = true;
            }
        }
        if let (Some(t), Some((_, b))) = (self.cfg.target, &self.best)
            && *b >= t
        {
            self.finished = true;
            return accepted;
        }

        // Rank: best first, ties by index (a stable sort).
        let mut order: Vec<usize> = (0..fit.len()).collect();
        order.sort_by(|&a, &b| fit[b].total_cmp(&fit[a]));

        // y_i = (u_i − m)/σ;  m ← Σ w_i u_{i:λ};  y_w = (m_new − m)/σ.
        let old = self.mean.clone();
        let ys: Vec<Vec<f64>> = order[..st.mu]
            .iter()
            .map(|&k| (0..n).map(|i| (self.pending[k][i] - old[i]) / self.sigma).collect())
            .collect();
        let mut yw = vec![0.0; n];
        for (w, y) in st.weights.iter().zip(&ys) {
            for i in 0..n {
                yw[i] += w * y[i];
            }
        }
        for i in 0..n {
            self.mean[i] = old[i] + self.sigma * yw[i];
        }

        // p_σ ← (1 − c_σ) p_σ + √(c_σ(2 − c_σ)μ_eff) C^{-1/2} y_w,  C^{-1/2} = B D⁻¹ Bᵀ.
        let bty: Vec<f64> =
            (0..n).map(|k| (0..n).map(|i| self.b[i * n + k] * yw[i]).sum::<f64>() / self.d[k]).collect();
        let cs_f = (st.cs * (2.0 - st.cs) * st.mueff).sqrt();
        for i in 0..n {
            let ci: f64 = (0..n).map(|k| self.b[i * n + k] * bty[k]).sum();
            self.ps[i] = (1.0 - st.cs) * self.ps[i] + cs_f * ci;
        }
        let ps_norm = self.ps.iter().map(|v| v * v).sum::<f64>().sqrt();
        // h_σ = 1 if ‖p_σ‖ / √(1 − (1 − c_σ)^{2(g+1)}) < (1.4 + 2/(n + 1)) E‖N(0, I)‖.
        let g = (self.generation + 1) as i32;
        let hsig =
            ps_norm / (1.0 - (1.0 - st.cs).powi(2 * g)).sqrt() < (1.4 + 2.0 / (n as f64 + 1.0)) * self.chi_n;
        let hs = if hsig { 1.0 } else { 0.0 };
        // p_c ← (1 − c_c) p_c + h_σ √(c_c(2 − c_c)μ_eff) y_w.
        let cc_f = (st.cc * (2.0 - st.cc) * st.mueff).sqrt();
        for (pc, y) in self.pc.iter_mut().zip(&yw) {
            *pc = (1.0 - st.cc) * *pc + hs * cc_f * y;
        }
        // C ← (1 − c₁ − c_μ + (1 − h_σ) c₁ c_c(2 − c_c)) C + c₁ p_c p_cᵀ + c_μ Σ w_i y_i y_iᵀ.
        let keep = 1.0 - st.c1 - st.cmu + (1.0 - hs) * st.c1 * st.cc * (2.0 - st.cc);
        for i in 0..n {
            for j in 0..=i {
                let mut rank_mu = 0.0;
                for (w, y) in st.weights.iter().zip(&ys) {
                    rank_mu += w * y[i] * y[j];
                }
                let v = keep * self.c[i * n + j] + st.c1 * self.pc[i] * self.pc[j] + st.cmu * rank_mu;
                self.c[i * n + j] = v;
                self.c[j * n + i] = v;
            }
        }
        // σ ← σ exp((c_σ/d_σ)(‖p_σ‖/E‖N(0, I)‖ − 1)).
        self.sigma *= ((st.cs / st.damps) * (ps_norm / self.chi_n - 1.0)).exp();
        self.generation += 1;

        // Decompose C every ~1/(10 n (c₁ + c_μ)) generations (tutorial, B.2).
        let gap = (1.0 / ((st.c1 + st.cmu) * n as f64 * 10.0)).max(1.0);
        if (self.generation - self.eigen_generation) as f64 >= gap {
            self.eigen_generation = self.generation;
            let mut w = vec![0.0; n];
            symmetric_eigen(&self.c, n, &mut w, &mut self.b);
            for (d, w) in self.d.iter_mut().zip(&w) {
                *d = w.max(1e-300).sqrt();
            }
        }

        let gen_best = fit[order[0]];
        self.history.push(gen_best);
        if self.stop_run(&fit) {
            if self.restart < self.cfg.restarts {
                self.start_restart();
            } else {
                self.finished = true;
            }
        }
        accepted
    }

    fn best(&self) -> Option<(&[f64], f64)> {
        self.best.as_ref().map(|(x, f)| (x.as_slice(), *f))
    }
}
