//! The exponential and logarithm of SO(3): orientation deviations and errors as rotation
//! vectors (axis times angle, base frame).

use nalgebra::{Matrix3, Vector3};

/// Below this angle (rad) the series forms are used (their truncation error, about
/// `angle^4 / 120`, is below rounding).
const SMALL_ANGLE: f64 = 1e-4;

/// `Exp(w)`: the rotation by `|w|` about `w / |w|` (Rodrigues). `Exp(0)` is exactly the
/// identity.
pub(crate) fn exp(w: &Vector3<f64>) -> Matrix3<f64> {
    let angle2 = w.norm_squared();
    let angle = angle2.sqrt();
    let (a, b) = if angle < SMALL_ANGLE {
        (1.0 - angle2 / 6.0, 0.5 - angle2 / 24.0)
    } else {
        let (s, c) = angle.sin_cos();
        (s / angle, (1.0 - c) / angle2)
    };
    let k = skew(w);
    Matrix3::identity() + k * a + (k * k) * b
}

/// `Log(r)`: the rotation vector `w` with `Exp(w) = r`, `|w|` in `[0, pi]`, for a rotation
/// matrix `r`. The axis is read from the skew-symmetric part of `r` (so a symmetric `r`,
/// e.g. `R R^T` computed in floating point, gives exactly zero), and from the symmetric part
/// near `pi`, where the skew part vanishes.
pub(crate) fn log(r: &Matrix3<f64>) -> Vector3<f64> {
    // s = sin(angle) axis; cos(angle) from the trace.
    let s = 0.5
        * Vector3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let c = (0.5 * (r.trace() - 1.0)).clamp(-1.0, 1.0);
    let sin = s.norm();
    let angle = sin.atan2(c);
    if angle < SMALL_ANGLE {
        // angle / sin(angle) = 1 + angle^2 / 6 + ...
        return s * (1.0 + angle * angle / 6.0);
    }
    if c > -0.9 {
        return s * (angle / sin);
    }
    // Near pi: (r + r^T) / 2 - c I = (1 - c) a a^T; take its largest column.
    let sym = 0.5 * (r + r.transpose()) - Matrix3::identity() * c;
    let k = (0..3)
        .max_by(|&i, &j| sym[(i, i)].total_cmp(&sym[(j, j)]))
        .unwrap_or(0);
    let column = sym.column(k).into_owned();
    let norm = column.norm();
    if norm.is_nan() || norm <= 0.0 {
        return s * (angle / sin.max(f64::MIN_POSITIVE));
    }
    let mut axis = column / norm;
    if axis.dot(&s) < 0.0 {
        axis = -axis;
    }
    axis * angle
}

/// `[w]x`, the cross-product matrix.
fn skew(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Matrix3<f64>, b: &Matrix3<f64>, tol: f64) -> bool {
        (a - b).abs().max() <= tol
    }

    #[test]
    fn exp_and_log_are_inverse_over_the_whole_range() {
        let axes = [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.3, -0.5, 0.8).normalize(),
            Vector3::new(-0.2, 0.1, -0.97).normalize(),
        ];
        for axis in axes {
            for angle in [
                0.0,
                1e-9,
                1e-5,
                1e-3,
                0.3,
                1.0,
                2.0,
                2.9,
                3.1,
                std::f64::consts::PI - 1e-5,
                std::f64::consts::PI - 1e-9,
            ] {
                let w = axis * angle;
                let r = exp(&w);
                // A rotation: orthonormal with determinant 1.
                assert!(close(&(r * r.transpose()), &Matrix3::identity(), 1e-14));
                assert!((r.determinant() - 1.0).abs() < 1e-14);
                let back = log(&r);
                assert!(
                    (back - w).norm() <= 1e-9 * (1.0 + angle),
                    "angle {angle}: {back} vs {w}"
                );
            }
        }
    }

    #[test]
    fn exp_matches_the_rotation_about_a_coordinate_axis() {
        let r = exp(&Vector3::new(0.0, 0.0, 0.5));
        let (s, c) = 0.5f64.sin_cos();
        assert!(close(
            &r,
            &Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
            1e-15
        ));
    }

    #[test]
    fn zero_is_exact() {
        assert_eq!(exp(&Vector3::zeros()), Matrix3::identity());
        // R R^T of an arbitrary rotation is symmetric in floating point: its log is exactly 0.
        let r = exp(&Vector3::new(0.4, -1.1, 0.7));
        assert_eq!(log(&(r * r.transpose())), Vector3::zeros());
    }
}
