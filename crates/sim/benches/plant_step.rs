//! Criterion benchmark of one plant step on the Baxter left arm at the plant step
//! (5 kHz): semi-implicit Euler (MuJoCo's scheme, the side-by-side comparison with
//! `mj_step`) and the default RK4 split beside it; each on the free frictionless arm and
//! on experiment A's plant (friction on every joint, s0 deadzone, s1 spring). The state
//! goes back to the mid-range pose every 0.2 s of simulated time.

use std::hint::black_box;

use admittance_dynamics::Model;
use admittance_sim::{DeadzoneConfig, FrictionConfig, Integrator, Plant, PlantConfig};
use criterion::{criterion_group, criterion_main, Criterion};

fn baxter() -> Model {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/baxter_left_arm.urdf"
    );
    Model::from_urdf_file(path.as_ref(), Some("base"), Some("left_hand")).expect("baxter model")
}

fn config(model: &Model, integrator: Integrator, scenario: bool) -> PlantConfig {
    let mut c = PlantConfig {
        rate_hz: 5000.0,
        control_rate_hz: 5000.0,
        integrator,
        initial_q: model
            .position_limits()
            .map(|(lo, hi)| 0.5 * (lo + hi))
            .collect(),
        ..PlantConfig::default()
    };
    if scenario {
        c.friction = vec![FrictionConfig {
            joint: "*".into(),
            viscous: 0.5,
            coulomb: 0.3,
            v_s: 0.01,
        }];
        c.deadzones = vec![DeadzoneConfig {
            joint: "left_s0".into(),
            d_left: -0.49,
            d_right: 0.49,
            ..Default::default()
        }];
        c.spring.enabled = true;
    }
    c
}

fn plant_step(c: &mut Criterion) {
    let model = baxter();
    let tau = [0.5, -0.25, 0.17, -0.125, 0.1, -0.083, 0.071];
    let mut group = c.benchmark_group("plant_step");
    for (name, integrator, scenario) in [
        ("semi_implicit_euler", Integrator::SemiImplicitEuler, false),
        ("rk4_split", Integrator::Rk4Split, false),
        (
            "semi_implicit_euler_scenario",
            Integrator::SemiImplicitEuler,
            true,
        ),
        ("rk4_split_scenario", Integrator::Rk4Split, true),
    ] {
        let cfg = config(&model, integrator, scenario);
        let mut plant = Plant::new(&model, &cfg).expect("plant");
        let zero = [0.0; 7];
        group.bench_function(name, |b| {
            b.iter(|| {
                if plant.time() >= 0.2 {
                    plant.reset();
                    plant.set_state(&cfg.initial_q, &zero).ok();
                }
                black_box(plant.step(black_box(&tau)).ok());
            })
        });
    }
    group.finish();
}

criterion_group!(benches, plant_step);
criterion_main!(benches);
