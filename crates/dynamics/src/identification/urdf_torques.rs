//! The URDF arm's torque on every sample, computed once for the recording checks and the
//! prior's scale (each needed an RNEA pass of its own over the same samples).

use crate::algorithms::rnea::rnea_pass_at_placements;
use crate::algorithms::update_joint_placements;
use crate::data::Data;
use crate::identification::samples::Samples;
use crate::model::Model;

/// Per sample (row-major, `n` per sample): the URDF's torque `M q'' + C q' + G` and, when
/// asked for, its gravity and Coriolis part `C q' + G`. The values of `rnea` and
/// `nonlinear_effects` called on each sample, bit for bit (the same passes on the same joint
/// placements, computed once per sample instead of twice).
pub(super) struct UrdfTorques {
    pub total: Vec<f64>,
    /// Empty unless asked for.
    pub bias: Vec<f64>,
}

impl UrdfTorques {
    pub(super) fn new(model: &Model, samples: &Samples, with_bias: bool) -> Self {
        let n = model.nq();
        let mut data = Data::new(model);
        let mut total = Vec::with_capacity(samples.len() * n);
        let mut bias = Vec::with_capacity(if with_bias { samples.len() * n } else { 0 });
        for k in 0..samples.len() {
            let r = k * n..(k + 1) * n;
            let (q, qd, qdd) = (
                &samples.q[r.clone()],
                &samples.qdot[r.clone()],
                &samples.qddot[r],
            );
            update_joint_placements(model, &mut data, q);
            if with_bias {
                rnea_pass_at_placements(model, &mut data, Some(qd), None, None);
                bias.extend_from_slice(data.tau.as_slice());
            }
            rnea_pass_at_placements(model, &mut data, Some(qd), Some(qdd), None);
            total.extend_from_slice(data.tau.as_slice());
        }
        UrdfTorques { total, bias }
    }

    /// Each joint's rms difference between the recorded torque of `samples` (those these
    /// torques were computed on) and the URDF's: the URDF arm's own false torque there.
    pub(super) fn rms_errors(&self, samples: &Samples) -> Vec<f64> {
        let n = samples.dof;
        let mut sq = vec![0.0; n];
        for (predicted, recorded) in self.total.chunks_exact(n).zip(samples.tau.chunks_exact(n)) {
            for i in 0..n {
                sq[i] += (predicted[i] - recorded[i]).powi(2);
            }
        }
        let len = samples.len().max(1) as f64;
        sq.iter().map(|s| (s / len).sqrt()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithms::rnea::{nonlinear_effects, rnea};

    /// Equal to `rnea` and `nonlinear_effects` sample by sample, bit for bit.
    #[test]
    fn equals_the_two_algorithms_bit_for_bit() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let model = Model::from_urdf_file(&root.join("../../models/franka_panda.urdf"), None, None)
            .expect("model");
        let n = model.nq();
        let count = 50;
        let wave = |k: usize, f: f64| ((k as f64) * f).sin() * (k % 4) as f64;
        let q: Vec<f64> = (0..count * n).map(|k| wave(k, 0.37)).collect();
        let qd: Vec<f64> = (0..count * n).map(|k| wave(k, 1.13)).collect();
        let qdd: Vec<f64> = (0..count * n).map(|k| 3.0 * wave(k, 0.71)).collect();
        let tau = vec![0.0; count * n];
        let samples = Samples {
            q: &q,
            qdot: &qd,
            qddot: &qdd,
            tau: &tau,
            dof: n,
        };
        let torques = UrdfTorques::new(&model, &samples, true);
        let mut data = Data::new(&model);
        for k in 0..count {
            let r = k * n..(k + 1) * n;
            let want = rnea(
                &model,
                &mut data,
                &q[r.clone()],
                &qd[r.clone()],
                &qdd[r.clone()],
            )
            .unwrap()
            .clone();
            let bias = nonlinear_effects(&model, &mut data, &q[r.clone()], &qd[r.clone()])
                .unwrap()
                .clone();
            for i in 0..n {
                assert_eq!(torques.total[k * n + i].to_bits(), want[i].to_bits());
                assert_eq!(torques.bias[k * n + i].to_bits(), bias[i].to_bits());
            }
        }
        assert!(UrdfTorques::new(&model, &samples, false).bias.is_empty());
    }
}
