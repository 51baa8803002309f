//! The model terms of the generalised momentum observer (docs/method.md section 5, the
//! baseline): `p = M(q) v`, `C(q, v)^T v` and `G(q)`, in one pass over the chain, without
//! forming `M` or `C`.
//!
//! In the base frame, with `s_i` joint i's world motion axis, `v_i` body i's world
//! velocity, `Y_i` and `B_i` the composite (from i to the tip) world inertia and
//! Christoffel matrix of [`crate::coriolis_matrix`], and `sdot_i = v_i x s_i`:
//!
//! * `M[i, j] = s_i . Y_max(i,j) s_j`, so `(M v)_i = s_i . (Y_i v_i + a_i)` with
//!   `a_i = sum_{j > i} v_j Y_j s_j`, because `sum_{j <= i} s_j v_j = v_i`;
//! * `C[i, j] = s_i . (Y_j sdot_j + B_j s_j)` for `j >= i` and
//!   `(Y_i s_i) . sdot_j + (B_i^T s_i) . s_j` for `j < i`, so
//!   `(C^T v)_i = v_i . (Y_i sdot_i + B_i s_i) + a_i . sdot_i + c_i . s_i` with
//!   `c_i = sum_{j > i} v_j B_j^T s_j`;
//! * `G_i = s_i . Y_i a_0`, `a_0 = (-g, 0)` the base acceleration that stands for gravity.
//!
//! `a_i` and `c_i` accumulate from the tip in the same backward pass as the composites,
//! so the cost is O(n) against the O(n^2) of forming `M` and `C` (and the joint
//! placements are computed once instead of three times).

use nalgebra::Vector6;

use super::coriolis::{motion_of, world_forward_pass};
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;
use crate::spatial::Motion;

/// `M(q) v`, `C(q, v)^T v` and `G(q)` into `data.momentum`, `data.coriolis_transpose_v`
/// and `data.gravity_torque`: the same values as [`crate::crba`] times `v`,
/// [`crate::coriolis_matrix`] transposed times `v` and [`crate::gravity_torque`] (to
/// rounding; tested), for the momentum observer's update (docs/method.md section 5).
pub fn momentum_observer_terms(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<(), DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    world_forward_pass(model, data, q, v);
    let base_acceleration = Motion {
        linear: -model.gravity,
        angular: nalgebra::Vector3::zeros(),
    };
    // a = sum_{j > i} v_j Y_j s_j and c = sum_{j > i} v_j B_j^T s_j.
    let mut a = Vector6::zeros();
    let mut c = Vector6::zeros();
    for i in (0..n).rev() {
        let s = data.world_subspace[i];
        let ds = data.world_subspace_rate[i];
        let y = data.composite[i];
        let b = data.coriolis_b[i];
        let vi = data.world_velocity[i];
        let yv = y.mul_motion(&vi).to_vector();
        data.momentum[i] = s.dot(&(yv + a));
        let dfdv = y.mul_motion(&motion_of(&ds)).to_vector() + b * s;
        data.coriolis_transpose_v[i] = vi.to_vector().dot(&dfdv) + a.dot(&ds) + c.dot(&s);
        data.gravity_torque[i] = s.dot(&y.mul_motion(&base_acceleration).to_vector());
        a += y.mul_motion(&motion_of(&s)).to_vector() * v[i];
        c += b.tr_mul(&s) * v[i];
        if i > 0 {
            data.composite[i - 1] = data.composite[i - 1].add(&y);
            data.coriolis_b[i - 1] += b;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{coriolis_matrix, crba, gravity_torque};

    fn baxter() -> Model {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/baxter_left_arm.urdf"
        );
        Model::from_urdf_file(std::path::Path::new(path), Some("base"), Some("left_hand"))
            .expect("the project's Baxter model loads")
    }

    fn check_arm(model: &Model) {
        let n = model.nq();
        let mut data = Data::new(model);
        let mut reference = Data::new(model);
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        for _ in 0..50 {
            let q: Vec<f64> = (0..n).map(|_| next()).collect();
            let v: Vec<f64> = (0..n).map(|_| 2.0 * next()).collect();
            momentum_observer_terms(model, &mut data, &q, &v).unwrap();
            let m = crba(model, &mut reference, &q).unwrap().clone();
            let c = coriolis_matrix(model, &mut reference, &q, &v)
                .unwrap()
                .clone();
            let g = gravity_torque(model, &mut reference, &q).unwrap().clone();
            let vv = nalgebra::DVector::from_column_slice(&v);
            let p = &m * &vv;
            let ctv = c.transpose() * &vv;
            let close = |got: f64, want: f64, scale: f64| (got - want).abs() <= 1e-12 * scale;
            let (sp, sc, sg) = (p.amax() + 1.0, ctv.amax() + 1.0, g.amax() + 1.0);
            for i in 0..n {
                assert!(close(data.momentum[i], p[i], sp), "M v [{i}]");
                assert!(
                    close(data.coriolis_transpose_v[i], ctv[i], sc),
                    "C^T v [{i}]"
                );
                assert!(close(data.gravity_torque[i], g[i], sg), "G [{i}]");
            }
        }
    }

    #[test]
    fn equals_the_matrices_on_the_baxter_arm() {
        let model = baxter();
        check_arm(&model);
    }

    #[test]
    fn rejects_wrong_lengths() {
        let model = baxter();
        let mut data = Data::new(&model);
        assert!(momentum_observer_terms(&model, &mut data, &[0.0; 3], &[0.0; 7]).is_err());
        assert!(momentum_observer_terms(&model, &mut data, &[0.0; 7], &[0.0; 6]).is_err());
    }
}
