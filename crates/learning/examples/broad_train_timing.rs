//! Times the broad network fit at the paper's size (docs/method.md section 5: N = 450,000
//! samples, L = 1000 nodes, d_in = 21, d_out = 7) on a deterministic synthetic data set,
//! times a growth by 100 nodes against a full retrain, and writes the data, the centres,
//! widths, standardisation and weights for `scripts/bench/broad_numpy.py` to reproduce the
//! same fit in numpy.
//!
//! ```text
//! cargo run --release -p admittance-learning --example broad_train_timing -- \
//!     [--rows 450000] [--nodes 1000] [--grow 100] [--threads 0] [--block 2048]
//!     [--strategy per-thread|shared] [--out DIR] [--skip-growth] [--repeat 2]
//!     [--fixed-from DIR]
//! ```
//!
//! `--fixed-from DIR` runs only one fixed-node fit on the nodes and lambda that a run with
//! `--out DIR` wrote (the benchmark script alternates it with numpy's fit).
//!
//! Timings on a shared machine fluctuate: the fixed-node fit, the growth and the retrain
//! are repeated `--repeat` times (growth and retrain alternating) and the minimum is kept.

use admittance_learning::broad::{
    exp_nonpositive_slice, fit, fit_with_nodes, BroadConfig, Dataset, GramStrategy, GrowthSpec,
    NodeSet,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::io::Write;
use std::time::Instant;

const J: usize = 7;

/// Synthetic free-motion data: 7 joints with two-sine trajectories (incommensurate
/// periods of 15 to 33 s, fixed phases) sampled at 1 kHz from sample `start` on, inputs
/// [q, q', q''], outputs a smooth nonlinear "torque" with inertia-like, gravity-like,
/// Coriolis-like, viscous and Coulomb (tanh) terms, plus Gaussian noise of std 0.01
/// (generator seeded by `noise_seed`). Training uses samples 0..N (450 s), validation
/// the continuation of the same motion.
fn make_data(rows: usize, start: usize, noise_seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let amp: [f64; J] = [1.2, 0.9, 1.8, 1.0, 2.0, 1.1, 2.2];
    let centre: [f64; J] = [0.0, -0.5, 0.0, 1.2, 0.0, 0.3, 0.0];
    let omega: [f64; J] = [0.31, 0.23, 0.37, 0.29, 0.41, 0.19, 0.43];
    let phase: Vec<f64> = (0..2 * J)
        .map(|_| rng.random::<f64>() * std::f64::consts::TAU)
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(noise_seed);
    let mut x = vec![0.0; rows * 3 * J];
    let mut y = vec![0.0; rows * J];
    for r in 0..rows {
        let t = (start + r) as f64 * 1e-3;
        let row = &mut x[r * 3 * J..(r + 1) * 3 * J];
        for i in 0..J {
            let (w1, w2) = (omega[i], 2.3 * omega[i]);
            let (a1, a2) = (0.7 * amp[i], 0.3 * amp[i]);
            let (s1, c1) = (w1 * t + phase[i]).sin_cos();
            let (s2, c2) = (w2 * t + phase[J + i]).sin_cos();
            row[i] = centre[i] + a1 * s1 + a2 * s2;
            row[J + i] = a1 * w1 * c1 + a2 * w2 * c2;
            row[2 * J + i] = -a1 * w1 * w1 * s1 - a2 * w2 * w2 * s2;
        }
        let (q, qd, qdd) = (&row[..J], &row[J..2 * J], &row[2 * J..]);
        for i in 0..J {
            let ip = (i + 1) % J;
            let mut coupling = 0.0;
            for j in 0..J {
                coupling += qdd[j] * (q[i] - q[j]).cos();
            }
            let noise = {
                let u1: f64 = rng.random::<f64>().max(1e-300);
                let u2: f64 = rng.random::<f64>();
                (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
            };
            y[r * J + i] = (1.0 + 0.2 * i as f64) * qdd[i]
                + 0.05 * coupling
                + 3.0 * (q[i] + 0.5 * q[ip]).sin()
                + 0.2 * qd[i] * qd[ip]
                + 0.3 * qd[i]
                + 0.5 * (qd[i] / 0.02).tanh()
                + 0.01 * noise;
        }
    }
    (x, y)
}

fn write_f64(path: &std::path::Path, v: &[f64]) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).expect("create"));
    for x in v {
        f.write_all(&x.to_le_bytes()).expect("write");
    }
}

fn read_f64(path: &std::path::Path) -> Vec<f64> {
    let bytes = std::fs::read(path).expect("read");
    bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect()
}

/// `--fixed-from DIR`: one fixed-node fit (features + Gram + solve) on the nodes and
/// lambda that an earlier run wrote to DIR, the same data regenerated; prints its time.
/// The benchmark script alternates this with numpy's fit, round by round.
fn fixed_fit_from(dir: &str, config: &BroadConfig) {
    let dir = std::path::Path::new(dir);
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("meta.json")).expect("meta"))
            .expect("meta json");
    let rows = meta["rows"].as_u64().expect("rows") as usize;
    let nodes = NodeSet {
        dim: 3 * J,
        centres: read_f64(&dir.join("centres.f64")),
        widths: read_f64(&dir.join("widths.f64")),
    };
    let mut fixed = config.clone();
    fixed.nodes = nodes.len();
    fixed.lambda_grid = vec![meta["lambda_rel"].as_f64().expect("lambda_rel")];
    let (x, y) = make_data(rows, 0, 1);
    let train = Dataset::new(&x, &y, 3 * J, J).expect("train data");
    let c0 = cpu_s();
    let t = Instant::now();
    let (model, _) = fit_with_nodes(&train, None, &fixed, &nodes).expect("fit fixed");
    let fit_s = t.elapsed().as_secs_f64();
    let cpu = cpu_s() - c0;
    let same = rel_diff(model.weights(), &read_f64(&dir.join("weights_rust.f64")));
    let out =
        serde_json::json!({"fixed_nodes_fit_s": fit_s, "cpu_s": cpu, "weights_rel_diff": same});
    println!("{out}");
}

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(f64::NAN)
}

/// User + system CPU seconds of this process so far (Linux /proc; NaN elsewhere).
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
            Some(ticks / 100.0)
        })
        .unwrap_or(f64::NAN)
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    let den: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    num / den
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let rows: usize = get("--rows")
        .map(|v| v.parse().expect("--rows"))
        .unwrap_or(450_000);
    let nodes: usize = get("--nodes")
        .map(|v| v.parse().expect("--nodes"))
        .unwrap_or(1000);
    let grow: usize = get("--grow")
        .map(|v| v.parse().expect("--grow"))
        .unwrap_or(100);
    let threads: usize = get("--threads")
        .map(|v| v.parse().expect("--threads"))
        .unwrap_or(0);
    let block: usize = get("--block")
        .map(|v| v.parse().expect("--block"))
        .unwrap_or(2048);
    let strategy = match get("--strategy").as_deref() {
        Some("shared") => GramStrategy::SharedGemm,
        _ => GramStrategy::PerThread,
    };
    let out_dir = get("--out");
    let skip_growth = args.iter().any(|a| a == "--skip-growth");
    let repeat: usize = get("--repeat")
        .map(|v| v.parse().expect("--repeat"))
        .unwrap_or(2)
        .max(1);

    let mut config = BroadConfig::for_arm(J);
    config.nodes = nodes;
    config.threads = threads;
    config.block_rows = block;
    config.gram_strategy = strategy;
    if let Some(dir) = get("--fixed-from") {
        fixed_fit_from(&dir, &config);
        return;
    }

    // Fast exp versus libm exp, 10 M values.
    let vals: Vec<f64> = (0..10_000_000)
        .map(|i| -((i % 100_000) as f64) * 1e-4)
        .collect();
    let mut v = vals.clone();
    let t = Instant::now();
    exp_nonpositive_slice(&mut v);
    let fast_ns = t.elapsed().as_secs_f64() / 1e7 * 1e9;
    let t = Instant::now();
    let mut s = 0.0;
    for x in &vals {
        s += x.exp();
    }
    let std_ns = t.elapsed().as_secs_f64() / 1e7 * 1e9;
    std::hint::black_box(s);
    drop(vals);
    drop(v);

    let t = Instant::now();
    let (x, y) = make_data(rows, 0, 1);
    let (xv, yv) = make_data(rows / 10, rows, 2);
    let gen_s = t.elapsed().as_secs_f64();
    let train = Dataset::new(&x, &y, 3 * J, J).expect("train data");
    let val = Dataset::new(&xv, &yv, 3 * J, J).expect("validation data");

    // 1. Full fit: centres, Gram, lambda scan on the validation set.
    let (model, report) = fit(&train, Some(&val), &config).expect("fit");

    // 2. Refit with the same nodes and the chosen lambda: features + Gram + solve, the
    //    computation numpy reproduces.
    let mut fixed = config.clone();
    fixed.lambda_grid = vec![model.lambda_rel()];
    let mut fixed_s = f64::INFINITY;
    let mut fixed_runs = Vec::new();
    let mut last = None;
    let mut fixed_cpu = f64::INFINITY;
    for _ in 0..repeat {
        let t = Instant::now();
        let c0 = cpu_s();
        let out = fit_with_nodes(&train, None, &fixed, model.nodes()).expect("fit fixed");
        let e = t.elapsed().as_secs_f64();
        fixed_cpu = fixed_cpu.min(cpu_s() - c0);
        fixed_runs.push(e);
        fixed_s = fixed_s.min(e);
        last = Some(out);
    }
    let (model2, report2) = last.expect("at least one run");
    let same_w = rel_diff(model2.weights(), model.weights());
    // A pass that forms every pattern block but multiplies it only by W (P x 7): about
    // the cost of the features alone.
    let t = Instant::now();
    let _ = model.evaluate(&train, threads).expect("evaluate");
    let features_pass_s = t.elapsed().as_secs_f64();

    // 3. Growth by `grow` nodes versus a full retrain on the grown node set.
    let mut growth = serde_json::Value::Null;
    if !skip_growth && grow > 0 {
        let spec = GrowthSpec::KMeansPlusPlus {
            count: grow,
            seed: 99,
        };
        let (mut best_grow, mut best_retrain) = (f64::INFINITY, f64::INFINITY);
        let (mut grow_runs, mut retrain_runs) = (Vec::new(), Vec::new());
        let (mut grow_cpu, mut retrain_cpu) = (Vec::new(), Vec::new());
        let mut result = None;
        for _ in 0..repeat {
            let mut grown = model.clone();
            let c0 = cpu_s();
            let g = grown.grow(&train, &spec, &config).expect("grow");
            let c1 = cpu_s();
            let t = Instant::now();
            let (retrained, _) =
                fit_with_nodes(&train, None, &fixed, grown.nodes()).expect("retrain");
            let retrain_s = t.elapsed().as_secs_f64();
            grow_cpu.push(c1 - c0);
            retrain_cpu.push(cpu_s() - c1);
            grow_runs.push(g.total_s);
            retrain_runs.push(retrain_s);
            best_grow = best_grow.min(g.total_s);
            best_retrain = best_retrain.min(retrain_s);
            result = Some((grown, g, retrained));
        }
        let (grown, g, retrained) = result.expect("at least one run");
        let diff = rel_diff(grown.weights(), retrained.weights());
        let e_grown = grown.evaluate(&val, threads).expect("eval");
        growth = serde_json::json!({
            "nodes_added": g.nodes_added,
            "grow_s": best_grow,
            "grow_runs_s": grow_runs,
            "grow_cross_terms_s": g.cross_terms_s,
            "grow_solve_s": g.solve_s,
            "grow_centres_s": g.centres_s,
            "retrain_s": best_retrain,
            "retrain_runs_s": retrain_runs,
            "grow_over_retrain": best_grow / best_retrain,
            "grow_over_full_fit": best_grow / report.times.total_s,
            "grow_cpu_s": grow_cpu,
            "retrain_cpu_s": retrain_cpu,
            "weights_rel_diff_vs_retrain": diff,
            "validation_nrmse_after_growth": e_grown,
        });
    }

    if let Some(dir) = &out_dir {
        let dir = std::path::Path::new(dir);
        std::fs::create_dir_all(dir).expect("out dir");
        let mut data = Vec::with_capacity(rows * 4 * J);
        for r in 0..rows {
            data.extend_from_slice(&x[r * 3 * J..(r + 1) * 3 * J]);
            data.extend_from_slice(&y[r * J..(r + 1) * J]);
        }
        write_f64(&dir.join("data.f64"), &data);
        drop(data);
        write_f64(&dir.join("mean.f64"), &model.standardiser().mean);
        write_f64(&dir.join("std.f64"), &model.standardiser().std);
        write_f64(&dir.join("centres.f64"), &model.nodes().centres);
        write_f64(&dir.join("widths.f64"), &model.nodes().widths);
        write_f64(&dir.join("weights_rust.f64"), model2.weights());
        let meta = serde_json::json!({
            "rows": rows, "d_in": 3 * J, "d_out": J, "nodes": model.n_nodes(),
            "pattern_width": model.pattern_width(), "bias_index": model.bias_index(),
            "friction_columns": model.friction().columns, "friction_scales": model.friction().scales,
            "lambda": model2.lambda(), "lambda_rel": model.lambda_rel(), "rust_fixed_fit_s": fixed_s,
        });
        std::fs::write(
            dir.join("meta.json"),
            serde_json::to_string_pretty(&meta).unwrap(),
        )
        .expect("meta");
    }

    let summary = serde_json::json!({
        "rows": rows, "nodes": nodes, "threads": threads, "block_rows": block,
        "strategy": format!("{strategy:?}"),
        "data_generation_s": gen_s,
        "fast_exp_ns_per_value": fast_ns, "libm_exp_ns_per_value": std_ns,
        "fit_report": report,
        "fixed_nodes_fit_s": fixed_s,
        "fixed_nodes_fit_runs_s": fixed_runs,
        "fixed_nodes_fit_cpu_s": fixed_cpu,
        "fixed_nodes_times": report2.times,
        "features_pass_s": features_pass_s,
        "fixed_fit_weights_rel_diff": same_w,
        "growth": growth,
        "peak_rss_mb": peak_rss_mb(),
    });
    println!("{}", serde_json::to_string_pretty(&summary).unwrap());
}
