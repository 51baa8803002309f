//! Synthetic free motion of the Baxter model for the command-line tests: three harmonics
//! per joint at 200 Hz and the torque its inverse dynamics needs, plus what each test adds
//! (friction no URDF knows, noise no model explains), as a free-motion CSV
//! (docs/outputs.md).

use std::path::{Path, PathBuf};

use admittance_dynamics::{rnea, Data, Model};

/// The Baxter's left arm, base to hand.
pub(crate) fn baxter() -> Model {
    let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/baxter_left_arm.urdf");
    Model::from_urdf_file(&urdf, Some("base"), Some("left_hand")).unwrap()
}

/// Writes `seconds` of motion `seed` to `path`, the columns naming the joints `names`
/// (the Baxter's, or another 7-joint arm's); joint `i`'s torque at sample `k` is the RNEA's
/// plus `added(k, i, qdot)`.
pub(crate) fn multisine_csv(
    path: PathBuf,
    seed: f64,
    seconds: f64,
    names: &[String],
    mut added: impl FnMut(usize, usize, &[f64]) -> f64,
) -> PathBuf {
    let model = baxter();
    let mut csv = String::from("t");
    for s in ["q", "qdot", "qddot", "tau"] {
        for j in names {
            csv += &format!(",{s}.{j}");
        }
    }
    csv.push('\n');
    let mut data = Data::new(&model);
    for k in 0..(seconds * 200.0) as usize {
        let t = k as f64 / 200.0;
        let (mut q, mut qd, mut qdd) = (vec![0.0; 7], vec![0.0; 7], vec![0.0; 7]);
        for i in 0..7 {
            for h in 1..=3 {
                let w = 2.0
                    * std::f64::consts::PI
                    * (0.11 * h as f64 + 0.03 * i as f64)
                    * (1.0 + 0.2 * seed);
                let (a, ph) = (0.5 / h as f64, seed * (1 + i + h) as f64);
                q[i] += a * (w * t + ph).sin();
                qd[i] += a * w * (w * t + ph).cos();
                qdd[i] -= a * w * w * (w * t + ph).sin();
            }
        }
        let tau = rnea(&model, &mut data, &q, &qd, &qdd).unwrap().clone();
        csv += &format!("{t}");
        for v in q.iter().chain(&qd).chain(&qdd) {
            csv += &format!(",{v}");
        }
        for i in 0..7 {
            csv += &format!(",{}", tau[i] + added(k, i, &qd));
        }
        csv.push('\n');
    }
    std::fs::write(&path, csv).unwrap();
    path
}

/// The joint names of `model` in chain order.
pub(crate) fn names(model: &Model) -> Vec<String> {
    model.joint_names().map(String::from).collect()
}

/// The free-motion CSV `from` played `factor` times as fast, written to `to`: its times
/// divided by `factor`, velocities multiplied by it, accelerations by its square; positions
/// and torques as recorded (a task faster than the motion an identification saw).
pub(crate) fn played_faster(from: &Path, to: &Path, factor: f64) {
    let text = std::fs::read_to_string(from).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let scale = |c: &str| match c.split('.').next() {
        Some("t") => 1.0 / factor,
        Some("qdot") => factor,
        Some("qddot") => factor * factor,
        _ => 1.0,
    };
    let scales: Vec<f64> = header.split(',').map(scale).collect();
    let mut out = format!("{header}\n");
    for line in lines {
        let cells: Vec<String> = line
            .split(',')
            .zip(&scales)
            .map(|(c, k)| (c.parse::<f64>().unwrap() * k).to_string())
            .collect();
        out += &(cells.join(",") + "\n");
    }
    std::fs::write(to, out).unwrap();
}
