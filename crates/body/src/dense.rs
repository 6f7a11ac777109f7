//! A small dense symmetric positive-definite solve in caller-owned storage: the articulated mass
//! matrix of one humanoid is 16 × 16, far below where a library pays off, and owning the buffers keeps
//! the step loop free of allocation.

/// An n × n symmetric positive-definite system, row-major, factorised in place (Cholesky, L Lᵀ).
#[derive(Debug, Clone)]
pub(crate) struct SpdSystem {
    n: usize,
    a: Vec<f64>,
}

impl SpdSystem {
    pub fn new(n: usize) -> Self {
        Self { n, a: vec![0.0; n * n] }
    }

    pub fn clear(&mut self) {
        self.a.fill(0.0);
    }

    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        self.a[i * self.n + j] += v;
    }

    /// Factorises A = L Lᵀ in place (lower triangle). Returns false if A is not positive definite.
    pub fn factorise(&mut self) -> bool {
        let n = self.n;
        for j in 0..n {
            let mut d = self.a[j * n + j];
            for k in 0..j {
                d -= self.a[j * n + k] * self.a[j * n + k];
            }
            if d <= 0.0 || !d.is_finite() {
                return false;
            }
            let d = d.sqrt();
            self.a[j * n + j] = d;
            for i in j + 1..n {
                let mut s = self.a[i * n + j];
                for k in 0..j {
                    s -= self.a[i * n + k] * self.a[j * n + k];
                }
                self.a[i * n + j] = s / d;
            }
        }
        true
    }

    /// Solves A x = b in place after [`SpdSystem::factorise`].
    #[expect(clippy::needless_range_loop, reason = "index form mirrors the triangular substitutions")]
    pub fn solve(&self, x: &mut [f64]) {
        let n = self.n;
        for i in 0..n {
            let mut s = x[i];
            for k in 0..i {
                s -= self.a[i * n + k] * x[k];
            }
            x[i] = s / self.a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = x[i];
            for k in i + 1..n {
                s -= self.a[k * n + i] * x[k];
            }
            x[i] = s / self.a[i * n + i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_known_system() {
        // A = [[4, 2, 0], [2, 5, 1], [0, 1, 3]], x = (1, −2, 3) → b = A x.
        let a = [[4.0, 2.0, 0.0], [2.0, 5.0, 1.0], [0.0, 1.0, 3.0]];
        let x = [1.0, -2.0, 3.0];
        let mut sys = SpdSystem::new(3);
        for (i, row) in a.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                sys.add(i, j, v);
            }
        }
        let mut b: Vec<f64> = (0..3).map(|i| (0..3).map(|j| a[i][j] * x[j]).sum()).collect();
        assert!(sys.factorise());
        sys.solve(&mut b);
        for (i, (bi, xi)) in b.iter().zip(x).enumerate() {
            assert!((bi - xi).abs() < 1e-12, "x[{i}] = {bi}");
        }
    }

    #[test]
    fn rejects_an_indefinite_matrix() {
        let mut sys = SpdSystem::new(2);
        sys.add(0, 0, 1.0);
        sys.add(0, 1, 2.0);
        sys.add(1, 0, 2.0);
        sys.add(1, 1, 1.0);
        assert!(!sys.factorise());
    }
}
