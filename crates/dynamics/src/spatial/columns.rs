//! The CRBA's composite inertia in a column layout.

use nalgebra::Vector3;

use super::{Force, Inertia, Motion, Transform};

/// A spatial inertia in the layout of the CRBA's composite pass: the rotational inertia
/// as three columns and the first moment, each padded to four values, so that a frame
/// change is a few independent 4-wide multiply-adds (the same formula as
/// [`Inertia::transformed`], ordered for short dependency chains).
#[derive(Clone, Copy, Debug)]
pub(crate) struct InertiaColumns {
    mass: f64,
    first_moment: [f64; 4],
    columns: [[f64; 4]; 3],
}

/// `sum_k v[k] * c[k]` over three padded columns.
#[inline(always)]
fn combine(c: &[[f64; 4]; 3], v: [f64; 3]) -> [f64; 4] {
    let mut out = [0.0; 4];
    for (l, o) in out.iter_mut().enumerate() {
        *o = c[0][l] * v[0] + c[1][l] * v[1] + c[2][l] * v[2];
    }
    out
}

impl InertiaColumns {
    /// The column form of `inertia`.
    #[inline(always)]
    pub(crate) fn new(inertia: &Inertia) -> Self {
        let i = &inertia.rotational;
        let h = &inertia.first_moment;
        Self {
            mass: inertia.mass,
            first_moment: [h.x, h.y, h.z, 0.0],
            columns: [
                [i[(0, 0)], i[(1, 0)], i[(2, 0)], 0.0],
                [i[(0, 1)], i[(1, 1)], i[(2, 1)], 0.0],
                [i[(0, 2)], i[(1, 2)], i[(2, 2)], 0.0],
            ],
        }
    }

    /// Sum of two inertias in the same frame.
    #[inline(always)]
    pub(crate) fn add(&self, o: &Self) -> Self {
        let mut out = *self;
        out.mass += o.mass;
        for l in 0..4 {
            out.first_moment[l] += o.first_moment[l];
            for k in 0..3 {
                out.columns[k][l] += o.columns[k][l];
            }
        }
        out
    }

    /// Expressed in the parent frame of `x`: `h' = R h + m p`,
    /// `I' = R I R^T - (p w^T + w p^T) + 2 (p . w) 1` with `w = R h + (m / 2) p`
    /// (the parallel-axis terms of [`Inertia::transformed`] regrouped).
    #[inline(always)]
    pub(crate) fn transformed(&self, x: &Transform) -> Self {
        let r = &x.rotation;
        let rc = [
            [r[(0, 0)], r[(1, 0)], r[(2, 0)], 0.0],
            [r[(0, 1)], r[(1, 1)], r[(2, 1)], 0.0],
            [r[(0, 2)], r[(1, 2)], r[(2, 2)], 0.0],
        ];
        let p = [x.translation.x, x.translation.y, x.translation.z, 0.0];
        let m = self.mass;
        let h = &self.first_moment;
        let rh = combine(&rc, [h[0], h[1], h[2]]);
        // R I, column by column, then (R I) R^T.
        let c = &self.columns;
        let ri = [
            combine(&rc, [c[0][0], c[0][1], c[0][2]]),
            combine(&rc, [c[1][0], c[1][1], c[1][2]]),
            combine(&rc, [c[2][0], c[2][1], c[2][2]]),
        ];
        let mut w = [0.0; 4];
        let mut first_moment = [0.0; 4];
        for l in 0..4 {
            w[l] = rh[l] + 0.5 * m * p[l];
            first_moment[l] = rh[l] + m * p[l];
        }
        let pw2 = 2.0 * (p[0] * w[0] + p[1] * w[1] + p[2] * w[2]);
        let mut columns = [[0.0; 4]; 3];
        for (j, col) in columns.iter_mut().enumerate() {
            *col = combine(&ri, [rc[0][j], rc[1][j], rc[2][j]]);
            for l in 0..4 {
                col[l] -= p[l] * w[j] + w[l] * p[j];
            }
            col[j] += pw2;
        }
        Self {
            mass: m,
            first_moment,
            columns,
        }
    }

    /// The momentum `I m` of a body moving with `m` ([`Inertia::mul_motion`]).
    #[inline(always)]
    pub(crate) fn mul_motion(&self, m: &Motion) -> Force {
        let h = Vector3::new(
            self.first_moment[0],
            self.first_moment[1],
            self.first_moment[2],
        );
        let iw = combine(&self.columns, [m.angular.x, m.angular.y, m.angular.z]);
        Force {
            linear: m.linear * self.mass + m.angular.cross(&h),
            angular: Vector3::new(iw[0], iw[1], iw[2]) + h.cross(&m.linear),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::rpy_to_matrix;
    use nalgebra::Matrix3;

    fn sample_transform() -> Transform {
        Transform::new(rpy_to_matrix(0.3, -0.7, 1.1), Vector3::new(0.2, -0.4, 0.9))
    }

    #[test]
    fn column_form_transform_matches_inertia_transform() {
        let x = sample_transform();
        let a = Inertia::from_com(
            2.5,
            Vector3::new(0.1, -0.05, 0.2),
            Matrix3::new(0.3, 0.01, -0.02, 0.01, 0.25, 0.03, -0.02, 0.03, 0.2),
        );
        let b = Inertia::from_com(
            1.2,
            Vector3::new(-0.3, 0.2, 0.1),
            Matrix3::identity() * 0.05,
        );
        let m = Motion {
            linear: Vector3::new(0.1, 0.2, -0.3),
            angular: Vector3::new(1.0, -2.0, 0.5),
        };
        let want = b.add(&a.transformed(&x)).mul_motion(&m).to_vector();
        let cols = InertiaColumns::new(&b).add(&InertiaColumns::new(&a).transformed(&x));
        let got = cols.mul_motion(&m).to_vector();
        assert!((got - want).norm() < 1e-13 * want.norm(), "{got} vs {want}");
    }
}
