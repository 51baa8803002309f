//! Composite-rigid-body algorithm: the joint-space inertia matrix M(q) (docs/method.md eq. 1).
//!
//! One backward pass from the tip. At joint j the composite inertia `Ic_j` of bodies j..n
//! (in frame j) gives column j's wrench `F_j = Ic_j S_j`; entry `M(j, i) = S_j^T F_i` for
//! every column i >= j whose wrench has been carried down to frame j. The wrenches of up to
//! [`LANES`] columns are carried together, stored component by component across columns
//! ([`ForceLanes`]), so that each joint's transform is applied to all of them as a few
//! independent vector operations instead of one serial chain of 6-vector transforms per
//! column. Only the lower triangle (`i >= j`) is computed; the upper is copied from it.

use nalgebra::{DMatrix, Matrix3, Vector3};

#[cfg(doc)]
use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::{JointKind, Model};
use crate::spatial::{
    rotate_about_axis_sin_cos, sin_cos_lanes, Force, Inertia, InertiaColumns, Transform,
    SIN_COS_LANES,
};

/// `M(q)`, full and symmetric, into `data.mass_matrix`.
pub fn crba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
) -> Result<&'d DMatrix<f64>, DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    update_placements_lanes(model, data, q);
    crba_pass(model, data);
    Ok(&data.mass_matrix)
}

/// `data.joint_placements` for `q` as [`update_joint_placements`] fills them, with the
/// sines and cosines of eight joints at a time ([`sin_cos_lanes`], within an ulp of
/// `f64::sin_cos`, which took a quarter of the call).
#[inline(always)]
fn update_placements_lanes(model: &Model, data: &mut Data, q: &[f64]) {
    let joints = model.joints.chunks(SIN_COS_LANES);
    let placements = data.joint_placements.chunks_mut(SIN_COS_LANES);
    for ((joints, placements), q) in joints.zip(placements).zip(q.chunks(SIN_COS_LANES)) {
        let mut x = [0.0; SIN_COS_LANES];
        x[..q.len()].copy_from_slice(q);
        let (sin, cos) = sin_cos_lanes(&x);
        for (l, (joint, out)) in joints.iter().zip(placements.iter_mut()).enumerate() {
            *out = match joint.kind {
                JointKind::Prismatic => joint.transform(q[l]),
                _ => Transform {
                    rotation: rotate_about_axis_sin_cos(
                        &joint.placement.rotation,
                        &joint.axis,
                        sin[l],
                        cos[l],
                    ),
                    translation: joint.placement.translation,
                },
            };
        }
    }
}

/// Columns whose wrenches are carried down the chain together (one AVX-512 vector, two
/// AVX2 vectors per component).
const LANES: usize = 8;

/// The wrenches of up to [`LANES`] columns of M, in one joint frame, component-major:
/// `linear[r][l]` is component r of the force of lane l.
#[derive(Clone, Copy)]
struct ForceLanes {
    linear: [[f64; LANES]; 3],
    angular: [[f64; LANES]; 3],
}

impl ForceLanes {
    fn zero() -> Self {
        Self {
            linear: [[0.0; LANES]; 3],
            angular: [[0.0; LANES]; 3],
        }
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, f: &Force) {
        for r in 0..3 {
            self.linear[r][lane] = f.linear[r];
            self.angular[r][lane] = f.angular[r];
        }
    }

    /// `a . v` for each lane of the 3-vectors `v`.
    #[inline(always)]
    fn dot3(a: &Vector3<f64>, v: &[[f64; LANES]; 3]) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        for l in 0..LANES {
            out[l] = a.x * v[0][l] + a.y * v[1][l] + a.z * v[2][l];
        }
        out
    }

    /// `S^T f` of each lane for a joint of `kind` about `axis`.
    #[inline(always)]
    fn project(&self, kind: JointKind, axis: &Vector3<f64>) -> [f64; LANES] {
        match kind {
            JointKind::Prismatic => Self::dot3(axis, &self.linear),
            _ => Self::dot3(axis, &self.angular),
        }
    }

    /// `R v` for each lane.
    #[inline(always)]
    fn rotate(r: &Matrix3<f64>, v: &[[f64; LANES]; 3]) -> [[f64; LANES]; 3] {
        let mut out = [[0.0; LANES]; 3];
        for (i, o) in out.iter_mut().enumerate() {
            let (a, b, c) = (r[(i, 0)], r[(i, 1)], r[(i, 2)]);
            for l in 0..LANES {
                o[l] = a * v[0][l] + b * v[1][l] + c * v[2][l];
            }
        }
        out
    }

    /// Every lane expressed in the parent frame of `x`: `f = R f`, `n = R n + p x f`
    /// ([`Transform::act_force`] lane by lane).
    #[inline(always)]
    fn act_force(&mut self, x: &Transform) {
        let f = Self::rotate(&x.rotation, &self.linear);
        let mut n = Self::rotate(&x.rotation, &self.angular);
        let p = &x.translation;
        for l in 0..LANES {
            n[0][l] += p.y * f[2][l] - p.z * f[1][l];
            n[1][l] += p.z * f[0][l] - p.x * f[2][l];
            n[2][l] += p.x * f[1][l] - p.y * f[0][l];
        }
        self.linear = f;
        self.angular = n;
    }
}

/// The CRBA on `data.joint_placements` as they are (already updated for `q`): the AVX-512
/// lanes when the CPU has them, the portable ones otherwise (the same operations, rounded
/// alike up to the fused multiply-adds).
#[inline(always)]
pub(crate) fn crba_pass(model: &Model, data: &mut Data) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU has AVX-512F (checked just above).
        unsafe { avx512::pass(model, data) };
        return;
    }
    pass_portable(model, data);
}

/// The upper triangle of the column-major n x n `m` from its lower triangle.
#[inline(always)]
fn mirror_lower(m: &mut [f64], n: usize) {
    for i in 1..n {
        for j in 0..i {
            m[i * n + j] = m[j * n + i];
        }
    }
}

/// The portable CRBA pass.
///
/// Columns are taken in groups of [`LANES`] from the tip. A group's columns enter at their
/// own joints (composite inertia `Ic_j = I_j + X_{j+1} Ic_{j+1}` formed there, once, for
/// the group that owns column j) and ride down to the base together.
#[inline(always)]
fn pass_portable(model: &Model, data: &mut Data) {
    let n = model.nq();
    let m = data.mass_matrix.as_mut_slice();
    let placements = &data.joint_placements;
    // Composite inertia of bodies j..n in frame j, carried from group to group.
    let mut composite = InertiaColumns::new(&Inertia::zero());
    let mut end = n;
    while end > 0 {
        let start = end.saturating_sub(LANES);
        let mut lanes = ForceLanes::zero();
        for j in (0..end).rev() {
            let joint = &model.joints[j];
            // Entries M(i, j) of column j: rows max(j, start)..end.
            let first = if j >= start {
                let body = InertiaColumns::new(&model.bodies[j]);
                composite = if j + 1 < n {
                    body.add(&composite.transformed(&placements[j + 1]))
                } else {
                    body
                };
                lanes.set(j - start, &composite.mul_motion(&joint.motion_subspace()));
                j
            } else {
                start
            };
            // Column j of the lower triangle is contiguous.
            let row = lanes.project(joint.kind, &joint.axis);
            let column = &mut m[j * n..(j + 1) * n];
            column[first..end].copy_from_slice(&row[first - start..end - start]);
            if j > 0 {
                lanes.act_force(&placements[j]);
            }
        }
        end = start;
    }
    mirror_lower(m, n);
}

/// The pass with the lanes in AVX-512 registers: one 8-lane vector per wrench component,
/// a column entering with a masked broadcast (a scalar store into a vector that is read
/// at once would stall the load), the entries of M written with masked stores.
#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use super::LANES;
    use crate::data::Data;
    use crate::model::{JointKind, Model};
    use crate::spatial::{Inertia, InertiaColumns, Transform};

    /// `a . v` of each lane.
    #[inline(always)]
    unsafe fn dot3(a: &nalgebra::Vector3<f64>, v: &[__m512d; 3]) -> __m512d {
        let t = _mm512_mul_pd(_mm512_set1_pd(a.x), v[0]);
        let t = _mm512_fmadd_pd(_mm512_set1_pd(a.y), v[1], t);
        _mm512_fmadd_pd(_mm512_set1_pd(a.z), v[2], t)
    }

    /// `R v` of each lane.
    #[inline(always)]
    unsafe fn rotate(x: &Transform, v: &[__m512d; 3]) -> [__m512d; 3] {
        let r = &x.rotation;
        let row = |i: usize| {
            let t = _mm512_mul_pd(_mm512_set1_pd(r[(i, 0)]), v[0]);
            let t = _mm512_fmadd_pd(_mm512_set1_pd(r[(i, 1)]), v[1], t);
            _mm512_fmadd_pd(_mm512_set1_pd(r[(i, 2)]), v[2], t)
        };
        [row(0), row(1), row(2)]
    }

    /// Every lane expressed in the parent frame of `x`: `f = R f`, `n = R n + p x f`.
    #[inline(always)]
    unsafe fn act_force(x: &Transform, lin: &mut [__m512d; 3], ang: &mut [__m512d; 3]) {
        let f = rotate(x, lin);
        let n = rotate(x, ang);
        let p = &x.translation;
        let (px, py, pz) = (
            _mm512_set1_pd(p.x),
            _mm512_set1_pd(p.y),
            _mm512_set1_pd(p.z),
        );
        ang[0] = _mm512_fmadd_pd(py, f[2], _mm512_fnmadd_pd(pz, f[1], n[0]));
        ang[1] = _mm512_fmadd_pd(pz, f[0], _mm512_fnmadd_pd(px, f[2], n[1]));
        ang[2] = _mm512_fmadd_pd(px, f[1], _mm512_fnmadd_pd(py, f[0], n[2]));
        *lin = f;
    }

    /// [`super::pass_portable`] with the lanes in registers.
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn pass(model: &Model, data: &mut Data) {
        let n = model.nq();
        let m = data.mass_matrix.as_mut_slice();
        assert!(m.len() >= n * n);
        let placements = &data.joint_placements;
        let mut composite = InertiaColumns::new(&Inertia::zero());
        let mut end = n;
        while end > 0 {
            let start = end.saturating_sub(LANES);
            let mut lin = [_mm512_setzero_pd(); 3];
            let mut ang = [_mm512_setzero_pd(); 3];
            for j in (0..end).rev() {
                let joint = &model.joints[j];
                let first = if j >= start {
                    let body = InertiaColumns::new(&model.bodies[j]);
                    composite = if j + 1 < n {
                        body.add(&composite.transformed(&placements[j + 1]))
                    } else {
                        body
                    };
                    let f = composite.mul_motion(&joint.motion_subspace());
                    let k: __mmask8 = 1 << (j - start);
                    for r in 0..3 {
                        lin[r] = _mm512_mask_mov_pd(lin[r], k, _mm512_set1_pd(f.linear[r]));
                        ang[r] = _mm512_mask_mov_pd(ang[r], k, _mm512_set1_pd(f.angular[r]));
                    }
                    j
                } else {
                    start
                };
                let row = match joint.kind {
                    JointKind::Prismatic => dot3(&joint.axis, &lin),
                    _ => dot3(&joint.axis, &ang),
                };
                // M(i, j) for i in first..end: lanes first - start..end - start, stored
                // at rows start + lane of column j (masked lanes are not touched).
                let upto = (1u32 << (end - start)) - 1;
                let from = (1u32 << (first - start)) - 1;
                let mask = (upto & !from) as __mmask8;
                _mm512_mask_storeu_pd(m.as_mut_ptr().add(j * n + start), mask, row);
                if j > 0 {
                    act_force(&placements[j], &mut lin, &mut ang);
                }
            }
            end = start;
        }
        super::mirror_lower(m, n);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::algorithms::update_joint_placements;
    use crate::spatial::Inertia;

    /// The CRBA before the lanes (one 6-vector transform per entry, `Joint::transform`
    /// placements): the reference the fast path must equal to rounding, and the plant's
    /// `mass_matrix_and_bias` bit for bit.
    pub(crate) fn reference(model: &Model, q: &[f64]) -> DMatrix<f64> {
        let n = model.nq();
        let mut data = Data::new(model);
        update_joint_placements(model, &mut data, q);
        let x = &data.joint_placements;
        let mut composite: Vec<Inertia> = model.bodies.clone();
        let mut m = DMatrix::zeros(n, n);
        for i in (0..n).rev() {
            let joint = &model.joints[i];
            let mut f = composite[i].mul_motion(&joint.motion_subspace());
            m[(i, i)] = joint.subspace_dot(&f);
            for j in (0..i).rev() {
                f = x[j + 1].act_force(&f);
                m[(j, i)] = model.joints[j].subspace_dot(&f);
                m[(i, j)] = m[(j, i)];
            }
            if i > 0 {
                let moved = composite[i].transformed(&x[i]);
                composite[i - 1] = composite[i - 1].add(&moved);
            }
        }
        m
    }

    fn model(relative: &str) -> Model {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        Model::from_urdf_file(&root.join(relative), None, None).expect("test model")
    }

    /// Baxter (7 joints), Panda and 9- and 2-joint fixture arms (two lane groups, one
    /// lane): the fast CRBA, portable and AVX-512 passes, equals the reference within
    /// 1e-12 of the largest entry, exactly symmetric.
    #[test]
    fn lanes_equal_the_reference() {
        let arms = [
            "../../models/baxter_left_arm.urdf",
            "../../models/franka_panda.urdf",
            "tests/fixtures/arms/arm_07.urdf",
            "tests/fixtures/arms/arm_31.urdf",
            "tests/fixtures/arms/arm_00.urdf",
        ];
        for arm in arms {
            let model = model(arm);
            let n = model.nq();
            let mut data = Data::new(&model);
            for k in 0..50 {
                let q: Vec<f64> = (0..n)
                    .map(|j| 3.0 * ((k * n + j) as f64 * 0.7311).sin() * (1.0 + k as f64))
                    .collect();
                let want = reference(&model, &q);
                let scale = want.amax();
                let got = crba(&model, &mut data, &q).unwrap().clone();
                update_joint_placements(&model, &mut data, &q);
                pass_portable(&model, &mut data);
                let portable = data.mass_matrix.clone();
                for (what, m) in [("crba", &got), ("portable pass", &portable)] {
                    let err = (m - &want).amax();
                    assert!(
                        err <= 1e-12 * scale,
                        "{arm} {what} q {q:?}: {err:e} of {scale:e}"
                    );
                    assert_eq!(m, &m.transpose(), "{arm} {what}: not symmetric");
                }
            }
        }
    }
}
