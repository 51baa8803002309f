//! A small dense Cholesky factorisation done in place on a preallocated buffer, so that
//! the plant step does not allocate (nalgebra's `Cholesky` takes its matrix by value).

/// An `n x n` symmetric positive-definite system: the matrix is written into
/// [`SpdSystem::matrix_mut`] (row-major, full), factored in place by
/// [`SpdSystem::factor`] and then solved any number of times.
#[derive(Clone, Debug)]
pub(crate) struct SpdSystem {
    n: usize,
    /// Row-major; after `factor` its lower triangle holds L (`A = L L^T`).
    a: Vec<f64>,
    /// 1 / L_jj.
    inv_diag: Vec<f64>,
}

impl SpdSystem {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            a: vec![0.0; n * n],
            inv_diag: vec![0.0; n],
        }
    }

    /// The row-major matrix to fill before [`Self::factor`].
    #[inline(always)]
    pub(crate) fn matrix_mut(&mut self) -> &mut [f64] {
        &mut self.a
    }

    /// Factors in place. Returns `false` (and leaves the system unusable) when the matrix
    /// is not numerically positive definite or not finite.
    #[inline]
    pub(crate) fn factor(&mut self) -> bool {
        match self.n {
            7 => self.factor_n::<7>(),
            6 => self.factor_n::<6>(),
            _ => self.factor_n::<0>(),
        }
    }

    /// [`Self::factor`] with the size a constant (`N > 0`, so that the loops unroll and the
    /// bounds checks fold away) or `self.n` (`N = 0`); the same operations either way.
    #[inline(always)]
    fn factor_n<const N: usize>(&mut self) -> bool {
        let n = if N > 0 { N } else { self.n };
        let a = &mut self.a[..n * n];
        let inv_diag = &mut self.inv_diag[..n];
        for j in 0..n {
            let mut d = a[j * n + j];
            for k in 0..j {
                let l = a[j * n + k];
                d -= l * l;
            }
            if !(d > 0.0 && d.is_finite()) {
                return false;
            }
            let ljj = d.sqrt();
            a[j * n + j] = ljj;
            let inv = 1.0 / ljj;
            inv_diag[j] = inv;
            for i in j + 1..n {
                let mut s = a[i * n + j];
                for k in 0..j {
                    s -= a[i * n + k] * a[j * n + k];
                }
                a[i * n + j] = s * inv;
            }
        }
        true
    }

    /// Solves `A x = b` in place (`x` holds `b` on entry), after a successful `factor`.
    #[inline]
    pub(crate) fn solve_in_place(&self, x: &mut [f64]) {
        match self.n {
            7 => self.solve_n::<7>(x),
            6 => self.solve_n::<6>(x),
            _ => self.solve_n::<0>(x),
        }
    }

    /// [`Self::solve_in_place`] with the size a constant or `self.n` (see
    /// [`Self::factor_n`]).
    #[inline(always)]
    fn solve_n<const N: usize>(&self, x: &mut [f64]) {
        let n = if N > 0 { N } else { self.n };
        let a = &self.a[..n * n];
        let inv_diag = &self.inv_diag[..n];
        let x = &mut x[..n];
        // L y = b.
        for i in 0..n {
            let row = &a[i * n..i * n + i];
            let mut s = x[i];
            for (k, l) in row.iter().enumerate() {
                s -= l * x[k];
            }
            x[i] = s * inv_diag[i];
        }
        // L^T x = y.
        for i in (0..n).rev() {
            let mut s = x[i];
            for k in i + 1..n {
                s -= a[k * n + i] * x[k];
            }
            x[i] = s * inv_diag[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_random_spd_system() {
        let n = 7;
        // A = B B^T + n I with a fixed B.
        let b: Vec<f64> = (0..n * n)
            .map(|k| ((k * 37 % 11) as f64 - 5.0) / 7.0)
            .collect();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                let mut s = if i == j { n as f64 } else { 0.0 };
                for k in 0..n {
                    s += b[i * n + k] * b[j * n + k];
                }
                a[i * n + j] = s;
            }
        }
        let rhs: Vec<f64> = (0..n).map(|i| i as f64 - 3.0).collect();
        let mut sys = SpdSystem::new(n);
        sys.matrix_mut().copy_from_slice(&a);
        assert!(sys.factor());
        let mut x = rhs.clone();
        sys.solve_in_place(&mut x);
        for i in 0..n {
            let r: f64 = (0..n).map(|j| a[i * n + j] * x[j]).sum();
            assert!((r - rhs[i]).abs() < 1e-12, "row {i}: {r} vs {}", rhs[i]);
        }
    }

    #[test]
    fn rejects_indefinite_and_nan() {
        let mut sys = SpdSystem::new(2);
        sys.matrix_mut().copy_from_slice(&[1.0, 2.0, 2.0, 1.0]);
        assert!(!sys.factor());
        sys.matrix_mut().copy_from_slice(&[f64::NAN, 0.0, 0.0, 1.0]);
        assert!(!sys.factor());
    }
}
