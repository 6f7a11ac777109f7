//! Forces of the FLEX3D surface model (Nedel 1993 §3.2) and the acceleration they give.

use anima_geom::DVec3;

use super::desc::FrictionMode;

/// Material and layout of one surface, as the force kernel needs them.
#[derive(Debug, Clone)]
pub(crate) struct SurfaceForces {
    pub offset: usize,
    pub rows: usize,
    pub cols: usize,
    pub spacing: f64,
    pub mass: f64,
    /// Horizontal, vertical, diagonal spring stiffness.
    pub k: [f64; 3],
    /// Horizontal, vertical, diagonal angular-spring stiffness.
    pub kc: [f64; 3],
    /// Gravity plus external force on each free particle: m·g + F_ext (or m·(g + F_ext)).
    pub body_force: DVec3,
}

impl SurfaceForces {
    pub fn n_particles(&self) -> usize {
        self.rows * self.cols
    }
}

/// Hooke spring force on the first end, p: f = −k (L − L0) d/L with d = x_p − x_q (Nedel 1993 §3.2.3,
/// Eq. 3.1 read with P_f the moving end). No force when the ends coincide.
#[inline(always)]
fn hooke(xp: DVec3, xq: DVec3, k: f64, l0: f64) -> DVec3 {
    let d = xp - xq;
    let l2 = d.length_squared();
    if l2 == 0.0 {
        return DVec3::ZERO;
    }
    let l = l2.sqrt();
    d * (-k * (l - l0) / l)
}

/// Elastic forces of one surface (horizontal, vertical, diagonal and anti-diagonal springs) added to `f`.
/// `x` and `f` are the surface's own slices.
///
/// The springs form a regular stencil on the grid, so no index arrays are needed. The loop walks the grid a
/// pair of rows at a time with row slices of known length, so that the compiler can drop bounds checks:
/// this is the hot loop of a FLEX3D step.
pub(crate) fn add_spring_forces(s: &SurfaceForces, x: &[DVec3], f: &mut [DVec3]) {
    let (m, n, r) = (s.rows, s.cols, s.spacing);
    let rd = r * std::f64::consts::SQRT_2;
    let [kh, kv, kd] = s.k;
    for i in 0..m {
        let (f_top, f_rest) = f[i * n..].split_at_mut(n);
        let x_top = &x[i * n..(i + 1) * n];
        if kh != 0.0 {
            for j in 0..n - 1 {
                let fp = hooke(x_top[j], x_top[j + 1], kh, r);
                f_top[j] += fp;
                f_top[j + 1] -= fp;
            }
        }
        if i + 1 == m {
            break;
        }
        let x_bot = &x[(i + 1) * n..(i + 2) * n];
        let f_bot = &mut f_rest[..n];
        if kv != 0.0 {
            for j in 0..n {
                let fp = hooke(x_top[j], x_bot[j], kv, r);
                f_top[j] += fp;
                f_bot[j] -= fp;
            }
        }
        if kd != 0.0 {
            // (i, j)–(i+1, j+1) and (i, j+1)–(i+1, j).
            for j in 0..n - 1 {
                let fp = hooke(x_top[j], x_bot[j + 1], kd, rd);
                f_top[j] += fp;
                f_bot[j + 1] -= fp;
                let fq = hooke(x_top[j + 1], x_bot[j], kd, rd);
                f_top[j + 1] += fq;
                f_bot[j] -= fq;
            }
        }
    }
}

/// Angular springs (Nedel 1993 §3.2.4): for each opposite neighbour pair (a, b) of P, a zero-length
/// spring pulls P towards M = P + (r/2)(û_a + û_b), the midpoint of the two length-r arms:
/// F = k_c (r/2)(û_a + û_b). It vanishes when a–P–b is straight. With `reaction`, −F/2 goes to each of a
/// and b so that momentum is conserved (an anima extension; the thesis puts no reaction on them).
pub(crate) fn add_bending_forces(s: &SurfaceForces, x: &[DVec3], f: &mut [DVec3], reaction: bool) {
    let (m, n, r) = (s.rows, s.cols, s.spacing);
    let [kch, kcv, kcd] = s.kc;
    let half_r = 0.5 * r;
    let mut pair = |p: usize, a: usize, b: usize, kc: f64| {
        let ua = (x[a] - x[p]).normalize_or_zero();
        let ub = (x[b] - x[p]).normalize_or_zero();
        let fp = (ua + ub) * (kc * half_r);
        f[p] += fp;
        if reaction {
            f[a] -= fp * 0.5;
            f[b] -= fp * 0.5;
        }
    };
    for i in 0..m {
        for j in 0..n {
            let p = i * n + j;
            let (has_up, has_down) = (i > 0, i + 1 < m);
            let (has_left, has_right) = (j > 0, j + 1 < n);
            if kch != 0.0 && has_left && has_right {
                pair(p, p - 1, p + 1, kch);
            }
            if kcv != 0.0 && has_up && has_down {
                pair(p, p - n, p + n, kcv);
            }
            if kcd != 0.0 && has_up && has_down && has_left && has_right {
                pair(p, p - n - 1, p + n + 1, kcd);
                pair(p, p - n + 1, p + n - 1, kcd);
            }
        }
    }
}

/// Turns the resultant F' of a free particle into its acceleration, with friction (Nedel 1993 §3.2.7):
/// literal: F = F' − μ|F'| v/|v|; viscous: F = F' − μ v. Returns a = F/m. With `clamp_dt = Some(Δt)`
/// the friction force is limited to m|v|/Δt, so that it cannot reverse the velocity in one step.
#[inline(always)]
pub(crate) fn acceleration_with_friction(
    f: DVec3,
    v: DVec3,
    inv_mass: f64,
    mode: FrictionMode,
    mu: f64,
    clamp_dt: Option<f64>,
) -> DVec3 {
    let mut friction = match mode {
        FrictionMode::Literal => {
            let speed2 = v.length_squared();
            if speed2 == 0.0 || mu == 0.0 {
                DVec3::ZERO
            } else {
                // μ|F'|/|v| with one square root.
                v * (-mu * (f.length_squared() / speed2).sqrt())
            }
        }
        FrictionMode::Viscous => v * -mu,
    };
    if let Some(dt) = clamp_dt {
        let limit = v.length() / (inv_mass * dt);
        let size = friction.length();
        if size > limit {
            friction *= limit / size;
        }
    }
    (f + friction) * inv_mass
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface(rows: usize, cols: usize, k: [f64; 3], kc: [f64; 3]) -> SurfaceForces {
        SurfaceForces { offset: 0, rows, cols, spacing: 1.0, mass: 1.0, k, kc, body_force: DVec3::ZERO }
    }

    fn flat_grid(rows: usize, cols: usize) -> Vec<DVec3> {
        (0..rows).flat_map(|i| (0..cols).map(move |j| DVec3::new(j as f64, -(i as f64), 0.0))).collect()
    }

    #[test]
    fn rest_grid_has_no_elastic_or_bending_force() {
        let s = surface(4, 5, [3.0, 4.0, 5.0], [1.0, 1.0, 1.0]);
        let x = flat_grid(4, 5);
        let mut f = vec![DVec3::ZERO; 20];
        add_spring_forces(&s, &x, &mut f);
        add_bending_forces(&s, &x, &mut f, false);
        assert!(f.iter().all(|v| v.length() < 1e-12), "{f:?}");
    }

    #[test]
    fn spring_forces_sum_to_zero_and_pull_back() {
        let s = surface(3, 3, [10.0, 20.0, 30.0], [0.0; 3]);
        let mut x = flat_grid(3, 3);
        x[4] += DVec3::new(0.1, 0.2, 0.3);
        let mut f = vec![DVec3::ZERO; 9];
        add_spring_forces(&s, &x, &mut f);
        let total: DVec3 = f.iter().copied().sum();
        assert!(total.length() < 1e-12, "springs must conserve momentum: {total}");
        assert!(f[4].dot(DVec3::new(0.1, 0.2, 0.3)) < 0.0, "the displaced centre is pulled back");
    }

    #[test]
    fn angular_spring_straightens_a_kink() {
        let s = surface(1, 3, [0.0; 3], [2.0, 0.0, 0.0]);
        // P at the origin, neighbours at ±x but raised: angle < 180°, force towards +y with size k_c·r·cos(θ/2).
        let x = vec![DVec3::new(-1.0, 1.0, 0.0), DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)];
        let mut f = vec![DVec3::ZERO; 3];
        add_bending_forces(&s, &x, &mut f, false);
        let expected = 2.0 * 1.0 * (std::f64::consts::FRAC_PI_4).cos();
        assert!((f[1] - DVec3::new(0.0, expected, 0.0)).length() < 1e-12, "{}", f[1]);
        assert_eq!(f[0], DVec3::ZERO, "the thesis puts no reaction on the neighbours");
        let mut g = vec![DVec3::ZERO; 3];
        add_bending_forces(&s, &x, &mut g, true);
        assert!(g.iter().copied().sum::<DVec3>().length() < 1e-12);
    }

    #[test]
    fn friction_modes() {
        let f = DVec3::new(0.0, -10.0, 0.0);
        let v = DVec3::new(2.0, 0.0, 0.0);
        let a = acceleration_with_friction(f, v, 0.5, FrictionMode::Literal, 0.5, None);
        assert_eq!(a, DVec3::new(-2.5, -5.0, 0.0));
        let a = acceleration_with_friction(f, v, 0.5, FrictionMode::Viscous, 0.5, None);
        assert_eq!(a, DVec3::new(-0.5, -5.0, 0.0));
        let a = acceleration_with_friction(f, DVec3::ZERO, 1.0, FrictionMode::Literal, 0.5, None);
        assert_eq!(a, f);
        // Clamped: friction on a slow particle stops it at most.
        let a = acceleration_with_friction(
            DVec3::ZERO,
            DVec3::X * 0.01,
            1.0,
            FrictionMode::Viscous,
            100.0,
            Some(0.1),
        );
        assert!((a.x + 0.1).abs() < 1e-15, "{a}");
    }
}
