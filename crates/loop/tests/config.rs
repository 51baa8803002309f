//! `LoopConfig`: the TOML shape, the defaults, and every problem at its dotted key.

use admittance_loop::{ControllerKind, LoopConfig, LoopError, ObserverKind};

fn parse(text: &str) -> LoopConfig {
    toml::from_str(text).unwrap()
}

const PD: &str = "[controller]\nkind = \"pd\"\npd = { kp = 100.0, kd = 20.0 }\n";

#[test]
fn defaults_fill_everything_but_the_controller_kind() {
    let c = parse("[controller]\nkind = \"neural\"\n");
    assert_eq!(c.control_rate_hz, 1000.0);
    assert_eq!(c.controller.kind, ControllerKind::Neural);
    assert!(c.controller.subtract_estimate);
    assert!(c.admittance.is_none() && c.task_admittance.is_none());
    assert_eq!(c.observer.kind, ObserverKind::None);
    assert_eq!(
        (
            c.observer.cutoff_hz,
            c.observer.input_filter_hz,
            c.observer.warmup
        ),
        (0.0, 0.0, 0.5)
    );
    assert_eq!(c.observer.nominal_inertia_scale, 1.0);
    assert!(c.problems().is_empty());
    assert!(toml::from_str::<LoopConfig>("[observer]\nkind = \"momentum\"\n").is_err());
}

#[test]
fn unknown_keys_and_a_training_table_are_refused() {
    let e = toml::from_str::<LoopConfig>(&format!("{PD}[observer]\ncutof_hz = 5.0\n"));
    assert!(e.unwrap_err().to_string().contains("cutof_hz"));
    let e = toml::from_str::<LoopConfig>(&format!("{PD}[observer.training]\ndata = \"x.csv\"\n"));
    assert!(e.unwrap_err().to_string().contains("trained networks"));
}

#[test]
fn every_problem_is_named_by_its_dotted_key() {
    let c = parse(
        "control_rate_hz = 500.0\n[controller]\nkind = \"pd\"\n\
         [admittance]\ndamping = 3.0\nstiffness = 5.0\n\
         [task_admittance]\n\
         [observer]\nkind = \"momentum\"\ncutoff_hz = -1.0\ninput_filter_hz = 250.0\nwarmup = -0.5\nnominal_inertia_scale = 0.0\n"
    );
    let keys: Vec<String> = c.problems().iter().map(LoopError::key).collect();
    assert_eq!(
        keys,
        [
            "controller.pd",
            "observer.nominal_inertia_scale",
            "observer.cutoff_hz",
            "observer.warmup",
            "observer.input_filter_hz",
            "task_admittance",
        ]
    );
    assert_eq!(c.validate().unwrap_err().key(), "controller.pd");
    let mut c = parse(PD);
    c.control_rate_hz = f64::NAN;
    assert_eq!(c.validate().unwrap_err().key(), "control_rate_hz");
}
