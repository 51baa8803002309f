//! Criterion benchmarks of every algorithm on the Baxter left arm (7 joints).
//! `cargo bench -p admittance-dynamics`; the side-by-side ratio against Pinocchio's C++
//! is scripts/bench/compare_pinocchio.sh.

use std::hint::black_box;

use admittance_dynamics::*;
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector6;

fn baxter() -> Model {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/baxter_left_arm.urdf");
    Model::from_urdf_file(&path, Some("base"), Some("left_hand")).expect("Baxter model")
}

fn algorithms(c: &mut Criterion) {
    let model = baxter();
    let mut data = Data::new(&model);
    let q = [0.3, -0.6, 0.2, 1.4, -0.4, 0.8, 0.1];
    let v = [0.5, -0.3, 0.2, 0.4, -0.6, 0.1, 0.9];
    let a = [1.0, 0.5, -0.5, 0.2, 0.3, -0.1, 0.7];
    let w = Vector6::new(1.0, 2.0, 3.0, 0.1, 0.2, 0.3);
    let mut group = c.benchmark_group("baxter");
    group.bench_function("rnea", |b| {
        b.iter(|| black_box(rnea(&model, &mut data, black_box(&q), &v, &a).is_ok()))
    });
    group.bench_function("rnea_with_tip_wrench", |b| {
        b.iter(|| {
            black_box(rnea_with_tip_wrench(&model, &mut data, black_box(&q), &v, &a, &w).is_ok())
        })
    });
    group.bench_function("crba", |b| {
        b.iter(|| black_box(crba(&model, &mut data, black_box(&q)).is_ok()))
    });
    group.bench_function("aba", |b| {
        b.iter(|| black_box(aba(&model, &mut data, black_box(&q), &v, &a).is_ok()))
    });
    group.bench_function("coriolis", |b| {
        b.iter(|| black_box(coriolis_matrix(&model, &mut data, black_box(&q), &v).is_ok()))
    });
    // The momentum observer's terms: fused O(n) pass against the three calls it replaces.
    group.bench_function("momentum_observer_terms", |b| {
        b.iter(|| black_box(momentum_observer_terms(&model, &mut data, black_box(&q), &v).is_ok()))
    });
    group.bench_function("crba_coriolis_gravity", |b| {
        b.iter(|| {
            let q = black_box(&q);
            black_box(crba(&model, &mut data, q).is_ok());
            black_box(coriolis_matrix(&model, &mut data, q, &v).is_ok());
            black_box(gravity_torque(&model, &mut data, q).is_ok())
        })
    });
    // The plant's force evaluation: M (composite pass), C v + G and G on one set of
    // placements; without M, the difference is the composite pass.
    group.bench_function("mass_matrix_and_bias", |b| {
        b.iter(|| {
            black_box(mass_matrix_and_bias(&model, &mut data, black_box(&q), &v, true).is_ok())
        })
    });
    group.bench_function("bias_and_gravity", |b| {
        b.iter(|| black_box(bias_and_gravity(&model, &mut data, black_box(&q), &v, true).is_ok()))
    });
    // One sample's row block of the identification least squares.
    group.bench_function("joint_torque_regressor", |b| {
        b.iter(|| {
            black_box(joint_torque_regressor(&model, &mut data, black_box(&q), &v, &a).is_ok())
        })
    });
    group.bench_function("gravity", |b| {
        b.iter(|| black_box(gravity_torque(&model, &mut data, black_box(&q)).is_ok()))
    });
    group.bench_function("nonlinear_effects", |b| {
        b.iter(|| black_box(nonlinear_effects(&model, &mut data, black_box(&q), &v).is_ok()))
    });
    group.bench_function("forward_kinematics", |b| {
        b.iter(|| black_box(forward_kinematics(&model, &mut data, black_box(&q)).is_ok()))
    });
    group.bench_function("jacobian", |b| {
        b.iter(|| black_box(tip_jacobian(&model, &mut data, black_box(&q)).is_ok()))
    });
    group.bench_function("jdot_qdot", |b| {
        b.iter(|| black_box(tip_jdot_qdot(&model, &mut data, black_box(&q), &v).is_ok()))
    });
    group.finish();
}

criterion_group!(benches, algorithms);
criterion_main!(benches);
