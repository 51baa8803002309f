//! What a forward-dynamics step with an implicit solve needs at one configuration: `M(q)`,
//! `C(q, v) v + G(q)` and, optionally, `G(q)` (docs/method.md eq. 1), from one set of joint
//! placements.
//!
//! The three are independent recursions over the same placements: the RNEA with zero
//! acceleration (forward and backward), the gravity pass (forward and backward) and the
//! composite-body CRBA (backward). Each is a chain of dependent 3-vector operations, so one
//! after the other the processor waits on one short chain at a time. Here the forward steps
//! of the first two share one loop and the backward steps of all three another: the same
//! operations in the same order within each recursion, so the same values bit for bit as the
//! three passes called in turn (`tests::interleaved_equals_the_passes_bit_for_bit`), with
//! the chains overlapped.

// Parallel per-joint arrays read clearest indexed.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector3;

use crate::algorithms::rnea::forward_step;
use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::error::{check_len, DimensionError};
use crate::model::Model;
use crate::spatial::{Force, Motion};

/// `M(q)`, `C(q, v) v + G(q)` and, when `gravity`, `G(q)` at one configuration, into
/// `data.mass_matrix`, `data.nonlinear_effects` and `data.gravity_torque`: the values of
/// [`crate::crba`] (within rounding: the composite-body pass), [`crate::nonlinear_effects`]
/// and [`crate::gravity_torque`] called one after the other, with the joint placements
/// computed once instead of three times.
pub fn mass_matrix_and_bias(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    gravity: bool,
) -> Result<(), DimensionError> {
    at_configuration::<true>(model, data, q, v, gravity)
}

/// `C(q, v) v + G(q)` and, when `gravity`, `G(q)` at one configuration, into
/// `data.nonlinear_effects` and `data.gravity_torque`: [`mass_matrix_and_bias`] without the
/// mass matrix, the same values bit for bit (the same recursions on the same placements).
/// For a step that holds `M` from an earlier configuration (the plant's `hold_mass_matrix`).
pub fn bias_and_gravity(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    gravity: bool,
) -> Result<(), DimensionError> {
    at_configuration::<false>(model, data, q, v, gravity)
}

/// The two functions above: checks, placements, then the recursions.
fn at_configuration<const MATRIX: bool>(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    gravity: bool,
) -> Result<(), DimensionError> {
    let n = model.nq();
    check_len("q", q, n)?;
    check_len("v", v, n)?;
    update_joint_placements(model, data, q);
    if gravity {
        interleaved::<MATRIX, true>(model, data, v);
    } else {
        interleaved::<MATRIX, false>(model, data, v);
    }
    Ok(())
}

/// The recursions of the module doc on `data.joint_placements` as they are: the RNEA always,
/// the composite CRBA when `MATRIX`, the gravity pass when `GRAVITY`. Each recursion's
/// expressions are those of its own pass (the RNEA's `forward_step` with zero acceleration,
/// the composite-body CRBA the plant used before the lanes, `gravity_pass`), the last two
/// written out again here so that they interleave.
#[inline(always)]
fn interleaved<const MATRIX: bool, const GRAVITY: bool>(model: &Model, data: &mut Data, v: &[f64]) {
    let n = model.nq();
    let mut v_parent = Motion::zero();
    let mut a_parent = Motion {
        linear: -model.gravity,
        angular: Vector3::zeros(),
    };
    let mut gravity_acceleration = -model.gravity;
    for i in 0..n {
        let (vi, ai) = forward_step(model, data, i, (&v_parent, &a_parent), v[i], 0.0);
        v_parent = vi;
        a_parent = ai;
        if GRAVITY {
            // v = 0 and a = 0: each body's acceleration is gravity seen in its frame.
            let (x, inertia) = (&data.joint_placements[i], &model.bodies[i]);
            gravity_acceleration = x.rotation.tr_mul(&gravity_acceleration);
            data.gravity_forces[i] = Force {
                linear: gravity_acceleration * inertia.mass,
                angular: inertia.first_moment.cross(&gravity_acceleration),
            };
        }
    }
    if MATRIX {
        data.composite.copy_from_slice(&model.bodies);
    }
    let m = data.mass_matrix.as_mut_slice();
    for i in (0..n).rev() {
        let joint = &model.joints[i];
        data.tau[i] = joint.subspace_dot(&data.forces[i]);
        if i > 0 {
            let moved = data.joint_placements[i].act_force(&data.forces[i]);
            data.forces[i - 1] += moved;
        }
        if GRAVITY {
            let f = data.gravity_forces[i];
            data.gravity_torque[i] = joint.subspace_dot(&f);
            if i > 0 {
                let moved = data.joint_placements[i].act_force(&f);
                data.gravity_forces[i - 1] += moved;
            }
        }
        if MATRIX {
            // Column i: the wrench that accelerates the composite body i..n at unit
            // qddot_i, carried back through the ancestors.
            let mut f = data.composite[i].mul_motion(&joint.motion_subspace());
            m[i * n + i] = joint.subspace_dot(&f);
            for j in (0..i).rev() {
                f = data.joint_placements[j + 1].act_force(&f);
                let value = model.joints[j].subspace_dot(&f);
                m[i * n + j] = value;
                m[j * n + i] = value;
            }
            if i > 0 {
                let moved = data.composite[i].transformed(&data.joint_placements[i]);
                data.composite[i - 1] = data.composite[i - 1].add(&moved);
            }
        }
    }
    data.nonlinear_effects.copy_from(&data.tau);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithms::crba::tests::reference as crba_reference;
    use crate::algorithms::rnea::{gravity_pass, rnea_pass_at_placements};

    fn model(relative: &str) -> Model {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        Model::from_urdf_file(&root.join(relative), None, None).expect("test model")
    }

    fn bits(values: &[f64]) -> Vec<u64> {
        values.iter().map(|x| x.to_bits()).collect()
    }

    /// The interleaved recursions give the bits of the three passes called in turn (what
    /// the plant computed before), on arms of 2, 7 and 9 joints, prismatic joints included,
    /// with and without the matrix and gravity.
    #[test]
    fn interleaved_equals_the_passes_bit_for_bit() {
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
            let (mut fused, mut reference) = (Data::new(&model), Data::new(&model));
            for k in 0..200 {
                let q: Vec<f64> = (0..n)
                    .map(|j| 3.0 * ((k * n + j) as f64 * 0.7311).sin() * (1.0 + k as f64 / 50.0))
                    .collect();
                let v: Vec<f64> = (0..n)
                    .map(|j| 4.0 * ((k * n + j) as f64 * 1.917).cos())
                    .collect();
                for gravity in [false, true] {
                    for matrix in [false, true] {
                        update_joint_placements(&model, &mut reference, &q);
                        if matrix {
                            reference.mass_matrix = crba_reference(&model, &q);
                            mass_matrix_and_bias(&model, &mut fused, &q, &v, gravity).unwrap();
                        } else {
                            bias_and_gravity(&model, &mut fused, &q, &v, gravity).unwrap();
                        }
                        rnea_pass_at_placements(&model, &mut reference, Some(&v), None, None);
                        reference.nonlinear_effects.copy_from(&reference.tau);
                        if gravity {
                            gravity_pass(&model, &mut reference);
                        }
                        let what = format!("{arm}, state {k}, gravity {gravity}, matrix {matrix}");
                        assert_eq!(
                            bits(fused.nonlinear_effects.as_slice()),
                            bits(reference.nonlinear_effects.as_slice()),
                            "C v + G: {what}"
                        );
                        assert_eq!(
                            bits(fused.gravity_torque.as_slice()),
                            bits(reference.gravity_torque.as_slice()),
                            "G: {what}"
                        );
                        if matrix {
                            assert_eq!(
                                bits(fused.mass_matrix.as_slice()),
                                bits(reference.mass_matrix.as_slice()),
                                "M: {what}"
                            );
                        }
                    }
                }
            }
        }
    }
}
