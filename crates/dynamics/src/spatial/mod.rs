//! Spatial algebra on fixed-size nalgebra types.
//!
//! Six-dimensional quantities are stored as a pair of 3-vectors, **linear part first**
//! (the convention of the Jacobian this crate returns):
//!
//! * a [`Motion`] (spatial velocity or acceleration) `(v, w)`: the linear velocity of the
//!   body point that coincides with the frame origin, and the angular velocity;
//! * a [`Force`] (wrench) `(f, n)`: the force and the moment about the frame origin.
//!
//! A [`Transform`] `(R, p)` maps coordinates of a child frame into its parent:
//! `x_parent = R x_child + p`. Spatial inertia ([`Inertia`]) is kept in the compact
//! `(m, h = m c, I_o)` form, which is closed under addition and frame changes.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

mod columns;
mod lanes;

pub(crate) use columns::InertiaColumns;
pub(crate) use lanes::{sin_cos_lanes, SIN_COS_LANES};

/// The skew-symmetric matrix `[a]x` such that `[a]x b = a x b`.
#[inline(always)]
pub fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// Rotation by `angle` about the unit vector `axis` (Rodrigues' formula).
#[inline(always)]
pub fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let (x, y, z) = (axis.x, axis.y, axis.z);
    Matrix3::new(
        t * x * x + c,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        t * y * y + c,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        t * z * z + c,
    )
}

/// `p * R(axis, angle)` from `sin angle` and `cos angle`, with a coordinate axis (most
/// URDFs) done on columns; the rotation of a revolute joint frame (the same operations as
/// [`crate::model::Joint::transform`] after its `sin_cos`).
#[inline(always)]
pub(crate) fn rotate_about_axis_sin_cos(
    p: &Matrix3<f64>,
    axis: &Vector3<f64>,
    s: f64,
    c: f64,
) -> Matrix3<f64> {
    let (c0, c1, c2) = (p.column(0), p.column(1), p.column(2));
    if axis.x == 0.0 && axis.y == 0.0 {
        let s = s * axis.z;
        Matrix3::from_columns(&[c0 * c + c1 * s, c1 * c - c0 * s, c2.into_owned()])
    } else if axis.y == 0.0 && axis.z == 0.0 {
        let s = s * axis.x;
        Matrix3::from_columns(&[c0.into_owned(), c1 * c + c2 * s, c2 * c - c1 * s])
    } else if axis.x == 0.0 && axis.z == 0.0 {
        let s = s * axis.y;
        Matrix3::from_columns(&[c0 * c - c2 * s, c1.into_owned(), c2 * c + c0 * s])
    } else {
        let t = 1.0 - c;
        let (x, y, z) = (axis.x, axis.y, axis.z);
        p * Matrix3::new(
            t * x * x + c,
            t * x * y - s * z,
            t * x * z + s * y,
            t * x * y + s * z,
            t * y * y + c,
            t * y * z - s * x,
            t * x * z - s * y,
            t * y * z + s * x,
            t * z * z + c,
        )
    }
}

/// Rotation from URDF roll-pitch-yaw angles: `R = Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy_to_matrix(roll: f64, pitch: f64, yaw: f64) -> Matrix3<f64> {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )
}

/// A rigid transform (element of SE(3)) from a child frame to its parent frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Orientation of the child frame's axes in the parent frame.
    pub rotation: Matrix3<f64>,
    /// Position of the child frame's origin in the parent frame.
    pub translation: Vector3<f64>,
}

impl Default for Transform {
    fn default() -> Self {
        Self::identity()
    }
}

impl Transform {
    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// A transform from a rotation and a translation.
    pub fn new(rotation: Matrix3<f64>, translation: Vector3<f64>) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// Composition `self * other`: first `other` (grandchild to child), then `self`.
    #[inline(always)]
    pub fn compose(&self, other: &Transform) -> Transform {
        Transform {
            rotation: self.rotation * other.rotation,
            translation: self.translation + self.rotation * other.translation,
        }
    }

    /// The inverse transform (parent to child).
    pub fn inverse(&self) -> Transform {
        let rt = self.rotation.transpose();
        Transform {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    /// Maps a point from child to parent coordinates.
    #[inline(always)]
    pub fn transform_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }

    /// Expresses a child-frame motion in the parent frame.
    #[inline(always)]
    pub fn act_motion(&self, m: &Motion) -> Motion {
        let ang = self.rotation * m.angular;
        Motion {
            linear: self.rotation * m.linear + self.translation.cross(&ang),
            angular: ang,
        }
    }

    /// Expresses a parent-frame motion in the child frame.
    #[inline(always)]
    pub fn act_inv_motion(&self, m: &Motion) -> Motion {
        Motion {
            linear: self
                .rotation
                .tr_mul(&(m.linear - self.translation.cross(&m.angular))),
            angular: self.rotation.tr_mul(&m.angular),
        }
    }

    /// Expresses a child-frame force in the parent frame.
    #[inline(always)]
    pub fn act_force(&self, f: &Force) -> Force {
        let lin = self.rotation * f.linear;
        Force {
            linear: lin,
            angular: self.rotation * f.angular + self.translation.cross(&lin),
        }
    }

    /// Expresses a parent-frame force in the child frame.
    #[inline(always)]
    pub fn act_inv_force(&self, f: &Force) -> Force {
        Force {
            linear: self.rotation.tr_mul(&f.linear),
            angular: self
                .rotation
                .tr_mul(&(f.angular - self.translation.cross(&f.linear))),
        }
    }
}

/// A spatial motion vector (velocity or acceleration), linear part first.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Motion {
    /// Linear velocity of the body point at the frame origin.
    pub linear: Vector3<f64>,
    /// Angular velocity.
    pub angular: Vector3<f64>,
}

impl Motion {
    /// The zero motion.
    pub fn zero() -> Self {
        Self {
            linear: Vector3::zeros(),
            angular: Vector3::zeros(),
        }
    }

    /// Motion cross product `self x m` (derivative of a motion carried by `self`).
    #[inline(always)]
    pub fn cross_motion(&self, m: &Motion) -> Motion {
        Motion {
            linear: self.angular.cross(&m.linear) + self.linear.cross(&m.angular),
            angular: self.angular.cross(&m.angular),
        }
    }

    /// Force cross product `self x* f`.
    #[inline(always)]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force {
            linear: self.angular.cross(&f.linear),
            angular: self.angular.cross(&f.angular) + self.linear.cross(&f.linear),
        }
    }

    /// As a 6-vector `[linear; angular]`.
    #[inline(always)]
    pub fn to_vector(&self) -> Vector6<f64> {
        Vector6::new(
            self.linear.x,
            self.linear.y,
            self.linear.z,
            self.angular.x,
            self.angular.y,
            self.angular.z,
        )
    }

    /// Scales both parts.
    #[inline(always)]
    pub fn scaled(&self, s: f64) -> Motion {
        Motion {
            linear: self.linear * s,
            angular: self.angular * s,
        }
    }
}

impl std::ops::Add for Motion {
    type Output = Motion;
    #[inline(always)]
    fn add(self, o: Motion) -> Motion {
        Motion {
            linear: self.linear + o.linear,
            angular: self.angular + o.angular,
        }
    }
}

/// A spatial force (wrench), force first, moment about the frame origin second.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Force {
    /// Force.
    pub linear: Vector3<f64>,
    /// Moment about the frame origin.
    pub angular: Vector3<f64>,
}

impl Force {
    /// The zero wrench.
    pub fn zero() -> Self {
        Self {
            linear: Vector3::zeros(),
            angular: Vector3::zeros(),
        }
    }

    /// As a 6-vector `[force; moment]`.
    #[inline(always)]
    pub fn to_vector(&self) -> Vector6<f64> {
        Vector6::new(
            self.linear.x,
            self.linear.y,
            self.linear.z,
            self.angular.x,
            self.angular.y,
            self.angular.z,
        )
    }

    /// Power pairing with a motion: `f . m`.
    #[inline(always)]
    pub fn dot(&self, m: &Motion) -> f64 {
        self.linear.dot(&m.linear) + self.angular.dot(&m.angular)
    }
}

impl std::ops::Add for Force {
    type Output = Force;
    #[inline(always)]
    fn add(self, o: Force) -> Force {
        Force {
            linear: self.linear + o.linear,
            angular: self.angular + o.angular,
        }
    }
}

impl std::ops::AddAssign for Force {
    #[inline(always)]
    fn add_assign(&mut self, o: Force) {
        self.linear += o.linear;
        self.angular += o.angular;
    }
}

impl std::ops::SubAssign for Force {
    #[inline(always)]
    fn sub_assign(&mut self, o: Force) {
        self.linear -= o.linear;
        self.angular -= o.angular;
    }
}

/// Spatial inertia of a rigid body about a frame origin, in that frame's axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia {
    /// Mass (kg).
    pub mass: f64,
    /// First mass moment `m c` (c: centre of mass in this frame).
    pub first_moment: Vector3<f64>,
    /// Rotational inertia about the frame origin (not about the centre of mass).
    pub rotational: Matrix3<f64>,
}

impl Default for Inertia {
    fn default() -> Self {
        Self::zero()
    }
}

impl Inertia {
    /// A massless body.
    pub fn zero() -> Self {
        Self {
            mass: 0.0,
            first_moment: Vector3::zeros(),
            rotational: Matrix3::zeros(),
        }
    }

    /// From mass, centre of mass and the rotational inertia about the centre of mass,
    /// all in this frame's axes.
    pub fn from_com(mass: f64, com: Vector3<f64>, inertia_about_com: Matrix3<f64>) -> Self {
        let c = skew(&com);
        // Parallel-axis theorem: I_o = I_c - m [c]x [c]x.
        Self {
            mass,
            first_moment: com * mass,
            rotational: inertia_about_com - c * c * mass,
        }
    }

    /// Centre of mass (the origin for a massless body).
    pub fn com(&self) -> Vector3<f64> {
        if self.mass > 0.0 {
            self.first_moment / self.mass
        } else {
            Vector3::zeros()
        }
    }

    /// Rotational inertia about the centre of mass.
    pub fn inertia_about_com(&self) -> Matrix3<f64> {
        if self.mass > 0.0 {
            let c = skew(&self.com());
            self.rotational + c * c * self.mass
        } else {
            self.rotational
        }
    }

    /// The inertia-times-motion product: the momentum `I m` of a body moving with `m`.
    #[inline(always)]
    pub fn mul_motion(&self, m: &Motion) -> Force {
        Force {
            linear: m.linear * self.mass + m.angular.cross(&self.first_moment),
            angular: self.rotational * m.angular + self.first_moment.cross(&m.linear),
        }
    }

    /// Expresses a child-frame inertia in the parent frame of `x`.
    #[inline(always)]
    pub fn transformed(&self, x: &Transform) -> Inertia {
        let r = &x.rotation;
        let p = &x.translation;
        let rh = r * self.first_moment;
        // R I_o R^T, using the symmetry of the result.
        let ri = r * self.rotational;
        let mut rot = Matrix3::zeros();
        for i in 0..3 {
            for j in i..3 {
                let v = ri[(i, 0)] * r[(j, 0)] + ri[(i, 1)] * r[(j, 1)] + ri[(i, 2)] * r[(j, 2)];
                rot[(i, j)] = v;
                rot[(j, i)] = v;
            }
        }
        // I_o' = R I_o R^T - ([Rh]x [p]x + [p]x [Rh]x) - m [p]x [p]x, with
        // [a]x [b]x = b a^T - (a.b) 1:
        //   [Rh]x[p]x + [p]x[Rh]x = p Rh^T + Rh p^T - 2 (p.Rh) 1,   [p]x[p]x = p p^T - |p|^2 1.
        let m = self.mass;
        let diag = 2.0 * p.dot(&rh) + m * p.norm_squared();
        for i in 0..3 {
            for j in i..3 {
                let v = rot[(i, j)] - (p[i] * rh[j] + rh[i] * p[j]) - m * p[i] * p[j];
                rot[(i, j)] = v;
                rot[(j, i)] = v;
            }
            rot[(i, i)] += diag;
        }
        Inertia {
            mass: m,
            first_moment: rh + p * m,
            rotational: rot,
        }
    }

    /// Sum of two inertias expressed in the same frame.
    #[inline(always)]
    pub fn add(&self, o: &Inertia) -> Inertia {
        Inertia {
            mass: self.mass + o.mass,
            first_moment: self.first_moment + o.first_moment,
            rotational: self.rotational + o.rotational,
        }
    }

    /// The 6x6 matrix form, rows and columns ordered `[linear; angular]`.
    #[inline(always)]
    pub fn to_matrix(&self) -> Matrix6<f64> {
        let h = skew(&self.first_moment);
        let mut out = Matrix6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0).fill_diagonal(self.mass);
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-h));
        out.fixed_view_mut::<3, 3>(3, 0).copy_from(&h);
        out.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.rotational);
        out
    }

    /// Kinetic energy `0.5 m^T I m` of the body moving with `m`.
    #[inline(always)]
    pub fn kinetic_energy(&self, m: &Motion) -> f64 {
        0.5 * self.mul_motion(m).dot(m)
    }
}

/// Force cross product written as a function of its motion argument: `f_bar(f) m = m x* f`.
/// Appears in the Christoffel-consistent body Coriolis matrix.
#[inline(always)]
pub(crate) fn add_force_cross_matrix(f: &Force, out: &mut Matrix6<f64>) {
    let fl = skew(&f.linear);
    let fa = skew(&f.angular);
    {
        let mut tr = out.fixed_view_mut::<3, 3>(0, 3);
        tr -= fl;
    }
    {
        let mut bl = out.fixed_view_mut::<3, 3>(3, 0);
        bl -= fl;
    }
    let mut br = out.fixed_view_mut::<3, 3>(3, 3);
    br -= fa;
}

/// Transforms a 6x6 articulated inertia (rows and columns `[linear; angular]`) from a
/// child frame into its parent: `X* Ia X^-1` with `X*` the child-to-parent force transform.
#[inline(always)]
pub(crate) fn transform_articulated_inertia(x: &Transform, ia: &Matrix6<f64>) -> Matrix6<f64> {
    let r = &x.rotation;
    let rt = r.transpose();
    let a = r * ia.fixed_view::<3, 3>(0, 0) * rt;
    let b = r * ia.fixed_view::<3, 3>(0, 3) * rt;
    let d = r * ia.fixed_view::<3, 3>(3, 3) * rt;
    let p = skew(&x.translation);
    let pa = p * a;
    let top_right = b - a * p;
    let pb = p * b;
    let bottom_right = d - pa * p + pb + pb.transpose();
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&a);
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&top_right);
    out.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&top_right.transpose());
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&bottom_right);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_transform() -> Transform {
        Transform::new(rpy_to_matrix(0.3, -0.7, 1.1), Vector3::new(0.2, -0.4, 0.9))
    }

    #[test]
    fn rpy_matches_axis_angle_product() {
        let (r, p, y) = (0.3, -0.7, 1.1);
        let expected = axis_angle(&Vector3::z(), y)
            * axis_angle(&Vector3::y(), p)
            * axis_angle(&Vector3::x(), r);
        assert!((rpy_to_matrix(r, p, y) - expected).norm() < 1e-14);
    }

    #[test]
    fn force_and_motion_transforms_preserve_power() {
        let x = sample_transform();
        let m = Motion {
            linear: Vector3::new(0.1, 0.2, -0.3),
            angular: Vector3::new(1.0, -2.0, 0.5),
        };
        let f = Force {
            linear: Vector3::new(3.0, -1.0, 2.0),
            angular: Vector3::new(0.4, 0.1, -0.2),
        };
        let p_child = f.dot(&m);
        let p_parent = x.act_force(&f).dot(&x.act_motion(&m));
        assert!((p_child - p_parent).abs() < 1e-12);
        let back = x.act_inv_motion(&x.act_motion(&m));
        assert!((back.to_vector() - m.to_vector()).norm() < 1e-12);
        let backf = x.act_inv_force(&x.act_force(&f));
        assert!((backf.to_vector() - f.to_vector()).norm() < 1e-12);
    }

    #[test]
    fn inertia_transform_matches_matrix_form() {
        let x = sample_transform();
        let inertia = Inertia::from_com(
            2.5,
            Vector3::new(0.1, -0.05, 0.2),
            Matrix3::new(0.3, 0.01, -0.02, 0.01, 0.25, 0.03, -0.02, 0.03, 0.2),
        );
        let m = Motion {
            linear: Vector3::new(0.1, 0.2, -0.3),
            angular: Vector3::new(1.0, -2.0, 0.5),
        };
        // Momentum computed in the child then moved to the parent equals the parent-frame
        // inertia applied to the parent-frame motion.
        let direct = x.act_force(&inertia.mul_motion(&m));
        let via = inertia.transformed(&x).mul_motion(&x.act_motion(&m));
        assert!((direct.to_vector() - via.to_vector()).norm() < 1e-12);
        let as_matrix = inertia.to_matrix() * m.to_vector();
        assert!((as_matrix - inertia.mul_motion(&m).to_vector()).norm() < 1e-12);
        let ia = transform_articulated_inertia(&x, &inertia.to_matrix());
        assert!((ia - inertia.transformed(&x).to_matrix()).norm() < 1e-12);
        assert!(
            (inertia.inertia_about_com()
                - Matrix3::new(0.3, 0.01, -0.02, 0.01, 0.25, 0.03, -0.02, 0.03, 0.2))
            .norm()
                < 1e-12
        );
    }
}
