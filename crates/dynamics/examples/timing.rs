//! Per-call timing of each algorithm, printed as `<algorithm> <median ns>` lines, for the
//! side-by-side comparison with Pinocchio (scripts/bench/compare_pinocchio.sh), which
//! times its C++ library the same way: 1000 random states, 1000 batches of 100 calls
//! cycling through them, median over batches (short batches keep scheduler pauses on a
//! busy machine out of most samples).
//!
//! Usage: cargo run --release -p admittance-dynamics --example timing -- URDF TIP

use std::hint::black_box;
use std::time::Instant;

use admittance_dynamics::*;
use rand::{Rng, SeedableRng};

const STATES: usize = 1000;
const DEFAULT_BATCHES: usize = 1000;
const PER_BATCH: usize = 100;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let urdf = args
        .get(1)
        .map(String::as_str)
        .unwrap_or("models/baxter_left_arm.urdf");
    let tip = args.get(2).map(String::as_str);
    let model = match Model::from_urdf_file(urdf.as_ref(), None, tip) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let n = model.nq();
    // TIMING_BATCHES=1 makes one quick pass (e.g. under callgrind).
    let batches: usize = std::env::var("TIMING_BATCHES")
        .ok()
        .and_then(|b| b.parse().ok())
        .unwrap_or(DEFAULT_BATCHES)
        .max(1);
    let mut data = Data::new(&model);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut draw = |scale: f64| -> Vec<Vec<f64>> {
        (0..STATES)
            .map(|_| (0..n).map(|_| rng.random_range(-scale..scale)).collect())
            .collect()
    };
    let (qs, vs, as_) = (draw(1.5), draw(2.0), draw(5.0));

    let time = |name: &str, f: &mut dyn FnMut(usize)| {
        for k in 0..STATES {
            f(k);
        }
        let mut per_call = Vec::with_capacity(batches);
        let mut first = 0;
        for _ in 0..batches {
            let start = Instant::now();
            for k in first..first + PER_BATCH {
                f(k % STATES);
            }
            per_call.push(start.elapsed().as_nanos() as f64 / PER_BATCH as f64);
            first = (first + PER_BATCH) % STATES;
        }
        per_call.sort_by(|a, b| a.total_cmp(b));
        println!("{name} {:.1}", per_call[batches / 2]);
    };
    time("rnea", &mut |k| {
        black_box(rnea(&model, &mut data, &qs[k], &vs[k], &as_[k]).ok());
    });
    time("crba", &mut |k| {
        black_box(crba(&model, &mut data, &qs[k]).ok());
    });
    time("aba", &mut |k| {
        black_box(aba(&model, &mut data, &qs[k], &vs[k], &as_[k]).ok());
    });
    time("jacobian", &mut |k| {
        black_box(tip_jacobian(&model, &mut data, &qs[k]).ok());
    });
    time("coriolis", &mut |k| {
        black_box(coriolis_matrix(&model, &mut data, &qs[k], &vs[k]).ok());
    });
    time("gravity", &mut |k| {
        black_box(gravity_torque(&model, &mut data, &qs[k]).ok());
    });
    time("fk", &mut |k| {
        black_box(forward_kinematics(&model, &mut data, &qs[k]).ok());
    });
    time("regressor", &mut |k| {
        black_box(joint_torque_regressor(&model, &mut data, &qs[k], &vs[k], &as_[k]).is_ok());
    });
}
