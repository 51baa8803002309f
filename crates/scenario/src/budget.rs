//! The work and memory a run needs, checked against [`crate::Limits`] before it starts.

use crate::context::Ctx;
use crate::error::ScenarioError;
use crate::limits::Limits;
use crate::spec::Scenario;

/// A number as a person reads it: plain when moderate, in exponent form when huge.
fn num(x: f64) -> String {
    if x.is_finite() && x.abs() < 1e6 {
        format!("{x}")
    } else {
        format!("{x:.3e}")
    }
}

fn human_bytes(b: f64) -> String {
    if b >= (1u64 << 30) as f64 {
        format!("{:.3e} GiB", b / (1u64 << 30) as f64)
    } else {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    }
}

/// Refuses a variant whose plant steps or recorded series exceed the limits.
pub(crate) fn check_run(
    ctx: &Ctx<'_>,
    s: &Scenario,
    n: usize,
    limits: &Limits,
) -> Result<(), ScenarioError> {
    let plant_steps = s.duration * s.plant.rate_hz;
    if !(plant_steps <= limits.max_plant_steps) {
        // Blame the rate when it is the unusual factor.
        let key = if s.plant.rate_hz > 1e5 {
            "plant.rate_hz"
        } else {
            "duration"
        };
        return Err(ctx.err(
            key,
            format!(
                "the run needs {} plant steps (duration {} s x plant.rate_hz {} Hz), more than the limit of {}",
                num(plant_steps),
                num(s.duration),
                num(s.plant.rate_hz),
                num(limits.max_plant_steps)
            ),
            Some("shorten `duration` or lower `plant.rate_hz`; the limit is `--max-plant-steps`"),
        ));
    }
    let control_steps = s.duration * s.plant.control_rate_hz;
    let decimation = s.output.decimation.max(1) as f64;
    // A row of VARIANT.csv: t, 9 signals per joint, ee_error, f and f_hat, nodes.
    let row = (1 + 9 * n + 1 + 2 * n + 1) as f64 * 8.0;
    let mut bytes = control_steps / decimation * row;
    if s.record.free_motion_csv {
        bytes += control_steps * (1 + 4 * n) as f64 * 8.0;
    }
    if !(bytes <= limits.max_series_bytes) {
        return Err(ctx.err(
            "duration",
            format!(
                "the run would keep {} of time series (duration {} s at {} Hz, a row every {} steps), more than the limit of {}",
                human_bytes(bytes),
                num(s.duration),
                num(s.plant.control_rate_hz),
                s.output.decimation,
                human_bytes(limits.max_series_bytes)
            ),
            Some("shorten `duration`, raise `output.decimation`, or raise the limit with `--max-series-gb`"),
        ));
    }
    Ok(())
}
